"""Irradiance of rasters larger than memory: the four bands of ``irradiance`` region by region,
each region written into OUTPUT as it is made, or each region a Dask task (``--scheduler``) that
writes its part, put together through a VRT at the end (as ``run.sun_hours_windows`` does for
sun hours). Every cell gets the bits a run in memory gives it.

A region's bands are the in-memory run's per-cell arithmetic on the region's cells
(``engine.irradiance.sums``, float64 sums in the samples' order, then float32):

* Dozier's sky view Vd of the region from the windowed horizon march
  (``run.horizon_windows.region_outputs``: the rays to the raster's edge, exact), or read from
  ``--sky-view FILE`` window by window (``run.sky_view_file.VdFile``);
* the region's voids and slopes (Horn's normals) from its heights and a cell around it;
* each sample's direct term max(cos i, 0) · lit from the windowed shadows
  (``engine.windows.WindowLighting.light_incidence`` of the sun's pieces cut to the region), the
  samples in groups whose windows fit memory together and are read once
  (``engine.sun_sums.plan_regions``, ``sun_pieces``), as sun-hours' sums are.

Only the samples with direct light to cast (``engine.irradiance.casts``) are planned and lit,
those whose direct term the sums ask for. The regions' shape and the groups are sun-hours'
(``run.sun_hours_windows.plan_sums``); a window cell's bytes count the region's share too
(the sums' float64 arrays, or the horizon march before them), the region lying inside its
windows. The same helpers make a ``--context`` tile's bands in memory (``run.irradiance``).

With --monthly, or --albedo by month, the samples are grouped by their local month as in memory
(``engine.irradiance.Groups``): each region's sums give each month's global band too (bands 5
on), each month's reflected light with its albedo. A raster of the sky's inputs (an albedo,
Linke turbidity or clear-sky index raster, or a month's of a ``{month}`` pattern) is
resampled once to the whole output grid, by the very call a run in memory makes
(``run.sky_inputs.resample``: ``rasterio.warp.reproject`` of the raster to the grid,
bilinear) into a float64 file beside OUTPUT mapped in memory (``SkyGrids``: the pages the
system's to drop, the disk holding 8 bytes a cell a raster), and each region reads its cells
from it. Resampling each region's window on its own would not do: GDAL's warper computes each
cell's position in the raster from the window's origin (and interpolates positions along its
chunks' rows), which changes the last bits of the bilinear weights, so of the bands.

With Linke turbidity or index rasters that vary over the DEM the open sky is each cell's
(``engine.irradiance.CellSky``): the run's ``run.irradiance.open_sky_inputs`` with each
raster's figures over the DEM's valid cells from its grid (``open_sky_grids``), and each
region's ``CellSky`` built from its cut cells as the run in memory builds the whole grid's
(``sky_inputs.CellInputs``: the month's rasters held while the samples are in that month,
its voids the DEM's mean), so every cell gets the bits of the run in memory.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import HillshadeError

# bytes per cell of a region's sums (``engine.irradiance.sums``): beam and diffuse (float64),
# Vd in float64, Perez's cos S, sin S and horizon share (float64), the heights and voids with a
# cell around, a sample's direct term, the four float32 bands and the float64 temporaries of
# the last sums
SUMS_BYTES_PER_CELL = 100
NORMALS_BYTES_PER_CELL = 24       # Horn's normals of a run in memory (three float64)
_TASK_LOCK = threading.Lock()     # one numba computation at a time per Dask worker process


def memory_per_cell(lighting) -> int:
    """Bytes per cell of a run in memory: lighting the DEM whole (``engine.windows.
    bytes_per_cell``, product "sun"), Horn's normals and the sums."""
    from ..engine.windows import bytes_per_cell
    return (bytes_per_cell(lighting.algorithm, "sun", lighting.soft) + NORMALS_BYTES_PER_CELL
            + SUMS_BYTES_PER_CELL)


def window_bytes_per_cell(lighting, months: int = 0, rasters: int = 0) -> int:
    """Bytes per cell of a group's window: lighting it, the group's heights
    (``engine.sun_sums.BYTES_PER_GROUP_CELL``) and the region's share (the region lies inside
    its windows): its sums, or the horizon march of its sky view before them, the larger; with
    ``months`` groups of samples (--monthly, --albedo by month) the float64 running sums kept
    at each group's start and each month's float32 band, and the ``rasters`` (float64) a
    region holds of the sky's inputs (albedo, a month's Linke turbidity and clear-sky
    indices)."""
    from ..engine.sun_sums import BYTES_PER_GROUP_CELL
    from ..engine.windows import bytes_per_cell
    from .horizon_windows import BYTES_PER_REGION_CELL
    groups = (16 + 4 * months) if months else 0
    return (bytes_per_cell(lighting.algorithm, "sun", lighting.soft) + BYTES_PER_GROUP_CELL
            + max(SUMS_BYTES_PER_CELL + groups + 8 * rasters, BYTES_PER_REGION_CELL))


# ---------------------------------------------------------------------------------------------
# what a region's bands take, shared with a --context tile's

