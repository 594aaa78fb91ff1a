"""cli/profile.py, ``hillshade-rt profile``: every option reaches ``run.config.ProfileConfig``
(the points parsed), which goes to ``run.profile.profile``. (The profiles:
tests/run/test_profile.py.)"""

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import ProfileConfig, ReadOptions, RunOptions


def test_every_option_reaches_the_config(calls, runner):
    runs = calls("hillshade_rt.run.profile", "profile")
    r = runner.invoke(cli, [
        "profile", "dem.tif", "--at", "7.5,46.25", "--at-xy", "400000,5000000", "--at-xy",
        "400030.5,4999970", "--points", "p.csv", "--height-above-ground", "2", "--step", "5",
        "--format", "pvgis", "-o", "o.txt", "--earth-curvature", "--refraction-coefficient",
        "0.1", "--preview", "p.png", "--report", "r.json", "--overwrite", "-q", "-z", "2"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert isinstance(cfg, ProfileConfig)
    assert cfg.dem == "dem.tif" and cfg.points == "p.csv" and cfg.at == [(7.5, 46.25)]
    assert cfg.at_xy == [(400000.0, 5000000.0), (400030.5, 4999970.0)]
    assert (cfg.height_above_ground, cfg.step, cfg.fmt, cfg.output) == (2.0, 5.0, "pvgis",
                                                                        "o.txt")
    assert (cfg.curvature, cfg.refraction_k) == (True, 0.1)
    assert cfg.read == ReadOptions(z_factor=2.0)
    assert cfg.run == RunOptions(report_path="r.json", overwrite=True, quiet=True,
                                 preview="p.png", say=say)


def test_defaults(calls, runner):
    runs = calls("hillshade_rt.run.profile", "profile")
    r = runner.invoke(cli, ["profile", "dem.tif", "--at", "7,46"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert (cfg.step, cfg.fmt, cfg.output, cfg.height_above_ground, cfg.curvature) == (
        1.0, "csv", None, 0.0, None)
    assert cfg.read == ReadOptions() and cfg.run == RunOptions(say=say)
