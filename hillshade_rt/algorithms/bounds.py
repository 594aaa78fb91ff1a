"""``bounds``: exact shadows from guaranteed bounds of every cell's horizon, the pyramid march
for the few cells the bounds leave open.

The flag-map sweep of seed 001 (``sweep``) stores for each cell what its ray met and lets the
next rays interpolate it: fast, and wrong where a thin ridge passes between two neighbouring
rays. Here the stored values are made **conservative**, so that a cell is decided only when no
ray between the stored ones could decide it otherwise:

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
whose terrain could still reach it (``_drop_and_margin``).

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
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..geometry import SunRays
from . import brute
from .field import cell_ray
from .frames import Frame, dem_index, frame_of
from .sweep import _load_lines, _store_lines, _z_range, strip_bounds, wave_block, wave_steps
from .sweep import _strips as sweep_strips

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
    void = not (ta == ta and tb == tb)
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
        sua, sub, suc = su_n[ma], su_n[mb], su_n[mc]
        sla, slb, slc = sl_n[ma], sl_n[mb], sl_n[mc]
        ou = su_c[m]
        ol = sl_c[m]
        for i in range(i0, i1):
            a = zb[zo + i]
            b = zb[zo + i + 1]
            if straddle:
                h1, l1 = _bin_bounds(a, b, fa, 1.0)
                h2, l2 = _bin_bounds(b, zb[zo + i + 2], 0.0, fb - 1.0)
                hi_t = h1 if h1 > h2 else h2
                lo_t = l2 if l1 > l2 else l1
            else:
                hi_t, lo_t = _bin_bounds(a, b, fa, fb)
            if W == 1:
                u = sua[da + i]
                lw = sla[da + i]
            elif W == 2:
                x, y = sua[da + i], sub[db + i]
                u = x if x > y else y
                x, y = sla[da + i], slb[db + i]
                lw = y if x > y else x
            elif W == 3:
                x, y, w = sua[da + i], sub[db + i], suc[dc + i]
                x = x if x > y else y
                u = x if x > w else w
                x, y, w = sla[da + i], slb[db + i], slc[dc + i]
                x = y if x > y else x
                lw = w if x > w else x
            else:    # rays of many rows spread over more bins
                u = -np.inf
                lw = np.inf
                for j in range(W):
                    mj = (q + j) % Q
                    dj = padp + (q + j) // Q + i
                    u = max(u, su_n[mj, dj])
                    lw = min(lw, sl_n[mj, dj])
            u -= d_up
            lw -= d_lo
            ou[padp + i] = u if u > hi_t else hi_t
            ol[padp + i] = lw if lw > lo_t else lo_t


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
    sh = (e > h + margin) or (lw > hk + margin)
    lit = (e_hi <= h - margin) and (u <= hk - margin) and (x <= P - 1 - 1e-6)
    c = np.uint8(1) if sh else (np.uint8(0) if lit else np.uint8(UNDECIDED))
    return np.uint8(255) if h != h else c


@njit(cache=True)
def _decide_line(ZL, SU, SL, R, v, p0, p1, P, s, rise, curv, K, pad, margin, ok, s_c, e, e_hi,
                 out):
    """Codes of positions [p0, p1) of canonical line v whose cells share one ray (s, rise,
    curv): the same decisions as ``_decide_positions``, with the sample offsets and fractions of the
    line computed once, in passes along the line that vectorise. ``e``, ``e_hi``: work space."""
    n = p1 - p0
    row = v % R
    if not ok:
        for q in range(n):
            h = ZL[row, p0 + q]
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
        zr = ZL[(v + k) % R]
        if f == 0.0:
            for q in range(n):
                t = zr[p0 + d + q] - drop
                e[q] = t if t > e[q] else e[q]     # NaN (void, outside) compares false
                e_hi[q] = t if t > e_hi[q] else e_hi[q]
        else:
            snap = f < SNAP or f > 1.0 - SNAP
            for q in range(n):
                za = zr[p0 + d + q]
                zb = zr[p0 + d + q + 1]
                t = za + f * (zb - za) - drop
                if not snap:
                    e[q] = t if t > e[q] else e[q]
                else:
                    t = _sample_hi(za, zb, f) - drop
                e_hi[q] = t if t > e_hi[q] else e_hi[q]
    xk = K * s
    _, phi = _phase(v + K, s_c)
    y = (xk - phi) * BINS             # bin of position p + xk on line v+K: BINS * p + y
    b0 = int(math.floor(y - EPS_BIN))
    b1 = int(math.ceil(y + EPS_BIN)) - 1
    sua, sla, sub, slb, da, db = _lookup_rows(SU, SL, (v + K) % R, b0, b1, pad)
    hk = K * rise + K * K * curv
    zl = ZL[row]
    for q in range(n):   # _looked_up written out: inlined here it stops the loop vectorising
        p = p0 + q        # (Big Tujunga and a 2048² fractal 12-15 % slower)
        u = sua[da + p]
        lw = sla[da + p]
        if b1 > b0:
            u = max(u, sub[db + p])
            lw = min(lw, slb[db + p])
        h = zl[p]
        out[q] = _code(e[q], e_hi[q], lw, u, h, h + hk, margin, p + xk, P)


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
def _decide_run(ZL, SU, SL, R, v, p0, p1, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad, margin,
                D, b0, b1, out):
    """``_decide_positions`` for a run of positions [p0, p1) whose rays differ (each its row's)
    but share their whole offsets (``_run_offsets``): one pass, each cell's K samples (K =
    EXACT_STEPS, unrolled) and its lookup in registers; a cell within rounding of a cell centre
    takes the exact treatment of ``_decide_cells``."""
    zl = ZL[v % R]
    sua, sla, sub, slb, da, db = _lookup_rows(SU, SL, (v + K) % R, b0, b1, pad)
    vr = v % R
    for p in range(p0, p1):
        sp = s_arr[p]
        rp = rise_arr[p]
        cp = curv_arr[p]
        e = -np.inf
        e_hi = -np.inf
        snaps = False
        for k in range(1, EXACT_STEPS + 1):
            rk = vr + k if vr + k < R else vr + k - R      # ring row of line v + k
            d = D[k]
            f = k * sp - d
            za = ZL[rk, p + d]
            t = za + f * (ZL[rk, p + d + 1] - za) - (k * rp + k * k * cp)
            snap = (f < SNAP) | (f > 1.0 - SNAP)
            snaps |= snap
            te = -np.inf if snap else t
            e = te if te > e else e                 # NaN (void, outside) compares false
            e_hi = t if t > e_hi else e_hi
        if snaps:                                   # within rounding of a cell centre (rare)
            for k in range(1, EXACT_STEPS + 1):
                rk = (v + k) % R
                d = D[k]
                f = k * sp - d
                if f < SNAP or f > 1.0 - SNAP:
                    za = ZL[rk, p + d]
                    drop = k * rp + k * k * cp
                    if f == 0.0:                    # the model's sample is the centre itself
                        e = max(e, za - drop) if za == za else e
                    t = _sample_hi(za, ZL[rk, p + d + 1], f) - drop
                    e_hi = t if t > e_hi else e_hi
        u, lw = _looked_up(sua, sla, sub, slb, da, db, p, b1 > b0)
        h = zl[p]
        c = _code(e, e_hi, lw, u, h, h + K * rp + K * K * cp, margin, p + K * sp, P)
        out[p - p0] = c if ok_arr[p] or h != h else np.uint8(UNDECIDED)


@njit(cache=True)
def _decide_positions(ZL, SU, SL, R, v, p0, p1, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad,
                      margin, s_c, out, fld, W, D):
    """Codes of positions [p0, p1) of canonical line v when each position has its own ray
    (``s_arr`` ... indexed by position: lines that are DEM columns of a per-row grid), or, with
    a field ``fld`` (``_field_args``: use, lattice, dx, dy, signs, curvature, shape, frame),
    each cell its own sun (``field.cell_ray``; a cell whose sun is down is shadowed, one whose
    ray is not in the frame's octant undecided): K exact samples, then the bounds K lines on;
    0 / 1 when they decide, UNDECIDED otherwise (the same tests as ``_decide_line``). Rows' rays
    change slowly along a line: runs of ``RUN`` positions whose rays share their whole offsets
    go to ``_decide_run`` (contiguous passes), the others and the field's cells to
    ``_decide_cells``. ``W`` (5 x strip width), ``D`` (K + 1): work space."""
    n = p1 - p0
    if fld[0] or K != EXACT_STEPS:
        _decide_cells(ZL, SU, SL, R, v, p0, 0, n, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad,
                      margin, s_c, out, fld, W)
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
            _decide_run(ZL, SU, SL, R, v, p0 + qa, p0 + qb, P, s_arr, rise_arr, curv_arr, ok_arr,
                        K, pad, margin, D, b0, b1, out[qa:qb])
        elif step > RUN:
            step = RUN
            continue
        else:
            _decide_cells(ZL, SU, SL, R, v, p0, qa, qb, P, s_arr, rise_arr, curv_arr, ok_arr, K,
                          pad, margin, s_c, out, fld, W)
        qa = qb


@njit(cache=True)
def _decide_cells(ZL, SU, SL, R, v, p0, qa, qb, P, s_arr, rise_arr, curv_arr, ok_arr, K, pad,
                  margin, s_c, out, fld, W):
    """``_decide_positions`` cell by cell for positions p0 + [qa, qb): each cell's ray (its
    row's, or its own sun's), its K samples at their own offsets, its lookup."""
    use, vec, fdx, fdy, csign, rsign, ccoef, nrows, ncols, L, fdom, fsd, fl_line, fl_pos = fld
    ss, rr, cc, e, e_hi = W[0], W[1], W[2], W[3], W[4]
    zl = ZL[v % R]
    if not use:                              # each position its own row's ray
        for q in range(qa, qb):
            p = p0 + q
            h = zl[p]
            e[q] = -np.inf
            e_hi[q] = -np.inf
            good = ok_arr[p] and h == h
            out[q] = np.uint8(UNDECIDED) if h == h else np.uint8(255)
            ss[q] = s_arr[p] if good else np.nan
            rr[q] = rise_arr[p]
            cc[q] = curv_arr[p]
    for q in range(qa, qb if use else qa):   # each cell's sun; NaN: a cell already coded
        p = p0 + q
        h = zl[p]
        e[q] = -np.inf
        e_hi[q] = -np.inf
        if h != h:
            out[q] = np.uint8(255)
            ss[q] = np.nan
            continue
        r, c = dem_index(v, p, L, P, fdom, fl_line, fl_pos)
        night, dc, sd, so, rise, curv = cell_ray(r, c, nrows, ncols, vec, fdx, fdy, csign,
                                                 rsign, ccoef)
        sp = -so if fl_pos else so
        if night:
            out[q] = np.uint8(1)
            ss[q] = np.nan
            continue
        if dc != fdom or sd != fsd or not sp >= 0.0:
            out[q] = np.uint8(UNDECIDED)
            ss[q] = np.nan
            continue
        ss[q] = sp
        rr[q] = rise
        cc[q] = curv
    for k in range(1, K + 1):                # the exact samples, one pass each (selects only:
        zr = ZL[(v + k) % R]                 # it vectorises; a coded cell samples harmlessly)
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
    _load_lines(z, ZL, v_top, nb, max(p0 - 1, 0), p1, dom_col, flip_line, flip_pos)
    i0 = p0 - 1
    i1 = min(p1, P)
    W = np.empty((5, p1 - p0))        # work rows of the decisions
    D = np.empty(K + 1, np.int64)
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
        if per_line and not fld[0]:
            _decide_line(ZL, SU, SL, R, v, p0, p1, P, s_arr[v], rise_arr[v], curv_arr[v], K, pad,
                         margin, ok_arr[v], s_c, W[3], W[4], RO[row, p0:p1])
        else:
            _decide_positions(ZL, SU, SL, R, v, p0, p1, P, s_arr, rise_arr, curv_arr, ok_arr, K,
                              pad, margin, s_c, RO[row, p0:p1], fld, W, D)
    _store_lines(out, RO, v_top, nb, p0, p1, dom_col, flip_line, flip_pos)


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


def _field_args(vec=None, grid=None, curv_coef=0.0, shape=(1, 1), f=None, L=1):
    """The field tuple of the kernels: (use, lattice, dx, dy, col sign, row sign, curvature,
    rows, cols, L, frame dom_col, frame step_dom, flip_line, flip_pos); unused without a field."""
    if vec is None:
        return (False, np.zeros((2, 2, 3)), np.ones(1), np.ones(1), 1.0, -1.0, 0.0, np.int64(1),
                np.int64(1), np.int64(1), False, np.int64(1), False, False)
    from .field import sun_args
    return (True, *sun_args(grid, vec, curv_coef), np.int64(shape[0]), np.int64(shape[1]),
            np.int64(L), bool(f.dom_col), np.int64(f.sd), bool(f.flip_line), bool(f.flip_pos))


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


def _drop_and_margin(zmin: float, zmax: float, L: int, K: int, r_lo: float, r_hi: float,
                     c_hi: float) -> tuple[float, float]:
    """(d_lo, margin): the per-step rise of the straight ray the lower bound follows, and the
    margin that keeps every decision clear of the bounds' rounding.

    The lower bound K lines on is max_j T(j) - j d_lo over the samples j steps further; a cell
    is shadowed when it exceeds the cell's ray there. That is safe when j d_lo is at least the
    curved ray's rise over those j steps, j r + (2Kj + j^2) c, for every j whose term could
    matter: terms with j d_lo >= zmax - zmin fall below the lowest cell and never do. So d_lo
    >= r + (2K + j) c for j < (zmax - zmin) / d_lo: the smallest such d_lo solves d^2 - (r +
    2Kc) d - (zmax - zmin) c = 0 (or j < L). It was r + (2 kmax + 1) c, the steepest step of
    the whole reach, twice the excess over r (the Moon's small radius: 1.7x the flat run at 3
    deg)."""
    kmax = min(L, math.ceil((zmax - zmin) / r_lo) + 1) if r_lo > 0 else L
    a = r_hi + 2 * K * c_hi
    span = max(0.0, zmax - zmin)
    d_lo = min(0.5 * (a + math.sqrt(a * a + 4.0 * span * c_hi)), a + L * c_hi)
    d_lo = d_lo * (1.0 + 1e-12) + 1e-12 * c_hi
    big = max(abs(zmin), abs(zmax)) + 1.0
    return d_lo, 1e-9 * big + 4e-16 * (L + K + 8) * (big + kmax * d_lo)


MIN_STRIP = 64     # fewest positions per strip: a 400-column tile still takes two threads


def _strips(P: int, s: float, K: int) -> int:
    """The sweep's strips (``sweep._strips``), wider by the bins' reach on the next line, and
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
    zmin, zhi = (_z_range(z)[:2] if zrange is None else (float(zrange[0]), float(zrange[1])))
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
        d_lo, margin = _drop_and_margin(zmin, zmax, L, K, r_lo, r_hi, c_hi)
        per_line = not f.dom_col
        if f.dom_col and ok.all() and s_lo == s_hi and r_lo == r_hi and c_lo == c_hi:
            # one ray for every row: the line passes (indexed by line) serve the column frames too
            s, rise, curv = np.full(L, s_lo), np.full(L, r_lo), np.full(L, c_lo)
            ok, per_line = np.ones(L, np.bool_), True
        _bounds_sweep(z, L, P, f.dom_col, f.flip_line, f.flip_pos, s_lo, s_hi,
                      r_lo + (2 * K + 1) * c_lo,
                      d_lo, s, rise, curv, ok, per_line, K, margin,
                      _strips(P, s_hi, K), out, _field_args())
    else:
        out[...] = np.where(np.isnan(z), np.uint8(255), np.uint8(UNDECIDED))
    left = brute.refine(z, rays, out, UNDECIDED, zmax, pyramid)
    if stats is not None:   # of all cells (a count of the valid ones would cost a pass)
        stats["undecided_fraction"] = left / max(1, out.size)
    return out


