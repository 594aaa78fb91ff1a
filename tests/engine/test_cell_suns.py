"""bodysun: bodies of --body, the sun's position from its subsolar point, each cell's frame and
its own sun, checked against spherical trigonometry and pyproj's geodesics."""

import math

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.engine import cell_suns
from hillshade_rt.model.earth import Body, dem_body
from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.testing import MOON_GEOGRAPHIC, MOON_NORTH_POLAR, memory_dem

FAR = 1e16   # a sun so far that parallax is below 1e-8 degrees on the Moon


def test_body_from_option():
    moon = cell_suns.body_from_option("moon")
    assert (moon.a, moon.b, moon.earth) == (1737400.0, 1737400.0, False)
    mars = cell_suns.body_from_option("Mars")
    assert (mars.a, mars.b) == (3396190.0, 3396190.0)
    mola = Body(3396190.0, 3376200.0, 12.0, False, "MOLA")
    m2 = cell_suns.body_from_option("mars", mola)
    assert (m2.a, m2.b, m2.lat) == (3396190.0, 3376200.0, 12.0)
    earth = cell_suns.body_from_option("earth")
    assert earth.earth and earth.b < earth.a
    r = cell_suns.body_from_option("2500000")
    assert (r.a, r.b, r.earth) == (2500000.0, 2500000.0, False)
    assert cell_suns.body_from_option(None, mola) is mola
    for bad in ("venus", "-3", "nan"):
        with pytest.raises(UsageProblem):
            cell_suns.body_from_option(bad)
    assert cell_suns.mean_sun_distance(mars) == 227939200000.0
    assert cell_suns.mean_sun_distance(moon) == cell_suns.AU == cell_suns.mean_sun_distance(earth)
    assert cell_suns.mean_sun_distance(r) == cell_suns.AU


def test_sun_vector():
    moon = cell_suns.body_from_option("moon")
    s = cell_suns.sun_vector(moon, 20.0, -130.0, 2e11)
    phi, lam = math.radians(20.0), math.radians(-130.0)
    want = 2e11 * np.array([math.cos(phi) * math.cos(lam), math.cos(phi) * math.sin(lam),
                            math.sin(phi)])
    np.testing.assert_allclose(s, want, rtol=1e-12)
    # on an ellipsoid: |S| is the distance and the sun is at the subsolar point's zenith
    earth = cell_suns.body_from_option("earth")
    s = cell_suns.sun_vector(earth, 37.0, 12.0)
    assert math.isclose(float(np.linalg.norm(s)), cell_suns.AU, rel_tol=1e-12)
    fr = cell_suns.CellFrames(*(np.array([[v]], np.float32) for v in (
        math.sin(math.radians(37.0)), math.cos(math.radians(37.0)), math.sin(math.radians(12.0)),
        math.cos(math.radians(12.0)), 1.0, 0.0)))
    _, el = cell_suns.cell_suns(fr, earth, s)
    assert el[0, 0] > 90.0 - 1e-4
    with pytest.raises(HillshadeError, match="latitude"):
        cell_suns.sun_vector(moon, 95.0, 0.0)
    with pytest.raises(HillshadeError, match="exceed the body's radius"):
        cell_suns.sun_vector(moon, 10.0, 0.0, 1.0e6)


def _lonlat(dem):
    from pyproj import CRS, Transformer
    rows, cols = dem.shape
    t = dem.transform
    xx, yy = np.meshgrid(t.c + t.a * (np.arange(cols) + 0.5), t.f + t.e * (np.arange(rows) + 0.5))
    pcrs = CRS.from_user_input(dem.crs.to_wkt())
    if pcrs.is_geographic:
        return xx, yy
    lon, lat = Transformer.from_crs(pcrs, pcrs.geodetic_crs, always_xy=True).transform(xx, yy)
    return np.asarray(lon), np.asarray(lat)


@pytest.mark.parametrize("crs, transform", [
    (MOON_GEOGRAPHIC, Affine(0.5, 0, -30.0, 0, -0.5, 30.0)),
    (MOON_NORTH_POLAR, Affine(10000.0, 0, -300000.0, 0, -10000.0, 300000.0))])
