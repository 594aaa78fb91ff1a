"""Reading DEMs (GDAL rasters, plain TIFF, raw grids) and writing results atomically.

Every DEM becomes a :class:`Dem`: float32 heights with NaN for nodata (the z-factor applied), the
geotransform and CRS of the source, and its :class:`~hillshade_rt.geometry.Grid` (ground spacing
per row). Outputs are written to a temporary file in the destination folder and renamed into
place only when complete.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import sys
import warnings
from dataclasses import dataclass, field

import numpy as np

from ._preload import while_numba_starts
from .errors import HillshadeError
from .geometry import Grid, grid_from_transform, orientation

RAW_DTYPES = ("int16", "uint16", "int32", "float32", "float64")
TIFF_EXTS = (".tif", ".tiff")
RAW_EXTS = (".raw", ".bin", ".dem", ".r32", ".r16", ".f32")

_HGT_NAME = re.compile(r"^([NS])(\d{2})([EW])(\d{3})", re.IGNORECASE)


@dataclass
class Dem:
    """A DEM in memory, ready for the shadow algorithms."""

    heights: np.ndarray          # float32, NaN = nodata, z-factor applied
    grid: Grid
    path: str
    kind: str                    # "gdal", "tiff" or "raw"
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
            from .algorithms.counts import valid_range
            n, lo, hi = valid_range(self.heights)
            self._survey = (int(n), float(lo), float(hi))
        return self._survey

    def valid_count(self) -> int:
        return self.survey()[0]

    def centre_height(self) -> tuple[float, str]:
        """The observer's height for suns from times (``sun.centre_height_of``)."""
        from .sun import centre_height_of
        return centre_height_of(self.heights)

    def height_range(self) -> tuple[float, float]:
        """(lowest, highest) valid height; (inf, -inf) when none is valid."""
        return self.survey()[1:]

    def crs_string(self) -> str | None:
        if self.crs is None:
            return None
        epsg = self.crs.to_epsg()
        return f"EPSG:{epsg}" if epsg else self.crs.to_wkt()

    def crs_name(self) -> str | None:
        return crs_name(self.crs)


# bodies by their mean or equatorial radius (m), IAU / NASA figures; a sphere or ellipsoid within
# 0.2 % of one is named after it
_BODIES = {"the Moon": 1737400.0, "Mars": 3396190.0, "Mars (mean)": 3389500.0,
           "Mercury": 2439700.0, "Venus": 6051800.0, "Ceres": 469700.0, "Vesta": 262700.0,
           "Europa": 1560800.0, "Ganymede": 2631200.0, "Callisto": 2410300.0, "Titan": 2574730.0,
           "Io": 1821600.0, "Pluto": 1188300.0}


def body_name(a_m: float) -> str | None:
    """The body whose radius is ``a_m`` (within 0.2 %), the Earth for the semi-major axes of its
    ellipsoids (``sun.EARTH_A_RANGE``)."""
    from .sun import EARTH_A_RANGE
    if EARTH_A_RANGE[0] <= a_m <= EARTH_A_RANGE[1]:
        return "the Earth"
    for name, r in _BODIES.items():
        if abs(a_m - r) <= 0.002 * r:
            return name.replace(" (mean)", "")
    return None


def crs_name(crs) -> str | None:
    """A CRS's name for people: its own, or, for one without a name (``+proj=stere
    +R=1737400``), the projection and the body or ellipsoid it is on ("Polar Stereographic
    (variant A) on the Moon (sphere, R 1737400 m)")."""
    if crs is None:
        return None
    from pyproj import CRS as PCRS
    try:
        pcrs = PCRS.from_user_input(crs.to_wkt() if hasattr(crs, "to_wkt") else crs)
    except Exception:  # noqa: BLE001 -- a name is only for display
        return crs.to_string()
    if pcrs.name and pcrs.name.lower() not in ("unknown", "unnamed", ""):
        return pcrs.name
    op = pcrs.coordinate_operation
    what = (op.method_name if op is not None and op.method_name else
            "geographic (longitude, latitude)" if pcrs.is_geographic else "unnamed CRS")
    ell = pcrs.ellipsoid
    if ell is None:
        return what
    a = ell.semi_major_metre
    shape = (f"sphere, R {a:.0f} m" if not ell.inverse_flattening
             else f"ellipsoid a {a:.0f} m, 1/f {ell.inverse_flattening:g}")
    named = ell.name if ell.name and ell.name.lower() not in ("unknown", "unnamed") else None
    body = body_name(a)
    on = ", ".join(x for x in (named, shape) if x)
    return f"{what} on {body + ' (' + on + ')' if body else on}"


