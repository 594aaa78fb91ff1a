"""Lambert shading by a point light: ``hillshade --light-position``
and its lightmaps, and the light seen from points (``query --light-position``).

Per valid cell (row r, column c, height h, lifted by ``lift``): N the unit surface normal of
Horn's method [1]_ exactly as the directional hillshade computes it (``relief.horn_gradient``, the
row's own ground spacing, the same edges and voids); V the vector from the cell's 3-D position
to the light in ground metres (grid east: (col_l - c) dx[r] col_sign; grid north:
(row_l - r) dy[r] row_sign; up: height_l - h - lift; the spacing of the cell's row for the whole
way, the rows and columns being straight lines toward a light that is near); d = |V|.
The direct light is

    direct = max(0, N . V / d) x lit x falloff,   lit 0 where the cast-shadow mask is 1,

falloff 1 (``none``) or min(1, (d_ref / d)^2) (``inverse-square``), d_ref chosen by the caller
(the run: the light's height above the ground beneath it, so that the cell right under the
light gets 1 and nothing is brighter than it). A cell right under the light (d = 0, a light on
the ground) faces it: direct = lit. Voids: NaN.

``encode`` turns direct light into the hillshade's integers, as the directional hillshade does:
1 + round(levels x (ambient + (1 - ambient) x direct)), 0 on voids; levels 254 (uint8, 1..255)
or 65534 (uint16, 1..65535).

References
----------
.. [1] B. K. P. Horn, "Hill shading and the reflectance map," Proc. IEEE, vol. 69, no. 1,
       pp. 14-47, 1981. :doi:`10.1109/PROC.1981.11918`
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ._jitcache import njit
from .raymath import line_position, madd, terrain_on_line
from .relief import horn_gradient

FALLOFFS = ("none", "inverse-square")


@njit(parallel=True, cache=True)
def _direct(z, dx, dy, csign, rsign, mask, row_l, col_l, height_l, lift, d_ref, inverse_square,
            out):
    rows, cols = z.shape
    d_ref2 = d_ref * d_ref
    for r in prange(rows):
        for c in range(cols):
            h = z[r, c]
            if math.isnan(h):
                out[r, c] = np.nan
                continue
            if mask[r, c] == 1:
                out[r, c] = 0.0
                continue
            ge, gn = horn_gradient(z, r, c, dx[r], dy[r], csign, rsign)
            ve = (col_l - c) * dx[r] * csign
            vn = (row_l - r) * dy[r] * rsign
            vu = height_l - (float(h) + lift)
            d2 = ve * ve + vn * vn + vu * vu
            if d2 == 0.0:
                out[r, c] = 1.0
                continue
            cosi = (vu - ge * ve - gn * vn) / math.sqrt((1.0 + ge * ge + gn * gn) * d2)
            if cosi <= 0.0:
                out[r, c] = 0.0
                continue
            if inverse_square and d2 > d_ref2:
                cosi *= d_ref2 / d2
            out[r, c] = cosi


def direct_light(z: np.ndarray, grid, mask: np.ndarray, row: float, col: float, height: float,
                 lift: float = 0.0, falloff: str = "none", d_ref: float = 0.0) -> np.ndarray:
    """float32 direct light 0..1 (NaN on voids) of heights ``z`` (2-D float32, not copied) on
    ``grid`` lit by a point light at fractional (``row``, ``col``; cell centres at whole
    numbers) and ``height``, cast shadows from ``mask`` (uint8, 1 shadow: e.g.
    ``point.shadow_mask`` of the same light), each cell's point ``lift`` above it; ``falloff``
    one of ``FALLOFFS`` (``d_ref``: the distance at which inverse-square gives 1)."""
    if z.dtype != np.float32 or z.ndim != 2 or mask.shape != z.shape:
        raise TypeError("heights must be a 2-D float32 array and the mask of the same shape")
    if falloff not in FALLOFFS:
        raise ValueError(f"falloff must be one of {FALLOFFS}, got {falloff!r}")
    out = np.empty(z.shape, np.float32)
    _direct(z, grid.dx, grid.dy, float(grid.col_sign), float(grid.row_sign), mask, float(row),
            float(col), float(height), float(lift), float(d_ref), falloff == "inverse-square",
            out)
    return out


@njit(parallel=True, cache=True)
def _encode(direct, ambient, levels, out):
    rows, cols = direct.shape
    for r in prange(rows):
        for c in range(cols):
            v = direct[r, c]
            if math.isnan(v):
                out[r, c] = 0
            else:
                out[r, c] = 1.0 + np.rint(levels * (ambient + (1.0 - ambient) * float(v)))


def encode(direct: np.ndarray, ambient: float, bits: int = 8) -> np.ndarray:
    """The hillshade's integers of ``direct`` light (NaN voids): uint8 1..255 (``bits`` 8) or
    uint16 1..65535 (16), 1 + round(levels x (ambient + (1 - ambient) x direct)), 0 nodata."""
    if bits not in (8, 16):
        raise ValueError(f"bits must be 8 or 16, got {bits!r}")
    out = np.empty(direct.shape, np.uint8 if bits == 8 else np.uint16)
    _encode(direct, float(ambient), 254.0 if bits == 8 else 65534.0, out)
    return out


@njit(cache=True)
def _blocked_from(z, row0, col0, h0, row_l, col_l, height_l):
    """True when the line from the point (``row0``, ``col0``, fractional) at height ``h0`` to
    the light passes strictly below the terrain where it crosses the grid lines of its dominant
    axis strictly between the two (``algorithms.point_light``'s model; from a cell centre the same
    crossings and the same arithmetic)."""
    rows, cols = z.shape
    drow = row_l - row0
    dcol = col_l - col0
    if abs(dcol) >= abs(drow):
        dom_col = True
        d = abs(dcol)
        sd = 1 if dcol > 0 else -1
        so = drow / d if d > 0.0 else 0.0
        line0, other0, n_dom, n_oth = col0, row0, cols, rows
    else:
        dom_col = False
        d = abs(drow)
        sd = 1 if drow > 0 else -1
        so = dcol / d
        line0, other0, n_dom, n_oth = row0, col0, rows, cols
    if d == 0.0:
        return False
    rise = (height_l - h0) / d
    # the first grid line strictly beyond the point toward the light
    line = int(math.floor(line0)) + 1 if sd > 0 else int(math.ceil(line0)) - 1
    while True:
        k = (line - line0) * sd          # the distance along the dominant axis, in cells
        if k >= d:                       # at or beyond the light
            return False
        if line < 0 or line >= n_dom:
            return False
        pos = line_position(madd(other0, k, so), n_oth)
        if pos < 0.0:
            return False
        t = terrain_on_line(z, dom_col, line, pos)
        if t > madd(h0, k, rise):
            return True
        line += sd


@njit(cache=True)
def _light_points(z, dx, dy, csign, rsign, rows, cols, heights, row_l, col_l, height_l, out):
    for i in range(rows.size):
        r, c = rows[i], cols[i]
        ri = min(max(int(round(r)), 0), z.shape[0] - 1)     # the nearest cell: its normal
        ci = min(max(int(round(c)), 0), z.shape[1] - 1)     # and its row's spacing
        ve = (col_l - c) * dx[ri] * csign
        vn = (row_l - r) * dy[ri] * rsign
        vu = height_l - heights[i]
        h = math.hypot(ve, vn)
        out[i, 0] = math.degrees(math.atan2(ve, vn)) % 360.0
        out[i, 1] = math.degrees(math.atan2(vu, h))
        dist = math.sqrt(h * h + vu * vu)
        out[i, 2] = dist
        if math.isnan(z[ri, ci]) or dist == 0.0:
            out[i, 3] = np.nan
        else:
            ge, gn = horn_gradient(z, ri, ci, dx[ri], dy[ri], csign, rsign)
            out[i, 3] = (vu - ge * ve - gn * vn) / math.sqrt((1.0 + ge * ge + gn * gn)
                                                             * dist * dist)
        out[i, 4] = 0.0 if _blocked_from(z, r, c, heights[i], row_l, col_l, height_l) else 1.0


def light_at_points(z: np.ndarray, grid, rows, cols, heights, row: float, col: float,
                    height: float) -> dict:
    """The point light at fractional (``row``, ``col``) and ``height`` seen from points at
    fractional (``rows``, ``cols``) and absolute ``heights`` over ``z`` (2-D float32) on
    ``grid``: per point ``azimuth`` (degrees clockwise from grid north), ``elevation`` (degrees
    above the horizontal), ``distance`` (metres; the spacing of the nearest cell's row),
    ``incidence`` (cos of the light's incidence on the surface of the nearest cell, its Horn
    normal as the hillshade's; negative: it faces away; NaN on a void), ``lit`` (bool: no
    terrain strictly above the straight line to the light where it crosses the grid lines: at
    a cell centre the point light's mask of that cell, ``point.shadow_mask``)."""
    rr = np.ascontiguousarray(rows, np.float64).ravel()
    cc = np.ascontiguousarray(cols, np.float64).ravel()
    hh = np.ascontiguousarray(heights, np.float64).ravel()
    if not rr.size == cc.size == hh.size:
        raise ValueError("rows, cols and heights must have the same length")
    out = np.empty((rr.size, 5), np.float64)
    _light_points(z, grid.dx, grid.dy, float(grid.col_sign), float(grid.row_sign), rr, cc, hh,
                  float(row), float(col), float(height), out)
    return {"azimuth": out[:, 0], "elevation": out[:, 1], "distance": out[:, 2],
            "incidence": out[:, 3], "lit": out[:, 4] == 1.0}
