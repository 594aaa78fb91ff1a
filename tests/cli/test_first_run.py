"""The first run says it is compiling (issue 18, item 8): numba compiles kernels that are not in
its cache yet, seconds to a minute with nothing else on screen."""

import os

from hillshade_rt.algorithms import _jitcache
from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
SUN = ["--azimuth", "203.7", "--elevation", "12"]


def test_cli_says_once_that_it_compiles_and_quiet_says_nothing(tmp_path, runner, monkeypatch):
    from hillshade_rt.cli import errors as cli_errors
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "z.tif")] + SUN)
    assert "compiling" not in r.stderr        # not a terminal: logs keep their one line
    monkeypatch.setattr(cli_errors, "stderr_is_terminal", lambda: True)
    seen = []
    monkeypatch.setattr(_jitcache, "cached", lambda m: seen.append(m) or m != "bounds")
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "a.tif")] + SUN)
    assert r.exit_code == 0, r.output
    notes = [l for l in r.stderr.splitlines() if "compiling" in l]
    assert len(notes) == 1 and "bounds kernels (first run only" in notes[0]
    assert os.path.expanduser("~") not in notes[0] or "NUMBA_CACHE_DIR" in os.environ
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "b.tif"), "-q"] + SUN)
    assert r.exit_code == 0 and r.stderr == ""
    r = runner.invoke(cli, ["hillshade", LIDAR, str(tmp_path / "c.tif"), "--algorithm", "brute"])
    assert r.exit_code == 0 and "compiling" not in r.stderr     # brute and relief are cached
    assert "relief" in seen
