"""Writing rasters: the GDAL driver an output gets and what it can hold, the one GeoTIFF profile,
:class:`BandWriter` (bands or windows of bands into one file), COGs, copies of VRT documents,
PNG pictures. Every file goes through :func:`.write.atomic_path` (a temporary file beside it,
published whole or not at all) and its GDAL calls through :func:`.write.gdal_checked`."""

from __future__ import annotations

import contextlib
import logging
import os
import re
import sys
import warnings

import numpy as np

from ..errors import HillshadeError, UsageProblem
from .write import GdalRecords, atomic_path, gdal_checked, temp_beside

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
    if not _can_write(drv):
        raise HillshadeError(f"{path}: GDAL's {drv} driver reads only, it cannot write (e.g. "
                             "GTiff, COG, PNG, HFA, ENVI, AAIGrid)")
    if cog:
        if drv not in ("GTiff", "COG"):
            raise HillshadeError(f"{path}: --cog writes a GeoTIFF; this path names {drv}")
        drv = "COG"
    return drv


def _can_write(drv: str) -> bool:
    """Whether GDAL's driver ``drv`` creates datasets (Create or CreateCopy)."""
    import rasterio
    try:
        from rasterio._base import driver_can_create, driver_can_create_copy
    except ImportError:     # (not public API: assume it can, GDAL says otherwise when it copies)
        return True
    with rasterio.Env():
        return bool(driver_can_create(drv) or driver_can_create_copy(drv))


def check_output_format(path: str, drv: str, dtype: str, count: int, continuous: bool,
                        co: dict | None = None, resampling: str = "nearest") -> None:
    """Refuse what ``drv`` cannot hold: float values in an integer-only format (soft shadows in
    PNG are the exception: 16 bits, see :class:`BandWriter`), a lossy format for masks, a
    lossy compression (``co``) for masks and classes, more bands than one in a picture
    format; then, for any format but the default GeoTIFF and COG, and whenever there are
    creation options ``co`` (``--co``), GDAL's own verdict on the file
    (:func:`check_creation`): before any work, nothing written."""
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
    co = co or {}
    lossy = _lossy_compression(co)
    if lossy and not continuous and dtype != "float32":   # (floats: LERC's error is a choice)
        raise HillshadeError(f"{path}: --co {lossy} is lossy and would change the mask's "
                             "values; use a lossless COMPRESS (DEFLATE, ZSTD, LZW, ...)")
    if co or drv not in ("GTiff", "COG"):
        written = "uint16" if drv in _INTEGER_ONLY and dtype == "float32" else dtype
        check_creation(path, drv, written, count,
                       output_options(drv, written, count, co, resampling), co)


# --------------------------------------------------------------------------------------------
# creation options: --co NAME=VALUE (rasterio's spelling) over the tool's defaults

_YES = ("YES", "TRUE", "ON", "1")
# the codecs GDAL's GeoTIFF and COG drivers apply a PREDICTOR to
_PREDICTED = ("DEFLATE", "LZW", "ZSTD", "LZMA")
# rasterio.open's own keywords: everything else in a profile is a creation option
_PROFILE_KEYS = ("driver", "width", "height", "count", "dtype", "nodata", "crs", "transform")


def parse_creation_options(items) -> dict:
    """``--co NAME=VALUE`` as rasterio's ``--co`` takes them (a sequence of "NAME=VALUE", or a
    mapping in the Python API) -> {NAME: VALUE}: names upper-cased (GDAL's are case-blind),
    the last of a name winning, True/False as YES/NO. A malformed one (no "=", no name or an
    odd one, no value) is a :class:`UsageProblem` (exit status 2)."""
    if not items:
        return {}
    if isinstance(items, str):
        items = [items]
    if hasattr(items, "items"):
        pairs = list(items.items())
    else:
        pairs = []
        for item in items:
            name, sep, value = str(item).partition("=")
            if not sep:
                raise UsageProblem(f"--co {item}: expected NAME=VALUE, e.g. --co COMPRESS=ZSTD")
            pairs.append((name, value))
    out = {}
    for name, value in pairs:
        name = str(name).strip()
        if isinstance(value, bool):
            value = "YES" if value else "NO"
        value = "" if value is None else str(value).strip()
        if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", name) or not value:
            raise UsageProblem(f"--co {name}={value}: expected NAME=VALUE, e.g. "
                               "--co COMPRESS=ZSTD")
        out[name.upper()] = value
    return out


