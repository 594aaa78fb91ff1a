"""Writing rasters: the GDAL driver an output gets and what it can hold, the one GeoTIFF profile,
:class:`BandWriter` (bands or windows of bands into one file), COGs, copies of VRT documents,
PNG pictures. Every file goes through :func:`.write.atomic_path` (a temporary file beside it,
published whole or not at all) and its GDAL calls through :func:`.write.gdal_checked`."""

from __future__ import annotations

import contextlib
import os
import sys
import warnings

import numpy as np

from ..errors import HillshadeError
from .write import atomic_path, gdal_checked, temp_beside

# formats GDAL writes by copying a finished dataset (CreateCopy) rather than block by block;
# what each can hold
_INTEGER_ONLY = {"PNG": ("uint8", "uint16"), "JPEG": ("uint8",), "WEBP": ("uint8",),
                 "BMP": ("uint8",), "GIF": ("uint8",)}
_LOSSY = ("JPEG", "WEBP")
_NOT_FOR_OUTPUT = {"VRT": "a VRT only points at other files", "MEM": "it stays in memory"}


def output_driver(path: str, fmt: str | None = None, cog: bool = False) -> str:
    """The GDAL driver an output is written with: ``fmt`` (like gdal_translate's -of, any case),
    else the one GDAL names for the path's extension, else GTiff; "COG" with ``cog``."""
    import rasterio
    from rasterio.drivers import driver_from_extension

    if fmt is not None:
        with rasterio.Env() as env:
            names = {n.lower(): n for n in env.drivers()}
        drv = names.get(str(fmt).lower())
        if drv is None:
            raise HillshadeError(f"--format {fmt}: not a GDAL raster driver here (e.g. GTiff, "
                                 "COG, PNG, JPEG, AAIGrid)")
    else:
        try:
            drv = driver_from_extension(os.fspath(path))
        except ValueError:
            drv = "GTiff"
    if drv in _NOT_FOR_OUTPUT:
        raise HillshadeError(f"{path}: cannot write {drv} ({_NOT_FOR_OUTPUT[drv]}); use .tif")
    if cog:
        if drv not in ("GTiff", "COG"):
            raise HillshadeError(f"{path}: --cog writes a GeoTIFF; this path names {drv}")
        drv = "COG"
    return drv


def check_output_format(path: str, drv: str, dtype: str, count: int, continuous: bool) -> None:
    """Refuse what ``drv`` cannot hold: float values in an integer-only format (soft shadows in
    PNG are the exception: 16 bits, see :class:`BandWriter`), a lossy format for masks, more
    bands than one in a picture format."""
    if drv in _INTEGER_ONLY:
        if dtype == "float32" and not (continuous and "uint16" in _INTEGER_ONLY[drv]):
            raise HillshadeError(f"{path}: {drv} holds integers, this product is float32; write "
                                 "a GeoTIFF (.tif)")
        if count > 1:
            raise HillshadeError(f"{path}: {drv} holds one band, this run makes {count} (one "
                                 "per sun); use --output-pattern or a GeoTIFF (.tif)")
    if drv in _LOSSY and not continuous:
        raise HillshadeError(f"{path}: {drv} is lossy and would change the mask's values; use "
                             "PNG (.png) or GeoTIFF (.tif)")


DEFLATE_LEVEL = 1   # GeoTIFF outputs: DEFLATE at this level (see gtiff_profile)
GTIFF_BLOCK = 256   # their tiles' side


def gtiff_profile(dem, dtype: str, nodata) -> dict:
    """The one GeoTIFF profile of the outputs written block by block (``BandWriter``): one
    band of ``dtype`` and ``nodata`` georeferenced like ``dem`` (a ``Dem`` or ``DemSource``),
    deflated at ``DEFLATE_LEVEL`` on every core, 256 x 256 tiles."""
    rows, cols = dem.shape
    # num_threads: GDAL compresses the blocks on every core (same bytes, less time); zlevel 1:
    # a 10000² shadow mask in 0.20 s instead of 0.31 s at level 3 (1.4 s at GDAL's default
    # 6), 7 % larger than at 3 (20 % than at 6); float32 bands about the same size and time
    # at 1 and 3
    prof = dict(driver="GTiff", width=cols, height=rows, count=1, dtype=dtype, nodata=nodata,
                compress="deflate", zlevel=DEFLATE_LEVEL, tiled=True, blockxsize=GTIFF_BLOCK,
                blockysize=GTIFF_BLOCK, num_threads="ALL_CPUS")
    if dem.crs is not None:
        prof["crs"] = dem.crs
    if dem.transform is not None:
        prof["transform"] = dem.transform
    return prof


def write_raster(path: str, data: np.ndarray, dem, nodata, description: str = "",
                 tags: dict | None = None, cog: bool = False,
                 overview_resampling: str = "nearest", overwrite: bool = False,
                 fmt: str | None = None) -> None:
    """Write one band georeferenced like ``dem`` (temporary file, then rename)."""
    with BandWriter(path, dem, 1, str(data.dtype), nodata, tags, cog,
                    overview_resampling, overwrite=overwrite, fmt=fmt) as w:
        w.write(1, data, description)


