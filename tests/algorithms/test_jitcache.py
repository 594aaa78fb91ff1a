"""algorithms/_jitcache.py: the kernels' numba cache. ``njit`` caches every kernel in this
version's folder (a digest of algorithms/*.py) and lists it in ``KERNELS``, which names every
kernel of the package; ``loadable`` and ``cached`` read numba's own index for this install;
``stale_files`` tells what numba would never load again. (The warm-up that fills the cache:
tests/test_warm.py; ``hillshade-rt cache``: tests/cli/test_cache.py.)"""

import ast
import hashlib
import importlib
import os
import pickle
import shutil
import subprocess
import sys

import numba
import pytest

from hillshade_rt.algorithms import _jitcache

TIMEOUT = 900
PACKAGE = os.path.dirname(os.path.dirname(_jitcache.__file__))


def _python(code_or_args, env, cwd=None):
    args = code_or_args if isinstance(code_or_args, list) else ["-c", code_or_args]
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=TIMEOUT)


def _jitted(path):
    """(qualified name, decorator options) of each function of the source file ``path``
    decorated with a ``njit``/``jit`` (bare or called, any module's)."""
    with open(path, encoding="utf-8") as fh:
        tree = ast.parse(fh.read(), path)

    def walk(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.ClassDef)):
                name = prefix + child.name
                for d in getattr(child, "decorator_list", []):
                    call = d if isinstance(d, ast.Call) else None
                    f = call.func if call else d
                    if (f.id if isinstance(f, ast.Name) else getattr(f, "attr", None)) in (
                            "njit", "jit"):
                        yield name, {k.arg: ast.literal_eval(k.value)
                                     for k in (call.keywords if call else [])}
                inner = ".<locals>." if isinstance(child, ast.FunctionDef) else "."
                yield from walk(child, name + inner)
            else:
                yield from walk(child, prefix)
    yield from walk(tree, "")


def test_kernels_lists_every_kernel_of_the_package():
    """Every function of the package's sources decorated with ``njit(cache=True)`` is in
    ``KERNELS`` (the warm-up compiles what is listed there, and ``cached`` looks there), with
    the ``njit`` of this module (numba's own would cache outside the digest folder); and
    ``KERNELS`` holds nothing else."""
    found = {}
    for folder, dirs, files in os.walk(PACKAGE):
        dirs[:] = [d for d in dirs if d not in ("__pycache__", "view_static")]
        for f in files:
            if f.endswith(".py") and f != "_jitcache.py":
                path = os.path.join(folder, f)
                module = os.path.relpath(path[:-3], os.path.dirname(PACKAGE)).replace(os.sep, ".")
                for name, options in _jitted(path):
                    found[module, name] = options
    cached = {key for key, options in found.items() if options.get("cache")}
    assert len(cached) > 60 and len(found) == len(cached)     # every kernel is cached
    for module in {m for m, _ in found}:
        mod = importlib.import_module(module)
        assert mod.njit is _jitcache.njit, module
    listed = {(k.py_func.__module__, k.py_func.__qualname__) for k in _jitcache.KERNELS}
    assert listed == cached, (cached - listed, listed - cached)


def test_compiled_alone_leaves_out_inlined_kernels():
    from hillshade_rt.algorithms import per_cell_sun, raymath
    inlined = [k for k in _jitcache.KERNELS if k.targetoptions.get("inline") == "always"]
    assert inlined and not any(_jitcache.compiled_alone(k) for k in inlined)
    assert any(k.py_func.__module__ == per_cell_sun.__name__ for k in inlined)
    assert _jitcache.compiled_alone(raymath.madd) is (
        raymath.madd.targetoptions.get("inline") != "always")


def test_cached_asks_loadable_of_each_kernel_compiled_alone(monkeypatch):
    """``cached(module)``: every kernel of the module that is compiled alone is loadable; an
    inlined one is never asked; a module with none, or none at all, is not cached."""
    from hillshade_rt.algorithms import counts
    mine = [k for k in _jitcache.KERNELS if k.py_func.__module__ == counts.__name__]
    assert len(mine) >= 5
    asked = []
    missing = {mine[2].py_func.__name__}
    monkeypatch.setattr(_jitcache, "loadable", lambda k: asked.append(k.py_func.__name__)
                        or k.py_func.__name__ not in missing)
    assert _jitcache.cached("counts") is False
    missing.clear()
    asked.clear()
    assert _jitcache.cached("counts") is True
    assert sorted(asked) == sorted(k.py_func.__name__ for k in mine)
    assert _jitcache.cached("no_such_module") is False
    monkeypatch.setattr(_jitcache, "compiled_alone", lambda k: False)
    assert _jitcache.cached("counts") is False              # nothing compiled alone