def merged_options(defaults: dict, co: dict | None = None) -> dict:
    """The creation options of one file: the tool's ``defaults`` (names upper-cased, True/False
    as YES/NO) overridden by the user's ``co``. A default that belongs to the default
    compression goes when ``co`` names another: its level (ZLEVEL, LEVEL), and the PREDICTOR
    unless the new codec takes one; BLOCKXSIZE goes with TILED=NO (strips)."""
    out = {}
    for k, v in defaults.items():
        if v is None:
            continue
        out[k.upper()] = ("YES" if v else "NO") if isinstance(v, bool) else str(v)
    co = co or {}
    comp = co.get("COMPRESS")
    if comp is not None and comp.upper() != out.get("COMPRESS", "").upper():
        for k in ("ZLEVEL", "LEVEL"):
            out.pop(k, None)
        if comp.upper() not in _PREDICTED:
            out.pop("PREDICTOR", None)
    if co.get("TILED", "YES").upper() not in _YES:
        out.pop("BLOCKXSIZE", None)
    out.update(co)
    return out


def _split(prof: dict) -> tuple[dict, dict]:
    """A rasterio profile as (rasterio.open's keywords, creation options upper-cased)."""
    return ({k: v for k, v in prof.items() if k in _PROFILE_KEYS},
            merged_options({k: v for k, v in prof.items() if k not in _PROFILE_KEYS}))


def output_options(drv: str, dtype: str, count: int, co: dict | None = None,
                   resampling: str = "nearest", big: bool = False) -> dict:
    """The creation options a finished output of ``drv`` is written with: the tool's defaults
    for it (GeoTIFF: :func:`gtiff_profile`'s and :class:`BandWriter`'s; COG: :func:`to_cog`'s;
    PNG: ZLEVEL 6; others: GDAL's) overridden by ``co`` (:func:`merged_options`)."""
    if drv == "GTiff":
        defaults = dict(COMPRESS="DEFLATE", ZLEVEL=DEFLATE_LEVEL, TILED=True,
                        BLOCKXSIZE=GTIFF_BLOCK, BLOCKYSIZE=GTIFF_BLOCK, NUM_THREADS="ALL_CPUS")
        if count > 1:
            defaults["INTERLEAVE"] = "BAND"   # bands are written one after another
        if dtype == "float32":
            defaults["PREDICTOR"] = 3
        if big:
            defaults["BIGTIFF"] = "IF_SAFER"
    elif drv == "COG":
        defaults = dict(COMPRESS="DEFLATE", BLOCKSIZE=COG_BLOCK, RESAMPLING=resampling.upper(),
                        OVERVIEWS="AUTO", BIGTIFF="IF_SAFER")
        if dtype == "float32":
            defaults["PREDICTOR"] = "YES"
    elif drv == "PNG":
        defaults = {"ZLEVEL": 6}
    else:
        defaults = {}
    return merged_options(defaults, co)


def _lossy_compression(co: dict) -> str | None:
    """The ``--co`` that makes a GeoTIFF's compression lossy (COMPRESS=JPEG, WEBP without
    WEBP_LOSSLESS, LERC with a MAX_Z_ERROR), if any."""
    comp = co.get("COMPRESS", "").upper()
    if comp == "JPEG":
        return "COMPRESS=JPEG"
    if comp == "WEBP" and co.get("WEBP_LOSSLESS", "NO").upper() not in _YES:
        return "COMPRESS=WEBP"
    if comp.startswith("LERC"):
        try:
            if float(co.get("MAX_Z_ERROR", "0")) > 0:
                return f"COMPRESS={comp} with MAX_Z_ERROR={co['MAX_Z_ERROR']}"
        except ValueError:
            pass
    return None


