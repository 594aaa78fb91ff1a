"""cli/group.py: the ``hillshade-rt`` group holds every command module's command, and ``run``
runs one command line in this process to its exit status (what ``cli.main`` and a server's
worker use)."""

import click
import pytest

from hillshade_rt.cli import group
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")


def test_the_group_holds_every_command_module():
    """Each module of cli/ that declares a click command has it in the group, under its own
    name (a new command module not added would be invisible)."""
    import importlib
    import pkgutil

    from hillshade_rt import cli as package
    declared = []
    for info in pkgutil.iter_modules(package.__path__):
        module = importlib.import_module(f"{package.__name__}.{info.name}")
        declared += [obj for obj in vars(module).values() if isinstance(obj, click.Command)
                     and getattr(obj.callback, "__module__", None) == module.__name__]
    subcommands = [c for g in declared if isinstance(g, click.Group) and g is not group.cli
                   for c in g.commands.values()]
    declared = {c.name: c for c in declared
                if c is not group.cli and all(c is not s for s in subcommands)}
    assert {"shadow", "hillshade", "sun-hours", "horizon", "skyview", "irradiance", "info",
            "query", "profile", "view", "illumination", "animate", "cache",
            "serve"} <= set(declared)
    assert group.cli.commands == declared


def test_run_returns_0_for_a_run_that_succeeds(capsys):
    assert group.run(["info", LIDAR, "--json"]) == 0
    out = capsys.readouterr()
    assert '"shape": [\n    400,\n    400\n  ]' in out.out and out.err == ""


def test_run_returns_1_for_a_failed_run_and_2_for_a_malformed_line(tmp_path, capsys):
    assert group.run(["info", str(tmp_path / "missing.tif")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("hillshade-rt: error: ") and "missing.tif" in err
    assert err.count("\n") == 1
    assert group.run(["info"]) == 2
    assert "Missing argument 'DEM'" in capsys.readouterr().err
    assert group.run(["no-such-command"]) == 2
    assert "No such command 'no-such-command'" in capsys.readouterr().err


@pytest.mark.parametrize("code, status, said", [(None, 0, ""), (0, 0, ""), (3, 3, ""),
                                                  (130, 130, ""), ("a reason", 1, "a reason\n")])
def test_run_turns_any_exit_into_a_status(monkeypatch, capsys, code, status, said):
    """SystemExit's code as the status: None is 0, a number itself, anything else is said on
    stderr and is 1."""
    def main(*args, **kwargs):
        raise SystemExit(code)
    monkeypatch.setattr(group.cli, "main", main)
    assert group.run(["anything"]) == status
    assert capsys.readouterr().err == said


def test_run_without_arguments_reads_sys_argv(monkeypatch, capsys):
    monkeypatch.setattr("sys.argv", ["hillshade-rt", "info", LIDAR, "--json"])
    assert group.run() == 0
    assert '"crs": "EPSG:26915"' in capsys.readouterr().out