@pytest.mark.slow
def test_loadable_reads_numbas_index_for_this_install(tmp_path):
    """A kernel is loadable once it has been compiled (its index written in this install's
    subfolder), in the process that compiled it and in the next; a truncated index, or none,
    is not; a function without a cache never is. (Fresh processes: the cache folder is fixed
    when the kernels' modules are imported.)"""
    code = ("import os, sys, glob\n"
            "import numpy as np\n"
            "from hillshade_rt.algorithms import _jitcache, counts\n"
            "k = counts._row_range\n"
            "before = _jitcache.loadable(k)\n"
            "if sys.argv[1] == 'compile':\n"
            "    k(np.array([1.0, 2.0]))\n"
            "after = _jitcache.loadable(k)\n"
            "index = glob.glob(os.path.join(_jitcache.cache_dir(), '*',\n"
            "                               'counts._row_range-*.nbi'))\n"
            "if sys.argv[1] == 'truncate':\n"
            "    open(index[0], 'wb').close()\n"
            "    after = _jitcache.loadable(k)\n"
            "print(before, after, len(index), _jitcache.loadable(_jitcache.njit(lambda x: x)))\n")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    results = []
    for step in ("look", "compile", "look", "truncate"):
        r = _python(["-c", code, step], env)
        assert r.returncode == 0, r.stderr
        results.append(r.stdout.split())
    assert results == [["False", "False", "0", "False"], ["False", "True", "1", "False"],
                       ["True", "True", "1", "False"], ["True", "False", "1", "False"]]


def test_source_digest_follows_every_source_file_of_the_folder(tmp_path, monkeypatch):
    """The same sources, the same digest; a change of one byte in any .py file of the folder,
    or a new one, another; other files count for nothing."""
    copy = tmp_path / "algorithms"
    shutil.copytree(os.path.dirname(_jitcache.__file__), copy,
                    ignore=shutil.ignore_patterns("__pycache__"))
    real = _jitcache.source_digest()
    monkeypatch.setattr(_jitcache, "_HERE", str(copy))

    def digest():
        _jitcache.source_digest.cache_clear()
        return _jitcache.source_digest()
    try:
        assert digest() == real and len(real) == 16
        (copy / "notes.txt").write_text("not a source")
        assert digest() == real
        with open(copy / "brute.py", "a") as fh:
            fh.write("\n")
        edited = digest()
        assert edited != real
        (copy / "new.py").write_text("")
        assert digest() not in (real, edited)
    finally:
        _jitcache.source_digest.cache_clear()


def test_cache_dir_is_numbas_setting_else_the_users_cache(monkeypatch, tmp_path):
    digest = _jitcache.source_digest()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "n"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "x"))
    assert _jitcache.cache_dir() == str(tmp_path / "n" / digest)
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    assert _jitcache.cache_dir() == str(tmp_path / "x" / "hillshade-rt" / "numba" / digest)
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert _jitcache.cache_dir() == str(tmp_path / "home" / ".cache" / "hillshade-rt" / "numba"
                                        / digest)


