"""_preload.py: numba's start-up cut to what loading this package's cached kernels needs. A
kernel of the package found in numba's cache loads without numba's registries refreshed, one that
is not there still compiles (and refreshes them), and any other function's cache is numba's as
before; ``start_numba`` loads numba's array functions without SciPy's BLAS.
(``while_numba_starts``: tests/io/test_read.py, with the read it overlaps.)"""

import json
import os
import subprocess
import sys

import numba.core.caching
import pytest

from hillshade_rt import _preload
from hillshade_rt.algorithms import _jitcache  # noqa: F401 -- installs light loading

# one process of the test below: a kernel of the package and a function of another folder (both
# cache=True), each called once, with numba's registry refreshes and the kernel's cache hits
# and misses counted
CALLS = """
import json, sys
from numba.core.base import BaseContext
refreshes = []
original = BaseContext.refresh
BaseContext.refresh = lambda self: refreshes.append(1) or original(self)
import numpy as np
from hillshade_rt.algorithms import counts
ours = counts._row_range(np.array([4.0, np.nan, -1.5, 2.0]))
ours_refreshes = len(refreshes)
import elsewhere
theirs = elsewhere.twice(21.0)
print(json.dumps({"ours": [float(v) for v in ours], "ours_refreshes": ours_refreshes,
                  "hits": sum(counts._row_range.stats.cache_hits.values()),
                  "misses": sum(counts._row_range.stats.cache_misses.values()),
                  "theirs": theirs, "their_refreshes": len(refreshes) - ours_refreshes,
                  "their_hits": sum(elsewhere.twice.stats.cache_hits.values())}))
"""


def test_light_loading_is_installed_once():
    load = numba.core.caching.Cache.load_overload
    assert getattr(load, "_hillshade_rt", False)
    _preload.light_loading()
    assert numba.core.caching.Cache.load_overload is load          # not wrapped twice


@pytest.mark.slow
def test_a_cached_kernel_loads_without_refreshing_numba_and_a_miss_compiles(tmp_path):
    """First process, empty cache: the kernel compiles (a miss: numba refreshes its registries
    as ever) and is cached. Second process: it loads from the cache with no refresh at all,
    and gives the same result; a function of another folder loads through numba's own path
    (which refreshes)."""
    (tmp_path / "elsewhere.py").write_text("import numba\n\n\n@numba.njit(cache=True)\n"
                                           "def twice(x):\n    return 2 * x\n")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")]))

    def run():
        r = subprocess.run([sys.executable, "-c", CALLS], capture_output=True, text=True,
                           env=env, timeout=300)
        assert r.returncode == 0, r.stderr
        return json.loads(r.stdout)
    first, second = run(), run()
    assert first["ours"] == second["ours"] == [3.0, -1.5, 4.0]
    assert first["theirs"] == second["theirs"] == 42.0
    assert (first["misses"], first["hits"]) == (1, 0) and first["ours_refreshes"] >= 1
    assert (second["misses"], second["hits"]) == (0, 1)
    assert second["ours_refreshes"] == 0
    assert second["their_hits"] == 1 and second["their_refreshes"] >= 1


def test_start_numba_loads_arraymath_without_scipys_blas():
    code = ("import json, sys\n"
            "from hillshade_rt import _preload\n"
            "_preload.start_numba()\n"
            "loaded = ['numba.np.arraymath' in sys.modules, 'scipy.linalg' in sys.modules,\n"
            "          'scipy.linalg.cython_blas' in sys.modules, _preload._done]\n"
            "import importlib.util\n"
            "if importlib.util.find_spec('scipy'):\n"    # nothing held back afterwards
            "    import scipy.linalg.cython_blas\n"
            "from numba.core.runtime import rtsys\n"
            "print(json.dumps(loaded + [rtsys._init]))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == [True, False, False, True, True]
