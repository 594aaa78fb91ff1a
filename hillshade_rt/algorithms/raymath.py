"""Per-ray arithmetic of the terrain model, written once as plain Python functions.

Every algorithm and backend uses these. They are ``njit`` functions, so CPU kernels call them
directly; ``hillshade_rt.engine.gpu`` compiles the same source (``.py_func``) with
``numba.cuda.jit(device=True)`` for the CUDA kernels. Keep them free of anything a CUDA device
function cannot do (no allocation, no exceptions, no Python objects).

A multiply followed by an add is written ``madd(a, b, c)``: CUDA compilers fuse ``a + b * c`` into
one fused multiply-add (one rounding instead of two), which would make GPU samples differ from the
CPU's in the last bit and, on a tie, flip a cell. The GPU build swaps ``madd`` for libdevice's
``dadd_rn(a, dmul_rn(b, c))``, which is never fused, so both backends round alike.

The model (docs/model.md): a ray leaves the centre of a cell toward the sun and is sampled where it
crosses the grid lines of its dominant axis; on such a line the terrain height is linearly
interpolated between the two nearest cell centres. Outside the raster there is no terrain.
"""

import math

import numpy as np

from ._jitcache import njit

# A position within EDGE_EPS of the first or last cell centre of a line counts as on it: this
# absorbs the rounding of ``start + k * step`` without changing the model.
EDGE_EPS = 1e-9


@njit(cache=True, inline="always")
def madd(a, b, c):
    """``a + b * c`` with the product rounded before the sum (never fused; see above)."""
    return a + b * c


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
    return madd(a, f, b - a)


@njit(cache=True)
def ray_origin(z, r, c, dom_col):
    """(line0, other0, n_dom, n_oth) of the ray from cell (r, c): its grid line and its position
    on that line, and how many lines and positions the raster has along the ray's axes."""
    rows, cols = z.shape
    r = np.int64(r)  # prange / grid indices may be unsigned; mixing them with int64 gives floats
    c = np.int64(c)
    if dom_col:
        return c, r, np.int64(cols), np.int64(rows)
    return r, c, np.int64(rows), np.int64(cols)


@njit(cache=True)
def ray_sample(z, dom_col, line0, other0, n_dom, n_oth, k, step_dom, step_other):
    """(inside, T): the model's k-th sample of the ray from ``ray_origin``; inside is False when
    that sample lies outside the raster (the ray has left it; T is then meaningless). T is NaN on
    a void."""
    line = line0 + k * step_dom
    if line < 0 or line >= n_dom:
        return False, 0.0
    pos = line_position(madd(float(other0), float(k), step_other), n_oth)
    if pos < 0.0:
        return False, 0.0
    return True, terrain_on_line(z, dom_col, line, pos)


@njit(cache=True)
def ray_is_blocked(z, r, c, dom_col, step_dom, step_other, rise, curv, zmax, lift):
    """True when the ray from the centre of cell (r, c), ``lift`` metres above it (0: on the
    ground; an observer above every cell: ``--height-above-ground``), passes strictly below the
    terrain.

    Marches grid line by grid line toward the sun; stops when the ray leaves the raster or climbs
    to ``zmax`` (the highest cell), above which nothing can block it. Heights in float64, the k-th
    sample computed as ``h0 + k * rise + k * k * curv`` (no accumulated drift; ``curv`` is the
    Earth-curvature term, 0 for a flat Earth, and then adds exactly nothing).
    """
    line0, other0, n_dom, n_oth = ray_origin(z, r, c, dom_col)
    h0 = float(z[np.int64(r), np.int64(c)]) + lift    # + 0.0 leaves the height as it is
    k = 1
    while True:
        hr = madd(h0, float(k), rise)
        if curv != 0.0:   # a flat Earth pays nothing for the curvature term
            hr = madd(hr, float(k * k), curv)
        if hr >= zmax:
            return False
        inside, t = ray_sample(z, dom_col, line0, other0, n_dom, n_oth, k, step_dom, step_other)
        if not inside:
            return False
        if t > hr:
            return True
        k += 1
