"""Per-cell suns (``engine.cell_suns``): every cell lit by the sun as seen from its own
place on the body, the sun given by its position S in the body-fixed frame (its subsolar point
and distance).

For each valid cell: its place P on the ellipsoid at its height (plus ``lift``), v = S - P in
the cell's east/north/up frame (``cell_sun``: dot products with the per-cell sin/cos of
``engine.cell_suns.CellFrames``, no trigonometry per cell); v.up <= 0: the sun is below the cell's
horizon, the body itself hides it (shadow). Else the horizontal direction (true east, north) is
turned by theta (the grid azimuth of true north) into grid east/north and becomes a ray in pixel
units exactly as ``geometry.ray_steps`` makes one (the row's dx, dy, col_sign, row_sign); its
rise per step tan(el) * step_m = v.up / |v_h| * step_m; its curvature term (1 - k) / (2 R) *
step_m^2 with R the body's radius of curvature in the ray's true azimuth at the cell's latitude
(Euler: 1/R = cos^2(a) / M + sin^2(a) / N) when ``curv_k`` >= 0 (the refraction k; -1: no
curvature). Then the exact march over the maximum-height pyramid
(``pyramid.ray_is_blocked_pyramid``), as brute. Codes: 1 shadow, 0 lit, 255 void.

CPU (``prange`` over rows) and CUDA twins from one device function (``_subsolar_cell``); every
``a + b * c`` of the per-cell sun is ``raymath.madd`` (never fused on the GPU), so both backends
compute the same rays bit for bit.
"""

import math

import numpy as np
from numba import prange

from ._cuda import cuda, kernel
from ._jitcache import njit
from .pyramid import ray_is_blocked_pyramid
from .raymath import madd, ray_is_blocked, ray_origin, ray_sample


@njit(cache=True)
def cell_sun(slat, clat, slon, clon, a, e2, sx, sy, sz, h):
    """(east, north, up) of the vector from a cell (sin/cos latitude, longitude; height ``h``
    above the ellipsoid of semi-major axis ``a``, eccentricity squared ``e2``) to the sun at
    (sx, sy, sz), in the cell's local frame (metres)."""
    n = a / math.sqrt(madd(1.0, -e2 * slat, slat))
    px = (n + h) * clat * clon
    py = (n + h) * clat * slon
    pz = madd(h, n, 1.0 - e2) * slat
    vx = sx - px
    vy = sy - py
    vz = sz - pz
    up = madd(madd(clat * clon * vx, clat * slon, vy), slat, vz)
    east = madd(-slon * vx, clon, vy)
    north = madd(madd(-slat * clon * vx, -slat * slon, vy), clat, vz)
    return east, north, up


@njit(cache=True)
def cell_ray(slat, clat, slon, clon, cth, sth, a, e2, sx, sy, sz, h, dx, dy, col_sign, row_sign,
             curv_k):
    """(up, hor, dom_col, step_dom, step_other, step_m, curv) of the ray from a cell toward the
    sun: ``up`` and ``hor`` the vertical and horizontal parts of the vector to the sun (tan(el)
    = up / hor; up <= 0: the sun's centre is at or below the cell's horizon); ``step_dom`` 0:
    the sun at the zenith (no direction)."""
    e, n, u = cell_sun(slat, clat, slon, clon, a, e2, sx, sy, sz, h)
    hor = math.sqrt(madd(e * e, n, n))
    if hor == 0.0:
        return u, hor, False, 0, 0.0, 0.0, 0.0
    te = e / hor
    tn = n / hor
    ge = madd(te * cth, tn, sth)       # grid azimuth = true azimuth + theta
    gn = madd(tn * cth, -te, sth)
    pc = ge * col_sign / dx            # as geometry.ray_steps
    pr = gn * row_sign / dy
    if abs(pc) >= abs(pr):
        dom_col = True
        a_dom = abs(pc)
        sd = 1 if pc > 0.0 else -1
        so = pr / a_dom
    else:
        dom_col = False
        a_dom = abs(pr)
        sd = 1 if pr > 0.0 else -1
        so = pc / a_dom
    step_m = 1.0 / a_dom
    curv = 0.0
    if curv_k >= 0.0:
        w2 = madd(1.0, -e2 * slat, slat)
        big_n = a / math.sqrt(w2)
        big_m = a * (1.0 - e2) / (w2 * math.sqrt(w2))
        inv_r = madd(tn * tn / big_m, te * te, 1.0 / big_n)
        curv = (1.0 - curv_k) * 0.5 * inv_r * step_m * step_m
    return u, hor, dom_col, sd, so, step_m, curv


