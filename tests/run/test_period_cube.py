"""A period's sums into OUTPUT.nc / OUTPUT.zarr (``run.period_cube``): ``irradiance`` and
``sun-hours`` write a CF-1.8 dataset xarray decodes (the totals on (y, x), with --monthly the
months on a time axis of month starts with their cell bounds), every variable the GeoTIFF's band
of the same command line bit for bit, in memory, in windows and on Dask; ``-f netCDF`` keeps
GDAL's bands; --co is refused."""

from __future__ import annotations

import datetime as dt
import json
import os

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.run import period_cube
from hillshade_rt.run.config import IrradianceConfig, RunOptions, SunHoursConfig
from hillshade_rt.testing import fractal_terrain, write_geotiff

xr = pytest.importorskip("xarray")
pytest.importorskip("netCDF4")
pytest.importorskip("rioxarray")     # (da.rio)

# pvlib 0.16 asks pandas 3 for DatetimeIndex.dayofyear (deprecated there), inside pvlib
pytestmark = pytest.mark.filterwarnings("ignore:DatetimeIndex.dayofyear:DeprecationWarning")

UTM11 = CRS.from_epsg(32611)
CUBES = ["c.nc", pytest.param("c.zarr", marks=pytest.mark.skipif(
    __import__("importlib").util.find_spec("zarr") is None, reason="zarr not installed"))]
RSUN = ("beam_rad", "diff_rad", "refl_rad", "glob_rad")
# two months, few samples (the run in windows' tests' period, a day longer)
MONTHLY = ["--date", "2026-01-30", "--end-date", "2026-02-02", "--step", "3h", "--monthly",
           "--tz", "America/Los_Angeles", "--skyview-directions", "8", "-q"]


def _dem(tmp_path, rows=30, cols=36, voids=True, name="f.tif"):
    z = fractal_terrain(rows, cols, 5, relief=250.0)
    if voids:
        z[3:6, 20:24] = -32768.0
    return write_geotiff(tmp_path / name, z, Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0),
                         UTM11, nodata=-32768.0)


def _run(runner, command, args, code=0):
    r = runner.invoke(cli, [command] + [str(a) for a in args])
    assert r.exit_code == code, r.output
    return r


def _bands(path):
    with rasterio.open(path) as ds:
        return ds.read(), ds.descriptions


def _engine(path):
    return "zarr" if str(path).endswith(".zarr") else None


def _raw(path, names):
    """The variables as stored (no mask, no scale): a stack in ``names``' order."""
    with xr.open_dataset(path, engine=_engine(path), mask_and_scale=False) as ds:
        out = []
        for n in names:
            v = ds[n].values
            out.extend(v if v.ndim == 3 else [v])
        return np.stack(out)


# -- irradiance --------------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("name", CUBES)
def test_irradiance_monthly_cube_is_the_geotiffs_bands(tmp_path, runner, name):
    """irradiance --monthly to OUTPUT.tif and to OUTPUT.nc / .zarr (with --report and --preview):
    xarray decodes r.sun's four totals on (y, x) and glob_rad_monthly on the months' first days
    with their bounds (the period's first day, the month's end, the day after the last), the
    months' labels and sampled hours as coordinates; units, long names, grid mapping,
    _FillValue; every variable the GeoTIFF's band bit for bit, voids included."""
    dem = _dem(tmp_path)
    tif, cube, rep, png = (tmp_path / "g.tif", tmp_path / name, tmp_path / "c.json",
                           tmp_path / "c.png")
    _run(runner, "irradiance", [dem, tif] + MONTHLY)
    _run(runner, "irradiance", [dem, cube, "--report", rep, "--preview", png] + MONTHLY)
    v, desc = _bands(tif)
    assert v.shape == (6, 30, 36) and desc[4:] == ("2026-01", "2026-02")
    doc = json.loads(rep.read_text())
    assert doc["output"] == str(cube) and png.stat().st_size > 0
    with xr.open_dataset(cube, engine=_engine(cube)) as ds:
        assert ds.attrs["Conventions"] == "CF-1.8" and "--monthly" in ds.attrs["history"]
        assert ds.attrs["period_start"] == "2026-01-30"
        assert ds.attrs["period_end"] == "2026-02-02"
        assert "America/Los_Angeles" in ds.attrs["period"]
        assert "units" not in ds.attrs and "months" not in ds.attrs    # the variables say
        for n in RSUN:
            da = ds[n]
            assert da.dims == ("y", "x") and da.attrs["units"] == "Wh m-2"
            assert da.attrs["long_name"] and da.attrs["cell_methods"] == "time: sum"
            assert da.encoding["_FillValue"] == -9999.0 and da.rio.crs == UTM11
            assert np.isnan(da.values[4, 21]) and np.isnan(da.values).sum() == 12
        mo = ds["glob_rad_monthly"]
        assert mo.dims == ("time", "y", "x") and mo.attrs["units"] == "Wh m-2"
        assert mo.rio.crs == UTM11 and mo.encoding["_FillValue"] == -9999.0
        np.testing.assert_array_equal(ds["time"].values, np.array(
            ["2026-01-01", "2026-02-01"], "datetime64[ns]"))
        np.testing.assert_array_equal(ds["time_bnds"].values, np.array(
            [["2026-01-30", "2026-02-01"], ["2026-02-01", "2026-02-03"]], "datetime64[ns]"))
        assert "America/Los_Angeles" in ds["time"].attrs["comment"]
        assert list(mo["month"].values) == ["2026-01", "2026-02"]
        np.testing.assert_array_equal(mo["hours"].values,
                                      [m["hours"] for m in doc["months"]])
        np.testing.assert_array_equal(mo["hours"].values, [48.0, 48.0])
        # the months add up to the period (float32 sums of their own)
        np.testing.assert_allclose(mo.sum("time", skipna=False).values,
                                   ds["glob_rad"].values, rtol=1e-5)
    np.testing.assert_array_equal(_raw(cube, RSUN + ("glob_rad_monthly",)), v)  # bit for bit
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["c.json", "c.png", "f.tif", "g.tif", name])                 # no temporary left


