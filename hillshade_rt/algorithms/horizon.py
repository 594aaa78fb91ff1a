"""``horizon``: single-azimuth horizon mapping (Aslandere, Flatken & Gerndt [1]_).

For every cell, the horizon angle β along the sun's azimuth only (their eq. 3-5),

    β = atan( max_k (T_k - h0) / d_k ),

over the model's samples ``T_k`` of the ray (grid-line crossings, interpolated as in ``brute``) at
ground distance ``d_k = k * step``; the cell is lit iff β <= α, the sun elevation (eq. 6). β may be
negative: a cell on a summit or a convex slope looks down on everything ahead. A cell with no
terrain ahead inside the raster (its ray leaves at once) gets β = -90°.

Two ways to get β:

``scan`` (default, exact): the paper's per-cell march, with two exact early exits: the march stops
when even the highest cell of the DEM could not raise the maximum further, and, for a mask, as soon
as the maximum exceeds α or can no longer reach it. ``sample_spacing`` = sp > 1 takes every sp-th
sample only (the paper's ``sp``): faster, approximate (figures in docs/algorithms.md).
``max_distance`` M (metres) ends each ray at its last sample within M of ground distance
(k <= floor(M / step_m), the row's metres per step). One march (``_march``) serves the raster in
memory and windows of it (``Marches``: a region's rays carried from window to window, state and
all, for rasters larger than memory: ``run.horizon_windows``), with the same bits. In memory the
angles are taken row by row (``rowscan``): all cells of a row share their rays' geometry, so
their k-th samples are one vectorised loop; the same bits as the march, several times faster.

``hull`` (fast, O(N log N)): Dozier & Frew's idea [2]_ as in topocalc: along one straight line in
the sun direction the horizon of every point follows from the upper convex hull of the samples
ahead of it, built incrementally from the sun's edge. The lines used are those through whole
offsets ``o = p - s*v`` of the canonical frame; their samples are exactly the model's. A cell lies
on such a line only when ``s*v`` is whole (on the axes and diagonals: always, and there ``hull``
equals ``scan``); otherwise its tangent of β is interpolated linearly between the two lines that
bracket it, i.e. the horizon of rays shifted sideways by less than a cell. Its error against the
exact model is measured in docs/algorithms.md. Needs one ray direction for the whole raster.

References
----------
.. [1] T. Aslandere, M. Flatken, A. Gerndt, "A Real-Time Physically Based Algorithm for Hard
       Shadows on Dynamic Height-Fields," German Aerospace Center (DLR), Simulation and Software
       Technology (no date given in the paper).
.. [2] J. Dozier, J. Frew, "Rapid calculation of terrain parameters for radiation modeling from
       digital elevation data," IEEE Trans. Geosci. Remote Sens., vol. 28, no. 5, pp. 963-969,
       1990. :doi:`10.1109/36.58986`
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..model.geometry import SunRays
from ._cuda import cuda, kernel
from ._jitcache import njit
from .frames import frame_of, uniform_rays
from .pyramid import climb, pyramid_args, samples_left
from .raymath import line_position, madd, ray_origin, terrain_on_line
from .rowscan import CHUNK, DENSE_COLS, DENSE_ROWS, row_dense

METHODS = ("scan", "hull")


# why the rays differ from row to row (the note of a run that could not share one ray)
PER_ROW_SPACING = ("the ground spacing varies per row (a geographic CRS, or a "
                   "projection whose scale changes across the raster, as lunar polar "
                   "stereographic DEMs)")


# no limit on the steps of a ray (--max-distance not given)
NO_LIMIT = np.int64(1) << np.int64(62)


@njit(cache=True)
def last_step(max_dist, step_m):
    """The last sample k of a ray within ground distance ``max_dist`` (m) of its cell, the
    samples being ``step_m`` metres apart: floor(max_dist / step_m), ``NO_LIMIT`` for inf."""
    q = max_dist / step_m
    if q >= 4.0e18:
        return NO_LIMIT
    return np.int64(math.floor(q))


@njit(cache=True, inline="always")
def _march(z, pyr, off, widths, nlev, wl0, wo0, line0, other0, n_dom, n_oth, h0, dom_col, sd,
           so, sp, zmax, rise, cv, decide, best, kbest, k, kmax, cap):
    """March samples k, k + sp, ... of the ray of one cell: (the maximum of
    (T_k - h0 - k*k*cv) / k, starting at ``best``; the k of that maximum, starting at
    ``kbest`` (0: none yet); the next sample to march, 0 when the march is over).

    The cell is at ``line0`` (its grid line along the dominant axis) and ``other0`` (its
    position on that line) in the raster's coordinates, which has ``n_dom`` lines of ``n_oth``
    positions; ``h0`` its height. ``z`` holds the heights of a window of the raster whose first
    line is ``wl0`` and first position ``wo0`` (0, 0 and ``z`` the raster: a march in memory);
    the march stops at the first sample ``z`` does not hold, and says so by returning that
    sample as the next one (a window that ends at the raster's edge ends the march there, as
    the raster does). A sample is computed in the raster's coordinates (the same rounding
    whatever the window) and read from the window: a window's march takes the same steps and
    decisions as the march in memory, so the two give the same bits.

    The march is over once ``k`` passes ``kmax`` (the last step within --max-distance), the ray
    leaves the raster, or no later sample can raise the maximum (even the highest cell of the
    raster, ``zmax``); ``decide`` (a mask): as soon as the result is known relative to ``rise``;
    ``cap``: once the maximum exceeds it (soft shadows). Over the maximum-height pyramid of
    ``z`` (``nlev`` > 0, sp = 1) a block is skipped while the maximum is >= 0 and the block lies
    below h0 + max*k + k*k*cv, which only rises along the ray: no sample in it could raise the
    maximum, so the result is the plain march's. ``cv`` is the Earth-curvature term (the terrain
    k steps away sits k*k*cv lower; 0 when flat)."""
    if dom_col:
        wn_dom = np.int64(z.shape[1])
        wn_oth = np.int64(z.shape[0])
    else:
        wn_dom = np.int64(z.shape[0])
        wn_oth = np.int64(z.shape[1])
    lev = 0
    while True:
        if k > kmax:
            return best, kbest, 0
        if zmax - h0 <= best * k:           # no later sample can raise the maximum
            return best, kbest, 0
        if decide and zmax - h0 <= rise * k:  # nothing ahead can reach the sun's elevation
            return best, kbest, 0
        line = line0 + k * sd
        if line < 0 or line >= n_dom:
            return best, kbest, 0
        pos = line_position(madd(float(other0), float(k), so), n_oth)
        if pos < 0.0:
            return best, kbest, 0
        wl = line - wl0
        wpos = pos - wo0                     # exact: an integer off a larger number
        wi = np.int64(math.floor(wpos))
        if wl < 0 or wl >= wn_dom or wpos < 0.0 or wpos > wn_oth - 1:
            return best, kbest, k            # beyond the window: the next window goes on
        if nlev > 0 and best >= 0.0:
            hr = h0 + best * k + k * k * cv
            lev = climb(pyr, off, widths, nlev, lev, wi if dom_col else wl,
                        wl if dom_col else wi, hr)
            if lev > 0:        # no sample in the block can raise the maximum: past it
                k += samples_left(lev, wl, wi, wpos, sd, so) + 1
                continue
        t = terrain_on_line(z, dom_col, wl, wpos)
        lift = t - h0
        if cv != 0.0:   # t - h0 - k*k*cv, never fused on the GPU
            lift = madd(lift, -float(k * k), cv)
        if lift > best * k:   # NaN (void) compares false: skipped
            best = lift / k
            kbest = k
            if decide and best > rise:
                return best, kbest, 0
            if best > cap:
                return best, kbest, 0
        k += sp


@njit(cache=True)
def _scan_cell(z, pyr, off, widths, nlev, r, c, dom_col, sd, so, sp, zmax, rise, cv, decide,
               floor, cap, kmax, lift):
    """(max of (T_k - h0 - k*k*cv) / k over the samples k = sp, 2sp, ... up to ``kmax``
    (-inf if none), the k of that maximum (0 if none)): ``_march`` over the whole raster
    ``z`` from the cell (r, c). ``floor``: start the maximum there (the answer is then
    max(β, floor): soft shadows need no horizon below the sun's lower edge). ``lift``: the
    observer stands that many metres above the cell (h0 = z[r, c] + lift; 0: the ground)."""
    line0, other0, n_dom, n_oth = ray_origin(z, r, c, dom_col)
    h0 = float(z[np.int64(r), np.int64(c)]) + lift
    best, kbest, _ = _march(z, pyr, off, widths, nlev, np.int64(0), np.int64(0), line0, other0,
                            n_dom, n_oth, h0, dom_col, sd, so, sp, zmax, rise, cv, decide, floor,
                            np.int64(0), sp, kmax, cap)
    return best, kbest


@njit(cache=True, inline="always")
def _angle(t, sm, floor_tan, cap_tan):
    """β in degrees from the maximum ``t`` (per step of ``sm`` metres) of ``_march``: -90 with
    nothing ahead (or nothing above the floor), 90 above the cap."""
    if t == -np.inf or (floor_tan > -np.inf and t <= floor_tan * sm):
        return -90.0      # nothing ahead, or nothing above the floor: all the disk
    if t > cap_tan * sm:
        return 90.0       # above the cap: none of the disk
    return math.degrees(math.atan(t / sm))


@njit(cache=True, inline="always")
def _scan_write(z, pyr, off, widths, nlev, r, c, dom_col, step_dom, step_other, rise, step_m,
                curv, sp, zmax, want_mask, mask, beta, floor_tan, cap_tan, want_dist, dist,
                max_dist, lift):
    """Cell (r, c) of the scan: its mask code (want_mask) or its angle β in degrees (at least
    atan(floor_tan); above atan(cap_tan) only known to be above it), and with ``want_dist`` the
    ground distance (m) to the sample of the maximum, the horizon point (NaN on a void or with
    nothing ahead); samples up to ``max_dist`` metres away (inf: to the raster's edge); the
    observer ``lift`` metres above the cell. The per-cell body of both backends."""
    if math.isnan(z[r, c]):
        if want_mask:
            mask[r, c] = 255
        else:
            beta[r, c] = np.nan
        if want_dist:
            dist[r, c] = np.nan
        return
    ri = rise[r]
    sm = step_m[r]
    t, kb = _scan_cell(z, pyr, off, widths, nlev if sp == 1 else np.int64(0), r, c,
                       dom_col[r] != 0, np.int64(step_dom[r]), step_other[r], sp, zmax, ri,
                       curv[r], want_mask, floor_tan * sm, cap_tan * sm,
                       last_step(max_dist, sm), lift)
    if want_dist:
        dist[r, c] = kb * sm if kb > 0 else np.nan
    if want_mask:
        mask[r, c] = 1 if t > ri else 0
    else:
        beta[r, c] = _angle(t, sm, floor_tan, cap_tan)


@njit(parallel=True, cache=True)
def _scan_kernel(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, step_m, curv, sp,
                 zmax, want_mask, mask, beta, floor_tan, cap_tan, want_dist, dist, max_dist, lift):
    rows, cols = z.shape
    for r in prange(rows):
        for c in range(cols):
            _scan_write(z, pyr, off, widths, nlev, r, c, dom_col, step_dom, step_other, rise,
                        step_m, curv, sp, zmax, want_mask, mask, beta, floor_tan, cap_tan,
                        want_dist, dist, max_dist, lift)


@njit(parallel=True, cache=True)
def _rows_kernel(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, step_m, curv, zmax,
                 beta, floor_tan, cap_tan, want_dist, dist, max_dist, lift):
    """The angles of ``_scan_kernel`` (sp = 1), row by row (``rowscan``): every row's rays
    sampled densely over the whole row while enough of them march, the rest by ``_march``
    from where the dense samples left them. The same bits."""
    rows, cols = z.shape
    for r in prange(rows):
        sm = step_m[r]
        dc = dom_col[r] != 0
        sd = np.int64(step_dom[r])
        so = step_other[r]
        cv = curv[r]
        kmax = last_step(max_dist, sm)
        cap = cap_tan * sm
        best = np.empty(cols)
        kb = np.zeros(cols, np.int64)
        done = np.zeros(cols, np.uint8)
        h0 = np.empty(cols)
        for c in range(cols):
            h0[c] = float(z[r, c]) + lift
            best[c] = floor_tan * sm
            if math.isnan(h0[c]):
                done[c] = 1
        ratio = DENSE_COLS if dc else DENSE_ROWS
        k1 = 0
        left = cols
        while True:
            ka = k1 + 1
            k1 = min(kmax, k1 + CHUNK)
            left = row_dense(z, r, dc, sd, so, cv, zmax, cap, ka, k1, h0, best, kb, done)
            if left == 0 or k1 >= kmax or left * ratio < cols:
                break
        if left > 0 and k1 < kmax:
            for c in range(cols):
                if done[c] == 0:
                    line0, other0, n_dom, n_oth = ray_origin(z, r, c, dc)
                    best[c], kb[c], _ = _march(z, pyr, off, widths, nlev, np.int64(0),
                                               np.int64(0), line0, other0, n_dom, n_oth, h0[c],
                                               dc, sd, so, np.int64(1), zmax, 0.0, cv, False,
                                               best[c], kb[c], k1 + 1, kmax, cap)
        for c in range(cols):
            if math.isnan(z[r, c]):
                beta[r, c] = np.nan
                if want_dist:
                    dist[r, c] = np.nan
                continue
            if want_dist:
                dist[r, c] = kb[c] * sm if kb[c] > 0 else np.nan
            beta[r, c] = _angle(best[c], sm, floor_tan, cap_tan)


@kernel
def _scan_gpu(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, step_m, curv, sp,
              zmax, want_mask, mask, beta, floor_tan, cap_tan, want_dist, dist, max_dist, lift):
    """CUDA twin of ``_scan_kernel``: one thread per cell."""
    c, r = cuda.grid(2)
    if r < z.shape[0] and c < z.shape[1]:
        _scan_write(z, pyr, off, widths, nlev, r, c, dom_col, step_dom, step_other, rise,
                    step_m, curv, sp, zmax, want_mask, mask, beta, floor_tan, cap_tan,
                    want_dist, dist, max_dist, lift)


@njit(cache=True)
def _hull_best(hv, ht, top, v, h0):
    """Max slope (T - h0) / (x - v) from (v, h0) to the hull points (unimodal: binary search)."""
    if top == 0:
        return -np.inf
    lo = 0
    hi = top - 1
    while lo < hi:
        m = (lo + hi) // 2
        if (ht[m] - h0) / (hv[m] - v) < (ht[m + 1] - h0) / (hv[m + 1] - v):
            lo = m + 1
        else:
            hi = m
    return (ht[lo] - h0) / (hv[lo] - v)


@njit(parallel=True, cache=True)
def _hull_kernel(Z, s, left, right, lift):
    """Per whole-offset line o, from the sun's edge: answer the cells it brackets, then add its
    sample on this line to the upper hull. left/right: tangent (per step) from the line below /
    above each cell's offset, the observer ``lift`` metres above the cell (the tangent from a
    point left of every hull point is unimodal whatever its height)."""
    L, P = Z.shape
    omin = int(math.floor(-s * (L - 1))) - 1
    omax = P
    for io in prange(omax - omin + 1):
        o = omin + io
        hv = np.empty(L, np.float64)
        ht = np.empty(L, np.float64)
        top = 0
        for v in range(L - 1, -1, -1):
            x = o + s * v
            if x < -1.0 - 1e-9:   # and lower lines lie further left: done
                break
            if x > P:   # lines move to larger positions as v grows: beyond the raster here
                continue
            base = int(math.floor(x))
            for c in (base, base + 1):
                if c < 0 or c > P - 1:
                    continue
                h0 = float(Z[v, c]) + lift
                if math.isnan(h0):
                    continue
                q = c - s * v
                o1 = int(math.floor(q))
                if o1 == o:
                    left[v, c] = _hull_best(hv, ht, top, v, h0)
                elif o1 + 1 == o:
                    right[v, c] = _hull_best(hv, ht, top, v, h0)
            xs = line_position(x, P)
            if xs < 0.0:
                continue
            t = terrain_on_line(Z, False, v, xs)
            if math.isnan(t):
                continue
            # add (v, t) at the near end; drop points no longer on the upper hull
            while top >= 2:
                b_v, b_t = hv[top - 1], ht[top - 1]
                a_v, a_t = hv[top - 2], ht[top - 2]
                if (b_t - t) * (a_v - v) <= (a_t - t) * (b_v - v):
                    top -= 1
                else:
                    break
            hv[top] = v
            ht[top] = t
            top += 1


@njit(parallel=True, cache=True)
def _hull_combine(Z, s, left, right, out):
    """tan = (1-w)*left + w*right, w the cell's offset fraction (a missing side: the other)."""
    L, P = Z.shape
    for v in prange(L):
        for c in range(P):
            q = c - s * v
            w = q - math.floor(q)
            a = left[v, c]
            b = right[v, c]
            if w == 0.0 or b == -np.inf:
                out[v, c] = a
            elif a == -np.inf:
                out[v, c] = b
            else:
                out[v, c] = (1.0 - w) * a + w * b


def horizon_tangent(z: np.ndarray, rays: SunRays, lift: float = 0.0) -> np.ndarray:
    """Hull path: tangent of β per step (float64, DEM-shaped), -inf where nothing is ahead;
    the observer ``lift`` metres above each cell."""
    f = frame_of(rays)
    Z = f.view(z)
    left = np.full(z.shape, -np.inf)
    right = np.full(z.shape, -np.inf)
    _hull_kernel(Z, f.s, f.view(left), f.view(right), float(lift))
    out = np.empty(z.shape)
    _hull_combine(Z, f.s, f.view(left), f.view(right), f.view(out))
    out[np.isnan(z)] = np.nan
    return out


def _check(method, sample_spacing, rays):
    from ..errors import HillshadeError
    if method not in METHODS:
        raise HillshadeError(f"horizon method must be one of {', '.join(METHODS)}, got {method!r}")
    if int(sample_spacing) != sample_spacing or sample_spacing < 1:
        raise HillshadeError(f"sample spacing must be a whole number >= 1, got {sample_spacing}")
    if method == "hull" and sample_spacing != 1:
        raise HillshadeError("--sample-spacing applies to the scan method only")
    return method == "hull" and uniform_rays(rays) and not rays.curved


def _max_distance(max_distance, method: str = "scan") -> float:
    """--max-distance as the kernels take it: metres > 0, inf for none."""
    from ..errors import HillshadeError
    if max_distance is None:
        return math.inf
    m = float(max_distance)
    if not m > 0.0:     # NaN too
        raise HillshadeError(f"the maximum distance must be a positive number of metres, got "
                         f"{max_distance}")
    if method != "scan" and math.isfinite(m):
        raise HillshadeError("a maximum distance applies to the scan method only (the hull "
                             "keeps the whole line ahead)")
    return m


def _lift(lift) -> float:
    """The observer's height above each cell as the kernels take it: metres, finite (< 0: below
    it, as negative openness marches the inverted terrain -z from -(z + H))."""
    from ..errors import HillshadeError
    h = float(lift)
    if not math.isfinite(h):
        raise HillshadeError(f"the height above the ground must be a finite number of metres, "
                             f"got {lift}")
    return h


def _tan_deg(a: float | None, default: float) -> float:
    if a is None or not math.isfinite(a):
        return default
    if a <= -90.0:
        return -np.inf
    if a >= 90.0:
        return np.inf
    return math.tan(math.radians(a))


def horizon_angles(z: np.ndarray, rays: SunRays, method: str = "scan", sample_spacing: int = 1,
                   zmax: float | None = None, stats: dict | None = None, pyramid=True,
                   floor_deg: float | None = None, cap_deg: float | None = None,
                   distance: np.ndarray | None = None,
                   max_distance: float | None = None, lift: float = 0.0,
                   row_wise: bool = True) -> np.ndarray:
    """β in degrees (float32, NaN on voids, -90 where no terrain lies ahead in the raster).
    ``distance``: a DEM-shaped float32 array that receives the ground distance in metres to
    each cell's horizon point (the sample of the maximum; NaN on voids and with nothing ahead;
    the scan only). ``max_distance``: metres; terrain farther from the cell along the ray
    (its samples k with k * step_m > max_distance, step_m its row's metres per step) is
    ignored (None: the whole raster; the scan only).

    The scan marches over the maximum-height pyramid (``pyramid``: True, a ``MaxPyramid`` to
    reuse, or False for the plain scan: same angles). ``floor_deg`` / ``cap_deg`` (soft
    shadows): β at or below the floor comes back as -90 (nothing above the floor: the whole
    disc in view), β above the cap as 90 (the march stops there: none of it). ``lift``: the observer stands that many metres above each cell
    (``--height-above-ground``; >= 0, 0 the ground: the same bits as without).

    The scan (sp = 1) runs row by row (``rowscan``; ``row_wise`` False: cell by cell, the
    reference it equals bit for bit)."""
    hull = _check(method, sample_spacing, rays)
    lift = _lift(lift)
    max_dist = _max_distance(max_distance, method)
    if distance is not None and method != "scan":
        from ..errors import HillshadeError
        raise HillshadeError("the distance to the horizon comes from the scan method only")
    if zmax is None:
        zmax = float(np.nanmax(z))
    if hull:
        t = horizon_tangent(z, rays, lift)
        step_m = float(rays.step_m[0])
        with np.errstate(invalid="ignore"):
            beta = np.degrees(np.arctan(t / step_m)).astype(np.float32)
        return beta
    if method == "hull" and stats is not None:
        stats["note"] = ("Earth curvature on: hull replaced by scan (exact, slower)"
                         if rays.curved else
                         PER_ROW_SPACING + ": hull replaced by scan (exact, slower)")
    beta = np.empty(z.shape, np.float32)
    dist = np.empty((1, 1), np.float32) if distance is None else distance
    if sample_spacing == 1 and row_wise:
        _rows_kernel(z, *pyramid_args(z, pyramid), rays.dom_col, rays.step_dom, rays.step_other,
                     rays.step_m, rays.curv, float(zmax), beta, _tan_deg(floor_deg, -np.inf),
                     _tan_deg(cap_deg, np.inf), distance is not None, dist, max_dist, lift)
        return beta
    _scan_kernel(z, *pyramid_args(z, pyramid), rays.dom_col, rays.step_dom, rays.step_other,
                 rays.rise, rays.step_m, rays.curv, np.int64(sample_spacing), float(zmax), False,
                 np.empty((1, 1), np.uint8), beta, _tan_deg(floor_deg, -np.inf),
                 _tan_deg(cap_deg, np.inf), distance is not None, dist, max_dist, lift)
    return beta


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None, stats: dict | None = None,
                method: str = "scan", sample_spacing: int = 1, pyramid=True) -> np.ndarray:
    """Mask by eq. 6 (lit iff β <= α): uint8 1 shadow / 0 lit / 255 void. ``scan`` with sp = 1
    equals ``brute`` cell for cell."""
    hull = _check(method, sample_spacing, rays)
    if zmax is None:
        zmax = float(np.nanmax(z))
    if hull:
        t = horizon_tangent(z, rays)
        out = np.where(np.isnan(z), 255, (t > rays.rise[0]).astype(np.uint8)).astype(np.uint8)
        return out
    if method == "hull" and stats is not None:
        stats["note"] = ("Earth curvature on: hull replaced by scan (exact, slower)"
                         if rays.curved else
                         PER_ROW_SPACING + ": hull replaced by scan (exact, slower)")
    out = np.empty(z.shape, np.uint8)
    _scan_kernel(z, *pyramid_args(z, pyramid), rays.dom_col, rays.step_dom, rays.step_other, rays.rise,
                 rays.step_m, rays.curv, np.int64(sample_spacing), float(zmax), True, out,
                 np.empty((1, 1), np.float32), -np.inf, np.inf, False,
                 np.empty((1, 1), np.float32), math.inf, 0.0)
    return out


