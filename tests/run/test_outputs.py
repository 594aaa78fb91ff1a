"""Where a run's products go (run.outputs): the names ``--output-pattern`` gives (fields, tiles,
the refusals), the tags, and through the command: a write that fails in a series leaves the files
before it whole and nothing under the failed file's final name."""

import datetime as dt
import errno
import os
from zoneinfo import ZoneInfo

import pytest
import rasterio

from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import write as writes
from hillshade_rt.model.sun import SunOver
from hillshade_rt.run import outputs
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
UTC = dt.timezone.utc


def _suns(*times, az=(163.0, 203.7, 290.0)):
    return [SunOver(t, a, 12.5) for t, a in zip(times, az)]


def test_tile_name():
    assert outputs.tile_name("/data/n46/e007.tif") == "e007"
    assert outputs.tile_name("zip:///x/t.zip!n46/e007.hgt") == "e007"
    assert outputs.tile_name("folder/") == "folder"


def test_pattern_fields_and_tiles():
    t0 = dt.datetime(2026, 6, 21, 9, 30, tzinfo=UTC)
    suns = _suns(t0, t0 + dt.timedelta(minutes=15))
    p = outputs.OutputPattern("o/{tile}_{index:02d}_{time:%H%M}_{azimuth:.1f}_{elevation:.0f}.tif")
    paths = p.paths(suns, ["/a/n46e007.tif", "/b/n46e008.tif"])
    assert paths == [["o/n46e007_00_0930_163.0_12.tif", "o/n46e008_00_0930_163.0_12.tif"],
                     ["o/n46e007_01_0945_203.7_12.tif", "o/n46e008_01_0945_203.7_12.tif"]]
    assert p.per_tile and p.planned == [q for ps in paths for q in ps]
    one = outputs.OutputPattern("{index}.tif")
    assert one.paths(suns, ["/a/x.tif", "/b/y.tif"]) == [["0.tif"], ["1.tif"]]


def test_pattern_refusals():
    with pytest.raises(HillshadeError, match="unknown field"):
        outputs.OutputPattern("{when}.tif")
    with pytest.raises(HillshadeError, match="output-pattern"):
        outputs.OutputPattern("{time.tif")
    t0 = dt.datetime(2026, 6, 21, 9, 30, tzinfo=UTC)
    with pytest.raises(HillshadeError, match="same file name"):
        outputs.OutputPattern("{time:%Y%m%d}.tif").paths(
            _suns(t0, t0 + dt.timedelta(hours=1)))
    with pytest.raises(HillshadeError, match="rename one"):
        outputs.OutputPattern("{tile}_{index}.tif").paths(_suns(t0), ["/a/e7.tif", "/b/e7.tif"])
    # the hour repeated when the clocks go back: 01:30 EDT and 01:30 EST
    ny = ZoneInfo("America/New_York")
    first = dt.datetime(2026, 11, 1, 5, 30, tzinfo=UTC).astimezone(ny)
    second = dt.datetime(2026, 11, 1, 6, 30, tzinfo=UTC).astimezone(ny)
    assert first.strftime("%H%M") == second.strftime("%H%M") == "0130"
    with pytest.raises(HillshadeError, match="clocks go back"):
        outputs.OutputPattern("{time:%Y%m%dT%H%M}.tif").paths(_suns(first, second))
    ok = outputs.OutputPattern("{time:%Y%m%dT%H%M%z}.tif").paths(_suns(first, second))
    assert ok == [["20261101T0130-0400.tif"], ["20261101T0130-0500.tif"]]


def test_tags_and_label():
    t = dt.datetime(2026, 6, 21, 9, 30, tzinfo=UTC)
    s = SunOver(t, 203.7, 12.25)
    tags = outputs.sun_tags(s)
    assert tags == {"SUN_AZIMUTH": "203.700000", "SUN_ELEVATION": "12.250000", "NIGHT": "no",
                    "TIME": "2026-06-21T09:30+00:00"}
    assert outputs.label(s) == "2026-06-21T09:30+00:00"
    assert outputs.label(SunOver(None, 290.0, 7.5)) == "sun az 290 el 7.5"


def test_a_failed_write_in_a_series_leaves_no_partial_file(tmp_path, monkeypatch, runner):
    real = writes._fsync
    calls = []

    def second_fails(path):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)
        return real(path)

    monkeypatch.setattr(writes, "_fsync", second_fails)
    out = tmp_path / "s"
    out.mkdir()
    r = runner.invoke(cli, ["shadow", LIDAR, "--output-pattern", str(out / "t_{index}.tif"),
                            "--start", "2026-06-21T09:00-05:00", "--end",
                            "2026-06-21T11:00-05:00", "--step", "1h", "-q"])
    assert r.exit_code == 1 and "no space left on device" in r.stderr.lower()
    names = sorted(os.listdir(out))
    assert names == ["t_0.tif"], names            # nothing hidden, nothing under t_1's name
    with rasterio.open(out / "t_0.tif") as ds:   # the one before is whole
        m = ds.read(1)
        assert m.shape == (400, 400) and set(map(int, set(m.ravel()))) <= {0, 1, 255}


# --------------------------------------------------------------------------------------------
# a series into OUTPUT.nc / OUTPUT.zarr: one CF time cube (io.cube)

SERIES = ["--start", "2026-06-21T08:10-05:00", "--end", "2026-06-21T17:40-05:00", "--step",
          "190min"]


def _zarr_here():
    import importlib.util
    return importlib.util.find_spec("zarr") is not None