@njit(cache=True)
def _subsolar_cell(z, pyr, off, widths, nlev, r, c, slat, clat, slon, clon, cth, sth, dx, dy,
                   col_sign, row_sign, a, e2, sx, sy, sz, curv_k, zmax, lift, out):
    """Decide cell (r, c): the per-cell body of both backends."""
    h = z[r, c]
    if math.isnan(h):
        out[r, c] = 255
        return
    u, hor, dc, sd, so, sm, cv = cell_ray(float(slat[r, c]), float(clat[r, c]),
                                          float(slon[r, c]), float(clon[r, c]), float(cth[r, c]),
                                          float(sth[r, c]), a, e2, sx, sy, sz, float(h) + lift,
                                          dx[r], dy[r], col_sign, row_sign, curv_k)
    if u <= 0.0:
        out[r, c] = 1
        return
    if sd == 0:
        out[r, c] = 0
        return
    ri = (u / hor) * sm
    if nlev > 0:
        blocked = ray_is_blocked_pyramid(z, pyr, off, widths, nlev, r, c, dc, np.int64(sd), so,
                                         ri, cv, zmax, lift)
    else:
        blocked = ray_is_blocked(z, r, c, dc, np.int64(sd), so, ri, cv, zmax, lift)
    out[r, c] = 1 if blocked else 0


@njit(parallel=True, cache=True)
def _subsolar_cpu(z, pyr, off, widths, nlev, slat, clat, slon, clon, cth, sth, dx, dy, col_sign,
                  row_sign, a, e2, sx, sy, sz, curv_k, zmax, lift, out):
    rows, cols = z.shape
    for r in prange(rows):
        for c in range(cols):
            _subsolar_cell(z, pyr, off, widths, nlev, np.int64(r), np.int64(c), slat, clat, slon,
                           clon, cth, sth, dx, dy, col_sign, row_sign, a, e2, sx, sy, sz, curv_k,
                           zmax, lift, out)


@kernel
def _subsolar_gpu(z, pyr, off, widths, nlev, slat, clat, slon, clon, cth, sth, dx, dy, col_sign,
                  row_sign, a, e2, sx, sy, sz, curv_k, zmax, lift, out):
    """CUDA twin of ``_subsolar_cpu``: one thread per cell."""
    c, r = cuda.grid(2)
    if r < z.shape[0] and c < z.shape[1]:
        _subsolar_cell(z, pyr, off, widths, nlev, np.int64(r), np.int64(c), slat, clat, slon,
                       clon, cth, sth, dx, dy, col_sign, row_sign, a, e2, sx, sy, sz, curv_k,
                       zmax, lift, out)


@njit(cache=True)
def _blocked(z, pyr, off, widths, nlev, r, c, dc, sd, so, ri, cv, zmax, lift):
    if nlev > 0:
        return ray_is_blocked_pyramid(z, pyr, off, widths, nlev, r, c, dc, np.int64(sd), so, ri,
                                      cv, zmax, lift)
    return ray_is_blocked(z, r, c, dc, np.int64(sd), so, ri, cv, zmax, lift)


@njit(cache=True)
def _horizon_tan(z, r, c, dc, sd, so, step_m, cv, zmax, lift, rise_stop):
    """The highest tan of the terrain's elevation angle seen from the cell (``lift`` above it)
    along its ray, curvature included, over the samples until a ray rising ``rise_stop`` per
    step clears ``zmax`` (beyond, no sample is higher than that ray's angle); -inf: none."""
    line0, other0, n_dom, n_oth = ray_origin(z, r, c, dc)
    h0 = float(z[r, c]) + lift
    best = -math.inf
    k = 1
    while True:
        if madd(madd(h0, float(k), rise_stop), float(k * k), cv) >= zmax:
            return best
        inside, t = ray_sample(z, dc, line0, other0, n_dom, n_oth, k, np.int64(sd), so)
        if not inside:
            return best
        if not math.isnan(t):
            v = (t - madd(h0, float(k * k), cv)) / (float(k) * step_m)
            if v > best:
                best = v
        k += 1


