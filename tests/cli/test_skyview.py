"""cli/skyview.py, ``hillshade-rt skyview``: every option reaches ``run.config.SkyviewConfig``;
one DEM goes to ``run.skyview.skyview``, several (--each) to ``run.batch.skyview_each``. (The
factor itself: tests/run/test_skyview.py, tests/algorithms/test_skyview.py.)"""

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import ReadOptions, RunOptions, SkyviewConfig


def test_every_option_reaches_the_config(calls, runner):
    runs = calls("hillshade_rt.run.skyview", "skyview")
    r = runner.invoke(cli, [
        "skyview", "dem.tif", "out.tif", "--directions", "12", "--definition", "dozier",
        "--terrain-configuration", "--max-distance", "3000", "--earth-curvature",
        "--refraction-coefficient", "0.1", "--height-above-ground", "1.5", "--preview", "p.png",
        "--backend", "cpu", "--threads", "1", "--report", "r.json", "--max-memory", "3GB",
        "--window-size", "128", "--overwrite", "-q", "-f", "GTiff", "--co", "TILED=YES",
        "-z", "2", "--nodata", "-9999"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert isinstance(cfg, SkyviewConfig)
    assert (cfg.dem, cfg.output, cfg.directions, cfg.definition, cfg.terrain_configuration,
            cfg.openness) == ("dem.tif", "out.tif", 12, "dozier", True, None)
    assert (cfg.max_distance, cfg.curvature, cfg.refraction_k, cfg.height_above_ground) == (
        3000.0, True, 0.1, 1.5)
    assert (cfg.max_memory, cfg.window_size, cfg.scheduler) == ("3GB", "128", None)
    assert cfg.read == ReadOptions(z_factor=2.0, nodata=-9999.0)
    assert cfg.run == RunOptions(backend="cpu", threads=1, report_path="r.json", overwrite=True,
                                 quiet=True, fmt="GTiff", preview="p.png", say=say,
                                 creation_options={"TILED": "YES"})


def test_defaults_and_openness(calls, runner):
    runs = calls("hillshade_rt.run.skyview", "skyview")
    r = runner.invoke(cli, ["skyview", "dem.tif", "out.tif"])
    assert r.exit_code == 0, r.output
    cfg = runs.pop()[0]
    assert (cfg.directions, cfg.definition, cfg.terrain_configuration, cfg.openness,
            cfg.max_distance, cfg.height_above_ground) == (32, "zaksek", False, None, None, 0.0)
    assert cfg.read == ReadOptions() and cfg.run == RunOptions(say=say)
    r = runner.invoke(cli, ["skyview", "dem.tif", "out.tif", "--openness", "negative"])
    assert r.exit_code == 0, r.output
    assert runs.pop()[0].openness == "negative"


def test_each_goes_to_the_batch(calls, runner):
    runs = calls("hillshade_rt.run.skyview", "skyview")
    each = calls("hillshade_rt.run.batch", "skyview_each")
    r = runner.invoke(cli, ["skyview", "a.tif", "b.tif", "--each", "--output-pattern",
                            "{stem}_svf.tif", "--directions", "8"])
    assert r.exit_code == 0, r.output
    assert runs == []
    [(cfg, dems, pattern)] = each
    assert dems == ["a.tif", "b.tif"] and pattern == "{stem}_svf.tif" and cfg.directions == 8
