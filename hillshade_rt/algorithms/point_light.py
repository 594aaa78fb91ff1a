"""A point light: the light at a position instead of a direction, as the source documents place
the sun ("B = coordinates of the sun position projection ... L = A - C" [1]_; "draw a straight
line from the sun to the point of interest" [2]_).

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
``ray_sample``'s arithmetic (``raymath``).

**The march over the pyramid** (the default; ``pyramid=False``: the plain march, O(cells x
reach)): brute's maximum-height pyramid (``pyramid.MaxPyramid``) with brute's skip
(``pyramid.samples_left``), adapted to a ray that ends and may descend. At each sample the march
climbs to the coarsest block, around the sample, lower than the ray over every sample a skip
would pass: with the light higher than the cell (rise >= 0) the ray's height at this sample;
with the light lower (rise < 0) its height at the last sample skipped, computed per level (k +
the samples left in that block, at most the last sample before the light: ``madd(h0, k, rise)``
is monotonic in k, so that height is the lowest the plain march would compare). Every sample it
does not take is one the plain march finds below the ray: the mask is the plain march's cell for
cell (tests). The march ends at the light (k < D; a skip past it ends the march) or where the
ray leaves the raster; it stops early once the ray is above the highest cell, for a rising ray
at its current sample, for a descending one at its last sample (then before it starts).
One per-cell body (``point_is_blocked``) for the CPU kernel (rows in parallel) and the CUDA
kernel (``shadow_mask_gpu``: one thread per cell), as ``brute``.

References
----------
.. [1] M. Marghidanu, "Fast Computation of Terrain Shadow Maps," GameDev.net, 2002.
.. [2] T. A. Franke, "Static Terrain Shadowmapping," tutorial (no date given in the text).
.. [3] A. Tevs, I. Ihrke, H.-P. Seidel, "Maximum mipmaps for fast, accurate, and scalable dynamic
       height field rendering," in Proc. 2008 Symp. on Interactive 3D Graphics and Games (I3D '08),
       pp. 183-190, 2008. :doi:`10.1145/1342250.1342279`
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ._cuda import cuda, kernel
from ._jitcache import njit
from .pyramid import pyramid_args, samples_left
from .raymath import line_position, madd, terrain_on_line


@njit(cache=True)
def point_is_blocked(z, pyr, off, widths, nlev, r, c, h0, row_l, col_l, height_l, zmax, org_r,
                     org_c, rows, cols):
    """True when the line from cell (r, c) of ``z`` at height ``h0`` to the light at (``row_l``,
    ``col_l``, ``height_l``) passes strictly below the terrain at one of its grid-line crossings
    before the light. Over the pyramid ``(pyr, off, widths, nlev)`` of ``z`` when ``nlev`` > 0
    (the same answer, skipping blocks lower than the ray; see the module's docstring); ``zmax``:
    the highest cell of ``z`` (or more). ``z`` is the window at (``org_r``, ``org_c``) of a
    raster of ``rows`` x ``cols`` (the whole raster: 0, 0 and z's shape), the light in the
    raster's coordinates: the ray's arithmetic is the raster's, so a window gives its cells what
    the whole raster gives them, bit for bit, as long as it holds every sample (``halo``)."""
    rg = np.int64(r) + org_r
    cg = np.int64(c) + org_c
    drow = row_l - rg
    dcol = col_l - cg
    if abs(dcol) >= abs(drow):
        dom_col = True
        d = abs(dcol)
        sd = np.int64(1) if dcol > 0 else np.int64(-1)
        so = drow / d if d > 0.0 else 0.0
        line0 = cg
        other0 = rg
        n_dom = np.int64(cols)
        n_oth = np.int64(rows)
        org_line = org_c
        org_oth = org_r
    else:
        dom_col = False
        d = abs(drow)
        sd = np.int64(1) if drow > 0 else np.int64(-1)
        so = dcol / d
        line0 = rg
        other0 = cg
        n_dom = np.int64(rows)
        n_oth = np.int64(cols)
        org_line = org_r
        org_oth = org_c
    if d == 0.0:
        return False
    rise = (height_l - h0) / d
    # the last sample: strictly before the light (k < d), on the raster along the dominant axis
    klast = np.int64(math.ceil(d)) - 1
    kexit = (n_dom - 1 - line0) if sd > 0 else line0
    if kexit < klast:
        klast = kexit
    descending = rise < 0.0
    if descending and madd(h0, float(klast), rise) >= zmax:
        return False                # the ray's lowest sample is above the highest cell
    k = np.int64(1)
    lev = np.int64(0)
    while k <= klast:
        hr = madd(h0, float(k), rise)
        if hr >= zmax and not descending:
            return False
        line = line0 + k * sd - org_line       # in z (a window: exact shifts by whole cells)
        pos = line_position(madd(float(other0), float(k), so), n_oth)
        if pos < 0.0:
            return False
        pos -= org_oth
        i0 = np.int64(math.floor(pos))
        rr = i0 if dom_col else line
        cc = line if dom_col else i0
        # climb: the coarsest level (from one above the last) whose block here is lower than
        # the ray over every sample the skip would pass (rising: this one; descending: the
        # last of them, at most klast)
        up = lev + 1 if lev < nlev else lev
        left = np.int64(0)
        if descending:
            while up > 0:
                left = samples_left(up, line, i0, pos, sd, so)
                kend = k + left
                if kend > klast:
                    kend = klast
                if pyr[off[up] + (rr >> up) * widths[up] + (cc >> up)] < madd(h0, float(kend),
                                                                              rise):
                    break
                up -= 1
        else:
            while up > 0 and not pyr[off[up] + (rr >> up) * widths[up] + (cc >> up)] < hr:
                up -= 1
            if up > 0:
                left = samples_left(up, line, i0, pos, sd, so)
        lev = up
        if lev == 0:
            if terrain_on_line(z, dom_col, line, pos) > hr:
                return True
            k += 1
        else:           # no sample in the block can block the ray: past it (maybe past the end)
            k += left + 1
    return False


@njit(cache=True, inline="always")
def _point_cell(z, pyr, off, widths, nlev, r, c, row_l, col_l, height_l, lift, zmax, place,
                out):
    """Decide cell (r, c): the per-cell body of both backends. ``place``: (org_r, org_c, rows,
    cols) of ``z`` in its raster."""
    h = z[r, c]
    if math.isnan(h):
        out[r, c] = 255
    elif point_is_blocked(z, pyr, off, widths, nlev, r, c, float(h) + lift, row_l, col_l,
                          height_l, zmax, place[0], place[1], place[2], place[3]):
        out[r, c] = 1
    else:
        out[r, c] = 0


@njit(parallel=True, cache=True)
def _point_cpu(z, pyr, off, widths, nlev, row_l, col_l, height_l, lift, zmax, place, out):
    rows, cols = z.shape
    for r in prange(rows):
        for c in range(cols):
            _point_cell(z, pyr, off, widths, nlev, r, c, row_l, col_l, height_l, lift, zmax,
                        place, out)


@kernel
def _point_gpu(z, pyr, off, widths, nlev, row_l, col_l, height_l, lift, zmax, place, out):
    """CUDA twin of ``_point_cpu``: one thread per cell."""
    c, r = cuda.grid(2)
    if r < z.shape[0] and c < z.shape[1]:
        _point_cell(z, pyr, off, widths, nlev, r, c, row_l, col_l, height_l, lift, zmax, place,
                    out)


def _zmax(z, zmax):
    if zmax is None:
        return float(np.nanmax(z)) if np.isfinite(z).any() else -np.inf
    return float(zmax)


def _place(z, origin, shape):
    r0, c0 = origin
    rows, cols = z.shape if shape is None else shape
    return np.array([r0, c0, rows, cols], np.int64)


def halo(region, row: float, col: float, shape) -> tuple[int, int, int, int]:
    """The window (r0, r1, c0, c1) of a raster of ``shape`` that holds every sample of the rays
    from the cells of ``region`` (r0, r1, c0, c1) to a light at (``row``, ``col``): the box
    around the region and the light's cell, clipped to the raster, one cell more all round (the
    interpolation's second cell, and a margin)."""
    rows, cols = shape
    r0, r1, c0, c1 = region
    fr, fc = math.floor(row), math.floor(col)
    return (max(0, min(r0, fr) - 1), min(rows, max(r1 - 1, fr) + 3),
            max(0, min(c0, fc) - 1), min(cols, max(c1 - 1, fc) + 3))


def shadow_mask(z: np.ndarray, row: float, col: float, height: float, lift: float = 0.0,
                pyramid=True, zmax: float | None = None, origin=(0, 0),
                shape=None) -> np.ndarray:
    """uint8 mask (1 shadow, 0 lit, 255 void) of float32 heights ``z`` lit by a point light at
    fractional (``row``, ``col``; cell centres at whole numbers, anywhere, also off the raster)
    and ``height`` (the heights' units); every cell's ray starts ``lift`` above it.
    ``pyramid``: True (default) marches over a new maximum-height pyramid of ``z``, a
    ``pyramid.MaxPyramid`` reuses one, False is the plain march (the same mask). ``zmax``: the
    highest height (default: computed), above which nothing blocks. ``z`` may be a window, at
    ``origin`` (row, column), of a raster of ``shape``, holding the ``halo`` of the cells asked
    for (the light in the raster's coordinates): its cells get the whole raster's answers, bit
    for bit."""
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    out = np.empty(z.shape, np.uint8)
    _point_cpu(z, *pyramid_args(z, pyramid), float(row), float(col), float(height), float(lift),
               _zmax(z, zmax), _place(z, origin, shape), out)
    return out


def shadow_mask_gpu(g, row: float, col: float, height: float, lift: float = 0.0,
                    pyramid=True, origin=(0, 0), shape=None) -> np.ndarray:
    """``shadow_mask`` on the GPU: ``g`` a ``gpu.GpuDem`` (heights on the device; its pyramid
    built and uploaded once, at its first use); ``origin``, ``shape`` as for ``shadow_mask``."""
    rows, cols = g.shape
    if not np.isfinite(g.zmax):          # nothing but voids
        return np.full(g.shape, 255, np.uint8)
    out = g.empty((rows, cols), np.uint8)
    with g.timed():
        g.launch(_point_gpu, rows, cols, g.z, *g.pyramid_args(pyramid is not False), float(row),
                 float(col), float(height), float(lift), float(g.zmax),
                 g.upload(_place(g, origin, shape)), out)
    return g.download(out)
