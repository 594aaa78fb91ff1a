"""Ground spacing of a raster and the sun direction in pixel units.

Conventions (see docs/model.md):

* Azimuth: degrees clockwise from north, measured from the raster's own north (the direction of
  decreasing row in a north-up raster), like ``gdaldem hillshade``. Any real value wraps.
* Elevation: degrees above the horizon, 0 < E <= 90.
* Spacing: ground metres per column (``dx``) and per row (``dy``), one value per row, because in a
  geographic CRS (and in projections whose scale varies with latitude) it changes from row to row.
  The rays of the cells of row ``r`` use the spacing of row ``r``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import HillshadeError


@dataclass(frozen=True)
class Grid:
    """Ground geometry of a raster: spacing per row and which way the indices run.

    dx, dy: float64 arrays of length ``rows``, ground metres between neighbouring cell centres along
    a row (dx) and along a column (dy), evaluated at each row.
    col_sign: +1 when the column index grows eastward, -1 when it grows westward.
    row_sign: +1 when the row index grows northward (south-up raster), -1 when it grows southward
    (the usual north-up raster).
    method: how the spacing was obtained (for ``info`` and reports).
    """

    rows: int
    cols: int
    dx: np.ndarray
    dy: np.ndarray
    col_sign: int = 1
    row_sign: int = -1
    method: str = "pixel size"

    @classmethod
    def uniform(cls, rows: int, cols: int, dx: float, dy: float | None = None,
                col_sign: int = 1, row_sign: int = -1, method: str = "pixel size") -> "Grid":
        """A grid with one spacing for every row (projected CRS, raw input, tests)."""
        dy = dx if dy is None else dy
        if not (dx > 0 and dy > 0 and math.isfinite(dx) and math.isfinite(dy)):
            raise HillshadeError(f"pixel size must be positive and finite, got {dx}, {dy}")
        return cls(rows, cols, np.full(rows, float(dx)), np.full(rows, float(dy)),
                   col_sign, row_sign, method)

    def centre_spacing(self) -> tuple[float, float]:
        """(dx, dy) in metres at the centre row."""
        r = self.rows // 2
        return float(self.dx[r]), float(self.dy[r])


def heights_and_grid(heights, spacing) -> tuple[np.ndarray, Grid]:
    """2-D float32 heights (a float32 array is used in place, other types converted once) and a
    Grid from ``d``, ``(dx, dy)`` or a Grid of the same shape."""
    z = np.asarray(heights)
    if z.ndim != 2 or z.size == 0:
        raise HillshadeError(f"heights must be a non-empty 2-D array, got shape {z.shape}")
    if z.dtype != np.float32:
        z = z.astype(np.float32)
    if not isinstance(spacing, Grid):
        dx, dy = (spacing, spacing) if np.isscalar(spacing) else spacing
        spacing = Grid.uniform(z.shape[0], z.shape[1], float(dx), float(dy))
    elif (spacing.rows, spacing.cols) != z.shape:
        raise HillshadeError(f"grid is {spacing.rows}x{spacing.cols} but heights are {z.shape}")
    return z, spacing


def normalize_azimuth(azimuth: float) -> float:
    """Wrap any real azimuth into [0, 360)."""
    if not math.isfinite(azimuth):
        raise HillshadeError(f"azimuth must be a finite number of degrees, got {azimuth}")
    a = math.fmod(azimuth, 360.0)
    if a < 0:
        a += 360.0
    return 0.0 if a == 360.0 else a


def equal_azimuths(step: float) -> list[float]:
    """Azimuths every ``step`` degrees clockwise from north, north first, below 360 (exactly
    i * 360 / n when ``step`` divides 360)."""
    n = int(round(360.0 / step))
    if n >= 1 and abs(n * step - 360.0) < 1e-9:
        return [360.0 * i / n for i in range(n)]
    return [float(a) for a in np.arange(0.0, 360.0, step)]


def check_elevation(elevation: float, what: str = "sun elevation") -> float:
    """Sun elevation in degrees: must be > 0 and <= 90. ``what`` names it in the error (e.g. the
    option it came from)."""
    if not (math.isfinite(elevation) and 0.0 < elevation <= 90.0):
        if math.isfinite(elevation) and elevation <= 0.0:
            raise HillshadeError(
                f"{what} must be > 0 and <= 90 degrees, got {elevation:g} "
                "(a sun at or below the horizon lights nothing)")
        raise HillshadeError(f"{what} must be a number of degrees in (0, 90], got {elevation:g}"
                             + (" (90 is the zenith)" if math.isfinite(elevation) else ""))
    return float(elevation)


def sincos_deg(angle: float) -> tuple[float, float]:
    """(sin, cos) of an angle in degrees, exact at multiples of 45 degrees.

    Exactness matters: at azimuth 180 a rounding residue of 1e-16 in sin would make the ray
    interpolate towards a column that does not exist; at 45 degrees on a square grid sin and cos
    must be equal so that the ray passes exactly through the diagonal cell centres.
    """
    a = normalize_azimuth(angle)
    q, rem = divmod(a, 90.0)
    if rem == 0.0:
        s, c = 0.0, 1.0
    elif rem == 45.0:
        s = c = math.sqrt(0.5)
    else:
        s, c = math.sin(math.radians(rem)), math.cos(math.radians(rem))
    for _ in range(int(q)):  # rotate by 90 degrees: (s, c) -> (c, -s)
        s, c = c, -s
    return s, c


@dataclass(frozen=True)
class SunRays:
    """The ray toward the sun from the cells of each row, in pixel units.

    For row r the ray advances one grid line of its dominant axis per step:
    ``dom_col[r]`` is 1 when that axis is the column index (the ray crosses columns), 0 when it is
    the row index; ``step_dom[r]`` is +1 or -1 (direction along the dominant index);
    ``step_other[r]`` is the change of the other index per step (|.| <= 1); ``rise[r]`` is the
    height gained per step in metres (tan(elevation) times the ground length of one step);
    ``curv[r]`` is the Earth-curvature gain: at step k the ray stands ``k*rise + k*k*curv`` above
    its start relative to the terrain (0 without curvature; see :func:`curvature_per_m2`).
    """

    azimuth: float
    elevation: float
    dom_col: np.ndarray    # int8
    step_dom: np.ndarray   # int8
    step_other: np.ndarray  # float64
    rise: np.ndarray       # float64
    step_m: np.ndarray     # float64, ground metres per step
    curv: np.ndarray       # float64, metres per step**2 (Earth curvature), zeros when off

    @property
    def curved(self) -> bool:
        return bool(np.any(self.curv != 0.0))


def sun_rays(grid: Grid, azimuth: float, elevation: float, curvature: float = 0.0) -> SunRays:
    """Sun direction in pixel units for every row of ``grid``.

    curvature: (1 - k) / (2 R) in 1/m (:func:`curvature_per_m2`), 0 for a flat Earth."""
    az = normalize_azimuth(azimuth)
    el = check_elevation(elevation)
    east, north = sincos_deg(az)
    dom_col, step_dom, step_other, step_m = ray_steps(east, north, grid.dx, grid.dy,
                                                      grid.col_sign, grid.row_sign)
    tan_el = math.inf if el == 90.0 else math.tan(math.radians(el))
    rise = tan_el * step_m
    if not (math.isfinite(curvature) and curvature >= 0.0):
        raise HillshadeError(f"curvature coefficient must be >= 0, got {curvature}")
    curv = float(curvature) * step_m * step_m
    return SunRays(az, el, dom_col, step_dom, step_other, rise.astype(np.float64), step_m,
                   curv.astype(np.float64))


def ray_steps(east, north, dx, dy, col_sign: int = 1, row_sign: int = -1):
    """(dom_col int8, step_dom int8, step_other, step_m float64) of the horizontal direction
    (``east``, ``north``: a unit vector, ``sincos_deg`` of the azimuth) on cells of ``dx`` x
    ``dy`` ground metres, as :class:`SunRays` holds them; every argument a number or an array
    (numpy broadcasting): :func:`sun_rays` for the rows of a grid, or many directions on one
    row's cells (``arrays.sun_at_points``: a sun per point)."""
    # pixels travelled per ground metre toward the sun, along columns and along rows
    pc = east * col_sign / dx
    pr = north * row_sign / dy
    dom_col = np.abs(pc) >= np.abs(pr)
    a_dom = np.where(dom_col, np.abs(pc), np.abs(pr))
    step_dom = np.where(dom_col, np.sign(pc), np.sign(pr)).astype(np.int8)
    step_other = np.where(dom_col, pr, pc) / a_dom
    step_m = 1.0 / a_dom
    return (dom_col.astype(np.int8), step_dom, np.asarray(step_other, np.float64),
            np.asarray(step_m, np.float64))


