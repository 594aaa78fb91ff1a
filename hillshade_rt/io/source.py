"""One way in for every DEM: :func:`open_dem` opens and checks it once, :class:`DemSource` reads it.

``open_dem(paths, options)`` takes a local file, any dataset name GDAL opens (``/vsizip/…``,
``zip://a.zip!dem.tif``, ``https://…``, ``NETCDF:f.nc:z``), ``-`` (all of standard input, read
into memory), or several paths shaded as one mosaic. It opens the DEM, checks it (the path, the
options, the band, the value type, the geotransform) and makes its :class:`Grid`, once, without
reading its values. The source then gives them

* whole: :meth:`DemSource.read` -> :class:`~.dem.Dem` (float32 heights in memory), or
* in windows: :meth:`DemSource.reader` -> :class:`Reader` (rows x columns at a time, bounded
  scratch: rasters larger than memory, Dask workers).

Dispatch, decided at opening: raw binary when any ``raw_*`` option is given or for the raw
extensions (.raw .bin .dem .r16 .r32 .f32), memory-mapped for windows; a .hgt tile through GDAL,
or as raw when GDAL cannot georeference it; several paths as a mosaic (a VRT document in memory,
float32 with NaN where no input has a valid cell); everything else through rasterio (GDAL). A
TIFF without georeferencing is read whole through tifffile (GDAL reads it in windows, and whole
when tifffile cannot); one that only tifffile opens is read at opening and can be read whole
only, as can a DEM from standard input.

The dataset opened to check the DEM stays open (:class:`_Held`): the whole read and the windowed
readers of the thread that opened it use it, one at a time, so that a run opens the file once.
A source is picklable (Dask sends it to workers): the copy opens the dataset again where it runs.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
import weakref
from dataclasses import dataclass, field

import numpy as np

from .._preload import while_numba_starts
from ..errors import AllNodata, HillshadeError, UsageProblem
from ..model.geometry import Grid
from . import raw as _raw
from .dem import Dem, check_transform, grid_of, heights_into, to_heights
from .gdal import check_band, has_tiff_magic, open_raster, read_error
from .paths import STDIN, STDIN_NAME, check_input_path, dataset_name, is_gdal_name, read_stdin
from .raw import RAW_EXTS, parse_raw_shape
from .tiff import TiffUnreadable, read_tiff
from .vrt import VrtSource, vrt_xml

TIFF_EXTS = (".tif", ".tiff")
READ_CHUNK = 32 << 20     # bytes of source values a windowed read takes at once (bounded scratch)


# ---------------------------------------------------------------------------------------------
# options

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


@dataclass(frozen=True)
class DemOptions:
    """How to read a DEM (the command line's DEM options): ``band`` (1-based), ``nodata``
    (overrides the file's), ``pixel_size`` (dx, dy metres: overrides the geotransform's spacing;
    required without georeferencing), ``z_factor`` (heights times it), ``raw_shape`` (rows,
    cols), ``raw_dtype`` and ``raw_byteorder`` of a raw grid. Checked by :func:`open_dem`."""

    band: int = 1
    nodata: float | None = None
    pixel_size: tuple[float, float] | None = None
    z_factor: float = 1.0
    raw_shape: tuple[int, int] | None = None
    raw_dtype: str | None = None
    raw_byteorder: str | None = None

    @classmethod
    def parse(cls, *, band: int = 1, nodata: float | None = None, z_factor: float = 1.0,
              pixel_size: str | None = None, raw_shape: str | None = None,
              raw_dtype: str | None = None, raw_byteorder: str | None = None) -> DemOptions:
        """From the command line's texts: --pixel-size 'DX[,DY]', --raw-shape 'ROWSxCOLS'."""
        return cls(band, nodata, parse_pixel_size(pixel_size), z_factor,
                   parse_raw_shape(raw_shape), raw_dtype, raw_byteorder)

    @property
    def raw(self) -> bool:
        """Whether a raw grid is asked for (any raw_* option)."""
        return (self.raw_shape is not None or self.raw_dtype is not None
                or self.raw_byteorder is not None)

    def check(self) -> None:
        check_z_factor(self.z_factor)
        if self.band < 1:
            raise HillshadeError(f"--band must be 1 or more, got {self.band}")


def _stdin_in_windows() -> UsageProblem:
    # the command line's own fault: a usage error
    return UsageProblem(f"{STDIN_NAME}: a DEM from standard input ('-') is read whole, in "
                        "memory: not in windows (--window-size, --max-memory, --scheduler) "
                        "nor as a tile of a mosaic")


# ---------------------------------------------------------------------------------------------
# the source

class _Held:
    """A dataset held open (with what keeps it open: a MemoryFile for bytes), lent to one user
    at a time in the thread that opened it; closed by ``close()`` or when collected."""

    def __init__(self, stack: contextlib.ExitStack, ds):
        self.ds = ds
        self.thread = threading.get_ident()
        self.lent = False
        self.close = weakref.finalize(self, stack.close)

    def lend(self):
        """The dataset, now lent; None when it is lent already, closed, or of another thread."""
        if self.lent or not self.close.alive or self.thread != threading.get_ident():
            return None
        self.lent = True
        return self.ds

    def give_back(self) -> None:
        self.lent = False

    def close_now(self) -> None:
        self.close()


@dataclass(eq=False)
class DemSource:
    """A DEM opened and checked by :func:`open_dem`, its values not read yet.

    ``name`` is what GDAL opens (an absolute path, a /vsi path, the VRT document of a mosaic; a
    raw grid's file); ``paths`` the inputs as given (messages name them); ``shape``,
    ``transform`` (None without georeferencing), ``crs``, ``nodata`` (the file's or the
    option's), ``band``, ``dtype`` (the values' type in the file; a raw grid's with its byte
    order), ``driver``, ``grid``, ``z_factor``; ``kind``: "gdal", "raw", "mosaic", or "tiff" (a
    TIFF only tifffile reads); ``tiles``: a mosaic's inputs (``path`` as given, ``name`` what
    GDAL opens, ``band``, ``window`` in the mosaic, ``transform``)."""

    name: str
    paths: list[str]
    shape: tuple[int, int]
    transform: object
    crs: object
    nodata: float | None
    band: int
    dtype: str
    driver: str
    grid: Grid = None          # type: ignore[assignment]
    z_factor: float = 1.0
    kind: str = "gdal"
    tiles: list[dict] = field(default_factory=list)
    options: DemOptions = field(default_factory=DemOptions)
    # a TIFF without georeferencing: read whole through tifffile first (GDAL when it cannot)
    tiff_first: bool = False
    data: bytes | None = field(default=None, repr=False)   # the bytes of a DEM from stdin
    # why it can be read whole only (standard input, a TIFF GDAL cannot open): reader() says so
    whole_only: HillshadeError | None = field(default=None, repr=False)
    _held: _Held | None = field(default=None, init=False, repr=False)
    _values: np.ndarray | None = field(default=None, init=False, repr=False)  # tifffile's

    @property
    def path(self) -> str:
        return self.paths[0] if len(self.paths) == 1 else f"mosaic of {len(self.paths)} files"

    @property
    def source_dtype(self) -> str:
        return self.dtype

    @property
    def itemsize(self) -> int:
        return np.dtype(self.dtype).itemsize

    def crs_string(self) -> str | None:
        from .crs import crs_string
        return crs_string(self.crs)

    def crs_name(self) -> str | None:
        from .crs import crs_name
        return crs_name(self.crs)

    # -- the dataset, opened once ------------------------------------------------------------

    def _hold(self, stack: contextlib.ExitStack, ds) -> None:
        self._held = _Held(stack, ds)

    def _acquire(self):
        """(an open dataset, how to give it back): the one held, lent (in the thread that
        opened it, to one user at a time), or one opened now, then held if none is."""
        h = self._held
        ds = h.lend() if h is not None else None
        if ds is not None:
            return ds, h.give_back
        stack = contextlib.ExitStack()
        try:
            ds = open_raster(self.path, stack, self.data,
                             None if self.data is not None else self.name)
        except BaseException:
            stack.close()
            raise
        new = _Held(stack, ds)
        if h is None or not h.close.alive:
            new.lent = True
            self._held = new
            return ds, new.give_back
        return ds, new.close_now      # (the bound method keeps it open until then)

    def close(self) -> None:
        """Close the dataset held open and drop what was kept to read the DEM whole (the bytes
        of standard input, a TIFF tifffile read): at the end of a ``with`` block; the dataset
        also when the source is collected."""
        if self._held is not None:
            self._held.close()
            self._held = None
        self.data = None
        self._values = None

    def __enter__(self) -> DemSource:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __getstate__(self) -> dict:
        """A copy for another process opens the dataset again there."""
        state = self.__dict__.copy()
        state["_held"] = None
        return state

    # -- whole -------------------------------------------------------------------------------

    def read(self) -> Dem:
        """The whole DEM in memory: float32 heights, NaN for nodata, the z-factor applied. An
        empty raster or one whose every cell is nodata is refused."""
        scaled = False
        if self.kind == "raw":
            values = _raw.read_whole(self.name, self.dtype, self.shape, self.data)
            dem = self._dem(values, self.nodata, "raw", self.driver, self.dtype)
        elif self.kind == "mosaic":
            z = np.empty(self.shape, np.float32)
            with self.reader() as rd:
                rd.read((0, self.shape[0], 0, self.shape[1]), z)
            dem = Dem(heights=z, grid=self.grid, path=self.path, kind="mosaic",
                      transform=self.transform, crs=self.crs, nodata=self.nodata,
                      driver=self.driver, source_dtype=self.dtype)
            scaled = True        # the reader applied the z-factor
        elif self.kind == "tiff":
            values = self._values
            dem = self._dem(values, self.nodata, "tiff", self.driver, str(values.dtype))
        else:
            dem = self._read_tiff() if self.tiff_first else None
            if dem is None:
                dem = self._read_gdal()
        if self.z_factor != 1.0 and not scaled:
            with np.errstate(over="ignore"):
                dem.heights *= np.float32(self.z_factor)
            # a height the factor takes beyond float32 is no height (NaN, as -inf/inf on reading)
            dem._survey = heights_into(dem.heights, None, dem.heights)
        if dem.heights.size == 0:
            raise HillshadeError(f"{self.path}: the raster is empty")
        if dem.valid_count() == 0:
            raise AllNodata(f"{self.path}: every cell is nodata, nothing to shade")
        return dem

    def _dem(self, values: np.ndarray, nodata, kind: str, driver: str, dtype: str) -> Dem:
        z, survey = to_heights(values, nodata)
        grid = self.grid
        if z.shape != tuple(self.shape):   # tifffile saw another shape than GDAL did
            grid = grid_of(self.path, self.transform, self.crs, z.shape,
                           self.options.pixel_size)
        return Dem(heights=z, grid=grid, path=self.path, kind=kind, transform=self.transform,
                   crs=self.crs, nodata=nodata, band=self.band, driver=driver,
                   source_dtype=dtype, _survey=survey)

    def _read_tiff(self) -> Dem | None:
        """Through tifffile (its own nodata tag); None when tifffile cannot read the file."""
        try:
            values, file_nodata = read_tiff(self.path, self.band, self.data)
        except TiffUnreadable:
            return None     # GDAL reads it, or says why it cannot (truncated, corrupt)
        nd = file_nodata if self.options.nodata is None else self.options.nodata
        return self._dem(values, nd, "tiff", "TIFF (tifffile)", str(values.dtype))

    def _read_gdal(self) -> Dem:
        from rasterio.errors import RasterioError

        ds, give_back = self._acquire()
        try:     # (numba starts meanwhile: its first kernel follows, the nodata pass)
            values = while_numba_starts(lambda: ds.read(self.band))
        except (RasterioError, OSError) as exc:
            raise read_error(self.path, exc, self.name) from None
        finally:
            give_back()
        return self._dem(values, self.nodata, "gdal", self.driver, str(values.dtype))

    # -- in windows --------------------------------------------------------------------------

    def check_windows(self) -> None:
        """Refuse windowed reads of a DEM that can be read whole only: one from standard input
        (a usage error), a TIFF only tifffile reads (GDAL's reason)."""
        if self.whole_only is not None:
            raise type(self.whole_only)(str(self.whole_only))

    @contextlib.contextmanager
    def reader(self):
        """An open :class:`Reader` (one per process or task)."""
        r = Reader(self)
        try:
            yield r
        finally:
            r.close()

    def files(self) -> list[str] | None:
        """The local files whose bytes make the heights (a VRT and the files it references, as
        GDAL lists them; a raw grid's file; each tile of a mosaic's), absolute; None when one
        of them is not a local file (standard input, a /vsi path or URL): then nothing can
        tell whether the heights changed."""
        if self.data is not None:
            return None
        if self.kind == "raw" or self.kind == "tiff":
            names = [self.name if self.kind == "raw" else self.path]
        elif self.kind == "mosaic":
            names = []
            for t in self.tiles:
                with contextlib.ExitStack() as stack:
                    names += list(open_raster(t["path"], stack, name=t.get("name")).files)
        else:
            ds, give_back = self._acquire()
            try:
                names = list(ds.files)
            finally:
                give_back()
        out = []
        for n in names or [self.name]:
            n = str(n)
            if n.startswith("/vsi") or "://" in n or not os.path.isfile(n):
                return None
            out.append(os.path.abspath(n))
        return sorted(set(out))

    def centre_height(self) -> tuple[float, str]:
        """The height at the centre, as ``site.dem_site`` takes it, read from the centre only."""
        from ..model.site import centre_height_of
        rows, cols = self.shape
        r, c = rows // 2, cols // 2
        r0, c0 = max(0, r - 128), max(0, c - 128)
        r1, c1 = min(rows, r + 129), min(cols, c + 129)
        z = np.empty((r1 - r0, c1 - c0), np.float32)
        with self.reader() as rd:
            rd.read((r0, r1, c0, c1), z)
        if not np.isfinite(z).any():
            return 0.0, "sea level (no valid cell within 128 cells of the centre)"
        return centre_height_of(z, r - r0, c - c0)


class Reader:
    """Windowed reads of a :class:`DemSource` into float32 heights (NaN voids, z-factor
    applied): a raw grid through a memory map, the rest through the source's dataset."""

    def __init__(self, source: DemSource):
        source.check_windows()
        self.source = source
        self.bytes_read = 0
        self._ds = None
        self._give_back = None
        self._mm = None
        if source.kind == "raw":
            self._mm = _raw.memmap(source.name, source.dtype, source.shape)
        else:
            self._ds, self._give_back = source._acquire()

    def close(self):
        if self._give_back is not None:
            give_back, self._give_back, self._ds = self._give_back, None, None
            give_back()
        self._mm = None

    def read(self, bounds: tuple[int, int, int, int], out: np.ndarray) -> None:
        """Heights of rows r0:r1, columns c0:c1 into ``out`` (float32, that shape; may be a view),
        a band of rows at a time (bounded scratch)."""
        r0, r1, c0, c1 = bounds
        if r1 <= r0 or c1 <= c0:
            return
        src = self.source
        step = max(1, READ_CHUNK // max(1, (c1 - c0) * src.itemsize))
        for a in range(r0, r1, step):
            b = min(r1, a + step)
            if self._mm is not None:
                data = np.asarray(self._mm[a:b, c0:c1])
            else:
                from rasterio.windows import Window
                try:
                    data = self._ds.read(src.band, window=Window(c0, a, c1 - c0, b - a))
                except Exception as exc:  # noqa: BLE001 -- GDAL read errors of many kinds
                    if src.tiles:   # which tile? each one under the window, read on its own
                        raise _bad_tile(src, (a, b, c0, c1)) or read_error(src.path, exc) \
                            from None
                    raise read_error(src.path, exc, src.name) from None
            self.bytes_read += data.nbytes
            heights_into(data, src.nodata, out[a - r0:b - r0], src.z_factor)


def _bad_tile(src: DemSource, bounds) -> HillshadeError | None:
    """The error of the first tile of the mosaic ``src`` under ``bounds`` (r0, r1, c0, c1) that
    cannot be opened or read there on its own (None if every one can)."""
    from rasterio.windows import Window
    r0, r1, c0, c1 = bounds
    for t in src.tiles:
        tr0, tr1, tc0, tc1 = t["window"]
        a, b, c, d = max(r0, tr0), min(r1, tr1), max(c0, tc0), min(c1, tc1)
        if a >= b or c >= d:
            continue
        try:
            with contextlib.ExitStack() as stack:
                ds = open_raster(t["path"], stack, name=t.get("name"))
                ds.read(t.get("band", 1), window=Window(c - tc0, a - tr0, d - c, b - a))
        except HillshadeError as exc:
            return exc
        except Exception as exc:  # noqa: BLE001 -- GDAL read errors of many kinds
            return read_error(t["path"], exc, t.get("name"))
    return None


# ---------------------------------------------------------------------------------------------
# opening

def open_dem(paths, options: DemOptions | None = None, *, windows: bool = False) -> DemSource:
    """The DEM at ``paths`` opened and checked, not read (see the module's notes).

    Parameters
    ----------
    paths : str, os.PathLike or sequence of them
        One path (a local file, any dataset name GDAL opens, ``-`` for standard input), or
        several shaded as one mosaic.
    options : DemOptions, optional
        How to read it: ``band`` (1-based), ``nodata`` (overrides the file's), ``pixel_size``
        ((dx, dy) metres, overrides the geotransform's spacing; required without
        georeferencing), ``z_factor`` (heights times it, to metres), ``raw_shape`` (rows, cols),
        ``raw_dtype``, ``raw_byteorder``.
    windows : bool, default False
        It will be read in windows, so what can be read whole only is refused now: standard
        input before it is read (a usage error), a TIFF only tifffile opens (GDAL's reason).

    Returns
    -------
    DemSource
        Its shape, transform, CRS, nodata, value type and :class:`~hillshade_rt.model.geometry.Grid`
        (ground metres per cell); :meth:`DemSource.read` reads it whole, :meth:`DemSource.reader`
        in windows. A context manager (closes the dataset it holds).

    Raises
    ------
    HillshadeError
        No DEM given, a path that does not exist or cannot be opened, bad options (band, z-factor,
        pixel size, raw layout), several raw grids as one mosaic, an unusable geotransform.
    UsageProblem
        Standard input with ``windows`` or in a mosaic.
    """
    opts = options or DemOptions()
    paths = [os.fspath(p) for p in ([paths] if isinstance(paths, (str, os.PathLike)) else paths)]
    if not paths:
        raise HillshadeError("no DEM given")
    if STDIN in paths and (windows or len(paths) > 1):
        raise _stdin_in_windows()
    for p in paths:
        check_input_path(p)
    opts.check()
    if len(paths) > 1:
        if opts.raw or os.path.splitext(paths[0])[1].lower() in RAW_EXTS:
            raise HillshadeError("several raw grids cannot be shaded as one mosaic; give one, or "
                                 "GeoTIFFs")
        src = _open_mosaic(paths, opts)
    else:
        src = _open_one(paths[0], opts, windows)
    if src.data is not None:
        src.whole_only = _stdin_in_windows()
    return src


def place_in(context: DemSource, tile: DemSource) -> tuple[int, int, int, int]:
    """Where the cells of ``tile`` lie in ``context`` (``--context``): (r0, r1, c0, c1), rows and
    columns of the context. Both georeferenced, in one CRS, with the same cell size, the tile's
    cells on the context's, and all of them inside it; a usage error (one line) otherwise."""
    name, ctx = tile.path, context.path
    if tile.transform is None or context.transform is None:
        raise UsageProblem(f"{name if tile.transform is None else ctx}: --context needs "
                           "georeferenced rasters (the tile is placed in the context by its "
                           "geotransform)")
    t, c = tile.transform, context.transform
    if tile.crs != context.crs:
        raise UsageProblem(f"--context {ctx}: its CRS differs from {name}'s; the context must be "
                           "on the tile's grid (reproject with gdalwarp first)")
    if not (t.b == 0 and t.d == 0 and c.b == 0 and c.d == 0):
        raise UsageProblem(f"--context {ctx}: rotated geotransforms cannot be placed in one "
                           "another")
    if not (math.isclose(t.a, c.a, rel_tol=1e-9) and math.isclose(t.e, c.e, rel_tol=1e-9)):
        raise UsageProblem(f"--context {ctx}: its cell size ({c.a:g}, {c.e:g}) differs from "
                           f"{name}'s ({t.a:g}, {t.e:g}); the context must be on the tile's grid")
    fx, fy = (t.c - c.c) / c.a, (t.f - c.f) / c.e
    if abs(fx - round(fx)) > 1e-6 or abs(fy - round(fy)) > 1e-6:
        raise UsageProblem(f"--context {ctx}: its cells are not aligned with {name}'s (offset "
                           f"{fx % 1:.3f}, {fy % 1:.3f} cells); the context must be on the tile's "
                           "grid")
    r0, c0 = int(round(fy)), int(round(fx))
    r1, c1 = r0 + tile.shape[0], c0 + tile.shape[1]
    rows, cols = context.shape
    if r0 < 0 or c0 < 0 or r1 > rows or c1 > cols:
        raise UsageProblem(f"--context {ctx} does not contain {name} (the tile's rows {r0}..{r1} "
                           f"and columns {c0}..{c1} against the context's {rows} x {cols})")
    return r0, r1, c0, c1


def read_dem(path, *, band: int = 1, nodata: float | None = None,
             pixel_size: tuple[float, float] | None = None, z_factor: float = 1.0,
             raw_shape: tuple[int, int] | None = None, raw_dtype: str | None = None,
             raw_byteorder: str | None = None) -> Dem:
    """Read the DEM at ``path`` whole.

    ``open_dem(path, DemOptions(...)).read()``, the dataset closed afterwards.

    Parameters
    ----------
    path : str or os.PathLike
        A local file, any dataset name GDAL opens (``/vsizip/a.zip/dem.tif``,
        ``zip://a.zip!dem.tif``, ``/vsigzip/…``, ``/vsimem/…``, ``/vsicurl/…``,
        ``NETCDF:f.nc:z``), or ``-``: all of standard input, read into memory (any format GDAL
        reads, or raw with the ``raw_*`` options).
    band : int, default 1
        The band to read, 1-based.
    nodata : float, optional
        Nodata value in the file's units, overriding the file's.
    pixel_size : (float, float), optional
        (dx, dy) ground metres per cell, overriding the spacing from the geotransform; required
        when the input has no georeferencing.
    z_factor : float, default 1.0
        Heights times this factor (finite, non-zero), e.g. 0.3048 for feet to metres.
    raw_shape : (int, int), optional
        (rows, cols) of a raw grid.
    raw_dtype : str, optional
        Value type of a raw grid: "int16", "uint16", "int32", "float32" or "float64".
    raw_byteorder : str, optional
        Byte order of a raw grid, "little" or "big" (default big for .hgt tiles, else little).

    Returns
    -------
    Dem
        ``heights`` (float32 metres, NaN nodata, the z-factor applied), ``grid`` (ground metres
        per cell), ``transform``, ``crs``, ``nodata`` and the source's details.

    Raises
    ------
    HillshadeError
        A path that does not exist or cannot be read, bad options, an unusable geotransform.
    AllNodata
        Every cell is nodata.
    """
    opts = DemOptions(band, nodata, pixel_size, z_factor, raw_shape, raw_dtype, raw_byteorder)
    with open_dem(path, opts) as src:
        return src.read()


def open_windowed(paths, **options) -> DemSource:
    """``open_dem(paths, DemOptions(**options), windows=True)``: the options as keywords."""
    return open_dem(paths, DemOptions(**options), windows=True)


def _open_one(path: str, opts: DemOptions, windows: bool) -> DemSource:
    data = None
    if path == STDIN:
        data = read_stdin()
        path = STDIN_NAME
    ext = os.path.splitext(path)[1].lower() if data is None else ""
    if opts.raw or ext in RAW_EXTS:
        return _open_raw(path, opts, data)
    if ext == ".hgt":
        try:
            return _open_gdal(path, opts)
        except HillshadeError:
            if is_gdal_name(path) and not os.path.exists(path):
                raise
            return _open_raw(path, opts)     # big-endian int16, square (raw.layout)
    tiff = ext in TIFF_EXTS or (data is not None and has_tiff_magic(path, data))
    return _open_gdal(path, opts, data, tiff, windows)


def _is_height(dtype: str) -> bool:
    try:
        return np.dtype(dtype).kind in "iuf"
    except TypeError:      # GDAL's complex_int16 and the like
        return False


def _open_checked(path: str, band: int, stack: contextlib.ExitStack, data: bytes | None = None,
                  name: str | None = None):
    """``path`` opened by GDAL (kept open by ``stack``) and checked: not empty, the band there,
    its values heights; (dataset, whether it is georeferenced)."""
    ds = open_raster(path, stack, data, name)
    georef = check_band(ds, path, band)
    dtype = ds.dtypes[band - 1]
    if not _is_height(dtype):
        raise HillshadeError(f"{path}: pixel type {dtype} is not a height")
    return ds, georef


def _open_gdal(path: str, opts: DemOptions, data: bytes | None = None, tiff: bool = False,
               windows: bool = False) -> DemSource:
    """Through rasterio (GDAL); ``data``: the raster's bytes (standard input), ``path`` then only
    names it. A TIFF GDAL cannot open goes to tifffile (read whole, now); one without
    georeferencing is read whole through tifffile first (``DemSource.tiff_first``)."""
    name = None if data is not None else dataset_name(path)
    stack = contextlib.ExitStack()
    try:
        try:
            ds, georef = _open_checked(path, opts.band, stack, data, name)
        except HillshadeError as err:
            if tiff and not windows:
                src = _open_tifffile(path, opts, data, err)
                if src is not None:
                    return src
            raise
        transform = ds.transform if georef else None
        shape = (ds.height, ds.width)
        src = DemSource(name or path, [path], shape, transform, ds.crs,
                        ds.nodatavals[opts.band - 1] if opts.nodata is None else opts.nodata,
                        opts.band, ds.dtypes[opts.band - 1], ds.driver,
                        grid_of(path, transform, ds.crs, shape, opts.pixel_size),
                        opts.z_factor, "gdal", options=opts, tiff_first=tiff and not georef,
                        data=data)
    except BaseException:
        stack.close()
        raise
    src._hold(stack, ds)
    return src


def _open_tifffile(path: str, opts: DemOptions, data: bytes | None,
                   gdal_error: HillshadeError) -> DemSource | None:
    """A TIFF GDAL cannot open, read whole through tifffile now (None if tifffile cannot read
    it either: GDAL's error stands)."""
    try:
        values, file_nodata = read_tiff(path, opts.band, data)
        grid = grid_of(path, None, None, values.shape, opts.pixel_size)
    except HillshadeError:
        return None
    src = DemSource(path, [path], values.shape, None, None,
                    file_nodata if opts.nodata is None else opts.nodata, opts.band,
                    str(values.dtype), "TIFF (tifffile)", grid, opts.z_factor, "tiff",
                    options=opts, whole_only=gdal_error)
    src._values = values
    return src


def _open_raw(path: str, opts: DemOptions, data: bytes | None = None) -> DemSource:
    """A raw grid from a local file, or from ``data`` (its bytes: standard input)."""
    if data is None and not os.path.isfile(path):
        raise HillshadeError(f"{path}: a raw grid is read from a local file or standard input "
                             "only (GDAL reads it from elsewhere given an ENVI .hdr or a VRT)")
    size = os.path.getsize(path) if data is None else len(data)
    lay = _raw.layout(path, size, opts.raw_shape, opts.raw_dtype, opts.raw_byteorder,
                      opts.nodata)
    transform, crs = _raw.hgt_geometry(path, lay.shape[0])
    return DemSource(os.path.abspath(path) if data is None else path, [path], lay.shape,
                     transform, crs, lay.nodata, 1, lay.dtype, lay.driver,
                     grid_of(path, transform, crs, lay.shape, opts.pixel_size), opts.z_factor,
                     "raw", options=opts, data=data)


def _open_mosaic(paths: list[str], opts: DemOptions) -> DemSource:
    """Several rasters on one grid (same CRS and cell size, cells aligned) as one surface: a VRT
    document in memory, float32 with NaN where no input has a valid cell."""
    band, metas = opts.band, []
    for p in paths:
        name = dataset_name(p)
        with contextlib.ExitStack() as stack:
            ds, georef = _open_checked(p, band, stack, name=name)
            metas.append(dict(shape=(ds.height, ds.width),
                              transform=ds.transform if georef else None, crs=ds.crs,
                              nodata=ds.nodatavals[band - 1], name=name))
    first = metas[0]
    t0 = first["transform"]
    if t0 is None:
        raise HillshadeError(f"{paths[0]}: a mosaic needs georeferenced inputs")
    for p, m in zip(paths, metas):     # rotated, degenerate: named before any arithmetic
        if m["transform"] is not None:
            check_transform(p, m["transform"])
    offs = []
    for p, m in zip(paths, metas):
        t = m["transform"]
        if t is None or m["crs"] != first["crs"]:
            raise HillshadeError(f"{p}: its CRS differs from {paths[0]}'s; a mosaic needs one CRS "
                                 "(reproject with gdalwarp first)")
        if not (math.isclose(t.a, t0.a, rel_tol=1e-9) and math.isclose(t.e, t0.e, rel_tol=1e-9)
                and t.b == 0 and t.d == 0):
            raise HillshadeError(f"{p}: its cell size ({t.a:g}, {t.e:g}) differs from "
                                 f"{paths[0]}'s ({t0.a:g}, {t0.e:g}); a mosaic needs one cell size")
        fx, fy = (t.c - t0.c) / t0.a, (t.f - t0.f) / t0.e
        if abs(fx - round(fx)) > 1e-6 or abs(fy - round(fy)) > 1e-6:
            raise HillshadeError(f"{p}: its cells are not aligned with {paths[0]}'s (offset "
                                 f"{fx:.3f}, {fy:.3f} cells); a mosaic needs aligned grids")
        offs.append((int(round(fy)), int(round(fx))))
    r_min = min(o[0] for o in offs)
    c_min = min(o[1] for o in offs)
    rows = max(o[0] + m["shape"][0] for o, m in zip(offs, metas)) - r_min
    cols = max(o[1] + m["shape"][1] for o, m in zip(offs, metas)) - c_min
    if rows * cols > 10 * sum(m["shape"][0] * m["shape"][1] for m in metas) + (1 << 20):
        raise HillshadeError("the inputs lie far apart (their bounding box is more than ten times "
                             "their area): shade them separately")
    from affine import Affine
    transform = t0 @ Affine.translation(c_min, r_min)
    tiles, sources = [], []
    for p, o, m in zip(paths, offs, metas):
        r0, c0 = o[0] - r_min, o[1] - c_min
        tiles.append({"path": p, "window": (r0, r0 + m["shape"][0], c0, c0 + m["shape"][1]),
                      "transform": m["transform"], "name": m["name"], "band": band})
        nd = m["nodata"] if opts.nodata is None else opts.nodata
        sources.append(VrtSource(m["name"], band, (r0, c0), m["shape"], nd))
    doc = vrt_xml((rows, cols), transform, first["crs"], [sources], "Float32", math.nan)
    path = f"mosaic of {len(paths)} files"
    return DemSource(doc, paths, (rows, cols), transform, first["crs"], math.nan, 1, "float32",
                     "VRT (mosaic)", grid_of(path, transform, first["crs"], (rows, cols),
                                             opts.pixel_size),
                     opts.z_factor, "mosaic", tiles, options=opts)
