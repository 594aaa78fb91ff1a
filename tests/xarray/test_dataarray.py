"""hillshade_rt.xarray.dataarray: a DataArray in and out: x/y-only inputs with crs=,
attrs["crs"] or spacing=, _FillValue as nodata, rows running south to north, slices keeping
their origin, and the DataArrays that are no grid of heights."""

from __future__ import annotations

import numpy as np
import pytest
import rioxarray           # the `xarray` extra, in `test`
import xarray as xr

import hillshade_rt.xarray as hx
from hillshade_rt import HillshadeError
from hillshade_rt.engine.arrays import shadow_mask
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")      # UTM 15N, 1 m, 31 m of relief


def test_xy_only_input_and_its_crs():
    da = rioxarray.open_rasterio(LIDAR).isel(band=0, drop=True)
    z = da.values.astype(np.float32)
    plain = xr.DataArray(z, dims=("y", "x"), coords={"y": da.y.values, "x": da.x.values})
    with pytest.raises(HillshadeError, match="no CRS.*spacing="):
        plain.hrt.shadow(azimuth=163, elevation=8)
    # a sun from a time needs the place: the message names this function's keywords
    with pytest.raises(HillshadeError, match="give lat= and lon= .* for a sun from time="):
        plain.hrt.shadow(time="2026-06-21T12:00Z", spacing=1.0)
    located = plain.hrt.shadow(time="2026-06-21T12:00Z", spacing=1.0, lat=45.0, lon=-93.0)
    assert located.attrs["sun_site"] == "45.000000, -93.000000 (lat/lon)"
    # projected metres from spacing=: the array API's mask
    out = plain.hrt.shadow(azimuth=163, elevation=8, spacing=1.0)
    np.testing.assert_array_equal(out.values, shadow_mask(z, 163, 8, 1.0))
    assert out.rio.crs is None
    np.testing.assert_array_equal(out.x.values, da.x.values)
    # the CRS from crs= or attrs["crs"]: the georeferenced answer, and the CRS written
    ref = da.hrt.shadow(azimuth=163, elevation=8)
    for given in (plain.hrt.shadow(azimuth=163, elevation=8, crs="EPSG:26915"),
                  plain.assign_attrs(crs="EPSG:26915").hrt.shadow(azimuth=163, elevation=8)):
        np.testing.assert_array_equal(given.values, ref.values)
        assert given.rio.crs == ref.rio.crs and given.rio.transform() == ref.rio.transform()
    # nodata from _FillValue: those cells are voids
    holes = plain.copy(data=np.where(z < 385, np.float32(-1), z)).assign_attrs(_FillValue=-1.0)
    got = holes.hrt.shadow(azimuth=163, elevation=8, spacing=1.0)
    assert ((got.values == 255) == (z < 385)).all() and (z < 385).any()
    # module functions and the accessor are the same
    np.testing.assert_array_equal(hx.shadow(plain, 163, 8, spacing=1.0).values, out.values)


def test_rows_running_south_to_north_and_a_slice():
    """A DataArray flipped to rows running south to north (y ascending; rioxarray's stored
    transform still says north-up) is the same terrain: the flipped mask; a slice keeps its own
    origin."""
    da = rioxarray.open_rasterio(LIDAR).isel(band=0)
    ref = da.hrt.shadow(azimuth=163, elevation=8)
    up = da.isel(y=slice(None, None, -1))
    got = up.hrt.shadow(azimuth=163, elevation=8)
    np.testing.assert_array_equal(got.values[::-1], ref.values)
    np.testing.assert_array_equal(got.y.values, up.y.values)
    assert got.rio.transform().e == 1.0 and got.rio.transform(recalc=True) == got.rio.transform()
    lazy = up.chunk({"y": 64, "x": 64}).hrt.shadow(azimuth=163, elevation=8)
    np.testing.assert_array_equal(lazy.values, got.values)
    sub = da.isel(y=slice(100, 300), x=slice(50, 250))
    part = sub.hrt.shadow(azimuth=163, elevation=8)
    assert part.rio.transform() == sub.rio.transform() != da.rio.transform()


def test_a_dataarray_that_is_no_grid_of_heights_is_one_clear_message():
    """More than one band, not 2-D, coordinates not regularly spaced: one line each, from
    ``dataarray.as_input``, before anything is computed."""
    da = rioxarray.open_rasterio(LIDAR)
    three = xr.concat([da, da], dim="band").assign_coords(band=[1, 2])
    with pytest.raises(HillshadeError, match=r"^the DataArray has 2 bands .*da\.sel\(band=1\)"):
        three.hrt.shadow(azimuth=163, elevation=8)
    with pytest.raises(HillshadeError, match="2-D"):
        xr.DataArray(np.zeros((2, 3, 4)), dims=("t", "y", "x")).hrt.horizon(90, spacing=1.0)
    bent = da.isel(band=0).assign_coords(x=da.x.values + 0.3 * (np.arange(da.sizes['x']) % 2))
    with pytest.raises(HillshadeError, match="not regularly spaced"):
        bent.hrt.shadow(azimuth=163, elevation=8)


def test_as_input_and_wrap_keep_the_place_and_make_voids_nan():
    """``as_input``: float32 heights (NaN where the file's nodata is; a Dask array stays one),
    the grid's metres per cell; ``wrap``: the same coordinates, CRS, transform, nodata."""
    import dask.array as dka

    from hillshade_rt.xarray.dataarray import as_input, wrap
    everest = data_path("everest_srtm3_voids_crop200.tif")
    da = rioxarray.open_rasterio(everest).isel(band=0, drop=True)
    inp = as_input(da)
    void = da.values == -32768
    assert inp.heights.dtype == np.float32 and void.any()
    assert (np.isnan(inp.heights) == void).all() and not inp.lazy
    dx, dy = inp.grid.centre_spacing()
    assert 70.0 < dx < 95.0 and 85.0 < dy < 95.0       # 3 arc-seconds at 28 degrees north
    lazy = as_input(da.chunk({"y": 64, "x": 48}))
    assert lazy.lazy and isinstance(lazy.heights, dka.Array)
    np.testing.assert_array_equal(np.asarray(lazy.heights), inp.heights)
    out = wrap(inp.heights, inp, {"product": "heights", "skipped": None}, np.nan, "z")
    assert out.rio.crs == da.rio.crs and out.rio.transform() == da.rio.transform()
    np.testing.assert_array_equal(out.x.values, da.x.values)
    assert out.attrs["product"] == "heights" and "skipped" not in out.attrs
    assert np.isnan(out.rio.nodata)
