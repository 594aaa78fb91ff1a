"""Runs on this machine (run.local), through the public API: the DEM in memory and in windows
give the independent reference's mask at non-special azimuths, every product is the same either
way, and the report's statistics of windows equal those of the whole raster."""

import numpy as np
import pytest
from affine import Affine

import hillshade_rt as hr
from hillshade_rt.testing import fractal_terrain, read_band, reference_mask, write_geotiff

TR = Affine(10.0, 0, 5000.0, 0, -10.0, 9000.0)


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    z = fractal_terrain(150, 171, seed=21, relief=300.0)
    z[70:73, 60:90] = np.nan
    return z, write_geotiff(tmp_path_factory.mktemp("local") / "dem.tif", z, TR)


@pytest.mark.slow      # the plain-Python reference: about 5 s a sun
@pytest.mark.parametrize("az", [163.0, 203.7, 290.0])
def test_memory_and_windows_are_the_reference(tmp_path, dem, az):
    z, path = dem
    sun = dict(azimuth=az, elevation=11.0, curvature=False)
    a = hr.shade(path, str(tmp_path / "a.tif"), **sun)
    b = hr.shade(path, str(tmp_path / "b.tif"), window_size=(64, 70), **sun)
    assert a["processing"]["mode"] == "in memory"
    assert b["processing"]["mode"] == "tiled" and b["processing"]["windows"] >= 6
    ref = reference_mask(z, 10.0, 10.0, az, 11.0)
    np.testing.assert_array_equal(read_band(tmp_path / "a.tif"), ref)
    np.testing.assert_array_equal(read_band(tmp_path / "b.tif"), ref)
    frac = (ref == 1).sum() / (ref != 255).sum()
    for rep in (a, b):
        assert rep["sun"]["shadow_fraction"] == pytest.approx(frac)


@pytest.mark.parametrize("product,soft", [("classes", False), ("hillshade", False),
                                          ("shadow", True)])
def test_every_product_is_the_same_in_windows(tmp_path, dem, product, soft):
    _, path = dem
    sun = dict(azimuth=290.0, elevation=7.0, curvature=False, product=product, soft=soft)
    a = hr.shade(path, str(tmp_path / "a.tif"), **sun)
    b = hr.shade(path, str(tmp_path / "b.tif"), window_size=(64, 64), **sun)
    np.testing.assert_array_equal(read_band(tmp_path / "a.tif"), read_band(tmp_path / "b.tif"))
    sa, sb = a["sun"], b["sun"]
    for k in ("shadow_fraction", "shadow_cells", "lit_cells", "nodata_cells"):
        if k in sa or k in sb:
            if isinstance(sa.get(k), float):
                assert sb.get(k) == pytest.approx(sa[k]), k
            else:
                assert sb.get(k) == sa.get(k), k
