"""sun-hours in windows and on Dask (``run.sun_hours_windows``): region by region, each
region's suns in groups whose windows fit memory, written as the regions are made, or each
region a Dask task: every cell the bits of the run in memory (voids, geographic DEMs, soft
light, the lift, SMap), with --monthly each month's band too; --max-memory decides; the
command line, refusals and an interrupt."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.run import ReadOptions, RunOptions, SunHoursConfig, sun_hours
from hillshade_rt.testing import read_band, write_geotiff

TZ = "Europe/Zurich"
CELL = 10.0                              # metres
ORIGIN = Affine(CELL, 0, 600000.0, 0, -CELL, 5150000.0)     # UTM 32N, about 46.5 N 8.3 E
UTM32 = CRS.from_epsg(32632)
SIDE = 80
PILLAR = (slice(38, 43), slice(38, 43))  # 50 m square, rows/cols 38..42
PILLAR_M = 200.0


def _dem(tmp_path, z, name="dem.tif", transform=ORIGIN):
    return write_geotiff(str(tmp_path / name), z.astype(np.float32), transform, UTM32, -9999.0)


def _pillar():
    z = np.full((SIDE, SIDE), 500.0, np.float32)
    z[PILLAR] += PILLAR_M
    return z



def _hours(tmp_path, dem, out, report=None, step="40min", **kw):
    """The hours (the band read back, -9999 nodata) and the report of ``dem`` on the solstice
    at Zurich's clock, every ``step``."""
    cfg = SunHoursConfig(dem=dem, output=str(tmp_path / out), date="2026-12-21", step=step,
                         place={"tz": TZ}, run=RunOptions(overwrite=True, quiet=True,
                                                          report_path=report), **kw)
    rep = sun_hours(cfg)
    return read_band(tmp_path / out), rep


@pytest.fixture
def any_window(monkeypatch):
    """--window-size down to one cell a side (the command line asks for 64 at least)."""
    from hillshade_rt.run import config
    monkeypatch.setattr(config, "MIN_WINDOW_SIDE", 1)


def _voids():
    """The pillar on a rough slope with a void across the pillar's shadow."""
    rng = np.random.default_rng(163)
    z = _pillar() + rng.normal(0.0, 3.0, (SIDE, SIDE)).astype(np.float32)
    z += np.linspace(0.0, 60.0, SIDE, dtype=np.float32)[:, None]
    z[20:24, 45:70] = np.nan
    z[60:, :3] = np.nan
    return z


@pytest.mark.parametrize("size", [pytest.param("1x80", marks=pytest.mark.slow),
                                  pytest.param("80x1", marks=pytest.mark.slow),
                                  pytest.param("7x50", marks=pytest.mark.slow), "64", "30x45"])
