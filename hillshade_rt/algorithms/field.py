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
kernel (``gpu.device``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..gpu import cuda, kernel
from .pyramid import pyramid_args, ray_is_blocked_pyramid
from .raymath import ray_is_blocked


@njit(cache=True)
def cell_ray(r, c, rows, cols, vec, dx, dy, col_sign, row_sign, curv_coef):
    """(night, dom_col, step_dom, step_other, rise, curv) of cell (r, c): its sun interpolated
    on the lattice ``vec`` (n x n x 3 unit vectors east, north, up; node (i, j) at row
    i*(rows-1)/(n-1), column j*(cols-1)/(n-1)); night when that sun is at or below the horizon."""
    n = vec.shape[0]
    fi = (r * (n - 1.0) / (rows - 1.0)) if rows > 1 else 0.0
    fj = (c * (n - 1.0) / (cols - 1.0)) if cols > 1 else 0.0
    i0 = min(int(fi), n - 2) if n > 1 else 0
    j0 = min(int(fj), n - 2) if n > 1 else 0
    ti = fi - i0
    tj = fj - j0
    i1 = min(i0 + 1, n - 1)
    j1 = min(j0 + 1, n - 1)
    w00 = (1.0 - ti) * (1.0 - tj)
    w01 = (1.0 - ti) * tj
    w10 = ti * (1.0 - tj)
    w11 = ti * tj
    e = w00 * vec[i0, j0, 0] + w01 * vec[i0, j1, 0] + w10 * vec[i1, j0, 0] + w11 * vec[i1, j1, 0]
    no = w00 * vec[i0, j0, 1] + w01 * vec[i0, j1, 1] + w10 * vec[i1, j0, 1] + w11 * vec[i1, j1, 1]
    up = w00 * vec[i0, j0, 2] + w01 * vec[i0, j1, 2] + w10 * vec[i1, j0, 2] + w11 * vec[i1, j1, 2]
    h = math.sqrt(e * e + no * no)
    if up <= 0.0 or h == 0.0:
        return True, False, np.int64(1), 0.0, 0.0, 0.0
    east = e / h
    north = no / h
    pc = east * col_sign / dx[r]
    pr = north * row_sign / dy[r]
    dom_col = abs(pc) >= abs(pr)
    a_dom = abs(pc) if dom_col else abs(pr)
    sd = (1 if pc >= 0.0 else -1) if dom_col else (1 if pr >= 0.0 else -1)
    step_other = (pr if dom_col else pc) / a_dom
    step_m = 1.0 / a_dom
    rise = (up / h) * step_m
    return False, dom_col, np.int64(sd), step_other, rise, curv_coef * step_m * step_m


@njit(cache=True, inline="always")
def _field_cell(z, pyr, off, widths, nlev, r, c, rows, cols, vec, dx, dy, col_sign, row_sign,
                curv_coef, zmax, out, only):
    """Decide cell (r, c) with its own sun (with only >= 0: only if its code in ``out`` is
    ``only``; returns 1 when it decided it): the per-cell body of both backends."""
    if only >= 0 and out[r, c] != only:
        return 0
    if math.isnan(z[r, c]):
        out[r, c] = 255
        return 1
    night, dc, sd, so, ri, cv = cell_ray(r, c, rows, cols, vec, dx, dy, col_sign, row_sign,
                                         curv_coef)
    if night:
        out[r, c] = 1
    elif nlev > 0:
        out[r, c] = 1 if ray_is_blocked_pyramid(z, pyr, off, widths, nlev, r, c, dc, sd, so, ri,
                                                cv, zmax) else 0
    else:
        out[r, c] = 1 if ray_is_blocked(z, r, c, dc, sd, so, ri, cv, zmax) else 0
    return 1


@njit(parallel=True, cache=True)
def _field_cpu(z, pyr, off, widths, nlev, vec, dx, dy, col_sign, row_sign, curv_coef, zmax, out,
               only):
    rows, cols = z.shape
    n = 0
    for r in prange(rows):
        for c in range(cols):
            if only >= 0 and out[r, c] != only:
                continue
            n += _field_cell(z, pyr, off, widths, nlev, r, c, rows, cols, vec, dx, dy, col_sign,
                             row_sign, curv_coef, zmax, out, only)
    return n


@kernel
def _field_gpu(z, pyr, off, widths, nlev, vec, dx, dy, col_sign, row_sign, curv_coef, zmax, out):
    c, r = cuda.grid(2)
    rows, cols = z.shape
    if r < rows and c < cols:
        _field_cell(z, pyr, off, widths, nlev, r, c, rows, cols, vec, dx, dy, col_sign,
                    row_sign, curv_coef, zmax, out, -1)


@njit(parallel=True, cache=True)
def field_ranges(rows, cols, vec, dx, dy, col_sign, row_sign, curv_coef, f_dom, f_sd, flip_pos):
    """(s_lo, s_hi, rise_lo, rise_hi, curv_lo, curv_hi, n) over the cells whose sun is up and
    whose ray lies in the frame's octant (dominant axis ``f_dom``, direction ``f_sd``, position
    step >= 0 once flipped by ``flip_pos``): what ``bounds`` needs of a field."""
    a = np.full((rows, 6), np.nan)
    cnt = np.zeros(rows, np.int64)
    for r in prange(rows):
        s_lo, s_hi, r_lo, r_hi, c_lo, c_hi = np.inf, -np.inf, np.inf, -np.inf, np.inf, -np.inf
        k = 0
        for c in range(cols):
            night, dc, sd, so, ri, cv = cell_ray(r, c, rows, cols, vec, dx, dy, col_sign,
                                                 row_sign, curv_coef)
            s = -so if flip_pos else so
            if night or dc != f_dom or sd != f_sd or not s >= 0.0:
                continue
            k += 1
            s_lo, s_hi = min(s_lo, s), max(s_hi, s)
            r_lo, r_hi = min(r_lo, ri), max(r_hi, ri)
            c_lo, c_hi = min(c_lo, cv), max(c_hi, cv)
        cnt[r] = k
        a[r, 0], a[r, 1], a[r, 2], a[r, 3], a[r, 4], a[r, 5] = s_lo, s_hi, r_lo, r_hi, c_lo, c_hi
    n = cnt.sum()
    if n == 0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, n
    ok = cnt > 0
    return (a[ok, 0].min(), a[ok, 1].max(), a[ok, 2].min(), a[ok, 3].max(), a[ok, 4].min(),
            a[ok, 5].max(), n)


def lattice_vectors(azimuth, elevation) -> np.ndarray:
    """n x n x 3 unit vectors (east, north, up) from n x n grid azimuths and elevations (deg)."""
    a = np.radians(np.asarray(azimuth, np.float64))
    e = np.radians(np.asarray(elevation, np.float64))
    return np.ascontiguousarray(np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a),
                                          np.sin(e)], axis=-1))


