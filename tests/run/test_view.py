"""hillshade-rt view, the command: it serves until Ctrl-C (exit 130, one line), its errors are
one line, a bad --tz or --port is a usage error."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import urllib.request

from hillshade_rt.testing import data_path

DEM = data_path("everest_srtm3_voids_crop200.tif")     # EPSG:4326, 19.5 % voids


def test_cli_serves_and_stops_on_ctrl_c(tmp_path):
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    p = subprocess.Popen([sys.executable, "-m", "hillshade_rt", "view", DEM, "--no-browser"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        line = p.stdout.readline()
        assert "http://127.0.0.1:" in line, (line, p.stderr.read() if p.poll() is not None else "")
        url = line.split("at ", 1)[1].split()[0]
        with urllib.request.urlopen(url + "api/info", timeout=60) as r:
            assert json.loads(r.read())["rows"] == 200
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 130
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert "interrupted" in err


def test_cli_errors_are_one_line(tmp_path):
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    r = CliRunner().invoke(cli, ["view", str(tmp_path / "none.tif"), "--no-browser"])
    assert r.exit_code == 1 and len(r.output.strip().splitlines()) == 1
    r = CliRunner().invoke(cli, ["view", DEM, "--port", "70000"])
    assert r.exit_code == 2


def test_cli_unknown_zone_is_a_usage_error():
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    r = CliRunner().invoke(cli, ["view", DEM, "--no-browser", "--tz", "Mars/Olympus"])
    assert r.exit_code == 2 and "not an IANA time zone" in r.output
