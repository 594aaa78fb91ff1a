"""cli/sun_hours.py, ``hillshade-rt sun-hours``: every option reaches ``run.SunHoursConfig``, one
DEM goes to ``run.sun_hours`` and several (--each) to ``run.batch.sun_hours_each``; its own
values are usage errors before the DEM is read."""

import os

import pytest

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import ReadOptions, SunHoursConfig


def test_every_option_reaches_the_config(calls, runner):
    runs = calls("hillshade_rt.run", "sun_hours")
    each = calls("hillshade_rt.run.batch", "sun_hours_each")
    r = runner.invoke(cli, [
        "sun-hours", "dem.tif", "out.tif", "--date", "2026-03-20", "--end-date", "2026-03-27",
        "--monthly", "--step", "7min", "--tz", "Europe/Zurich", "--lat", "46.5", "--lon", "7.9",
        "--pressure", "900", "--temperature", "5", "--no-refraction", "--sun-tolerance", "0.1",
        "--algorithm", "brute", "--earth-curvature", "--refraction-coefficient", "0.2", "--soft",
        "--height-above-ground", "1.7", "--no-self-shadow", "--preview", "p.png", "--backend",
        "cpu", "--threads", "2", "--report", "r.json", "--max-memory", "1GB", "--window-size",
        "512", "--overwrite", "-q", "-f", "netCDF", "--co", "COMPRESS=LZW", "-b", "2", "-z", "2",
        "--nodata", "-1"])
    assert r.exit_code == 0, r.output
    assert each == []
    [(cfg,)] = runs
    assert isinstance(cfg, SunHoursConfig)
    assert (cfg.dem, cfg.output, cfg.date, cfg.end_date, cfg.step, cfg.monthly) == (
        "dem.tif", "out.tif", "2026-03-20", "2026-03-27", "7min", True)
    assert cfg.place == {"tz": "Europe/Zurich", "lat": 46.5, "lon": 7.9, "pressure": 900.0,
                         "temperature": 5.0, "no_refraction": True, "sun_tolerance": 0.1}
    assert (cfg.algorithm, cfg.curvature, cfg.refraction_k, cfg.soft, cfg.self_shadow,
            cfg.height_above_ground) == ("brute", True, 0.2, True, False, 1.7)
    assert (cfg.max_memory, cfg.window_size, cfg.scheduler) == ("1GB", "512", None)
    assert cfg.read == ReadOptions(band=2, nodata=-1.0, z_factor=2.0)
    run = cfg.run
    assert (run.backend, run.threads, run.report_path, run.overwrite, run.quiet, run.fmt,
            run.preview, run.creation_options) == ("cpu", 2, "r.json", True, True, "netCDF",
                                                   "p.png", {"COMPRESS": "LZW"})
    assert run.say is say


def test_defaults_and_self_shadow(calls, runner):
    """Unset, --self-shadow is None (the run decides by the observer's height); given, it is
    what it says."""
    runs = calls("hillshade_rt.run", "sun_hours")
    for flag, want in (([], None), (["--self-shadow"], True), (["--no-self-shadow"], False)):
        r = runner.invoke(cli, ["sun-hours", "dem.tif", "out.tif", "--date", "2026-06-21"] + flag)
        assert r.exit_code == 0, r.output
        assert runs.pop()[0].self_shadow is want
    r = runner.invoke(cli, ["sun-hours", "dem.tif", "out.tif", "--date", "2026-06-21"])
    cfg = runs.pop()[0]
    assert (cfg.step, cfg.end_date, cfg.monthly, cfg.algorithm, cfg.height_above_ground) == (
        "10min", None, False, "auto", 0.0)
    assert cfg.read == ReadOptions() and cfg.run.overwrite is False and cfg.run.quiet is False


def test_each_goes_to_the_batch(calls, runner):
    runs = calls("hillshade_rt.run", "sun_hours")
    each = calls("hillshade_rt.run.batch", "sun_hours_each")
    r = runner.invoke(cli, ["sun-hours", "a.tif", "b.tif", "--each", "--output-pattern",
                            "o/{stem}_h.tif", "--date", "2026-03-20", "--step", "1h"])
    assert r.exit_code == 0, r.output
    assert runs == []
    [(cfg, dems, pattern)] = each
    assert dems == ["a.tif", "b.tif"] and cfg.dem == dems and cfg.output is None
    assert pattern == "o/{stem}_h.tif" and cfg.step == "1h"


@pytest.mark.parametrize("extra", [["--step", "abc"], ["--step", "0s"], ["--date", "21/06/2026"],
                                   ["--date", "2026-06-21T12:00"], ["--tz", "Mars/Olympus_Mons"],
                                   ["--end-date", "2026-06-20"]])
def test_sun_hours_options_are_usage_errors_before_the_dem_is_read(tmp_path, runner, extra):
    """Found by the fuzz test: sun-hours checked its step, date and zone after reading the DEM,
    so a bad value was exit 1 (or hidden behind a damaged input's error)."""
    bad = tmp_path / "damaged.tif"
    bad.write_bytes(b"II*\x00" + bytes(12))
    args = ["sun-hours", str(bad), str(tmp_path / "o.tif"), "--date", "2026-06-21"] + extra
    r = runner.invoke(cli, args)
    assert r.exit_code == 2, r.output
    assert r.stderr.strip().count("\n") == 0 and "damaged" not in r.stderr
    assert os.listdir(tmp_path) == ["damaged.tif"]