class BandWriter:
    """A raster georeferenced like ``dem`` (a ``Dem`` or a ``DemSource``) written one band, or
    one window of a band, at a time, into a temporary file published under ``path`` only when
    every band is written and the file closed without error (:mod:`.write`)::

        with BandWriter(path, dem, count, "uint8", 255) as w:
            w.write(1, mask, description="2026-06-21T14:30+02:00", tags={...})
            w.write(2, part, window=(r0, r1, c0, c1))

    The format is ``fmt`` or the path's extension (:func:`output_driver`): GeoTIFF is written
    directly; a COG (``cog``: 512 x 512 tiles, deflate, overviews by ``overview_resampling``) and
    the formats GDAL only copies into (PNG, JPEG, AAIGrid, ...) are made from a finished GeoTIFF
    beside the output, GDAL streaming block by block. Soft shadows (float32 0..1) in PNG are
    16-bit: 1 + round(65534 v), 0 nodata (like the hillshade's 1..255, 0 nodata)."""

    def __init__(self, path: str, dem, count: int, dtype: str, nodata, tags: dict | None = None,
                 cog: bool = False, overview_resampling: str = "nearest",
                 overwrite: bool = False, fmt: str | None = None):
        self.path, self.dem, self.count, self.dtype, self.nodata = path, dem, count, dtype, nodata
        self.tags = tags or {}
        self.cog, self.resampling, self.overwrite = cog, overview_resampling, overwrite
        self.driver = output_driver(path, fmt, cog)
        self.continuous = overview_resampling == "average"
        check_output_format(path, self.driver, dtype, count, self.continuous)
        # soft shadows in a 16-bit format: written as integers
        self.encode16 = self.driver in _INTEGER_ONLY and dtype == "float32"
        self._stack = contextlib.ExitStack()
        self._dst = None
        self._tmp = None
        self._finished = False

    def __enter__(self):
        import rasterio
        from rasterio.errors import NotGeoreferencedWarning

        dtype, nodata = ("uint16", 0) if self.encode16 else (self.dtype, self.nodata)
        prof = gtiff_profile(self.dem, dtype, nodata)
        prof["count"] = self.count
        if self.count > 1:
            prof["interleave"] = "band"   # bands are written one after another
        if dtype == "float32":
            prof["predictor"] = 3
        if self.dem.shape[0] * self.dem.shape[1] * np.dtype(dtype).itemsize * self.count > 2e9:
            prof["BIGTIFF"] = "IF_SAFER"
        try:
            self._final = self._stack.enter_context(
                atomic_path(self.path, ".tif" if self.driver in ("GTiff", "COG") else
                            os.path.splitext(self.path)[1] or ".out",
                            overwrite=self.overwrite, sidecars=True))
            if self.driver != "GTiff":   # the GeoTIFF the bands go into; copied at the end
                self._tmp = self._stack.enter_context(_scratch_path(self.path, ".tif"))
            self._stack.enter_context(warnings.catch_warnings())
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            with gdal_checked(self.path):
                self._dst = rasterio.open(self._tmp or self._final, "w", **prof)
            self._stack.callback(self._close)
            if self.tags:
                self._dst.update_tags(**{k: str(v) for k, v in self.tags.items()})
        except BaseException:
            # the contexts must see the failure: close() would exit them as if all went well,
            # and atomic_path would publish the empty temporary file
            if not self._stack.__exit__(*sys.exc_info()):
                raise
        return self

    def _close(self):
        if self._dst is not None:
            dst, self._dst = self._dst, None
            with gdal_checked(self.path):
                dst.close()

    def write(self, band: int, data: np.ndarray, description: str = "", tags: dict | None = None,
              window: tuple[int, int, int, int] | None = None):
        """Band ``band`` (1-based), whole or its ``window`` (r0, r1, c0, c1)."""
        if self.encode16:
            ok = np.isfinite(data) & (data != self.nodata)
            data = np.where(ok, 1 + np.rint(np.clip(data, 0, 1) * 65534), 0).astype(np.uint16)
        # as a 3-D view with a list of bands: given a 2-D array and one band, rasterio stacks
        # it into a new 3-D copy first (0.05-0.2 s of page faults for a 10000² mask)
        data3 = data[np.newaxis] if data.ndim == 2 else data
        with gdal_checked(self.path):
            if window is None:
                self._dst.write(data3, [band])
            else:
                from rasterio.windows import Window
                r0, r1, c0, c1 = window
                self._dst.write(data3, [band], window=Window(c0, r0, c1 - c0, r1 - r0))
            self.describe(band, description, tags)

    def describe(self, band: int, description: str = "", tags: dict | None = None):
        """Band ``band``'s description and tags."""
        if description:
            self._dst.set_band_description(band, description)
        if tags:
            self._dst.update_tags(band, **{k: str(v) for k, v in tags.items()})

    def finish(self) -> None:
        """Close the file and publish it now (GDAL compresses the last blocks at the close),
        not at the end of the ``with`` block, which then does nothing more: a caller can time
        it as part of writing."""
        self.__exit__(None, None, None)

    def __exit__(self, *exc):
        if self._finished:
            return False
        self._finished = True
        if exc[0] is None:
            try:
                self._close()
                if self.driver == "COG":
                    to_cog(self._tmp, self._final, self.resampling)
                elif self.driver != "GTiff":
                    _copy_as(self._tmp, self._final, self.driver, self.path)
            except BaseException as err:
                self._stack.__exit__(type(err), err, err.__traceback__)
                raise
        return self._stack.__exit__(*exc)


