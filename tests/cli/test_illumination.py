"""cli/illumination.py, ``hillshade-rt illumination``: every option reaches
``run.config.IllumConfig``, which goes to ``run.illumination.illumination``. (The run:
tests/run/test_illumination.py.)"""

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import IllumConfig, ReadOptions, RunOptions


def test_every_option_reaches_the_config(calls, runner):
    runs = calls("hillshade_rt.run.illumination", "illumination")
    r = runner.invoke(cli, [
        "illumination", "dem.tif", "out.tif", "--subsolar-file", "s.csv", "--sun-distance",
        "1.5e11", "--body", "moon", "--height-above-ground", "2", "--earth-curvature",
        "--refraction-coefficient", "0", "--soft", "--preview", "p.png", "--max-memory", "1GB",
        "--window-size", "300", "--backend", "cpu", "--threads", "2", "--report", "r.json",
        "--overwrite", "-q", "-f", "GTiff", "--co", "TILED=YES", "-z", "2", "-b", "3"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert isinstance(cfg, IllumConfig)
    assert (cfg.files, cfg.subsolar_file, cfg.sun_distance, cfg.body) == (
        ["dem.tif", "out.tif"], "s.csv", 1.5e11, "moon")
    assert (cfg.height_above_ground, cfg.curvature, cfg.refraction_k, cfg.soft) == (
        2.0, True, 0.0, True)
    assert (cfg.max_memory, cfg.window_size, cfg.scheduler) == ("1GB", "300", None)
    assert cfg.read == ReadOptions(z_factor=2.0, band=3)
    assert cfg.run == RunOptions(backend="cpu", threads=2, report_path="r.json", overwrite=True,
                                 quiet=True, fmt="GTiff", preview="p.png", say=say,
                                 creation_options={"TILED": "YES"})


def test_defaults(calls, runner):
    runs = calls("hillshade_rt.run.illumination", "illumination")
    r = runner.invoke(cli, ["illumination", "dem.tif", "out.tif", "--subsolar-file", "s.csv"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert (cfg.sun_distance, cfg.body, cfg.height_above_ground, cfg.soft, cfg.curvature) == (
        None, None, 0.0, False, None)
    assert cfg.read == ReadOptions() and cfg.run == RunOptions(say=say)
