"""The exact scan of ``horizon`` taken row by row: the same samples, comparisons and bits as the
per-cell march (``horizon._march``), several times faster for the first samples of every ray.

For one direction, the rays of all cells of a row share their geometry (the row's step along
the dominant axis, its step across, its curvature term). Their k-th samples therefore lie on
one grid line position (rays crossing columns: row ``r + k*so`` for every cell, the cells'
samples k columns apart; rays crossing rows: row ``r + k*sd``, positions ``c + k*so``), so
sample k of the whole row is one loop over contiguous memory that the compiler vectorises
(one division per cell and sample, no branch: the update is a select). Looping over k outside
and the cells inside takes each cell's samples in the march's order with the march's
arithmetic (``raymath``'s position, snapping and interpolation; ``lift > best*k``, then
``best = lift/k``), including its exits (past ``--max-distance``, out of the raster, nothing
higher ahead than the DEM's highest cell, above the cap), so each cell ends with the march's
maximum and its k, bit for bit. ``horizon._rows_kernel`` drives it.

A row stays dense while at least one cell in 8 (rays crossing columns) or 2 (crossing rows,
whose loads are costlier) still marches; its remaining cells then finish with the per-cell
march over the maximum-height pyramid, from the state the dense samples left (the march
resumes from any sample with the same bits: ``horizon._march``). Short rays
(``--max-distance`` of tens of cells, the usual sky view factor radius) are all dense; long
rays spend their first samples dense, where most of the rays of a rough DEM are decided, and
their long tails in the pyramid march. The GPU keeps one thread per cell (``horizon._scan_gpu``).

References
----------
.. [1] T. Aslandere, M. Flatken, A. Gerndt, "A Real-Time Physically Based Algorithm for Hard
       Shadows on Dynamic Height-Fields," German Aerospace Center (DLR), Simulation and Software
       Technology (no date given in the paper).
"""

import math

import numpy as np
from ._jitcache import njit
from .raymath import EDGE_EPS, line_position, madd

# a row stays dense while more than one cell in DENSE_COLS (rays crossing columns: contiguous
# loads) or DENSE_ROWS (rays crossing rows) still marches; measured on the repository's DEMs
DENSE_COLS = 8
DENSE_ROWS = 2
# samples between two counts of the cells still marching
CHUNK = 16


@njit(cache=True, inline="always")
def _take(j, a, bb, f, out, h0, best, kb, done, fk, kk, cv, zmax, cap, k):
    """Cell j's sample k, between heights ``a`` and ``bb`` at fraction ``f`` (``out``: the
    sample lies outside the raster), as the march takes it: stop once no later sample can
    raise the maximum (``zmax``), else raise the maximum ``best`` (per step; ``kb`` its k)
    where the sample is higher, and stop past ``cap``. Branch-free (selects), so the loops
    that call it vectorise."""
    b0 = best[j]
    h = h0[j]
    bk = b0 * fk
    t = a if f == 0.0 else madd(a, f, bb - a)
    lift = t - h
    if cv != 0.0:
        lift = madd(lift, -kk, cv)
    nb = lift / fk
    stop = zmax - h <= bk
    d = done[j]
    upd = (d == 0) & (not stop) & (not out) & (lift > bk)
    best[j] = nb if upd else b0
    kb[j] = k if upd else kb[j]
    done[j] = d | stop | out | (upd & (nb > cap))


@njit(cache=True)
def _step_cols(s0, s1, f, h0, best, kb, done, fk, kk, cv, zmax, cap, k):
    """Sample k of a run of cells of a row whose rays cross columns: every cell's sample lies
    on the same row position (fraction ``f``), its two neighbours at the same index of ``s0``
    and ``s1`` (the two rows' cells k columns ahead, contiguous): one vectorised loop of
    ``_take``."""
    n = best.shape[0]
    for j in range(n):
        a = float(s0[j])
        bb = float(s1[j])
        _take(j, a, bb, f, False, h0, best, kb, done, fk, kk, cv, zmax, cap, k)


