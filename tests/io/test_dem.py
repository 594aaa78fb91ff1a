"""io/dem.py: a source's values into heights (nodata, NaN and +-inf as NaN, z-factor; the
parallel in-place pass and the general one agree), the survey, the geotransform into a grid."""

import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import dem as demmod
from hillshade_rt.model.geometry import Grid


def _reference(data, nodata, z_factor=1.0):
    """float32 heights of float32 ``data``, written plainly."""
    z = data.astype(np.float64)
    bad = ~np.isfinite(z)
    if nodata is not None and not math.isnan(nodata):
        bad |= data == np.float32(nodata)       # float32 data: nodata compared as float32
    z[bad] = np.nan
    return (z * z_factor).astype(np.float32)


@pytest.mark.parametrize("shape", [(7, 9), (256, 300)])   # general pass; in place, parallel
def test_heights_into_float32_in_place(shape):
    rng = np.random.default_rng(1)
    data = (rng.random(shape) * 1000 - 100).astype(np.float32)
    data[1, 2] = -9999.0
    data[3, 4] = np.inf
    data[5, 0] = -np.inf
    data[6, 8] = np.nan
    want = _reference(data, -9999.0)
    survey = demmod.heights_into(data, -9999.0, data)
    np.testing.assert_array_equal(data, want)
    if shape[0] * shape[1] >= 1 << 16:
        valid = np.isfinite(want)
        assert survey == (int(valid.sum()), float(want[valid].min()), float(want[valid].max()))
    else:
        assert survey is None


def test_heights_into_other_types_and_z_factor():
    data = np.array([[0, 65535, 12], [300, 7, 65535]], np.uint16)
    out = np.empty(data.shape, np.float32)
    demmod.heights_into(data, 65535.0, out, z_factor=0.5)
    np.testing.assert_array_equal(out, [[0, np.nan, 6], [150, 3.5, np.nan]])
    # a nodata the type cannot hold matches nothing (no wrap-around to 65535)
    demmod.heights_into(data, -1.0, out)
    np.testing.assert_array_equal(out, data.astype(np.float32))
    # float32's lowest value given as a float64 still matches its float32 cells
    f = np.array([[np.float32(-3.4028235e38), 1.0]], np.float32)
    z, _ = demmod.to_heights(f.copy(), -3.4028235e38)
    assert math.isnan(z[0, 0]) and z[0, 1] == 1.0
    i = np.array([[-32768, 5]], np.int16)
    z, survey = demmod.to_heights(i, -32768.0)
    assert z.dtype == np.float32 and math.isnan(z[0, 0]) and z[0, 1] == 5.0 and survey is None


def test_dem_survey_and_ranges():
    z = np.array([[1.0, np.nan], [-2.5, 9.0]], np.float32)
    d = demmod.Dem(z, Grid.uniform(2, 2, 1.0), "x.tif", "gdal")
    assert d.survey() == (3, -2.5, 9.0) and d.valid_count() == 3
    assert d.height_range() == (-2.5, 9.0) and d.shape == (2, 2)
    empty = demmod.Dem(np.full((2, 2), np.nan, np.float32), Grid.uniform(2, 2, 1.0), "e", "raw")
    assert empty.valid_count() == 0 and empty.height_range() == (math.inf, -math.inf)
    assert empty.crs_string() is None and empty.crs_name() is None


def test_check_transform_refuses_rotation_and_non_finite():
    assert demmod.check_transform("a.tif", Affine(10, 0, 0, 0, -10, 0)) == (1, -1)
    assert demmod.check_transform("a.tif", Affine(-10, 0, 0, 0, 10, 0)) == (-1, 1)
    with pytest.raises(HillshadeError, match="^a.tif: "):
        demmod.check_transform("a.tif", Affine(10, 1, 0, 0, -10, 0))
    with pytest.raises(HillshadeError, match="^b.tif: geotransform has non-finite terms"):
        demmod.check_transform("b.tif", Affine(math.nan, 0, 0, 0, -10, 0))


def test_grid_of():
    utm = CRS.from_epsg(32632)
    g = demmod.grid_of("a.tif", Affine(10, 0, 500000, 0, -20, 5200000), utm, (4, 5))
    assert (g.rows, g.cols, g.col_sign, g.row_sign) == (4, 5, 1, -1)
    # ground metres: the grid's spacing over UTM's scale factor on its central meridian, 0.9996
    np.testing.assert_allclose(g.dx, 10.0 / 0.9996, rtol=1e-5)
    np.testing.assert_allclose(g.dy, 20.0 / 0.9996, rtol=1e-5)
    # --pixel-size keeps the orientation of the geotransform
    g = demmod.grid_of("a.tif", Affine(-1, 0, 0, 0, 1, 0), None, (3, 3), pixel_size=(2.0, 3.0))
    assert (g.col_sign, g.row_sign, g.method) == (-1, 1, "--pixel-size")
    np.testing.assert_allclose(g.dy, 3.0)
    with pytest.raises(HillshadeError, match="^r.raw: has no georeferencing; give the ground "
                                             "spacing with --pixel-size"):
        demmod.grid_of("r.raw", None, None, (3, 3))


def test_to_heights_float64_beyond_float32_is_void_without_a_warning():
    """A float64 value beyond float32's range (a damaged file) becomes a void, silently: numpy's
    overflow warning would be a second line on stderr."""
    import warnings
    data = np.array([[1.5, 1e300], [-1e300, 2.0]], np.float64)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        z, _ = demmod.to_heights(data, None)
    assert z.dtype == np.float32
    assert z[0, 0] == np.float32(1.5) and z[1, 1] == np.float32(2.0)
    assert np.isnan(z[0, 1]) and np.isnan(z[1, 0])
