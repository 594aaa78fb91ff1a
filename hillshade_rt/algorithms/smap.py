"""``smap``: Sakalauskas' hybrid terrain shadow ray casting [1]_, exact on the model.

The idea: along a ray, the terrain-minus-ray difference ``g_k`` reaches its maximum at a
*silhouette* sample (higher than the ray's previous sample by more than the rise per step, and not
lower than the next one minus the rise). A ray is blocked iff that maximum is positive, so only
silhouette samples need checking. Rays are grouped in **beams** of unit cross-section along the
sun direction; an **SMap** element (beam, line) is **Black** when some ray of the beam has a
silhouette on that line, and **NextV** points each element to the nearest Black line of its beam
toward the sun. A cell's ray then jumps Black to Black (``IsShadowed``) instead of marching line by
line.

Exactness (the model of docs/model.md, cell for cell equal to ``brute``):

* The paper tests five positions of the cross-section (``a, b, C1u, C0u+Lu, C2u-Lu``). That is not
  always enough: between two break points both silhouette inequalities are linear in the position
  and can hold together only in the middle. Here every break point is tested as a point (with the
  model's own sampling, which matters next to voids and on the axes, where rays pass exactly
  through cell centres) and every open piece between break points conservatively (each inequality
  satisfied at one of its ends). Black is thus a superset of the true silhouettes, which costs a
  little time and never a wrong answer.
* The silhouette test uses ``>`` toward the ray's start and ``>=`` toward the sun (the first sample
  where ``g`` peaks), and treats a void or the raster's edge as no terrain, as the model does.
* Beams are widened by ``WIDEN`` (1e-6 cell) on both sides and the inequalities get a tolerance of
  1e-7 of the height range, so that rounding in ``start + k*step`` can never put a ray in a beam
  that misses its silhouette.
* The final comparison at a Black sample is ``brute``'s own code (``raymath``) with the same
  arguments, so the two masks agree bit for bit (tests: hypothesis, real DEMs, analytic boxes).

NextV, three ways that give identical tables (tests):

* ``scan`` (default): one sweep from the sun's edge, line by line; ``NextV[v] = v+1`` if that
  element is Black, else ``NextV[v+1]`` of the same beam. O(1) per element, cache friendly.
* ``binary``: the paper's log-step search, per beam, doubling the block size ``DIST`` each pass.
* ``quad``: the paper's variant merging four blocks per pass (half the passes).

``better_nextv`` (the paper's section 9): after a Black sample is found unblocked, skip the later
Black samples of the beam that it hides: ``max`` height of the later element minus its ray rise is
at most the ``min`` height of this one minus its rise, so if this sample did not block, they cannot.
Computed with a monotone stack per beam; exact; measured in docs/benchmarks.md.

Rays must be the same for every row (one sun direction in pixel units: projected CRSs, raw grids).
With per-row spacing (geographic CRSs) the beams of different rows do not coincide; ``shadow_mask``
then marches each cell's ray like ``brute`` and says so in ``stats["note"]``.

References
----------
.. [1] T. Sakalauskas, "Hybrid Terrain Shadow Ray Casting," in WSCG 2008 Communication Papers, 16th
       Int. Conf. in Central Europe on Computer Graphics, Visualization and Computer Vision, Plzeň:
       UNION Agency, pp. 175-182, 2008.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..errors import HillshadeError
from ..model.geometry import Grid, SunRays, heights_and_grid, sun_rays
from ._cuda import cuda, kernel
from ._jitcache import njit
from .frames import Frame, frame_of, reach, uniform_rays
from .pyramid import NO_PYRAMID, climb, pyramid_args, samples_left
from .raymath import line_position, madd, ray_origin, terrain_on_line

WIDEN = 1e-6        # beams are widened by this much (cells) on both sides
_BLOCK = 256        # elements per parallel work item in the Black pass
NEXTV_METHODS = ("scan", "binary", "quad")
PYRAMID_REACH = 32  # the jump loop takes the pyramid when rays may run this many steps or more
PYRAMID_BLACK = 0.03  # ... and this share of the elements or more is Black


# why the rays differ from row to row (the note of a run that could not share one ray)
PER_ROW_SPACING = ("the ground spacing varies per row (a geographic CRS, or a "
                   "projection whose scale changes across the raster, as lunar polar "
                   "stereographic DEMs)")


def tolerance(zabs: float, rise: float) -> float:
    """Slack of the silhouette inequalities for heights up to ``zabs`` in magnitude: 1e-7 of the
    height range, so that rounding never turns a silhouette White."""
    return 1e-7 * (1.0 + zabs + rise)


# ------------------------------------------------------------------------------------------
# pass 0: colour (Black = some ray of the beam may peak here)

@njit(cache=True)
def _pt(Z, v, x, P):
    """Model sample on canonical line v at position x (NaN: void or outside)."""
    x = line_position(x, P)
    if x < 0.0:
        return np.nan
    return terrain_on_line(Z, False, v, x)


@njit(cache=True)
def _point_peaks(Z, v, x, s, rise, tol, has_prev, has_next):
    P = Z.shape[1]
    cur = _pt(Z, v, x, P)
    if math.isnan(cur):
        return False
    if has_prev:
        pv = _pt(Z, v - 1, x - s, P)
        if not math.isnan(pv) and not (cur - pv - rise > -tol):
            return False
    if has_next:
        nv = _pt(Z, v + 1, x + s, P)
        if not math.isnan(nv) and not (cur - nv + rise > -tol):
            return False
    return True


@njit(cache=True)
def _piece_may_peak(Z, v, l, r, s, rise, tol, has_prev, has_next):
    """Conservative test on the open piece (l, r), where all three lines are linear."""
    P = Z.shape[1]
    mid = 0.5 * (l + r)
    j = int(math.floor(mid))
    if j < 0 or j > P - 2:
        return False
    a = float(Z[v, j])
    b = float(Z[v, j + 1])
    if math.isnan(a) or math.isnan(b):
        return False
    cl = a + (l - j) * (b - a)
    cr = a + (r - j) * (b - a)
    if has_prev:
        jp = int(math.floor(mid - s))
        if jp >= 0 and jp <= P - 2:
            a2 = float(Z[v - 1, jp])
            b2 = float(Z[v - 1, jp + 1])
            if not (math.isnan(a2) or math.isnan(b2)):
                pl = a2 + (l - s - jp) * (b2 - a2)
                pr = a2 + (r - s - jp) * (b2 - a2)
                if not (max(cl - pl, cr - pr) - rise > -tol):
                    return False
    if has_next:
        jn = int(math.floor(mid + s))
        if jn >= 0 and jn <= P - 2:
            a2 = float(Z[v + 1, jn])
            b2 = float(Z[v + 1, jn + 1])
            if not (math.isnan(a2) or math.isnan(b2)):
                nl = a2 + (l + s - jn) * (b2 - a2)
                nr = a2 + (r + s - jn) * (b2 - a2)
                if not (max(cl - nl, cr - nr) + rise > -tol):
                    return False
    return True


@njit(cache=True)
def _section(e, fv, P):
    """Widened cross-section of element e on a line with fraction fv, clipped to the raster."""
    xa = e - 2 + fv - WIDEN
    xb = e - 1 + fv + WIDEN
    if xa < 0.0:
        xa = 0.0
    if xb > P - 1:
        xb = float(P - 1)
    return xa, xb


@njit(cache=True)
def _span(Z, v, xa, xb):
    """(min, max, complete) of the cells of line v under [xa, xb]; complete is False when a void
    or the raster's edge lies under it (then a ray there may have no sample on this line)."""
    P = Z.shape[1]
    j0 = int(math.floor(xa))
    j1 = int(math.ceil(xb))
    complete = True
    if j0 < 0:
        j0 = 0
        complete = False
    if j1 > P - 1:
        j1 = P - 1
        complete = False
    lo = np.inf
    hi = -np.inf
    for j in range(j0, j1 + 1):
        h = float(Z[v, j])
        if math.isnan(h):
            complete = False
        else:
            lo = min(lo, h)
            hi = max(hi, h)
    return lo, hi, complete


