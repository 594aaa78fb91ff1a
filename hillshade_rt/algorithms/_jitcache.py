"""Keep numba's on-disk cache honest across modules.

numba keys a cached function on its own source file only: when ``raymath.py`` changes but
``brute.py`` does not, ``cache=True`` would keep loading the old compiled kernel (stale results
after an upgrade or an edit). So the kernels are cached in a folder named after a digest of every
source file of this package folder: any change to any of them starts a fresh cache.

The kernel modules take ``njit`` from here, not from numba: the folder is chosen when the
decorator runs, so a module gets it however it is imported (``from .algorithms.counts import
...`` straight from ``io.py`` as much as through the registry), and importing the registry
(``algorithms/__init__.py``) need not import every kernel module first.
"""

import contextlib
import functools
import hashlib
import os
import threading

import numba

_HERE = os.path.dirname(os.path.abspath(__file__))
_SETTING = threading.RLock()    # numba's CACHE_DIR is global: one decorator at a time sets it


@functools.lru_cache(maxsize=None)
def source_digest() -> str:
    h = hashlib.sha256(numba.__version__.encode())
    for name in sorted(os.listdir(_HERE)):
        if name.endswith(".py"):
            h.update(name.encode())
            with open(os.path.join(_HERE, name), "rb") as fh:
                h.update(fh.read())
    return h.hexdigest()[:16]


def _cache_root() -> str:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return os.environ["NUMBA_CACHE_DIR"]
    xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(xdg, "hillshade-rt", "numba")


def cache_dir() -> str:
    """Where this version's compiled kernels are cached."""
    return os.path.join(_cache_root(), source_digest())


def cached(module: str) -> bool:
    """Whether numba's cache already holds compiled kernels of ``algorithms/<module>.py`` for this
    version (an index file ``<module>.<function>-<line>.py311.nbi``): if not, the first call
    compiles them (seconds to a minute), which the command line says before it happens."""
    root = cache_dir()
    try:
        subs = [os.path.join(root, d) for d in os.listdir(root)]
        return any(f.startswith(module + ".") and f.endswith(".nbi")
                   for sub in subs if os.path.isdir(sub) for f in os.listdir(sub))
    except OSError:
        return False


@contextlib.contextmanager
def kernel_cache():
    """While a decorator runs (``njit``), point numba's cache at ``<root>/<digest>``; restore
    the user's setting afterwards (numba resolves the folder when a decorator runs, so other
    libraries are unaffected). Modules imported by two threads at once take turns."""
    with _SETTING:
        old = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = cache_dir()
        try:
            yield
        finally:
            numba.config.CACHE_DIR = old


def njit(*args, **options):
    """``numba.njit`` whose cached functions go to this version's folder (``cache_dir()``):
    ``@njit(cache=True, ...)`` as with numba's (or bare ``@njit``)."""
    if args and callable(args[0]):            # bare @njit
        with kernel_cache():
            return numba.njit(*args, **options)
    decorate = numba.njit(*args, **options)

    def apply(fn):
        with kernel_cache():
            return decorate(fn)
    return apply
