"""``sweep``: the flag-map propagation ("Faster Ray Traced Terrain Shadow Maps" [1]_).

The tutorial's idea (an acceleration of the brute march of [2]_): process cells from the sun's side
and let every cell store what its own ray met, so that a later ray reaching an already visited cell
reuses that instead of marching on. What each cell stores here is the **left-over height** of its
ray, in absolute form: ``S``, the lowest height at the cell's position from which a ray toward the
sun clears every sample ahead (``S - h`` is the most by which the cell's own ray passes under the
terrain, negative when it clears; ``zfloor``, a height below the lowest cell, when it never meets
terrain). It obeys an exact recurrence along a ray:

    S(cell) = max( max_{k<=K} (T_k - k*rise) , S(K-th sample point) - K*rise )

where ``T_k`` are the model's samples on the next K grid lines toward the sun (marched exactly).
The K-th sample point lies between two cells of its line, whose ``S`` are already known: it is
interpolated linearly between them (the tutorial's interpolation of stored values). Only the last
K lines of ``S`` are kept (a ring buffer), not a flag map of the whole DEM. A cell is shadowed iff
``S > h`` (strict, as in the model).

**Unsure cells.** The two stored neighbours ``S_a``, ``S_b`` bracket the interpolated value. When
the decision would differ between them (``max(E, min(S_a,S_b) - K*rise) <= h <
max(E, max(S_a,S_b) - K*rise)``, E the exact part), the cell is near a shadow edge where the
interpolation can err: it is flagged and, after the sweep, decided by brute's exact march
(``brute.refine``; parallel). Elsewhere both neighbouring rays agree and so, almost always, does
the ray between them. The report gives the flagged share (``unsure_fraction``: 0 at high sun,
0.35-0.56 % at 3° on a 2048² fractal terrain with K = 8).

**Voids.** A void is a hole in the model: a ray through it meets no terrain there, while its
neighbours may pass beside it, so next to voids both neighbours can agree and still be wrong.
On a DEM with voids each cell also carries ``W``, the highest void-edge terrain its ray (and its
neighbours' rays) met, less its drop; where ``W > h`` that terrain is within reach and the cell
is unsure unless its K exact samples already shadow it. The cost is more refinement on
void-heavy DEMs (4-29 % of the cells on SRTM Everest, 0.2-0.7 % on New Zealand's nodata sea).

**Rays that differ per row** (geographic CRS; equirectangular and other projected grids whose
spacing is not uniform). A stored S is that of the ray of its own row, so a cell's S is really
computed along a chain of rays, K steps each with the geometry of the row where the block starts.
Two kinds of cells therefore go to the exact march (``_trusted_floor``, a height floor per row):
every cell of a row whose own dominant axis is not the frame's (toward the poles dx shrinks and a
sun from 163 deg moves more columns than rows per metre; re-expressed in the centre row's lines its
samples would not be the model's and would skip terrain: errors of up to 25-67 deg were measured),
and the cells whose chain drifts, within the reach of their own ray, more than ``DRIFT_CELLS``
sideways or ``DRIFT_RISE`` (relative) in height from it. Uniform rays never take this path.

Speed. With one ray direction for the raster (projected CRS) every cell of a line has the same
sample offsets and interpolation fractions, so each exact sample and the stored-value lookup is
one SIMD pass along a contiguous line buffer; the DEM is read and the mask written a block of
lines at a time (also when the lines are DEM columns). A line depends on the K lines before it,
but a cell only on cells at most K*s positions toward the sun: the positions are cut into one
strip per thread and the strips run as a wavefront (strip j one block of lines behind strip
j-1), in parallel. The refinement is parallel too. Rays that differ per row (geographic CRS)
take a per-cell kernel, parallel over the cells of a line.

Fixes of the published code: no restart of the inner loop at a wrong index (the loops run over
canonical lines and positions, ``frames``); no ±0.5 epsilon around an interpolated "never hit"
flag of -1 (``zfloor`` lies below every real height, so it interpolates without a special case,
and when one of the two stored values is ``zfloor``, i.e. that neighbour's ray met no terrain,
a valid cell marches on exactly instead, until its ray is above the highest cell); no square
root per pixel (the k-th sample is ``k`` steps on).

**Approximate.** On the axes and diagonals the K-th sample is a cell centre, nothing is
interpolated and ``sweep`` equals ``brute`` (tests). Elsewhere a cell is wrong only when both
neighbouring rays agree and the ray between them does not (a thin ridge between them).
Measured against ``brute`` on the real DEMs of the project: ``ERROR_SUMMARY`` below and
docs/algorithms.md. The bound (under 0.5 % of the cells, wrong cells within about 1 deg of the
sun) holds on per-row grids too: on a global lunar grid (equirectangular and lon/lat on the
1737.4 km sphere, 0.5 deg, +-88 deg, 9 suns) 0 wrong cells (before the per-row checks: 0.57 %,
2.97 % at the worst sun, 5.5 % at |lat| >= 80, up to 24.8 deg), on WGS84 60-85 N 0.006 %, worst
sun 0.055 %, 0.60 deg (before: 0.17 %, 1.34 %, 3.93 deg); tests/algorithms/test_sweep.py.

References
----------
.. [1] "Faster Ray Traced Terrain Shadow Maps," tutorial, Freeworld3D (no author or date given in
       the text).
.. [2] M. Marghidanu, "Fast Computation of Terrain Shadow Maps," GameDev.net, 2002.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from ..model.geometry import SunRays
from . import brute
from ._cuda import cuda, kernel
from ._jitcache import njit
from .counts import z_range
from .frames import frame_of, uniform_rays
from .raymath import line_position, madd, terrain_on_line

EXACT_STEPS = 8   # samples marched exactly before the stored values are used
UNSURE = 2        # mask code of a cell left to the exact refinement pass
MIN_STRIP = 256   # fewest positions per strip of the parallel wavefront
# Rays that differ per row: how far the chain of stored rays may drift from a cell's own ray before
# the cell goes to the exact march (``_trusted_floor``): sideways, in cells; in height, relative
# to the ray's own rise over the same steps.
DRIFT_CELLS = 1.0
DRIFT_RISE = 0.01

ERROR_SUMMARY = (
    "K=8 vs brute, 7 real DEMs x 8 suns (benchmarks/accuracy.py): mean 0.008-0.049 % of cells per "
    "DEM, worst sun 0.29 %; wrong cells within 1 deg of the sun elevation (largest 0.93 deg) "
    "except one cell at 1.04 deg on SRTM Everest; per-row grids (global lunar, WGS84 60-85 N): "
    "at most 0.055 % per sun, within 0.60 deg")


@njit(cache=True)
def _stored_pair(ring, row, x):
    """The two stored S bracketing position x of a ring-buffer row and the fraction between them
    (b = a when x is a cell centre)."""
    i0 = int(math.floor(x))
    f = x - i0
    a = ring[row, i0]
    b = a if f == 0.0 else ring[row, i0 + 1]
    return a, b, f


@njit(cache=True)
def _decide(S, lo, hi, h):
    """Mask code of a cell: 255 void, 1 / 0 when its two stored neighbours agree, UNSURE when the
    decision would flip between them (the refinement pass then marches it exactly). Written as
    selects, without branches, so that the line pass that calls it stays vectorised."""
    sh = np.uint8(1) if S > h else np.uint8(0)
    c = np.uint8(UNSURE) if (lo <= h and h < hi) else sh
    return np.uint8(255) if h != h else c


@njit(cache=True)
def _void_edge(line, i, P):
    """Highest valid height among cells i-1 .. i+2 of a line when one of them is a void (the
    terrain a ray beside this sample may see or miss because of the hole), else -inf."""
    hole = False
    m = -np.inf
    for j in range(max(0, i - 1), min(P, i + 3)):
        x = line[j]
        if x != x:
            hole = True
        elif x > m:
            m = x
    return m if hole else -np.inf


@njit(cache=True)
def _march_cell(Z, ring, wring, void, zfloor, zmax, v, p, s, rise, K):
    """(S, lo, hi, W) of canonical cell (v, p): K samples marched exactly, then the stored S of
    the K-th sample's neighbours, interpolated (S) and taken at either neighbour (lo, hi). A ray
    that leaves the raster within K samples is exact (lo = -inf, hi = S: never unsure).

    S is kept at or above ``zfloor`` (below every valid height, so no decision changes): a ray
    that met no terrain stores a finite value, which interpolates. When a stored neighbour holds
    ``zfloor`` (its ray met no terrain: the raster's far edge, or open sea) a valid cell marches
    on exactly instead, until its ray is above ``zmax`` (exact: never unsure); a void cell, whose
    S only serves its successors, interpolates.

    ``void`` (the DEM has voids): W is the highest void-edge terrain (``_void_edge``) met along
    the ray, less its drop, carried from the stored neighbours (``wring``) like S. Where W > h a
    hole within reach could make the ray between the neighbours differ from both, so unless the
    K exact samples already shadow the cell it is left unsure (lo = E, hi = inf)."""
    L, P = Z.shape
    R = ring.shape[0]
    h = Z[v, p]
    S = zfloor
    W = -np.inf
    k = 1
    march_on = False
    while (k <= K or (march_on and madd(zmax, -float(k), rise) > S)) and v + k < L:
        x = line_position(madd(float(p), float(k), s), P)
        if x < 0.0:
            break
        # x - k*rise is written madd(x, -k, rise): the same number, never fused on a GPU
        t = madd(terrain_on_line(Z, False, v + k, x), -float(k), rise)
        if t > S:   # NaN (void) compares false
            S = t
        if void:
            w = madd(_void_edge(Z[v + k], int(math.floor(x)), P), -float(k), rise)
            W = w if w > W else W
        if k == K:
            a, b, f = _stored_pair(ring, (v + k) % R, x)
            if (a == zfloor or b == zfloor) and h == h:
                march_on = True
            else:
                lo = max(S, madd(min(a, b), -float(k), rise))
                hi = max(S, madd(max(a, b), -float(k), rise))
                E = S
                S = max(E, madd(madd(a, f, b - a), -float(k), rise))
                if void:
                    wa, wb, _ = _stored_pair(wring, (v + k) % R, x)
                    W = max(W, madd(max(wa, wb), -float(k), rise))
                    if W > h:
                        lo = E
                        hi = np.inf
                return S, lo, hi, W
        k += 1
    return S, -np.inf, S, W


@njit(cache=True)
def _line_pass(ZL, VE, ring, wring, void, zfloor, zmax, T, ol, d, fr, v, K, rise, p0, n, Z,
               s):
    """Positions p0 <= p < p0 + n of line v (all inside the line: K samples and both stored
    neighbours): K exact sample passes, the stored-value pass, the decision pass. ``ZL``, ``VE``
    (void edges), ``ring`` (S) and ``wring`` (W) are ring buffers, row ``v % R``; the rows of
    ``T`` (E, LO, HI, W work arrays) and ``ol`` are indexed from p0. Same codes as
    ``_march_cell`` cell by cell."""
    R = ring.shape[0]
    row = v % R
    e = T[0, :n]
    LO = T[1, :n]
    HI = T[2, :n]
    w = T[3, :n]
    e[:] = zfloor
    w[:] = -np.inf
    for k in range(1, K + 1):
        dk = p0 + d[k]
        f = fr[k]
        kr = k * rise
        za = ZL[(v + k) % R, dk:dk + n]
        if f == 0.0:
            for p in range(n):
                t = za[p] - kr
                e[p] = t if t > e[p] else e[p]   # NaN (void) compares false
        else:
            zb = ZL[(v + k) % R, dk + 1:dk + 1 + n]
            for p in range(n):
                t = za[p] + f * (zb[p] - za[p]) - kr
                e[p] = t if t > e[p] else e[p]
        if void:
            ve = VE[(v + k) % R, dk:dk + n]
            for p in range(n):
                t = ve[p] - kr
                w[p] = t if t > w[p] else w[p]
    dK = p0 + d[K]
    fK = fr[K]
    rK = K * rise
    sa = ring[(v + K) % R, dK:dK + n]
    sb = ring[(v + K) % R, dK + 1:dK + 1 + n] if fK > 0.0 else sa
    srow = ring[row, p0:p0 + n]
    for p in range(n):
        a = sa[p]
        b = sb[p]
        t = a + fK * (b - a) - rK
        srow[p] = t if t > e[p] else e[p]
        t = min(a, b) - rK
        LO[p] = t if t > e[p] else e[p]
        t = max(a, b) - rK
        HI[p] = t if t > e[p] else e[p]
    zl = ZL[row, p0:p0 + n]
    wrow = wring[row, p0:p0 + n]
    if void:
        wa = wring[(v + K) % R, dK:dK + n]
        wb = wring[(v + K) % R, dK + 1:dK + 1 + n] if fK > 0.0 else wa
        for p in range(n):
            t = max(wa[p], wb[p]) - rK
            wrow[p] = t if t > w[p] else w[p]
            hole = wrow[p] > zl[p]
            LO[p] = e[p] if hole else LO[p]
            HI[p] = np.inf if hole else HI[p]
    for p in range(n):
        if (sa[p] == zfloor or sb[p] == zfloor) and zl[p] == zl[p]:   # rare: see _march_cell
            srow[p], LO[p], HI[p], wrow[p] = _march_cell(Z, ring, wring, void, zfloor, zmax, v,
                                                         p0 + p, s, rise, K)
    for p in range(n):
        ol[p] = _decide(srow[p], LO[p], HI[p], zl[p])


@njit(cache=True)
def _dem_index(i, n, flip):
    return n - 1 - i if flip else i


@njit(cache=True)
def _line_slots(v, nb, R, L, flip_line):
    """Ring row and DEM column of canonical lines v, v-1, ..., v-nb+1 (lines that are DEM
    columns), worked out once per block for ``load_lines`` and ``store_lines``."""
    rows = np.empty(nb, np.int64)
    cols = np.empty(nb, np.int64)
    for i in range(nb):
        rows[i] = (v - i) % R
        cols[i] = _dem_index(v - i, L, flip_line)
    return rows, cols


@njit(cache=True)
def load_lines(z, ring, v, nb, p0, p1, dom_col, flip_line, flip_pos):
    """Copy canonical lines v, v-1, ..., v-nb+1 at positions [p0, p1) of the DEM-shaped array
    ``z`` into the ring rows ``(v - i) % R`` of ``ring``. Lines that are DEM columns go position
    by position, so that each DEM row is touched once per block, contiguously. ``z`` is only
    read (the caller's heights may be read-only: a memory map, ``setflags(write=False)``); its
    twin ``store_lines`` writes the mask, so that no kernel has a store into ``z``."""
    R = ring.shape[0]
    if dom_col:
        P, L = z.shape
        rows, cols = _line_slots(v, nb, R, L, flip_line)
        for p in range(p0, p1):
            r = _dem_index(p, P, flip_pos)
            for i in range(nb):
                ring[rows[i], p] = z[r, cols[i]]
    else:
        L, P = z.shape
        for i in range(nb):
            r = _dem_index(v - i, L, flip_line)
            dst = ring[(v - i) % R]
            if flip_pos:
                for p in range(p0, p1):
                    dst[p] = z[r, P - 1 - p]
            else:
                for p in range(p0, p1):
                    dst[p] = z[r, p]


@njit(cache=True)
def store_lines(out, ring, v, nb, p0, p1, dom_col, flip_line, flip_pos):
    """The inverse of ``load_lines``: ring rows of lines v, ..., v-nb+1 at positions [p0, p1)
    into the DEM-shaped array ``out`` (the mask)."""
    R = ring.shape[0]
    if dom_col:
        P, L = out.shape
        rows, cols = _line_slots(v, nb, R, L, flip_line)
        for p in range(p0, p1):
            r = _dem_index(p, P, flip_pos)
            for i in range(nb):
                out[r, cols[i]] = ring[rows[i], p]
    else:
        L, P = out.shape
        for i in range(nb):
            r = _dem_index(v - i, L, flip_line)
            src = ring[(v - i) % R]
            if flip_pos:
                for p in range(p0, p1):
                    out[r, P - 1 - p] = src[p]
            else:
                for p in range(p0, p1):
                    out[r, p] = src[p]


@njit(cache=True)
def _strip_block(z, Z, RZ, RS, RO, void, zfloor, zmax, T, d, fr, v_top, nb, p0, p1, n_in,
                 dom_col, flip_line, flip_pos, s, rise, K, out):
    """Lines v_top, ..., v_top-nb+1, positions [p0, p1): load, sweep, store. RZ holds the ring
    buffers of heights and void edges, RS those of S and W, RO that of the mask codes."""
    L, P = Z.shape
    ZL, VE, ring, wring = RZ[0], RZ[1], RS[0], RS[1]
    R = ring.shape[0]
    # one position more on the near side for the void edges (same values as the next strip's)
    load_lines(z, ZL, v_top, nb, max(0, p0 - 1), p1, dom_col, flip_line, flip_pos)
    if void:
        for i in range(nb):
            row = (v_top - i) % R
            for p in range(p0, p1):
                VE[row, p] = _void_edge(ZL[row], p, P)
    for i in range(nb):
        v = v_top - i
        row = v % R
        q = max(p0, min(p1, n_in)) if v + K < L else p0   # cells [p0, q) take the line passes
        if q > p0:
            _line_pass(ZL, VE, ring, wring, void, zfloor, zmax, T, RO[row, p0:q], d, fr, v, K,
                       rise, p0, q - p0, Z, s)
        for p in range(q, p1):
            S, lo, hi, w = _march_cell(Z, ring, wring, void, zfloor, zmax, v, p, s, rise, K)
            ring[row, p] = S
            wring[row, p] = w
            RO[row, p] = _decide(S, lo, hi, ZL[row, p])
    store_lines(out, RO, v_top, nb, p0, p1, dom_col, flip_line, flip_pos)


@njit(cache=True)
def strip_bounds(P, NS):
    """Strip j of the wavefront covers positions [out[j+1], out[j]) (strip 0 at the far end of
    the lines, the sun's side of the positions)."""
    out = np.empty(NS + 1, np.int64)
    for j in range(NS + 1):
        out[j] = P - (j * P) // NS
    return out


@njit(cache=True, inline="always")
def wave_block(t, j, L, B):
    """(v_top, nb) of the block of lines strip j sweeps at step t of the wavefront: lines
    v_top .. v_top-nb+1 from the sun's edge, strip j one block behind strip j-1; nb = 0 when
    strip j has no block at that step. Steps run over range(wave_steps(L, B, NS))."""
    b = t - j
    if b < 0 or b >= (L + B - 1) // B:
        return np.int64(0), np.int64(0)
    v_top = L - 1 - b * B
    return np.int64(v_top), np.int64(min(B, v_top + 1))


@njit(cache=True, inline="always")
def wave_steps(L, B, NS):
    return (L + B - 1) // B + NS - 1


@njit(parallel=True, cache=True)
def _sweep_uniform(z, Z, dom_col, flip_line, flip_pos, s, rise, K, nstrips, void, zfloor,
                   zmax, out):
    """One ray direction for the whole raster: every cell of a line has the same sample offsets,
    so each of the K exact samples and the stored-value lookup is one pass along the line with a
    constant interpolation fraction, over contiguous line buffers (SIMD). ``z`` and ``out`` are
    the DEM-shaped arrays; ``Z`` is the canonical view of ``z`` for the few cells that take
    ``_march_cell`` (samples running off the far end of the line, the K lines at the sun's edge).
    ``void``: the DEM has voids (track W, see ``_march_cell``).

    Parallel as a wavefront: the positions are cut into ``nstrips`` strips, strip 0 at the far
    end of the lines (positions grow toward the sun, so a cell depends only on its own strip and
    the next one toward strip 0, as long as a strip is wider than the K-th sample's offset). The
    lines are cut into blocks of B >= K lines; at step t strip j does block t - j, so the lines
    it reads from strip j - 1 were finished a step earlier. Each strip reads its heights from and
    writes its mask to the DEM-shaped arrays a block at a time."""
    L, P = Z.shape
    B = max(32, K)                    # lines per block (>= K: the lag between strips suffices)
    NS = nstrips
    R = NS * B + K + 1                # ring rows: every line in flight plus K lines ahead
    W = P + 17                        # padded rows: power-of-two rows filled column-wise
    RS = np.full((2, R, W), -np.inf)  # would share cache sets. S and W
    RZ = np.empty((2, R, W))          # heights (float64, canonical order) and void edges
    RO = np.empty((R, W), np.uint8)   # mask codes
    d = np.empty(K + 1, np.int64)
    fr = np.empty(K + 1)
    for k in range(1, K + 1):
        d[k] = int(math.floor(k * s))
        fr[k] = k * s - d[k]
    # positions whose K samples and both stored neighbours lie inside the line
    n_in = max(0, P - d[K] - (1 if fr[K] > 0.0 else 0))
    bounds = strip_bounds(P, NS)
    wmax = P // NS + 1
    T = np.empty((NS, 4, wmax))            # per strip: E, LO, HI, W of a line
    for t in range(wave_steps(L, B, NS)):
        for jj in prange(NS):
            j = np.int64(jj)
            v_top, nb = wave_block(t, j, L, B)
            if nb > 0:
                _strip_block(z, Z, RZ, RS, RO, void, zfloor, zmax, T[j], d, fr, v_top, nb,
                             bounds[j + 1], bounds[j], n_in, dom_col, flip_line, flip_pos,
                             s, rise, K, out)


@njit(cache=True, inline="always")
def _sweep_cell(Z, ring, wring, void, zfloor, zmax, v, p, s_arr, rise_arr, hmin_arr, per_line, K,
                out):
    """Canonical cell (v, p) with its own row's ray (``s_arr``/``rise_arr``/``hmin_arr`` indexed
    by line or by position): S and W into the rings, the code into ``out``. A cell lower than
    its row's ``hmin_arr`` (``_trusted_floor``: its ray reaches rows whose rays differ too much
    from its own) is left unsure, i.e. to the exact march. The per-cell body of both backends."""
    v = np.int64(v)   # prange / grid indices may be unsigned; keep integer arithmetic integral
    p = np.int64(p)
    i = v if per_line else p
    S, lo, hi, w = _march_cell(Z, ring, wring, void, zfloor, zmax, v, p, s_arr[i], rise_arr[i], K)
    row = v % ring.shape[0]
    ring[row, p] = S
    wring[row, p] = w
    h = Z[v, p]
    if h < hmin_arr[i]:
        lo = -np.inf
        hi = np.inf
    out[v, p] = _decide(S, lo, hi, h)


@njit(parallel=True, cache=True)
def _sweep_lines(Z, s_arr, rise_arr, hmin_arr, per_line, K, void, zfloor, zmax, out):
    """Rays that differ from row to row (geographic CRS): lines from the sun's edge, the cells of
    a line in parallel, each through ``_march_cell`` with its own row's ray."""
    L, P = Z.shape
    RS = np.full((2, K + 1, P), -np.inf)
    ring, wring = RS[0], RS[1]
    for v in range(L - 1, -1, -1):
        for p in prange(P):
            _sweep_cell(Z, ring, wring, void, zfloor, zmax, v, p, s_arr, rise_arr, hmin_arr,
                        per_line, K, out)


@kernel
def _sweep_gpu(Z, ring, wring, void, zfloor, zmax, v_top, nlines, s_arr, rise_arr, hmin_arr,
               per_line, K, out):
    """CUDA: lines v_top, ..., v_top - nlines + 1 (nlines <= K) at once, one thread per cell. A
    line reads the stored S of the line K before it only, so K consecutive lines are independent;
    the rings hold 2K lines (those written, those read)."""
    p, i = cuda.grid(2)
    if i < nlines and p < Z.shape[1]:
        _sweep_cell(Z, ring, wring, void, zfloor, zmax, v_top - i, p, s_arr, rise_arr, hmin_arr,
                    per_line, K, out)


def _per_cell_rays(rays: SunRays):
    """Frame of the centre row, and s / rise of every row expressed in that frame, indexed by the
    canonical index that runs over the DEM's rows (lines when lines are rows, else positions;
    ``per_line`` says which).

    With per-row spacing (geographic CRS) each row keeps its own direction; a row whose own
    dominant axis differs (sun near a diagonal) is re-expressed in the frame's axis (|s| > 1)."""
    f = frame_of(rays, len(rays.rise) // 2)
    same = rays.dom_col.astype(bool) == f.dom_col
    so = np.abs(rays.step_other)
    s = np.where(same, so, 1.0 / np.maximum(so, 1e-300)).astype(np.float64)
    rise = np.where(same, rays.rise, rays.rise / np.maximum(so, 1e-300)).astype(np.float64)
    per_line = not f.dom_col
    if f.flip_line if per_line else f.flip_pos:
        s, rise = s[::-1].copy(), rise[::-1].copy()
    return f, s, rise, per_line


@njit(cache=True)
def _trusted_floor(s_arr, rise_arr, per_line, K, zmin, zmax, shift, rtol):
    """Per canonical index over the DEM's rows (``_per_cell_rays``): the lowest height from
    which a cell there may use the stored values; a lower cell goes to the exact march.

    A stored S is that of the ray of *its* row. Where the rays differ per row (geographic and
    equirectangular grids: s and rise follow 1/cos(lat) or cos(lat)), a cell's S is in effect
    computed along a chain of rays, K steps each with the geometry of the row where that block
    starts: a path that drifts sideways from the cell's own straight ray by the sum of
    K * |s_row - s| and whose height drifts by the sum of K * |rise_row - rise|. Walking the
    chain block by block (the rows it may touch: those of the stored neighbours, widened by the
    drift so far), the chain is trusted for the first m steps while the sideways drift stays
    within ``shift`` cells and the height drift within ``rtol`` of the ray's own rise over those
    steps. A cell whose ray clears ``zmax`` within those m steps decides nothing beyond them
    (every later sample of the chain is lower than zmax less the chain's rise, itself at least
    m * rise less the drift): such cells are trusted. Where the chain leaves the raster or the
    lowest cell's ray clears ``zmax`` within the trusted steps, the floor is -inf. A row whose
    own dominant axis is the other one (s > 1 once re-expressed) gets +inf: all its cells are
    marched exactly. Cost: at most (zmax - zmin) / (K * rise) blocks per row. Uniform rays
    (one ray for the raster) never come here."""
    n = len(s_arr)
    out = np.full(n, -np.inf)
    for i in range(n):
        s0 = s_arr[i]
        r0 = rise_arr[i]
        if s0 > 1.0:
            # the row's own dominant axis is the other one (``_per_cell_rays``): re-expressed in
            # the frame's lines, its K "exact" samples would not be the model's (more than one
            # position per line: terrain between the lines is never sampled). All exact.
            out[i] = np.inf
            continue
        need = (zmax - zmin) / r0   # steps after which even the lowest cell's ray is clear
        ds = 0.0
        dr = 0.0
        b = 1
        while b * K < need:
            if per_line:      # block b: lines i + b*K on, with the geometry of line i + b*K
                q0 = i + b * K
                q1 = q0
                if q0 >= n:
                    break     # the chain left the raster: nothing beyond it
            else:             # positions around i + b*K*s0, with those rows' geometry
                x = i + b * K * s0
                q0 = int(math.floor(x - ds))
                q1 = int(math.floor(x + ds)) + 1
                if q0 > n - 1:
                    break
                q0 = max(q0, 0)
                q1 = min(q1, n - 1)
            es = 0.0
            er = 0.0
            for q in range(q0, q1 + 1):
                es = max(es, abs(s_arr[q] - s0))
                er = max(er, abs(rise_arr[q] - r0))
            if ds + K * es > shift or dr + K * er > rtol * (b + 1) * K * r0:
                out[i] = zmax - b * K * r0 + dr
                break
            ds += K * es
            dr += K * er
            b += 1
    return out


def strip_count(P: int, s: float, K: int, slack: int = 2, min_strip: int = MIN_STRIP) -> int:
    """How many strips the wavefront cuts a line of P positions into: one per thread, each at
    least ``min_strip`` positions and wider than the K-th sample's reach (plus ``slack``)."""
    return max(1, min(numba.get_num_threads(),
                      P // max(min_strip, int(math.ceil(K * s)) + slack)))


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None,
                stats: dict | None = None, exact_steps: int = EXACT_STEPS,
                pyramid=True) -> np.ndarray:
    """Shadow mask by the flag-map sweep: uint8 1 shadow / 0 lit / 255 void. ``pyramid``: for
    the exact march of the unsure cells (as ``brute.refine``)."""
    out = np.empty(z.shape, np.uint8)
    if not math.isfinite(float(rays.rise[0])):   # sun at the zenith
        out[...] = np.where(np.isnan(z), 255, 0)
        return out
    K = np.int64(max(1, int(exact_steps)))
    zmin, zhi, void = z_range(z)
    if not math.isfinite(zmin):   # nothing but voids
        out[...] = 255
        return out
    zfloor = float(zmin) - 1.0    # below every valid height
    zmax = float(zhi) if zmax is None else float(zmax)
    if uniform_rays(rays):
        f = frame_of(rays)
        _sweep_uniform(z, f.view(z), f.dom_col, f.flip_line, f.flip_pos, f.s, f.rise, K,
                       strip_count(z.shape[0] if f.dom_col else z.shape[1], f.s, int(K)), void,
                       zfloor, zmax, out)
    else:
        f, s, rise, per_line = _per_cell_rays(rays)
        hmin = _trusted_floor(s, rise, per_line, K, float(zmin), zmax, DRIFT_CELLS, DRIFT_RISE)
        _sweep_lines(f.view(z), s, rise, hmin, per_line, K, void, zfloor, zmax, f.view(out))
    unsure = brute.refine(z, rays, out, UNSURE, zmax, pyramid)
    if stats is not None:
        stats["unsure_fraction"] = unsure / max(1, out.size)
    return out


def shadow_mask_gpu(g, rays: SunRays, zmax: float, stats: dict | None = None,
                    exact_steps: int = EXACT_STEPS) -> np.ndarray:
    """``shadow_mask`` on the GPU (``g``: a ``gpu.GpuDem``): the per-cell form of the sweep, K
    lines per launch from the sun's edge, then brute's exact kernel on the unsure cells. Same
    codes as the CPU's line passes (the line pass equals ``_march_cell`` cell by cell)."""
    from ._cuda import grid_2d
    rows, cols = g.shape
    if not math.isfinite(float(rays.rise[0])) or not math.isfinite(g.zmin):
        return brute.shadow_mask_gpu(g, rays, zmax)   # sun at the zenith, or nothing but voids
    K = max(1, int(exact_steps))
    if uniform_rays(rays):
        f = frame_of(rays)
        L = cols if f.dom_col else rows
        s, rise, per_line = np.full(L, f.s), np.full(L, f.rise), True
        hmin = np.full(L, -np.inf)
    else:
        f, s, rise, per_line = _per_cell_rays(rays)
        hmin = _trusted_floor(s, rise, per_line, np.int64(K), float(g.zmin), float(zmax),
                              DRIFT_CELLS, DRIFT_RISE)
    L, P = (cols, rows) if f.dom_col else (rows, cols)
    d_s, d_rise, d_hmin = g.upload(s), g.upload(rise), g.upload(hmin)
    rays_d = g.rays(rays)
    R = 2 * K
    rings = g.upload(np.full((2, R, P), -np.inf))
    outc = g.empty((L, P), np.uint8)
    out = g.empty((rows, cols), np.uint8)
    zfloor = g.zmin - 1.0
    with g.timed():
        Zc = g.canonical(f)
        for v_top in range(L - 1, -1, -K):
            n = min(K, v_top + 1)
            blocks, threads = grid_2d(n, P, (128, 1))
            _sweep_gpu[blocks, threads, g.stream](Zc, rings[0], rings[1], g.void, zfloor,
                                                  float(zmax), np.int64(v_top), np.int64(n),
                                                  d_s, d_rise, d_hmin, per_line, np.int64(K),
                                                  outc)
        from . import frames
        g.launch(frames.canonical_copy_gpu, L, P, out, outc, f.dom_col, f.flip_line, f.flip_pos,
                 False)
        unsure = brute.refine_gpu(g, rays_d, out, UNSURE, zmax)
    if stats is not None:
        stats["unsure_fraction"] = unsure / max(1, rows * cols)
    return g.download(out)
