"""TIFF files without georeferencing, read through tifffile (GDAL reads the others, and these
when tifffile cannot)."""

from __future__ import annotations

import contextlib

import numpy as np

from ..errors import HillshadeError


class TiffUnreadable(HillshadeError):
    """tifffile could not read the file (GDAL may still)."""


@contextlib.contextmanager
def _quiet_logger(name: str):
    """The library logger ``name`` silenced in the block: what it says about a damaged file is
    in the one-line error (tifffile logs a line per bad tag, printed when no handler is set)."""
    import logging
    log = logging.getLogger(name)
    was = log.disabled
    log.disabled = True
    try:
        yield
    finally:
        log.disabled = was


def read_tiff(path: str, band: int, data: bytes | None = None) -> tuple[np.ndarray, float | None]:
    """Band ``band`` of the first page of the TIFF ``path`` (``data``: its bytes, held in
    memory) and the nodata value of its GDAL_NODATA tag. :class:`TiffUnreadable` when tifffile
    cannot read it; a missing band, an image that is not 2-D or values that are no heights are
    refused (HillshadeError)."""
    import io

    import tifffile

    try:
        with _quiet_logger("tifffile"), \
                tifffile.TiffFile(io.BytesIO(data) if data is not None else path) as tif:
            page = tif.pages[0]
            values = page.asarray()
            tag = page.tags.get("GDAL_NODATA") or page.tags.get(42113)
            file_nodata = float(str(tag.value).strip("\x00 ")) if tag is not None else None
    except Exception as exc:  # noqa: BLE001 -- tifffile raises many kinds for bad files
        msg = " ".join(str(exc).split()) or type(exc).__name__
        raise TiffUnreadable(f"{path}: cannot read as a TIFF ({msg})") from None
    if values.ndim == 3:
        # planar (bands, rows, cols) or contiguous (rows, cols, samples)
        if page.planarconfig == 2 or values.shape[0] < values.shape[-1]:
            values = np.moveaxis(values, 0, -1)
        if band > values.shape[-1]:
            raise HillshadeError(f"{path}: has {values.shape[-1]} band(s), --band {band} asked")
        values = values[..., band - 1]
    elif values.ndim != 2 or band != 1:
        raise HillshadeError(f"{path}: expected a single-band 2-D image, got shape {values.shape}")
    if values.dtype.kind not in "iuf":
        raise HillshadeError(f"{path}: pixel type {values.dtype} is not a height")
    return values, file_nodata
