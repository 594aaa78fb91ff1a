"""cli/horizon.py, ``hillshade-rt horizon``: every option reaches ``run.HorizonConfig``; one DEM
goes to ``run.horizon``, several (--each) to ``run.batch.horizon_each``. (The angles themselves:
tests/run/test_horizon.py, tests/algorithms/test_horizon.py.)"""

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import HorizonConfig, ReadOptions, RunOptions


def test_every_option_reaches_the_config(calls, runner):
    runs = calls("hillshade_rt.run", "horizon")
    r = runner.invoke(cli, [
        "horizon", "dem.tif", "out.tif", "--start", "10", "--end", "200", "--step", "15",
        "--angle-unit", "radians", "--distance", "d.tif", "--method", "hull",
        "--sample-spacing", "3", "--max-distance", "5000", "--earth-curvature",
        "--refraction-coefficient", "0.1", "--height-above-ground", "2", "--preview", "p.png",
        "--backend", "cpu", "--threads", "3", "--report", "r.json", "--max-memory", "2GB",
        "--window-size", "256", "--overwrite", "-q", "--progress", "json", "-f", "GTiff",
        "--co", "TILED=YES", "-z", "3", "--pixel-size", "5"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert isinstance(cfg, HorizonConfig)
    assert (cfg.dem, cfg.output, cfg.azimuth, cfg.directions) == ("dem.tif", "out.tif", None, None)
    assert (cfg.start, cfg.end, cfg.step, cfg.angle_unit) == (10.0, 200.0, 15.0, "radians")
    assert (cfg.distance, cfg.method, cfg.sample_spacing, cfg.max_distance) == (
        "d.tif", "hull", 3, 5000.0)
    assert (cfg.curvature, cfg.refraction_k, cfg.height_above_ground) == (True, 0.1, 2.0)
    assert (cfg.max_memory, cfg.window_size, cfg.scheduler) == ("2GB", "256", None)
    assert cfg.read == ReadOptions(z_factor=3.0, pixel_size="5")
    assert cfg.run == RunOptions(backend="cpu", threads=3, report_path="r.json", overwrite=True,
                                 quiet=True, progress="json", fmt="GTiff", preview="p.png",
                                 say=say, creation_options={"TILED": "YES"})


def test_azimuth_or_directions(calls, runner):
    runs = calls("hillshade_rt.run", "horizon")
    for args, want in ((["--azimuth", "203.7"], (203.7, None)), (["--directions", "24"],
                                                                  (None, 24))):
        r = runner.invoke(cli, ["horizon", "dem.tif", "out.tif"] + args)
        assert r.exit_code == 0, r.output
        cfg = runs.pop()[0]
        assert (cfg.azimuth, cfg.directions) == want
        assert (cfg.method, cfg.sample_spacing, cfg.angle_unit, cfg.curvature) == (
            "scan", 1, "degrees", None)
        assert cfg.read == ReadOptions() and cfg.run == RunOptions(say=say)


def test_each_goes_to_the_batch(calls, runner):
    runs = calls("hillshade_rt.run", "horizon")
    each = calls("hillshade_rt.run.batch", "horizon_each")
    r = runner.invoke(cli, ["horizon", "a.tif", "b.tif", "c.tif", "--each", "--output-pattern",
                            "{stem}_hz.tif", "--azimuth", "90"])
    assert r.exit_code == 0, r.output
    assert runs == []
    [(cfg, dems, pattern)] = each
    assert dems == ["a.tif", "b.tif", "c.tif"] and pattern == "{stem}_hz.tif"
    assert cfg.azimuth == 90.0
