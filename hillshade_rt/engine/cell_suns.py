"""Per-cell suns on a body: the sun given by its subsolar point (latitude,
longitude on the body) and its distance, each cell's own sun direction from the cell's own place
on the body's ellipsoid (or sphere).

* :func:`body_from_option`: ``--body moon|mars|earth|RADIUS`` -> an ``earth.Body``;
  :func:`mean_sun_distance`: the body's mean distance from the sun (the ``--sun-distance``
  default).
* :class:`CellFrames`: what every cell needs, built once per DEM (or window) from its transform
  and CRS: sin/cos of its geodetic latitude and longitude and cos/sin of theta, the grid azimuth
  of true north at the cell (the projection's convergence), float32: 24 bytes per cell.
* :func:`sun_vector`: the sun's position in the body-fixed Cartesian frame.
* :func:`cell_suns`: each cell's true azimuth and elevation of the sun (degrees; a numba kernel).

Conventions: a cell's *grid* azimuth (the one ``geometry.sun_rays`` takes, clockwise from the
raster's own north) is its true azimuth plus theta. The cell's place P is on the body's
ellipsoid (a, b) at its height h (metres above the ellipsoid): P = ((N + h) cos(phi) cos(lam),
(N + h) cos(phi) sin(lam), (N (1 - e^2) + h) sin(phi)), N the prime-vertical radius; its local
east/north/up frame from the geodetic normal. The sun seen from P: v = S - P; elevation
atan2(v.up, |v_horizontal|) (geometric: no refraction), azimuth atan2(v.east, v.north).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.earth import Body
from ..errors import HillshadeError, UsageProblem
from ..model.geometry import WGS84_A, WGS84_B

AU = 149597870700.0
SUN_RADIUS_M = 695700000.0
MOON_RADIUS = 1737400.0
MARS_RADIUS = 3396190.0            # IAU sphere
MARS_POLAR = 3376200.0             # MOLA ellipsoid's polar semi-axis
MARS_DISTANCE = 227939200000.0     # 1.5237 AU, Mars' mean distance from the sun


def _near(a: float, b: float) -> bool:
    return abs(a - b) <= 0.01 * b


def body_from_option(text, dem_body: Body | None = None) -> Body:
    """The body of ``--body``: 'moon' (sphere 1737400 m), 'mars' (the DEM's CRS's Mars
    ellipsoid when it has one, e.g. MOLA's 3396190/3376200, else the IAU sphere 3396190 m),
    'earth' (WGS84), or a radius in metres (a sphere); None: ``dem_body`` (the CRS's). The
    latitude (curvature reports) is ``dem_body``'s."""
    lat = dem_body.lat if dem_body is not None else 0.0
    if text is None or (isinstance(text, str) and not text.strip()):
        if dem_body is None:
            raise HillshadeError("no body: give --body moon|mars|earth|RADIUS or a DEM with a CRS")
        return dem_body
    name = str(text).strip().lower()
    if name == "moon":
        return Body(MOON_RADIUS, MOON_RADIUS, lat, False, "Moon (sphere 1737400 m)")
    if name == "mars":
        if dem_body is not None and not dem_body.earth and _near(dem_body.a, MARS_RADIUS):
            return Body(dem_body.a, dem_body.b, lat, False, f"Mars ({dem_body.source})")
        return Body(MARS_RADIUS, MARS_RADIUS, lat, False, "Mars (IAU sphere 3396190 m)")
    if name == "earth":
        return Body(WGS84_A, WGS84_B, lat, True, "WGS84")
    try:
        r = float(name)
    except ValueError:
        raise UsageProblem(f"--body takes moon, mars, earth or a radius in metres, got {text!r}")
    if not (math.isfinite(r) and r > 0):
        raise UsageProblem(f"--body radius must be positive metres, got {text!r}")
    return Body(r, r, lat, False, f"sphere {r:g} m")


def mean_sun_distance(body: Body) -> float:
    """The body's mean distance from the sun (m): Mars' 1.5237 AU for a body of Mars' size, 1 AU
    otherwise (the Earth, the Moon, a sphere of a given radius)."""
    if not body.earth and _near(body.a, MARS_RADIUS):
        return MARS_DISTANCE
    return AU


def _e2(body: Body) -> float:
    return 1.0 - (body.b * body.b) / (body.a * body.a)


def sun_vector(body: Body, lat_s: float, lon_s: float, distance_m: float | None = None
               ) -> np.ndarray:
    """The sun's position (x, y, z metres, body-fixed: x toward lon 0 on the equator, z the
    north pole) for the subsolar point (``lat_s``, ``lon_s``: geodetic degrees) and the sun's
    ``distance_m`` from the body's centre (default :func:`mean_sun_distance`): on the ellipsoid
    normal at the subsolar point (the sun is exactly at its zenith there), |S| = distance."""
    lat_s, lon_s = float(lat_s), float(lon_s)
    if not (math.isfinite(lat_s) and -90.0 <= lat_s <= 90.0):
        raise HillshadeError(f"subsolar latitude must be in [-90, 90] degrees, got {lat_s:g}")
    if not math.isfinite(lon_s):
        raise HillshadeError(f"subsolar longitude must be finite degrees, got {lon_s:g}")
    d = mean_sun_distance(body) if distance_m is None else float(distance_m)
    if not (math.isfinite(d) and d > body.a):
        raise HillshadeError(f"the sun's distance must exceed the body's radius ({body.a:.0f} m), "
                             f"got {d:g} m")
    phi, lam = math.radians(lat_s), math.radians(lon_s)
    n = np.array([math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam), math.sin(phi)])
    e2 = _e2(body)
    big_n = body.a / math.sqrt(1.0 - e2 * math.sin(phi) ** 2)
    p = np.array([big_n * n[0], big_n * n[1], big_n * (1.0 - e2) * n[2]])
    pn = float(p @ n)
    t = -pn + math.sqrt(pn * pn - float(p @ p) + d * d)
    return p + t * n


def sun_radius_deg(distance_m: float) -> float:
    """The solar disk's angular radius (degrees) at ``distance_m``: asin(R_sun / d)."""
    return math.degrees(math.asin(min(1.0, SUN_RADIUS_M / float(distance_m))))


@dataclass
class CellFrames:
    """Per-cell float32 arrays of a DEM's shape: ``slat``, ``clat`` (sin, cos of geodetic
    latitude), ``slon``, ``clon`` (longitude), ``cth``, ``sth`` (cos, sin of theta, the grid
    azimuth of true north: a direction of true azimuth A has grid azimuth A + theta). 24 bytes a
    cell, built once per DEM and shared by every sun."""

    slat: np.ndarray
    clat: np.ndarray
    slon: np.ndarray
    clon: np.ndarray
    cth: np.ndarray
    sth: np.ndarray

    @property
    def shape(self):
        return self.slat.shape

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in (self.slat, self.clat, self.slon, self.clon, self.cth,
                                      self.sth))

    @classmethod
    def from_transform(cls, transform, crs, shape) -> "CellFrames":
        """The frames of a north-up (or south-up) raster of ``shape`` with ``transform`` in
        ``crs`` (a rasterio CRS, a pyproj CRS or anything pyproj takes). Latitude and longitude
        of every cell centre from pyproj (the CRS's own geodetic CRS), vectorised; theta from
        central differences of the projection along the meridian (a step of 1e-6 degrees each
        way, clamped at the poles, so that a cell on a pole takes its longitude's meridian)."""
        from pyproj import CRS as PCRS, Transformer

        from ..model.geometry import orientation
        if crs is None or transform is None:
            raise HillshadeError("per-cell suns need a DEM with a geotransform and a CRS")
        orientation(transform)
        pcrs = PCRS.from_user_input(crs.to_wkt() if hasattr(crs, "to_wkt") else crs)
        rows, cols = shape
        x = transform.c + transform.a * (np.arange(cols, dtype=np.float64) + 0.5)
        y = transform.f + transform.e * (np.arange(rows, dtype=np.float64) + 0.5)
        if pcrs.is_geographic:
            unit = pcrs.axis_info[0].unit_conversion_factor * 180.0 / math.pi   # deg per unit
            # the axis order of pyproj's geographic CRS is irrelevant here: transforms are x, y
            lon = np.broadcast_to(x[None, :] * unit, shape)
            lat = np.broadcast_to(np.clip(y[:, None] * unit, -90.0, 90.0), shape)
            theta = None
        else:
            xx, yy = np.meshgrid(x, y)
            to_geo = Transformer.from_crs(pcrs, pcrs.geodetic_crs, always_xy=True)
            lon, lat = to_geo.transform(xx, yy)
            lon, lat = np.asarray(lon), np.asarray(lat)
            if not (np.isfinite(lon).all() and np.isfinite(lat).all()):
                raise HillshadeError("some cells of the DEM have no place on the body (outside "
                                     "the projection's domain)")
            to_crs = Transformer.from_crs(pcrs.geodetic_crs, pcrs, always_xy=True)
            h = 1e-6
            x1, y1 = to_crs.transform(lon, np.minimum(lat + h, 90.0))
            x0, y0 = to_crs.transform(lon, np.maximum(lat - h, -90.0))
            theta = np.arctan2(np.asarray(x1) - np.asarray(x0), np.asarray(y1) - np.asarray(y0))
            theta = np.where(np.isfinite(theta), theta, 0.0)
        phi, lam = np.radians(lat), np.radians(lon)
        f32 = np.float32
        if theta is None:
            cth, sth = np.ones(shape, f32), np.zeros(shape, f32)
        else:
            cth, sth = np.cos(theta).astype(f32), np.sin(theta).astype(f32)
        return cls(np.sin(phi).astype(f32), np.cos(phi).astype(f32), np.sin(lam).astype(f32),
                   np.cos(lam).astype(f32), cth, sth)

    @classmethod
    def of_dem(cls, dem) -> "CellFrames":
        """The frames of a Dem from ``read_dem``."""
        return cls.from_transform(dem.transform, dem.crs, dem.heights.shape)

    def args(self) -> tuple:
        return (self.slat, self.clat, self.slon, self.clon, self.cth, self.sth)