@njit(cache=True)
def _is_black(Z, v, e, s, fv, rise, tol, bp):
    L, P = Z.shape
    xa, xb = _section(e, fv, P)
    if xa > xb:
        return False
    has_prev = v > 0
    has_next = v < L - 1
    # quick rejection by cell bounds: interpolated samples lie between their cells' extremes
    lo_c, hi_c, full_c = _span(Z, v, xa, xb)
    if hi_c == -np.inf:
        return False
    full_p = True
    full_n = True
    if has_prev:
        lo_p, _, full_p = _span(Z, v - 1, xa - s, xb - s)
        if full_p and not (hi_c - lo_p - rise > -tol):
            return False
    if has_next:
        lo_n, _, full_n = _span(Z, v + 1, xa + s, xb + s)
        if full_n and not (hi_c - lo_n + rise > -tol):
            return False
    bp[0] = xa
    bp[1] = xb
    n = 2
    for j in range(int(math.ceil(xa)), int(math.floor(xb)) + 1):
        bp[n] = j
        n += 1
    if has_prev:   # kinks of the previous line: x - s integer
        for j in range(int(math.ceil(xa - s)), int(math.floor(xb - s)) + 1):
            bp[n] = min(max(j + s, xa), xb)
            n += 1
    if has_next:   # kinks of the next line: x + s integer
        for j in range(int(math.ceil(xa + s)), int(math.floor(xb + s)) + 1):
            bp[n] = min(max(j - s, xa), xb)
            n += 1
    for i in range(1, n):  # insertion sort of at most 8 break points
        x = bp[i]
        k = i - 1
        while k >= 0 and bp[k] > x:
            bp[k + 1] = bp[k]
            k -= 1
        bp[k + 1] = x
    pieces = 0
    for i in range(n - 1):
        if bp[i + 1] > bp[i]:
            pieces += 1
            if _piece_may_peak(Z, v, bp[i], bp[i + 1], s, rise, tol, has_prev, has_next):
                return True
    # Points need their own test only where the pieces do not cover them: next to a void or the
    # raster's edge (a sample exactly on a cell centre uses that cell alone), or no piece at all.
    if pieces > 0 and full_c and full_p and full_n:
        return False
    for i in range(n):
        if _point_peaks(Z, v, bp[i], s, rise, tol, has_prev, has_next):
            return True
    return False


