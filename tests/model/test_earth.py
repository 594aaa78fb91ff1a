"""The body a DEM lies on (model.earth): the curvature coefficient against the closed forms (the
sphere's drop, Euler's radius of curvature of the ellipsoid), "auto", refraction, the body of a
CRS and the report."""

import math
from types import SimpleNamespace

import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError
from hillshade_rt.model import earth

AZIMUTHS = (163.0, 203.7, 290.0)


def euler_radius(lat, az, a, b):
    """Independent: meridian M and prime-vertical N radii, 1/R = cos^2 az / M + sin^2 az / N."""
    e2 = (a * a - b * b) / (a * a)
    s2 = math.sin(math.radians(lat)) ** 2
    m = a * (1 - e2) / (1 - e2 * s2) ** 1.5
    n = a / math.sqrt(1 - e2 * s2)
    c = math.cos(math.radians(az))
    return 1.0 / (c * c / m + (1 - c * c) / n)


@pytest.mark.parametrize("az", AZIMUTHS)
@pytest.mark.parametrize("lat", [0.0, 34.3, 61.5, -78.0])
def test_coefficient_is_euler_radius_and_drop_matches_the_sphere(az, lat):
    body = earth.Body(lat=lat)
    for k in (0.0, 0.13):
        c = earth.curvature_coefficient(True, body, k, 5e4, (0.0, 10.0), az, 20.0)
        r = euler_radius(lat, az, body.a, body.b)
        assert c == pytest.approx((1 - k) / (2 * r), rel=1e-12)
        if k == 0.0:
            # the exact drop of a sphere of that radius below a tangent plane at ground distance
            # d (along the tangent) is sqrt(R^2 + d^2) - R; c d^2 is its leading term
            for d in (1e3, 1e4, 5e4):
                exact = math.sqrt(r * r + d * d) - r
                assert c * d * d == pytest.approx(exact, rel=2 * d * d / (r * r) + 1e-12)


def test_off_is_zero_and_auto_turns_on_past_one_kilometre():
    body = earth.Body(lat=45.0)
    assert earth.curvature_coefficient(False, body, 0.13, 1e6, (0, 4000), 203.7, 1.0) == 0.0
    # a raster 900 m across: no ray longer than 1 km
    assert earth.curvature_coefficient("auto", body, 0.13, 900.0, (0, 4000), 163, 1.0) == 0.0
    # 100 m of relief under a 20 degree sun: rays rise above everything within 275 m
    assert earth.curvature_coefficient("auto", body, 0.13, 5e4, (0, 100), 290, 20.0) == 0.0
    # under a 2 degree sun they run 2.9 km
    on = earth.curvature_coefficient("auto", body, 0.13, 5e4, (0, 100), 290, 2.0)
    assert on == pytest.approx(0.87 / (2 * euler_radius(45.0, 290, body.a, body.b)))
    # the sun below the horizon: the raster's extent decides
    assert earth.curvature_coefficient("auto", body, 0.13, 5e4, (0, 100), 290, -1.0) > 0


def test_refraction_defaults_and_checks():
    assert earth.refraction_for(earth.Body(), None) == 0.13
    moon = earth.Body(1737400.0, 1737400.0, 0.0, False, "Moon")
    assert earth.refraction_for(moon, None) == 0.0
    assert earth.refraction_for(moon, 0.25) == 0.25
    for bad in (-0.1, 1.0, float("nan")):
        with pytest.raises(HillshadeError):
            earth.refraction_for(earth.Body(), bad)


def test_dem_body_takes_the_centre_latitude_and_a_foreign_ellipsoid():
    # geographic, 0.01 degree cells, 200 x 100, top-left at (10 E, 50 N): centre at 49 N
    geo = SimpleNamespace(crs=CRS.from_epsg(4326), transform=Affine(0.01, 0, 10, 0, -0.01, 50),
                          shape=(200, 100))
    b = earth.dem_body(geo)
    assert b.earth and b.lat == pytest.approx(49.0) and (b.a, b.b) == (earth.WGS84_A, earth.WGS84_B)
    assert earth.dem_body(geo, lat=12.5).lat == 12.5
    moon = SimpleNamespace(crs=CRS.from_wkt(
        'GEOGCS["Moon 2000",DATUM["D_Moon_2000",SPHEROID["Moon_2000_IAU_IAG",1737400.0,0.0]],'
        'PRIMEM["Greenwich",0],UNIT["Decimal_Degree",0.0174532925199433]]'),
        transform=Affine(0.01, 0, 0, 0, -0.01, -20), shape=(100, 100))
    m = earth.dem_body(moon)
    assert not m.earth and m.a == pytest.approx(1737400.0) and m.lat == pytest.approx(-20.5)
    assert m.radius(203.7) == pytest.approx(1737400.0)
    assert earth.refraction_for(m, None) == 0.0
    bare = SimpleNamespace(crs=None, transform=None, shape=(10, 10))
    assert earth.dem_body(bare).radius(290) == pytest.approx(earth.EARTH_MEAN_RADIUS)
    assert earth.dem_body(bare, lat=30.0).lat == 30.0


def test_report_names_one_radius_or_the_mean_and_range():
    body = earth.Body()
    one = earth.curvature_report("auto", {True, 6.37e6}, body, 0.13)
    assert one["applied"] and one["radius_m"] == 6.37e6 and "radius_m_range" not in one
    two = earth.curvature_report(True, {True, False, 6.36e6, 6.38e6}, body, 0.13)
    assert two["radius_m"] == pytest.approx(6.37e6) and two["radius_m_range"] == [6.36e6, 6.38e6]
    none = earth.curvature_report("auto", {False}, body, 0.13)
    assert not none["applied"] and none["radius_m"] is None and none["body"] == "WGS84"
