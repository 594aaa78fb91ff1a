"""The body a DEM lies on, for Earth curvature and refraction: its ellipsoid (the CRS's: the
Earth's, the Moon's, Mars'), the DEM's latitude, and the curvature coefficient (1 - k) / 2R that
the rays take (docs/model.md): at ground distance d from its cell a ray stands d^2 (1 - k) / (2R)
higher above the terrain than on a flat surface. The constants and the radius of curvature in an
azimuth are ``geometry``'s (the ground spacing of geographic grids needs them too)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .geometry import REFRACTION_K, WGS84_A, WGS84_B, curvature_per_m2, radius_in_azimuth

CURVATURE_AUTO_M = 1000.0   # curvature "auto" turns on when rays can be longer than this


def curvature_coefficient(setting, body: "Body", k: float, extent_m: float,
                          zrange: tuple[float, float], azimuth: float, elevation: float) -> float:
    """(1 - k) / 2R for this sun, or 0 when curvature is off: ``setting`` True, False or "auto"
    (on when a ray can run longer than 1 km before it rises above the highest cell or leaves a
    raster ``extent_m`` across)."""
    if setting is False:
        return 0.0
    if setting == "auto":
        reach = extent_m if elevation <= 0 or elevation >= 90 else min(
            extent_m, (zrange[1] - zrange[0]) / math.tan(math.radians(elevation)))
        if reach <= CURVATURE_AUTO_M:
            return 0.0
    return curvature_per_m2(body.radius(azimuth), k)


def refraction_for(body: "Body", refraction_k: float | None) -> float:
    """The terrestrial refraction coefficient: ``refraction_k`` if given (checked), else 0.13 on
    the Earth and 0 elsewhere."""
    k = (REFRACTION_K if body.earth else 0.0) if refraction_k is None else float(refraction_k)
    curvature_per_m2(1.0, k)   # validates k
    return k


def curvature_report(setting, used: set, body: "Body", k: float) -> dict:
    """The report's ``curvature``: the setting, whether any sun's rays were curved, the radius
    the curved rays used (the body's radius of curvature in the sun's direction: one sun's, or
    the mean of a series' with ``radius_m_range``) and refraction. ``used``: the set of True/False
    seen and the radii (float metres) of the suns whose rays were curved (``Shader.rays``)."""
    radii = sorted(v for v in used if type(v) is float)
    rep = {"setting": setting, "applied": (True in used),
           "radius_m": (radii[0] if len(radii) == 1 else sum(radii) / len(radii)) if radii
           else None, "refraction_k": k, "body": body.source}
    if len(radii) > 1:
        rep["radius_m_range"] = [radii[0], radii[-1]]
    return rep


@dataclass
class Body:
    """The surface the DEM lies on, for curvature: ellipsoid axes, latitude of the DEM, whether it
    is the Earth (terrestrial refraction applies) and where the figures came from."""

    a: float = WGS84_A
    b: float = WGS84_B
    lat: float = 45.0
    earth: bool = True
    source: str = "WGS84"

    def radius(self, azimuth: float) -> float:
        return radius_in_azimuth(self.lat, azimuth, self.a, self.b)


def dem_body(dem, lat: float | None = None) -> Body:
    """The :class:`Body` of a DEM: its CRS's ellipsoid when that is not the Earth's (the Moon,
    Mars), WGS84 otherwise, at the DEM's centre latitude (or ``lat``)."""
    from .site import EARTH_A_RANGE
    if dem.crs is None or dem.transform is None:
        if lat is not None:
            return Body(lat=lat, source="WGS84 at --lat")
        return mean_earth()
    from pyproj import CRS as PCRS, Transformer
    pcrs = PCRS.from_user_input(dem.crs.to_wkt())
    ell = pcrs.ellipsoid
    rows, cols = dem.shape
    tr = dem.transform
    try:
        _, la = Transformer.from_crs(pcrs, pcrs.geodetic_crs, always_xy=True).transform(
            tr.c + tr.a * cols / 2.0, tr.f + tr.e * rows / 2.0)
        la = float(la) if math.isfinite(la) else 45.0
    except Exception:  # noqa: BLE001 -- a CRS pyproj cannot invert: mid-latitude
        la = 45.0
    if lat is not None:
        la = lat
    if ell is not None and not (EARTH_A_RANGE[0] <= ell.semi_major_metre <= EARTH_A_RANGE[1]):
        return Body(ell.semi_major_metre, ell.semi_minor_metre, la, False, ell.name)
    return Body(lat=la, source="WGS84")


EARTH_MEAN_RADIUS = 6371008.8


def mean_earth() -> Body:
    """The body of heights without a CRS: a sphere of the Earth's mean radius."""
    r = EARTH_MEAN_RADIUS
    return Body(r, r, 0.0, True, "no CRS: the Earth's mean radius")
