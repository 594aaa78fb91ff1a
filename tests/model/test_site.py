"""Where a DEM's sun is computed: the observer's height at the centre (or near it, around a
void), the centre's longitude and latitude, the meridian convergence that turns a true azimuth
to the raster's grid north (pyproj's, independently), --lat/--lon, and DEMs on other bodies."""

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.site import centre_height_of, dem_site
from hillshade_rt.testing import fractal_terrain, memory_dem


def test_the_centre_cell_or_the_median_around_a_void():
    z = np.arange(49, dtype=np.float32).reshape(7, 7)
    assert centre_height_of(z) == (24.0, "the DEM's centre cell")
    z[3, 3] = np.nan
    h, how = centre_height_of(z)
    win = z[1:6, 1:6]
    assert h == pytest.approx(float(np.nanmedian(win))) and "within 2" in how
    z = np.full((301, 301), np.nan, np.float32)
    z[0, 0] = 5.0                      # nothing valid near the centre: the whole DEM's median
    assert centre_height_of(z) == (5.0, "median of the DEM (its centre is a void)")


def test_utm_centre_and_meridian_convergence_match_pyproj():
    """A UTM 32N DEM west of the zone's central meridian (9 E): its centre's place and the grid
    azimuth of true north there equal pyproj's, at the centre and at a corner."""
    from pyproj import Proj, Transformer
    rows, cols = 60, 80
    tr = Affine(30.0, 0, 419150.0, 0, -30.0, 5160600.0)
    dem = memory_dem(fractal_terrain(rows, cols, 5, relief=300.0) + 500.0, tr, "EPSG:32632")
    site = dem_site(dem)
    x, y = tr.c + tr.a * (cols / 2.0), tr.f + tr.e * (rows / 2.0)     # the centre cell's middle
    lon, lat = Transformer.from_crs(32632, 4326, always_xy=True).transform(x, y)
    assert (site.lon, site.lat) == pytest.approx((lon, lat), abs=1e-9)
    assert site.source == "the DEM's centre"
    for r, c in (((rows - 1) / 2.0, (cols - 1) / 2.0), (0.0, cols - 1.0)):
        lo, la = site.to_lonlat(np.array([r]), np.array([c]))
        gamma = Proj(32632).get_factors(float(lo[0]), float(la[0])).meridian_convergence
        assert gamma < -0.5                    # west of 9 E: true north leans east of grid north
        assert site.convergence(np.array([r]), np.array([c]))[0] == pytest.approx(-gamma, abs=2e-3)


def test_lat_lon_given_keeps_the_grid_north_of_the_dem():
    tr = Affine(30.0, 0, 419150.0, 0, -30.0, 5160600.0)
    dem = memory_dem(np.full((20, 20), 700.0, np.float32), tr, "EPSG:32632")
    site = dem_site(dem, 46.0, 368.5)              # longitudes wrap into [-180, 180)
    assert (site.lat, site.lon, site.height) == (46.0, pytest.approx(8.5), 700.0)
    assert site.to_lonlat is None and site.north_offset == pytest.approx(
        dem_site(dem).convergence(np.array([9.5]), np.array([9.5]))[0])
    with pytest.raises(HillshadeError, match="go together"):
        dem_site(dem, 46.0, None)
    with pytest.raises(HillshadeError, match=r"within \[-90, 90\]"):
        dem_site(dem, 95.0, 8.0)


def test_a_dem_on_another_body_is_refused_with_the_advice():
    moon = "+proj=longlat +a=1737400 +b=1737400 +no_defs"
    dem = memory_dem(np.zeros((10, 10), np.float32), Affine(0.01, 0, 20.0, 0, -0.01, 10.0), moon)
    with pytest.raises(HillshadeError, match="not the Earth; the solar position from --time is for the Earth"):
        dem_site(dem)
    with pytest.raises(HillshadeError, match="not the Earth; use --subsolar"):
        dem_site(dem, other_body="use --subsolar")
