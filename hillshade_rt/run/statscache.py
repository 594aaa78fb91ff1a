"""The block statistics of a ``--context`` raster kept between runs.

Every run of a tile with ``--context`` needs the context's 256 x 256 block height ranges
(``engine.windows.block_stats``: the halos' bound, Earth curvature "auto"), one streaming pass over
the whole context. A Makefile of N tiles would read the context N times; with this cache the
first run reads it and stores the ranges, the others read a few kilobytes.

Where: ``$HILLSHADE_RT_STATS_DIR`` if set (``off``: no cache), else
``$XDG_CACHE_HOME/hillshade-rt/stats`` (``~/.cache/hillshade-rt/stats``), beside numba's
kernel cache. One ``.npz`` file per context, named after a digest of what makes its heights:
the context's files (the raster, and every file a VRT references, as GDAL lists them: path,
size and modification time in nanoseconds), the band, nodata, z-factor and the other read
options, the shape, the block size and this format's version. Touching or rewriting any of
those files gives another digest (the old entry is left to ``prune``). A context that is not
made of local files (standard input, /vsi paths, URLs) is never cached.

Writes are atomic (a temporary file in the folder, then ``os.replace``): concurrent runs
(``make -j``) may both compute and store, one wins, both results are the same. An entry that
cannot be read, or whose recorded key or arrays do not fit, is ignored (computed again and
replaced); a folder that cannot be written leaves the run uncached, never failed.
"""

from __future__ import annotations

import hashlib
import io as _io
import json
import os
import tempfile
import time

import numpy as np

VERSION = 1
SUFFIX = ".npz"


def stats_root() -> str | None:
    """The cache's folder (None: the cache is off)."""
    env = os.environ.get("HILLSHADE_RT_STATS_DIR")
    if env is not None:
        return None if env.strip().lower() in ("", "off", "0", "no", "none") else env
    xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(xdg, "hillshade-rt", "stats")


def _stamp(path: str) -> list:
    st = os.stat(path)
    return [path, int(st.st_size), int(st.st_mtime_ns)]


def key_of(source, block: int) -> dict | None:
    """What the heights of ``source`` (an ``io.DemSource``) and their statistics depend on, as
    plain values; None when it cannot be known (not local files)."""
    try:
        files = source.files()
        if not files:
            return None
        stamps = [_stamp(f) for f in files]
    except Exception:  # noqa: BLE001 -- no key, no cache: the run reads the context itself
        return None
    opts = source.options
    return {"version": VERSION, "block": int(block), "files": stamps,
            # what GDAL opens (a path; a mosaic's VRT document): its digest
            "name": hashlib.sha256(str(source.name).encode()).hexdigest(),
            "shape": [int(n) for n in source.shape], "band": int(source.band),
            "nodata": None if source.nodata is None else repr(float(source.nodata)),
            "z_factor": repr(float(source.z_factor)), "dtype": str(source.dtype),
            "raw": [opts.raw_shape, opts.raw_dtype, opts.raw_byteorder]
            if opts.raw else None}


def digest(key: dict) -> str:
    text = json.dumps(key, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def load(path: str, key: dict, shape: tuple[int, int]):
    """(lo, hi, valid) stored at ``path`` for ``key``, or None (missing, unreadable, another
    key, arrays of another shape)."""
    try:
        with np.load(path, allow_pickle=False) as f:
            if str(f["key"]) != json.dumps(key, sort_keys=True, default=str):
                return None
            lo, hi, valid = f["lo"], f["hi"], int(f["valid"])
    except Exception:  # noqa: BLE001 -- a partial, corrupt or foreign file: compute again
        return None
    if (lo.shape != shape or hi.shape != shape or lo.dtype != np.float32
            or hi.dtype != np.float32 or valid < 0):
        return None
    return lo, hi, valid


def store(folder: str, path: str, key: dict, lo, hi, valid: int) -> bool:
    """Write the entry atomically; False (and nothing left behind) when it cannot be."""
    tmp = None
    try:
        os.makedirs(folder, exist_ok=True)
        buf = _io.BytesIO()
        np.savez(buf, key=np.array(json.dumps(key, sort_keys=True, default=str)),
                 lo=np.asarray(lo, np.float32), hi=np.asarray(hi, np.float32),
                 valid=np.array(int(valid), np.int64))
        fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=SUFFIX, dir=folder)
        with os.fdopen(fd, "wb") as fh:
            fh.write(buf.getvalue())
        os.replace(tmp, path)
        return True
    except OSError:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        return False


def cached_block_stats(source, block: int):
    """``(engine.windows.BlockStats, what the report says)``: the block statistics of ``source``
    from the cache, or from one pass over it (then stored). The report's dict: ``cache``
    ("hit", "stored", "off", "not cached: ..."), ``bytes_read`` (0 on a hit), ``file``."""
    from ..errors import AllNodata
    from ..engine.windows import BlockStats, block_stats
    rows, cols = source.shape
    full = rows * cols * source.itemsize
    folder = stats_root()
    key = key_of(source, block) if folder is not None else None
    if key is None:
        why = "off" if folder is None else "not cached: not local files"
        return block_stats(source, block), {"cache": why, "bytes_read": full, "file": None}
    path = os.path.join(folder, digest(key) + SUFFIX)
    got = load(path, key, (-(-rows // block), -(-cols // block)))
    if got is not None:
        lo, hi, valid = got
        if valid == 0:
            raise AllNodata(f"{source.path}: every cell is nodata, nothing to shade")
        return BlockStats(block, lo, hi, valid), {"cache": "hit", "bytes_read": 0,
                                                  "file": path}
    bs = block_stats(source, block)
    ok = store(folder, path, key, bs.lo, bs.hi, bs.valid)
    return bs, {"cache": "stored" if ok else "not cached: the folder cannot be written",
                "bytes_read": full, "file": path if ok else None}


def _stale(path: str) -> bool:
    """Whether the entry at ``path`` can no longer be hit: unreadable, of another format, or
    one of its files changed or gone."""
    try:
        with np.load(path, allow_pickle=False) as f:
            key = json.loads(str(f["key"]))
        if key.get("version") != VERSION:
            return True
        return any(_stamp(p) != [p, size, mtime] for p, size, mtime in key["files"])
    except Exception:  # noqa: BLE001 -- unreadable: stale
        return True


def survey(prune: bool = False) -> dict:
    """The cache's folder, its entries and their bytes, the stale ones (a file of theirs
    changed or gone, unreadable entries, temporary files over an hour old); ``prune``:
    those removed."""
    folder = stats_root()
    found = {"root": folder, "entries": 0, "bytes": 0, "stale": []}
    if folder is None or not os.path.isdir(folder):
        return found
    now = time.time()
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name)
        if not os.path.isfile(path) or not name.endswith(SUFFIX):
            continue
        try:
            st = os.stat(path)
        except OSError:
            continue
        if name.startswith(".tmp-"):
            stale = now - st.st_mtime > 3600
        else:
            found["entries"] += 1
            found["bytes"] += st.st_size
            stale = _stale(path)
        if stale:
            found["stale"].append((path, st.st_size))
            if prune:
                try:
                    os.unlink(path)
                except OSError:
                    pass
    return found