def _scan_gpu_run(g, rays, sample_spacing, zmax, want_mask, floor_deg=None, cap_deg=None,
                  distance=None, max_dist=math.inf, lift=0.0):
    rows, cols = g.shape
    dom_col, step_dom, step_other, rise, step_m, curv = g.rays(rays)
    dummy = g.empty((1, 1), np.float32 if want_mask else np.uint8)
    out = g.empty((rows, cols), np.uint8 if want_mask else np.float32)
    args = (out, dummy) if want_mask else (dummy, out)
    dist = g.empty((rows, cols) if distance is not None else (1, 1), np.float32)
    with g.timed():
        g.launch(_scan_gpu, rows, cols, g.z, *g.pyramid_args(True), dom_col, step_dom,
                 step_other, rise, step_m, curv, np.int64(sample_spacing), float(zmax),
                 want_mask, *args, _tan_deg(floor_deg, -np.inf), _tan_deg(cap_deg, np.inf),
                 distance is not None, dist, float(max_dist), float(lift))
    if distance is not None:
        distance[...] = g.download(dist)
    return g.download(out)


def _gpu_method(method, sample_spacing, rays):
    from ..errors import HillshadeError
    _check(method, sample_spacing, rays)
    if method == "hull":
        raise HillshadeError("the hull method has no GPU kernel (its per-line hulls are as long "
                             "as a line): use the scan, or the CPU backend")


