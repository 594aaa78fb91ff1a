"""``brute``: exhaustive ray casting, the reference every other algorithm is tested against.

For every valid cell, march the ray toward the sun grid line by grid line (``raymath``), as the
source tutorials do [1]_ [2]_, until it is blocked, leaves the raster, or rises above the highest
cell. Exact on the terrain model by construction (docs/model.md). Parallel over rows.

By default the march skips, over the DEM's maximum-height pyramid (``pyramid``, [3]_), every block
lower than the ray: the same samples decide, the others are never taken, so the mask is the plain
march's cell for cell. ``pyramid=False`` (``--no-pyramid``) is the plain march, O(N * L) for rays
of L steps: the reference the benchmarks measure everything against.

Output codes: 1 shadow, 0 lit, 255 nodata (a void cell is neither lit nor shadowed; rays crossing a
void skip it, so a void casts no shadow).

References
----------
.. [1] M. Marghidanu, "Fast Computation of Terrain Shadow Maps," GameDev.net, 2002.
.. [2] T. A. Franke, "Static Terrain Shadowmapping," tutorial (no date given in the text).
.. [3] A. Tevs, I. Ihrke, H.-P. Seidel, "Maximum mipmaps for fast, accurate, and scalable dynamic
       height field rendering," in Proc. 2008 Symp. on Interactive 3D Graphics and Games (I3D '08),
       pp. 183-190, 2008. :doi:`10.1145/1342250.1342279`
"""

import math

import numpy as np
from numba import prange

from ..model.geometry import SunRays
from ._cuda import cuda, kernel
from ._jitcache import njit
from .counts import any_code
from .pyramid import pyramid_args, ray_is_blocked_pyramid
from .raymath import ray_is_blocked

NODATA = np.uint8(255)


@njit(cache=True, inline="always")
def _brute_cell(z, pyr, off, widths, nlev, r, c, dc, sd, so, ri, cv, zmax, lift, out, only):
    """Decide cell (r, c) whose row's ray is (dc, sd, so, ri, cv), leaving ``lift`` metres above
    the cell (or, with only >= 0, leave it unless its code in ``out`` is ``only``), over the
    pyramid when ``nlev`` > 0. Returns 1 when it decided the cell. The per-cell body of both
    backends."""
    if only >= 0 and out[r, c] != only:
        return 0
    if math.isnan(z[r, c]):
        out[r, c] = 255
        return 1
    if nlev > 0:
        blocked = ray_is_blocked_pyramid(z, pyr, off, widths, nlev, r, c, dc, sd, so, ri, cv,
                                         zmax, lift)
    else:
        blocked = ray_is_blocked(z, r, c, dc, sd, so, ri, cv, zmax, lift)
    out[r, c] = 1 if blocked else 0
    return 1


@njit(parallel=True, cache=True)
def _brute_cpu(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, curv, zmax, lift,
               out, only):
    """Every cell, or (only >= 0) just the cells whose code in ``out`` is ``only``. Returns how
    many cells it decided."""
    rows, cols = z.shape
    n = 0
    for r in prange(rows):
        dc = dom_col[r] != 0
        sd = np.int64(step_dom[r])
        so = step_other[r]
        ri = rise[r]
        cv = curv[r]
        for c in range(cols):
            if only >= 0 and out[r, c] != only:   # (also in _brute_cell) a vectorised skip
                continue
            n += _brute_cell(z, pyr, off, widths, nlev, r, c, dc, sd, so, ri, cv, zmax, lift, out,
                             only)
    return n


@njit(cache=True)
def _brute_box_row(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, curv, zmax,
                   lift, out, r0, c0, i):
    """Row ``i`` of the box of ``out``'s shape at (r0, c0) of ``z``: each cell marched over all
    of ``z`` with its row's ray (``_brute_cell``'s decision, written box-relative)."""
    r = r0 + i
    dc = dom_col[r] != 0
    sd = np.int64(step_dom[r])
    so = step_other[r]
    ri = rise[r]
    cv = curv[r]
    for j in range(out.shape[1]):
        c = c0 + j
        if math.isnan(z[r, c]):
            out[i, j] = 255
        elif nlev > 0:
            out[i, j] = 1 if ray_is_blocked_pyramid(z, pyr, off, widths, nlev, r, c, dc, sd, so,
                                                    ri, cv, zmax, lift) else 0
        else:
            out[i, j] = 1 if ray_is_blocked(z, r, c, dc, sd, so, ri, cv, zmax, lift) else 0


@njit(parallel=True, cache=True)
def _brute_box_cpu(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, curv, zmax,
                   lift, out, r0, c0):
    for i in prange(out.shape[0]):
        _brute_box_row(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, curv,
                       zmax, lift, out, r0, c0, i)


@njit(cache=True)
def _brute_box_serial(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, curv,
                      zmax, lift, out, r0, c0):
    for i in range(out.shape[0]):
        _brute_box_row(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, curv,
                       zmax, lift, out, r0, c0, i)


# a box of fewer cells is marched on one thread: starting the parallel loop costs milliseconds
# on a busy 2-core machine (4-8 ms measured, other processes running), more than its march
BOX_SERIAL_CELLS = 16384