def test_kernel_cache_sets_numbas_folder_only_while_a_decorator_runs(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(numba.config, "CACHE_DIR", "/users/own/setting")
    with _jitcache.kernel_cache():
        assert numba.config.CACHE_DIR == _jitcache.cache_dir()
    assert numba.config.CACHE_DIR == "/users/own/setting"
    with pytest.raises(ZeroDivisionError):
        with _jitcache.kernel_cache():
            1 / 0
    assert numba.config.CACHE_DIR == "/users/own/setting"


def test_njit_bare_and_with_options_registers(monkeypatch):
    monkeypatch.setattr(_jitcache, "KERNELS", [])

    @_jitcache.njit
    def bare(x):
        return x + 1

    @_jitcache.njit(cache=False, fastmath=False)
    def called(x):
        return x * 3
    assert _jitcache.KERNELS == [bare, called]
    assert isinstance(bare, numba.core.registry.CPUDispatcher) and bare(1) == 2
    assert called(2) == 6 and called.targetoptions.get("fastmath") is False


def _index(path, version, stamp, data):
    with open(path, "wb") as fh:
        pickle.dump(version, fh)
        fh.write(pickle.dumps((stamp, {("sig", i): d for i, d in enumerate(data)})))


def test_stale_files(tmp_path):
    """Index files of another numba, of a source that changed or is gone, or unreadable, are
    stale; so are data files no fresh index names. Fresh ones are kept."""
    src, cache = tmp_path / "src", tmp_path / "cache"
    src.mkdir()
    cache.mkdir()
    (src / "mod.py").write_text("def f(): pass\n")
    (src / "old.py").write_text("def g(): pass\n")
    sha = hashlib.sha256((src / "mod.py").read_bytes()).digest()
    st = os.stat(src / "old.py")
    _index(cache / "mod.f-1.py311.nbi", numba.__version__, sha, ["mod.f-1.py311.1.nbc"])
    _index(cache / "old.g-1.py311.nbi", numba.__version__, (st.st_mtime, st.st_size),
           ["old.g-1.py311.1.nbc"])                       # numba < 0.59's stamp: still fresh
    _index(cache / "mod.h-9.py311.nbi", "0.1.0", sha, ["mod.h-9.py311.1.nbc"])   # another numba
    _index(cache / "mod.k-3.py311.nbi", numba.__version__, b"\0" * 32,              # edited
           ["mod.k-3.py311.1.nbc"])
    _index(cache / "gone.f-1.py311.nbi", numba.__version__, sha, ["gone.f-1.py311.1.nbc"])
    (cache / "mod.z-1.py311.nbi").write_bytes(b"\x80garbage")
    for name in ("mod.f-1.py311.1.nbc", "old.g-1.py311.1.nbc", "mod.h-9.py311.1.nbc",
                 "mod.k-3.py311.1.nbc", "mod.f-1.py311.2.nbc", "notes.txt"):
        (cache / name).write_bytes(b"")
    stale = _jitcache.stale_files(str(cache), str(src))
    assert stale == [str(cache / n) for n in sorted([
        "gone.f-1.py311.nbi", "mod.f-1.py311.2.nbc", "mod.h-9.py311.1.nbc",
        "mod.h-9.py311.nbi", "mod.k-3.py311.1.nbc", "mod.k-3.py311.nbi", "mod.z-1.py311.nbi"])]
    assert _jitcache.stale_files(str(tmp_path / "absent"), str(src)) == []


def test_a_kernel_module_imported_alone_caches_in_this_versions_folder(tmp_path):
    """Kernel modules take ``njit`` from ``_jitcache``: one imported straight (``io.py`` imports
    ``counts`` alone, the registry imports none) still caches in this version's digest folder,
    and numba's setting is the user's again afterwards."""
    import subprocess
    import sys
    code = ("import numba, hillshade_rt.algorithms.counts as c, hillshade_rt.algorithms._jitcache "
            "as j; print(c.valid_range._cache._cache_path.startswith(j.cache_dir() + '/'), "
            "j.cache_dir().startswith(numba.config.CACHE_DIR), numba.config.CACHE_DIR)")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split() == ["True", "True", str(tmp_path)]
def test_cached_ignores_index_files_of_another_folder(tmp_path):
    """``cached`` reads numba's own index of this install's files: a file of the right name in
    another checkout's subfolder (or an empty one) does not count. (A fresh process: the
    kernels' cache folder is fixed when their modules are imported.)"""
    code = ("import os, sys\n"
            "from hillshade_rt import warm\n"
            "from hillshade_rt.algorithms import _jitcache\n"
            "sub = os.path.join(sys.argv[1], _jitcache.source_digest(), 'algorithms_0123')\n"
            "os.makedirs(sub)\n"
            "for k in warm.kernels():\n"
            "    if k.py_func.__module__.endswith('.brute'):\n"
            "        open(os.path.join(sub, 'brute.%s-1.py311.nbi' % k.py_func.__qualname__),"
            " 'wb').close()\n"
            "print(_jitcache.cached('brute'), len(os.listdir(sub)))\n")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    r = _python(["-c", code, str(tmp_path)], env)
    assert r.returncode == 0, r.stderr
    found, files = r.stdout.split()
    assert found == "False" and int(files) >= 3
