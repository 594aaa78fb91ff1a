"""run.runner: the preamble and tail every run shares."""

from __future__ import annotations

import json

import numba
import pytest

from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.run.config import RunOptions
from hillshade_rt.run.runner import RunContext


def _options(tmp_path, **kw):
    said = []
    ro = RunOptions(say=lambda kind, msg: said.append((kind, msg)), **kw)
    return ro, said


def test_start_claims_every_path_against_the_inputs(tmp_path):
    dem = tmp_path / "dem.tif"
    dem.write_bytes(b"x")
    ro, _ = _options(tmp_path, report_path=str(dem), overwrite=True)
    with pytest.raises(UsageProblem, match="--report is also an input"):
        RunContext.start(ro, inputs=[str(dem)], outputs=[(str(tmp_path / "o.tif"), "OUTPUT")])
    ro, _ = _options(tmp_path, preview=str(tmp_path / "o.tif"))
    with pytest.raises(UsageProblem, match="name the same file"):
        RunContext.start(ro, inputs=[str(dem)], outputs=[(str(tmp_path / "o.tif"), "OUTPUT")])


def test_an_output_with_checks_runs_in_its_turn(tmp_path):
    seen = []
    ro, _ = _options(tmp_path, report_path=str(tmp_path / "r.json"))

    def check(claims):
        seen.append([what for _, what in claims.paths])
        claims.claim(str(tmp_path / "item.json"), "--stac-item")
    ctx = RunContext.start(ro, outputs=[(str(tmp_path / "o.tif"), "OUTPUT"), check,
                                        (None, "unused")])
    assert seen == [["OUTPUT"]]
    assert [w for _, w in ctx.claims.paths] == ["OUTPUT", "--stac-item", "--report"]


def test_threads_and_backend(tmp_path):
    before = numba.get_num_threads()
    try:
        ro, _ = _options(tmp_path, threads=1, backend="cpu")
        ctx = RunContext.start(ro, algorithm="bounds")
        assert ctx.threads == 1 == numba.get_num_threads()
        assert ctx.backend == "cpu"
        ro, _ = _options(tmp_path, backend="auto")
        assert RunContext.start(ro, backend=False).backend == "cpu"
        ro, _ = _options(tmp_path, backend="sideways")
        with pytest.raises(HillshadeError, match="backend must be"):
            RunContext.start(ro, algorithm="bounds")
    finally:
        numba.set_num_threads(before)


def test_finish_writes_the_report_then_says_the_lines_in_order(tmp_path):
    report = tmp_path / "r.json"
    ro, said = _options(tmp_path, report_path=str(report))
    ctx = RunContext.start(ro, backend=False)
    with ctx.timer("compute"):
        pass
    rep = {"answer": 42, "seconds": ctx.seconds()}
    assert set(rep["seconds"]) == {"compute", "total"}
    out = ctx.finish(rep, [("note", "first"), ("summary", None), ("summary", "last")])
    assert out is rep
    assert json.loads(report.read_text())["answer"] == 42
    assert said == [("note", "first"), ("summary", "last")]


def test_quiet_says_nothing_but_writes_the_report(tmp_path):
    report = tmp_path / "r.json"
    ro, said = _options(tmp_path, report_path=str(report), quiet=True)
    ctx = RunContext.start(ro, algorithm="brute")
    ctx.finish({"a": 1}, [("summary", "x")])
    assert said == [] and report.exists()