def _shade(runner, command, out, *extra):
    import json
    r = runner.invoke(cli, [command, LIDAR, str(out), *SERIES, "-q", "--report",
                            f"{out}.json", *extra])
    assert r.exit_code == 0, r.output
    with open(f"{out}.json") as f:
        return json.load(f)


@pytest.mark.parametrize("command, name, extra", [
    ("shadow", "s.nc", []),
    pytest.param("shadow", "s.nc", ["--window-size", "160x130"], marks=pytest.mark.slow),
    ("shadow", "s.nc", ["--soft"]),
    pytest.param("hillshade", "s.nc", [], marks=pytest.mark.slow),
    pytest.param("shadow", "s.zarr", ["--window-size", "160x130"], marks=[
        pytest.mark.slow, pytest.mark.skipif(not _zarr_here(), reason="zarr not installed")]),
])
def test_a_series_into_a_cube_equals_the_geotiffs_bands(tmp_path, runner, command, name, extra):
    import numpy as np
    xr = pytest.importorskip("xarray")
    pytest.importorskip("rioxarray")
    rep_tif = _shade(runner, command, tmp_path / "s.tif", *extra)
    rep = _shade(runner, command, tmp_path / name, *extra)
    with rasterio.open(tmp_path / "s.tif") as ds:
        bands = ds.read()
        nodata = ds.nodata
    with rasterio.open(LIDAR) as ds:
        dem_crs = ds.crs
    suns = rep["times"]
    assert len(suns) == bands.shape[0] == 4
    var = "visible_fraction" if "--soft" in extra else command
    engine = "zarr" if name.endswith(".zarr") else None
    with xr.open_dataset(tmp_path / name, engine=engine) as ds:
        want = np.array([dt.datetime.fromisoformat(s["time"]).astimezone(UTC)
                         .replace(tzinfo=None) for s in suns], "datetime64[ns]")
        np.testing.assert_array_equal(ds["time"].values, want)
        assert ds.rio.crs == dem_crs and ds[var].rio.crs == dem_crs
        np.testing.assert_array_equal(ds["azimuth"].values, [s["azimuth"] for s in suns])
        np.testing.assert_array_equal(ds["elevation"].values, [s["elevation"] for s in suns])
        np.testing.assert_array_equal(ds["true_azimuth"].values,
                                      [s["true_azimuth"] for s in suns])
        assert ds.attrs["Conventions"] == "CF-1.8"
        assert ds.attrs["source"].startswith("hillshade-rt ")
        assert f"{command} " in ds.attrs["history"] and name in ds.attrs["history"]
        assert ds[var].encoding["_FillValue"] == nodata
    with xr.open_dataset(tmp_path / name, engine=engine, mask_and_scale=False) as ds:
        assert ds[var].dtype == bands.dtype
        np.testing.assert_array_equal(ds[var].values, bands)        # bit for bit
    assert rep["product"]["bands"] == rep_tif["product"]["bands"] == 4
    assert sorted(os.listdir(tmp_path)) == sorted(["s.tif", "s.tif.json", name, name + ".json"])


@pytest.mark.parametrize("extra, said", [
    (["--co", "COMPRESS=ZSTD"], "--co sets GDAL's creation options"),
    (["--cog"], "--cog writes a GeoTIFF"),
    (["--stac-item", "ITEM"], "--stac-item describes a GeoTIFF OUTPUT"),
])
def test_a_cube_refuses_what_it_cannot_take(tmp_path, runner, extra, said):
    extra = [str(tmp_path / "i.json") if e == "ITEM" else e for e in extra]
    if "--stac-item" in extra:
        pytest.importorskip("pystac")
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "c.nc"), *SERIES, "-q", *extra])
    assert r.exit_code == 2, r.output
    assert said in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert os.listdir(tmp_path) == []


def test_a_cube_is_not_replaced_without_overwrite(tmp_path, runner):
    out = tmp_path / "c.nc"
    _shade(runner, "shadow", out)
    before = out.read_bytes()
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), *SERIES, "-q"])
    assert r.exit_code == 1 and "already exists (use --overwrite" in r.stderr
    assert out.read_bytes() == before
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), *SERIES, "-q", "--overwrite", "--soft"])
    assert r.exit_code == 0, r.output
    assert sorted(os.listdir(tmp_path)) == ["c.nc", "c.nc.json"]


@pytest.mark.parametrize("name", ["c.nc", pytest.param("c.zarr", marks=pytest.mark.skipif(
    not _zarr_here(), reason="zarr not installed"))])
def test_a_failed_series_leaves_no_cube(tmp_path, runner, monkeypatch, name):
    from hillshade_rt.io import cube
    real = cube.CubeWriter.write

    def third_fails(self, band, data, *a, **k):
        if band == 3:
            raise HillshadeError(f"{self.path}: cannot write (input/output error)")
        return real(self, band, data, *a, **k)
    monkeypatch.setattr(cube.CubeWriter, "write", third_fails)
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / name), *SERIES, "-q"])
    assert r.exit_code == 1 and "input/output error" in r.stderr
    assert os.listdir(tmp_path) == []


def test_a_single_given_sun_into_nc_stays_gdals(tmp_path, runner):
    """No times, no series: GDAL's netCDF driver writes the band, as before."""
    out = tmp_path / "one.nc"
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "--azimuth", "203.7", "--elevation",
                            "20", "-q"])
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as ds:
        assert ds.driver == "netCDF" and ds.count == 1
