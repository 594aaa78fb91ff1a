"""A point light (issue 21, item 1): the light at a position instead of a direction, as the source
documents place the sun ("B = coordinates of the sun position projection ... L = A - C", seed
003; "draw a straight line from the sun to the point of interest", seed 004).

The model (docs/model.md) with the ray ending at the light: from each cell centre (row r, column
c, height h0 + lift) the straight line to the light at fractional (``row_l``, ``col_l``) and
height ``height_l`` is sampled where it crosses the grid lines of its dominant axis (the axis
along which the light is farther, in cells), the terrain interpolated between the two nearest
centres on the line as everywhere; only the crossings strictly between the cell and the light
count (terrain beyond the light cannot shadow it). At the k-th crossing, a fraction k / D of the
way to the light (D the distance in cells along the dominant axis), the ray is at
h0 + (height_l - h0) k / D: the line is straight in the raster's rows and columns, so the ground
spacing does not enter (no Earth curvature: a light over a DEM is near). A cell is shadowed iff
some sample lies strictly above the ray; a cell under the light (D = 0) is lit; a light below a
cell's own height shadows it only through terrain, as any ray. Voids: 255, and a void casts no
shadow (NaN compares false).

A light 10^9 m away along an azimuth and elevation gives the directional mask (a test).
Plain march, O(cells x reach), CPU; ``ray_sample``'s arithmetic (``raymath``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ._jitcache import njit
from .raymath import line_position, madd, terrain_on_line


@njit(cache=True)
def _blocked(z, r, c, h0, row_l, col_l, height_l):
    """True when the line from cell (r, c) at height h0 to the light passes strictly below the
    terrain at one of its grid-line crossings before the light."""
    rows, cols = z.shape
    drow = row_l - r
    dcol = col_l - c
    if abs(dcol) >= abs(drow):
        dom_col = True
        d = abs(dcol)
        sd = 1 if dcol > 0 else -1
        so = drow / d if d > 0.0 else 0.0
        line0, other0, n_dom, n_oth = c, r, cols, rows
    else:
        dom_col = False
        d = abs(drow)
        sd = 1 if drow > 0 else -1
        so = dcol / d
        line0, other0, n_dom, n_oth = r, c, rows, cols
    if d == 0.0:
        return False
    rise = (height_l - h0) / d
    k = 1
    while k < d:                    # crossings strictly before the light
        line = line0 + k * sd
        if line < 0 or line >= n_dom:
            return False
        pos = line_position(madd(float(other0), float(k), so), n_oth)
        if pos < 0.0:
            return False
        t = terrain_on_line(z, dom_col, line, pos)
        if t > madd(h0, float(k), rise):
            return True
        k += 1
    return False


@njit(parallel=True, cache=True)
def _point_cpu(z, row_l, col_l, height_l, lift, out):
    rows, cols = z.shape
    for r in prange(rows):
        for c in range(cols):
            h = z[r, c]
            if math.isnan(h):
                out[r, c] = 255
                continue
            out[r, c] = 1 if _blocked(z, np.int64(r), np.int64(c), float(h) + lift, row_l,
                                      col_l, height_l) else 0


def shadow_mask(z: np.ndarray, row: float, col: float, height: float,
                lift: float = 0.0) -> np.ndarray:
    """uint8 mask (1 shadow, 0 lit, 255 void) of float32 heights ``z`` lit by a point light at
    fractional (``row``, ``col``; cell centres at whole numbers, anywhere, also off the raster)
    and ``height`` (the heights' units); every cell's ray starts ``lift`` above it."""
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    out = np.empty(z.shape, np.uint8)
    _point_cpu(z, float(row), float(col), float(height), float(lift), out)
    return out
