"""``run.report``'s progress, --progress json: the run's progress as lines of JSON on stderr (for programs such as the
QGIS plugin), instead of tqdm's bar."""

from __future__ import annotations

import io
import json

import pytest
from click.testing import CliRunner

from hillshade_rt.cli import cli
from hillshade_rt.run.report import PROGRESS_MODES, JsonProgress, progress, progress_total
from hillshade_rt.testing import data_path

DEM = data_path("lidar_dem_1m_utm15n_400x400.tif")


def fractions(text: str) -> list:
    return [json.loads(line)["progress"] for line in text.splitlines()
            if line.startswith('{"progress"')]


def test_json_progress_lines():
    out = io.StringIO()
    assert list(JsonProgress(list("abcd"), stream=out)) == list("abcd")
    assert fractions(out.getvalue()) == [0.25, 0.5, 0.75, 1.0]
    # counted by update(); a line only when the fraction (3 decimals) moves on
    out = io.StringIO()
    with JsonProgress(total=3000, stream=out) as bar:
        for _ in range(3000):
            bar.update(1)
    got = fractions(out.getvalue())
    assert got == sorted(set(got)) and got[-1] == 1.0 and len(got) == 1000
    # json whatever -q says; a single step still ends at 1.0
    assert isinstance(progress([1], True, "x", mode="json"), JsonProgress)
    assert isinstance(progress_total(1, True, "x", "w", mode="json"), JsonProgress)


def test_cli_declares_the_modes():
    from hillshade_rt.cli.options import PROGRESS_MODES as declared
    assert declared == PROGRESS_MODES


@pytest.mark.parametrize("args", [
    ["sun-hours", "--date", "2026-06-21", "--step", "2h"],
    ["shadow", "--start", "2026-06-21T08:00", "--end", "2026-06-21T16:00", "--step", "2h",
     "--tz", "America/Chicago"],
])
def test_cli_progress_json_multi_sun(tmp_path, args):
    """A run over many suns: increasing fractions on stderr, the last 1.0; no bar."""
    runner = CliRunner()
    res = runner.invoke(cli, [args[0], DEM, str(tmp_path / "o.tif"), *args[1:],
                              "--progress", "json"])
    assert res.exit_code == 0, res.output
    got = fractions(res.stderr)
    assert len(got) >= 4, res.stderr
    assert all(a < b for a, b in zip(got, got[1:])) and got[-1] == 1.0
    assert "it/s" not in res.stderr and "\r" not in res.stderr
    # --progress=json also parses; a bad mode is refused
    res = runner.invoke(cli, [args[0], DEM, str(tmp_path / "p.tif"), *args[1:],
                              "--progress=json", "-q"])
    assert res.exit_code == 0 and fractions(res.stderr)[-1] == 1.0
    assert runner.invoke(cli, [args[0], DEM, str(tmp_path / "q.tif"), *args[1:],
                               "--progress", "xml"]).exit_code == 2


def test_timer_excludes_a_stage_timed_inside():
    """``timer(stage, exclude=inner)``: the inner stage's seconds inside the block are not
    counted in the outer one too (a window's writes inside its compute)."""
    import time as _time

    from hillshade_rt.run.report import Timer
    t = Timer()
    with t("compute", exclude="write"):
        with t("write"):
            _time.sleep(0.05)
    assert t.seconds["write"] >= 0.05
    assert 0.0 <= t.seconds["compute"] < 0.04
    assert t.total() >= t.seconds["write"] + t.seconds["compute"]