@njit(cache=True)
def _soft_cell(z, pyr, off, widths, nlev, r, c, slat, clat, slon, clon, cth, sth, dx, dy,
               col_sign, row_sign, a, e2, sx, sy, sz, curv_k, zmax, lift, radius_deg, out):
    """The visible fraction of the solar disk (angular radius ``radius_deg``) at cell (r, c):
    0 when the ray toward the disk's top edge is blocked (or the top is below the horizon), 1
    when the ray toward its bottom edge is free and above the horizon, else the disk above the
    horizon angle (the terrain's, or the astronomical 0 if higher) as ``solar.disk_fraction``."""
    h = z[r, c]
    if math.isnan(h):
        out[r, c] = np.float32(np.nan)
        return
    u, hor, dc, sd, so, sm, cv = cell_ray(float(slat[r, c]), float(clat[r, c]),
                                          float(slon[r, c]), float(clon[r, c]), float(cth[r, c]),
                                          float(sth[r, c]), a, e2, sx, sy, sz, float(h) + lift,
                                          dx[r], dy[r], col_sign, row_sign, curv_k)
    if sd == 0:                       # the sun's centre at the zenith
        out[r, c] = np.float32(1.0 if u > 0.0 else 0.0)
        return
    el = math.degrees(math.atan2(u, hor))
    hi = el + radius_deg
    lo = el - radius_deg
    if hi <= 0.0:
        out[r, c] = np.float32(0.0)
        return
    if hi < 90.0 and _blocked(z, pyr, off, widths, nlev, r, c, dc, sd, so,
                              math.tan(math.radians(hi)) * sm, cv, zmax, lift):
        out[r, c] = np.float32(0.0)
        return
    if lo > 0.0 and not _blocked(z, pyr, off, widths, nlev, r, c, dc, sd, so,
                                 math.tan(math.radians(lo)) * sm, cv, zmax, lift):
        out[r, c] = np.float32(1.0)
        return
    rise_stop = math.tan(math.radians(lo)) * sm if lo > 0.0 else 0.0
    best = _horizon_tan(z, np.int64(r), np.int64(c), dc, sd, so, sm, cv, zmax, lift, rise_stop)
    horizon = math.degrees(math.atan(best)) if best > 0.0 else 0.0
    d = (horizon - el) / radius_deg
    d = min(1.0, max(-1.0, d))
    out[r, c] = np.float32((math.acos(d) - d * math.sqrt(1.0 - d * d)) / math.pi)


@njit(parallel=True, cache=True)
def _soft_cpu(z, pyr, off, widths, nlev, slat, clat, slon, clon, cth, sth, dx, dy, col_sign,
              row_sign, a, e2, sx, sy, sz, curv_k, zmax, lift, radius_deg, out):
    rows, cols = z.shape
    for r in prange(rows):
        for c in range(cols):
            _soft_cell(z, pyr, off, widths, nlev, np.int64(r), np.int64(c), slat, clat, slon,
                       clon, cth, sth, dx, dy, col_sign, row_sign, a, e2, sx, sy, sz, curv_k,
                       zmax, lift, radius_deg, out)


@kernel
def _soft_gpu(z, pyr, off, widths, nlev, slat, clat, slon, clon, cth, sth, dx, dy, col_sign,
              row_sign, a, e2, sx, sy, sz, curv_k, zmax, lift, radius_deg, out):
    """CUDA twin of ``_soft_cpu``: one thread per cell."""
    c, r = cuda.grid(2)
    if r < z.shape[0] and c < z.shape[1]:
        _soft_cell(z, pyr, off, widths, nlev, np.int64(r), np.int64(c), slat, clat, slon, clon,
                   cth, sth, dx, dy, col_sign, row_sign, a, e2, sx, sy, sz, curv_k, zmax, lift,
                   radius_deg, out)


def soft_fraction(z, pyr_args, frames, grid, a, e2, sun_xyz, radius_deg, curv_k=-1.0,
                  zmax=None, lift=0.0, out=None):
    """float32 visible fraction (0..1, NaN on voids) of the solar disk of angular radius
    ``radius_deg`` at every cell; arguments as ``shadow_mask`` (``out``: a float32 array of z's
    shape to fill, reused across suns)."""
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    if zmax is None:
        zmax = float(np.nanmax(z)) if np.isfinite(z).any() else -np.inf
    if out is None:
        out = np.empty(z.shape, np.float32)
    _soft_cpu(z, *pyr_args, *_args(frames, grid, a, e2, sun_xyz, curv_k, zmax, lift),
              float(radius_deg), out)
    return out


