"""hillshade-rt inside rasterio's ``rio`` (``rasterio.rio_plugins`` entry points,
``hillshade_rt/cli/rio.py``): run through the environment's own ``rio`` script, as a user would."""

import os
import subprocess
import sys
from importlib.metadata import entry_points

import numpy as np
import pytest
import rasterio

from hillshade_rt.cli import cli
from hillshade_rt.cli import rio as plugin
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
BIN = os.path.dirname(sys.executable)
TOP = {"shadow", "hillshade", "sun-hours", "horizon", "skyview", "irradiance"}


def run(program, *args):
    exe = os.path.join(BIN, program)
    if not os.path.exists(exe):
        pytest.fail(f"{exe} is missing: the package is installed without its scripts")
    return subprocess.run([exe, *map(str, args)], capture_output=True, text=True, timeout=300)


def commands_listed(help_text: str) -> set[str]:
    lines = help_text.split("Commands:", 1)[1].splitlines()
    return {ln.split()[0] for ln in lines if ln.startswith("  ") and ln.split()}


def test_rio_help_lists_the_commands_and_keeps_rios_own():
    r = run("rio", "--help")
    assert r.returncode == 0, r.stderr
    listed = commands_listed(r.stdout)
    assert TOP | {"hillshade-rt"} <= listed
    assert "Warning: could not load plugin" not in r.stdout      # click-plugins' broken entry
    # rio's own `info` is still rasterio's, ours is under the group
    info = [ln for ln in r.stdout.splitlines() if ln.startswith("  info ")]
    assert info and "Print information about a data file" in info[0]
    group = run("rio", "hillshade-rt", "--help")
    assert group.returncode == 0
    assert commands_listed(group.stdout) == set(cli.commands)


def test_no_plugin_takes_the_name_of_a_rio_command():
    """click-plugins adds rio's own commands first, then the plugins: a plugin of the same name
    would replace rio's. Ours are named apart from every command rasterio declares."""
    ours = {ep.name for ep in entry_points(group="rasterio.rio_plugins")
            if ep.value.startswith("hillshade_rt.")}
    assert ours == TOP | {"hillshade-rt"}
    rios = {ep.name for ep in entry_points(group="rasterio.rio_commands")}
    assert {"info", "shapes", "warp"} <= rios and not ours & rios
    for ep in entry_points(group="rasterio.rio_plugins"):
        if ep.name in ours:
            assert ep.load().name == ep.name


def test_the_plugin_commands_are_ours_not_copies():
    """The same parameter objects (one declaration of each option), callback and subcommands."""
    assert plugin.shadow.params is cli.commands["shadow"].params
    assert plugin.shadow.callback is cli.commands["shadow"].callback
    assert plugin.sun_hours.params is cli.commands["sun-hours"].params
    assert plugin.hillshade_rt.commands is cli.commands
    assert plugin.hillshade_rt.name == "hillshade-rt" and cli.name != "hillshade-rt"   # a view
    assert isinstance(plugin.shadow, type(cli.commands["shadow"]))


def _tags(path):
    with rasterio.open(path) as ds:
        drop = lambda tags: {k: v for k, v in tags.items() if "TIME" not in k}   # noqa: E731
        return (ds.read(), ds.profile, drop(ds.tags()),
                [drop(ds.tags(b)) for b in range(1, ds.count + 1)],
                ds.descriptions)


@pytest.mark.slow
def test_rio_shadow_writes_what_hillshade_rt_shadow_writes(tmp_path):
    sun = ["--azimuth", "203.7", "--elevation", "8"]
    a, b = tmp_path / "rio.tif", tmp_path / "ours.tif"
    r = run("rio", "shadow", LIDAR, a, *sun)
    assert r.returncode == 0, r.stderr
    assert "in shadow" in r.stderr                 # the same summary line
    r = run("hillshade-rt", "shadow", LIDAR, b, *sun)
    assert r.returncode == 0, r.stderr
    pa, pb = _tags(a), _tags(b)
    assert np.array_equal(pa[0], pb[0])
    assert 0 < (pa[0] == 1).sum() < pa[0].size       # a mask with shadow and light
    assert pa[1:] == pb[1:]
    assert pa[2]["VALUES"] == "1=shadow 0=lit 255=nodata"


@pytest.mark.parametrize("args, status, words", [
    (["shadow", LIDAR, "OUT.tif", "--azimuth", "10", "--elevation", "5", "--no-such-flag"], 2,
     "No such option '--no-such-flag'"),
    (["shadow", LIDAR, "OUT.tif", "--azimuth", "10", "--elevation", "100"], 2, "--elevation"),
    (["hillshade-rt", "shadow", LIDAR, "OUT.tif", "--azimuth", "x"], 2, "--azimuth"),
    (["hillshade-rt", "no-such-command"], 2, "No such command"),
    (["sun-hours", "missing-dem.tif", "OUT.tif", "--date", "2026-06-21"], 1, "missing-dem.tif"),
])
def test_errors_inside_rio_are_one_line_with_our_status(tmp_path, args, status, words):
    args = [str(tmp_path / a) if a == "OUT.tif" else a for a in args]
    r = run("rio", *args)
    assert r.returncode == status, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hillshade-rt: error: "), r.stderr
    assert words in lines[0] and "Traceback" not in r.stderr
    assert not (tmp_path / "OUT.tif").exists()
    if status == 2:
        assert "--help')" in lines[0] and "rio " in lines[0]


@pytest.mark.parametrize("raised, status, words", [
    (KeyboardInterrupt(), 130, "interrupted (SIGINT); no output written"),
    (ZeroDivisionError("boom"), 1, "internal error (ZeroDivisionError: boom)"),
])
def test_a_run_stopped_inside_another_group_is_one_line(tmp_path, monkeypatch, raised, status,
                                                        words):
    """In a plain click group, as rio's: an interrupt and a bug in a run end as they do in
    hillshade-rt (130 and 1, one line), not as click's 'Aborted!' or a traceback."""
    import click
    from click.testing import CliRunner

    import hillshade_rt.run as run

    def shade(config):
        raise raised
    monkeypatch.setattr(run, "shade", shade)
    monkeypatch.delenv("HILLSHADE_RT_DEBUG", raising=False)

    @click.group()
    def other():
        pass
    other.add_command(plugin.shadow)
    r = CliRunner().invoke(other, ["shadow", LIDAR, str(tmp_path / "m.tif"), "--azimuth", "10",
                                   "--elevation", "5"])
    assert r.exit_code == status
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], r.stderr
