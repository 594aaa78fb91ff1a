"""Suns that vary across the raster: every cell's own sun direction, in the march itself.

A sun given by a time is not in the same direction everywhere over a large DEM (0.35 deg across
61 km). ``sun.sun_over`` evaluates the SPA on a lattice of n x n places over the raster; here each
cell's direction is the bilinear interpolation of the lattice's unit vectors (grid azimuth and
apparent elevation) at the cell's centre, normalised, and its ray in pixel units is made from
it with its own row's spacing exactly as ``geometry.sun_rays`` makes one from an azimuth and an
elevation. The ray is then marched over the maximum-height pyramid (``pyramid``), so a varying
sun costs one march per cell like a fixed one, without tiles and their halos. The direction is
smooth to second order between lattice nodes (the tiles' one vector per tile is first order).
A cell whose own sun is at or below the horizon is in shadow (night), as for one vector.

``cell_ray`` is a plain njit function without allocation, shared by the CPU kernel and the CUDA
kernel (``_cuda.device``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ._cuda import cuda, kernel
from ._jitcache import njit
from .counts import any_code
from .frames import dem_index
from .pyramid import pyramid_args, ray_is_blocked_pyramid
from .raymath import ray_is_blocked


@njit(cache=True, inline="always")
def lattice_scale(n, m):
    """Lattice nodes per cell along an axis of m cells for an n x n lattice (0 for one cell)."""
    return (n - 1.0) / (m - 1.0) if m > 1 else 0.0


@njit(cache=True, inline="always")
def lattice_at(r, c, si, sj, vec):
    """(east, north, up) at cell (r, c): the bilinear interpolation of the lattice ``vec`` (n x n
    x 3 unit vectors; node (i, j) at row i / si, column j / sj, ``lattice_scale``), not
    normalised: along the columns first, then along the rows."""
    n = vec.shape[0]
    fi = r * si
    fj = c * sj
    i0 = min(int(fi), n - 2) if n > 1 else 0
    j0 = min(int(fj), n - 2) if n > 1 else 0
    ti = fi - i0
    tj = fj - j0
    i1 = min(i0 + 1, n - 1)
    j1 = min(j0 + 1, n - 1)
    a = vec[i0, j0, 0] + tj * (vec[i0, j1, 0] - vec[i0, j0, 0])
    b = vec[i1, j0, 0] + tj * (vec[i1, j1, 0] - vec[i1, j0, 0])
    e = a + ti * (b - a)
    a = vec[i0, j0, 1] + tj * (vec[i0, j1, 1] - vec[i0, j0, 1])
    b = vec[i1, j0, 1] + tj * (vec[i1, j1, 1] - vec[i1, j0, 1])
    no = a + ti * (b - a)
    a = vec[i0, j0, 2] + tj * (vec[i0, j1, 2] - vec[i0, j0, 2])
    b = vec[i1, j0, 2] + tj * (vec[i1, j1, 2] - vec[i1, j0, 2])
    up = a + ti * (b - a)
    return e, no, up


@njit(cache=True, inline="always")
def ray_of(e, no, up, dx_r, dy_r, col_sign, row_sign, curv_coef):
    """(night, dom_col, step_dom, step_other, rise, curv) of the sun (east, north, up: any
    length) on a row of spacing dx_r, dy_r, the ray ``geometry.sun_rays`` makes from its
    azimuth and elevation (up to rounding), with one division: the unit vector's length
    cancels. Night when the sun is at or below the horizon. Selects only: a loop over cells
    vectorises."""
    h2 = e * e + no * no
    night = not ((up > 0.0) & (h2 > 0.0))
    ae = abs(e) * dy_r
    an = abs(no) * dx_r
    dom_col = ae >= an                  # |east| / dx >= |north| / dy
    num = 1.0 if night else (ae if dom_col else an)
    u = 1.0 / num
    m = dx_r * dy_r * u                  # metres per step / horizontal length of the vector
    lead = e * col_sign if dom_col else no * row_sign
    sd = np.int64(1) if ((lead >= 0.0) | night) else np.int64(-1)
    step_other = 0.0 if night else (no * row_sign * dx_r if dom_col else e * col_sign * dy_r) * u
    rise = 0.0 if night else up * m
    curv = 0.0 if night else curv_coef * h2 * m * m
    return night, dom_col & (not night), sd, step_other, rise, curv


@njit(cache=True)
def cell_ray(r, c, vec, dx, dy, col_sign, row_sign, curv_coef, r0, c0, rows, cols):
    """(night, dom_col, step_dom, step_other, rise, curv) of cell (r, c) of an array that is
    the window at (r0, c0) of the rows x cols raster the lattice ``vec`` spans (``sun_args``):
    its sun interpolated on the lattice at (r0 + r, c0 + c) (``lattice_at``), its ray on its
    row's spacing ``dx[r]``, ``dy[r]`` (``ray_of``); night when that sun is at or below the
    horizon."""
    n = vec.shape[0]
    e, no, up = lattice_at(r0 + r, c0 + c, lattice_scale(n, rows), lattice_scale(n, cols), vec)
    return ray_of(e, no, up, dx[r], dy[r], col_sign, row_sign, curv_coef)


@njit(cache=True, inline="always")
def _field_cell(z, pyr, off, widths, nlev, r, c, vec, dx, dy, col_sign, row_sign, curv_coef,
                r0, c0, rows, cols, zmax, lift, out, only):
    """Decide cell (r, c) with its own sun, its ray leaving ``lift`` metres above it (with
    only >= 0: only if its code in ``out`` is ``only``; returns 1 when it decided it): the
    per-cell body of both backends."""
    if only >= 0 and out[r, c] != only:
        return 0
    if math.isnan(z[r, c]):
        out[r, c] = 255
        return 1
    night, dc, sd, so, ri, cv = cell_ray(r, c, vec, dx, dy, col_sign, row_sign, curv_coef, r0,
                                         c0, rows, cols)
    if night:
        out[r, c] = 1
    elif nlev > 0:
        out[r, c] = 1 if ray_is_blocked_pyramid(z, pyr, off, widths, nlev, r, c, dc, sd, so, ri,
                                                cv, zmax, lift) else 0
    else:
        out[r, c] = 1 if ray_is_blocked(z, r, c, dc, sd, so, ri, cv, zmax, lift) else 0
    return 1


@njit(parallel=True, cache=True)
def _field_cpu(z, pyr, off, widths, nlev, vec, dx, dy, col_sign, row_sign, curv_coef, r0, c0,
               rows_l, cols_l, zmax, lift, out, only):
    rows, cols = z.shape
    n = 0
    for r in prange(rows):
        for c in range(cols):
            if only >= 0 and out[r, c] != only:
                continue
            n += _field_cell(z, pyr, off, widths, nlev, r, c, vec, dx, dy, col_sign, row_sign,
                             curv_coef, r0, c0, rows_l, cols_l, zmax, lift, out, only)
    return n


@kernel
def _field_gpu(z, pyr, off, widths, nlev, vec, dx, dy, col_sign, row_sign, curv_coef, r0, c0,
               rows_l, cols_l, zmax, lift, out):
    c, r = cuda.grid(2)
    rows, cols = z.shape
    if r < rows and c < cols:
        _field_cell(z, pyr, off, widths, nlev, r, c, vec, dx, dy, col_sign, row_sign, curv_coef,
                    r0, c0, rows_l, cols_l, zmax, lift, out, -1)


@njit(cache=True)
def field_sample(rows, cols, vec, dx, dy, col_sign, row_sign, curv_coef, r0, c0, rows_l, cols_l,
                 f_dom, f_sd, flip_line, flip_pos, step):
    """The rays of every ``step``-th canonical line and position (and the last ones) of the
    frame (dominant axis ``f_dom``, direction ``f_sd``, flips): (line, position, s, rise, curv)
    of those whose sun is up and whose ray lies in the frame's octant (s >= 0 once flipped).
    What ``bounds`` fits and takes the ranges of."""
    L, P = (cols, rows) if f_dom else (rows, cols)
    nv = (L - 1) // step + 2
    npos = (P - 1) // step + 2
    a = np.empty((nv * npos, 5))
    k = 0
    for iv in range(nv):
        v = min(iv * step, L - 1)
        if iv == nv - 1 and (L - 1) % step == 0:
            continue
        for ip in range(npos):
            p = min(ip * step, P - 1)
            if ip == npos - 1 and (P - 1) % step == 0:
                continue
            r, c = dem_index(v, p, L, P, f_dom, flip_line, flip_pos)
            night, dc, sd, so, ri, cv = cell_ray(r, c, vec, dx, dy, col_sign, row_sign,
                                                 curv_coef, r0, c0, rows_l, cols_l)
            s = -so if flip_pos else so
            if night or dc != f_dom or sd != f_sd or not s >= 0.0:
                continue
            a[k, 0], a[k, 1], a[k, 2], a[k, 3], a[k, 4] = v, p, s, ri, cv
            k += 1
    return a[:k]


def lattice_vectors(azimuth, elevation) -> np.ndarray:
    """n x n x 3 unit vectors (east, north, up) from n x n grid azimuths and elevations (deg)."""
    a = np.radians(np.asarray(azimuth, np.float64))
    e = np.radians(np.asarray(elevation, np.float64))
    return np.ascontiguousarray(np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a),
                                          np.sin(e)], axis=-1))


def sun_args(grid, vec: np.ndarray, curv_coef: float = 0.0, place=None) -> tuple:
    """(lattice, dx, dy, col sign, row sign, curvature, r0, c0, rows, cols): what ``cell_ray``
    takes besides the cell, in the kernels' types. ``place``: (r0, c0, rows, cols) when the
    heights are the window at (r0, c0) of the rows x cols raster the lattice spans (``grid``
    the window's); default the whole raster."""
    r0, c0, rows, cols = place if place is not None else (0, 0, grid.rows, grid.cols)
    return (np.ascontiguousarray(vec, np.float64), np.ascontiguousarray(grid.dx, np.float64),
            np.ascontiguousarray(grid.dy, np.float64), float(grid.col_sign),
            float(grid.row_sign), float(curv_coef), np.int64(r0), np.int64(c0), np.int64(rows),
            np.int64(cols))


def shadow_mask(z: np.ndarray, grid, vec: np.ndarray, curv_coef: float = 0.0,
                zmax: float | None = None, pyramid=True, place=None,
                lift: float = 0.0) -> np.ndarray:
    """Cast-shadow mask (uint8 1 / 0 / 255) of ``z`` on ``grid`` with every cell's own sun from
    the lattice ``vec`` (``lattice_vectors``); ``curv_coef``: (1 - k) / 2R or 0; ``pyramid`` and
    ``lift`` as for ``brute.shadow_mask``; ``place`` as for ``sun_args`` (a window of the
    raster)."""
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    if zmax is None:
        zmax = float(np.nanmax(z)) if np.isfinite(z).any() else -np.inf
    out = np.empty(z.shape, np.uint8)
    _field_cpu(z, *pyramid_args(z, pyramid), *sun_args(grid, vec, curv_coef, place), float(zmax),
               float(lift), out, np.int64(-1))
    return out


def refine(z: np.ndarray, grid, vec: np.ndarray, curv_coef: float, zmax: float,
           out: np.ndarray, code: int, pyramid=True, place=None, lift: float = 0.0) -> int:
    """Replace every ``code`` in ``out`` by the exact answer with the cell's own sun (``lift``
    as for ``shadow_mask``); returns how many cells were refined."""
    if not any_code(out, code):
        return 0
    return int(_field_cpu(z, *pyramid_args(z, pyramid), *sun_args(grid, vec, curv_coef, place),
                          float(zmax), float(lift), out, np.int64(code)))


def shadow_mask_gpu(g, grid, vec: np.ndarray, curv_coef: float, zmax: float,
                    place=None, lift: float = 0.0) -> np.ndarray:
    """``shadow_mask`` on the GPU (``g``: a ``gpu.GpuDem``; ``lift`` as for ``shadow_mask``)."""
    rows, cols = g.shape
    out = g.empty((rows, cols), np.uint8)
    v, dx, dy, cs, rs, cc, r0, c0, nr, nc = sun_args(grid, vec, curv_coef, place)
    with g.timed():
        g.launch(_field_gpu, rows, cols, g.z, *g.pyramid_args(True), g.upload(v), g.upload(dx),
                 g.upload(dy), cs, rs, cc, r0, c0, nr, nc, float(zmax), float(lift), out)
    return g.download(out)