# --------------------------------------------------------------------------------------------
# Earth curvature

WGS84_A = 6378137.0
WGS84_B = 6356752.314245179
REFRACTION_K = 0.13   # terrestrial refraction coefficient (light bends with radius R / k)


def radius_in_azimuth(lat_deg: float, azimuth: float, a: float = WGS84_A,
                      b: float = WGS84_B) -> float:
    """Radius of curvature (m) of ellipsoid (a, b) at ``lat_deg`` along ``azimuth`` (Euler:
    1/R = cos^2(az)/M + sin^2(az)/N)."""
    e2 = 1.0 - (b * b) / (a * a)
    s = math.sin(math.radians(lat_deg))
    w = math.sqrt(1.0 - e2 * s * s)
    n = a / w
    m = a * (1.0 - e2) / w ** 3
    az = math.radians(azimuth)
    return 1.0 / (math.cos(az) ** 2 / m + math.sin(az) ** 2 / n)


def curvature_per_m2(radius_m: float, k: float = REFRACTION_K) -> float:
    """(1 - k) / (2 R): a ray ``d`` metres from its start stands ``d**2 (1 - k) / (2 R)`` higher
    above the curved terrain than above a flat one (the terrain falls away below the observer's
    horizontal plane by d^2/2R; terrestrial refraction bends the ray back down by k of that)."""
    if not (math.isfinite(k) and 0.0 <= k < 1.0):
        raise HillshadeError(f"refraction coefficient must be >= 0 and < 1, got {k}")
    if not (math.isfinite(radius_m) and radius_m > 0):
        raise HillshadeError(f"Earth radius must be positive, got {radius_m}")
    return (1.0 - k) / (2.0 * radius_m)