def lighting_job(src, lighting, body, bstats):
    """The ``engine.windows.WindowLighting`` of the beam's cast shadows and incidence (product
    "sun") over ``src``, with the whole raster's height range and extent (``bstats``: the
    statistics pass's), so that every window decides curvature as a run in memory does."""
    from ..engine.windows import WindowLighting
    rows, cols = src.shape
    dx, dy = src.grid.centre_spacing()
    return WindowLighting(src, lighting, body, (bstats.zmin, bstats.zmax),
                          math.hypot(cols * dx, rows * dy), "sun")


def sky_view_job(src, lighting, body, bstats, directions: int):
    """(the ``run.horizon_windows.HorizonJob`` of Dozier's sky view in ``directions``
    azimuths, seen from the lighting's lift, with no --max-distance; its horizon Shader: the
    curvature, refraction coefficient and body the Vd file's tags name)."""
    from ..model.geometry import equal_azimuths
    from .horizon import horizon_job
    return horizon_job(src, equal_azimuths(360.0 / int(directions)), lighting.backend,
                       lighting.curvature, lighting.refraction_k, "scan", bstats, False, 1,
                       math.inf, lighting.lift, body=body)


def region_vd(hjob, rd, region) -> tuple[np.ndarray, object]:
    """(Dozier's Vd of ``region`` (r0, r1, c0, c1): float32, NaN voids, as ``skyview
    --definition dozier`` makes it; the march's ``horizon_windows.Figures``) by the windowed
    horizon march of ``hjob``, read through ``rd``."""
    from .horizon_windows import Product, region_outputs
    out = []
    fig = region_outputs(hjob, rd, region, Product("skyview", definition="dozier"),
                         lambda name, band, arr: out.append(arr))
    return out[0], fig


def surface(read, grid, shape, region) -> tuple[np.ndarray, object]:
    """(the voids of ``region`` (r0, r1, c0, c1) of a raster of ``shape`` on ``grid``, a
    function giving its slopes' (cos S, sin S), float64, from Horn's normals): from its heights
    and a cell around them, ``read(window)`` (float32 heights of a window)."""
    from ..algorithms.relief import incidence
    from ..engine.windows import window_grid
    rows, cols = shape
    r0, r1, c0, c1 = region
    m = (max(0, r0 - 1), min(rows, r1 + 1), max(0, c0 - 1), min(cols, c1 + 1))
    zm = read(m)
    inner = (slice(r0 - m[0], r1 - m[0]), slice(c0 - m[2], c1 - m[2]))

    def slopes():
        cos_s = incidence(zm, window_grid(grid, m), 0.0, 90.0, *inner).astype(np.float64)
        return cos_s, np.sqrt(np.maximum(1.0 - cos_s * cos_s, 0.0))
    return np.isnan(zm[inner]), slopes


def add_direct(job, out: np.ndarray, origin, piece, z, stats, used, carry=None) -> None:
    """max(cos i, 0) · lit of ``piece``'s region (``job.light_incidence`` of its window's
    heights ``z``) into ``out``, whose first cell is the raster's ``origin`` (row, col)."""
    lit, cosi = job.light_incidence(z, piece, stats, used, carry)
    a0, a1, b0, b1 = piece.region
    out[a0 - origin[0]:a1 - origin[0], b0 - origin[1]:b1 - origin[1]] = \
        np.maximum(cosi, np.float32(0.0)) * lit


# ---------------------------------------------------------------------------------------------
# the sky's rasters on the output's grid (albedo, Linke turbidity, clear-sky indices), and the
# samples' months

@dataclass(frozen=True)
class SkyGrid:
    """One raster of the sky's inputs resampled to the output's whole grid: a float64 ``.npy``
    file (``path``) of that grid, whose first cell is the raster's ``origin`` (row, col)
    (picklable: a Dask task reads its regions' cells from it)."""

    path: str
    origin: tuple = (0, 0)

    def cut(self, region) -> np.ndarray:
        """The values of ``region`` (r0, r1, c0, c1), float64 (a copy)."""
        r0, r1, c0, c1 = region
        o0, o1 = self.origin
        return np.array(np.load(self.path, mmap_mode="r")[r0 - o0:r1 - o0, c0 - o1:c1 - o1])


def albedo_of(a, region):
    """The albedo of ``region``: a number as it is, a :class:`SkyGrid` its cells."""
    return a.cut(region) if isinstance(a, SkyGrid) else a


CELLS_AT_ONCE = 1 << 20         # cells of a grid checked at once


def _allocate(path: str, nbytes: int, option: str) -> None:
    """The disk's blocks of the file ``path`` taken now (where the system can): a disk too
    full for a raster on the DEM's grid is one line here, not a crash (SIGBUS) when a mapped
    page is written."""
    import errno
    if not hasattr(os, "posix_fallocate"):
        return
    try:
        with open(path, "r+b") as fh:
            os.posix_fallocate(fh.fileno(), 0, os.path.getsize(path))
    except OSError as exc:
        if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
            raise HillshadeError(f"{os.path.dirname(os.path.dirname(path))}: no room for the "
                                 f"{option} raster on the DEM's grid ({nbytes:,} bytes): "
                                 f"{exc.strerror or exc}") from None


@dataclass(frozen=True)
class GridFigures:
    """A raster on the grid over the DEM's valid cells: their ``count``, ``total`` (float64
    sums of row bands in order: :func:`numpy.mean`'s bits where the grid is one band), ``lo``,
    ``hi``; over all the cells it has a value on, ``seen`` of them summing ``seen_total``."""

    count: int
    total: float
    lo: float
    hi: float
    seen: int
    seen_total: float