@njit(cache=True)
def _line_pieces(s, fv, oc, op, on, fr):
    """The pieces of every cross-section of a line, relative to its element index.

    On a line with fraction ``fv`` each element's section is ``e - 2 + fv + t`` for t in
    [-WIDEN, 1 + WIDEN], and the kinks of the three lines fall at the same ``t`` for every element.
    For piece i: cell pairs start at ``e + oc[i]`` (this line), ``e + op[i]`` (previous line),
    ``e + on[i]`` (next line); ``fr[i, 0:6]`` are the fractions at the piece's two ends within those
    pairs. Returns the number of pieces."""
    tb = np.empty(11)
    tb[0] = -WIDEN
    tb[1] = 1.0 + WIDEN
    n = 2
    for base in (-fv, s - fv, -s - fv):
        k0 = base - math.floor(base)
        for t in (k0 - 1.0, k0, k0 + 1.0):
            if t > -WIDEN and t < 1.0 + WIDEN:
                tb[n] = t
                n += 1
    tb[:n].sort()
    m = 0
    for i in range(n - 1):
        tl = tb[i]
        tr = tb[i + 1]
        if tr <= tl:
            continue
        tm = 0.5 * (tl + tr)
        for q, sh in enumerate((0.0, -s, s)):
            fl = math.floor(fv + tm + sh)
            off = int(fl) - 2
            if q == 0:
                oc[m] = off
            elif q == 1:
                op[m] = off
            else:
                on[m] = off
            fr[m, 2 * q] = fv + tl + sh - fl
            fr[m, 2 * q + 1] = fv + tr + sh - fl
        m += 1
    return m


@njit(cache=True)
def _pair_at(Z, v, j, fl, frr):
    """Values at two fractions of the pair (j, j+1) of line v; ok False if outside or void."""
    P = Z.shape[1]
    if j < 0 or j > P - 2:
        return False, 0.0, 0.0
    a = float(Z[v, j])
    b = float(Z[v, j + 1])
    if math.isnan(a) or math.isnan(b):
        return False, 0.0, 0.0
    return True, a + fl * (b - a), a + frr * (b - a)


@njit(cache=True)
def _is_black_fast(Z, v, e, rise, tol, npc, oc, op, on, fr, has_prev, has_next):
    """PlannedWindow test with the line's precomputed pieces. Returns 1 Black, 0 White, -1 undecided (a
    pair is outside the raster or void: the general test must decide)."""
    for i in range(npc):
        ok, cl, cr = _pair_at(Z, v, e + oc[i], fr[i, 0], fr[i, 1])
        if not ok:
            return -1
        peak = True
        if has_prev:
            ok, pl, pr = _pair_at(Z, v - 1, e + op[i], fr[i, 2], fr[i, 3])
            if not ok:
                return -1
            peak = max(cl - pl, cr - pr) - rise > -tol
        if has_next:
            ok, nl, nr = _pair_at(Z, v + 1, e + on[i], fr[i, 4], fr[i, 5])
            if not ok:
                return -1
            peak = peak and (max(cl - nl, cr - nr) + rise > -tol)
        if peak:
            return 1
    return 0


@njit(parallel=True, cache=True)
def _pieces_table(s, frac):
    """``_line_pieces`` of every line: (npc[L], oc, op, on [L, 7], fr [L, 7, 6]). Small (L x 43
    numbers); shared by every element of a line, on either backend."""
    L = frac.shape[0]
    npc = np.zeros(L, np.int64)
    oc = np.zeros((L, 7), np.int64)
    op = np.zeros((L, 7), np.int64)
    on = np.zeros((L, 7), np.int64)
    fr = np.zeros((L, 7, 6))
    for v in prange(L):
        npc[v] = _line_pieces(s, frac[v], oc[v], op[v], on[v], fr[v])
    return npc, oc, op, on, fr


@njit(cache=True, inline="always")
def _colour(Z, v, e, s, rise, tol, fv, npc, oc, op, on, fr, bp, J):
    """J[v, e] = -2 - (v + 1) for a Black element (next line to examine: v + 1), -1 for White.
    The per-element body of both backends: ``fv`` and the pieces are line v's (rows of
    ``_pieces_table``); ``bp`` is scratch for 8 break points."""
    L = Z.shape[0]
    if v == 0:          # no ray samples the line farthest from the sun
        J[v, e] = -1
        return
    P = Z.shape[1]
    valid = False      # a section over voids only has no sample to peak (seas: most elements)
    for j in range(max(0, e - 3), min(P, e + 1)):
        valid = valid or Z[v, j] == Z[v, j]
    if not valid:
        J[v, e] = -1
        return
    has_next = v < L - 1
    c = _is_black_fast(Z, v, e, rise, tol, npc, oc, op, on, fr, True, has_next)
    if c < 0:
        c = 1 if _is_black(Z, v, e, s, fv, rise, tol, bp) else 0
    J[v, e] = -2 - (v + 1) if c == 1 else -1


