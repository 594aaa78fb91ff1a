"""Opening datasets through rasterio (GDAL), and what GDAL says when it cannot, as one line.

rasterio chains the errors GDAL reports; :func:`gdal_message` finds the useful one (libtiff's,
deepest) and :func:`open_error` / :func:`read_error` say what it means for the user: no such file,
truncated or corrupt, not a raster GDAL can read.
"""

from __future__ import annotations

import contextlib
import os
import re
import warnings

from ..errors import HillshadeError
from .paths import gdal_path

_TIFF_MAGIC = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")
_CORRUPT_HINTS = re.compile(r"TIFF|IReadBlock|read error|decod|decompress|truncat|corrupt|"
                            r"checksum|data check|unexpected end|short read", re.IGNORECASE)


def gdal_message(exc: BaseException, *names: str) -> str:
    """GDAL's first useful message behind ``exc`` (one line): rasterio chains the errors GDAL
    reported, the first reported (the most specific: libtiff's) deepest; the generic "Read
    failed. See previous exception" is skipped, and a leading ``name:`` of the file dropped."""
    msgs, seen, e = [], set(), exc
    while e is not None and id(e) not in seen:
        seen.add(id(e))
        text = " ".join(str(e).split())
        if text and "see previous exception" not in text.lower():
            msgs.append(text)
        e = e.__cause__ or e.__context__
    msg = msgs[-1] if msgs else type(exc).__name__
    prefixes = [n for n in names if n] + [os.path.basename(n) for n in names if n]
    for _ in range(3):   # "c.tif: c.tif:Cannot read TIFF header", "x.tif, band 1: …"
        for p in prefixes:
            for tail in (":", ", band"):
                if msg.startswith(p + tail):
                    msg = msg[len(p):].lstrip(":, ")
                    if msg.startswith("band "):
                        msg = re.sub(r"^band \d+:\s*", "", msg)
    msg = re.sub(r"^[A-Za-z_]\w*:(?=\S)", "", msg) or msg   # libtiff's "TIFFFillTile:Read …"
    return msg if len(msg) <= 200 else msg[:197] + "..."


def has_tiff_magic(path: str, data: bytes | None = None) -> bool:
    """Whether the file ``path`` (or the bytes ``data``) begins as a TIFF or BigTIFF does."""
    if data is None:
        try:
            with open(path, "rb") as fh:
                data = fh.read(4)
        except OSError:
            return False
    return data[:4] in _TIFF_MAGIC


def open_error(path: str, exc: BaseException, *, data: bytes | None = None,
               gdal_name: str | None = None) -> HillshadeError:
    """The one-line error for a dataset GDAL could not open: no such file (GDAL says it does not
    exist), truncated or corrupt (a TIFF that its header names, or GDAL's decoders say so), or
    cannot read as a raster (GDAL's reason)."""
    msg = gdal_message(exc, path, gdal_name or path)
    low = msg.lower()
    if "does not exist in the file system" in low or "no such file or directory" in low:
        return HillshadeError(f"{path}: no such file")
    tiff = has_tiff_magic(path, data) if (data is not None or os.path.isfile(path)) else False
    if tiff or ("not recognized" not in low and _CORRUPT_HINTS.search(msg)):
        return HillshadeError(f"{path}: truncated or corrupt ({msg})")
    if "not recognized as" in low or "not recognised" in low:
        msg = "not a raster format GDAL can read"
    return HillshadeError(f"{path}: cannot read as a raster ({msg})")


def read_error(path: str, exc: BaseException, gdal_name: str | None = None) -> HillshadeError:
    """The one-line error for a dataset that opened but whose values could not be read."""
    return HillshadeError(f"{path}: truncated or corrupt "
                          f"({gdal_message(exc, path, gdal_name or path)})")


def check_band(ds, path: str, band: int) -> bool:
    """Refuse an empty raster or a missing band of the open dataset ``ds``; True when it is
    georeferenced (a CRS or a non-identity transform)."""
    if ds.count < 1 or ds.width < 1 or ds.height < 1:
        raise HillshadeError(f"{path}: the raster is empty")
    if band > ds.count:
        raise HillshadeError(f"{path}: has {ds.count} band(s), --band {band} asked")
    return ds.crs is not None or not ds.transform.is_identity


def open_raster(path: str, stack: contextlib.ExitStack, data: bytes | None = None,
                name: str | None = None):
    """``path`` opened by rasterio, kept open by ``stack``: what GDAL opens is ``name``, or
    :func:`~.paths.gdal_path` of ``path``, or ``data`` (the bytes of a raster held in memory,
    e.g. standard input, through a ``rasterio.MemoryFile``); GDAL's refusal as
    :func:`open_error`, naming ``path``. rasterio's warning that a dataset has no
    georeferencing (given when it opens) is silenced: the caller decides what that means."""
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning, RasterioError

    if data is None and name is None:
        name = gdal_path(path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            if data is not None:
                return stack.enter_context(stack.enter_context(rasterio.MemoryFile(data)).open())
            return stack.enter_context(rasterio.open(name))
    except (RasterioError, OSError) as exc:
        raise open_error(path, exc, data=data, gdal_name=name) from None