@njit(cache=True)
def _step_rows_fast(s0, s1, s2, j0q, ks, q, h0, best, kb, done, fk, kk, cv, zmax, cap, k):
    """Cells j0 .. of a row whose samples' two neighbours lie in s0/s1 or s1/s2 (contiguous
    slices starting at j0 + q, j0 + q + 1, j0 + q + 2): floor(pos) is base or base + 1."""
    n = best.shape[0]
    for j in range(n):
        base = float(j0q + j)          # j + q as a float, exact
        pos = float(j0q - q + j) + ks
        up = pos >= base + 1.0
        f = pos - (base + 1.0) if up else pos - base
        a = float(s1[j]) if up else float(s0[j])
        bb = float(s2[j]) if up else float(s1[j])
        _take(j, a, bb, f, False, h0, best, kb, done, fk, kk, cv, zmax, cap, k)


@njit(cache=True)
def _step_rows(zl, ks, h0, best, kb, done, fk, kk, cv, zmax, cap, k, ja, jb):
    """Sample k of cells ja..jb-1 of a row whose rays cross rows (the line ``zl``): each
    cell's own position ``j + ks`` on it, snapped or out as ``raymath.line_position`` does
    (the cells near the row's ends)."""
    n = zl.shape[0]
    top = float(n - 1)
    for j in range(ja, jb):
        pos = float(j) + ks
        out = (pos <= -EDGE_EPS) | (pos >= top + EDGE_EPS)
        pos = min(max(pos, 0.0), top)
        i0 = np.int64(math.floor(pos))
        f = pos - i0
        i1 = min(i0 + 1, n - 1)
        a = float(zl[i0])
        bb = float(zl[i1])
        _take(j, a, bb, f, out, h0, best, kb, done, fk, kk, cv, zmax, cap, k)


@njit(cache=True)
def row_dense(z, r, dom_col, sd, so, cv, zmax, cap, ka, k1, h0, best, kb, done):
    """Samples ka..k1 of every cell of row r, sample by sample over the whole row; returns
    how many cells still march (0 when the row's rays have all left the raster)."""
    rows, cols = z.shape
    for k in range(ka, k1 + 1):
        fk = float(k)
        kk = float(k * k)
        if dom_col:
            pos = line_position(madd(float(r), fk, so), rows)
            if pos < 0.0:
                return 0
            i0 = np.int64(math.floor(pos))
            f = pos - i0
            i1 = i0 + 1 if f != 0.0 else i0
            shift = k * sd
            lo = max(0, -shift)
            hi = min(cols, cols - shift)
            if hi <= lo:
                return 0
            done[:lo] = 1
            done[hi:] = 1
            _step_cols(z[i0, lo + shift:hi + shift], z[i1, lo + shift:hi + shift], f, h0[lo:hi],
                       best[lo:hi], kb[lo:hi], done[lo:hi], fk, kk, cv, zmax, cap, k)
        else:
            line = r + k * sd
            if line < 0 or line >= rows:
                return 0
            ks = fk * so
            q = np.int64(math.floor(ks))
            j0 = max(0, -q)
            j1 = min(cols, cols - 2 - q)
            if j1 > j0:
                zl = z[line]
                _step_rows(zl, ks, h0, best, kb, done, fk, kk, cv, zmax, cap, k, 0, j0)
                _step_rows_fast(zl[j0 + q:j1 + q], zl[j0 + q + 1:j1 + q + 1], zl[j0 + q + 2:j1 + q + 2],
                                j0 + q, ks, q, h0[j0:j1], best[j0:j1], kb[j0:j1], done[j0:j1],
                                fk, kk, cv, zmax, cap, k)
                _step_rows(zl, ks, h0, best, kb, done, fk, kk, cv, zmax, cap, k, j1, cols)
            else:
                _step_rows(z[line], ks, h0, best, kb, done, fk, kk, cv, zmax, cap, k, 0, cols)
    n = 0
    for c in range(cols):
        n += 1 - done[c]
    return n