@njit(parallel=True, cache=True)
def _colour_pass(Z, s, rise, tol, frac, pieces, J, v0, v1):
    """Colour lines v0:v1 (``pieces``: the rows of ``_pieces_table`` of those lines)."""
    P = Z.shape[1]
    E = P + 2
    npc, oc, op, on, fr = pieces
    nblk = (E + _BLOCK - 1) // _BLOCK
    for item in prange((v1 - v0) * nblk):
        i = item // nblk
        v = v0 + i
        blk = item % nblk
        bp = np.empty(8)
        fv, n, ocv, opv, onv, frv = frac[v], npc[i], oc[i], op[i], on[i], fr[i]
        for e in range(blk * _BLOCK, min(E, (blk + 1) * _BLOCK)):
            _colour(Z, v, e, s, rise, tol, fv, n, ocv, opv, onv, frv, bp, J)


@kernel
def _colour_gpu(Z, s, rise, tol, frac, npc, oc, op, on, fr, J):
    """CUDA twin of ``_colour_pass``: one thread per SMap element."""
    e, v = cuda.grid(2)
    if v < J.shape[0] and e < J.shape[1]:
        bp = cuda.local.array(8, np.float64)
        _colour(Z, v, e, s, rise, tol, frac[v], npc[v], oc[v], op[v], on[v], fr[v], bp, J)


# ------------------------------------------------------------------------------------------
# pass 1: NextV

@njit(cache=True)
def _nextv_scan(J, shift, top):
    """White elements of lines below ``top`` point to the nearest Black line of their beam toward
    the sun (or -1); line ``top`` is resolved already (the last line, or a carried one)."""
    L, E = J.shape
    for v in range(top - 1, -1, -1):
        d = shift[v + 1] - shift[v]
        for e in range(E):
            if J[v, e] > -2:
                e2 = e + d
                if e2 >= 0 and e2 < E:
                    j = J[v + 1, e2]
                    J[v, e] = v + 1 if j <= -2 else j
                else:
                    J[v, e] = -1


@njit(cache=True)
def _beam_lines(b, shift, E, L, lines, elems):
    """Lines (from the sun's edge) where beam b has an element, and those elements."""
    n = 0
    for v in range(L - 1, -1, -1):
        e = b + shift[v] + 2
        if e >= 0 and e < E:
            lines[n] = v
            elems[n] = e
            n += 1
    return n