def shadow_mask_gpu(g, rays: SunRays, zmax: float, stats: dict | None = None, method: str = "scan",
                    sample_spacing: int = 1) -> np.ndarray:
    """``shadow_mask`` on the GPU (``g``: a ``gpu.GpuDem``); the scan only."""
    _gpu_method(method, sample_spacing, rays)
    return _scan_gpu_run(g, rays, sample_spacing, zmax, True)


def horizon_angles_gpu(g, rays: SunRays, method: str = "scan", sample_spacing: int = 1,
                       stats: dict | None = None, floor_deg: float | None = None,
                       cap_deg: float | None = None,
                       distance: np.ndarray | None = None,
                       max_distance: float | None = None, lift: float = 0.0) -> np.ndarray:
    """``horizon_angles`` on the GPU (float32 degrees, NaN on voids, -90 nothing ahead;
    ``distance``, ``max_distance`` and ``lift`` as for ``horizon_angles``)."""
    _gpu_method(method, sample_spacing, rays)
    return _scan_gpu_run(g, rays, sample_spacing, g.zmax, False, floor_deg, cap_deg, distance,
                         _max_distance(max_distance), _lift(lift))


# ---------------------------------------------------------------------------------------------
# the scan in windows (rasters larger than memory: ``run.horizon_windows``)