# --------------------------------------------------------------------------------------------
# spacing from a geotransform and a CRS

def _ellipsoid_spacing(lat_deg: np.ndarray, a: float, b: float,
                       dlon_rad: float, dlat_rad: float) -> tuple[np.ndarray, np.ndarray]:
    """Ground metres spanned by dlon/dlat (radians) at each latitude, on ellipsoid (a, b)."""
    e2 = 1.0 - (b * b) / (a * a)
    phi = np.radians(lat_deg)
    w = np.sqrt(1.0 - e2 * np.sin(phi) ** 2)
    n = a / w                      # prime-vertical radius of curvature
    m = a * (1.0 - e2) / w ** 3    # meridional radius of curvature
    return n * np.cos(phi) * dlon_rad, m * dlat_rad


def _geodesic(geod, to_geo, x0, y0, x1, y1) -> np.ndarray:
    """Geodesic metres between projected points (NaN where a point has no place on the body:
    beyond a pole, outside the projection's domain)."""
    lon0, lat0 = to_geo.transform(x0, y0)
    lon1, lat1 = to_geo.transform(x1, y1)
    lat0, lat1 = np.asarray(lat0, np.float64), np.asarray(lat1, np.float64)
    g = np.asarray(geod.inv(lon0, lat0, lon1, lat1)[2], dtype=np.float64)
    bad = ~(np.isfinite(g) & (np.abs(lat0) <= 90.0) & (np.abs(lat1) <= 90.0))
    return np.where(bad, np.nan, g)


def _cell_step(geod, to_geo, xs, y, sx: float, sy: float) -> np.ndarray:
    """Ground metres of one cell step (``sx``, ``sy`` CRS units) centred at each (xs, y): the
    geodesic between the cell's two edges; where an edge lies beyond a pole or outside the
    projection (the first and last rows of a global grid whose edge overshoots the pole by a
    rounding), the derivative at the cell centre: a step of 1/1000 of the cell centred there,
    else one-sided from the centre toward the inside, scaled up. NaN where none exists."""
    g = _geodesic(geod, to_geo, xs - sx / 2, y - sy / 2, xs + sx / 2, y + sy / 2)
    h = 1e-3
    for lo, hi in ((-h / 2, h / 2), (0.0, h), (-h, 0.0)):
        bad = ~(np.isfinite(g) & (g > 0))
        if not bad.any():
            break
        part = _geodesic(geod, to_geo, xs[bad] + sx * lo, y[bad] + sy * lo, xs[bad] + sx * hi,
                         y[bad] + sy * hi) / h
        g[bad] = np.where(np.isfinite(part) & (part > 0), part, np.nan)
    return np.where(np.isfinite(g) & (g > 0), g, np.nan)


def orientation(transform) -> tuple[int, int]:
    """(col_sign, row_sign) of a north-up or south-up geotransform; refuses rotation and shear."""
    if transform.b != 0.0 or transform.d != 0.0:
        raise HillshadeError(
            "rotated or sheared geotransform is not supported; "
            "warp the DEM to a north-up grid first (gdalwarp)")
    if transform.a == 0.0 or transform.e == 0.0:
        raise HillshadeError("degenerate geotransform: pixel width or height is zero")
    return (1 if transform.a > 0 else -1), (1 if transform.e > 0 else -1)