def _copy_as(src: str, dst: str, driver: str, shown: str) -> None:
    """The finished GeoTIFF ``src`` copied by GDAL into ``dst`` in ``driver``'s format."""
    import rasterio.shutil
    from rasterio.errors import NotGeoreferencedWarning
    opts = {"ZLEVEL": 6} if driver == "PNG" else {}
    with warnings.catch_warnings(), gdal_checked(shown):
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        rasterio.shutil.copy(src, dst, driver=driver, **opts)


@contextlib.contextmanager
def _scratch_path(path: str, suffix: str = ""):
    """A temporary path beside ``path``, always removed afterwards."""
    tmp = temp_beside(path, ".scratch" + suffix)
    try:
        yield tmp
    finally:
        for p in (tmp, tmp + ".ovr", tmp + ".aux.xml"):
            with contextlib.suppress(OSError):
                os.remove(p)


def to_cog(src: str, dst: str, resampling: str = "nearest", blocksize: int = 512,
           shown: str | None = None) -> None:
    """Copy the GeoTIFF (or VRT document) ``src`` to ``dst`` as a Cloud-Optimized GeoTIFF with
    overviews."""
    import rasterio
    import rasterio.shutil
    from rasterio.errors import NotGeoreferencedWarning
    with rasterio.open(src) as ds:
        dtype = ds.dtypes[0]
    opts = dict(driver="COG", COMPRESS="DEFLATE", BLOCKSIZE=blocksize,
                RESAMPLING=resampling.upper(), OVERVIEWS="AUTO", BIGTIFF="IF_SAFER")
    if dtype == "float32":
        opts["PREDICTOR"] = "YES"
    with warnings.catch_warnings(), gdal_checked(shown or dst, "cannot write a COG"):
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        rasterio.shutil.copy(src, dst, **opts)


def read_decimated(path: str, shape: tuple[int, int], band: int = 1) -> np.ndarray:
    """Band ``band`` of a raster just written, read at ``shape`` (GDAL's nearest, or its
    overviews), float32 with NaN on nodata: the values of a product for its preview."""
    import rasterio
    with rasterio.open(path) as ds:
        a = ds.read(band, out_shape=shape, masked=True)
    return np.ma.filled(a.astype(np.float32), np.nan)


def write_png(path: str, rgb: np.ndarray, overwrite: bool = False) -> None:
    """Write an (rows, cols, 3) uint8 picture as PNG (temporary file, checked, then rename)."""
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning

    rows, cols, _ = rgb.shape
    with atomic_path(path, ".png", overwrite=overwrite) as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        try:
            with gdal_checked(path):
                with rasterio.open(tmp, "w", driver="PNG", width=cols, height=rows, count=3,
                                   dtype="uint8") as dst:
                    dst.write(np.moveaxis(rgb, -1, 0))
        finally:
            with contextlib.suppress(OSError):
                os.remove(tmp + ".aux.xml")   # GDAL's side-car of a PNG: nothing worth keeping


def copy_vrt(doc: str, path: str, dtype: str, cog: bool = False,
             resampling: str = "nearest", overwrite: bool = False,
             fmt: str | None = None) -> None:
    """The GDAL VRT document ``doc`` copied (block by block, by GDAL) into ``path``: a tiled,
    deflated GeoTIFF, a COG, or the format ``fmt`` or the path's extension names (through a
    GeoTIFF); through a temporary file published when complete."""
    import rasterio.shutil
    drv = output_driver(path, fmt, cog)
    if drv == "COG":
        with atomic_path(path, ".tif", overwrite=overwrite) as tmp:
            to_cog(doc, tmp, resampling, shown=path)
        return
    check_output_format(path, drv, dtype, 1, False)
    opts = dict(driver="GTiff", TILED="YES", BLOCKXSIZE=GTIFF_BLOCK, BLOCKYSIZE=GTIFF_BLOCK, COMPRESS="DEFLATE",
                INTERLEAVE="BAND", BIGTIFF="IF_SAFER")
    if dtype == "float32":
        opts["PREDICTOR"] = 3
    if drv == "GTiff":
        with atomic_path(path, ".tif", overwrite=overwrite) as tmp, gdal_checked(path):
            rasterio.shutil.copy(doc, tmp, **opts)
        return
    with atomic_path(path, os.path.splitext(path)[1] or ".out", overwrite=overwrite,
                     sidecars=True) as tmp, _scratch_path(path, ".tif") as gtiff:
        with gdal_checked(path):
            rasterio.shutil.copy(doc, gtiff, **opts)
        _copy_as(gtiff, tmp, drv, path)