class SkyGrids:
    """The rasters of the sky's inputs of a run in windows (--albedo, --linke-turbidity,
    --beam-index, --diffuse-index: ``sky_inputs.SkyValue``) on the output's grid (``geom``'s:
    the DEM's, or the --context tile's, whose first cell is the source's ``origin``): each
    month's of a pattern, or the one raster's, resampled once (``sky_inputs.resample`` into a
    file mapped in memory) into a folder beside OUTPUT, removed on :meth:`close` (its name the
    run's, ``io.write.scratch_folder``: a later run into that folder removes it where this
    one was killed). Checked as ``sky_inputs.SkyValue.on_grid`` checks them in memory, with
    its words: every valid cell of the DEM covered (its heights read band by band of rows),
    every value within the option's range."""

    def __init__(self, output: str):
        from ..io.write import scratch_folder
        self.folder = scratch_folder(output, "grids")
        self.grids: dict = {}
        self.figures: dict = {}
        self.valid = None       # the DEM's valid cells on the output grid (one pass, mapped)

    def grid(self, value, month: int, geom, src, origin, figures: bool = False) -> SkyGrid:
        """The :class:`SkyGrid` of ``value`` (a ``SkyValue`` of rasters) for ``month``; with
        ``figures`` its :class:`GridFigures` in ``self.figures`` too (the DEM's valid cells,
        :meth:`_valid`, read for them, or where the raster lacks cells)."""
        path = value.path if value.path is not None else value.pattern.format(month=month)
        if path in self.grids:
            if figures and path not in self.figures:
                out = np.load(self.grids[path].path, mmap_mode="r")
                self.figures[path] = self._check(value, path, out, src, origin, True)
                del out
            return self.grids[path]
        from .sky_inputs import resample
        dest = os.path.join(self.folder, f"grid_{len(self.grids)}.npy")
        rows, cols = geom.shape
        out = np.lib.format.open_memmap(dest, mode="w+", dtype=np.float64, shape=(rows, cols))
        try:
            _allocate(dest, rows * cols * 8, value.option)
            resample(path, geom.transform, geom.crs, (rows, cols), out=out)
            out.flush()
            f = self._check(value, path, out, src, origin, figures)
            if f is not None:
                self.figures[path] = f
        finally:
            del out
        self.grids[path] = SkyGrid(dest, tuple(origin))
        return self.grids[path]

    def resolved(self, value, month: int, geom, src, origin) -> tuple:
        """(the :class:`SkyGrid` of ``value`` for ``month``; (its value or its mean over the
        DEM's valid cells, whether it varies there, min, max) as ``SkyValue.resolved`` has
        them in memory (a raster of one value there is that value: the number's bits); the
        value its voids take (the mean))."""
        g = self.grid(value, month, geom, src, origin, figures=True)
        path = value.path if value.path is not None else value.pattern.format(month=month)
        f = self.figures[path]
        if not f.count:
            v = f.seen_total / f.seen if f.seen else value.low
            return g, (v, False, v, v), v
        if f.lo == f.hi:
            return g, (f.lo, False, f.lo, f.lo), f.lo
        mean = f.total / f.count
        return g, (mean, True, f.lo, f.hi), mean

    def _valid(self, src, origin, shape, option: str) -> np.ndarray:
        """The DEM's valid cells on the output grid (``shape`` from ``origin``), a bool array
        mapped from a file of the folder: the DEM read once, in row bands, for every raster's
        checks."""
        if self.valid is None:
            rows, cols = shape
            dest = os.path.join(self.folder, "valid.npy")
            valid = np.lib.format.open_memmap(dest, mode="w+", dtype=np.bool_, shape=shape)
            _allocate(dest, rows * cols, option)
            step = max(1, CELLS_AT_ONCE // max(cols, 1))
            with src.reader() as rd:
                for r0 in range(0, rows, step):
                    r1 = min(rows, r0 + step)
                    z = np.empty((r1 - r0, cols), np.float32)
                    rd.read((origin[0] + r0, origin[0] + r1, origin[1], origin[1] + cols), z)
                    np.logical_not(np.isnan(z), out=valid[r0:r1])
            valid.flush()
            del valid
            self.valid = np.load(dest, mmap_mode="r")
        return self.valid

    def _check(self, value, path, out, src, origin, figures: bool) -> GridFigures | None:
        from ..errors import UsageProblem
        rows, cols = out.shape
        step = max(1, CELLS_AT_ONCE // max(cols, 1))
        lacking, lo, hi, seen, seen_total = 0, math.inf, -math.inf, 0, 0.0
        count, total, vlo, vhi = 0, 0.0, math.inf, -math.inf
        for r0 in range(0, rows, step):
            r1 = min(rows, r0 + step)
            a = np.asarray(out[r0:r1])
            gap = np.isnan(a)
            seen_v = a[~gap]
            if seen_v.size:
                lo, hi = min(lo, float(seen_v.min())), max(hi, float(seen_v.max()))
                seen += seen_v.size
                seen_total += float(np.sum(seen_v))
            if not (figures or gap.any()):
                continue
            valid = np.asarray(self._valid(src, origin, out.shape, value.option)[r0:r1])
            lacking += int((gap & valid).sum())
            if not figures:
                continue
            inside = a[valid & ~gap]
            if inside.size:
                count += inside.size
                total += float(np.sum(inside))
                vlo, vhi = min(vlo, float(inside.min())), max(vhi, float(inside.max()))
        if lacking:
            raise UsageProblem(f"{value.option} {path}: the raster does not cover the DEM "
                               f"({lacking} of its cells lie outside or on its nodata)")
        if lo < value.low or hi > value.high:
            raise UsageProblem(f"{value.option} {path}: values must be between "
                               f"{value.low:g} and {value.high:g}, found {lo:g}..{hi:g}")
        return GridFigures(count, total, vlo, vhi, seen, seen_total) if figures else None

    def close(self) -> None:
        import shutil
        self.valid = None
        shutil.rmtree(self.folder, ignore_errors=True)


@dataclass
class GridSky:
    """The open sky per cell of a run in windows: ``inputs`` (``sky_inputs.CellInputs``: what
    the sky per cell takes, the run in memory's), ``grids`` {(i, month): (:class:`SkyGrid`, the
    value its voids take)} of the rasters that vary over the DEM, and the run's
    :class:`SkyGrids` (``store``: not sent to Dask's tasks)."""

    inputs: object
    grids: dict
    store: object = None

    def cells(self, region, void: np.ndarray):
        """The ``engine.irradiance.CellSky`` of ``region`` (r0, r1, c0, c1), whose voids are
        ``void``: each raster's cells cut from its grid, its voids the mean of the DEM's valid
        cells, as ``SkyValue.resolved`` makes the whole grid's in memory."""
        def raster(i, m):
            g, fill = self.grids[i, m]
            return np.ascontiguousarray(np.where(void, fill, g.cut(region)), np.float64)
        return self.inputs.cells(raster)

    def rasters(self) -> int:
        """How many float64 rasters of a region its sums hold at once: the month's Linke
        turbidity and its correction, the indices, each cell's GHI sum, a cut."""
        held = {i for i, _ in self.grids}
        return (2 if 0 in held else 0) + (1 in held) + (2 in held) + 2


def open_sky_grids(cfg, sampled, src, area, open_sky_inputs):
    """(the open sky, a :class:`GridSky` or None) of a run in windows (``src``: the DEM opened
    for windows; with ``area``, a ``run.context.Area``: its tile) whose --linke-turbidity,
    --beam-index or --diffuse-index are rasters: ``open_sky_inputs`` (the run's,
    ``run.irradiance.open_sky_inputs``) with each raster resampled to the output's grid once
    (:class:`SkyGrids`), the same values, checks and sky as the run in memory's. The grids'
    folder is the :class:`GridSky`'s ``store`` (``bands_in_windows`` removes it at its end; at
    once where no raster varies)."""
    geom = src if area is None else area.tile
    origin = (0, 0) if area is None else (area.bounds[0], area.bounds[2])
    given = (cfg.linke_input, cfg.beam_input, cfg.diffuse_input)
    store = SkyGrids(cfg.output)
    grids = {}
    try:
        def summarize(v, m):
            i = next(j for j, x in enumerate(given) if x is v)
            g, figures, fill = store.resolved(v, m, geom, src, origin)
            if figures[1]:
                grids[i, m] = (g, fill)
            return figures
        sky, inputs = open_sky_inputs(cfg, sampled.times, sampled.suns, sampled.site,
                                      sampled.tz, summarize)
    except BaseException:
        store.close()
        raise
    if inputs is None:
        store.close()
        return sky, None
    return sky, GridSky(inputs, grids, store)


@dataclass
class MonthGroups:
    """The samples' groups as a run in memory makes them (``run.irradiance._albedo_groups``):
    ``index`` each sample's month (0, 1, ...), ``keys`` the months' (year, month), ``hours``
    each month's hours, and whether each month's global band is asked (``bands``, --monthly)."""

    index: np.ndarray
    keys: list
    hours: list
    bands: bool


def month_groups(cfg, sampled) -> MonthGroups | None:
    """The samples' months where --monthly or a monthly albedo asks for them, else None."""
    from .sky_inputs import month_keys
    a = cfg.albedo_input
    if not (cfg.monthly or a.by_month):
        return None
    keys = month_keys(sampled.times, sampled.tz, sampled.site.lon)
    order = list(dict.fromkeys(keys))
    index = (np.array([order.index(k) for k in keys], np.int64) if keys
             else np.zeros(0, np.int64))
    hours = np.bincount(index, weights=np.asarray(sampled.weights, np.float64),
                        minlength=len(order))
    return MonthGroups(index, order, [float(h) for h in hours], bool(cfg.monthly))


def albedo_inputs(cfg, groups: MonthGroups | None, grids, geom, src, origin) -> tuple:
    """(the albedo of the whole period, each group's albedo or None) as a run in memory has
    them (numbers, or :class:`SkyGrid` where it has rasters; ``grids`` the run's
    :class:`SkyGrids`)."""
    a = cfg.albedo_input

    def on(month):
        return a.value_of_month(month) if not a.rasters else grids.grid(a, month, geom, src,
                                                                         origin)
    if groups is None or not a.by_month:
        return on(1), None
    return None, [on(m) for _, m in groups.keys]


# ---------------------------------------------------------------------------------------------
# a region's bands

@dataclass
class Jobs:
    """What every region's bands take (picklable: a Dask task gets it): ``light`` the
    ``WindowLighting`` of the beam, ``horizons`` the ``HorizonJob`` of Dozier's Vd (None: read
    from ``vd_file``, a ``sky_view_file.VdFile`` whose first cell is the raster's
    ``vd_origin``), the samples (``suns``, their ``weights`` in hours, the open ``sky`` at
    each), ``albedo`` (a number or a :class:`SkyGrid`), ``soft``, ``perez``, ``hours``:
    with --mean the period's hours (the bands divided by them), else None; ``groups`` the
    samples' months (:class:`MonthGroups`, or None), ``group_albedo`` each month's albedo (or
    None: ``albedo``), ``month_hours`` with --mean each month's hours (its band divided by
    them), ``cells`` the open sky per cell (a :class:`GridSky` without its store, or None:
    ``sky`` for every cell)."""

    light: object
    horizons: object
    vd_file: object
    suns: list
    weights: object
    sky: object
    albedo: float
    soft: bool = False
    perez: bool = False
    hours: float | None = None
    vd_origin: tuple = (0, 0)
    groups: MonthGroups | None = None
    group_albedo: list | None = None
    month_hours: list | None = None
    cells: GridSky | None = None

    def casting(self) -> list[int]:
        """The samples whose direct term the sums ask for, in order."""
        from ..engine.irradiance import casts, cell_casts
        if self.cells is not None:
            ci = self.cells.inputs
            return [k for k, s in enumerate(self.suns)
                    if cell_casts(ci.terms, k, ci.tl_on(k), s, self.soft, self.perez)]
        return [k for k, s in enumerate(self.suns)
                if casts(self.sky, k, s, self.soft, self.perez)]


@dataclass
class RegionMade:
    """A region's bands (``engine.irradiance.BANDS``: float32, NaN voids), its Vd, the horizon
    march's figures, the bytes its window cache copied instead of reading, and with --monthly
    each month's global band (float32, NaN voids)."""

    bands: dict
    vd: np.ndarray
    figures: object
    bytes_carried: int = 0
    months: list = field(default_factory=list)


def region_bands(jobs: Jobs, rd, rs, stats: dict, used: set, timer=None,
                 on_piece=None) -> RegionMade:
    """The four bands of the region of ``rs`` (``engine.sun_sums.RegionSuns`` of the samples
    of ``jobs.casting()``), read through ``rd``: its Vd, its voids and slopes, each sample's
    direct term from its pieces (each group's window read once), the sums
    (``engine.irradiance.sums``). ``stats``, ``used``: the algorithm's figures and the
    curvature used, added to; ``timer(stage)``: "sky view", "compute" (and the sums' own
    stages); ``on_piece(piece)`` after each piece lit."""
    from ..engine import irradiance as ir
    from ..engine.sun_sums import sun_pieces
    from ..engine.windows import WindowCache
    from .horizon_windows import Figures

    def timed(stage):
        return timer(stage) if timer is not None else contextlib.nullcontext()
    region = rs.region
    r0, r1, c0, c1 = region
    with timed("sky view"):
        if jobs.horizons is None:
            o0, o1 = jobs.vd_origin
            vd, fig = jobs.vd_file.read((r0 - o0, r1 - o0, c0 - o1, c1 - o1)), Figures()
        else:
            vd, fig = region_vd(jobs.horizons, rd, region)
    cache = WindowCache(rd)
    src = jobs.light.source
    lit_suns = jobs.casting()
    order = sun_pieces(cache.get, rs)
    with timed("compute"):
        void, slopes = surface(cache.get, src.grid, src.shape, region)

        def direct(s, timed):
            i, pieces = next(order, (None, None))
            if i is None or jobs.suns[lit_suns[i]] is not s:
                raise HillshadeError(f"region {region}: the planned suns are not the sums' "
                                     "(a bug)")
            out = np.empty((r1 - r0, c1 - c0), np.float32)
            with timed("shadows"):
                for p, z in pieces:
                    add_direct(jobs.light, out, (r0, c0), p, z, stats, used)
                    if on_piece is not None:
                        on_piece(p)
            return out
        mg, groups = jobs.groups, None
        if mg is not None:
            groups = ir.Groups(mg.index, None if jobs.group_albedo is None else
                               [albedo_of(a, region) for a in jobs.group_albedo], mg.bands)
        bands = ir.sums(direct, void, slopes, jobs.suns, jobs.weights, jobs.sky, vd,
                        albedo_of(jobs.albedo, region), soft=jobs.soft, perez=jobs.perez,
                        stats=stats, timer=timer, groups=groups,
                        cells=None if jobs.cells is None else jobs.cells.cells(region, void))
        months = bands.pop("groups", [])
        if jobs.hours is not None:        # --mean (÷ hours), --daily-mean (÷ days)
            bands = {k: (v / np.float32(jobs.hours)).astype(np.float32)
                     for k, v in bands.items()}
            months = [(v / np.float32(h)).astype(np.float32)
                      for v, h in zip(months, jobs.month_hours or [])]
    return RegionMade(bands, vd, fig, cache.carried_bytes, months)


# ---------------------------------------------------------------------------------------------
# the run's bands in windows

@dataclass
class WindowedBands:
    """What a windowed irradiance run made (its bands written already): each band's and the
    Vd's (min, mean, max) (``horizon_windows.ValueStats.as_dict``), the curvature as applied,
    the algorithm's figures, how it ran (the report's ``processing``), where the Vd came from
    and the tags of a --sky-view file read; with --monthly each month's ((year, month), hours,
    its global band's (min, mean, max)), in order."""

    values: dict
    vd_values: dict
    curvature: dict | None
    algo_stats: dict
    processing: dict
    vd_from: str = "computed"
    vd_tags: dict | None = None
    months: list | None = None


def bands_in_windows(cfg, ctx, src, lighting, body, sampled, tags: dict, band_meta: list,
                     want, *, limit: int, window_shape=None, scheduler=None,
                     area=None) -> WindowedBands:
    """Write the four bands of ``src`` (``io.DemSource`` opened for windows; with ``area``, a
    ``run.context.Area``: its tile only) to ``cfg.output`` region by region (or as Dask tasks,
    ``scheduler``), and with --sky-view-out the Vd too. ``sampled``: the run's samples
    (``suns``, ``weights``, ``sky``, ``work``, ``hours``); ``tags`` the output's,
    ``band_meta`` each band's (description, tags); ``want(hs)`` the Vd file's tags for the
    horizon Shader ``hs`` (``sky_view_file.dozier_tags``). ``limit``: --max-memory in bytes,
    ``window_shape``: --window-size. With --monthly each month's global band after the four
    (``band_meta``'s units); an albedo by month, or rasters, as in memory (the rasters
    resampled to the output's grid once, :class:`SkyGrids`, removed at the end); the open sky
    per cell of ``sampled.cells`` (a :class:`GridSky` of :func:`open_sky_grids`: its grids'
    folder removed at the end too). Raises
    ``AllNodata`` (before anything is written) for a DEM of voids only, ``HillshadeError`` for
    a memory limit too small for one window."""
    from .local import bounded_gdal_cache
    gs = sampled.cells if isinstance(sampled.cells, GridSky) else None
    grids = gs.store if gs is not None else None
    if grids is None and cfg.albedo_input.rasters:
        grids = SkyGrids(cfg.output)
    try:
        with bounded_gdal_cache():
            return _bands_in_windows(cfg, ctx, src, lighting, body, sampled, tags, band_meta,
                                     want, limit, window_shape, scheduler, area, grids, gs)
    finally:
        if grids is not None:
            grids.close()


def month_meta(band_meta: list, groups: MonthGroups | None) -> list:
    """The months' bands' (description, tags) after the four (--monthly), as the run in memory
    writes them: YYYY-MM, the bands' units, NAME global, the month's HOURS."""
    if groups is None or not groups.bands:
        return []
    unit = band_meta[0][1]["UNITS"]
    return [(f"{y}-{m:02d}", {"UNITS": unit, "NAME": "global", "HOURS": f"{h:g}"})
            for (y, m), h in zip(groups.keys, groups.hours)]


def _bands_in_windows(cfg, ctx, src, lighting, body, sampled, tags, band_meta, want, limit,
                      window_shape, scheduler, area, grids, gs) -> WindowedBands:
    from ..engine.windows import block_stats
    from ..engine import irradiance as ir
    from ..model.earth import curvature_report
    from .period_cube import period_writer
    from .horizon_windows import Figures, ValueStats
    from .report import progress_total
    from .sky_view_file import open_vd, vd_writer, write_vd_window
    from .sun_hours_windows import Tally, plan_sums

    ro, timer = cfg.run, ctx.timer
    rows, cols = src.shape
    geom = src if area is None else area.tile
    tally = Tally()
    with timer("prepare"):   # one pass for the height ranges; the plan; compilation
        if area is None:
            bstats = block_stats(src, preview_side=2048 if ro.preview is not None else None)
            stats_bytes = rows * cols * src.itemsize
        else:
            bstats = area.block_stats()
            stats_bytes = area.statistics["bytes_read"]
        job = lighting_job(src, lighting, body, bstats)
        hjob, hs = sky_view_job(src, lighting, body, bstats, cfg.skyview_directions)
        vd_file = None
        if cfg.sky_view is not None:
            vd_file = open_vd(cfg.sky_view, geom, want(hs))
        origin = (0, 0) if area is None else (area.bounds[0], area.bounds[2])
        groups = month_groups(cfg, sampled)
        albedo, group_albedo = albedo_inputs(cfg, groups, grids, geom, src, origin)
        per = 1.0 if cfg.mean else 24.0
        mean = cfg.mean or cfg.daily_mean
        jobs = Jobs(job, None if vd_file is not None else hjob, vd_file, sampled.suns,
                    np.asarray(sampled.weights, np.float64), sampled.sky, albedo,
                    lighting.soft, cfg.perez, float(sampled.hours) / per if mean else None,
                    origin, groups, group_albedo,
                    [h / per for h in groups.hours] if mean and groups is not None else None,
                    None if gs is None else replace(gs, store=None))
        mmeta = month_meta(band_meta, groups)
        casting = [sampled.suns[k] for k in jobs.casting()]
        whole = (memory_per_cell(lighting) if window_shape is None and scheduler is None
                 and area is None else None)
        rasters = (1 if isinstance(albedo, SkyGrid) else 0) + sum(
            isinstance(a, SkyGrid) for a in group_albedo or []) + (
            jobs.cells.rasters() if jobs.cells is not None else 0)
        regs, mem = plan_sums(job, casting, bstats, limit,
                              window_bytes_per_cell(lighting, len(mmeta), rasters),
                              window_shape, area, whole)
        tally.plan(regs)
        if sampled.work:
            job.warm_up(sampled.work[0])
    values = {k: ValueStats() for k in ir.BANDS}
    month_values = [ValueStats() for _ in mmeta]
    vd_values, fig, algo_stats, used = ValueStats(), Figures(), {}, set()
    pv = bstats.preview if area is None else None
    n = bstats.stride
    pv_global = np.full(pv.shape, np.nan, np.float32) if pv is not None else None
    vd_tags = want(hs) if cfg.sky_view_out is not None else None
    if scheduler is not None:
        with timer("compute"):
            _on_dask(cfg, scheduler, jobs, regs, tags, band_meta + mmeta, vd_tags, values,
                     vd_values, fig, algo_stats, used, tally, pv_global, n, month_values)
        mode = "dask"
    else:
        from ..pictures.preview import every_nth
        bar = progress_total(tally.windows, ro.quiet, "hillshade-rt irradiance", "window",
                             ro.progress)
        w = period_writer(cfg, geom, tags, list(zip(groups.keys, groups.hours)) if mmeta
                          else [], dem=src, resampling="average")
        vw = vd_writer(cfg.sky_view_out, geom, vd_tags, ro) if vd_tags is not None else None
        with w, (vw if vw is not None else contextlib.nullcontext()), src.reader() as rd, bar:
            for rs in regs:
                made = region_bands(jobs, rd, rs, algo_stats, used, timer,
                                    lambda p: bar.update(1))
                fig.add(made.figures)
                tally.bytes_carried += made.bytes_carried
                at = rs.region if area is None else area.local(rs.region)
                vd_values.add(made.vd)
                if pv_global is not None:
                    sub, (a, b) = every_nth(made.bands["global"], rs.region[0], rs.region[2],
                                            n)
                    pv_global[a:a + sub.shape[0], b:b + sub.shape[1]] = sub
                with timer("write"):
                    for i, k in enumerate(ir.BANDS):
                        v = made.bands[k]
                        values[k].add(v)
                        v[np.isnan(v)] = -9999.0
                        w.write(i + 1, v, *band_meta[i], window=at)
                    for i, v in enumerate(made.months):
                        month_values[i].add(v)
                        v[np.isnan(v)] = -9999.0
                        w.write(len(ir.BANDS) + i + 1, v, *mmeta[i], window=at)
                    if vw is not None:
                        write_vd_window(vw, made.vd, at)
                del made
            tally.bytes_read = rd.bytes_read
            with timer("write"):     # the close compresses the last blocks
                if vw is not None:
                    vw.finish()
                w.finish()
        mode = "windows"
    if pv_global is not None:
        _preview(ro, src, bstats, pv_global)
    processing = tally.processing(mode, geom.shape[0] * geom.shape[1], src.itemsize, mem,
                                  window_shape, stats_bytes)
    processing["sky_view"] = fig.as_dict() if vd_file is None else None
    if area is not None:
        processing["context"] = area.report()
    return WindowedBands({k: v.as_dict() for k, v in values.items()}, vd_values.as_dict(),
                         curvature_report(job.curvature, used, job.body, job.k), algo_stats,
                         processing, "computed" if vd_file is None else "read",
                         None if vd_file is None else vd_file.tags,
                         [(k, h, v.as_dict()) for k, h, v in
                          zip(groups.keys, groups.hours, month_values)] if mmeta else None)


def _preview(ro, src, bstats, pv_global) -> None:
    """--preview in windows: the global band over the relief of every n-th cell (the
    statistics pass's), 2nd..98th percentile of those cells."""
    from ..io import write_png
    from ..model.geometry import Grid
    from ..pictures.preview import relief_rgb, scaled
    pv, n = bstats.preview, bstats.stride
    g = Grid(pv.shape[0], pv.shape[1], src.grid.dx[::n] * n, src.grid.dy[::n] * n,
             src.grid.col_sign, src.grid.row_sign, src.grid.method)
    write_png(ro.preview, relief_rgb(pv, g, ramp=scaled(pv_global)), ro.overwrite)


# ---------------------------------------------------------------------------------------------
# regions as Dask tasks (--scheduler)

def region_task(jobs: Jobs, rs, paths: dict, stride: int | None = None) -> dict:
    """The Dask task: the bands of region ``rs`` (:func:`region_bands`, its windows read
    here), written to ``paths["bands"]`` (a GeoTIFF of the region, four bands and with
    --monthly each month's, -9999 nodata) and its Vd to ``paths["vd"]`` when there is one.
    Returns its figures: (min, sum, count, max) of each band (the months' in "months") and of
    Vd, the horizon march's, the algorithm's, the curvature used,
    bytes read and carried, and the every-``stride``-th cells of the global band for a
    preview."""
    import rasterio

    from ..engine import irradiance as ir
    from ..engine.windows import GDAL_CACHE_MB
    from ..pictures.preview import every_nth
    from .dask import write_part
    from .horizon_windows import ValueStats

    stats: dict = {}
    used: set = set()
    with rasterio.Env(GDAL_CACHEMAX=GDAL_CACHE_MB), jobs.light.source.reader() as rd, \
            _TASK_LOCK:
        made = region_bands(jobs, rd, rs, stats, used)
        nread = rd.bytes_read
    r0, _, c0, _ = rs.region

    def figures(v):
        vs = ValueStats()
        vs.add(v)
        return vs.lo, vs.total, vs.count, vs.hi
    values = {k: figures(v) for k, v in made.bands.items()}
    shade = None
    if stride:
        sub, at = every_nth(made.bands["global"], r0, c0, stride)
        shade = (sub.copy(), at)
    src = jobs.light.source
    months = [figures(v) for v in made.months]
    write_part(paths["bands"], np.stack([np.where(np.isnan(v), np.float32(-9999.0), v)
                                         for v in [made.bands[k] for k in ir.BANDS]
                                         + made.months]),
               src, r0, c0, -9999.0, predictor=3)
    if "vd" in paths:
        write_part(paths["vd"], np.where(np.isnan(made.vd), np.float32(-9999.0), made.vd),
                   src, r0, c0, -9999.0, predictor=3)
    return {"values": values, "months": months, "vd": figures(made.vd),
            "figures": made.figures,
            "algorithm_stats": stats, "curvature_used": used, "bytes_read": nread,
            "bytes_carried": made.bytes_carried, "shade": shade}


def _on_dask(cfg, scheduler, jobs: Jobs, regs, tags, band_meta, vd_tags, values, vd_values,
             fig, algo_stats, used, tally, pv_global, stride, month_values=()) -> None:
    """Every region a task (:func:`region_task`); their parts put together through VRTs into
    ``cfg.output`` (as the in-memory run's file: four float32 bands, and a band per month of
    ``band_meta`` after them, -9999 nodata, the same tags and descriptions) and, with
    ``vd_tags``, into --sky-view-out."""
    from ..io.vrt import VrtSource
    from .dask import DaskSession
    from .horizon_windows import VrtOutput
    from .period_cube import period_parts
    from .report import progress_total
    from .sky_view_file import DOZIER_PRODUCT

    ro = cfg.run
    src = jobs.light.source
    if jobs.horizons is not None:      # nothing large to the workers: no preview
        h = jobs.horizons
        jobs = replace(jobs, horizons=replace(h, stats=replace(h.stats, preview=None)))
    with DaskSession(scheduler, cfg.output, ro.worker_timeout) as session:
        client, folder = session.client, session.folder
        workers = session.workers()
        parts = {}
        for rs in regs:
            r0, _, c0, _ = rs.region
            paths = {"bands": os.path.join(folder, f"irradiance_r{r0}_c{c0}.tif")}
            if vd_tags is not None:
                paths["vd"] = os.path.join(folder, f"vd_r{r0}_c{c0}.tif")
            f = client.submit(region_task, jobs, rs, paths,
                              stride if pv_global is not None else None, pure=False)
            parts[f.key] = (rs.region, paths)
            session.futures.append(f)
        done = []
        bar = progress_total(len(session.futures), ro.quiet, "hillshade-rt irradiance (dask)",
                             "window", ro.progress)
        with bar:
            for f, res in session.completed(session.futures):
                done.append(parts[f.key])
                for k, v in res["values"].items():
                    values[k].merge(v)
                for vs, v in zip(month_values, res["months"]):
                    vs.merge(v)
                vd_values.merge(res["vd"])
                fig.add(res["figures"])
                tally.take(res, used, algo_stats, pv_global)
                bar.update(1)

        def sources(name, band):
            return [VrtSource(p[name], band, (r[0], r[2]), (r[1] - r[0], r[3] - r[2]))
                    for r, p in done]
        if vd_tags is not None:
            VrtOutput(cfg.sky_view_out, src.shape, src.transform, src.crs, [DOZIER_PRODUCT],
                      vd_tags, resampling="average",
                      overwrite=ro.overwrite).write([sources("vd", 1)])
        g = jobs.groups
        out = period_parts(cfg, src, [d for d, _ in band_meta], tags,
                           [t for _, t in band_meta], list(zip(g.keys, g.hours))
                           if g is not None and g.bands else [], dem=src, resampling="average")
        out.write([sources("bands", i + 1) for i in range(len(band_meta))])
        tally.extra = session.info(workers)


def asked_windows(cfg) -> tuple:
    """(--max-memory in bytes, default half of this machine's memory; --window-size as (rows,
    cols) or None): a malformed one is a usage error (exit status 2)."""
    from .config import parse_window_size
    from .horizon import memory_limit
    return memory_limit(cfg.max_memory), parse_window_size(cfg.window_size)


def windowed(cfg) -> bool:
    """Whether --window-size or --scheduler ask for windows whatever the DEM's size."""
    return cfg.window_size is not None or cfg.scheduler is not None