def cell_suns(frames: CellFrames, body: Body, sun_xyz, heights=None, lift: float = 0.0):
    """(true azimuth, elevation) of the sun at every cell, float64 degrees (azimuth clockwise
    from true north in [0, 360); elevation geometric, <= 0 below the cell's horizon), the cell at
    its height (``heights``, NaN and None: on the ellipsoid) plus ``lift``. The grid azimuth is
    the true azimuth + theta (``grid_azimuth``)."""
    shape = frames.shape
    z = np.zeros(shape, np.float32) if heights is None else np.asarray(heights, np.float32)
    az = np.empty(shape, np.float64)
    el = np.empty(shape, np.float64)
    sx, sy, sz = (float(v) for v in sun_xyz)
    from ..algorithms.subsolar import cell_suns_cpu
    cell_suns_cpu(frames.slat, frames.clat, frames.slon, frames.clon, z, float(body.a), _e2(body), sx, sy, sz, float(lift), az, el)
    return az, el


def grid_azimuth(frames: CellFrames, true_azimuth) -> np.ndarray:
    """The grid azimuth (degrees, [0, 360)) of the true azimuths at each cell: + theta."""
    th = np.degrees(np.arctan2(frames.sth.astype(np.float64), frames.cth.astype(np.float64)))
    return np.mod(np.asarray(true_azimuth) + th, 360.0)