def parse_pixel_size(text: str | None) -> tuple[float, float] | None:
    """'DX' or 'DX,DY' (metres) -> (dx, dy)."""
    if text is None:
        return None
    parts = [p.strip() for p in str(text).split(",")]
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        raise HillshadeError(f"--pixel-size must be DX or DX,DY in metres, got {text!r}") from None
    if len(vals) not in (1, 2) or not all(math.isfinite(v) and v > 0 for v in vals):
        raise HillshadeError(f"--pixel-size must be one or two positive numbers, got {text!r}")
    return (vals[0], vals[-1])


def check_z_factor(z_factor: float) -> float:
    """``-z/--z-factor``: a finite, non-zero number."""
    if not (math.isfinite(z_factor) and z_factor != 0):
        raise HillshadeError(f"--z-factor must be a finite non-zero number, got {z_factor}")
    return z_factor


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


# --------------------------------------------------------------------------------------------
# reading

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
_TIFF_MAGIC = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")
_CORRUPT_HINTS = re.compile(r"TIFF|IReadBlock|read error|decod|decompress|truncat|corrupt|"
                            r"checksum|data check|unexpected end|short read", re.IGNORECASE)


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


def _has_tiff_magic(path: str, data: bytes | None = None) -> bool:
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
    tiff = _has_tiff_magic(path, data) if (data is not None or os.path.isfile(path)) else False
    if tiff or ("not recognized" not in low and _CORRUPT_HINTS.search(msg)):
        return HillshadeError(f"{path}: truncated or corrupt ({msg})")
    if "not recognized as" in low or "not recognised" in low:
        msg = "not a raster format GDAL can read"
    return HillshadeError(f"{path}: cannot read as a raster ({msg})")


def read_error(path: str, exc: BaseException, gdal_name: str | None = None) -> HillshadeError:
    """The one-line error for a dataset that opened but whose values could not be read."""
    return HillshadeError(f"{path}: truncated or corrupt "
                          f"({gdal_message(exc, path, gdal_name or path)})")


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


def _read_stdin() -> bytes:
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


def read_dem(path: str, *, band: int = 1, nodata: float | None = None,
             pixel_size: tuple[float, float] | None = None, z_factor: float = 1.0,
             raw_shape: tuple[int, int] | None = None, raw_dtype: str | None = None,
             raw_byteorder: str | None = None) -> Dem:
    """Read a DEM from ``path``.

    ``path``: a local file, any dataset name GDAL opens (``/vsizip/a.zip/dem.tif``,
    ``zip://a.zip!dem.tif``, ``/vsigzip/…``, ``/vsimem/…``, ``/vsicurl/…``, ``NETCDF:f.nc:z``),
    or ``-``: all of standard input, read into memory (any format GDAL reads, or raw with the
    ``raw_*`` options).
    Dispatch: raw binary when any ``raw_*`` option is given, or for .hgt files GDAL cannot
    georeference, or for the raw extensions (.raw .bin .dem .r16 .r32 .f32); TIFF files without
    georeferencing through tifffile; everything else through rasterio (GDAL).
    ``pixel_size`` (metres) overrides the spacing from the geotransform; it is required when the
    input has no georeferencing.
    """
    path = os.fspath(path)
    check_input_path(path)
    check_z_factor(z_factor)
    if band < 1:
        raise HillshadeError(f"--band must be 1 or more, got {band}")
    data = None
    if path == STDIN:
        data = _read_stdin()
        path = STDIN_NAME
    ext = os.path.splitext(path)[1].lower() if data is None else ""
    raw_requested = raw_shape is not None or raw_dtype is not None or raw_byteorder is not None
    if raw_requested or ext in RAW_EXTS:
        dem = _read_raw(path, raw_shape, raw_dtype, raw_byteorder, nodata, pixel_size, data)
    elif ext == ".hgt":
        try:
            dem = _read_gdal(path, band, nodata, pixel_size)
        except HillshadeError:
            if is_gdal_name(path) and not os.path.exists(path):
                raise
            dem = _read_raw(path, None, "int16", "big", nodata, pixel_size)
    else:
        tiff = ext in TIFF_EXTS or (data is not None and _has_tiff_magic(path, data))
        dem = _read_gdal(path, band, nodata, pixel_size, tiff_fallback=tiff, data=data)
    if z_factor != 1.0:
        with np.errstate(over="ignore"):
            dem.heights *= np.float32(z_factor)
        # a height the factor takes beyond float32 is no height (NaN, as -inf/inf on reading)
        dem._survey = heights_into(dem.heights, None, dem.heights)
    if dem.heights.size == 0:
        raise HillshadeError(f"{path}: the raster is empty")
    if dem.valid_count() == 0:
        raise HillshadeError(f"{path}: every cell is nodata, nothing to shade")
    return dem