# the GeoTIFF driver's options that the COG driver spells otherwise, and back
_OTHER_NAME = {"COG": {"BLOCKXSIZE": "BLOCKSIZE", "BLOCKYSIZE": "BLOCKSIZE", "ZLEVEL": "LEVEL",
                       "ZSTD_LEVEL": "LEVEL", "TILED": "BLOCKSIZE: it is always tiled"},
               "GTiff": {"BLOCKSIZE": "BLOCKXSIZE and BLOCKYSIZE",
                         "LEVEL": "ZLEVEL, ZSTD_LEVEL or LZMA_PRESET"}}

_PROBE_BANDS = 16      # bands of a trial file at most (2000 bands: 1 s)
_VERDICTS: dict = {}   # check_creation's answers: (driver, type, bands, ext, options) -> reason


def check_creation(path: str, drv: str, dtype: str, count: int, options: dict,
                   co: dict | None = None) -> None:
    """GDAL's verdict on writing ``count`` bands of ``dtype`` to ``path`` with ``drv`` and the
    creation ``options``, before any work: a 16 x 16 dataset of the same kind written in a
    temporary folder (removed) the way the output will be (GeoTIFF directly, other formats by
    copying a GeoTIFF). GDAL checks the options against the driver's creation option list
    (DMD_CREATIONOPTIONLIST: names, types, allowed values) but only warns; here every warning
    or error GDAL signals is a :class:`HillshadeError` naming the ``--co`` (of ``co``) it is
    about, e.g. "out.tif: --co FOO=1: driver GTiff does not support creation option FOO"."""
    ext = ".tif" if drv in ("GTiff", "COG") else (os.path.splitext(path)[1] or ".out")
    # a year of hourly bands tried as 16: the drivers' limits on bands are 1, 3 or 4, or 2^16
    bands = min(count, _PROBE_BANDS)
    key = (drv, dtype, bands, ext, tuple(sorted(options.items())))
    if key not in _VERDICTS:
        _VERDICTS[key] = _probe(drv, dtype, bands, ext, options)
    reason = _VERDICTS[key]
    if reason is None:
        return
    co = co or {}
    named = [k for k in co if re.search(rf"\b{k}\b", reason, re.IGNORECASE)]
    if named:
        shown = f"--co {named[0]}={co[named[0]]}"
        other = _OTHER_NAME.get(drv, {}).get(named[0])
        if other and "does not support" in reason:
            reason += f" ({drv} takes {other})"
    elif co:
        shown = f"{drv} with " + " ".join(f"--co {k}={v}" for k, v in co.items())
    else:
        shown = f"{drv} cannot hold {count} band{'s' if count > 1 else ''} of {dtype}"
    raise HillshadeError(f"{path}: {shown}: {reason}")


class _GdalSignals(GdalRecords):
    """What GDAL signals in this thread while a probe runs: errors (``io.write``'s records),
    then warnings."""

    def __init__(self):
        super().__init__()
        self.errors = self.messages
        self.warnings: list[str] = []

    def emit(self, record):
        if record.thread != self.thread:
            return
        n = len(self.errors)
        super().emit(record)
        if len(self.errors) == n and record.levelno >= logging.WARNING:
            msg = record.getMessage()
            # "CPLE_NotSupported in driver GTiff does not support creation option FOO"
            self.warnings.append(msg.split(" in ", 1)[-1] if msg.startswith("CPLE_") else msg)


