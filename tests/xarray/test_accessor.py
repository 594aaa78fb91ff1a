"""hillshade_rt.xarray's accessor: ``da.hrt``'s products against the command line's GeoTIFFs
read back with rioxarray (coordinates, CRS, attributes), a series of times as a dimension, the
sun's errors, the imports the command line is spared, the docs' example."""

from __future__ import annotations

import numpy as np
import pytest
import rioxarray           # the `xarray` extra, in `test`

import hillshade_rt.xarray  # noqa: F401 -- registers da.hrt
from hillshade_rt import HillshadeError
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


def test_sun_and_algorithm_errors_are_one_clear_message():
    da = rioxarray.open_rasterio(LIDAR)
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


# -- irradiance, monthly sun hours, r.horizon's angles, shadow polygons -----------------------

def _small_dem(tmp_path, rows=30, cols=36, relief=250.0, voids=True):
    """A fractal DEM on UTM 11N (30 m cells) with a block of voids (nodata -32768)."""
    from affine import Affine
    from rasterio.crs import CRS

    from hillshade_rt.testing import fractal_terrain, write_geotiff
    z = fractal_terrain(rows, cols, 5, relief=relief)
    if voids:
        z[3:6, 20:24] = -32768.0
    return write_geotiff(tmp_path / "dem.tif", z, Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0),
                         CRS.from_epsg(32611), nodata=-32768.0)


def _run(*args):
    from click.testing import CliRunner

    from hillshade_rt.cli import cli as main
    r = CliRunner().invoke(main, [str(a) for a in args])
    assert r.exit_code == 0, r.output


def _bands(path):
    import rasterio
    with rasterio.open(path) as ds:
        return ds.read(), [ds.tags(b) for b in range(1, ds.count + 1)]


def _as_written(values):
    """An accessor's float32 result as the command line writes it: NaN voids as -9999."""
    return np.where(np.isnan(values), np.float32(-9999.0), values)


@pytest.mark.slow
@pytest.mark.parametrize("extra, kw, units", [
    ([], {}, "Wh m-2"), (["--daily-mean", "--perez"], {"daily_mean": True, "perez": True},
                         "Wh m-2 day-1")])
def test_irradiance_period_and_months_equal_the_command_line(tmp_path, extra, kw, units):
    """Two days across a month's end with --monthly: the Dataset's beam_rad, diff_rad,
    refl_rad, glob_rad are the GeoTIFF's bands 1-4 bit for bit (voids NaN where it has
    -9999), glob_rad_monthly its month bands on a time dimension of month starts with each
    month's hours; the attributes name the period."""
    dem = _small_dem(tmp_path)
    out = tmp_path / "p.tif"
    _run("irradiance", dem, out, "--date", "2026-06-30", "--end-date", "2026-07-01", "--step",
         "2h", "--tz", "America/Los_Angeles", "--skyview-directions", "8", "--monthly",
         "--albedo", "0.3", "-q", *extra)
    v, tags = _bands(out)
    da = rioxarray.open_rasterio(dem)
    ds = da.hrt.irradiance("2026-06-30", end_date="2026-07-01", step="2h",
                           tz="America/Los_Angeles", skyview_directions=8, monthly=True,
                           albedo=0.3, **kw)
    assert list(ds.data_vars) == ["beam_rad", "diff_rad", "refl_rad", "glob_rad",
                                  "glob_rad_monthly"]
    void = da.values[0] == -32768.0
    for j, name in enumerate(["beam_rad", "diff_rad", "refl_rad", "glob_rad"]):
        assert ds[name].dims == ("y", "x") and ds[name].dtype == np.float32
        assert ds[name].attrs["units"] == units
        np.testing.assert_array_equal(_as_written(ds[name].values), v[j])
        assert np.isnan(ds[name].values[void]).all() and void.sum() == 12
    m = ds["glob_rad_monthly"]
    assert m.dims == ("time", "y", "x") and v.shape[0] == 6
    np.testing.assert_array_equal(m["time"].values,
                                  np.array(["2026-06-01", "2026-07-01"], "datetime64[ns]"))
    assert list(m["month"].values) == ["2026-06", "2026-07"]
    np.testing.assert_array_equal(_as_written(m.values), v[4:])
    assert [float(h) for h in m["hours"].values] == [float(t["HOURS"]) for t in tags[4:]]
    hours = m["hours"].values
    if kw.get("daily_mean"):       # per day: the months' hours-weighted mean
        whole = (m.values * hours[:, None, None]).sum(axis=0) / hours.sum()
    else:                           # energy: the months' sum
        whole = m.values.sum(axis=0)
    np.testing.assert_allclose(ds.glob_rad.values, whole, rtol=2e-6)
    assert float(m.min()) > 1000.0
    assert ds.rio.crs == da.rio.crs and ds.glob_rad.rio.transform() == da.rio.transform()
    assert "2026-06-30" in ds.attrs["period"] and ds.attrs["samples"] == 24