def _to_heights(data: np.ndarray, nodata: float | None) -> tuple[np.ndarray, tuple | None]:
    """float32 heights with nodata (and NaN, and +-inf) as NaN, and their survey when the pass
    found it (``heights_into``).

    ``data`` is an array this module has just read and owns: a float32 one is converted in place,
    any other type is cast once.
    """
    z = data.astype(np.float32, copy=False)
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
        from .algorithms.counts import clean_heights
        use = nodata is not None and not math.isnan(nodata)
        n, lo, hi = clean_heights(data, float(nodata) if use else 0.0, use)
        return int(n), float(lo), float(hi)
    # one boolean scratch array and masked copies, no fancy indexing: on a 10000² DEM the read
    # stage spent 1 s here (four temporaries and two boolean-index passes)
    mask = np.empty(out.shape, np.bool_)
    bad = False
    if nodata is not None and not math.isnan(nodata):
        nd = np.asarray(nodata).astype(data.dtype)
        if data.dtype.kind == "f" or float(nd) == float(nodata):
            np.equal(data, nd, out=mask)
            bad = True
    if out is not data:
        out[...] = data
    nan = np.float32(np.nan)
    if bad:
        np.copyto(out, nan, where=mask)
    np.isfinite(out, out=mask)
    np.logical_not(mask, out=mask)
    np.copyto(out, nan, where=mask)
    if z_factor != 1.0:
        out *= np.float32(z_factor)


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
    """``path`` opened by rasterio inside ``stack``: what GDAL opens is ``name``, or
    :func:`gdal_path` of ``path``, or ``data`` (the bytes of a raster held in memory, e.g.
    standard input, through a ``rasterio.MemoryFile``); GDAL's refusal as :func:`open_error`,
    naming ``path``."""
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning, RasterioError

    stack.enter_context(warnings.catch_warnings())
    warnings.simplefilter("ignore", NotGeoreferencedWarning)
    if data is None and name is None:
        name = gdal_path(path)
    try:
        if data is not None:
            return stack.enter_context(stack.enter_context(rasterio.MemoryFile(data)).open())
        return stack.enter_context(rasterio.open(name))
    except (RasterioError, OSError) as exc:
        raise open_error(path, exc, data=data, gdal_name=name) from None


