"""Spacing from geotransforms and CRSs, and the sun direction."""

import math

import numpy as np
import pytest
from affine import Affine
from pyproj import CRS as PCRS, Geod
from rasterio.crs import CRS

from hillshade_rt import HillshadeError
from hillshade_rt.model.geometry import (
    check_elevation, grid_from_transform, normalize_azimuth, sincos_deg, sun_rays, Grid
)


def test_normalize_azimuth():
    assert normalize_azimuth(0) == 0 and normalize_azimuth(360) == 0
    assert normalize_azimuth(-90) == 270 and normalize_azimuth(725.5) == 5.5
    assert normalize_azimuth(-1e-20) == 0.0  # no 360.0 from rounding
    with pytest.raises(HillshadeError):
        normalize_azimuth(float("nan"))


@pytest.mark.parametrize("bad", [0.0, -5.0, 90.0001, float("nan"), float("inf")])
def test_elevation_out_of_range(bad):
    with pytest.raises(HillshadeError, match="elevation"):
        check_elevation(bad)


def test_sincos_exact_on_axes_and_diagonals():
    assert sincos_deg(0) == (0.0, 1.0)
    assert sincos_deg(90) == (1.0, 0.0)
    assert sincos_deg(180) == (0.0, -1.0)
    assert sincos_deg(270) == (-1.0, 0.0)
    for a in (45, 135, 225, 315):
        s, c = sincos_deg(a)
        assert abs(s) == abs(c)
    s, c = sincos_deg(203.7)
    assert s == pytest.approx(math.sin(math.radians(203.7)), abs=1e-15)
    assert c == pytest.approx(math.cos(math.radians(203.7)), abs=1e-15)


def test_sun_rays_pixel_direction():
    g = Grid.uniform(10, 10, 2.0, 1.0)  # north-up, 2 m columns, 1 m rows
    r = sun_rays(g, 270.0, 45.0)         # sun from the west: ray goes to lower columns
    assert r.dom_col[0] == 1 and r.step_dom[0] == -1 and r.step_other[0] == 0.0
    assert r.rise[0] == pytest.approx(2.0)  # one column = 2 m at tan 45
    r = sun_rays(g, 0.0, 45.0)           # sun from the north: ray goes to lower rows
    assert r.dom_col[0] == 0 and r.step_dom[0] == -1
    r = sun_rays(g, 45.0, 30.0)          # NE on 2x1 m pixels: 1 column per 2 rows
    assert r.dom_col[0] == 0 and r.step_dom[0] == -1 and r.step_other[0] == pytest.approx(0.5)
    south_up = Grid.uniform(10, 10, 1.0, 1.0, row_sign=1)
    assert sun_rays(south_up, 0.0, 45.0).step_dom[0] == 1


def _geodesic_spacing(crs, transform, rows, cols):
    """Ground metres between neighbouring cell centres at the centre column, by geodesics."""
    from pyproj import Transformer

    pc = PCRS.from_user_input(crs.to_wkt())
    geod = pc.get_geod()
    to_geo = Transformer.from_crs(pc, pc.geodetic_crs, always_xy=True)
    r = np.arange(rows) + 0.5
    c = cols / 2.0
    def lonlat(cc, rr):
        x, y = transform.c + transform.a * cc, transform.f + transform.e * rr
        return to_geo.transform(x, y)
    lo0, la0 = lonlat(np.full(rows, c - 0.5), r)
    lo1, la1 = lonlat(np.full(rows, c + 0.5), r)
    _, _, dx = geod.inv(lo0, la0, lo1, la1)
    lo0, la0 = lonlat(np.full(rows, c), r - 0.5)
    lo1, la1 = lonlat(np.full(rows, c), r + 0.5)
    _, _, dy = geod.inv(lo0, la0, lo1, la1)
    return dx, dy