@pytest.mark.slow
def test_irradiance_mean_cube_in_windows_is_the_cube_in_memory(tmp_path, runner):
    """--mean over --start/--end (offsets, no --tz: the months in local mean solar time at the
    DEM's centre) with --monthly, in memory and in windows of 64 cells (--window-size): the
    same values in W m-2; the months' bounds the period's ends in that clock."""
    from pyproj import Transformer
    dem = _dem(tmp_path, 100, 90, voids=False)
    args = ["--start", "2026-03-31T15:00-07:00", "--end", "2026-04-01T14:00-07:00", "--step",
            "2h", "--mean", "--monthly", "--skyview-directions", "8", "-q"]
    mem, win, tif = tmp_path / "m.nc", tmp_path / "w.nc", tmp_path / "m.tif"
    _run(runner, "irradiance", [dem, mem] + args)
    _run(runner, "irradiance", [dem, win, "--window-size", "64", "--report",
                                tmp_path / "w.json"] + args)
    _run(runner, "irradiance", [dem, tif] + args)
    assert json.loads((tmp_path / "w.json").read_text())["processing"]["regions"] > 1
    names = RSUN + ("glob_rad_monthly",)
    np.testing.assert_array_equal(_raw(win, names), _raw(mem, names))
    np.testing.assert_array_equal(_raw(mem, names), _bands(tif)[0])
    lon, _ = Transformer.from_crs(UTM11, "EPSG:4326", always_xy=True).transform(
        400000.0 + 45 * 30.0, 3800000.0 - 50 * 30.0)
    solar = dt.timedelta(hours=lon / 15.0)
    t0 = dt.datetime(2026, 3, 31, 22, 0) + solar        # --start in UTC, then solar time
    t1 = dt.datetime(2026, 4, 1, 21, 0) + solar
    with xr.open_dataset(win) as ds:
        assert ds["glob_rad"].attrs["units"] == "W m-2"
        assert ds["glob_rad_monthly"].attrs["cell_methods"] == "time: mean"
        assert ds.attrs["period_start"] == "2026-03-31T15:00-07:00"
        assert ds.attrs["period_end"] == "2026-04-01T14:00-07:00"
        assert f"longitude {lon:.4f}" in ds["time"].attrs["comment"]
        np.testing.assert_array_equal(ds["time"].values, np.array(
            ["2026-03-01", "2026-04-01"], "datetime64[ns]"))
        got = ds["time_bnds"].values.astype("datetime64[us]").astype(dt.datetime)
        want = [[t0, dt.datetime(2026, 4, 1)], [dt.datetime(2026, 4, 1), t1]]
        for g, w in zip(got.ravel(), np.array(want).ravel()):
            assert abs(g - w) < dt.timedelta(milliseconds=1), (g, w)