@njit(cache=True, inline="always")
def _span_cell(zw, pyr, off, widths, nlev, wr0, wc0, h0, i, j, r, c, n_rows, n_cols, q0, dom_col,
               step_dom, step_other, step_m, curv, sp, zmax, max_dist, best, kbest, nextk, lift):
    """Carry on the march of region cell (i, j), the raster's cell (r, c), through the window
    ``zw`` whose first row and column are ``wr0``, ``wc0`` (the rays: of the raster's rows from
    ``q0`` on; the observer ``lift`` metres above the cell, as in ``_scan_cell``)."""
    k = nextk[i, j]
    if k == 0:
        return
    q = r - q0
    dc = dom_col[q] != 0
    if dc:
        line0, other0, n_dom, n_oth, wl0, wo0 = c, r, n_cols, n_rows, wc0, wr0
    else:
        line0, other0, n_dom, n_oth, wl0, wo0 = r, c, n_rows, n_cols, wr0, wc0
    b, kb, nk = _march(zw, pyr, off, widths, nlev if sp == 1 else np.int64(0), wl0, wo0, line0,
                       other0, n_dom, n_oth, float(h0[i, j]) + lift, dc, np.int64(step_dom[q]),
                       step_other[q], sp, zmax, 0.0, curv[q], False, best[i, j], kbest[i, j],
                       k, last_step(max_dist, step_m[q]), np.inf)
    best[i, j] = b
    kbest[i, j] = kb
    nextk[i, j] = nk


