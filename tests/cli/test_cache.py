"""``hillshade-rt cache [--prune]``: numba's compiled kernels, and the stale ones removed
(``algorithms/_jitcache.survey`` and ``prune``), on files numba itself wrote."""

import os
import subprocess
import sys

import numba
import pytest

from hillshade_rt.algorithms import _jitcache
from hillshade_rt.cli import cli
from hillshade_rt.testing import repo_root

MODULE = """
import numba

{pad}@numba.njit(cache=True)
def twice(x):
    return 2 * x
"""


def _compile(pkg, cache, pad):
    """Write ``pkg/kern.py`` with ``twice`` ``pad`` lines down and let numba cache it (a fresh
    process: numba's cache as a user's run leaves it)."""
    (pkg / "kern.py").write_text(MODULE.format(pad="\n" * pad))
    code = f"import sys; sys.path.insert(0, {str(pkg.parent)!r}); import kpkg.kern as k; k.twice(3)"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    subprocess.run([sys.executable, "-c", code], env=env, check=True, timeout=300)


@pytest.mark.slow
def test_survey_and_prune_find_what_numba_left_stale(tmp_path, monkeypatch, runner):
    cache = tmp_path / "nc"
    pkg = tmp_path / "kpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    _compile(pkg, cache, 0)
    _compile(pkg, cache, 3)        # the function moved: a new index, the old one left behind
    sub = cache / _jitcache._numba_subfolder(str(pkg))
    files = sorted(os.listdir(sub))
    old = [f for f in files if "twice-4." in f]
    new = [f for f in files if "twice-7." in f]
    assert len(old) == 2 and len(new) == 2, files          # an .nbi and an .nbc each
    # other versions of our kernels, and garbage in this version's folder
    other = cache / "0123456789abcdef" / "algorithms_x"
    other.mkdir(parents=True)
    (other / "brute.f-1.py311.nbi").write_bytes(b"x" * 100)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(cache))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(cache))
    mine = cache / _jitcache.source_digest() / _jitcache._numba_subfolder(_jitcache._HERE)
    mine.mkdir(parents=True)
    (mine / "brute.gone-7.py311.nbi").write_bytes(b"truncated")
    (mine / "brute.gone-7.py311.1.nbc").write_bytes(b"data")
    not_numbas = cache / "notes"                 # not a digest: never touched
    not_numbas.mkdir()

    found = _jitcache.survey(str(pkg))
    assert found["root"] == str(cache)
    assert found["current"] == str(cache / _jitcache.source_digest())
    assert [p for p, _ in found["other_versions"]] == [str(cache / "0123456789abcdef")]
    assert found["other_versions"][0][1] == 100
    stale = sorted(os.path.basename(p) for p, _ in found["stale"])
    assert stale == sorted(old + ["brute.gone-7.py311.nbi", "brute.gone-7.py311.1.nbc"])

    r = runner.invoke(cli, ["cache"])
    assert r.exit_code == 0, r.output
    assert f"kernel cache: {cache}" in r.output
    assert "other versions' folders, stale: 1 (0.0 MB)" in r.output
    assert "stale files of this version, stale: 2" in r.output

    _jitcache.prune(str(pkg))
    assert sorted(os.listdir(sub)) == sorted(new)           # numba's fresh files kept
    assert not (cache / "0123456789abcdef").exists() and not_numbas.is_dir()
    assert os.listdir(mine) == []
    assert _jitcache.survey(str(pkg))["stale"] == []
    # what is left still loads: numba finds its fresh index (no new files written)
    _compile(pkg, cache, 3)
    assert sorted(os.listdir(sub)) == sorted(new)


def test_cache_prune_command(tmp_path, runner, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    (tmp_path / "fedcba9876543210").mkdir()
    (tmp_path / "fedcba9876543210" / "x.nbc").write_bytes(b"y" * 2_000_000)
    r = runner.invoke(cli, ["cache"])
    assert r.exit_code == 0
    assert "other versions' folders, stale: 1 (2.0 MB)" in r.output
    assert "hillshade-rt cache --prune removes them" in r.output
    r = runner.invoke(cli, ["cache", "--prune"])
    assert r.exit_code == 0 and "other versions' folders, removed: 1 (2.0 MB)" in r.output
    assert not (tmp_path / "fedcba9876543210").exists()
    r = runner.invoke(cli, ["cache"])
    assert "stale: 0 (0.0 MB)" in r.output and "--prune removes" not in r.output


def test_usage_documents_where_the_cache_is():
    doc = open(os.path.join(repo_root(), "docs", "usage.md"), encoding="utf-8").read()
    assert "hillshade-rt cache --prune" in doc and "NUMBA_CACHE_DIR" in doc
    assert "~/.cache/hillshade-rt/numba" in doc
