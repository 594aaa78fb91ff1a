"""Counting passes, parallel and without temporaries: a product's codes (the report's cell
counts, without the int64 copy of every cell that ``np.bincount`` makes of a uint8 array), a
DEM's valid cells and height range (``auto``'s survey, ``sweep``, ``bounds``, the GPU) and its
height range per block (``block_range``: the windowed runs' statistics pass), and the read's
nodata-to-NaN pass that finds them on the way (``clean_heights``)."""

import math

import numpy as np
from numba import prange

from ._jitcache import njit


@njit(parallel=True, cache=True)
def _count_rows(a):
    rows = a.shape[0]
    per = np.zeros((rows, 256), np.int64)
    for r in prange(rows):
        for v in a[r]:
            per[r, v] += 1
    return per.sum(axis=0)


def code_counts(a: np.ndarray) -> np.ndarray:
    """How many cells of the uint8 array ``a`` hold each of the 256 codes."""
    if a.ndim != 2:
        a = a.reshape(1, -1) if a.ndim == 1 else a.reshape(-1, a.shape[-1])
    if a.shape[0] < 64:   # few rows: count blocks of a flat view so that the pass stays parallel
        flat = np.ascontiguousarray(a).reshape(-1)
        n = flat.size - flat.size % 4096
        out = _count_rows(flat[:n].reshape(-1, 4096)) if n else np.zeros(256, np.int64)
        return out + np.bincount(flat[n:], minlength=256)
    return _count_rows(a)


@njit(cache=True)
def _row_range(row):
    """(valid cells, lowest, highest valid height) of one row (a function of its own: numba's
    parfor analysis of Python >= 3.12 bytecode fails on scalars updated in a loop nested in a
    prange: https://github.com/numba/numba/issues/10132)."""
    a, b, c = 0, np.inf, -np.inf
    for h in row:
        if h == h:
            a += 1
            b = min(b, h)
            c = max(c, h)
    return a, b, c


@njit(parallel=True, cache=True)
def valid_range(z):
    """(valid cells, lowest, highest valid height) of 2-D heights in one pass, parallel over
    rows (inf / -inf when nothing is valid)."""
    rows = z.shape[0]
    n = np.zeros(rows, np.int64)
    lo = np.full(rows, np.inf)
    hi = np.full(rows, -np.inf)
    for r in prange(rows):
        n[r], lo[r], hi[r] = _row_range(z[r])
    return n.sum(), lo.min() if rows else np.inf, hi.max() if rows else -np.inf


def z_range(z):
    """(lowest, highest valid height, whether there are voids) in one pass, no temporaries."""
    n, lo, hi = valid_range(z)
    return float(lo), float(hi), bool(n < z.size)


@njit(parallel=True, cache=True)
def block_range(z, B, bmin, bmax):
    """Lowest and highest valid height of each B x B block of ``z`` (rows of blocks in ``bmin``,
    ``bmax``; +inf / -inf for a block of voids); returns the count of valid cells (the windowed
    runs' statistics pass, ``engine.windows.block_stats``)."""
    nbr, nbc = bmin.shape
    rows, cols = z.shape
    counts = np.zeros(nbr * nbc, np.int64)
    for k in prange(nbr * nbc):
        i = k // nbc
        j = k % nbc
        lo = np.inf
        hi = -np.inf
        n = 0
        for r in range(i * B, min(rows, (i + 1) * B)):
            for c in range(j * B, min(cols, (j + 1) * B)):
                h = z[r, c]
                if not math.isnan(h):
                    n += 1
                    if h < lo:
                        lo = h
                    if h > hi:
                        hi = h
        bmin[i, j] = lo
        bmax[i, j] = hi
        counts[k] = n
    return counts.sum()


@njit(cache=True)
def _clean_line(line, nd, use_nodata):
    nan = np.float32(np.nan)
    a, b, c = 0, np.inf, -np.inf
    for j in range(line.shape[0]):
        h = line[j]
        if (use_nodata and h == nd) or not np.isfinite(h):
            line[j] = nan
        else:
            a += 1
            b = min(b, h)
            c = max(c, h)
    return a, b, c


@njit(parallel=True, cache=True)
def clean_heights(z, nodata, use_nodata):
    """In place on 2-D float32 heights: ``nodata`` (when ``use_nodata``), NaN and +-inf to NaN;
    returns ``valid_range`` of the result. One parallel pass (numpy's took five, 0.32 s of a
    10000² read, and the valid count and height range two more)."""
    rows = z.shape[0]
    nd = np.float32(nodata)
    n = np.zeros(rows, np.int64)
    lo = np.full(rows, np.inf)
    hi = np.full(rows, -np.inf)
    for r in prange(rows):
        n[r], lo[r], hi[r] = _clean_line(z[r], nd, use_nodata)
    return n.sum(), lo.min() if rows else np.inf, hi.max() if rows else -np.inf


@njit(parallel=True, cache=True)
def has_code(a, code):
    """Whether the 2-D uint8 array ``a`` holds ``code`` anywhere (parallel over rows, without the
    boolean copy of ``(a == code).any()``)."""
    rows = a.shape[0]
    hit = np.zeros(rows, np.bool_)
    for r in prange(rows):
        for v in a[r]:
            if v == code:
                hit[r] = True
                break
    return hit.any()


@njit(parallel=True, cache=True)
def count_code(a, code):
    """How many cells of the 2-D uint8 array ``a`` hold ``code`` (parallel over rows)."""
    rows = a.shape[0]
    n = np.zeros(rows, np.int64)
    for r in prange(rows):
        k = 0
        for v in a[r]:
            k += v == code
        n[r] = k
    return n.sum()


def any_code(a: np.ndarray, code: int) -> bool:
    """Whether ``a`` holds ``code`` anywhere: ``has_code`` on a C-contiguous 2-D uint8 mask,
    numpy otherwise (what the refinements ask before they march)."""
    if a.ndim == 2 and a.flags.c_contiguous and a.dtype == np.uint8:
        return bool(has_code(a, np.uint8(code)))
    return bool((a == code).any())