def test_irradiance_of_a_dem_of_voids_is_a_cube_of_voids(tmp_path, runner):
    """Every cell of the DEM nodata: the cube's four totals all voids, no time axis."""
    z = np.full((12, 14), -32768.0, np.float32)
    dem = write_geotiff(tmp_path / "v.tif", z, Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0),
                        UTM11, nodata=-32768.0)
    out = tmp_path / "v.nc"
    _run(runner, "irradiance", [dem, out, "--date", "2026-06-21", "--monthly", "-q"])
    with xr.open_dataset(out) as ds:
        assert set(ds.data_vars) == set(RSUN) and "time" not in ds.dims
        assert all(np.isnan(ds[n].values).all() for n in RSUN)
        assert ds.attrs["period_start"] == ds.attrs["period_end"] == "2026-06-21"


@pytest.mark.parametrize("command, extra", [
    ("irradiance", ["--date", "2026-06-21"]), ("sun-hours", ["--date", "2026-06-21"])])
def test_format_netcdf_keeps_gdals_bands_and_a_cube_takes_no_co(tmp_path, runner, command,
                                                               extra):
    """``-f netCDF`` is GDAL's driver (its Band1.. variables); OUTPUT.nc with --co is a usage
    error, one line, before any work, nothing written."""
    dem = _dem(tmp_path, 12, 14, voids=False)
    out = tmp_path / "o.nc"
    r = _run(runner, command, [dem, out, "--co", "COMPRESS=DEFLATE", "-q"] + extra, code=2)
    assert "drop --co" in r.output and len(r.output.strip().splitlines()) == 1, r.output
    assert not out.exists()
    _run(runner, command, [dem, out, "-f", "netCDF", "-q", "--step", "2h"] + extra)
    with xr.open_dataset(out) as ds:
        assert "Band1" in ds.data_vars and "glob_rad" not in ds and "insol_time" not in ds
        assert ds.attrs.get("Conventions") != "CF-1.8"


# -- sun-hours ---------------------------------------------------------------------------------

SUN = ["--date", "2026-01-30", "--end-date", "2026-02-02", "--step", "2h", "--tz",
       "Europe/Zurich", "-q"]


@pytest.mark.slow
@pytest.mark.parametrize("name", CUBES)
def test_sun_hours_monthly_cube_is_the_geotiffs_bands(tmp_path, runner, name):
    """sun-hours --monthly to OUTPUT.tif and to OUTPUT.nc / .zarr: insol_time on (y, x) in h,
    insol_time_monthly on the months (bounds clipped to the days), bit for bit the bands;
    without --monthly: insol_time alone, no time."""
    dem = _dem(tmp_path)
    tif, cube = tmp_path / "h.tif", tmp_path / name
    _run(runner, "sun-hours", [dem, tif, "--monthly"] + SUN)
    _run(runner, "sun-hours", [dem, cube, "--monthly", "--report", tmp_path / "r.json"] + SUN)
    v, desc = _bands(tif)
    assert v.shape == (3, 30, 36) and desc[1:] == ("2026-01", "2026-02")
    with xr.open_dataset(cube, engine=_engine(cube)) as ds:
        assert set(ds.data_vars) == {"insol_time", "insol_time_monthly", "time_bnds"}
        h, mo = ds["insol_time"], ds["insol_time_monthly"]
        assert h.dims == ("y", "x") and mo.dims == ("time", "y", "x")
        assert h.attrs["units"] == mo.attrs["units"] == "h" and h.rio.crs == UTM11
        assert h.encoding["_FillValue"] == -9999.0 and np.isnan(h.values).sum() == 12
        np.testing.assert_array_equal(ds["time_bnds"].values, np.array(
            [["2026-01-30", "2026-02-01"], ["2026-02-01", "2026-02-03"]], "datetime64[ns]"))
        assert list(mo["month"].values) == ["2026-01", "2026-02"] and "hours" not in mo.coords
        assert "Europe/Zurich" in ds["time"].attrs["comment"]
        assert (ds.attrs["period_start"], ds.attrs["period_end"]) == ("2026-01-30",
                                                                     "2026-02-02")
        assert "Europe/Zurich" in ds.attrs["period"]
        assert "sun-hours" in ds.attrs["history"] and "--monthly" in ds.attrs["history"]
        assert ds.attrs["title"] == "hillshade-rt: hours of direct sun over a period"
        assert float(h.max()) > 20.0
    np.testing.assert_array_equal(_raw(cube, ("insol_time", "insol_time_monthly")), v)
    one = tmp_path / ("one" + os.path.splitext(name)[1])
    _run(runner, "sun-hours", [dem, one] + SUN)
    with xr.open_dataset(one, engine=_engine(one)) as ds:
        assert set(ds.data_vars) == {"insol_time"} and "time" not in ds.dims
    np.testing.assert_array_equal(_raw(one, ("insol_time",))[0], v[0])


