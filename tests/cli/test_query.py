"""cli/query.py, ``hillshade-rt query``: every option reaches ``run.config.QueryConfig`` (the
points parsed, the sun's options together), which goes to ``run.query.query``. (The answers:
tests/run/test_query.py.)"""

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import SUN_KEYS, QueryConfig, ReadOptions, RunOptions


def test_every_option_reaches_the_config(calls, runner):
    runs = calls("hillshade_rt.run.query", "query")
    r = runner.invoke(cli, [
        "query", "dem.tif", "--at", "7.5,46.25", "--at", "8, 47", "--at-xy", "400000,5000000",
        "--points", "p.csv", "--azimuth", "120", "--elevation", "20", "--tz", "UTC", "--lat",
        "46", "--lon", "7", "--pressure", "90000", "--temperature", "3", "--no-refraction",
        "--sun-tolerance", "0.3", "--height-above-ground", "1.7", "--irradiance", "--format",
        "json", "-o", "o.json", "--earth-curvature", "--refraction-coefficient", "0.1",
        "--report", "r.json", "--overwrite", "-q", "-z", "2", "--light-position", "1,2,3"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert isinstance(cfg, QueryConfig)
    assert cfg.dem == "dem.tif" and cfg.points == "p.csv"
    assert cfg.at == [(7.5, 46.25), (8.0, 47.0)] and cfg.at_xy == [(400000.0, 5000000.0)]
    assert set(cfg.sun) == set(SUN_KEYS)
    assert {k: cfg.sun[k] for k in ("azimuth", "elevation", "time", "start", "tz", "lat", "lon",
                                    "pressure", "temperature", "no_refraction",
                                    "sun_tolerance")} == {
        "azimuth": 120.0, "elevation": 20.0, "time": (), "start": None, "tz": "UTC",
        "lat": 46.0, "lon": 7.0, "pressure": 90000.0, "temperature": 3.0,
        "no_refraction": True, "sun_tolerance": 0.3}
    assert (cfg.height_above_ground, cfg.irradiance, cfg.fmt, cfg.output) == (
        1.7, True, "json", "o.json")
    assert (cfg.curvature, cfg.refraction_k, cfg.light_position, cfg.light_lonlat) == (
        True, 0.1, "1,2,3", None)
    assert cfg.read == ReadOptions(z_factor=2.0)
    assert cfg.run == RunOptions(report_path="r.json", overwrite=True, quiet=True, say=say)


def test_times_and_defaults(calls, runner):
    runs = calls("hillshade_rt.run.query", "query")
    r = runner.invoke(cli, ["query", "dem.tif", "--at-xy", "1,2", "--time", "2026-06-21T12:00Z",
                            "--time", "2026-06-21T15:00Z"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert cfg.sun["time"] == ("2026-06-21T12:00Z", "2026-06-21T15:00Z")
    assert cfg.sun["azimuth"] is None and cfg.at == [] and cfg.at_xy == [(1.0, 2.0)]
    assert (cfg.fmt, cfg.output, cfg.irradiance, cfg.height_above_ground) == (
        None, None, False, 0.0)
    assert cfg.read == ReadOptions() and cfg.run == RunOptions(say=say)


def test_a_point_that_is_not_two_numbers_is_a_usage_error(calls, runner):
    runs = calls("hillshade_rt.run.query", "query")
    for flag in ("--at", "--at-xy"):
        r = runner.invoke(cli, ["query", "dem.tif", flag, "7.5;46", "--azimuth", "1",
                                "--elevation", "2"])
        assert r.exit_code == 2, r.output
        assert f"{flag} must be two numbers A,B, got '7.5;46'" in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1
    assert runs == []