def test_windows_give_the_bits_of_the_run_in_memory(tmp_path, any_window, size):
    """Windows of one row, of one column, and windows far shorter than the pillar's shadow
    (about 65 cells at noon): every cell equal to the run in memory, voids included."""
    dem = _dem(tmp_path, _voids())
    whole, rep = _hours(tmp_path, dem, "whole.tif")
    got, wrep = _hours(tmp_path, dem, "win.tif", window_size=size)
    np.testing.assert_array_equal(got, whole)
    assert (whole == -9999.0).sum() == 4 * 25 + 20 * 3
    assert rep["processing"] == {"mode": "in memory", "cells": SIDE * SIDE}
    p = wrep["processing"]
    rows, cols = (int(v) for v in (size.split("x") * 2)[:2])
    assert p["mode"] == "tiled" and p["regions"] == -(-SIDE // rows) * -(-SIDE // cols)
    assert p["windows"] >= p["regions"] * wrep["samples_with_sun"]
    assert p["window_shape_requested"] == [rows, cols]
    assert wrep["hours"]["min"] == rep["hours"]["min"]
    assert wrep["hours"]["max"] == rep["hours"]["max"]
    assert wrep["hours"]["mean"] == pytest.approx(rep["hours"]["mean"], rel=1e-12)
    for k in ("shape", "samples", "samples_with_sun", "curvature", "dates", "day_definition"):
        assert wrep[k] == rep[k], k


@pytest.mark.slow       # 770,000 cells, twice
def test_the_bundled_example_in_windows(tmp_path):
    """The bundled SRTM example (1197 x 643, UTM): in windows shorter than the low suns'
    shadows (--window-size 160x400), the bits of the run in memory."""
    from hillshade_rt.testing import repo_root
    dem = os.path.join(repo_root(), "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif")

    def run(out, **more):
        cfg = SunHoursConfig(dem=dem, output=str(tmp_path / out), date="2026-12-21",
                             step="2h", place={"tz": "America/Los_Angeles"},
                             run=RunOptions(overwrite=True, quiet=True), **more)
        rep = sun_hours(cfg)
        return read_band(tmp_path / out), rep
    whole, rep = run("whole.tif")
    assert 3.0 < rep["hours"]["mean"] < 10.0 and rep["hours"]["min"] < 1.0
    got, wrep = run("win.tif", window_size="160x400")
    np.testing.assert_array_equal(got, whole)
    assert wrep["processing"]["regions"] == 5 * 3


@pytest.mark.slow       # suns per tile on a geographic DEM: some seconds
@pytest.mark.parametrize("size", ["1x120", "24x40"])
def test_a_geographic_dem_with_voids_in_windows(tmp_path, any_window, size):
    """Everest's SRTM crop (geographic, the spacing per row; its 64 x 120 corner has two
    fifths voids): in windows of one row and of 24 x 40, every cell as in memory."""
    import rasterio
    from hillshade_rt.testing import data_path
    with rasterio.open(data_path("everest_srtm3_voids_crop200.tif")) as ds:
        z = ds.read(1, window=((0, 64), (0, 120))).astype(np.float32)
        dem = write_geotiff(str(tmp_path / "everest.tif"), z, ds.transform, ds.crs, ds.nodata)

    def run(out, **more):
        cfg = SunHoursConfig(dem=dem, output=str(tmp_path / out), date="2026-03-02",
                             step="1h", place={"tz": "Asia/Kathmandu"},
                             run=RunOptions(overwrite=True, quiet=True), **more)
        rep = sun_hours(cfg)
        return read_band(tmp_path / out), rep
    whole, rep = run("whole.tif")
    assert (whole == -9999.0).mean() > 0.3 and rep["processing"]["mode"] == "in memory"
    got, wrep = run("win.tif", window_size=size)
    np.testing.assert_array_equal(got, whole)
    assert wrep["processing"]["mode"] == "tiled"


@pytest.mark.parametrize("extra", [dict(soft=True), dict(height_above_ground=30.0),
                                   dict(self_shadow=False, algorithm="smap")])
def test_soft_lifted_and_smap_hours_in_windows(tmp_path, extra):
    """The disk's visible fraction, an observer 30 m up, SMap without self-shadow: in windows
    of 64 x 64 the bits of the run in memory."""
    dem = _dem(tmp_path, _voids())
    whole, _ = _hours(tmp_path, dem, "whole.tif", step="90min", **extra)
    got, _ = _hours(tmp_path, dem, "win.tif", window_size=64, step="90min", **extra)
    np.testing.assert_array_equal(got, whole)


def test_max_memory_decides_and_the_day_is_read_about_once(tmp_path, monkeypatch):
    """A --max-memory the DEM does not fit runs in windows (the DEM read about once: every
    sun's window of a region read together); a large one runs in memory."""
    from hillshade_rt.engine import windows
    # rough open ground, 3 m of relief: the low suns' shadows some 20 cells long
    rng = np.random.default_rng(203)
    dem = _dem(tmp_path, 500.0 + rng.uniform(0.0, 3.0, (200, 200)))
    whole, rep = _hours(tmp_path, dem, "whole.tif", max_memory="64GB")
    assert rep["processing"]["mode"] == "in memory"
    # the process as large as 200 MB whatever it holds: room for 1 MB beyond it, about
    # 29,000 cells of window (22 + 12 bytes each); the DEM in memory would need 1.2 MB
    monkeypatch.setattr(windows, "process_rss", lambda: 200_000_000)
    limit = 200_000_000 + (windows.GDAL_CACHE_MB << 20) + (32 << 20) + 1_000_000
    got, wrep = _hours(tmp_path, dem, "win.tif", max_memory=str(limit))
    np.testing.assert_array_equal(got, whole)
    p = wrep["processing"]
    assert p["mode"] == "tiled" and p["regions"] > 1
    assert p["windows_read"] == p["regions"] and 1.0 <= p["dem_reads"] < 3.0


def test_the_command_line_in_windows_with_a_preview(tmp_path):
    """--window-size, --report, --preview on the command line: the report says how it ran,
    the summary names the windows, the preview is the DEM's size (every cell: a small DEM)."""
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    dem = _dem(tmp_path, _voids())
    whole, _ = _hours(tmp_path, dem, "whole.tif", step="2h")
    r = CliRunner().invoke(cli, ["sun-hours", dem, str(tmp_path / "w.tif"), "--date",
                                 "2026-12-21", "--step", "2h", "--tz", TZ, "--window-size",
                                 "64x80", "--report", str(tmp_path / "w.json"), "--preview",
                                 str(tmp_path / "w.png")])
    assert r.exit_code == 0, r.output
    assert ", 2 windows" in r.stderr.strip().splitlines()[-1]
    np.testing.assert_array_equal(read_band(tmp_path / "w.tif"), whole)
    doc = json.loads((tmp_path / "w.json").read_text())
    assert doc["processing"]["mode"] == "tiled" and doc["processing"]["regions"] == 2
    assert read_band(tmp_path / "w.png").shape == (SIDE, SIDE)


def test_a_memory_limit_too_small_for_one_window_is_one_line(tmp_path):
    """As shadow says it: exit status 1, one line naming the smallest --max-memory, no
    output."""
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    dem = _dem(tmp_path, _voids())
    out = tmp_path / "o.tif"
    r = CliRunner().invoke(cli, ["sun-hours", dem, str(out), "--date", "2026-12-21",
                                 "--tz", TZ, "--max-memory", "10MB", "-q"])
    assert r.exit_code == 1, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "--max-memory" in lines[0] and "give at least" in lines[0]
    assert not out.exists()


def test_an_interrupt_in_windows_leaves_no_output(tmp_path, monkeypatch):
    """Ctrl-C while the third window is lit: exit status 130, nothing under OUTPUT's name nor
    beside it."""
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    from hillshade_rt.engine import windows
    (tmp_path / "in").mkdir()
    (tmp_path / "out").mkdir()
    dem = _dem(tmp_path / "in", _voids())
    calls = []
    real = windows.WindowLighting.light

    def light(self, *a, **k):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(self, *a, **k)
    monkeypatch.setattr(windows.WindowLighting, "light", light)
    r = CliRunner().invoke(cli, ["sun-hours", dem, str(tmp_path / "out" / "o.tif"), "--date",
                                 "2026-12-21", "--tz", TZ, "--window-size", "64"])
    assert r.exit_code == 130 and "no output written" in r.stderr
    assert len(calls) == 3 and os.listdir(tmp_path / "out") == []


@pytest.mark.slow       # a local cluster of two worker processes
def test_dask_gives_the_bits_of_the_run_in_memory(tmp_path):
    """Each region a task on two worker processes: the same bits, tags and description as in
    memory; the parts' folder gone."""
    pytest.importorskip("distributed")
    import rasterio
    dem = _dem(tmp_path, _voids())
    whole, rep = _hours(tmp_path, dem, "whole.tif")
    got, drep = _hours(tmp_path, dem, "dask.tif", window_size="64", scheduler="local:2")
    np.testing.assert_array_equal(got, whole)
    p = drep["processing"]
    assert p["mode"] == "dask" and p["workers"] == 2 and p["tasks"] == p["regions"] == 2 * 2
    assert drep["hours"]["min"] == rep["hours"]["min"]
    assert drep["hours"]["max"] == rep["hours"]["max"]
    with rasterio.open(tmp_path / "whole.tif") as a, rasterio.open(tmp_path / "dask.tif") as b:
        assert b.descriptions == a.descriptions and b.nodata == a.nodata
        assert {k: v for k, v in b.tags().items() if k != "AREA_OR_POINT"} == \
            {k: v for k, v in a.tags().items() if k != "AREA_OR_POINT"}
    assert sorted(os.listdir(tmp_path)) == ["dask.tif", "dem.tif", "whole.tif"]


# ---------------------------------------------------------------------------------------------
# --monthly in windows: each month's band the bits of the run in memory

def _monthly(tmp_path, dem, out, **kw):
    """Every band, the descriptions, the bands' tags, the file's tags and the report of
    ``dem``'s sun hours from 2027-01-30 to 2027-02-02 with --monthly (two months), every 70
    minutes at Zurich's clock."""
    import rasterio
    cfg = SunHoursConfig(dem=dem, output=str(tmp_path / out), date="2027-01-30",
                         end_date="2027-02-02", step="70min", place={"tz": TZ}, monthly=True,
                         run=RunOptions(overwrite=True, quiet=True), **kw)
    rep = sun_hours(cfg)
    with rasterio.open(tmp_path / out) as ds:
        tags = {k: v for k, v in ds.tags().items() if k != "AREA_OR_POINT"}
        return (ds.read(), ds.descriptions, [ds.tags(i) for i in range(1, ds.count + 1)],
                tags, rep)


def _same_monthly(got, want):
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1:4] == want[1:4]
    assert [m["month"] for m in got[4]["months"]] == ["2027-01", "2027-02"]
    for g, w in zip(got[4]["months"], want[4]["months"]):
        assert g["month"] == w["month"]
        assert g["hours"]["min"] == w["hours"]["min"] and g["hours"]["max"] == w["hours"]["max"]
        assert g["hours"]["mean"] == pytest.approx(w["hours"]["mean"], rel=1e-12)