def soft_fraction_gpu(g, frames_d, grid, a, e2, sun_xyz, radius_deg, curv_k=-1.0, zmax=None,
                      lift=0.0, pyramid=True):
    """``soft_fraction`` on the GPU (``shadow_mask_gpu``'s arguments)."""
    rows, cols = g.shape
    out = g.empty((rows, cols), np.float32)
    zmax = g.zmax if zmax is None else zmax
    with g.timed():
        g.launch(_soft_gpu, rows, cols, g.z, *g.pyramid_args(pyramid),
                 *_args(frames_d, grid, a, e2, sun_xyz, curv_k, zmax, lift), float(radius_deg),
                 out)
    return g.download(out)


def _args(frames, grid, a, e2, sun_xyz, curv_k, zmax, lift):
    sx, sy, sz = (float(v) for v in sun_xyz)
    return (*frames, np.ascontiguousarray(grid.dx, np.float64),
            np.ascontiguousarray(grid.dy, np.float64), np.int64(grid.col_sign),
            np.int64(grid.row_sign), float(a), float(e2), sx, sy, sz, float(curv_k), float(zmax),
            float(lift))


def shadow_mask(z, pyr_args, frames, grid, a, e2, sun_xyz, curv_k=-1.0, zmax=None, lift=0.0,
                out=None):
    """uint8 mask (1 shadow, 0 lit, 255 void) of float32 heights ``z`` for the sun at
    ``sun_xyz`` (body-fixed metres): ``pyr_args`` the pyramid's kernel arguments
    (``pyramid.pyramid_args``), ``frames`` the six per-cell arrays of ``CellFrames.args()``,
    ``grid`` a ``geometry.Grid``, (``a``, ``e2``) the body's ellipsoid, ``curv_k`` the
    refraction coefficient of curved rays (-1: no curvature), ``lift`` metres above each cell;
    ``out``: a uint8 array of z's shape to fill (reused across suns: the illumination run)."""
    if z.dtype != np.float32 or z.ndim != 2:
        raise TypeError("heights must be a 2-D float32 array")
    if zmax is None:
        zmax = float(np.nanmax(z)) if np.isfinite(z).any() else -np.inf
    if out is None:
        out = np.empty(z.shape, np.uint8)
    _subsolar_cpu(z, *pyr_args, *_args(frames, grid, a, e2, sun_xyz, curv_k, zmax, lift), out)
    return out


def shadow_mask_gpu(g, frames_d, grid, a, e2, sun_xyz, curv_k=-1.0, zmax=None, lift=0.0,
                    pyramid=True):
    """``shadow_mask`` on the GPU: ``g`` a ``gpu.GpuDem``, ``frames_d`` the six frames arrays
    uploaded once (``g.upload``)."""
    rows, cols = g.shape
    out = g.empty((rows, cols), np.uint8)
    zmax = g.zmax if zmax is None else zmax
    with g.timed():
        g.launch(_subsolar_gpu, rows, cols, g.z, *g.pyramid_args(pyramid),
                 *_args(frames_d, grid, a, e2, sun_xyz, curv_k, zmax, lift), out)
    return g.download(out)


@njit(cache=True, parallel=True)
def cell_suns_cpu(slat, clat, slon, clon, z, a, e2, sx, sy, sz, lift, az, el):
    """True azimuth and elevation (degrees) of the sun at every cell into ``az``, ``el`` (a
    NaN height: the cell on the ellipsoid)."""
    rows, cols = z.shape
    for r in prange(rows):
        for c in range(cols):
            h = float(z[r, c])
            if math.isnan(h):
                h = 0.0
            e, n, u = cell_sun(float(slat[r, c]), float(clat[r, c]), float(slon[r, c]),
                               float(clon[r, c]), a, e2, sx, sy, sz, h + lift)
            hor = math.sqrt(e * e + n * n)
            el[r, c] = math.degrees(math.atan2(u, hor))
            t = math.degrees(math.atan2(e, n))
            az[r, c] = t + 360.0 if t < 0.0 else t
