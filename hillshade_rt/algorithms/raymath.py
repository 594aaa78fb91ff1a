"""Per-ray arithmetic of the terrain model, written once as plain Python functions.

Every algorithm and backend uses these. They are ``njit`` functions, so CPU kernels call them
directly; their plain source stays available as ``.py_func`` for a GPU backend to compile with
``numba.cuda.jit(device=True)`` (numba-cuda also calls ``njit`` functions from kernels). Keep them
free of anything a CUDA device function cannot do (no allocation, no exceptions, no Python objects).

The model (docs/model.md): a ray leaves the centre of a cell toward the sun and is sampled where it
crosses the grid lines of its dominant axis; on such a line the terrain height is linearly
interpolated between the two nearest cell centres. Outside the raster there is no terrain.
"""

import math

import numpy as np
from numba import njit

# A position within EDGE_EPS of the first or last cell centre of a line counts as on it: this
# absorbs the rounding of ``start + k * step`` without changing the model.
EDGE_EPS = 1e-9


@njit(cache=True)
def line_position(pos, n):
    """Snap ``pos`` (fractional index along a grid line of n cells) into [0, n-1].

    Returns -1.0 when the position is outside the raster (the ray has left it).
    """
    if pos < 0.0:
        if pos > -EDGE_EPS:
            return 0.0
        return -1.0
    if pos > n - 1:
        if pos < n - 1 + EDGE_EPS:
            return float(n - 1)
        return -1.0
    return pos


@njit(cache=True)
def terrain_on_line(z, dom_col, line, pos):
    """Terrain height (float64) where a ray crosses grid line ``line`` at position ``pos``.

    ``dom_col`` true: the line is column ``line`` and pos runs over rows; false: the line is row
    ``line`` and pos runs over columns. ``pos`` must already be inside [0, n-1]
    (``line_position``). NaN (a void) propagates: comparisons with it are false, so a ray skips
    voids.
    """
    i0 = int(math.floor(pos))
    f = pos - i0
    if dom_col:
        a = float(z[i0, line])
        if f == 0.0:
            return a
        b = float(z[i0 + 1, line])
    else:
        a = float(z[line, i0])
        if f == 0.0:
            return a
        b = float(z[line, i0 + 1])
    # a + f*(b-a) is exact when a == b (flat tops stay flat)
    return a + f * (b - a)


@njit(cache=True)
def ray_is_blocked(z, r, c, dom_col, step_dom, step_other, rise, zmax):
    """True when the ray from the centre of cell (r, c) passes strictly below the terrain.

    Marches grid line by grid line toward the sun; stops when the ray leaves the raster or climbs
    to ``zmax`` (the highest cell), above which nothing can block it. Heights in float64, the k-th
    sample computed as ``h0 + k * rise`` (no accumulated drift).
    """
    rows, cols = z.shape
    r = np.int64(r)  # prange indices may be unsigned; mixing them with int64 would give floats
    c = np.int64(c)
    h0 = float(z[r, c])
    if dom_col:
        line0, other0, n_dom, n_oth = c, r, cols, rows
    else:
        line0, other0, n_dom, n_oth = r, c, rows, cols
    k = 1
    while True:
        hr = h0 + k * rise
        if hr >= zmax:
            return False
        line = line0 + k * step_dom
        if line < 0 or line >= n_dom:
            return False
        pos = line_position(other0 + k * step_other, n_oth)
        if pos < 0.0:
            return False
        if terrain_on_line(z, dom_col, line, pos) > hr:
            return True
        k += 1