@pytest.mark.parametrize("size", ["30x45", pytest.param("7x80", marks=pytest.mark.slow)])
def test_monthly_in_windows_gives_the_bits_of_the_run_in_memory(tmp_path, any_window, size):
    """--monthly in windows shorter than the pillar's shadow: the total and each month's band
    (its own float32 sum of its samples) equal the run in memory's, voids included; the
    months' bands differ from each other and add up to the total."""
    dem = _dem(tmp_path, _voids())
    whole = _monthly(tmp_path, dem, "whole.tif")
    got = _monthly(tmp_path, dem, "win.tif", window_size=size)
    _same_monthly(got, whole)
    assert whole[1][1:] == ("2027-01", "2027-02") and whole[0].shape[0] == 3
    bands = np.where(whole[0] == -9999.0, np.nan, whole[0])
    assert np.isnan(bands[1]).sum() == 4 * 25 + 20 * 3
    np.testing.assert_allclose(bands[1] + bands[2], bands[0], rtol=1e-6)
    assert np.nanmax(np.abs(bands[1] - bands[2])) > 0.5
    assert got[4]["processing"]["mode"] == "tiled" and got[4]["processing"]["regions"] > 4


def test_monthly_in_a_context_tile_in_windows(tmp_path, any_window):
    """--monthly for a --context tile in windows: the same cells of the whole DEM's run in
    memory, every band."""
    import rasterio
    dem = _dem(tmp_path, _voids())
    whole = _monthly(tmp_path, dem, "whole.tif")
    with rasterio.open(dem) as ds:
        w = ((17, 61), (30, 75))
        tile = write_geotiff(tmp_path / "tile.tif", ds.read(1, window=w),
                             ds.window_transform(w), ds.crs, -9999.0)
    got = _monthly(tmp_path, tile, "t.tif", read=ReadOptions(context=dem), window_size="20x25")
    np.testing.assert_array_equal(got[0], whole[0][:, 17:61, 30:75])
    assert got[1] == whole[1] and got[2] == whole[2]


@pytest.mark.slow       # a local cluster of two worker processes
def test_monthly_on_dask_gives_the_bits_of_the_run_in_memory(tmp_path):
    """--monthly, each region a task on two worker processes: every band, description and tag
    of the run in memory."""
    pytest.importorskip("distributed")
    dem = _dem(tmp_path, _voids())
    whole = _monthly(tmp_path, dem, "whole.tif")
    got = _monthly(tmp_path, dem, "dask.tif", window_size="64", scheduler="local:2")
    _same_monthly(got, whole)
    assert got[4]["processing"]["mode"] == "dask"
    assert sorted(os.listdir(tmp_path)) == ["dask.tif", "dem.tif", "whole.tif"]
