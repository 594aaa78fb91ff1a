"""Where a DEM is: local paths, GDAL dataset names and URLs, standard input; how messages and
reports name them.

GDAL opens more than files on the local disk (``/vsizip/a.zip/dem.tif``, ``zip://a.zip!dem.tif``,
``https://…``, ``NETCDF:f.nc:z``): only the checks the local disk can make are made here (no such
file, a folder); the rest is GDAL's to refuse (``gdal.open_error``).
"""

from __future__ import annotations

import contextlib
import os
import re

from ..errors import HillshadeError

STDIN = "-"                 # the DEM path that means standard input
STDIN_NAME = "<stdin>"      # how messages (and Dem.path) name it

# rasterio-style URL schemes (``zip://a.zip!dem.tif``, ``zip+https://…``, ``s3://…``) and the GDAL
# virtual file system of each; a ``scheme:`` GDAL knows otherwise (``NETCDF:f.nc:z``) is left alone
_URL = re.compile(r"^([A-Za-z][A-Za-z0-9]*(?:\+[A-Za-z][A-Za-z0-9]*)*)://(.*)$", re.DOTALL)
_VSI_OF = {"zip": "vsizip", "tar": "vsitar", "gzip": "vsigzip", "http": "vsicurl",
           "https": "vsicurl", "ftp": "vsicurl", "s3": "vsis3", "gs": "vsigs", "az": "vsiaz",
           "oss": "vsioss", "file": ""}
_ARCHIVES = ("zip", "tar", "gzip")
_CURL = ("http", "https", "ftp")
# a GDAL dataset name rather than a local path: /vsi…, a URL, DRIVER:… (one letter is a drive)
_GDAL_NAME = re.compile(r"^(/vsi[a-z0-9_]*/|[A-Za-z][A-Za-z0-9+.\-]+:)")


def is_gdal_name(path: str) -> bool:
    """Whether ``path`` is a GDAL or rasterio dataset name (``/vsizip/…``, ``/vsimem/…``,
    ``zip://…!…``, ``https://…``, ``NETCDF:…``) rather than a path on the local disk."""
    return bool(_GDAL_NAME.match(path))


def gdal_path(path: str) -> str:
    """What GDAL opens for ``path``: a rasterio-style URL as its /vsi path (``zip://a.zip!x.tif``
    -> ``/vsizip//abs/a.zip/x.tif``, the archive of a local one made absolute), any other path as
    it is. (rasterio's own conversion loses a relative archive without a folder, ``zip://a.zip!x``.)"""
    m = _URL.match(path)
    if not m:
        return path
    schemes = m.group(1).lower().split("+")
    if not all(s in _VSI_OF for s in schemes):
        return path
    rest, member = m.group(2), None
    archive = schemes[0] if schemes[0] in _ARCHIVES else None
    if archive and "!" in rest:
        rest, member = rest.rsplit("!", 1)
    transport = [s for s in schemes[1 if archive else 0:] if s != "file"]
    if len(transport) > 1 or (not archive and not transport and schemes != ["file"]):
        return path
    if not transport:
        loc = os.path.abspath(rest) if rest else rest
    elif transport[0] in _CURL:
        loc = f"/vsicurl/{transport[0]}://{rest}"
    else:
        loc = f"/{_VSI_OF[transport[0]]}/{rest}"
    if archive:
        loc = f"/{_VSI_OF[archive]}/{loc}"
        if member:
            loc += "/" + member.lstrip("/")
    return loc


def dataset_name(path: str) -> str:
    """What GDAL opens for the input ``path``, here, in a VRT or on another process: a local
    file's absolute path, else :func:`gdal_path` (``/vsizip/…``; rasterio URLs converted)."""
    if os.path.exists(path) and not path.startswith("/vsi"):
        return os.path.abspath(path)
    return gdal_path(path)


def input_label(path: str) -> str:
    """How a report names the input ``path``: a local file's absolute path, a GDAL name or URL
    as given (``os.path.abspath`` would mangle ``zip://…``), ``<stdin>`` for ``-``."""
    if path in (STDIN, STDIN_NAME):
        return STDIN_NAME
    if is_gdal_name(path) and not os.path.exists(path):
        return path
    return os.path.abspath(path)


def check_input_path(path: str) -> None:
    """The clear local checks of an input path (no such file, a folder); a name for GDAL
    (:func:`is_gdal_name`) that is not a local file is left to GDAL to open."""
    if path == STDIN:
        return
    if os.path.exists(path):
        if os.path.isdir(path) and not path.lower().rstrip("/").endswith((".gdb", ".zarr")):
            raise HillshadeError(f"{path}: is a folder, not a raster file")
        return
    if not is_gdal_name(path):
        raise HillshadeError(f"{path}: no such file")


def read_stdin() -> bytes:
    """All of standard input (a DEM piped in: ``curl … | hillshade-rt shadow - out.tif``)."""
    import sys
    stream = sys.stdin
    if stream is None:
        raise HillshadeError(f"{STDIN_NAME}: there is no standard input to read a DEM from")
    with contextlib.suppress(AttributeError, ValueError, OSError):
        if stream.isatty():
            raise HillshadeError(f"{STDIN_NAME}: is a terminal; pipe a DEM into it "
                                 "(e.g. curl URL | hillshade-rt shadow - out.tif)")
    try:
        data = getattr(stream, "buffer", stream).read()
    except (OSError, ValueError) as exc:   # closed, or captured (pytest)
        raise HillshadeError(f"{STDIN_NAME}: cannot read standard input ({exc})") from None
    if isinstance(data, str):
        raise HillshadeError(f"{STDIN_NAME}: standard input is text, not the bytes of a raster")
    if not data:
        raise HillshadeError(f"{STDIN_NAME}: standard input is empty")
    return data