def test_geographic_spacing_at_60_north_matches_geodesics():
    rows, cols = 50, 40
    t = Affine(3 / 3600, 0, 10.0, 0, -3 / 3600, 60.05)  # 3" cells just north of 60 N
    g = grid_from_transform(t, CRS.from_epsg(4326), (rows, cols))
    dx, dy = _geodesic_spacing(CRS.from_epsg(4326), t, rows, cols)
    np.testing.assert_allclose(g.dx, dx, rtol=1e-6)
    np.testing.assert_allclose(g.dy, dy, rtol=1e-6)
    # about 46 m east-west and 93 m north-south at 60 N, and dx shrinks northward
    assert 46.0 < g.dx[rows // 2] < 47.0 and 92.5 < g.dy[rows // 2] < 93.0
    assert g.dx[0] < g.dx[-1]


def test_lunar_geographic_uses_the_moon_sphere():
    moon = CRS.from_wkt(PCRS.from_proj4("+proj=longlat +R=1737400 +no_defs").to_wkt())
    t = Affine(0.01, 0, 0, 0, -0.01, 10.0)
    g = grid_from_transform(t, moon, (20, 20))
    expected_dy = 1737400 * math.radians(0.01)
    assert g.dy[10] == pytest.approx(expected_dy, rel=1e-12)
    assert g.dx[10] == pytest.approx(expected_dy * math.cos(math.radians(10.0 - 0.105)), rel=1e-9)


def test_web_mercator_ground_spacing_at_60_north():
    """Web Mercator (spherical formulas, WGS84 ground): a 100 m cell at 60 N spans
    100 * cos(60) / sqrt(1 - e2 sin2(60)) metres east-west on the ellipsoid -- not the 50 m that
    the sphere's scale factor alone gives."""
    a, e2 = 6378137.0, 0.00669437999014
    y60 = a * math.log(math.tan(math.pi / 4 + math.radians(60) / 2))
    t = Affine(100, 0, 1_000_000, 0, -100, y60 + 50)
    g = grid_from_transform(t, CRS.from_epsg(3857), (1, 10))
    w = math.sqrt(1 - e2 * math.sin(math.radians(60)) ** 2)
    assert g.dx[0] == pytest.approx(50.0 / w, rel=1e-6)
    assert g.dy[0] == pytest.approx(50.0 * (1 - e2) / w ** 3, rel=1e-5)
    assert "geodesic" in g.method


def test_conformal_projection_agrees_with_scale_factors():
    """For UTM the geodesic cell length equals pixel size / Proj.get_factors' scale."""
    from pyproj import Proj, Transformer

    crs = CRS.from_epsg(32611)
    t = Affine(30, 0, 250_000, 0, -30, 3_800_000)  # far from the central meridian: k ~ 1.0004
    g = grid_from_transform(t, crs, (3, 4))
    x, y = t.c + t.a * 2.0, t.f + t.e * 1.5
    lon, lat = Transformer.from_crs(32611, 4326, always_xy=True).transform(x, y)
    k = Proj(PCRS.from_epsg(32611)).get_factors(lon, lat).parallel_scale
    assert abs(k - 1) > 2e-4
    assert g.dx[1] == pytest.approx(30 / k, rel=1e-7)
    assert g.dy[1] == pytest.approx(30 / k, rel=1e-7)


def test_us_survey_feet_projection():
    # EPSG:2229 (California zone 5, US survey feet): 10 ft cells are 3.048 m
    t = Affine(10, 0, 6_500_000, 0, -10, 1_900_000)
    g = grid_from_transform(t, CRS.from_epsg(2229), (4, 4))
    assert g.dx[0] == pytest.approx(3.048006, rel=2e-4)  # within the conformal scale factor


@pytest.mark.parametrize("crs", [CRS.from_epsg(32611), CRS.from_epsg(3857)])
def test_projected_spacing_matches_geodesics(crs):
    t = Affine(30, 0, 400_000, 0, -30, 3_800_000) if crs.to_epsg() == 32611 else \
        Affine(30, 0, 1_000_000, 0, -30, 6_000_000)
    g = grid_from_transform(t, crs, (20, 20))
    dx, dy = _geodesic_spacing(crs, t, 20, 20)
    np.testing.assert_allclose(g.dx, dx, rtol=1e-6)
    np.testing.assert_allclose(g.dy, dy, rtol=1e-6)


def test_rotated_transform_refused():
    t = Affine(29.5, 5.2, 0, 5.2, -29.5, 0)  # rotated by 10 degrees
    with pytest.raises(HillshadeError, match="rotated"):
        grid_from_transform(t, CRS.from_epsg(32611), (10, 10))


def test_orientation_signs():
    g = grid_from_transform(Affine(30, 0, 0, 0, 30, 0), CRS.from_epsg(32611), (5, 5))
    assert g.row_sign == 1 and g.col_sign == 1  # south-up
    g = grid_from_transform(Affine(-30, 0, 0, 0, -30, 0), CRS.from_epsg(32611), (5, 5))
    assert g.row_sign == -1 and g.col_sign == -1