def shadow_mask_field(z: np.ndarray, grid, vec: np.ndarray, curv_coef: float = 0.0,
                      zmax: float | None = None, stats: dict | None = None, pyramid=True,
                      zrange: tuple[float, float] | None = None) -> np.ndarray:
    """``shadow_mask`` with every cell's own sun (``field``: the lattice ``vec``): the bounds
    take the range of the cells' rays, each cell its own ray for its exact samples and lookup,
    undecided cells the field's exact march. The mask equals ``field.shadow_mask``'s."""
    from . import field
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    out = np.empty(z.shape, np.uint8)
    zmin, zhi = (_z_range(z)[:2] if zrange is None else (float(zrange[0]), float(zrange[1])))
    if not math.isfinite(zmin):
        out[...] = 255
        return out
    zmax = float(zhi) if zmax is None else float(zmax)
    rows, cols = z.shape
    sun = field.sun_args(grid, vec, curv_coef)
    _, dc, sd, so, ri, _ = field.cell_ray(rows // 2, cols // 2, rows, cols, *sun)
    f = Frame(dom_col=bool(dc), flip_line=sd < 0, flip_pos=so < 0, s=abs(so), so=so, sd=int(sd),
              rise=ri, step_m=0.0)
    s_lo, s_hi, r_lo, r_hi, c_lo, c_hi, n = field.field_ranges(
        rows, cols, *sun, bool(dc), np.int64(sd), bool(f.flip_pos))
    L, P = (cols, rows) if f.dom_col else (rows, cols)
    K = EXACT_STEPS
    if n > 0 and L > 1 and P > 1 and math.isfinite(r_hi):
        d_lo, margin = _drop_and_margin(zmin, zmax, L, K, r_lo, r_hi, c_hi)
        one = np.zeros(1)
        _bounds_sweep(z, L, P, f.dom_col, f.flip_line, f.flip_pos, s_lo, s_hi,
                      r_lo + (2 * K + 1) * c_lo,
                      d_lo, one, one, one, np.ones(1, np.bool_), False, K, margin,
                      _strips(P, s_hi, K), out,
                      _field_args(vec, grid, curv_coef, z.shape, f, L))
    else:
        out[...] = np.where(np.isnan(z), np.uint8(255), np.uint8(UNDECIDED))
    left = field.refine(z, grid, vec, curv_coef, zmax, out, UNDECIDED, pyramid)
    if stats is not None:
        stats["undecided_fraction"] = left / max(1, out.size)
    return out