def grid_from_transform(transform, crs, shape: tuple[int, int]) -> Grid:
    """Ground spacing per row from a north-up (or south-up) geotransform and its CRS.

    * geographic CRS: metres per degree from the CRS's own ellipsoid at each row's latitude;
    * projected CRS: the geodesic length, on the CRS's own ellipsoid, of one cell step at the
      centre column of each row. For a conformal projection this equals the transform units times
      the CRS's linear unit divided by the scale factor (``Proj.get_factors``); unlike that
      quotient it stays right for projections defined on a sphere but used on an ellipsoid (Web
      Mercator: 0.2 % at 47 N) and for non-conformal ones (orthographic, equirectangular);
    * no CRS but a real geotransform: the transform's units are taken as metres.
    """
    rows, cols = shape
    a, c, e, f = transform.a, transform.c, transform.e, transform.f
    col_sign, row_sign = orientation(transform)
    r_idx = np.arange(rows, dtype=np.float64) + 0.5
    y = f + e * r_idx                       # centre of each row, CRS units
    x_mid = c + a * (cols / 2.0)            # centre column
    if crs is None:
        return Grid(rows, cols, np.full(rows, abs(a)), np.full(rows, abs(e)),
                    col_sign, row_sign, "geotransform units taken as metres (no CRS)")

    from pyproj import CRS as PCRS, Transformer

    pcrs = PCRS.from_user_input(crs.to_wkt() if hasattr(crs, "to_wkt") else crs)
    ell = pcrs.ellipsoid
    if pcrs.is_geographic:
        unit = pcrs.axis_info[0].unit_conversion_factor  # radians per CRS unit
        if ell is None:
            raise HillshadeError("geographic CRS without an ellipsoid: cannot convert degrees to metres")
        if np.any(np.abs(y) > 90.0 * (math.pi / 180.0) / unit + 1e-9):
            raise HillshadeError("geographic DEM has rows beyond the poles: check its geotransform")
        lat = np.clip(y * unit * 180.0 / math.pi, -90.0, 90.0)
        dx, dy = _ellipsoid_spacing(lat, ell.semi_major_metre, ell.semi_minor_metre,
                                    abs(a) * unit, abs(e) * unit)
        dx = np.maximum(dx, 1e-3)  # a row exactly at a pole spans no width
        return Grid(rows, cols, dx, dy, col_sign, row_sign,
                    f"ellipsoid {ell.name} (a={ell.semi_major_metre:.1f} m) at each row's latitude")
    if not pcrs.is_projected:
        # engineering / local CRS: units only
        unit = pcrs.axis_info[0].unit_conversion_factor if pcrs.axis_info else 1.0
        return Grid(rows, cols, np.full(rows, abs(a) * unit), np.full(rows, abs(e) * unit),
                    col_sign, row_sign, "local CRS: transform units times the CRS's unit")
    unit = pcrs.axis_info[0].unit_conversion_factor  # metres per CRS unit
    dx = np.full(rows, abs(a) * unit)
    dy = np.full(rows, abs(e) * unit)
    method = "projected: transform units x CRS unit (no geodesic correction possible)"
    try:
        geod = pcrs.get_geod()
        to_geo = Transformer.from_crs(pcrs, pcrs.geodetic_crs, always_xy=True)
        xs = np.full(rows, x_mid)
        gx = _cell_step(geod, to_geo, xs, y, a, 0.0)
        gy = _cell_step(geod, to_geo, xs, y, 0.0, e)
        okx, oky = np.isfinite(gx), np.isfinite(gy)
        if okx.any() or oky.any():
            dx[okx], dy[oky] = gx[okx], gy[oky]
            method = ("projected: geodesic length of one cell on the CRS's ellipsoid "
                      "at the centre column of each row")
            if not (okx.all() and oky.all()):
                method += f" (transform units where the projection has no inverse: " \
                          f"{int((~(okx & oky)).sum())} row(s))"
            dx, dy, snapped = snap_uniform(dx, dy)
            if snapped:
                method = ("projected: geodesic length of one cell on the CRS's ellipsoid at the "
                          f"centre; uniform (varies < {UNIFORM_RTOL:g} across rows)")
    except Exception:  # noqa: BLE001 -- a projection proj cannot invert: units only
        pass
    return Grid(rows, cols, dx, dy, col_sign, row_sign, method)


# Below this relative variation across rows, per-row spacing is projection noise (UTM: ~1e-7 over a
# 30 km raster): the centre row's value is used for every row, which gives one sun direction in
# pixel units for the whole raster (what smap, horizon's hull and sweep's fast path need).
UNIFORM_RTOL = 1e-5


def snap_uniform(dx: np.ndarray, dy: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
    """(dx, dy, snapped): the centre row's spacing everywhere when the variation is below
    ``UNIFORM_RTOL``."""
    def small(a):
        return float(np.max(a) - np.min(a)) <= UNIFORM_RTOL * float(np.min(a))
    if len(dx) and small(dx) and small(dy):
        m = len(dx) // 2
        return np.full(len(dx), dx[m]), np.full(len(dy), dy[m]), True
    return dx, dy, False