@njit(parallel=True, cache=True)
def _nextv_doubling(J, shift, quad):
    """The paper's log-step NextV search, per beam (t = 0 at the sun's edge; NextV < t).

    binary: passes DIST = 1, 2, 4, ...: an element of an odd DIST-block whose NextV is unknown
    looks at the last element of the block before it. quad: DIST = 1, 4, 16, ...: it looks at the
    last element of each of the (up to three) blocks before it within its 4*DIST block."""
    L, E = J.shape
    bmin = -2 - shift[L - 1]
    nb = E - bmin
    for ib in prange(nb):
        b = bmin + ib
        lines = np.empty(L, np.int64)
        elems = np.empty(L, np.int64)
        n = _beam_lines(b, shift, E, L, lines, elems)
        if n == 0:
            continue
        black = np.empty(n, np.bool_)
        nx = np.full(n, -1, np.int64)
        for t in range(n):
            black[t] = J[lines[t], elems[t]] <= -2
        dist = 1
        while dist < n:
            for t in range(n):
                if nx[t] != -1:
                    continue
                if quad:
                    lk = t - (t % dist) - 1
                    lo = t - t % (4 * dist)
                    while lk >= lo and nx[t] == -1:
                        nx[t] = lk if black[lk] else nx[lk]
                        lk -= dist
                elif (t // dist) % 2 == 1:
                    lk = t - (t % dist) - 1
                    nx[t] = lk if black[lk] else nx[lk]
            dist = dist * 4 if quad else dist * 2
        for t in range(n):
            if not black[t]:
                J[lines[t], elems[t]] = lines[nx[t]] if nx[t] >= 0 else -1


@kernel
def _nextv_pass_gpu(J, shift, dist):
    """One pass of the paper's log-step NextV search on the GPU (DIST = 1, 2, 4, ...), over all
    elements at once. Blocks are aligned on t = L-1-v for every beam (a beam's elements are a run
    of consecutive lines, so a block start outside the beam only means nothing lies beyond).
    A White element of an odd DIST-block whose NextV is unknown (-1) looks at the last element
    of the block before it: that element's line if it is Black, else its NextV. Writes go to odd
    blocks, reads to even ones: no races. Same table as ``_nextv_scan`` (tests)."""
    e, v = cuda.grid(2)
    L, E = J.shape
    if v < L and e < E and J[v, e] == -1:
        t = L - 1 - v
        if (t // dist) % 2 == 1:
            vk = L - 1 - (t - t % dist - 1)
            ek = e + shift[vk] - shift[v]
            if ek >= 0 and ek < E:
                j = J[vk, ek]
                J[v, e] = vk if j <= -2 else j


@njit(cache=True)
def _bounds(Z, v, e, fv, rise):
    """(min, max) of the cells under the widened cross-section, minus the ray rise to line v.
    min is -inf when a void is among them (nothing can be concluded from such a sample)."""
    P = Z.shape[1]
    xa, xb = _section(e, fv, P)
    lo = np.inf
    hi = -np.inf
    for j in range(max(0, int(math.floor(xa))), min(P - 1, int(math.ceil(xb))) + 1):
        h = float(Z[v, j])
        if math.isnan(h):
            lo = -np.inf
        else:
            lo = min(lo, h)
            hi = max(hi, h)
    return lo - rise * v, hi - rise * v


@njit(parallel=True, cache=True)
def _nextv_better(Z, J, frac, shift, rise, tol):
    """NextV that skips hidden silhouettes (paper, section 9). Per beam, from the sun's edge, a
    stack of Black lines whose ``hi`` increases downward: the next line worth checking after an
    unblocked Black line n is the first later Black line m with hi(m) > lo(n)."""
    L, E = J.shape
    bmin = -2 - shift[L - 1]
    nb = E - bmin
    for ib in prange(nb):
        b = bmin + ib
        st_line = np.empty(L, np.int64)
        st_hi = np.empty(L, np.float64)
        top = 0
        for v in range(L - 1, -1, -1):
            e = b + shift[v] + 2
            if e < 0 or e >= E:
                continue
            if J[v, e] <= -2:
                lo, hi = _bounds(Z, v, e, frac[v], rise)
                x = lo - tol
                # topmost stack entry with hi > x (st_hi decreases toward the top)
                a, c = 0, top        # answer index in [a, c) or none
                while a < c:
                    m = (a + c) // 2
                    if st_hi[m] > x:
                        a = m + 1
                    else:
                        c = m
                nxt = st_line[a - 1] if a > 0 else L
                J[v, e] = -2 - nxt
                while top > 0 and st_hi[top - 1] <= hi:
                    top -= 1
                st_line[top] = v
                st_hi[top] = hi
                top += 1
            else:
                J[v, e] = st_line[top - 1] if top > 0 else -1


# ------------------------------------------------------------------------------------------
# IsShadowed

@njit(cache=True)
def _cell_blocked(z, pyr, off, widths, nlev, J, frac, r, c, dom_col, sd, so, rise, flip_line,
                  flip_pos, zmax):
    """Whether cell (r, c)'s ray is blocked: Black to Black through NextV, and over the
    maximum-height pyramid ``(pyr, off, widths, nlev)`` of ``z`` (nlev 0: none) past every block
    lower than the ray (``pyramid.climb``), which skips the Black lines of rough terrain where
    the ray runs high (the jump loop alone visited most of them: 0.3-0.5x the plain march on
    spectral fractals). Both skip only samples that cannot block: the same answer."""
    line0, other0, n_dom, n_oth = ray_origin(z, r, c, dom_col)
    h0 = float(z[np.int64(r), np.int64(c)])
    v0 = n_dom - 1 - line0 if flip_line else line0
    k = 1
    lev = 0
    while True:
        v = v0 + k
        if v >= n_dom:
            return False
        hr = madd(h0, float(k), rise)
        if hr >= zmax:
            return False
        pos = line_position(madd(float(other0), float(k), so), n_oth)
        if pos < 0.0:
            return False
        if nlev > 0:
            line = line0 + k * sd
            i0 = np.int64(math.floor(pos))
            lev = climb(pyr, off, widths, nlev, lev, i0 if dom_col else line,
                        line if dom_col else i0, hr)
            if lev > 0:        # the block is lower than the ray: past it
                k += samples_left(lev, line, i0, pos, sd, so) + 1
                continue
        p = (n_oth - 1) - pos if flip_pos else pos
        j = J[v, int(math.floor(p - frac[v])) + 2]
        if j == -1:
            return False
        if j >= 0:             # White: jump to the beam's next Black line
            k += j - v
            continue
        if terrain_on_line(z, dom_col, line0 + k * sd, pos) > hr:
            return True
        k += (-2 - j) - v      # Black, not blocked here: go on after it


@njit(cache=True, inline="always")
def _mask_cell(z, pyr, off, widths, nlev, J, frac, r, c, dom_col, sd, so, rise, flip_line,
               flip_pos, zmax, out):
    if math.isnan(z[r, c]):
        out[r, c] = 255
    elif _cell_blocked(z, pyr, off, widths, nlev, J, frac, r, c, dom_col, sd, so, rise,
                       flip_line, flip_pos, zmax):
        out[r, c] = 1
    else:
        out[r, c] = 0


@njit(parallel=True, cache=True)
def _mask_kernel(z, pyr, off, widths, nlev, J, frac, dom_col, sd, so, rise, flip_line, flip_pos,
                 zmax, out, r0, r1, c0, c1):
    """The cells of rows r0:r1, columns c0:c1 (of ``z`` and ``out``)."""
    for r in prange(r0, r1):
        for c in range(c0, c1):
            _mask_cell(z, pyr, off, widths, nlev, J, frac, r, c, dom_col, sd, so, rise,
                       flip_line, flip_pos, zmax, out)


@kernel
def _mask_gpu(z, pyr, off, widths, nlev, J, frac, dom_col, sd, so, rise, flip_line, flip_pos,
              zmax, out):
    """CUDA twin of ``_mask_kernel``: one thread per cell."""
    c, r = cuda.grid(2)
    if r < z.shape[0] and c < z.shape[1]:
        _mask_cell(z, pyr, off, widths, nlev, J, frac, r, c, dom_col, sd, so, rise, flip_line,
                   flip_pos, zmax, out)


@njit(parallel=True, cache=True)
def _points_kernel(Z, J, frac, s, rise, zmax, pv, pp, ph, out):
    """Points in canonical coordinates (line, position, height): True where shadowed.

    The first sample inside the raster is checked directly (the peak argument needs a sample
    before the peak, which a free point does not provide for its first one); after it, Black to
    Black as for cells."""
    L, P = Z.shape
    for i in prange(pv.shape[0]):
        vp = pv[i]
        xp = pp[i]
        h = ph[i]
        v = int(math.floor(vp)) + 1
        if v < 0:
            v = 0
        if s > 0.0:       # enter the raster from its low side
            x0 = xp + (v - vp) * s
            if x0 < 0.0:
                v = max(v, int(math.ceil(vp + (-xp) / s)) - 1)
        res = False
        first = True
        while v < L:
            d = v - vp
            hr = h + d * rise
            if hr >= zmax:
                break
            praw = xp + d * s
            x = line_position(praw, P)
            if x < 0.0:
                if praw < 0.0 and s > 0.0 and first:
                    v += 1
                    continue
                break
            if first:
                first = False
                if terrain_on_line(Z, False, v, x) > hr:
                    res = True
                    break
                v += 1
                continue
            j = J[v, int(math.floor(x - frac[v])) + 2]
            if j == -1:
                break
            if j >= 0:
                v = j
                continue
            if terrain_on_line(Z, False, v, x) > hr:
                res = True
                break
            v = -2 - j
        out[i] = res


# ------------------------------------------------------------------------------------------
# Python side

class SMap:
    """The SMap of a DEM for one sun position, and the queries it answers.

    >>> sm = SMap(heights, azimuth=203.7, elevation=10.0, spacing=30.0)
    >>> mask = sm.mask()                     # uint8, 1 shadow / 0 lit / 255 void
    >>> sm.is_shadowed([[10.5, 20.25, 1234.0]])  # (row, col, height) points -> bool
    >>> sm.black_fraction                    # share of Black SMap elements

    ``heights``: 2-D array (float32 used in place; other types converted once). ``spacing``: metres
    per cell, ``(dx, dy)`` or a uniform :class:`Grid`. Points are in array coordinates (cell centres
    at integer row/col) with heights in the DEM's units; they may lie above, on or off the terrain
    and outside the raster.
    """

    def __init__(self, heights, azimuth: float, elevation: float,
                 spacing: float | tuple[float, float] | Grid = 1.0,
                 nextv: str = "scan", better_nextv: bool = False, *, rays: SunRays | None = None,
                 zmax: float | None = None):
        if rays is None:
            z, grid = heights_and_grid(heights, spacing)
            rays = sun_rays(grid, azimuth, elevation)
        else:
            z = heights if heights.dtype == np.float32 else heights.astype(np.float32)
        if not uniform_rays(rays):
            raise HillshadeError(
                "smap needs one sun direction in pixel units for the whole raster; this grid's "
                "spacing varies per row (geographic CRS): reproject it, or use brute or horizon")
        if nextv not in NEXTV_METHODS:
            raise HillshadeError(f"nextv must be one of {', '.join(NEXTV_METHODS)}, got {nextv!r}")
        self.z = z
        self.rays = rays
        self.frame: Frame = frame_of(rays)
        self.zmax = float(np.nanmax(z)) if zmax is None else float(zmax)
        f = self.frame
        self.Z = f.view(z)
        L, P = self.Z.shape
        self.J = np.empty((L, P + 2), np.int32)
        sv = f.s * np.arange(L, dtype=np.float64)
        self.shift = np.floor(sv).astype(np.int64)
        self.frac = sv - self.shift
        finite = np.isfinite(self.zmax) and math.isfinite(f.rise)
        self.black_fraction = 0.0
        if not finite:  # all voids, or the sun at the zenith: no shadow, no structure needed
            self.J.fill(-1)
            return
        zabs = float(np.nanmax(np.abs(z)))
        self.tol = tolerance(zabs, f.rise)
        _colour_pass(self.Z, f.s, f.rise, self.tol, self.frac, _pieces_table(f.s, self.frac), self.J,
                     0, L)
        self.black_fraction = float(np.count_nonzero(self.J <= -2)) / (L * P)
        if better_nextv:
            _nextv_better(self.Z, self.J, self.frac, self.shift, f.rise, self.tol)
        elif nextv == "scan":
            _nextv_scan(self.J, self.shift, L - 1)
        else:
            _nextv_doubling(self.J, self.shift, nextv == "quad")

    def mask(self, out: np.ndarray | None = None, pyramid=False) -> np.ndarray:
        """The mask; ``pyramid`` (True, or a ``MaxPyramid`` of the heights) lets the jump loop
        skip the blocks lower than a ray (same mask, less time on rough terrain)."""
        z, f = self.z, self.frame
        if out is None:
            out = np.empty(z.shape, np.uint8)
        if not (np.isfinite(self.zmax) and math.isfinite(f.rise)):
            out[...] = np.where(np.isnan(z), 255, 0)
            return out
        _mask_kernel(z, *pyramid_args(z, pyramid), self.J, self.frac, f.dom_col, np.int64(f.sd),
                     f.so, f.rise, f.flip_line, f.flip_pos, self.zmax, out, 0, z.shape[0], 0,
                     z.shape[1])
        return out

    def to_canonical(self, rows, cols):
        """Array (row, col) coordinates -> canonical (line, position)."""
        f = self.frame
        n_r, n_c = self.z.shape
        line, pos = (cols, rows) if f.dom_col else (rows, cols)
        n_line, n_pos = (n_c, n_r) if f.dom_col else (n_r, n_c)
        if f.flip_line:
            line = (n_line - 1) - line
        if f.flip_pos:
            pos = (n_pos - 1) - pos
        return line, pos

    def is_shadowed(self, points) -> np.ndarray:
        """Bool per point (row, col, height): does its ray toward the sun pass strictly below the
        terrain? The ray is sampled where it crosses grid lines strictly ahead of the point."""
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise HillshadeError("points must be an (N, 3) array of (row, col, height)")
        if not np.isfinite(pts).all():
            raise HillshadeError("points must be finite numbers")
        out = np.zeros(len(pts), np.bool_)
        f = self.frame
        if len(pts) == 0 or not (np.isfinite(self.zmax) and math.isfinite(f.rise)):
            return out
        line, pos = self.to_canonical(pts[:, 0], pts[:, 1])
        _points_kernel(self.Z, self.J, self.frac, f.s, f.rise, self.zmax,
                       np.ascontiguousarray(line), np.ascontiguousarray(pos),
                       np.ascontiguousarray(pts[:, 2]), out)
        return out


@njit(cache=True)
def _move_lines(J, src, dst, n, d):
    """Lines src:src+n of J to dst:dst+n (they may overlap), their line numbers raised by ``d``:
    the local numbering of a window whose first line lies ``d`` lines lower. -1 stays -1."""
    E = J.shape[1]
    for i in range(n):
        k = n - 1 - i if dst > src else i
        for e in range(E):
            j = J[src + k, e]
            if j >= 0:
                j += d
            elif j <= -2:
                j -= d
            J[dst + k, e] = j


def canonical_place(frame: Frame, window, shape) -> tuple[int, tuple[int, int]]:
    """(base, positions) of ``window`` (r0, r1, c0, c1) of a raster of ``shape`` in the frame:
    the canonical number of the window's first line in the whole raster, and the DEM rows or
    columns its positions span."""
    r0, r1, c0, c1 = window
    lo, hi, n, pos = (c0, c1, shape[1], (r0, r1)) if frame.dom_col else (r0, r1, shape[0], (c0, c1))
    return (n - hi if frame.flip_line else lo), pos


def carried_mask(z: np.ndarray, rays: SunRays, zmax: float, zabs: float, window, shape,
                 inner: tuple[slice, slice], carry) -> tuple[np.ndarray, int]:
    """SMap on one window of a tiled run with the tables carried from the window before, so that
    the lines two windows share are coloured and scanned once: (uint8 mask of the window ``z``
    (DEM order; ``window`` (r0, r1, c0, c1) of a raster of ``shape``) with the cells of ``inner``
    decided (1 shadow, 0 lit, 255 void) and the others 0, the lines coloured). ``zabs``: the
    largest height magnitude of the whole raster (one tolerance for every window). ``carry``
    (``engine.windows.BandCarry``) holds the table: ``key``, ``base``, ``L`` of the lines it
    holds, ``table(rows, E)`` its buffer as a rows x E table (the carried lines kept when it
    grows); they are updated here.

    The planner orders the windows of a band of positions away from the sun, each spanning the
    same positions and reaching at least as far toward the sun as the next one. A window's lines
    toward the sun were then all in the window before, with the same neighbours (the one below
    the previous window's region is its region's lower neighbour there too), and beams are
    aligned on the raster's absolute line numbers: their colours and NextV pointers are reused
    (renumbered in place in one buffer), and only the window's new lines are coloured and scanned.
    Pointers past the window's top mean "left the window": the halo guarantees that no terrain
    there rises above the region's rays, so the answer is the window's own, which is the whole
    raster's. Only the region's cells are masked.

    Equal, cell for cell, to ``shadow_mask`` on each window (tests: tiled runs at 163, 203.7 and
    291 degrees against the in-memory run; all eight octants with voids against brute)."""
    f = frame_of(rays)
    base, positions = canonical_place(f, window, shape)
    tol = tolerance(zabs, f.rise)
    Z = f.view(z)
    L, P = Z.shape
    E = P + 2
    key = (f.dom_col, f.flip_line, f.flip_pos, f.s, f.rise, positions, P)
    fresh = L
    if carry.key == key:
        lo, hi = max(base, carry.base + 1), base + L
        if lo < hi and carry.base + carry.L >= hi:
            J = carry.table(max(L, carry.L), E)
            _move_lines(J, lo - carry.base, lo - base, hi - lo, carry.base - base)
            fresh = lo - base
    carry.key = None if fresh == L else key
    J = carry.table(L, E)
    sv = f.s * (np.arange(L, dtype=np.float64) + base)
    shift = np.floor(sv).astype(np.int64)
    frac = sv - shift
    if fresh > 0:
        _colour_pass(Z, f.s, f.rise, tol, frac, _pieces_table(f.s, frac[:fresh]), J, 0, fresh)
    _nextv_scan(J, shift, min(fresh, L - 1))
    carry.key, carry.base, carry.L = key, base, L
    out = np.zeros(z.shape, np.uint8)
    rs, cs = inner
    _mask_kernel(z, *NO_PYRAMID, J, frac, f.dom_col, np.int64(f.sd), f.so, f.rise,
                 f.flip_line, f.flip_pos, float(zmax), out, rs.start, rs.stop, cs.start,
                 cs.stop)
    return out, fresh


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None, stats: dict | None = None,
                nextv: str = "scan", better_nextv: bool = False, pyramid=True) -> np.ndarray:
    """Shadow mask by SMap (uint8: 1 shadow, 0 lit, 255 void); equal to ``brute`` cell for cell.

    ``stats`` (a dict, optional) receives ``black_fraction`` and ``smap_bytes``, or a ``note`` when
    the rays vary per row and the cells were marched one by one (geographic CRS)."""
    if zmax is None:
        zmax = float(np.nanmax(z))
    if not uniform_rays(rays):
        from . import brute
        if stats is not None:
            stats["note"] = (PER_ROW_SPACING + ": smap marched every cell's ray like brute "
                             "(same result, brute's speed)")
        return brute.shadow_mask(z, rays, zmax, pyramid=pyramid)
    sm = SMap(z, 0.0, 0.0, rays=rays, zmax=zmax, nextv=nextv, better_nextv=better_nextv)
    # the pyramid pays where rays are long over rough terrain; on rays of a few steps, or where
    # NextV already jumps over most lines (few Black elements: smooth slopes), its reads cost
    # more than they skip (New Zealand's 1 km DEM at 20 deg: 7.9 ms against 4.8 for the jump
    # loop alone; the smooth facet fractal: 2-3x slower)
    if pyramid is not False and (sm.black_fraction < PYRAMID_BLACK or reach(
            z.shape, (float(np.nanmin(z)), zmax), rays) < PYRAMID_REACH):
        pyramid = False
    if stats is not None:
        stats["black_fraction"] = sm.black_fraction
        stats["smap_bytes"] = int(sm.J.nbytes)
        stats["pyramid"] = pyramid is not False
    return sm.mask(pyramid=pyramid)


def shadow_mask_gpu(g, rays: SunRays, zmax: float, stats: dict | None = None, nextv: str = "scan",
                    better_nextv: bool = False) -> np.ndarray:
    """``shadow_mask`` on the GPU (``g``: a ``gpu.GpuDem``): the Black pass, the NextV doubling
    passes and the per-cell jump loop, each one kernel over all elements or cells. NextV is
    always built by doubling here (the same table as every ``nextv`` method; ``better_nextv``
    has no GPU kernel and is refused by the caller)."""
    if nextv not in NEXTV_METHODS:
        raise HillshadeError(f"nextv must be one of {', '.join(NEXTV_METHODS)}, got {nextv!r}")
    if better_nextv:
        raise HillshadeError("--better-nextv runs on the CPU only (use --backend cpu)")
    from . import brute
    if not uniform_rays(rays):
        if stats is not None:
            stats["note"] = (PER_ROW_SPACING + ": smap marched every cell's ray like brute "
                             "(same result, brute's speed)")
        return brute.shadow_mask_gpu(g, rays, zmax)
    f = frame_of(rays)
    rows, cols = g.shape
    L, P = (cols, rows) if f.dom_col else (rows, cols)
    if not (math.isfinite(zmax) and math.isfinite(f.rise)):   # sun at the zenith: no shadow
        return brute.shadow_mask_gpu(g, rays, zmax)
    sv = f.s * np.arange(L, dtype=np.float64)
    shift = np.floor(sv).astype(np.int64)
    frac = sv - shift
    zabs = max(abs(g.zmin), abs(g.zmax))
    tol = tolerance(zabs, f.rise)
    tables = [g.upload(a) for a in (frac, shift) + _pieces_table(f.s, frac)]
    d_frac, d_shift, npc, oc, op, on, fr = tables
    J = g.empty((L, P + 2), np.int32)
    out = g.empty((rows, cols), np.uint8)
    with g.timed():
        Zc = g.canonical(f)
        g.launch(_colour_gpu, L, P + 2, Zc, f.s, f.rise, tol, d_frac, npc, oc, op, on, fr, J)
        dist = 1
        while dist < L:
            g.launch(_nextv_pass_gpu, L, P + 2, J, d_shift, np.int64(dist))
            dist *= 2
        g.launch(_mask_gpu, rows, cols, g.z, *g.pyramid_args(True), J, d_frac, f.dom_col,
                 np.int64(f.sd), f.so, f.rise, f.flip_line, f.flip_pos, float(zmax), out)
    if stats is not None:
        stats["smap_bytes"] = int(L * (P + 2) * 4)
    return g.download(out)
