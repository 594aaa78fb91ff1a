"""Raw binary grids (no header: the shape and value type come from options) and SRTM .hgt tiles
(big-endian int16, square, georeferenced from their name).

:func:`layout` checks the options against the file's size once; the grid is then read whole
(:func:`read_whole`) or memory-mapped for windows (:func:`memmap`).
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

import numpy as np

from ..errors import HillshadeError

RAW_DTYPES = ("int16", "uint16", "int32", "float32", "float64")
RAW_EXTS = (".raw", ".bin", ".dem", ".r32", ".r16", ".f32")

_HGT_NAME = re.compile(r"^([NS])(\d{2})([EW])(\d{3})", re.IGNORECASE)


def parse_raw_shape(text: str | None) -> tuple[int, int] | None:
    """'ROWSxCOLS' -> (rows, cols)."""
    if text is None:
        return None
    m = re.fullmatch(r"\s*(\d+)\s*[xX,]\s*(\d+)\s*", str(text))
    if not m:
        raise HillshadeError(f"--raw-shape must be ROWSxCOLS (e.g. 1201x1201), got {text!r}")
    rows, cols = int(m.group(1)), int(m.group(2))
    if rows == 0 or cols == 0:
        raise HillshadeError(f"--raw-shape {text!r} describes an empty raster")
    return rows, cols


def is_hgt(path: str) -> bool:
    return path.lower().endswith(".hgt")


@dataclass(frozen=True)
class Layout:
    """A raw grid's values as the file holds them: numpy type with its byte order, (rows, cols),
    the nodata value (-32768 for .hgt unless given), the driver's name for reports."""

    dtype: str
    shape: tuple[int, int]
    nodata: float | None
    driver: str


def layout(path: str, size: int, shape: tuple[int, int] | None, dtype: str | None,
           byteorder: str | None, nodata: float | None) -> Layout:
    """The layout of the raw grid ``path`` of ``size`` bytes given the --raw-* options; .hgt
    tiles default to big-endian int16, square, -32768 nodata. Every refusal names the file."""
    hgt = is_hgt(path)
    if size == 0:
        raise HillshadeError(f"{path}: the file is empty")
    if hgt:
        dtype = dtype or "int16"
        byteorder = byteorder or "big"
        if nodata is None:
            nodata = -32768.0
    if dtype is None:
        raise HillshadeError(f"{path}: raw input needs --raw-dtype ({', '.join(RAW_DTYPES)})")
    if dtype not in RAW_DTYPES:
        raise HillshadeError(f"--raw-dtype must be one of {', '.join(RAW_DTYPES)}, got {dtype!r}")
    byteorder = byteorder or "little"
    if byteorder not in ("little", "big"):
        raise HillshadeError(f"--raw-byteorder must be 'little' or 'big', got {byteorder!r}")
    dt = np.dtype(dtype).newbyteorder("<" if byteorder == "little" else ">")
    if size % dt.itemsize:
        raise HillshadeError(
            f"{path}: {size} bytes is not a whole number of {dtype} values ({dt.itemsize} bytes each)")
    count = size // dt.itemsize
    if shape is None:
        side = math.isqrt(count)
        if not hgt or side * side != count:
            raise HillshadeError(f"{path}: raw input needs --raw-shape ROWSxCOLS")
        shape = (side, side)
    if shape[0] * shape[1] != count:
        raise HillshadeError(
            f"{path}: --raw-shape {shape[0]}x{shape[1]} needs {shape[0] * shape[1]} {dtype} values "
            f"({shape[0] * shape[1] * dt.itemsize} bytes), the file holds {count} ({size} bytes)")
    return Layout(dt.str, (int(shape[0]), int(shape[1])), nodata,
                  "SRTM .hgt (raw)" if hgt else "raw")


def hgt_geometry(path: str, rows: int):
    """Transform and CRS of an SRTM .hgt tile from its name (cell centres on whole degrees);
    (None, None) for another name."""
    m = _HGT_NAME.match(os.path.basename(path))
    if not is_hgt(path) or not m or rows < 2:
        return None, None
    from affine import Affine
    from rasterio.crs import CRS

    lat = int(m.group(2)) * (1 if m.group(1).upper() == "N" else -1)
    lon = int(m.group(4)) * (1 if m.group(3).upper() == "E" else -1)
    step = 1.0 / (rows - 1)
    return (Affine(step, 0, lon - step / 2, 0, -step, lat + 1 + step / 2),
            CRS.from_epsg(4326))


def read_whole(path: str, dtype: str, shape: tuple[int, int],
               data: bytes | None = None) -> np.ndarray:
    """The grid's values (``dtype``, ``shape``: its :class:`Layout`'s), from the file or from
    ``data`` (its bytes: standard input), in an array the caller owns (float32 heights are
    converted in place)."""
    if data is None:
        return np.fromfile(path, dtype=np.dtype(dtype)).reshape(shape)
    return np.frombuffer(bytearray(data), dtype=np.dtype(dtype)).reshape(shape)


def memmap(path: str, dtype: str, shape: tuple[int, int]) -> np.ndarray:
    """The grid memory-mapped, read-only: windows read only their cells."""
    return np.memmap(path, dtype=np.dtype(dtype), mode="r", shape=shape)