@pytest.mark.slow
def test_sun_hours_cube_in_windows_is_the_cube_in_memory(tmp_path, runner):
    """sun-hours --monthly in windows of 64 cells: the cube of the run in memory, value for
    value."""
    dem = _dem(tmp_path, 100, 90)
    mem, win = tmp_path / "m.nc", tmp_path / "w.nc"
    _run(runner, "sun-hours", [dem, mem, "--monthly"] + SUN)
    _run(runner, "sun-hours", [dem, win, "--monthly", "--window-size", "64", "--report",
                               tmp_path / "w.json"] + SUN)
    assert json.loads((tmp_path / "w.json").read_text())["processing"]["regions"] > 1
    names = ("insol_time", "insol_time_monthly")
    np.testing.assert_array_equal(_raw(win, names), _raw(mem, names))
    with xr.open_dataset(win) as ds, xr.open_dataset(mem) as dm:
        np.testing.assert_array_equal(ds["time_bnds"].values, dm["time_bnds"].values)


@pytest.mark.slow       # a local cluster of two worker processes
def test_irradiance_monthly_cube_on_dask_is_the_cube_in_memory(tmp_path, runner):
    """irradiance --monthly, each region a Dask task (--scheduler local:2): the cube of the run
    in memory, every variable, bound and coordinate; no part left."""
    pytest.importorskip("distributed")
    dem = _dem(tmp_path, 100, 90)
    mem, dsk = tmp_path / "m.nc", tmp_path / "d.nc"
    _run(runner, "irradiance", [dem, mem] + MONTHLY)
    _run(runner, "irradiance", [dem, dsk, "--window-size", "64", "--scheduler", "local:2",
                                "--report", tmp_path / "d.json"] + MONTHLY)
    assert json.loads((tmp_path / "d.json").read_text())["processing"]["mode"] == "dask"
    names = RSUN + ("glob_rad_monthly",)
    np.testing.assert_array_equal(_raw(dsk, names), _raw(mem, names))
    with xr.open_dataset(dsk) as ds, xr.open_dataset(mem) as dm:
        for k in ("time", "time_bnds", "month", "hours"):
            np.testing.assert_array_equal(ds[k].values, dm[k].values)
    assert sorted(os.listdir(tmp_path)) == ["d.json", "d.nc", "f.tif", "m.nc"]


# -- the pieces --------------------------------------------------------------------------------

def test_month_bounds_clip_to_the_period():
    firsts, bounds = period_cube.month_bounds(
        [(2025, 12), (2026, 1), (2026, 2)], dt.datetime(2025, 12, 17, 6, 30),
        dt.datetime(2026, 2, 3))
    assert firsts == [dt.datetime(2025, 12, 1), dt.datetime(2026, 1, 1),
                      dt.datetime(2026, 2, 1)]
    assert bounds == [(dt.datetime(2025, 12, 17, 6, 30), dt.datetime(2026, 1, 1)),
                      (dt.datetime(2026, 1, 1), dt.datetime(2026, 2, 1)),
                      (dt.datetime(2026, 2, 1), dt.datetime(2026, 2, 3))]


def test_which_outputs_are_cubes_and_their_units():
    def irr(output, **kw):
        run = RunOptions(fmt=kw.pop("fmt", None), creation_options=kw.pop("co", {}))
        return IrradianceConfig(dem="d.tif", output=output, date="2026-01-01", run=run, **kw)
    assert period_cube.use_period_cube(irr("a.nc")) and period_cube.use_period_cube(irr("b.ZARR"))
    assert not period_cube.use_period_cube(irr("a.nc", fmt="netCDF"))
    assert not period_cube.use_period_cube(irr("a.tif"))
    assert not period_cube.use_period_cube(SunHoursConfig(dem="d.tif", output="x.tif",
                                                          date="2026-01-01"))
    assert [v.name for v in period_cube.cube_variables(irr("a.nc"), True)] == \
        list(RSUN) + ["glob_rad_monthly"]
    assert [v.timed for v in period_cube.cube_variables(irr("a.nc"), True)] == \
        [False] * 4 + [True]
    for kw, units in (({}, "Wh m-2"), ({"mean": True}, "W m-2"),
                      ({"daily_mean": True}, "Wh m-2 day-1")):
        assert {v.attrs["units"] for v in period_cube.cube_variables(irr("a.nc", **kw),
                                                                     True)} == {units}
    sun = SunHoursConfig(dem="d.tif", output="x.nc", date="2026-01-01")
    assert [(v.name, v.attrs["units"]) for v in period_cube.cube_variables(sun, True)] == \
        [("insol_time", "h"), ("insol_time_monthly", "h")]