def _read_gdal(path: str, band: int, nodata: float | None,
               pixel_size: tuple[float, float] | None, tiff_fallback: bool = False,
               data: bytes | None = None) -> Dem:
    """Through rasterio (GDAL); ``data``: the raster's bytes (standard input), ``path`` then only
    names it. A TIFF GDAL cannot open, or one without georeferencing, goes to tifffile."""
    from rasterio.errors import RasterioError

    with contextlib.ExitStack() as stack:
        try:
            ds = open_raster(path, stack, data)
        except HillshadeError:
            if tiff_fallback:
                with contextlib.suppress(HillshadeError):
                    return _read_tiff(path, band, nodata, pixel_size, data)
            raise
        georef = check_band(ds, path, band)
        if not georef and tiff_fallback:
            try:
                return _read_tiff(path, band, nodata, pixel_size, data)
            except _TiffUnreadable:
                pass    # GDAL reads it, or says why it cannot (truncated, corrupt)
        try:     # (numba starts meanwhile: its first kernel follows, the nodata pass)
            values = while_numba_starts(lambda: ds.read(band))
        except (RasterioError, OSError) as exc:
            raise read_error(path, exc, gdal_path(path)) from None
        src_nodata = ds.nodatavals[band - 1]
        nd = src_nodata if nodata is None else nodata
        z, survey = _to_heights(values, nd)
        dem = Dem(heights=z, grid=None, path=path,  # type: ignore[arg-type]
                  kind="gdal", transform=ds.transform if georef else None, crs=ds.crs,
                  nodata=nd, band=band, driver=ds.driver, source_dtype=str(values.dtype),
                  _survey=survey)
    dem.grid = _make_grid(dem, pixel_size)
    return dem


class _TiffUnreadable(HillshadeError):
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


def _read_tiff(path: str, band: int, nodata: float | None,
               pixel_size: tuple[float, float] | None, data: bytes | None = None) -> Dem:
    """A TIFF without georeferencing, through tifffile (``data``: its bytes, held in memory)."""
    import io as _io

    import tifffile

    try:
        with _quiet_logger("tifffile"), \
                tifffile.TiffFile(_io.BytesIO(data) if data is not None else path) as tif:
            page = tif.pages[0]
            values = page.asarray()
            tag = page.tags.get("GDAL_NODATA") or page.tags.get(42113)
            file_nodata = float(str(tag.value).strip("\x00 ")) if tag is not None else None
    except Exception as exc:  # noqa: BLE001 -- tifffile raises many kinds for bad files
        msg = " ".join(str(exc).split()) or type(exc).__name__
        raise _TiffUnreadable(f"{path}: cannot read as a TIFF ({msg})") from None
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
    nd = file_nodata if nodata is None else nodata
    z, survey = _to_heights(values, nd)
    dem = Dem(heights=z, grid=None, path=path,  # type: ignore[arg-type]
              kind="tiff", nodata=nd, band=band, driver="TIFF (tifffile)",
              source_dtype=str(values.dtype), _survey=survey)
    dem.grid = _make_grid(dem, pixel_size)
    return dem


def _hgt_geometry(path: str, rows: int):
    """Transform and CRS of an SRTM .hgt tile from its name (cell centres on whole degrees)."""
    m = _HGT_NAME.match(os.path.basename(path))
    if not m or rows < 2:
        return None, None
    from affine import Affine
    from rasterio.crs import CRS

    lat = int(m.group(2)) * (1 if m.group(1).upper() == "N" else -1)
    lon = int(m.group(4)) * (1 if m.group(3).upper() == "E" else -1)
    step = 1.0 / (rows - 1)
    return (Affine(step, 0, lon - step / 2, 0, -step, lat + 1 + step / 2),
            CRS.from_epsg(4326))


