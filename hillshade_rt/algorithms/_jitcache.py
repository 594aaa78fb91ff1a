"""Keep numba's on-disk cache honest across modules.

numba keys a cached function on its own source file only: when ``raymath.py`` changes but
``brute.py`` does not, ``cache=True`` would keep loading the old compiled kernel (stale results
after an upgrade or an edit). So the kernels are cached in a folder named after a digest of every
source file of this package folder: any change to any of them starts a fresh cache.

The kernel modules take ``njit`` from here, not from numba: the folder is chosen when the
decorator runs, so a module gets it however it is imported (``from ..algorithms.counts import
...`` straight from ``io/dem.py`` as much as through the registry), and importing the registry
(``algorithms/__init__.py``) need not import every kernel module first.
"""

import contextlib
import functools
import hashlib
import os
import threading

import numba

from .._preload import light_loading

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


#: Every kernel of the package, as its ``njit`` made it (``warm.missing`` checks each is cached).
KERNELS: list = []


def loadable(dispatcher) -> bool:
    """Whether numba's cache holds a compiled signature of ``dispatcher`` that this install
    loads: its index file in the folder numba's locator gives *this* install's source file
    (``<root>/<digest>/<folder>_<sha1 of the folder's path>``: another checkout of the same
    version has its own), written for the source as it is now (numba's stamp), with an entry
    for this machine's code generator and this function's bytecode (numba's index key)."""
    cache = getattr(dispatcher, "_cache", None)
    index_file = getattr(cache, "_cache_file", None)
    if index_file is None:
        return False
    try:
        overloads = index_file._load_index()
    except Exception:       # noqa: BLE001 -- an unreadable index is as good as none
        return False
    if not overloads:
        return False
    from numba.core.registry import cpu_target
    codegen = cpu_target.target_context.codegen()
    return any(key[1:] == cache._index_key(key[0], codegen)[1:] for key in overloads)


def cached(module: str) -> bool:
    """Whether numba's cache holds, for this install, compiled kernels of every function of
    ``algorithms/<module>.py`` (``loadable``): if not, the first call compiles them (seconds to
    a minute), which the command line says before it happens."""
    import importlib
    try:
        importlib.import_module(f"{__package__}.{module}")
    except ImportError:
        return False
    name = f"{__package__}.{module}"
    mine = [k for k in KERNELS if k.py_func.__module__ == name and compiled_alone(k)]
    return bool(mine) and all(loadable(k) for k in mine)


def compiled_alone(dispatcher) -> bool:
    """Whether numba compiles (and caches) ``dispatcher`` as a function of its own: a kernel
    inlined into its callers (``inline="always"``) is compiled into them, never alone."""
    return dispatcher.targetoptions.get("inline") != "always"


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
            return _register(numba.njit(*args, **options))
    decorate = numba.njit(*args, **options)

    def apply(fn):
        with kernel_cache():
            return _register(decorate(fn))
    return apply


def _register(dispatcher):
    KERNELS.append(dispatcher)
    return dispatcher


# this package's cached kernels load without numba's registries refreshed (``_preload``)
light_loading()


# ------------------------------------------------------------------------------------------
# what is stale, and pruning it (``hillshade-rt cache``)
#
# Each version of the kernels compiles into a new ``<root>/<digest>`` folder and the old ones
# stay; numba's own ``cache=True`` (``__pycache__`` beside the module, or
# ``$NUMBA_CACHE_DIR/run_<sha1 of its folder>``) leaves the index and data files of a function
# that moved to another line when its file was edited. An index file (``*.nbi``) holds numba's
# version, then the source's stamp (numba >= 0.59: the SHA-256 of the file's bytes; before:
# its mtime and size) and the data files (``*.N.nbc``) of its compiled signatures.

def _is_digest(name: str) -> bool:
    return len(name) == 16 and all(c in "0123456789abcdef" for c in name)