def _probe(drv: str, dtype: str, count: int, ext: str, options: dict) -> str | None:
    """Write a 16 x 16 dataset as :func:`check_creation` says; None, or GDAL's first word."""
    import tempfile

    import rasterio
    import rasterio.shutil
    from rasterio.errors import NotGeoreferencedWarning
    from rasterio.transform import from_origin

    from .write import stderr_dropped

    signals = _GdalSignals()
    loggers = [logging.getLogger(n) for n in ("rasterio._env", "rasterio._err", "rasterio._io",
                                              "rasterio._base")]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.addHandler(signals)
        if lg.getEffectiveLevel() > logging.INFO:
            lg.setLevel(logging.INFO)
    failure = None
    # what GDAL's TIFF library prints (from its compression threads too) is the probe's only
    try:
        with tempfile.TemporaryDirectory(prefix="hillshade-rt-co-") as tmp, stderr_dropped(), \
                warnings.catch_warnings(), rasterio.Env(GDAL_VALIDATE_CREATION_OPTIONS="YES"):
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            prof = dict(width=16, height=16, count=count, dtype=dtype,
                        transform=from_origin(0, 16, 1, 1))
            data = np.zeros((count, 16, 16), dtype)
            try:
                if drv == "GTiff":
                    with rasterio.open(os.path.join(tmp, "probe.tif"), "w", driver="GTiff",
                                       **prof, **options) as dst:
                        dst.write(data)
                else:
                    src = os.path.join(tmp, "src.tif")
                    with rasterio.open(src, "w", driver="GTiff", **prof) as dst:
                        dst.write(data)
                    rasterio.shutil.copy(src, os.path.join(tmp, "probe" + ext), driver=drv,
                                         **options)
            except Exception as exc:     # GDAL's, rasterio's (block sizes), numpy's
                failure = str(exc).splitlines()[0].strip() if str(exc) else type(exc).__name__
    finally:
        for lg, level in zip(loggers, levels):
            lg.removeHandler(signals)
            lg.setLevel(level)
    # rasterio's exception when it says something, else what GDAL signalled, errors first
    said = [_plain(m) for m in ([failure] if failure else []) + signals.errors + signals.warnings]
    useful = [m for m in said if m and "see previous exception" not in m.lower()]
    return (useful or [m for m in said if m] or [None])[0]


def _plain(message: str) -> str:
    """GDAL's message about a probe, without the probe's files and libtiff's function names."""
    m = " ".join(message.replace("\\n", " ").split())
    m = re.sub(r"\S*hillshade-rt-co-[^/\s]*/", "", m)
    m = re.sub(r"^_?TIFF\w*:\s*", "", m)
    return re.sub(r"^(src|probe)\.\w+(, band \d+)?:\s*", "", m)