def _read_raw(path: str, shape: tuple[int, int] | None, dtype: str | None,
              byteorder: str | None, nodata: float | None,
              pixel_size: tuple[float, float] | None, data: bytes | None = None) -> Dem:
    """A raw grid from a local file, or from ``data`` (its bytes: standard input)."""
    if data is None and not os.path.isfile(path):
        raise HillshadeError(f"{path}: a raw grid is read from a local file or standard input "
                             "only (GDAL reads it from elsewhere given an ENVI .hdr or a VRT)")
    is_hgt = path.lower().endswith(".hgt")
    size = os.path.getsize(path) if data is None else len(data)
    if size == 0:
        raise HillshadeError(f"{path}: the file is empty")
    if is_hgt:
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
        if not is_hgt or side * side != count:
            raise HillshadeError(f"{path}: raw input needs --raw-shape ROWSxCOLS")
        shape = (side, side)
    if shape[0] * shape[1] != count:
        raise HillshadeError(
            f"{path}: --raw-shape {shape[0]}x{shape[1]} needs {shape[0] * shape[1]} {dtype} values "
            f"({shape[0] * shape[1] * dt.itemsize} bytes), the file holds {count} ({size} bytes)")
    if data is None:
        values = np.fromfile(path, dtype=dt).reshape(shape)
    else:   # a writable copy: float32 heights are converted in place
        values = np.frombuffer(bytearray(data), dtype=dt).reshape(shape)
    transform, crs = _hgt_geometry(path, shape[0]) if is_hgt else (None, None)
    z, survey = _to_heights(values, nodata)
    dem = Dem(heights=z, grid=None, path=path,  # type: ignore[arg-type]
              kind="raw", transform=transform, crs=crs, nodata=nodata,
              driver="raw" if not is_hgt else "SRTM .hgt (raw)", source_dtype=dt.str,
              _survey=survey)
    dem.grid = _make_grid(dem, pixel_size)
    return dem


def _make_grid(dem: Dem, pixel_size: tuple[float, float] | None) -> Grid:
    return grid_of(dem.path, dem.transform, dem.crs, dem.heights.shape, pixel_size)


# --------------------------------------------------------------------------------------------
# writing

# re-exported: the checks and the atomic publishing live in ``writes``
from .writes import atomic_path, check_output_path, gdal_checked  # noqa: E402

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


DEFLATE_LEVEL = 1   # GeoTIFF outputs: DEFLATE at this level (see _profile)


def _profile(dem: Dem, dtype: str, nodata) -> dict:
    rows, cols = dem.shape
    # num_threads: GDAL compresses the blocks on every core (same bytes, less time); zlevel 1:
    # a 10000² shadow mask in 0.20 s instead of 0.31 s at level 3 (1.4 s at GDAL's default
    # 6), 7 % larger than at 3 (20 % than at 6); float32 bands about the same size and time
    # at 1 and 3
    prof = dict(driver="GTiff", width=cols, height=rows, count=1, dtype=dtype, nodata=nodata,
                compress="deflate", zlevel=DEFLATE_LEVEL, tiled=True, blockxsize=256,
                blockysize=256, num_threads="ALL_CPUS")
    if dem.crs is not None:
        prof["crs"] = dem.crs
    if dem.transform is not None:
        prof["transform"] = dem.transform
    return prof


def write_raster(path: str, data: np.ndarray, dem: Dem, nodata, description: str = "",
                 tags: dict | None = None, cog: bool = False,
                 overview_resampling: str = "nearest", overwrite: bool = False,
                 fmt: str | None = None) -> None:
    """Write one band georeferenced like ``dem`` (temporary file, then rename)."""
    with BandWriter(path, dem, 1, str(data.dtype), nodata, tags, cog,
                    overview_resampling, overwrite=overwrite, fmt=fmt) as w:
        w.write(1, data, description)


def write_json(path: str, obj: dict, overwrite: bool = False) -> None:
    """Write ``obj`` as JSON (temporary file, checked close, then rename)."""
    from .writes import os_error
    text = json.dumps(obj, indent=2) + "\n"
    with atomic_path(path, overwrite=overwrite) as tmp:
        try:
            with open(tmp, "w", encoding="utf-8") as fh:
                fh.write(text)
        except OSError as exc:
            raise os_error(path, exc) from None


class BandWriter:
    """A raster georeferenced like ``dem`` (a :class:`Dem` or a ``tiling.Source``) written one
    band, or one window of a band, at a time, into a temporary file published under ``path``
    only when every band is written and the file closed without error (``writes``)::

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
        prof = _profile(self.dem, dtype, nodata)
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
    from .writes import temp_beside
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
    opts = dict(driver="GTiff", TILED="YES", BLOCKXSIZE=256, BLOCKYSIZE=256, COMPRESS="DEFLATE",
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
