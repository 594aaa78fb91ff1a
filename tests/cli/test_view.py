"""cli/view.py, ``hillshade-rt view``: its options reach ``run.config.ViewConfig``, which goes to
``run.view.view``. (The viewer: tests/run/test_view*.py.)"""

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import ReadOptions, ViewConfig


def test_every_option_reaches_the_config(calls, runner):
    runs = calls("hillshade_rt.run.view", "view")
    r = runner.invoke(cli, ["view", "dem.tif", "--port", "8123", "--no-browser", "--tz",
                            "Europe/Paris", "--algorithm", "brute", "--backend", "cpu", "-b", "2",
                            "-z", "3"])
    assert r.exit_code == 0, r.output
    assert runs == [(ViewConfig(dem="dem.tif", read=ReadOptions(band=2, z_factor=3.0),
                                port=8123, open_browser=False, algorithm="brute", backend="cpu",
                                tz="Europe/Paris", say=say),)]


def test_defaults_open_the_browser(calls, runner):
    runs = calls("hillshade_rt.run.view", "view")
    r = runner.invoke(cli, ["view", "dem.tif"])
    assert r.exit_code == 0, r.output
    assert runs == [(ViewConfig(dem="dem.tif", read=ReadOptions(), port=0, open_browser=True,
                                algorithm="auto", backend="auto", tz=None, say=say),)]