def sun_args(grid, vec: np.ndarray, curv_coef: float = 0.0) -> tuple:
    """(lattice, dx, dy, col sign, row sign, curvature): what ``cell_ray`` takes besides the
    cell, in the kernels' types."""
    return (np.ascontiguousarray(vec, np.float64), np.ascontiguousarray(grid.dx, np.float64),
            np.ascontiguousarray(grid.dy, np.float64), float(grid.col_sign),
            float(grid.row_sign), float(curv_coef))


def shadow_mask(z: np.ndarray, grid, vec: np.ndarray, curv_coef: float = 0.0,
                zmax: float | None = None, pyramid=True) -> np.ndarray:
    """Cast-shadow mask (uint8 1 / 0 / 255) of ``z`` on ``grid`` with every cell's own sun from
    the lattice ``vec`` (``lattice_vectors``); ``curv_coef``: (1 - k) / 2R or 0; ``pyramid`` as
    for ``brute.shadow_mask``."""
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    if zmax is None:
        zmax = float(np.nanmax(z)) if np.isfinite(z).any() else -np.inf
    out = np.empty(z.shape, np.uint8)
    _field_cpu(z, *pyramid_args(z, pyramid), *sun_args(grid, vec, curv_coef), float(zmax), out,
               np.int64(-1))
    return out


def refine(z: np.ndarray, grid, vec: np.ndarray, curv_coef: float, zmax: float,
           out: np.ndarray, code: int, pyramid=True) -> int:
    """Replace every ``code`` in ``out`` by the exact answer with the cell's own sun; returns how
    many cells were refined."""
    if not (out == code).any():
        return 0
    return int(_field_cpu(z, *pyramid_args(z, pyramid), *sun_args(grid, vec, curv_coef),
                          float(zmax), out, np.int64(code)))


def shadow_mask_gpu(g, grid, vec: np.ndarray, curv_coef: float, zmax: float) -> np.ndarray:
    """``shadow_mask`` on the GPU (``g``: a ``gpu.GpuDem``)."""
    rows, cols = g.shape
    out = g.empty((rows, cols), np.uint8)
    v, dx, dy, cs, rs, cc = sun_args(grid, vec, curv_coef)
    with g.timed():
        g.launch(_field_gpu, rows, cols, g.z, *g.pyramid_args(True), g.upload(v), g.upload(dx),
                 g.upload(dy), cs, rs, cc, float(zmax), out)
    return g.download(out)
