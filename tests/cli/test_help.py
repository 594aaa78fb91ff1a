"""The help texts: each command's --tz speaks of that command, query's --time of rows,
view's --tz says its default, and the lighting commands list the algorithm internals after the
everyday options, under their own heading."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from hillshade_rt.cli import cli

TZ_COMMANDS = ["shadow", "hillshade", "query", "sun-hours", "irradiance", "animate", "view"]


def help_of(command: str) -> str:
    r = CliRunner().invoke(cli, [command, "--help"], prog_name="hillshade-rt", terminal_width=200)
    assert r.exit_code == 0, r.output
    return r.output


def option_help(command: str, name: str) -> str:
    """The help text of ``command``'s option ``name`` (its parameter name)."""
    param = next(p for p in cli.commands[command].params if p.name == name)
    return " ".join(param.help.split())


@pytest.mark.parametrize("command", TZ_COMMANDS)
def test_tz_help_speaks_of_its_own_command(command):
    text = option_help(command, "tz")
    others = [c for c in TZ_COMMANDS if c != command]
    for other in others:
        assert f"{other}:" not in text and (other != "sun-hours" or "sun-hours" not in text), \
            (command, text)
    assert "default" in text


def test_tz_help_of_each_sun_command():
    assert "sun-hours" not in option_help("shadow", "tz")
    assert "midnight" not in option_help("shadow", "tz")
    assert "offset" in option_help("shadow", "tz")
    assert "midnight to midnight" in option_help("sun-hours", "tz")
    assert "label" in option_help("animate", "tz")
    assert "rows" in option_help("query", "tz")


def test_query_time_promises_rows_not_bands():
    text = option_help("query", "time")
    assert "band" not in text and "row" in text
    assert "band" in option_help("shadow", "time")


def test_view_tz_default_is_clear():
    text = option_help("view", "tz")
    assert "(default, or" not in text
    assert "default: 'auto', the zone of the DEM's centre" in text


INTERNALS = ["--nextv", "--better-nextv", "--exact-steps", "--sample-spacing",
             "--horizon-method", "--no-pyramid", "--sun-tolerance", "--window-size",
             "--max-memory"]
EVERYDAY = ["--azimuth", "--elevation", "--time", "--tz", "--algorithm", "--soft", "--classes",
            "--self-shadow", "--preview", "--overwrite", "--nodata", "--help"]


def _lines_of(text, flag):
    return [i for i, line in enumerate(text.splitlines())
            if line.lstrip().startswith(flag + " ") or line.lstrip().startswith(flag + ",")
            or line.strip() == flag or f", {flag} " in line or line.rstrip().endswith(f", {flag}")]


def test_shadow_help_lists_internals_last_under_a_heading():
    text = help_of("shadow")
    lines = text.splitlines()
    assert lines.count("Options:") == 1 and lines.count("Algorithm internals:") == 1
    opts, internals = lines.index("Options:"), lines.index("Algorithm internals:")
    assert opts < internals
    for flag in INTERNALS:
        at = _lines_of(text, flag)
        assert at and all(i > internals for i in at), (flag, at)
    for flag in EVERYDAY:
        at = _lines_of(text, flag)
        assert at and all(opts < i < internals for i in at), (flag, at)


@pytest.mark.parametrize("command", ["hillshade", "query", "sun-hours", "irradiance", "animate",
                                     "horizon", "skyview", "illumination"])
def test_other_commands_keep_tuning_after_the_everyday_options(command):
    text = help_of(command)
    lines = text.splitlines()
    assert "Options:" in lines
    if "Algorithm internals:" in lines:
        internals = lines.index("Algorithm internals:")
        assert lines.index("Options:") < internals
        assert all(i > internals for i in _lines_of(text, "--sun-tolerance"))
        assert all(i < internals for i in _lines_of(text, "--help"))


def test_every_command_has_help():
    for name in cli.commands:
        assert help_of(name).startswith("Usage: hillshade-rt " + name)