@njit(parallel=True, cache=True)
def _span_kernel(zw, pyr, off, widths, nlev, wr0, wc0, h0, r0, c0, n_rows, n_cols, q0, dom_col,
                 step_dom, step_other, step_m, curv, sp, zmax, max_dist, best, kbest, nextk,
                 lift):
    rows, cols = h0.shape
    for i in prange(rows):
        for j in range(cols):
            _span_cell(zw, pyr, off, widths, nlev, wr0, wc0, h0, i, j, r0 + i, c0 + j, n_rows,
                       n_cols, q0, dom_col, step_dom, step_other, step_m, curv, sp, zmax,
                       max_dist, best, kbest, nextk, lift)


@kernel
def _span_gpu(zw, pyr, off, widths, nlev, wr0, wc0, h0, r0, c0, n_rows, n_cols, q0, dom_col,
              step_dom, step_other, step_m, curv, sp, zmax, max_dist, best, kbest, nextk, lift):
    """CUDA twin of ``_span_kernel``: one thread per region cell."""
    j, i = cuda.grid(2)
    if i < h0.shape[0] and j < h0.shape[1]:
        _span_cell(zw, pyr, off, widths, nlev, wr0, wc0, h0, i, j, r0 + i, c0 + j, n_rows,
                   n_cols, q0, dom_col, step_dom, step_other, step_m, curv, sp, zmax,
                   max_dist, best, kbest, nextk, lift)