@pytest.mark.slow
def test_irradiance_instants_equal_the_command_lines_bands_and_cube(tmp_path):
    """times=[...]: the five quantities on a time dimension (UTC), each the GeoTIFF's band
    of the same instants bit for bit, and the command line's time cube's variable."""
    xr = pytest.importorskip("xarray")
    dem = _small_dem(tmp_path)
    times = ["2026-06-21T07:35-07:00", "2026-06-21T20:10Z"]
    args = ["--skyview-directions", "8", "--linke-turbidity", "3.5", "-q"]
    for t in times:
        args += ["--time", t]
    _run("irradiance", dem, tmp_path / "i.tif", *args)
    _run("irradiance", dem, tmp_path / "i.nc", *args)
    v = _bands(tmp_path / "i.tif")[0].reshape(2, 5, 30, 36)
    ds = rioxarray.open_rasterio(dem).hrt.irradiance(times=times, skyview_directions=8,
                                                    linke_turbidity=3.5)
    np.testing.assert_array_equal(ds["time"].values, np.array(
        ["2026-06-21T14:35", "2026-06-21T20:10"], "datetime64[ns]"))
    assert list(ds["time_local"].values) == ["2026-06-21T07:35-07:00",
                                             "2026-06-21T20:10+00:00"]
    with xr.open_dataset(tmp_path / "i.nc") as cube:
        for j, name in enumerate(["beam_rad", "diff_rad", "refl_rad", "glob_rad",
                                  "incidout"]):
            assert ds[name].dims == ("time", "y", "x")
            np.testing.assert_array_equal(_as_written(ds[name].values), v[:, j])
            np.testing.assert_array_equal(ds[name].values, cube[name].values)
            assert ds[name].attrs["units"] == cube[name].attrs["units"]
        np.testing.assert_array_equal(ds["sun_elevation"].values, cube["elevation"].values)
        np.testing.assert_array_equal(ds["open_sky_ghi"].values, cube["open_sky_ghi"].values)
    assert float(ds.glob_rad.isel(time=1).max()) > 500.0


def test_irradiance_errors_name_the_keywords(tmp_path):
    da = rioxarray.open_rasterio(_small_dem(tmp_path))
    with pytest.raises(HillshadeError, match=r"give the period one way: date= .*or the "
                                             r"instants: times="):
        da.hrt.irradiance()
    with pytest.raises(HillshadeError, match=r"^times= gives the instants: date="):
        da.hrt.irradiance("2026-06-21", times=["2026-06-21T12:00Z"])
    with pytest.raises(HillshadeError, match=r"monthly= and daily_mean= are a period's sums"):
        da.hrt.irradiance(times=["2026-06-21T12:00Z"], monthly=True)


@pytest.mark.slow
@pytest.mark.parametrize("chunked", [False, True])
def test_sun_hours_monthly_equals_the_command_lines_month_bands(tmp_path, chunked):
    """monthly=True: a layer per month the days touch, on a time dimension of month starts,
    equal to sun-hours --monthly's bands after the total (in memory, and lazily for a
    Dask-backed input)."""
    dem = _small_dem(tmp_path)
    out = tmp_path / "h.tif"
    _run("sun-hours", dem, out, "--date", "2026-05-31", "--end-date", "2026-06-01", "--step",
         "1h", "--tz", "America/Los_Angeles", "--monthly", "-q")
    v, _ = _bands(out)
    da = rioxarray.open_rasterio(dem)
    if chunked:
        da = da.chunk({"x": 20, "y": 20})
    m = da.hrt.sun_hours("2026-05-31", end_date="2026-06-01", step="1h",
                         tz="America/Los_Angeles", monthly=True)
    assert m.dims == ("time", "y", "x") and v.shape[0] == 3
    np.testing.assert_array_equal(m["time"].values,
                                  np.array(["2026-05-01", "2026-06-01"], "datetime64[ns]"))
    values = m.values        # (computed, for a lazy one)
    np.testing.assert_array_equal(_as_written(values), v[1:])
    assert 5.0 < float(np.nanmax(values[0])) <= 15.0
    total = da.hrt.sun_hours("2026-05-31", end_date="2026-06-01", step="1h",
                             tz="America/Los_Angeles")
    np.testing.assert_allclose(values.sum(axis=0), total.values, rtol=1e-6)


