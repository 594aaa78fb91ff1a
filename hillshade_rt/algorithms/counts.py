"""Counting a product's codes in one parallel pass (the report's cell counts), without the
int64 copy of every cell that ``np.bincount`` makes of a uint8 array."""

import numpy as np
from numba import njit, prange


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