def march_box(z: np.ndarray, rays: SunRays, bounds: tuple[int, int, int, int], zmax: float,
              pyramid=True, lift: float = 0.0) -> np.ndarray:
    """brute's mask of the cells of ``bounds`` (r0, r1, c0, c1) of ``z`` only, each ray marched
    over all of ``z`` (no copy, no halo to choose): uint8 of the box's shape, as ``shadow_mask``
    of all of ``z`` gives them there. ``pyramid`` and ``lift`` as for ``shadow_mask`` (a
    ``MaxPyramid`` of ``z`` is reused)."""
    r0, r1, c0, c1 = (int(v) for v in bounds)
    out = np.empty((max(0, r1 - r0), max(0, c1 - c0)), np.uint8)
    if out.size:
        k = _brute_box_serial if out.size < BOX_SERIAL_CELLS else _brute_box_cpu
        k(z, *pyramid_args(z, pyramid), rays.dom_col, rays.step_dom, rays.step_other,
          rays.rise, rays.curv, float(zmax), float(lift), out, np.int64(r0), np.int64(c0))
    return out


@kernel
def _brute_gpu(z, pyr, off, widths, nlev, dom_col, step_dom, step_other, rise, curv, zmax, lift,
               out, only, count):
    """CUDA twin of ``_brute_cpu``: one thread per cell; ``count[0]`` += cells decided when
    ``only`` >= 0 (refinement)."""
    c, r = cuda.grid(2)
    if r < z.shape[0] and c < z.shape[1]:
        if _brute_cell(z, pyr, off, widths, nlev, r, c, dom_col[r] != 0, np.int64(step_dom[r]),
                       step_other[r], rise[r], curv[r], zmax, lift, out, only) and only >= 0:
            cuda.atomic.add(count, 0, 1)


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None,
                stats: dict | None = None, pyramid=True, lift: float = 0.0) -> np.ndarray:
    """Shadow mask of float32 heights ``z`` (NaN = void) for the sun rays of each row.

    Returns uint8: 1 shadow, 0 lit, 255 void. ``pyramid``: True (default) marches over a new
    maximum-height pyramid of ``z``, a ``MaxPyramid`` reuses one, False is the plain march (same
    mask). ``lift``: metres above each cell its ray starts from (an observer, a panel above every
    cell: ``--height-above-ground``; >= 0, 0 the cell itself). ``stats`` gets ``pyramid``
    (whether the pyramid was used).
    """
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    if zmax is None:
        zmax = float(np.nanmax(z)) if np.isfinite(z).any() else -np.inf   # -inf: only voids
    out = np.empty(z.shape, dtype=np.uint8)
    _brute_cpu(z, *pyramid_args(z, pyramid), rays.dom_col, rays.step_dom, rays.step_other,
               rays.rise, rays.curv, float(zmax), float(lift), out, np.int64(-1))
    if stats is not None:
        stats["pyramid"] = pyramid is not False
    return out


def refine(z: np.ndarray, rays: SunRays, out: np.ndarray, code: int, zmax: float,
           pyramid=True, lift: float = 0.0) -> int:
    """Replace every ``code`` in ``out`` by brute's exact answer for that cell (for the algorithms
    that flag the cells they are unsure of, and the curvature pass). ``pyramid`` and ``lift`` as
    for ``shadow_mask``. Returns how many cells were refined."""
    if not any_code(out, code):
        return 0
    return int(_brute_cpu(z, *pyramid_args(z, pyramid), rays.dom_col, rays.step_dom,
                          rays.step_other, rays.rise, rays.curv, float(zmax), float(lift), out,
                          np.int64(code)))


def shadow_mask_gpu(g, rays: SunRays, zmax: float, stats: dict | None = None,
                    pyramid=True, lift: float = 0.0) -> np.ndarray:
    """``shadow_mask`` on the GPU: ``g`` is a ``gpu.GpuDem`` (heights already on the device; its
    pyramid is built and uploaded once, at the first sun that uses it); ``lift`` as for
    ``shadow_mask``."""
    rows, cols = g.shape
    dom_col, step_dom, step_other, rise, _, curv = g.rays(rays)
    out = g.empty((rows, cols), np.uint8)
    with g.timed():
        g.launch(_brute_gpu, rows, cols, g.z, *g.pyramid_args(pyramid is not False), dom_col,
                 step_dom, step_other, rise, curv, float(zmax), float(lift), out, np.int64(-1),
                 g.empty(1, np.int64))
    if stats is not None:
        stats["pyramid"] = pyramid is not False
    return g.download(out)


def refine_gpu(g, rays_d, out, code: int, zmax: float, lift: float = 0.0) -> int:
    """``refine`` on the GPU (inside the caller's ``g.timed()``): ``rays_d`` from ``g.rays``,
    ``out`` a device mask. Returns how many cells were refined."""
    rows, cols = g.shape
    count = g.upload(np.zeros(1, np.int64))
    dom_col, step_dom, step_other, rise, _, curv = rays_d
    g.launch(_brute_gpu, rows, cols, g.z, *g.pyramid_args(True), dom_col, step_dom, step_other,
             rise, curv, float(zmax), float(lift), out, np.int64(code), count)
    return int(g.download(count)[0])