@njit(parallel=True, cache=True)
def _span_angles(h0, i0, step_m, best, kbest, beta, want_dist, dist):
    rows, cols = h0.shape
    for i in prange(rows):
        sm = step_m[i0 + i]
        for j in range(cols):
            if math.isnan(h0[i, j]):
                beta[i, j] = np.nan
                if want_dist:
                    dist[i, j] = np.nan
                continue
            beta[i, j] = _angle(best[i, j], sm, -np.inf, np.inf)
            if want_dist:
                kb = kbest[i, j]
                dist[i, j] = kb * sm if kb > 0 else np.nan


def window_pyramid(zw: np.ndarray, window, shape) -> tuple:
    """The maximum-height pyramid of ``zw``, the heights of ``window`` (r0, r1, c0, c1) of a
    raster of ``shape``, as the kernels take it (``pyramid.MaxPyramid.args``), with every block
    cut short by the window's far edge (its last row or column, where the raster goes on) made
    +inf: such a block stands for cells beyond the window that samples interpolate toward and
    lines the march would skip, none of them in ``zw``; the march samples there (and stops at the
    window's edge) instead."""
    from .pyramid import MaxPyramid
    data, off, widths, nlev = MaxPyramid(zw).args
    rows, cols = zw.shape
    cut_rows, cut_cols = window[1] < shape[0], window[3] < shape[1]
    if not (cut_rows or cut_cols) or nlev == 0:
        return data, off, widths, nlev
    data = data.copy()
    for lev in range(1, int(nlev) + 1):
        size = 1 << lev
        w = int(widths[lev])
        h = (int(off[lev + 1]) - int(off[lev])) // w
        blocks = data[int(off[lev]):int(off[lev + 1])].reshape(h, w)
        if cut_rows:   # block i covers rows i*size ..= (i+1)*size
            blocks[(np.arange(h) + 1) * size >= rows, :] = np.inf
        if cut_cols:
            blocks[:, (np.arange(w) + 1) * size >= cols] = np.inf
    return data, off, widths, nlev