def test_cell_suns_on_a_sphere(crs, transform):
    """Far sun on a sphere: elevation = 90 - angular distance to the subsolar point, azimuth =
    the initial great-circle bearing toward it."""
    dem = memory_dem(np.zeros((60, 60), np.float32), transform, crs)
    body = dem_body(dem)
    lat_s, lon_s = 31.0, 57.3
    fr = cell_suns.CellFrames.of_dem(dem)
    assert fr.nbytes == 24 * 60 * 60
    az, el = cell_suns.cell_suns(fr, body, cell_suns.sun_vector(body, lat_s, lon_s, FAR))
    lon, lat = _lonlat(dem)
    p, l = np.radians(lat), np.radians(lon)
    ps, ls = math.radians(lat_s), math.radians(lon_s)
    cosd = np.sin(p) * math.sin(ps) + np.cos(p) * math.cos(ps) * np.cos(l - ls)
    dist = np.degrees(np.arccos(np.clip(cosd, -1, 1)))
    assert np.abs(el - (90.0 - dist)).max() < 0.01
    bearing = np.degrees(np.arctan2(np.sin(ls - l) * math.cos(ps),
                                    np.cos(p) * math.sin(ps) - np.sin(p) * math.cos(ps)
                                    * np.cos(ls - l)))
    da = (az - bearing + 180.0) % 360.0 - 180.0
    assert np.abs(da[np.abs(lat) < 89.9]).max() < 0.01


@pytest.mark.parametrize("crs, transform, geod", [
    (MOON_NORTH_POLAR, Affine(10000.0, 0, -300000.0, 0, -10000.0, 300000.0),
     dict(a=1737400.0, b=1737400.0)),
    ("EPSG:32633", Affine(3000.0, 0, 200000.0, 0, -3000.0, 7000000.0), dict(ellps="WGS84")),
    ("EPSG:32633", Affine(-3000.0, 0, 790000.0, 0, 3000.0, 5000000.0), dict(ellps="WGS84"))])
def test_theta_is_the_grid_azimuth_of_true_north(crs, transform, geod):
    """A geodesic step in true azimuth A from a cell lands, projected, in grid azimuth
    A + theta (polar stereographic around the Moon's pole, UTM far from its central meridian,
    also with columns running west and rows north)."""
    from pyproj import CRS, Geod, Transformer
    dem = memory_dem(np.zeros((40, 40), np.float32), transform, crs)
    fr = cell_suns.CellFrames.of_dem(dem)
    theta = np.degrees(np.arctan2(fr.sth.astype(float), fr.cth.astype(float)))
    assert np.abs(theta).max() > 1.0          # the test means something
    lon, lat = _lonlat(dem)
    pcrs = CRS.from_user_input(dem.crs.to_wkt())
    to_crs = Transformer.from_crs(pcrs.geodetic_crs, pcrs, always_xy=True)
    x0, y0 = to_crs.transform(lon, lat)
    for a in (163.0, 203.7, 290.0, 0.0):
        lon1, lat1, _ = Geod(**geod).fwd(lon, lat, np.full(lon.shape, a), np.full(lon.shape, 1.0))
        x1, y1 = to_crs.transform(lon1, lat1)
        grid_az = np.degrees(np.arctan2(np.asarray(x1) - x0, np.asarray(y1) - y0))
        d = (cell_suns.grid_azimuth(fr, a) - grid_az + 180.0) % 360.0 - 180.0
        assert np.abs(d).max() < 1e-3, a


def test_geographic_theta_is_zero_and_frames_match_lonlat():
    dem = memory_dem(np.zeros((7, 9), np.float32), Affine(0.25, 0, 10.0, 0, -0.25, -40.0),
                     MOON_GEOGRAPHIC)
    fr = cell_suns.CellFrames.of_dem(dem)
    assert (fr.cth == 1).all() and (fr.sth == 0).all()
    lon, lat = _lonlat(dem)
    np.testing.assert_allclose(np.degrees(np.arcsin(fr.slat.astype(float))), lat, atol=1e-4)
    np.testing.assert_allclose(np.degrees(np.arctan2(fr.slon, fr.clon).astype(float)), lon,
                               atol=1e-4)


def test_frames_need_a_crs():
    with pytest.raises(HillshadeError, match="CRS"):
        cell_suns.CellFrames.from_transform(Affine(1, 0, 0, 0, -1, 0), None, (3, 3))
