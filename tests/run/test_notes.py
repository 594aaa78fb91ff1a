"""run/notes.py: numba's "compiling" line (only for kernels not cached, only on the CPU) and
which algorithm notes are shown."""

import os

from hillshade_rt.algorithms import _jitcache
from hillshade_rt.run import notes


def test_compile_note_names_the_missing_kernels(monkeypatch):
    missing = {"pyramid", "relief"}
    monkeypatch.setattr(_jitcache, "cached", lambda m: m not in missing)
    monkeypatch.setattr(_jitcache, "cache_dir",
                        lambda: os.path.join(os.path.expanduser("~"), ".cache", "k"))
    line = notes.compile_note("brute", "cpu", relief=True)
    assert line == ("compiling the pyramid and relief kernels (first run only: cached in "
                    "~/.cache/k)")
    assert notes.compile_note("brute", "cpu") == ("compiling the pyramid kernels (first run "
                                                  "only: cached in ~/.cache/k)")
    assert notes.compile_note("smap", "cpu", relief=False) is None
    assert notes.compile_note("brute", "gpu", relief=True) is None


def test_compile_note_none_when_everything_is_cached(monkeypatch):
    monkeypatch.setattr(_jitcache, "cached", lambda m: True)
    assert notes.compile_note("auto", "cpu", relief=True) is None


def test_note_to_show():
    st = {"note": "the hull was replaced by the scan"}
    assert notes.note_to_show({}, "horizon", {}, True) is None
    assert notes.note_to_show(st, "horizon", {}, False) == st["note"]
    # smap marching like brute: said only when smap was asked for, by name or by its options
    assert notes.note_to_show(st, "smap", {}, False) is None
    assert notes.note_to_show(st, "smap", {}, True) == st["note"]
    assert notes.note_to_show(st, "smap", {"pyramid": False}, False) == st["note"]