def _stamps(source: str) -> list:
    """The stamps numba may have written for ``source`` as it is now."""
    st = os.stat(source)
    with open(source, "rb") as fh:
        return [hashlib.sha256(fh.read()).digest(), (st.st_mtime, st.st_size)]


def _fresh_data(index: str, source: str) -> set[str] | None:
    """The data files a fresh index file names, or None when it is stale (another numba, a
    source that changed or is gone, or unreadable)."""
    import pickle
    try:
        with open(index, "rb") as fh:
            if pickle.load(fh) != numba.__version__:
                return None
            stamp, overloads = pickle.loads(fh.read())
        if stamp not in _stamps(source):
            return None
        return set(overloads.values())
    except Exception:   # noqa: BLE001 -- a truncated or foreign file is stale as much
        return None


def stale_files(folder: str, source_dir: str) -> list[str]:
    """The stale ``*.nbi``/``*.nbc`` files of numba's cache ``folder`` whose sources are the
    modules of ``source_dir``: index files that no longer match their module, and data files
    no fresh index names."""
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    fresh, stale = set(), []
    for name in names:
        if name.endswith(".nbi"):
            data = _fresh_data(os.path.join(folder, name),
                               os.path.join(source_dir, name.split(".", 1)[0] + ".py"))
            if data is None:
                stale.append(name)
            else:
                fresh |= data
    stale += [n for n in names if n.endswith(".nbc") and n not in fresh]
    return [os.path.join(folder, n) for n in sorted(stale)]


def _numba_subfolder(source_dir: str) -> str:
    """The subfolder numba's user-provided cache locator gives the functions of
    ``source_dir`` (``<folder name>_<sha1 of the absolute path>``)."""
    path = os.path.abspath(source_dir)
    return "_".join([os.path.basename(path), hashlib.sha1(path.encode()).hexdigest()])


def _size(path: str) -> int:
    if os.path.isfile(path):
        return os.path.getsize(path)
    return sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(path) for f in fs)


def survey(package_dir: str | None = None) -> dict:
    """Where the compiled kernels are and what of them is stale: ``root``, ``current`` (this
    version's folder), its ``bytes``; ``other_versions`` (folders of other digests: another
    version of the kernels or of numba, or another install of another version), ``stale``
    (files of this install's sources that numba would never load again); sizes in bytes.
    ``package_dir``: the package whose ``numba.njit(cache=True)`` modules (outside algorithms/)
    are checked too, by default this one."""
    package_dir = package_dir or os.path.dirname(_HERE)
    root, current = _cache_root(), cache_dir()
    try:
        others = sorted(os.path.join(root, d) for d in os.listdir(root)
                        if _is_digest(d) and os.path.join(root, d) != current)
    except OSError:
        others = []
    stale = stale_files(os.path.join(current, _numba_subfolder(_HERE)), _HERE)
    for d, subs, _ in os.walk(package_dir):
        subs[:] = [s for s in subs if s != "__pycache__" and not s.startswith(".")]
        if os.path.abspath(d) == _HERE:
            continue
        for folder in (os.path.join(d, "__pycache__"),
                       os.path.join(numba.config.CACHE_DIR or "", _numba_subfolder(d))
                       if numba.config.CACHE_DIR else None):
            if folder:
                stale += stale_files(folder, d)
    return {"root": root, "current": current,
            "bytes": _size(current) if os.path.isdir(current) else 0,
            "other_versions": [(p, _size(p)) for p in others],
            "stale": [(p, _size(p)) for p in stale]}


def prune(package_dir: str | None = None) -> dict:
    """Remove what ``survey`` finds stale: other versions' folders and stale files. Returns
    the survey (what was removed). A folder or file that vanished meanwhile is skipped."""
    import shutil
    found = survey(package_dir)
    for path, _ in found["other_versions"]:
        shutil.rmtree(path, ignore_errors=True)
    for path, _ in found["stale"]:
        with contextlib.suppress(FileNotFoundError):
            os.remove(path)
    return found