@pytest.mark.slow
def test_horizon_start_end_step_and_radians_equal_the_command_line(tmp_path):
    """r.horizon's start/end/step (and --directions): the azimuths the command line's bands
    have, each band's angles, in radians with angle_unit="radians"."""
    dem = _small_dem(tmp_path, voids=False)
    out = tmp_path / "h.tif"
    _run("horizon", dem, out, "--start", "12.5", "--end", "102.5", "--step", "30",
         "--angle-unit", "radians", "-q")
    v, _ = _bands(out)
    da = rioxarray.open_rasterio(dem)
    h = da.hrt.horizon(start=12.5, end=102.5, step=30, angle_unit="radians")
    assert h.dims == ("azimuth", "y", "x") and v.shape[0] == 3
    np.testing.assert_array_equal(h["azimuth"].values, [12.5, 42.5, 72.5])
    np.testing.assert_array_equal(h.values, v)
    assert h.attrs["units"] == "radians above the horizontal"
    assert h.attrs["no_terrain_ahead"] == pytest.approx(-np.pi / 2)
    deg = da.hrt.horizon(42.5)
    np.testing.assert_allclose(h.values[1], deg.values * np.float32(np.pi / 180), rtol=1e-6)
    eight = da.hrt.horizon(directions=8)
    np.testing.assert_array_equal(eight["azimuth"].values, np.arange(8) * 45.0)
    with pytest.raises(HillshadeError, match=r"start= and end= go with step="):
        da.hrt.horizon(start=10)
    with pytest.raises(HillshadeError, match=r"angle_unit= must be one of"):
        da.hrt.horizon(30, angle_unit="grads")


def test_shadow_polygons_cover_the_shadow_cells(tmp_path, monkeypatch):
    """The polygons of the mask's shadow cells: their areas add up to the shadow cells times
    the cell's area (30 m x 30 m), as many as the command line's --vector layer has, with the
    sun's azimuth and elevation; GeoJSON-like features without geopandas, a GeoDataFrame of
    them in the DEM's CRS with it."""
    import json
    import sys
    import types
    dem = _small_dem(tmp_path, relief=400.0)
    _run("shadow", dem, tmp_path / "m.tif", "--azimuth", "203.7", "--elevation", "14", "-q",
         "--vector", tmp_path / "v.geojson", "--report", tmp_path / "r.json")
    rep = json.loads((tmp_path / "r.json").read_text())["vector"]
    monkeypatch.setitem(sys.modules, "geopandas", None)     # not importable
    da = rioxarray.open_rasterio(dem)
    feats = da.hrt.shadow_polygons(azimuth=203.7, elevation=14)
    mask = da.hrt.shadow(azimuth=203.7, elevation=14).values
    cells = int((mask == 1).sum())
    assert 20 < cells < mask.size // 2 and isinstance(feats, list)
    assert len(feats) == rep["polygons"] > 1
    assert sum(f["properties"]["area_m2"] for f in feats) == pytest.approx(cells * 900.0)
    assert sum(f["properties"]["area"] for f in feats) == pytest.approx(rep["area"])
    f = feats[0]
    assert f["type"] == "Feature" and f["geometry"]["type"] == "Polygon"
    assert f["properties"]["azimuth"] == pytest.approx(203.7)
    assert f["properties"]["elevation"] == pytest.approx(14.0)
    series = da.hrt.shadow_polygons(time=["2026-06-21T07:30-07:00", "2026-06-21T17:10-07:00"],
                                    connectivity=8)
    assert {f["properties"]["index"] for f in series} == {0, 1}
    assert series[0]["properties"]["time"] == "2026-06-21T07:30-07:00"

    made = {}
    fake = types.ModuleType("geopandas")

    class GeoDataFrame:
        @classmethod
        def from_features(cls, features, crs=None):
            made.update(features=features, crs=crs)
            return cls()
    fake.GeoDataFrame = GeoDataFrame
    monkeypatch.setitem(sys.modules, "geopandas", fake)
    got = da.hrt.shadow_polygons(azimuth=203.7, elevation=14)
    assert isinstance(got, GeoDataFrame) and made["crs"] == da.rio.crs
    assert made["features"] == feats
    with pytest.raises(HillshadeError, match="connectivity must be 4 or 8"):
        da.hrt.shadow_polygons(azimuth=203.7, elevation=14, connectivity=6)
    with pytest.raises(HillshadeError, match="soft"):
        da.hrt.shadow_polygons(azimuth=203.7, elevation=14, soft=True)
