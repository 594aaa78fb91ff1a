"""``bounds``: exact shadows from guaranteed bounds of every cell's horizon, the pyramid march
for the few cells the bounds leave open.

The flag-map sweep of "Faster Ray Traced Terrain Shadow Maps" [1]_ (``sweep``) stores for each cell
what its ray met and lets the next rays interpolate it: fast, and wrong where a thin ridge passes
between two neighbouring rays. Here the stored values are made **conservative**, so that a cell is
decided only when no ray between the stored ones could decide it otherwise:

* In the canonical frame (``frames``: the sun toward increasing line index, positions growing by
  ``s`` per step) let ``S(v, x)`` be the lowest height at position x of line v from which a ray
  toward the sun clears every sample ahead: ``S(v, x) = max_j (T(v+j, x + j*s) - j*rise)``, T the
  model's interpolated terrain. A cell of height h is shadowed iff ``S(v+1, p+s) > h + rise``.
* Cut each line into bins of 1/``BINS`` cell that **follow the rays**: bin t of line v covers
  positions ``[t/BINS + phi_v, (t+1)/BINS + phi_v]``, the lattice of line 0 carried along the sun
  direction, so that the rays through a bin of line v all pass through one bin of line v+1 (a
  tube of rays half a cell wide). On a bin the terrain is linear, or has one cell
  centre inside, so its extremes are known exactly. Because ``S(v, x) = max(T(v, x),
  S(v+1, x+s) - rise)``, an upper bound of S over a bin is the larger of T's maximum there and
  the upper bound of its tube's bin on the next line, less the rise; a lower bound, the same
  with minima. One pass from the sun's edge fills both bounds for every bin in O(N * BINS), and
  they never widen along the tube: they are the exact S of the tube's best and worst ray but for
  the half cell's spread.
* A cell takes ``EXACT_STEPS`` samples exactly (as the plain march), then looks up the bounds at
  its ray's position ``EXACT_STEPS`` lines on: lit when both the exact samples and the upper bound
  clear its ray, shadowed when an exact sample or the lower bound blocks it, **undecided**
  otherwise. Undecided cells (``undecided_fraction``: 1-2 % of the cells on real projected
  DEMs and spectral fractals at 3-20 deg) are marched exactly over the maximum-height pyramid
  (``brute.refine``). A margin far larger than the rounding of the bounds (and far smaller than
  a millimetre) keeps every decision on the safe side, so the mask is brute's cell for cell
  (tests).

Voids: a bin with a void end is bounded above by its valid end and below by -inf (its interior
meets no terrain). Beyond the raster S is -inf (no terrain). Earth curvature: a cell looks the
bounds up K steps along its ray, after which its next j steps rise j r + (2Kj + j^2) c. The
upper bound follows a straight ray rising r + (2K + 1) c per step (no more than the curved one
over any j steps), the lower bound one rising at least as much as the curved one over every j
whose terrain could still reach it (``_drops``).

Rays that differ per row (geographic CRS) or per cell (a sun per cell): the bins follow the
slowest ray; a faster one drifts ahead of its tube by the slopes' spread per line. In blocks of
lines short enough that the drift stays under a bin (``_blocks``), each line's bins are widened by
the drift so far (their terrain bounded exactly) and carried bin to bin; only at a block's end do
they take two bins of the next line. The bounds so widen by one bin per block (one per 100-170
lines on SRTM tiles), about the rays' true spread, and leave about as few cells undecided as one
ray does (1.7-2.4 % on the Everest tile against 1.4-1.8 % on one spacing; 3-9 % when they
widened one bin per line). Each cell's exact samples and lookup use its own ray. Rows whose own
dominant axis is the other one (near a diagonal) are left undecided.

Parallel as the sweep's wavefront: strips of positions, each a block of lines behind the next.

References
----------
.. [1] "Faster Ray Traced Terrain Shadow Maps," tutorial, Freeworld3D (no author or date given in
       the text).
.. [2] A. Tevs, I. Ihrke, H.-P. Seidel, "Maximum mipmaps for fast, accurate, and scalable dynamic
       height field rendering," in Proc. 2008 Symp. on Interactive 3D Graphics and Games (I3D '08),
       pp. 183-190, 2008. :doi:`10.1145/1342250.1342279`
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..model.geometry import SunRays
from . import brute
from ._jitcache import njit
from .bounds_per_cell_sun import field_args, field_fit, field_line, field_runs, less_potential
from .counts import z_range
from .frames import Frame, frame_of, reach, steps_over
from .sweep import load_lines, store_lines, strip_bounds, wave_block, wave_steps
from .sweep import strip_count as sweep_strips

BINS = 2           # bins per segment between two cell centres (a power of two; 4 bins left
                   # half as many cells undecided and took 20 % longer)
LOG_BINS = 1
EXACT_STEPS = 4    # samples every cell marches exactly before it looks the bounds up
UNDECIDED = 2      # mask code of a cell the bounds leave to the exact march
EPS_BIN = 1e-7     # slack (in bins) on the bins a ray may reach: covers position rounding
SNAP = 1e-7        # fractions this close to 0 or 1 may be a cell centre in the model's rounding
ZO = 2             # NaN positions kept before each line of heights (the bins around position 0)
RUN = 64           # positions per run of rays that share their offsets (_decide_positions)


@njit(cache=True, inline="always")
def _bin_bounds(a, b, ga, gb):
    """(upper, lower) bound of the terrain on [ga, gb] (fractions) of the segment from height a
    to b: its ends (the terrain is linear there); with a void end, the valid end above (a ray
    may land exactly on it) and -inf below. Selects only: the pass vectorises."""
    ta = a + ga * (b - a)
    tb = a + gb * (b - a)
    hi_t = ta if ta > tb else tb
    lo_t = tb if ta > tb else ta
    void = not ((ta == ta) & (tb == tb))      # '&': no branch, the pass vectorises
    top = a if a == a else (b if b == b else -np.inf)
    return (top if void else hi_t), (-np.inf if void else lo_t)


@njit(cache=True, inline="always")
def _phase(v, s_c):
    """(off, phi) of line v's bins: bin t covers positions [t/BINS + phi, (t+1)/BINS + phi].
    The bins of line 0 carried along rays of step ``s_c``: off = floor(BINS v s_c), so that bin t
    of line v moves onto bin t + off(v+1) - off(v) of line v+1."""
    x = v * s_c * BINS
    off = math.floor(x)
    return np.int64(off), (x - off) / BINS


@njit(cache=True)
def _bin_pass(zb, zo, su_n, sl_n, su_c, sl_c, i0, i1, padp, phi, delta, ext, W, d_up, d_lo):
    """Bounds of the bins t = BINS*i + m, i in [i0, i1), of one line (heights ``zb``, position
    x at ``zb[zo + x]``, NaN beyond the line) from those of the next line (``su_n``, ``sl_n``).
    Bin t is stored at ``[m, padp + i]``. The bounds cover the rays through the bin *widened by
    ``ext`` cells on its far side* (the drift of the block's rays so far, see ``_blocks``), whose
    terrain is bounded exactly; they reach bins t + delta .. t + delta + W - 1 of the next line
    (W = 1 but at a block's end, and always when every row has the same ray). For each m the bins
    reached are at a fixed place: the pass over i is contiguous and vectorises."""
    Q = BINS
    inv = 1.0 / Q
    for m in range(Q):
        fa = m * inv + phi
        fb = fa + inv + ext
        straddle = fb > 1.0        # the bin holds the next cell centre
        q = m + delta
        ma = q % Q
        da = padp + q // Q
        mb = (q + 1) % Q
        db = padp + (q + 1) // Q
        mc = (q + 2) % Q
        dc = padp + (q + 2) // Q
        # views that start at 0: numba then drops its negative-index wrap (i0 may be -1), which
        # kept the loop from vectorising
        n = i1 - i0
        Z = zb[zo + i0:zo + i1 + 2]
        ua, ub, uc = su_n[ma, da + i0:da + i1], su_n[mb, db + i0:db + i1], su_n[mc, dc + i0:dc + i1]
        la, lb, lc = sl_n[ma, da + i0:da + i1], sl_n[mb, db + i0:db + i1], sl_n[mc, dc + i0:dc + i1]
        ou = su_c[m, padp + i0:padp + i1]
        ol = sl_c[m, padp + i0:padp + i1]
        if W <= 3:
            _bin_loop(Z, ua, ub, uc, la, lb, lc, ou, ol, n, fa, fb, straddle, W, d_up, d_lo)
            continue
        for j in range(n):   # rays of many rows spread over more bins (rare)
            hi_t, lo_t = _terrain_bin(Z, j, fa, fb, straddle)
            u = -np.inf
            lw = np.inf
            for k in range(W):
                mj = (q + k) % Q
                dj = padp + (q + k) // Q + i0 + j
                u = max(u, su_n[mj, dj])
                lw = min(lw, sl_n[mj, dj])
            u -= d_up
            lw -= d_lo
            ou[j] = u if u > hi_t else hi_t
            ol[j] = lw if lw > lo_t else lo_t


@njit(cache=True, inline="always")
def _terrain_bin(Z, j, fa, fb, straddle):
    """(upper, lower) bound of the terrain over the bin [fa, fb] of segment j of the heights
    ``Z`` (``straddle``: the bin holds the next centre, fb > 1)."""
    a = Z[j]
    b = Z[j + 1]
    if straddle:
        h1, l1 = _bin_bounds(a, b, fa, 1.0)
        h2, l2 = _bin_bounds(b, Z[j + 2], 0.0, fb - 1.0)
        return (h1 if h1 > h2 else h2), (l2 if l1 > l2 else l1)
    return _bin_bounds(a, b, fa, fb)


@njit(cache=True)
def _bin_loop(Z, ua, ub, uc, la, lb, lc, ou, ol, n, fa, fb, straddle, W, d_up, d_lo):
    """The pass of ``_bin_pass`` over one bin place m for W <= 3, on views that start at 0 and
    with selects only (in a function of its own it vectorises: 2x the speed of the pass)."""
    for j in range(n):
        hi_t, lo_t = _terrain_bin(Z, j, fa, fb, straddle)
        if W == 1:
            u = ua[j]
            lw = la[j]
        elif W == 2:
            x, y = ua[j], ub[j]
            u = x if x > y else y
            x, y = la[j], lb[j]
            lw = y if x > y else x
        else:
            x, y, w = ua[j], ub[j], uc[j]
            x = x if x > y else y
            u = x if x > w else w
            x, y, w = la[j], lb[j], lc[j]
            x = y if x > y else x
            lw = w if x > w else x
        u -= d_up
        lw -= d_lo
        ou[j] = u if u > hi_t else hi_t
        ol[j] = lw if lw > lo_t else lo_t


@njit(cache=True, inline="always")
def _sample_hi(za, zb, f):
    """An upper bound of the model's sample between heights za, zb at fraction f, NaN when it is
    surely a void. This frame's positions round differently from the model's (it counts from
    the other end of a flipped line, and splits k*s into whole and fraction): where f is within
    ``SNAP`` of 0 or 1 the model may land exactly on a cell centre, so a void neighbour does not
    make the sample a void there: the valid neighbour bounds it. (Nor is such a sample counted
    as a block: the model's may fall on the next segment, beside a void.)"""
    t = za + f * (zb - za)
    if t == t or not (f < SNAP or f > 1.0 - SNAP):
        return t
    if za == za:
        return za if not zb == zb else max(za, zb)
    return zb


@njit(cache=True)
def _lookup_rows(SU, SL, row, b0, b1, pad):
    """The rows of ring row ``row``'s bounds that bins BINS p + b0 and BINS p + b1 of every
    position p lie in, and their offsets: (sua, sla, sub, slb, da, db) for ``_looked_up``."""
    su = SU[row]
    sl = SL[row]
    ma, da = b0 & (BINS - 1), pad + (b0 >> LOG_BINS)
    mb, db = b1 & (BINS - 1), pad + (b1 >> LOG_BINS)
    return su[ma], sl[ma], su[mb], sl[mb], da, db


@njit(cache=True, inline="always")
def _looked_up(sua, sla, sub, slb, da, db, p, two):
    """(upper, lower) bound at position p from the rows of the bins it looks up (``sua``/``sla``
    of the first at offset ``da``; with ``two``, also ``sub``/``slb`` at ``db``)."""
    u = sua[da + p]
    lw = sla[da + p]
    if two:
        u = max(u, sub[db + p])
        lw = min(lw, slb[db + p])
    return u, lw


@njit(cache=True, inline="always")
def _code(e, e_hi, lw, u, h, hk, margin, x, P):
    """The decision of a cell of height ``h`` whose ray stands at ``hk`` K lines on, at position
    ``x``: shadowed (1) when an exact sample (max ``e``) or the lower bound ``lw`` blocks it, lit
    (0) when every sample (max ``e_hi``) and the upper bound ``u`` clear it and ``x`` is not within
    rounding of the far edge (where the model snaps a position onto the last cell centre),
    UNDECIDED otherwise; 255 on a void."""
    sh = (e > h + margin) | (lw > hk + margin)          # '|', '&': no branch, loops vectorise
    lit = (e_hi <= h - margin) & (u <= hk - margin) & (x <= P - 1 - 1e-6)
    c = np.uint8(1) if sh else (np.uint8(0) if lit else np.uint8(UNDECIDED))
    return np.uint8(255) if h != h else c


@njit(cache=True)
def _decide_line(ZB, SU, SL, R, v, p0, p1, P, s, rise, curv, K, pad, margin, ok, s_c, e, e_hi,
                 out, PF):
    """Codes of positions [p0, p1) of canonical line v whose cells share one ray (s, rise,
    curv): the same decisions as ``_decide_positions``, with the sample offsets and fractions of
    the line computed once, in passes along the line over views that start at 0 (numba then
    drops its negative-index wrap) with selects only: they vectorise. ``e``, ``e_hi``: work
    space; ``PF``: each position as a float (no conversion in the loop)."""
    n = p1 - p0
    row = v % R
    if not ok:
        for q in range(n):
            h = ZB[row, ZO + p0 + q]
            out[q] = np.uint8(255) if h != h else np.uint8(UNDECIDED)
        return
    for q in range(n):
        e[q] = -np.inf
        e_hi[q] = -np.inf
    for k in range(1, K + 1):
        ks = k * s
        d = int(ks)
        f = ks - d
        drop = k * rise + k * k * curv
        zv = ZB[(v + k) % R, ZO + p0 + d:ZO + p0 + d + n + 1]
        if f == 0.0:
            for q in range(n):
                t = zv[q] - drop
                e[q] = t if t > e[q] else e[q]     # NaN (void, outside) compares false
                e_hi[q] = t if t > e_hi[q] else e_hi[q]
        elif not (f < SNAP or f > 1.0 - SNAP):
            for q in range(n):
                za = zv[q]
                t = za + f * (zv[q + 1] - za) - drop
                e[q] = t if t > e[q] else e[q]
                e_hi[q] = t if t > e_hi[q] else e_hi[q]
        else:                         # within rounding of a cell centre: bounded above only
            for q in range(n):
                t = _sample_hi(zv[q], zv[q + 1], f) - drop
                e_hi[q] = t if t > e_hi[q] else e_hi[q]
    xk = K * s
    _, phi = _phase(v + K, s_c)
    y = (xk - phi) * BINS             # bin of position p + xk on line v+K: BINS * p + y
    b0 = int(math.floor(y - EPS_BIN))
    b1 = int(math.ceil(y + EPS_BIN)) - 1
    sua, sla, sub, slb, da, db = _lookup_rows(SU, SL, (v + K) % R, b0, b1, pad)
    hk = K * rise + K * K * curv
    ua = sua[da + p0:da + p1]
    la = sla[da + p0:da + p1]
    zl = ZB[row, ZO + p0:ZO + p1]
    X = PF[p0:p1]
    if b1 > b0:
        ub = sub[db + p0:db + p1]
        lb = slb[db + p0:db + p1]
        for q in range(n):
            u = max(ua[q], ub[q])
            lw = min(la[q], lb[q])
            h = zl[q]
            out[q] = _code(e[q], e_hi[q], lw, u, h, h + hk, margin, X[q] + xk, P)
    else:
        for q in range(n):
            h = zl[q]
            out[q] = _code(e[q], e_hi[q], la[q], ua[q], h, h + hk, margin, X[q] + xk, P)


@njit(cache=True)
def _run_offsets(s_lo, s_hi, K, phi, D):
    """Whether every ray of step in [s_lo, s_hi] has the same whole offsets: ``D[k]`` =
    floor(k s) for k = 1..K (written) and the bins it looks up K lines on (returned, with the
    answer: ok, b0, b1, bins of position p: BINS p + b0 .. BINS p + b1). These are monotone in
    s, so the two ends decide."""
    for k in range(1, K + 1):
        d = math.floor(k * s_lo)
        if math.floor(k * s_hi) != d:
            return False, 0, 0
        D[k] = d
    y_lo = (K * s_lo - phi) * BINS
    y_hi = (K * s_hi - phi) * BINS
    b0 = math.floor(y_lo - EPS_BIN)
    b1 = math.ceil(y_lo + EPS_BIN) - 1
    if math.floor(y_hi - EPS_BIN) != b0 or math.ceil(y_hi + EPS_BIN) - 1 != b1:
        return False, 0, 0
    return True, int(b0), int(b1)


@njit(cache=True)
def _decide_run(ZB, SU, SL, R, v, p0, p1, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad, margin,
                D, b0, b1, out, PF):
    """``_decide_positions`` for a run of positions [p0, p1) whose rays differ (each its row's
    or its own sun's) but share their whole offsets (``_run_offsets``): one pass, each cell's
    K = EXACT_STEPS = 4 samples and its lookup in registers, over views that start at 0 (numba
    then drops its negative-index wrap: the pass vectorises); a cell within rounding of a cell
    centre takes the exact treatment of ``_decide_cells`` after it. ``PF``: each position as a
    float (no conversion in the loop); selects only (``&``, ``|``): the pass vectorises."""
    n = p1 - p0
    X = PF[p0:p1]
    S = s_arr[p0:p1]
    RI = rise_arr[p0:p1]
    CU = curv_arr[p0:p1]
    OK = ok_arr[p0:p1]
    d1, d2, d3, d4 = D[1], D[2], D[3], D[4]
    z1 = ZB[(v + 1) % R, ZO + p0 + d1:ZO + p0 + d1 + n + 1]
    z2 = ZB[(v + 2) % R, ZO + p0 + d2:ZO + p0 + d2 + n + 1]
    z3 = ZB[(v + 3) % R, ZO + p0 + d3:ZO + p0 + d3 + n + 1]
    z4 = ZB[(v + 4) % R, ZO + p0 + d4:ZO + p0 + d4 + n + 1]
    sua, sla, sub, slb, da, db = _lookup_rows(SU, SL, (v + K) % R, b0, b1, pad)
    ua = sua[da + p0:da + p1]
    la = sla[da + p0:da + p1]
    ub = sub[db + p0:db + p1]
    lb = slb[db + p0:db + p1]
    zl = ZB[v % R, ZO + p0:ZO + p1]
    two = b1 > b0
    nsnap = 0
    for q in range(n):
        sp = S[q]
        rp = RI[q]
        cp = CU[q]
        f1 = sp - d1
        f2 = 2.0 * sp - d2
        f3 = 3.0 * sp - d3
        f4 = 4.0 * sp - d4
        t1 = z1[q] + f1 * (z1[q + 1] - z1[q]) - (rp + cp)
        t2 = z2[q] + f2 * (z2[q + 1] - z2[q]) - (2.0 * rp + 4.0 * cp)
        t3 = z3[q] + f3 * (z3[q + 1] - z3[q]) - (3.0 * rp + 9.0 * cp)
        t4 = z4[q] + f4 * (z4[q + 1] - z4[q]) - (4.0 * rp + 16.0 * cp)
        e_hi = t1 if t1 > -np.inf else -np.inf     # NaN (void, outside) compares false
        e_hi = t2 if t2 > e_hi else e_hi
        e_hi = t3 if t3 > e_hi else e_hi
        e_hi = t4 if t4 > e_hi else e_hi
        e = e_hi
        snaps = ((f1 < SNAP) | (f1 > 1.0 - SNAP) | (f2 < SNAP) | (f2 > 1.0 - SNAP)
                 | (f3 < SNAP) | (f3 > 1.0 - SNAP) | (f4 < SNAP) | (f4 > 1.0 - SNAP))
        u = ua[q]
        lw = la[q]
        if two:
            u = max(u, ub[q])
            lw = min(lw, lb[q])
        h = zl[q]
        c = _code(e, e_hi, lw, u, h, h + 4.0 * rp + 16.0 * cp, margin, X[q] + 4.0 * sp, P)
        c = c if (OK[q] | (h != h)) else np.uint8(UNDECIDED)
        mark = snaps & (c != 255)
        out[q] = np.uint8(UNDECIDED + 1) if mark else c
        nsnap += np.int64(1) if mark else np.int64(0)
    if nsnap == 0:
        return
    for q in range(n):     # within rounding of a cell centre (rare): sample by sample
        if out[q] != UNDECIDED + 1:
            continue
        e = -np.inf
        e_hi = -np.inf
        for k in range(1, K + 1):
            d = D[k]
            f = k * S[q] - d
            zr = ZB[(v + k) % R, ZO:]
            za = zr[p0 + q + d]
            zb = zr[p0 + q + d + 1]
            drop = k * RI[q] + k * k * CU[q]
            if f < SNAP or f > 1.0 - SNAP:
                if f == 0.0:                    # the model's sample is the centre itself
                    e = max(e, za - drop) if za == za else e
                t = _sample_hi(za, zb, f) - drop
            else:
                t = za + f * (zb - za) - drop
                e = t if t > e else e
            e_hi = t if t > e_hi else e_hi
        u, lw = _looked_up(sua, sla, sub, slb, da, db, p0 + q, two)
        h = zl[q]
        c = _code(e, e_hi, lw, u, h, h + K * RI[q] + K * K * CU[q], margin, p0 + q + K * S[q],
                  P)
        out[q] = c if OK[q] else np.uint8(UNDECIDED)


@njit(cache=True)
def _decide_positions(ZB, SU, SL, R, v, p0, p1, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad,
                      margin, s_c, out, W, D, PF):
    """Codes of positions [p0, p1) of canonical line v when each position has its own ray
    (``s_arr`` ... indexed by position: lines that are DEM columns of a per-row grid, or each
    cell's own sun, ``field_line``): K exact samples, then the bounds K lines on; 0 / 1 when
    they decide, UNDECIDED otherwise (the same tests as ``_decide_line``; a position whose
    ``ok_arr`` is False is UNDECIDED). Rays change slowly along a line: runs of ``RUN``
    positions whose rays share their whole offsets go to ``_decide_run`` (contiguous passes),
    the others to ``_decide_cells``. ``W`` (5 x strip width), ``D`` (K + 1): work space."""
    n = p1 - p0
    if K != 4:                               # (_decide_run takes exactly 4 samples)
        _decide_cells(ZB, SU, SL, R, v, p0, 0, n, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad,
                      margin, s_c, out, W)
        return
    _, phi = _phase(v + K, s_c)
    step = n                                 # the whole strip in one run, else runs of RUN
    qa = 0
    while qa < n:
        qb = min(n, qa + step)
        lo = np.inf
        hi = -np.inf
        for p in range(p0 + qa, p0 + qb):
            if ok_arr[p]:
                lo = min(lo, s_arr[p])
                hi = max(hi, s_arr[p])
        same, b0, b1 = False, 0, 0
        if lo <= hi:
            same, b0, b1 = _run_offsets(lo, hi, K, phi, D)
        if same:
            _decide_run(ZB, SU, SL, R, v, p0 + qa, p0 + qb, P, s_arr, rise_arr, curv_arr, ok_arr,
                        K, pad, margin, D, b0, b1, out[qa:qb], PF)
        elif step > RUN:
            step = RUN
            continue
        else:
            _decide_cells(ZB, SU, SL, R, v, p0, qa, qb, P, s_arr, rise_arr, curv_arr, ok_arr, K,
                          pad, margin, s_c, out, W)
        qa = qb


@njit(cache=True)
def _decide_cells(ZB, SU, SL, R, v, p0, qa, qb, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad,
                  margin, s_c, out, W):
    """``_decide_positions`` cell by cell for positions p0 + [qa, qb): each cell's ray, its K
    samples at their own offsets, its lookup."""
    ss, rr, cc, e, e_hi = W[0], W[1], W[2], W[3], W[4]
    zl = ZB[v % R, ZO:]                      # (rows of ZB: contiguous)
    for q in range(qa, qb):
        p = p0 + q
        h = zl[p]
        e[q] = -np.inf
        e_hi[q] = -np.inf
        good = ok_arr[p] and h == h
        out[q] = np.uint8(UNDECIDED) if h == h else np.uint8(255)
        ss[q] = s_arr[p] if good else np.nan       # NaN: a cell already coded
        rr[q] = rise_arr[p]
        cc[q] = curv_arr[p]
    for k in range(1, K + 1):                # the exact samples, one pass each (selects only:
        zr = ZB[(v + k) % R, ZO:]            # it vectorises; a coded cell samples harmlessly)
        for q in range(qa, qb):
            sp = ss[q]
            sp = sp if sp == sp else 0.0
            x = p0 + q + k * sp
            i0 = int(x)
            f = x - i0
            za = zr[i0]
            zb = zr[i0 + 1]
            drop = k * rr[q] + k * k * cc[q]
            t = (za if f == 0.0 else za + f * (zb - za)) - drop
            snap = f < SNAP or f > 1.0 - SNAP
            te = t if (f == 0.0 or not snap) else -np.inf
            e[q] = te if te > e[q] else e[q]        # NaN (void, outside) compares false
            # _sample_hi: near a cell centre a void neighbour does not make the sample a void
            alt = (za if za == za else zb) - drop
            th = alt if (snap and not t == t) else t
            e_hi[q] = th if th > e_hi[q] else e_hi[q]
    _, phi = _phase(v + K, s_c)
    su = SU[(v + K) % R]
    sl = SL[(v + K) % R]
    for q in range(qa, qb):                  # the bounds K lines on, and the decision
        sp = ss[q]
        if sp != sp:
            continue
        p = p0 + q
        h = zl[p]
        x = p + K * sp
        y = (x - phi) * BINS
        b0 = int(math.floor(y - EPS_BIN))
        b1 = int(math.ceil(y + EPS_BIN)) - 1
        # bin b: place b & (BINS - 1), segment b >> LOG_BINS
        u = su[b0 & (BINS - 1), pad + (b0 >> LOG_BINS)]
        lw = sl[b0 & (BINS - 1), pad + (b0 >> LOG_BINS)]
        if b1 > b0:
            u = max(u, su[b1 & (BINS - 1), pad + (b1 >> LOG_BINS)])
            lw = min(lw, sl[b1 & (BINS - 1), pad + (b1 >> LOG_BINS)])
        out[q] = _code(e[q], e_hi[q], lw, u, h, h + K * rr[q] + K * K * cc[q], margin, x, P)


@njit(cache=True)
def _blocks(spread):
    """(M, W_end): how rays of several slopes (``spread`` = the fastest's step less the
    slowest's, positions per line; the bins follow the slowest) are carried. Lines go in blocks
    of M (line v is the (v mod M)-th of its block): the bins of a line bound every ray that
    crossed the block's first line in the bin's tube, i.e. the bin widened on its far side by
    the drift so far, (v mod M) * spread, whose terrain ``_bin_pass`` bounds exactly; such rays
    stay in the tube of one bin of the next line, so the bounds are carried bin to bin without
    widening, but at a block's last line, where they reach the W_end bins that hold the tube
    at the next block's start (2 while M*BINS*spread < 1). So the bounds widen by W_end - 1
    bins per M lines, about the true spread of the rays (one bin per line before: 6-8 % of
    the cells of an SRTM tile undecided, 1 % now). One ray (spread 0): one block, no widening."""
    if spread <= 0.0:
        return np.int64(1) << 62, np.int64(1)
    M = int(math.floor((1.0 - 4.0 * EPS_BIN) / (BINS * spread)))
    if M < 1:
        M = 1
    W_end = int(math.ceil(1.0 + M * BINS * spread + EPS_BIN))
    return np.int64(M), np.int64(W_end)


@njit(cache=True)
def _strip_block(z, ZB, SU, SL, RO, v_top, nb, p0, p1, L, P, pad, s_c, M, spread, W_end, d_up,
                 d_lo, s_arr, rise_arr, curv_arr, ok_arr, per_line, K, margin, dom_col, flip_line,
                 flip_pos, out, fld):
    """Lines v_top .. v_top-nb+1, positions [p0, p1): load, bounds, decisions, store. ``ZB``
    holds the heights with ``ZO`` NaN positions before each line."""
    R = ZB.shape[0]
    ZL = ZB[:, ZO:]
    # the bins of the segment before the strip too, and the heights they need: a cell at p0
    # looks its bounds up K lines on where its ray is, which the lattice's phase can put in
    # segment p0 - 1, a segment of the strip behind, which has not reached those lines yet
    # (with two strips of 85 positions, 7 cells of a column differed from the plain march).
    # Both strips compute that segment of a line from the same values: the same bounds.
    load_lines(z, ZL, v_top, nb, max(p0 - 1, 0), p1, dom_col, flip_line, flip_pos)
    use = fld[0]
    if use:                           # a sun per cell: the heights less the field's potential
        less_potential(ZB, ZO, v_top, nb, max(p0 - 1, 0), p1, fld[16], fld[17])
    i0 = p0 - 1
    i1 = min(p1, P)
    W = np.empty((5, p1 - p0))        # work rows of the decisions
    D = np.empty(K + 1, np.int64)
    nf = P if use else 1              # each position's ray of a field's line, and its night
    FS, FR, FC = np.empty(nf), np.empty(nf), np.empty(nf)
    FOK, FN = np.zeros(nf, np.bool_), np.zeros(nf, np.bool_)
    IX = np.empty(nf, np.int64)
    XP, DXL, DYL = np.empty(nf), np.empty(nf), np.empty(nf)
    PF = np.empty(P)                  # each position as a float
    for p in range(p0, p1):
        PF[p] = p
    if use:   # positions' index in the lattice's raster (and spacing when it is per row)
        o_pos = fld[7] if fld[11] else fld[8]
        for p in range(p0, p1):
            x = P - 1 - p if fld[14] else p
            XP[p] = x + o_pos
            if fld[11]:
                DXL[p] = fld[2][x]
                DYL[p] = fld[3][x]
    RUNS = np.empty(fld[1].shape[0] + 2 if use else 1, np.int64)   # (at most n - 1 runs)
    nruns = field_runs(fld, p0, p1, XP, IX, RUNS) if use else 0
    for i in range(nb):
        v = v_top - i
        row = v % R
        nxt = (v + 1) % R
        off, phi = _phase(v, s_c)
        off1, _ = _phase(v + 1, s_c)
        jb = v % M                    # lines since the block's start: the drift so far
        ext = jb * spread + (EPS_BIN / BINS if jb > 0 and spread > 0.0 else 0.0)
        _bin_pass(ZB[row], ZO, SU[nxt], SL[nxt], SU[row], SL[row], i0, i1, pad, phi,
                  off1 - off, ext, W_end if jb == M - 1 else 1, d_up, d_lo)
        if use:
            field_line(fld, v, p0, p1, L, P, FS, FR, FC, FOK, FN, IX, XP, PF, DXL, DYL, RUNS,
                        nruns)
            ro = RO[row, p0:p1]
            _decide_positions(ZB, SU, SL, R, v, p0, p1, P, FS, FR, FC, FOK, K, pad, margin, s_c,
                              ro, W, D, PF)
            for q in range(p1 - p0):  # a cell whose sun is down is shadowed
                if FN[p0 + q] & (ro[q] != 255):
                    ro[q] = 1
        elif per_line:
            _decide_line(ZB, SU, SL, R, v, p0, p1, P, s_arr[v], rise_arr[v], curv_arr[v], K, pad,
                         margin, ok_arr[v], s_c, W[3], W[4], RO[row, p0:p1], PF)
        else:
            _decide_positions(ZB, SU, SL, R, v, p0, p1, P, s_arr, rise_arr, curv_arr, ok_arr, K,
                              pad, margin, s_c, RO[row, p0:p1], W, D, PF)
    store_lines(out, RO, v_top, nb, p0, p1, dom_col, flip_line, flip_pos)


@njit(parallel=True, cache=True)
def _bounds_sweep(z, L, P, dom_col, flip_line, flip_pos, s_lo, s_hi, d_up, d_lo, s_arr, rise_arr,
                  curv_arr, ok_arr, per_line, K, margin, nstrips, out, fld):
    """The sweep over canonical lines from the sun's edge (``L`` lines of ``P`` positions),
    as a wavefront of ``nstrips`` strips (see ``sweep._sweep_uniform``). Writes 0 / 1 /
    UNDECIDED / 255 into the DEM-shaped ``out``."""
    B = max(16, K)
    NS = nstrips
    R = NS * B + K + 2
    Q = BINS
    pad = 4                           # positions of -inf bins before the line
    s_c = s_lo                        # the bins follow the slowest ray
    M, W_end = _blocks(s_hi - s_lo)
    reach = int(math.ceil(K * max(s_hi, 0.0))) + 3
    ZB = np.full((R, ZO + P + reach + 2), np.nan)          # heights; NaN around the line
    SU = np.full((R, Q, pad + P + reach + pad), -np.inf)  # bounds; -inf around the line
    SL = np.full((R, Q, pad + P + reach + pad), -np.inf)
    RO = np.empty((R, P), np.uint8)
    bounds = strip_bounds(P, NS)
    for t in range(wave_steps(L, B, NS)):
        for jj in prange(NS):
            j = np.int64(jj)
            v_top, nb = wave_block(t, j, L, B)
            if nb > 0:
                _strip_block(z, ZB, SU, SL, RO, v_top, nb, bounds[j + 1], bounds[j], L, P, pad,
                             s_c, M, s_hi - s_lo, W_end, d_up, d_lo, s_arr, rise_arr, curv_arr,
                             ok_arr, per_line, K, margin, dom_col, flip_line, flip_pos, out, fld)


def _canonical_rays(rays: SunRays, f):
    """Each row's ray in the frame ``f``: (s, rise, curv, ok) indexed by the canonical index
    that runs over the DEM's rows (lines when lines are rows, else positions); ok is False for
    rows whose own dominant axis or direction is not the frame's."""
    ok = (rays.dom_col.astype(bool) == f.dom_col) & (rays.step_dom == f.sd)
    s = rays.step_other * (-1.0 if f.flip_pos else 1.0)
    ok &= (s >= 0.0) | ~np.isfinite(s)
    s = np.where(ok, s, 0.0).astype(np.float64)
    rise = np.where(ok, rays.rise, 0.0).astype(np.float64)
    curv = np.where(ok, rays.curv, 0.0).astype(np.float64)
    flip = f.flip_line if not f.dom_col else f.flip_pos
    if flip:
        s, rise, curv, ok = s[::-1].copy(), rise[::-1].copy(), curv[::-1].copy(), ok[::-1].copy()
    return s, rise, curv, ok.astype(np.bool_)


def _drops(zmin: float, zmax: float, L: int, K: int, r_lo: float, r_hi: float, c_lo: float,
           c_hi: float) -> tuple[float, float, float]:
    """(d_up, d_lo, margin): the per-step rise of the straight rays the upper and the lower
    bound follow, and the margin that keeps every decision clear of the bounds' rounding.

    K lines on, the ray of a cell rises j (r + (2K + j) c) over j more steps (rise r in
    [r_lo, r_hi], curvature c in [c_lo, c_hi]; c < 0 for a sun per cell, ``field_fit``).
    The upper bound is max_j T(j) - j d_up: safe when j d_up is at most that rise for every j
    whose term can matter, the lower bound max_j T(j) - j d_lo when j d_lo is at least it.
    A term whose ray has risen over zmax - zmin cannot shadow (nor can a lower bound's term
    with j d_lo >= zmax - zmin). So:

    * d_up = r_lo + (2K + 1) c_lo when c_lo >= 0, else r_lo + (2K + J) c_lo, J the steps after
      which every ray has risen over the relief (at most L);
    * d_lo = r_hi + (2K + 1) c_hi when c_hi <= 0, else d >= r_hi + (2K + j) c_hi for every
      j < (zmax - zmin) / d: the smallest such d solves d^2 - (r_hi + 2K c_hi) d - (zmax -
      zmin) c_hi = 0 (or j < L). (It was r + (2 kmax + 1) c, the steepest step of the whole
      reach, twice the excess over r: the Moon's small radius, 1.7x the flat run at 3 deg.)"""
    span = max(0.0, zmax - zmin)
    if c_lo >= 0.0:
        d_up = r_lo + (2 * K + 1) * c_lo
    else:
        slowest = r_lo + (2 * K + L) * c_lo      # the least a step rises within the raster
        J = min(L, math.ceil(span / slowest) + 1) if slowest > 0 else L
        d_up = (r_lo + (2 * K + J) * c_lo) * (1.0 - 1e-12) + 1e-12 * c_lo
    if c_hi <= 0.0:
        d_lo = r_hi + (2 * K + 1) * c_hi
    else:
        a = r_hi + 2 * K * c_hi
        d_lo = min(0.5 * (a + math.sqrt(a * a + 4.0 * span * c_hi)), a + L * c_hi)
        d_lo = d_lo * (1.0 + 1e-12) + 1e-12 * c_hi
    kmax = min(L, math.ceil(span / r_lo) + 1) if r_lo > 0 else L
    big = max(abs(zmin), abs(zmax)) + 1.0
    return d_up, d_lo, 1e-9 * big + 4e-16 * (L + K + 8) * (big + kmax * abs(d_lo))


def _pyramid_for_open(out: np.ndarray, pyramid, steps: float):
    """The pyramid for the cells the bounds left open (``pyramid.for_few``: none to build for a
    few of them)."""
    from .counts import count_code
    from .pyramid import for_few
    return for_few(pyramid, lambda: int(count_code(out, np.uint8(UNDECIDED))), out.size, steps)


MIN_STRIP = 64     # fewest positions per strip: a 400-column tile still takes two threads


def strip_count(P: int, s: float, K: int) -> int:
    """The sweep's strips (``sweep.strip_count``), wider by the bins' reach on the next line, and
    as narrow as ``MIN_STRIP`` (the sweep's 256 left small tiles to one thread: 1.6x slower)."""
    return sweep_strips(P, s, K, 8, MIN_STRIP)


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None,
                stats: dict | None = None, pyramid=True,
                zrange: tuple[float, float] | None = None) -> np.ndarray:
    """Exact shadow mask (uint8 1 shadow / 0 lit / 255 void), brute's cell for cell: the bounds
    decide most cells, the pyramid march the rest. ``pyramid``: a ``MaxPyramid`` of ``z`` to
    reuse (True: build one when cells are left; False: the plain march for them). ``zrange``:
    the lowest and highest valid height of ``z`` when the caller knows them (saves a pass)."""
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    out = np.empty(z.shape, np.uint8)
    zmin, zhi = (z_range(z)[:2] if zrange is None else (float(zrange[0]), float(zrange[1])))
    if not math.isfinite(zmin):      # nothing but voids
        out[...] = 255
        return out
    zmax = float(zhi) if zmax is None else float(zmax)
    if not math.isfinite(float(np.max(rays.rise))):   # sun at the zenith
        out[...] = np.where(np.isnan(z), 255, 0)
        return out
    f = frame_of(rays, len(rays.rise) // 2)
    s, rise, curv, ok = _canonical_rays(rays, f)
    L, P = (z.shape[1], z.shape[0]) if f.dom_col else z.shape
    K = EXACT_STEPS
    if ok.any() and L > 1 and P > 1:
        s_lo, s_hi = float(s[ok].min()), float(s[ok].max())
        r_lo, r_hi = float(rise[ok].min()), float(rise[ok].max())
        c_lo, c_hi = float(curv[ok].min()), float(curv[ok].max())
        d_up, d_lo, margin = _drops(zmin, zmax, L, K, r_lo, r_hi, c_lo, c_hi)
        per_line = not f.dom_col
        if f.dom_col and ok.all() and s_lo == s_hi and r_lo == r_hi and c_lo == c_hi:
            # one ray for every row: the line passes (indexed by line) serve the column frames too
            s, rise, curv = np.full(L, s_lo), np.full(L, r_lo), np.full(L, c_lo)
            ok, per_line = np.ones(L, np.bool_), True
        _bounds_sweep(z, L, P, f.dom_col, f.flip_line, f.flip_pos, s_lo, s_hi, d_up, d_lo, s,
                      rise, curv, ok, per_line, K, margin, strip_count(P, s_hi, K), out,
                      field_args())
    else:
        out[...] = np.where(np.isnan(z), np.uint8(255), np.uint8(UNDECIDED))
    left = brute.refine(z, rays, out, UNDECIDED, zmax,
                        _pyramid_for_open(out, pyramid, reach(z.shape, (zmin, zmax), rays)))
    if stats is not None:   # of all cells (a count of the valid ones would cost a pass)
        stats["undecided_fraction"] = left / max(1, out.size)
    return out


FIELD_SAMPLE = 1024    # rays a small raster's field is fitted to, about (``field_step``)


def field_step(cells: int) -> int:
    """Every how many lines and positions ``shadow_mask_field`` takes a cell's ray for the
    field's fit and ranges: 16 on a raster of over 2^16 cells, else about ``FIELD_SAMPLE`` rays
    (1 below 4096 cells). The mask does not depend on it (the bounds decide only the cells whose
    rays lie in the ranges, the exact march the rest): only the cells left to the march do."""
    if cells > 1 << 16:
        return 16
    return max(1, math.isqrt(cells // FIELD_SAMPLE))


def shadow_mask_field(z: np.ndarray, grid, vec: np.ndarray, curv_coef: float = 0.0,
                      zmax: float | None = None, stats: dict | None = None, pyramid=True,
                      zrange: tuple[float, float] | None = None, place=None) -> np.ndarray:
    """``shadow_mask`` with every cell's own sun (``field``: the lattice ``vec``; ``place`` as
    for ``per_cell_sun.sun_args``): the bounds made for the range of the cells' rays over the heights
    less the field's potential (``field_fit``), each cell its own ray for its exact samples
    and lookup, undecided cells the field's exact march. The mask equals
    ``per_cell_sun.shadow_mask``'s."""
    from . import per_cell_sun
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    out = np.empty(z.shape, np.uint8)
    zmin, zhi = (z_range(z)[:2] if zrange is None else (float(zrange[0]), float(zrange[1])))
    if not math.isfinite(zmin):
        out[...] = 255
        return out
    zmax = float(zhi) if zmax is None else float(zmax)
    rows, cols = z.shape
    sun = per_cell_sun.sun_args(grid, vec, curv_coef, place)
    _, dc, sd, so, ri, _ = per_cell_sun.cell_ray(rows // 2, cols // 2, *sun)
    f = Frame(dom_col=bool(dc), flip_line=sd < 0, flip_pos=so < 0, s=abs(so), so=so, sd=int(sd),
              rise=ri, step_m=0.0)
    L, P = (cols, rows) if f.dom_col else (rows, cols)
    # the rays of every 16th line and position (on a raster of up to 2^16 cells, every step-th
    # of about 1000 rays: all 30 000 of a 200 x 150 raster cost 10 ms a sun, 3x its sweep):
    # their fit and ranges; a cell whose ray falls outside the ranges is left to the exact march
    step = field_step(rows * cols)
    sample = per_cell_sun.field_sample(rows, cols, *sun, f.dom_col, np.int64(sd), f.flip_line,
                                f.flip_pos, np.int64(step))
    K = EXACT_STEPS
    if len(sample) and L > 1 and P > 1 and np.isfinite(sample[:, 3]).all():
        A, B, (s_lo, s_hi), (r_lo, r_hi), (c_lo, c_hi), (ph_lo, ph_hi) = field_fit(sample, L, P)
        d_up, d_lo, margin = _drops(zmin - ph_hi, zmax - ph_lo, L, K, r_lo, r_hi, c_lo, c_hi)
        one = np.zeros(1)
        _bounds_sweep(z, L, P, f.dom_col, f.flip_line, f.flip_pos, s_lo, s_hi, d_up, d_lo, one,
                      one, one, np.ones(1, np.bool_), False, K, margin, strip_count(P, s_hi, K),
                      out, field_args(vec, grid, curv_coef, f, L,
                                       (A, B, s_lo, s_hi, r_lo, r_hi, c_lo, c_hi), place))
    else:
        out[...] = np.where(np.isnan(z), np.uint8(255), np.uint8(UNDECIDED))
    left = per_cell_sun.refine(z, grid, vec, curv_coef, zmax, out, UNDECIDED,
                        _pyramid_for_open(out, pyramid, steps_over(zmax - zmin, ri, L)), place)
    if stats is not None:
        stats["undecided_fraction"] = left / max(1, out.size)
    return out
