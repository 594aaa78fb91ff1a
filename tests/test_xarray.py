"""hillshade_rt.xarray: the ``da.hrt`` accessor against the command line's GeoTIFFs read back
with rioxarray, Dask-backed inputs (chunks smaller than the sun's halo) against in-memory ones,
coordinates and CRS kept, x/y-only inputs, and the errors."""

from __future__ import annotations

import math

import numpy as np
import pytest
import rioxarray           # the `xarray` extra, in `test`
import xarray as xr

import hillshade_rt.xarray as hx
from hillshade_rt import HillshadeError
from hillshade_rt.engine.arrays import shadow_mask
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")      # UTM 15N, 1 m, 31 m of relief
EVEREST = data_path("everest_srtm3_voids_crop200.tif")    # EPSG:4326, voids (-32768)


def cli(*args):
    from click.testing import CliRunner

    from hillshade_rt.cli import cli as main
    r = CliRunner().invoke(main, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return rioxarray.open_rasterio(args[2])


def same_place(out, ref):
    """The same cells, coordinates, CRS and transform as the GeoTIFF ``ref``."""
    assert out.dims[-2:] == ("y", "x")
    np.testing.assert_array_equal(out.x.values, ref.x.values)
    np.testing.assert_array_equal(out.y.values, ref.y.values)
    assert out.rio.crs == ref.rio.crs
    assert out.rio.transform() == ref.rio.transform()


@pytest.mark.parametrize("dem, azimuth, elevation", [
    (LIDAR, 163.0, 8.0), (LIDAR, 203.7, 12.0), (EVEREST, 290.0, 25.0), (EVEREST, 203.7, 12.0)])
def test_shadow_equals_the_command_line(tmp_path, dem, azimuth, elevation):
    ref = cli("shadow", dem, tmp_path / "cli.tif", "--azimuth", azimuth, "--elevation", elevation)
    da = rioxarray.open_rasterio(dem)
    out = da.hrt.shadow(azimuth=azimuth, elevation=elevation)
    same_place(out, ref)
    assert out.dtype == np.uint8 and out.rio.nodata == 255
    np.testing.assert_array_equal(out.values, ref.values[0])
    assert 0.02 < float((out.values == 1).mean()) < 0.98     # shadows and light both
    assert out.attrs["sun_azimuth"] == pytest.approx(azimuth)
    assert out.attrs["sun_elevation"] == pytest.approx(elevation)
    assert out.attrs["product"] == "shadow" and out.attrs["algorithm"] == "auto"
    assert out.attrs["values"] == ref.attrs["VALUES"]
    if dem == EVEREST:        # the voids (the file's nodata) are nodata
        assert ((out.values == 255) == (da.values[0] == -32768)).all()
        assert (out.values == 255).sum() > 1000


TIMES = ["2026-06-21T03:00:00+00:00", "2026-06-21T09:30:00+00:00",
         "2026-06-21T18:00:00+00:00"]      # Everest: morning, afternoon, night


@pytest.mark.slow
def test_time_series_is_a_time_dimension_equal_to_the_command_line(tmp_path):
    args = [a for t in TIMES for a in ("--time", t)]
    ref = cli("shadow", EVEREST, tmp_path / "cli.tif", *args)
    out = rioxarray.open_rasterio(EVEREST).hrt.shadow(time=TIMES)
    assert out.dims == ("time", "y", "x") and out.sizes["time"] == 3
    same_place(out, ref)
    np.testing.assert_array_equal(out.values, ref.values)
    assert list(out.time.values) == [np.datetime64(t[:19], "ns") for t in TIMES]
    night = out.sun_elevation.values <= 0
    assert night.tolist() == [False, False, True]
    assert (out.values[2] != 0).all()            # night: no cell lit
    assert out.attrs["sun_site"].endswith("(the DEM's centre)")
    # xarray's times (naive datetime64: UTC) and aware datetimes: the same suns
    import datetime as dt
    utc = out.time.values
    again = rioxarray.open_rasterio(EVEREST).hrt.shadow(time=utc)
    np.testing.assert_array_equal(again.values, out.values)
    aware = [dt.datetime.fromisoformat(t) for t in TIMES[:2]]
    np.testing.assert_array_equal(
        rioxarray.open_rasterio(EVEREST).hrt.shadow(time=aware).values, out.values[:2])
    # one time: no time dimension, the time as a scalar coordinate and in the attributes
    one = rioxarray.open_rasterio(EVEREST).hrt.shadow(time=TIMES[1])
    assert one.dims == ("y", "x")
    np.testing.assert_array_equal(one.values, out.values[1])
    assert one.attrs["time"].startswith("2026-06-21T09:30")
    assert one.attrs["sun_azimuth"] == pytest.approx(float(out.sun_azimuth[1]))


@pytest.mark.slow
def test_horizon_skyview_and_sun_hours_equal_the_command_line(tmp_path):
    da = rioxarray.open_rasterio(EVEREST)
    void = da.values[0] == -32768
    ref = cli("horizon", EVEREST, tmp_path / "h.tif", "--azimuth", 203.7)
    out = da.hrt.horizon(203.7)
    same_place(out, ref)
    np.testing.assert_array_equal(np.where(void, -9999.0, out.values), ref.values[0])
    assert np.isnan(out.values[void]).all() and out.attrs["azimuth"] == pytest.approx(203.7)
    two = da.hrt.horizon([203.7, 20.0])
    assert two.dims == ("azimuth", "y", "x")
    np.testing.assert_array_equal(two.values[0], out.values)

    ref = cli("skyview", EVEREST, tmp_path / "s.tif", "--directions", 8)
    out = da.hrt.skyview(directions=8)
    same_place(out, ref)
    np.testing.assert_allclose(np.where(void, -9999.0, out.values), ref.values[0], rtol=0,
                               atol=0)
    assert 0.3 < float(np.nanmean(out.values)) < 1.0

    ref = cli("sun-hours", EVEREST, tmp_path / "h.tif", "--date", "2026-06-21", "--step", "2h",
              "--overwrite")
    out = da.hrt.sun_hours(date="2026-06-21", step="2h")
    same_place(out, ref)
    np.testing.assert_array_equal(np.where(void, -9999.0, out.values), ref.values[0])
    assert float(np.nanmax(out.values)) > 8.0 and out.attrs["units"] == "hours of direct sun"


@pytest.mark.slow
def test_dask_input_is_lazy_and_equals_in_memory_with_chunks_smaller_than_the_halo():
    import dask

    da = rioxarray.open_rasterio(EVEREST)
    dk = rioxarray.open_rasterio(EVEREST, chunks={"band": 1, "y": 32, "x": 40})
    lo, hi = float(da.where(da != -32768).min()), float(da.max())
    # the halo toward a sun at 12 degrees: more cells than a chunk (~ 90 m cells)
    assert (hi - lo) / math.tan(math.radians(12.0)) / 90.0 > 4 * 40
    calls = []
    real = hx._light_piece

    def counting(job, piece, z):
        calls.append((piece.region, piece.window))
        return real(job, piece, z)
    hx._light_piece = counting
    try:
        lazy = dk.hrt.shadow(azimuth=203.7, elevation=12.0)
        assert isinstance(lazy.data, dask.array.Array) and not calls    # nothing lit yet
        assert lazy.chunks == ((32,) * 6 + (8,), (40,) * 5)             # the input's chunks
        got = lazy.compute()
    finally:
        hx._light_piece = real
    mem = da.hrt.shadow(azimuth=203.7, elevation=12.0)
    np.testing.assert_array_equal(got.values, mem.values)
    same_place(got, mem)
    # windows: the region and the halo on the sun's side (south-south-west: higher rows,
    # lower columns), larger than a chunk
    assert len(calls) > 10
    assert any((w[1] - w[0]) > 2 * (r[1] - r[0]) for r, w in calls)
    assert all(w[0] >= r[0] - 3 and w[3] <= r[3] + 3 for r, w in calls)

    series = dk.hrt.shadow(time=TIMES)
    assert isinstance(series.data, dask.array.Array)
    np.testing.assert_array_equal(series.values, da.hrt.shadow(time=TIMES).values)
    hours = dk.hrt.sun_hours(date="2026-06-21", step="2h")
    assert isinstance(hours.data, dask.array.Array)
    np.testing.assert_array_equal(hours.values, da.hrt.sun_hours(date="2026-06-21",
                                                                  step="2h").values)
    # horizons: windows toward each azimuth, to the edge or within max_distance
    for kw in ({}, {"max_distance": 3000.0}):
        h = dk.hrt.horizon([100.0, 203.7], **kw)
        assert isinstance(h.data, dask.array.Array) and h.dims == ("azimuth", "y", "x")
        np.testing.assert_array_equal(h.values, da.hrt.horizon([100.0, 203.7], **kw).values)
    for kw in ({"max_distance": 2500.0}, {"max_distance": 2000.0, "openness": "negative"}):
        v = dk.hrt.skyview(directions=8, **kw)
        assert isinstance(v.data, dask.array.Array)
        np.testing.assert_array_equal(v.values, da.hrt.skyview(directions=8, **kw).values)


def test_dask_task_reads_only_its_window():
    """Computing one output chunk reads the input chunks of its window (the region and its
    halo toward the sun), not the whole input."""
    import dask.array as dka

    da = rioxarray.open_rasterio(EVEREST).isel(band=0, drop=True)
    reads = []

    def record(block, block_info=None):
        reads.append(tuple(block_info[0]["chunk-location"]))
        return block
    counted = dka.from_array(da.values, chunks=(32, 40)).map_blocks(record, dtype=da.dtype)
    dk = da.copy(data=counted)
    # a high sun: the halo toward the south-south-west is ~30 rows, ~15 columns here
    lazy = dk.hrt.shadow(azimuth=203.7, elevation=60.0)
    assert len(set(reads)) == 35          # the block height ranges: one pass over the input
    reads.clear()
    top_right = lazy[:32, 160:].compute()
    np.testing.assert_array_equal(
        top_right.values, da.hrt.shadow(azimuth=203.7, elevation=60.0).values[:32, 160:])
    assert set(reads) <= {(r, c) for r in (0, 1, 2) for c in (3, 4)}
    assert (1, 4) in set(reads) and (0, 4) in set(reads)


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


def test_errors_are_one_clear_message():
    da = rioxarray.open_rasterio(LIDAR)
    three = xr.concat([da, da], dim="band").assign_coords(band=[1, 2])
    with pytest.raises(HillshadeError, match=r"^the DataArray has 2 bands .*da\.sel\(band=1\)"):
        three.hrt.shadow(azimuth=163, elevation=8)
    with pytest.raises(HillshadeError, match="2-D"):
        xr.DataArray(np.zeros((2, 3, 4)), dims=("t", "y", "x")).hrt.horizon(90, spacing=1.0)
    bent = da.isel(band=0).assign_coords(x=da.x.values + 0.3 * (np.arange(da.sizes['x']) % 2))
    with pytest.raises(HillshadeError, match="not regularly spaced"):
        bent.hrt.shadow(azimuth=163, elevation=8)
    with pytest.raises(HillshadeError, match="one way"):
        da.hrt.shadow(azimuth=163, elevation=8, time="2026-06-21T12:00Z")
    with pytest.raises(HillshadeError, match="^no sun given"):
        da.hrt.shadow()
    with pytest.raises(HillshadeError, match="^azimuth and elevation go together"):
        da.hrt.shadow(azimuth=163)
    with pytest.raises(HillshadeError, match="no UTC offset"):
        da.hrt.shadow(time="2026-06-21T12:00")
    with pytest.raises(HillshadeError, match="algorithm"):
        da.hrt.shadow(azimuth=163, elevation=8, algorithm="nope")


def test_the_command_line_and_the_api_do_not_import_xarray():
    """xarray and rioxarray are imported by ``hillshade_rt.xarray`` only: the command line's
    start-up does not pay for them."""
    import subprocess
    import sys
    code = ("import sys, hillshade_rt, hillshade_rt.cli, hillshade_rt.api, hillshade_rt.engine.arrays\n"
            "print(sorted(m for m in ('xarray', 'rioxarray') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
    code = ("import sys, hillshade_rt.xarray, xarray\n"
            "print(hasattr(xarray.DataArray([[1.0]], dims=('y', 'x')), 'hrt'))")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "True"


@pytest.mark.slow
def test_the_docs_example_runs(tmp_path, monkeypatch):
    """docs/usage.md, "In xarray": its example, run from the repository's root as it says
    (the GeoTIFF it writes goes to a temporary folder here)."""
    import os
    import re

    from hillshade_rt.testing import repo_root
    text = open(os.path.join(repo_root(), "docs", "usage.md"), encoding="utf-8").read()
    section = text.split("## In xarray", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    code = code.replace('"examples/', '"' + os.path.join(repo_root(), "examples", ""))
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "usage.md", "exec"), scope)
    written = rioxarray.open_rasterio(tmp_path / "sun_hours.tif")
    assert written.rio.crs == scope["dem"].rio.crs
    assert float(written.max()) > 10.0 and scope["day"].sizes["time"] == 2