DEFLATE_LEVEL = 1   # GeoTIFF outputs: DEFLATE at this level (see gtiff_profile)
GTIFF_BLOCK = 256   # their tiles' side
COG_BLOCK = 512     # a COG's tiles' side


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
                 fmt: str | None = None, co: dict | None = None) -> None:
    """Write one band georeferenced like ``dem`` (temporary file, then rename)."""
    with BandWriter(path, dem, 1, str(data.dtype), nodata, tags, cog,
                    overview_resampling, overwrite=overwrite, fmt=fmt, co=co) as w:
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
    16-bit: 1 + round(65534 v), 0 nodata (like the hillshade's 1..255, 0 nodata).

    ``co``: the user's creation options (``--co``, :func:`parse_creation_options`) over the
    tool's defaults (:func:`output_options`) for the file published: the GeoTIFF written
    directly, or the COG or other format copied at the end (the GeoTIFF in between keeps the
    defaults); checked by GDAL before anything is written (:func:`check_output_format`)."""

    def __init__(self, path: str, dem, count: int, dtype: str, nodata, tags: dict | None = None,
                 cog: bool = False, overview_resampling: str = "nearest",
                 overwrite: bool = False, fmt: str | None = None, co: dict | None = None):
        self.path, self.dem, self.count, self.dtype, self.nodata = path, dem, count, dtype, nodata
        self.tags = tags or {}
        self.cog, self.resampling, self.overwrite = cog, overview_resampling, overwrite
        self.co = dict(co or {})
        self.driver = output_driver(path, fmt, cog)
        self.continuous = overview_resampling == "average"
        check_output_format(path, self.driver, dtype, count, self.continuous, self.co,
                            overview_resampling)
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
        prof, _ = _split(gtiff_profile(self.dem, dtype, nodata))
        prof["count"] = self.count
        big = self.dem.shape[0] * self.dem.shape[1] * np.dtype(dtype).itemsize * self.count > 2e9
        # the output itself (--co over the defaults), or the GeoTIFF another format is copied
        # from (the defaults)
        prof.update(output_options("GTiff", dtype, self.count,
                                   self.co if self.driver == "GTiff" else None, big=big))
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
                    to_cog(self._tmp, self._final, self.resampling, shown=self.path,
                           co=self.co)
                elif self.driver != "GTiff":
                    _copy_as(self._tmp, self._final, self.driver, self.path, self.co)
            except BaseException as err:
                self._stack.__exit__(type(err), err, err.__traceback__)
                raise
        return self._stack.__exit__(*exc)


def _copy_as(src: str, dst: str, driver: str, shown: str, co: dict | None = None) -> None:
    """The finished GeoTIFF ``src`` copied by GDAL into ``dst`` in ``driver``'s format, with
    the creation options ``co`` over the tool's (:func:`output_options`)."""
    import rasterio.shutil
    from rasterio.errors import NotGeoreferencedWarning
    opts = output_options(driver, "", 1, co)
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


def to_cog(src: str, dst: str, resampling: str = "nearest", blocksize: int = COG_BLOCK,
           shown: str | None = None, co: dict | None = None) -> None:
    """Copy the GeoTIFF (or VRT document) ``src`` to ``dst`` as a Cloud-Optimized GeoTIFF with
    overviews: deflated, ``blocksize`` tiles, the user's creation options ``co`` (``--co``,
    the COG driver's: COMPRESS, LEVEL, BLOCKSIZE, PREDICTOR, ...) over these."""
    import rasterio
    import rasterio.shutil
    from rasterio.errors import NotGeoreferencedWarning
    with rasterio.open(src) as ds:
        dtype, count = ds.dtypes[0], ds.count
    opts = output_options("COG", dtype, count, {"BLOCKSIZE": str(blocksize), **(co or {})},
                          resampling)
    with warnings.catch_warnings(), gdal_checked(shown or dst, "cannot write a COG"):
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        rasterio.shutil.copy(src, dst, driver="COG", **opts)


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
             fmt: str | None = None, co: dict | None = None) -> None:
    """The GDAL VRT document ``doc`` copied (block by block, by GDAL) into ``path``: a tiled,
    deflated GeoTIFF, a COG, or the format ``fmt`` or the path's extension names (through a
    GeoTIFF); through a temporary file published when complete. ``co``: the user's creation
    options for ``path`` (``--co``) over these."""
    import rasterio.shutil
    co = dict(co or {})
    drv = output_driver(path, fmt, cog)
    check_output_format(path, drv, dtype, 1, False, co, resampling)
    if drv == "COG":
        with atomic_path(path, ".tif", overwrite=overwrite) as tmp:
            to_cog(doc, tmp, resampling, shown=path, co=co)
        return
    defaults = dict(TILED="YES", BLOCKXSIZE=GTIFF_BLOCK, BLOCKYSIZE=GTIFF_BLOCK,
                    COMPRESS="DEFLATE", INTERLEAVE="BAND", BIGTIFF="IF_SAFER")
    if dtype == "float32":
        defaults["PREDICTOR"] = 3
    if drv == "GTiff":
        with atomic_path(path, ".tif", overwrite=overwrite) as tmp, gdal_checked(path):
            rasterio.shutil.copy(doc, tmp, driver="GTiff", **merged_options(defaults, co))
        return
    with atomic_path(path, os.path.splitext(path)[1] or ".out", overwrite=overwrite,
                     sidecars=True) as tmp, _scratch_path(path, ".tif") as gtiff:
        with gdal_checked(path):
            rasterio.shutil.copy(doc, gtiff, driver="GTiff", **merged_options(defaults))
        _copy_as(gtiff, tmp, drv, path, co)
