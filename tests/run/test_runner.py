"""run/runner.py: the skeleton every run shares: the claims before any work (outputs against
inputs and each other, the report and preview too), threads, the backend, the compile note
(not when quiet), the lines and the report at the end."""

import json

import numba
import pytest

from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.run import notes
from hillshade_rt.run.config import RunOptions
from hillshade_rt.run.runner import RunContext


def _ro(tmp_path, said, **kw):
    return RunOptions(say=lambda kind, msg: said.append((kind, msg)), **kw)


def test_outputs_report_and_preview_are_claimed(tmp_path):
    dem = tmp_path / "d.tif"
    dem.write_bytes(b"")
    said = []
    ro = _ro(tmp_path, said, report_path=str(tmp_path / "r.json"), backend="cpu")
    ctx = RunContext.start(ro, inputs=[str(dem)], outputs=[(str(tmp_path / "o.tif"), "OUTPUT"),
                                                           (None, "--distance")])
    assert [w for _, w in ctx.claims.paths] == ["OUTPUT", "--report"]
    with pytest.raises(UsageProblem, match="o.tif: --distance and OUTPUT name the same file"):
        ctx.claim(str(tmp_path / "o.tif"), "--distance")
    with pytest.raises(UsageProblem, match="d.tif: OUTPUT is also an input"):
        RunContext.start(RunOptions(backend="cpu", overwrite=True), inputs=[str(dem)],
                         outputs=[(str(dem), "OUTPUT")])
    with pytest.raises(HillshadeError, match="d.tif: already exists"):
        RunContext.start(RunOptions(backend="cpu"), outputs=[(str(dem), "OUTPUT")])
    with pytest.raises(UsageProblem, match="x: --preview and --report name the same file"):
        RunContext.start(RunOptions(backend="cpu", report_path=str(tmp_path / "x"),
                                    preview=str(tmp_path / "x")))


def test_threads_and_backend(tmp_path):
    before = numba.get_num_threads()
    try:
        ctx = RunContext.start(RunOptions(threads=1, backend="cpu"), algorithm=None)
        assert ctx.threads == 1 == numba.get_num_threads() and ctx.backend == "cpu"
        assert RunContext.start(RunOptions(backend="gpu"), backend=False).backend == "cpu"
    finally:
        numba.set_num_threads(before)


def test_the_compile_note_unless_quiet(monkeypatch, tmp_path):
    monkeypatch.setattr(notes, "compile_note",
                        lambda algorithm, backend, relief=False: f"compiling {algorithm} {relief}")
    said = []
    RunContext.start(_ro(tmp_path, said, backend="cpu"), algorithm="brute", relief=True)
    assert said == [("compile", "compiling brute True")]
    said.clear()
    RunContext.start(_ro(tmp_path, said, backend="cpu", quiet=True), algorithm="brute")
    RunContext.start(_ro(tmp_path, said, backend="cpu"), algorithm="brute", note=False)
    RunContext.start(_ro(tmp_path, said, backend="cpu"))
    assert said == []


def test_finish_writes_the_report_then_says_the_lines(tmp_path):
    said = []
    rep = tmp_path / "r.json"
    ctx = RunContext.start(_ro(tmp_path, said, backend="cpu", report_path=str(rep)))
    with ctx.timer("compute"):
        pass
    secs = ctx.seconds()
    assert set(secs) == {"compute", "total"} and secs["total"] >= secs["compute"] >= 0
    out = ctx.finish({"a": 1}, [("note", "first"), ("note", None), ("summary", "last")])
    assert out == {"a": 1} and json.loads(rep.read_text()) == {"a": 1}
    assert said == [("note", "first"), ("summary", "last")]
    quiet = []
    RunContext.start(_ro(tmp_path, quiet, backend="cpu", quiet=True)).finish(
        {}, [("summary", "x")])
    assert quiet == []


def test_an_output_with_checks_runs_in_its_turn(tmp_path):
    seen = []
    ro = RunOptions(report_path=str(tmp_path / "r.json"))

    def check(claims):
        seen.append([what for _, what in claims.paths])
        claims.claim(str(tmp_path / "item.json"), "--stac-item")
    ctx = RunContext.start(ro, outputs=[(str(tmp_path / "o.tif"), "OUTPUT"), check,
                                        (None, "unused")])
    assert seen == [["OUTPUT"]]
    assert [w for _, w in ctx.claims.paths] == ["OUTPUT", "--stac-item", "--report"]
