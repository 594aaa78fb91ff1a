"""cli/options.py: options declared once: the DEM options checked while the command line is
parsed (exit status 2), finite numbers, the algorithm flags from the registry, the configs built
from the parsed options, what was given, and the command line as a STAC item records it."""

import json

import click
import pytest
from click.testing import CliRunner

from hillshade_rt.algorithms import OPTIONS
from hillshade_rt.cli import options


def _command(*decorators):
    """A command echoing what the helpers make of its options (JSON)."""
    def run(**kw):
        out = {"given_band": options.given("band"), "given_none": options.given("no-such"),
               "line": options.command_line()}
        ro = options.to_read_options(kw)
        out["read"] = [ro.band, ro.nodata, ro.z_factor, ro.pixel_size, ro.raw_shape,
                       ro.context]
        out["left"] = sorted(kw)
        click.echo(json.dumps(out))
    f = run
    for d in reversed(decorators):
        f = d(f)
    return click.command("cmd")(f)


def _invoke(cmd, args):
    return CliRunner().invoke(cmd, args)


def test_dem_options_become_read_options():
    cmd = _command(click.argument("dem"), options.dem_options,
                   click.option("--azimuth", type=float, callback=options.finite))
    r = _invoke(cmd, ["d.tif", "--bidx", "2", "--nodata", "-9999", "-z", "0.3048",
                      "--pixel-size", "30,25", "--azimuth", "203.7"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.output)
    assert out["read"] == [2, -9999.0, 0.3048, "30,25", None, None]
    assert out["left"] == ["azimuth", "dem"] and out["given_band"] and out["given_none"]
    assert out["line"] == "cmd d.tif --band 2 --nodata -9999.0 --z-factor 0.3048 " \
                          "--pixel-size 30,25 --azimuth 203.7"
    r = _invoke(cmd, ["d.tif"])
    assert json.loads(r.output)["given_band"] is False


@pytest.mark.parametrize("args, words", [
    (["--pixel-size", "-3"], "--pixel-size must be one or two positive numbers"),
    (["--raw-shape", "12"], "--raw-shape must be ROWSxCOLS"),
    (["-z", "0"], "--z-factor must be a finite non-zero number"),
    (["--azimuth", "nan"], "must be a finite number, got nan"),
    (["--band", "0"], "Error: Invalid value for '-b'"),
])
def test_bad_values_are_usage_errors(args, words):
    cmd = _command(click.argument("dem"), options.dem_options,
                   click.option("--azimuth", type=float, callback=options.finite))
    r = _invoke(cmd, ["d.tif", *args])
    assert r.exit_code == 2 and words in r.output, r.output


def test_algorithm_flags_are_the_registrys():
    @click.command()
    @options.algorithm_flags
    def cmd(**kw):
        click.echo(json.dumps(sorted(k for k, v in kw.items() if v is not None)))
    flags = {p.opts[0] for p in cmd.params}
    assert flags == {opt.flag for _, opt in OPTIONS.values()}
    assert json.loads(_invoke(cmd, []).output) == []
    choice = next(opt for _, opt in OPTIONS.values() if opt.kind == "choice")
    r = _invoke(cmd, [choice.flag, choice.choices[-1]])
    assert json.loads(r.output) == [choice.param]
    assert _invoke(cmd, [choice.flag, "no-such-choice"]).exit_code == 2


def test_to_run_options_takes_what_is_there():
    say = []
    kw = {"backend": "cpu", "threads": 2, "quiet": True, "creation_options": ("COMPRESS=ZSTD",),
          "worker_timeout": 5.0, "other": 1}
    ro = options.to_run_options(kw, lambda k, m: say.append((k, m)))
    assert (ro.backend, ro.threads, ro.quiet, ro.worker_timeout) == ("cpu", 2, True, 5.0)
    assert ro.creation_options == {"COMPRESS": "ZSTD"} and kw == {"other": 1}
    ro.say("note", "hello")
    assert say == [("note", "hello")]


def test_outside_click():
    assert options.command_line() is None and options.given("band")
