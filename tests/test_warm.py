"""``python -m hillshade_rt.warm`` (run by ``make install``): every kernel of the package compiled
into numba's cache for *this* install, so that no command compiles at a user's first run; and a
cache another checkout filled is not taken for this install's."""

import os
import shutil
import subprocess
import sys

import pytest

from hillshade_rt import warm
from hillshade_rt.algorithms import _jitcache

TIMEOUT = 900


def _python(code_or_args, env, cwd=None):
    args = code_or_args if isinstance(code_or_args, list) else ["-c", code_or_args]
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=TIMEOUT)


@pytest.fixture(scope="module")
def warmed(tmp_path_factory):
    """A numba cache filled by the warm-up from empty: (its environment, the warm's result)."""
    cache = tmp_path_factory.mktemp("numba-cache")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env.pop("NUMBA_ENABLE_CUDASIM", None)
    return env, _python(["-m", "hillshade_rt.warm"], env)


@pytest.mark.slow
def test_warm_fills_an_empty_cache_with_every_kernel(warmed):
    env, p = warmed
    assert p.returncode == 0, p.stderr
    assert "compiling the kernels once for this install" in p.stderr
    assert "kernels ready" in p.stderr
    # every registered kernel has an entry this install loads
    check = _python(["-m", "hillshade_rt.warm", "--check"], env)
    assert check.returncode == 0 and check.stdout == "", check.stdout
    # and there are kernels to check (the registry is not empty)
    n = _python("from hillshade_rt import warm; print(len(warm.kernels()))", env)
    assert int(n.stdout) > 60, n.stderr
    # the run's "compiling" note (``cached``) agrees: nothing left to compile for any algorithm
    code = ("from hillshade_rt.algorithms import REGISTRY, _jitcache\n"
            "print(all(_jitcache.cached(m) for a in REGISTRY.values() for m in a.kernel_modules))")
    agree = _python(code, env)
    assert agree.stdout.strip() == "True", agree.stdout + agree.stderr
    # a second warm-up finds everything cached: nothing said, nothing run
    again = _python(["-m", "hillshade_rt.warm"], env)
    assert again.returncode == 0 and again.stderr == ""


@pytest.mark.slow
def test_after_the_warm_up_no_scenario_compiles(warmed):
    """Every command line of the warm-up again, in one process, with numba's compile events
    counted: every kernel comes from the cache."""
    env, p = warmed
    assert p.returncode == 0, p.stderr
    code = ("from hillshade_rt import warm\n"
            "names = []\n"
            "codes = [warm.run_group(g, names) for g in warm.GROUPS]\n"
            "print(codes, sorted(set(names)))\n")
    r = _python(code, env)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == f"{[0] * len(warm.GROUPS)} []", r.stdout


def test_another_checkouts_kernels_are_not_this_installs(warmed, tmp_path):
    """Two checkouts of one version share the digest folder, but numba keys its index files by
    the source's path: a copy of the package elsewhere finds none of its kernels cached
    (``--check`` lists them, exit 1), and its warm-up would compile them."""
    env, p = warmed
    assert p.returncode == 0, p.stderr
    other = tmp_path / "other"
    src = os.path.dirname(os.path.dirname(_jitcache.__file__))
    shutil.copytree(src, other / "hillshade_rt",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    env2 = dict(env, PYTHONPATH=str(other))
    r = _python(["-m", "hillshade_rt.warm", "--check"], env2, cwd=str(other))
    assert r.returncode == 1
    assert "hillshade_rt.algorithms.bounds" in r.stdout
    where = _python("import hillshade_rt.algorithms._jitcache as j; print(j.__file__, "
                    "j.cache_dir())", env2, cwd=str(other))
    path, digest_dir = where.stdout.split()
    assert path.startswith(str(other))
    # the same version: the same digest folder as this install's, yet nothing of it is loadable
    assert os.path.basename(digest_dir) == _jitcache.source_digest()


def test_groups_name_every_command_that_computes():
    """Every command that runs kernels has scenarios (a new command without them would compile
    at its first run)."""
    commands = {a[0] for g in warm.GROUPS.values() for a in g if not callable(a)}
    assert commands >= {"shadow", "hillshade", "sun-hours", "horizon", "skyview", "irradiance",
                        "query", "profile", "illumination", "animate"}
    assert warm._view in warm.GROUPS["lights"]


def test_every_kernel_lives_in_algorithms():
    """Every numba kernel of the package is in algorithms/ (its cache folder is keyed on a digest
    of algorithms/*.py, and the warm-up imports those modules to list them): the engine's
    modules, imported too, add none (the windowed runs' block ranges: counts.block_range)."""
    import importlib
    import pkgutil

    from hillshade_rt import engine
    for info in pkgutil.iter_modules(engine.__path__):
        importlib.import_module(f"{engine.__name__}.{info.name}")
    listed = warm.kernels()
    outside = {k.py_func.__module__ for k in _jitcache.KERNELS
               if not k.py_func.__module__.startswith("hillshade_rt.algorithms.")}
    assert not outside
    assert "block_range" in {k.py_func.__name__ for k in listed}
