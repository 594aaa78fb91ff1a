"""A DEM in memory (:class:`Dem`): float32 heights with NaN for nodata (the z-factor applied), the
geotransform and CRS of the source, and its :class:`~hillshade_rt.model.geometry.Grid` (ground spacing
per row); and the two conversions every read shares: a source's values into such heights
(:func:`heights_into`) and its geotransform into a grid (:func:`grid_of`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import HillshadeError
from ..model.geometry import Grid, grid_from_transform, orientation
from .crs import crs_name, crs_string


@dataclass
class Dem:
    """A DEM in memory, ready for the shadow algorithms (``DemSource.read``, ``read_dem``)."""

    heights: np.ndarray          # float32, NaN = nodata, z-factor applied
    grid: Grid
    path: str
    kind: str                    # "gdal", "tiff", "raw" or "mosaic"
    transform: object = None     # affine.Affine or None (not georeferenced)
    crs: object = None           # rasterio CRS or None
    nodata: float | None = None  # the source's nodata value (before conversion to NaN)
    band: int = 1
    driver: str = ""
    source_dtype: str = ""
    notes: list[str] = field(default_factory=list)
    _survey: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def shape(self) -> tuple[int, int]:
        return self.heights.shape  # type: ignore[return-value]

    def survey(self) -> tuple[int, float, float]:
        """(valid cells, lowest, highest valid height), found by the read's nodata pass or by one
        parallel pass, kept (whoever changes ``heights`` in place sets ``_survey`` to None)."""
        if self._survey is None:
            from ..algorithms.counts import valid_range
            n, lo, hi = valid_range(self.heights)
            self._survey = (int(n), float(lo), float(hi))
        return self._survey

    def valid_count(self) -> int:
        return self.survey()[0]

    def centre_height(self) -> tuple[float, str]:
        """The observer's height for suns from times (``site.centre_height_of``)."""
        from ..model.site import centre_height_of
        return centre_height_of(self.heights)

    def height_range(self) -> tuple[float, float]:
        """(lowest, highest) valid height; (inf, -inf) when none is valid."""
        return self.survey()[1:]

    def crs_string(self) -> str | None:
        return crs_string(self.crs)

    def crs_name(self) -> str | None:
        return crs_name(self.crs)


def to_heights(data: np.ndarray, nodata: float | None) -> tuple[np.ndarray, tuple | None]:
    """float32 heights with nodata (and NaN, and +-inf) as NaN, and their survey when the pass
    found it (:func:`heights_into`).

    ``data`` is an array the caller has just read and owns: a float32 one is converted in place,
    any other type is cast once.
    """
    z = data if data.dtype == np.float32 else np.empty(data.shape, np.float32)
    return z, heights_into(data, nodata, z)


def heights_into(data: np.ndarray, nodata: float | None, out: np.ndarray,
                 z_factor: float = 1.0) -> tuple | None:
    """``out[...]`` = float32 heights of ``data`` (``out`` may be ``data`` itself): nodata, NaN and
    +-inf as NaN, times ``z_factor``. Nodata is compared in the source type: a float32 cast of
    e.g. -3.4028235e38 must still match; a value the type cannot hold (-1 for uint16) matches
    nothing instead of wrapping around. Float32 heights converted in place take one parallel
    pass that also returns their (valid cells, lowest, highest); otherwise None."""
    if (out is data and data.dtype == np.float32 and data.ndim == 2 and z_factor == 1.0
            and data.flags.c_contiguous and data.flags.writeable and data.size >= 1 << 16):
        from ..algorithms.counts import clean_heights
        use = nodata is not None and not math.isnan(nodata)
        n, lo, hi = clean_heights(data, float(nodata) if use else 0.0, use)
        return int(n), float(lo), float(hi)
    # one boolean scratch array and masked copies, no fancy indexing: on a 10000² DEM the read
    # stage spent 1 s here (four temporaries and two boolean-index passes)
    mask = np.empty(out.shape, np.bool_)
    bad = False
    if nodata is not None and not math.isnan(nodata):
        with np.errstate(invalid="ignore", over="ignore"):   # not in the type: matches nothing
            nd = np.asarray(nodata).astype(data.dtype)
        if data.dtype.kind == "f" or float(nd) == float(nodata):
            np.equal(data, nd, out=mask)
            bad = True
    if out is not data:
        with np.errstate(over="ignore"):     # beyond float32 (a damaged file): inf, then void
            out[...] = data
    nan = np.float32(np.nan)
    if bad:
        np.copyto(out, nan, where=mask)
    np.isfinite(out, out=mask)
    np.logical_not(mask, out=mask)
    np.copyto(out, nan, where=mask)
    if z_factor != 1.0:
        out *= np.float32(z_factor)


def check_transform(path: str, transform) -> tuple[int, int]:
    """(col_sign, row_sign) of the geotransform of ``path`` (see ``geometry.orientation``); a
    rotated, sheared, degenerate (zero pixel size) or non-finite one is refused, naming the
    file."""
    try:
        if not all(math.isfinite(v) for v in tuple(transform)[:6]):
            raise HillshadeError(f"geotransform has non-finite terms {tuple(transform)[:6]}")
        return orientation(transform)
    except HillshadeError as exc:
        raise HillshadeError(f"{path}: {exc}") from None


def grid_of(path: str, transform, crs, shape: tuple[int, int],
            pixel_size: tuple[float, float] | None = None) -> Grid:
    """The :class:`Grid` of a raster at ``path`` (``pixel_size``: the --pixel-size override);
    a rotated, sheared, degenerate (zero pixel size) or non-finite geotransform is refused
    with a message that names the file."""
    rows, cols = shape
    col_sign, row_sign = check_transform(path, transform) if transform is not None else (1, -1)
    if pixel_size is None:
        if transform is None:
            raise HillshadeError(f"{path}: has no georeferencing; give the ground spacing with "
                                 "--pixel-size DX[,DY] (metres)")
        try:
            return grid_from_transform(transform, crs, (rows, cols))
        except HillshadeError as exc:   # rows beyond the poles, a CRS without an ellipsoid
            raise HillshadeError(f"{path}: {exc}") from None
    return Grid.uniform(rows, cols, pixel_size[0], pixel_size[1], col_sign, row_sign,
                        "--pixel-size")