class ScanWindow:
    """The heights ``zw`` of ``window`` (r0, r1, c0, c1) of a raster of ``shape`` made ready to
    march through: its pyramid (``window_pyramid``; ``pyramid`` False: the plain march), and
    with ``gpu`` (``gpu.GpuDem``, the class) both uploaded to the device once, for every
    direction that marches through it."""

    def __init__(self, zw: np.ndarray, window, shape, pyramid: bool = True, gpu=None):
        self.zw, self.window = zw, tuple(int(v) for v in window)
        self.pyr = window_pyramid(zw, window, shape) if pyramid else pyramid_args(zw, False)
        self.g = self.dpyr = None
        if gpu is not None:
            self.g = gpu(zw)
            self.dpyr = tuple(self.g.upload(a) for a in self.pyr[:3]) + (self.pyr[3],)


class Marches:
    """The scan's rays toward one azimuth from the cells of a ``region`` (r0, r1, c0, c1) of
    a raster of ``shape``, marched window after window (``ScanWindow``): the same samples,
    decisions and bits as ``horizon_angles`` over the whole raster, whatever windows they cross.

    ``h0``: the region's heights (float32, NaN voids); ``rays``: the ``SunRays`` of the
    raster's rows, or of the region's rows only (then they start at row r0); ``zmax``: the
    raster's highest height (as the march in memory takes it). :meth:`march` carries every
    open ray as far as a window holds its samples; a ray is closed once its march is over
    (``max_distance``, the raster's edge, nothing left that could raise it); then
    :meth:`angles`. ``lift``: the observer stands that many metres above each cell (as for
    ``horizon_angles``)."""

    def __init__(self, h0: np.ndarray, region, rays: SunRays, shape, zmax: float,
                 sample_spacing: int = 1, max_distance: float | None = None,
                 lift: float = 0.0):
        _check("scan", sample_spacing, rays)
        self.lift = _lift(lift)
        self.h0 = np.ascontiguousarray(h0, np.float32)
        self.region, self.rays, self.shape = tuple(int(v) for v in region), rays, tuple(shape)
        r0, r1 = self.region[:2]
        if len(rays.step_m) == self.shape[0]:
            self.q0 = 0
        elif len(rays.step_m) == r1 - r0:
            self.q0 = r0
        else:
            raise ValueError("rays must be of the raster's rows or of the region's")
        self.zmax, self.sp = float(zmax), np.int64(sample_spacing)
        self.max_dist = _max_distance(max_distance)
        self.best = np.full(self.h0.shape, -np.inf)
        self.kbest = np.zeros(self.h0.shape, np.int64)
        self.nextk = np.where(np.isnan(self.h0), 0, self.sp).astype(np.int64)

    def open(self) -> np.ndarray:
        """Where the march goes on (a boolean per region cell)."""
        return self.nextk > 0

    def _args(self, sw: ScanWindow):
        wr0, _, wc0, _ = sw.window
        r0, _, c0, _ = self.region
        rows, cols = self.shape
        return (np.int64(wr0), np.int64(wc0), np.int64(r0), np.int64(c0), np.int64(rows),
                np.int64(cols), np.int64(self.q0))

    def march(self, sw: ScanWindow) -> None:
        """Carry every open ray through the window ``sw``, as far as it holds its samples."""
        wr0, wc0, r0, c0, rows, cols, q0 = self._args(sw)
        ry = self.rays
        if sw.g is not None:
            g = sw.g
            dom_col, step_dom, step_other, _, step_m, curv = g.rays(ry)
            state = [g.upload(a) for a in (self.h0, self.best, self.kbest, self.nextk)]
            with g.timed():
                g.launch(_span_gpu, self.h0.shape[0], self.h0.shape[1], g.z, *sw.dpyr, wr0,
                         wc0, state[0], r0, c0, rows, cols, q0, dom_col, step_dom, step_other,
                         step_m, curv, self.sp, self.zmax, self.max_dist, *state[1:],
                         self.lift)
            self.best, self.kbest, self.nextk = (g.download(a) for a in state[1:])
            return
        _span_kernel(sw.zw, *sw.pyr, wr0, wc0, self.h0, r0, c0, rows, cols, q0, ry.dom_col,
                     ry.step_dom, ry.step_other, ry.step_m, ry.curv, self.sp, self.zmax,
                     self.max_dist, self.best, self.kbest, self.nextk, self.lift)

    def skip_to(self, k: int) -> None:
        """Open rays go on at their first sample past ``k`` (on their spacing): the caller knows
        that no sample up to ``k`` could raise their maxima (:meth:`can_rise`)."""
        o = self.nextk > 0
        n = self.nextk[o]
        ahead = n <= k
        n[ahead] += -(-(k + 1 - n[ahead]) // self.sp) * self.sp
        self.nextk[o] = n

    def can_rise(self, highest: float, ka: int, kb: int) -> bool:
        """Whether terrain no higher than ``highest`` at samples ``ka``..``kb`` could raise the
        maximum of any open ray: highest - h0 > best * k for some such k, rounded as the march
        rounds (which also takes the curvature term, >= 0, off the lift: only lower)."""
        o = self.nextk > 0
        if not o.any() or highest == -np.inf:      # nothing open, or voids only
            return False
        best = self.best[o]
        h0 = self.h0[o].astype(np.float64) + self.lift     # as the march takes it
        kw = np.where(best >= 0.0, float(ka), float(kb))
        with np.errstate(invalid="ignore"):
            return bool(np.any(~((highest - h0) <= best * kw)))

    def angles(self, distance: np.ndarray | None = None) -> np.ndarray:
        """β of the region's cells (float32 degrees, NaN on voids, -90 with nothing ahead);
        ``distance`` (float32, the region's shape) receives the ground metres to the horizon
        point (NaN on voids and with nothing ahead)."""
        beta = np.empty(self.h0.shape, np.float32)
        _span_angles(self.h0, np.int64(self.region[0] - self.q0), self.rays.step_m, self.best,
                     self.kbest, beta, distance is not None,
                     np.empty((1, 1), np.float32) if distance is None else distance)
        return beta


# ---------------------------------------------------------------------------------------------
# horizon profiles at points (``hillshade-rt profile``)

@njit(cache=True)
def _profile_ray(z, r0, c0, h0, dom_col, sd, so, step_m, cv, zmax):
    """(tangent of the horizon angle, ground distance to the horizon point) of the ray from the
    point (row ``r0``, column ``c0``: fractional) at height ``h0`` along one direction (the
    rays of its row: dominant axis, step, step of the other index, metres per step, curvature
    per step²). The samples are where the ray crosses the grid lines of its dominant axis, at
    t = |line - origin| steps (t = 1, 2, ... from a cell centre: the scan's samples), the
    terrain interpolated on the line as the model does; (-inf, NaN) when nothing lies ahead."""
    rows, cols = z.shape
    if dom_col:
        o_dom, o_oth, n_dom, n_oth = c0, r0, cols, rows
    else:
        o_dom, o_oth, n_dom, n_oth = r0, c0, rows, cols
    if sd > 0:
        line = np.int64(math.floor(o_dom)) + 1
    else:
        line = np.int64(math.ceil(o_dom)) - 1
    best = -np.inf
    tbest = 0.0
    while 0 <= line < n_dom:
        t = abs(line - o_dom)
        pos = line_position(madd(o_oth, t, so), n_oth)
        if pos < 0.0:
            break
        if zmax - h0 <= best * t:          # no later sample can raise the maximum
            break
        v = terrain_on_line(z, dom_col, line, pos)
        lift = v - h0
        if cv != 0.0:
            lift = madd(lift, -t * t, cv)
        if lift > best * t:                  # NaN (void) compares false: skipped
            best = lift / t
            tbest = t
        line += sd
    if best == -np.inf:
        return -np.inf, np.nan
    return best / step_m, tbest * step_m


@njit(parallel=True, cache=True)
def _profile_kernel(z, rr, cc, hh, dom_col, sd, so, step_m, cv, zmax, tan_out, dist_out):
    """Every point (rows of ``rr``, ``cc``, ``hh``) along every direction (columns of the ray
    arrays, one ray per point and direction)."""
    n, m = tan_out.shape
    for i in prange(n):
        for j in range(m):
            tan_out[i, j], dist_out[i, j] = _profile_ray(
                z, rr[i], cc[i], hh[i], dom_col[i, j] != 0, np.int64(sd[i, j]), so[i, j],
                step_m[i, j], cv[i, j], zmax)


def profile(z: np.ndarray, rows: np.ndarray, cols: np.ndarray, heights: np.ndarray,
            rays_of: list[SunRays], zmax: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(angles in degrees, distances in metres), each (points, directions): the horizon of each
    point (fractional ``rows``, ``cols``; the observer at ``heights``) along the rays of each
    direction (``rays_of``: one ``SunRays`` per direction, each point taking the rays of its
    nearest row). -90 and NaN where nothing lies ahead inside the raster."""
    n, m = len(rows), len(rays_of)
    idx = np.clip(np.rint(rows).astype(np.int64), 0, z.shape[0] - 1)
    fields = [np.empty((n, m)) for _ in range(5)]
    for j, rays in enumerate(rays_of):
        for f, a in zip(fields, (rays.dom_col, rays.step_dom, rays.step_other, rays.step_m,
                                 rays.curv)):
            f[:, j] = a[idx]
    tan_out, dist_out = np.empty((n, m)), np.empty((n, m))
    if zmax is None:
        zmax = float(np.nanmax(z))
    _profile_kernel(z, np.asarray(rows, np.float64), np.asarray(cols, np.float64),
                    np.asarray(heights, np.float64), fields[0].astype(np.int8),
                    fields[1].astype(np.int64), fields[2], fields[3], fields[4], float(zmax),
                    tan_out, dist_out)
    with np.errstate(invalid="ignore"):
        angles = np.where(np.isneginf(tan_out), -90.0, np.degrees(np.arctan(tan_out)))
    return angles, dist_out


def bilinear(z: np.ndarray, r: float, c: float) -> float:
    """The height at fractional (row ``r``, column ``c``; cell centres at whole numbers),
    bilinear between the four centres around it (NaN beside a void or outside the centres)."""
    rows, cols = z.shape
    if not (0.0 <= r <= rows - 1 and 0.0 <= c <= cols - 1):
        return math.nan
    r0 = min(int(math.floor(r)), max(rows - 2, 0))
    c0 = min(int(math.floor(c)), max(cols - 2, 0))
    fr, fc = r - r0, c - c0
    q = z[r0:r0 + 2, c0:c0 + 2].astype(np.float64)
    if q.shape != (2, 2):
        return float(z[int(round(r)), int(round(c))])
    top = q[0, 0] + fc * (q[0, 1] - q[0, 0])
    bot = q[1, 0] + fc * (q[1, 1] - q[1, 0])
    return float(top + fr * (bot - top))
