"""numba's one-off start-up cost, cut to what loading cached kernels needs and paid while GDAL
reads the DEM.

Loading a kernel from numba's cache (``Cache.load_overload``) first refreshes the CPU target's
typing and lowering registries (``BaseContext.refresh``): it imports some thirty modules of
numba's and installs thousands of implementations, 0.1-0.2 s of Python work, of which a cached
kernel needs none: its machine code is already there; what it links against is numba's runtime
(``rtsys.initialize``), and the modules its environment names are imported by numba as it
rebuilds it. So ``light_loading`` makes the CPU loads of this package's kernels do just that,
and a kernel that is not in the cache is compiled as ever (numba's compiler refreshes the
registries itself before it compiles anything).

And one import numba does on the way costs 0.08-0.17 s for nothing here: ``numba.np.arraymath``
imports ``scipy.linalg`` (where SciPy is installed) only to learn whether ``np.convolve`` may
call BLAS; no kernel of ours calls it. ``start_numba`` imports that module with
``scipy.linalg.cython_blas`` held back, so that it falls back on its own loop (numba's linear
algebra, should anything else use it, imports SciPy itself when it compiles).

``while_numba_starts`` runs a read in a thread while the calling thread does that start-up
(under numba's compiler lock): the read releases the GIL. No kernel ever runs on another thread.
"""

from __future__ import annotations

import os
import sys
import threading

_done = False
_PACKAGE = os.path.dirname(os.path.abspath(__file__)) + os.sep


def light_loading() -> None:
    """Make numba load this package's cached CPU kernels without refreshing its registries
    (once per process; other functions' caches are numba's as before). Where numba's internals
    are not as expected, nothing changes."""
    try:
        from numba.core import caching
        from numba.core.registry import cpu_target
    except Exception:      # noqa: BLE001 -- numba moved: its own loading, slower
        return
    cls = caching.Cache
    original = cls.load_overload
    if getattr(original, "_hillshade_rt", False) or not hasattr(cls, "_load_overload"):
        return

    def load_overload(self, sig, target_context):
        py_func = getattr(self, "_py_func", None)
        source = getattr(getattr(py_func, "__code__", None), "co_filename", "")
        if target_context is not cpu_target.target_context or not source.startswith(_PACKAGE):
            return original(self, sig, target_context)
        start_numba()
        with self._guard_against_spurious_io_errors():
            return self._load_overload(sig, target_context)

    load_overload._hillshade_rt = True
    cls.load_overload = load_overload


def start_numba() -> None:
    """What a cached kernel needs of numba before it loads: its runtime, and ``arraymath``
    imported without SciPy (once per process)."""
    global _done
    if _done:
        return
    _done = True
    try:
        from numba.core.compiler_lock import global_compiler_lock
        from numba.core.registry import cpu_target
        from numba.core.runtime import rtsys
        with global_compiler_lock:
            _without_blas_probe()
            rtsys.initialize(cpu_target.target_context)
    except Exception:      # noqa: BLE001 -- an internal API moved: the first kernel pays
        pass


def _without_blas_probe() -> None:
    """``numba.np.arraymath`` imported with ``scipy.linalg.cython_blas`` unavailable for the
    while (unless SciPy's linear algebra is loaded already)."""
    name = "scipy.linalg.cython_blas"
    if "numba.np.arraymath" in sys.modules or name in sys.modules:
        import numba.np.arraymath  # noqa: F401
        return
    sys.modules[name] = None            # "import scipy.linalg.cython_blas" raises ImportError
    try:
        import numba.np.arraymath  # noqa: F401
    finally:
        if sys.modules.get(name, 0) is None:
            del sys.modules[name]


def while_numba_starts(read):
    """``read()`` (I/O that releases the GIL) in a thread while this thread starts numba; its
    result, or its exception raised here."""
    if _done:
        return read()
    box = {}

    def run():
        try:
            box["value"] = read()
        except BaseException as exc:       # raised in the caller's thread below
            box["error"] = exc

    t = threading.Thread(target=run, name="hillshade-rt-read", daemon=True)
    t.start()
    start_numba()
    t.join()
    if "error" in box:
        raise box["error"]
    return box["value"]
