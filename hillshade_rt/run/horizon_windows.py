"""Horizons of rasters larger than memory: the horizon scan (``horizon``, ``skyview``) in
windows read through the DEM's windowed reader, exact: every cell gets the bits a run in memory
gives it.

**How far a ray reaches.** The horizon angle of a cell toward an azimuth is the maximum of
(T_k - h0 - k²c) / k over the samples k of its ray. Terrain at step k can raise a maximum b only
if zmax - h0 > b k, zmax the raster's highest cell: a cell that has found a horizon above the
horizontal (b > 0) needs no terrain beyond (zmax - h0) / b steps (the scan's own early exit).
But a cell whose horizon is at or below the horizontal (a summit, or a slope falling toward the
azimuth) is raised by any terrain ahead that is less far below it, however far away: its exact
horizon may come from the raster's edge. So without ``--max-distance`` the only a-priori halo
of a window is the rest of the raster toward each azimuth, which is the whole raster in the
worst case (a summit cell's skyview). ``--max-distance M`` bounds it: no ray reads beyond M.

**Windows.** Reading "the rest of the raster" at once would make a window as large as the
raster, so a ray is marched in pieces instead (``algorithms.horizon.Marches``): the march of a
cell is a running maximum over its samples in order, so it can stop at the last sample a window
holds and go on in the next window from the state it left (maximum, its step, next step), with
the same arithmetic in the raster's coordinates: the same bits. For each region of the output
(``--window-size``, or as large as ``--max-memory`` allows):

1. The *first window*: the region and, around it, the samples of every direction's rays up to
   step K0 (K0 the last step within M when the window fits, else the largest that fits), with
   a cell of margin all round (interpolation, Horn's normals for Dozier's definition). Read
   once; its maximum-height pyramid built once; every direction marches through it.
2. Rays still open (they left the first window, their march not over) go on in *continuation
   windows*, per direction: the bounding box of the open rays' samples from the first open step
   ka to the largest kb whose box fits the same memory, read, marched, and so on until every ray
   is closed (M, the raster's edge, or nothing left that could raise it). Before a
   continuation window is read, the statistics pass's block maxima bound its terrain: when no
   open ray could be raised by terrain that high at steps ka..kb (``Marches.can_rise``, with the
   march's own rounding), the window is skipped, not read.
3. A window's pyramid has the blocks that its far edge cuts (where the raster goes on) made
   +inf (``window_pyramid``), so that no skip passes a sample the window does not hold.

Memory: two windows of at most ``WINDOW_FACTOR`` times the region's cells (the first, kept for
every direction, and one continuation window), their pyramids, and the region's state and
outputs: ``BYTES_PER_REGION_CELL``. Reads: with M, each region reads its window once (the halo M
all round); without M, each direction's open rays may read as far as the raster's edge (the
block maxima skip what cannot matter): exact, bounded in memory, more reading.

What a region makes (``Product``: the horizon's bands, or a skyview definition's result) is
handed over as it is made (``region_outputs``): written into the outputs' windows in order, or,
with ``--scheduler``, each region a Dask task (``region_task``) that writes its parts, put
together through a VRT at the end (``run_on_dask``), as ``run.dask`` does for shadows.
"""

from __future__ import annotations

import contextlib
import math
import os
from dataclasses import dataclass

import numpy as np

# a window (first or continuation) holds at most this many times the region's cells
WINDOW_FACTOR = 4
# bytes per region cell: two windows of WINDOW_FACTOR x (4 B heights + ~1.4 B pyramid), the
# region's state (maximum 8, its step 8, next step 8, heights 4), angles and distances (8),
# a definition's sums (8 + 8 + 4: Dozier's cos S and sin S cos(φ - A), openness' counts)
BYTES_PER_REGION_CELL = 2 * WINDOW_FACTOR * 6 + 28 + 8 + 20
ALIGN = 256     # region sides: multiples of the output's blocks (when that large)
MARGIN = 1      # cells around every window's samples, and around the region (Horn's normals)


def region_shape(shape, budget_cells: int, window_shape=None) -> tuple[int, int]:
    """The regions' (rows, columns): ``window_shape`` (--window-size) or the largest square-ish
    block of at most ``budget_cells`` cells, sides multiples of ``ALIGN`` when that large."""
    rows, cols = shape
    if window_shape is not None:
        return min(rows, int(window_shape[0])), min(cols, int(window_shape[1]))
    side = max(16, int(math.isqrt(max(1, budget_cells))))
    if side >= ALIGN:
        side = side // ALIGN * ALIGN
    if side >= cols:
        return max(1, min(rows, budget_cells // max(1, cols))), cols
    if side >= rows:
        return rows, max(1, min(cols, budget_cells // max(1, rows)))
    return side, side


def regions(shape, rshape) -> list[tuple[int, int, int, int]]:
    """The raster cut into regions of ``rshape``, row by row."""
    rows, cols = shape
    tr, tc = rshape
    return [(r, min(rows, r + tr), c, min(cols, c + tc))
            for r in range(0, rows, tr) for c in range(0, cols, tc)]


def _cells(w) -> int:
    return 0 if w is None else (w[1] - w[0]) * (w[3] - w[2])


def _union(a, b):
    if a is None:
        return b
    if b is None:
        return a
    return min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3])


@dataclass
class RegionRays:
    """The rays toward one azimuth of a region's rows (``geometry.SunRays`` of rows r0:r1) and
    what bounds their samples: per row, the last step inside the raster along the dominant axis
    and the last step within the maximum distance."""

    rays: object
    region: tuple
    shape: tuple
    sp: int
    max_distance: float

    def __post_init__(self):
        ry, (r0, r1, c0, c1), (rows, cols) = self.rays, self.region, self.shape
        rr = np.arange(r0, r1)
        dc = ry.dom_col != 0
        fwd = ry.step_dom > 0
        inside = np.where(dc, np.where(fwd, cols - 1 - c0, c1 - 1),
                          np.where(fwd, rows - 1 - rr, rr))
        if math.isfinite(self.max_distance):
            within = np.floor(self.max_distance / ry.step_m)
            inside = np.minimum(inside, np.minimum(within, 2.0 ** 62))
        self.last = int(inside.max()) if inside.size else 0   # no sample beyond this step

    def span(self, ka: int, kb: int):
        """The window (r0, r1, c0, c1) holding every sample of steps ka..kb of the region's
        rays (both cells a sample interpolates between, ``MARGIN`` around), within the raster;
        None when they all lie outside it."""
        ry, (r0, r1, c0, c1), (rows, cols) = self.rays, self.region, self.shape
        rr = np.arange(r0, r1, dtype=np.float64)
        dc = ry.dom_col != 0
        sd = ry.step_dom.astype(np.float64)
        la, lb = ka * sd, kb * sd
        lo_line, hi_line = np.minimum(la, lb), np.maximum(la, lb)
        pa, pb = ka * ry.step_other, kb * ry.step_other
        lo_pos, hi_pos = np.minimum(pa, pb), np.maximum(pa, pb)
        # dominant axis the columns: lines are columns c0.., positions rows r + k*so
        # else: lines are rows r + k*sd, positions columns c + k*so for c in c0..c1-1
        row_lo = np.where(dc, np.floor(rr + lo_pos), rr + lo_line)
        row_hi = np.where(dc, np.floor(rr + hi_pos) + 1, rr + hi_line)
        col_lo = np.where(dc, c0 + lo_line, np.floor(c0 + lo_pos))
        col_hi = np.where(dc, c1 - 1 + hi_line, np.floor(c1 - 1 + hi_pos) + 1)
        a = max(0, int(row_lo.min()) - MARGIN)
        b = min(rows, int(row_hi.max()) + 1 + MARGIN)
        c = max(0, int(col_lo.min()) - MARGIN)
        d = min(cols, int(col_hi.max()) + 1 + MARGIN)
        if a >= b or c >= d:
            return None
        return a, b, c, d

    def reach(self, ka: int, cap: int) -> int:
        """The largest kb (ka <= kb <= ``last``) whose span from ka fits ``cap`` cells (ka if
        none larger does)."""
        lo, hi = ka, max(ka, self.last)
        if _cells(self.span(ka, hi)) <= cap:
            return hi
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if _cells(self.span(ka, mid)) <= cap:
                lo = mid
            else:
                hi = mid
        return lo


@dataclass
class Figures:
    """What the windows of a run did (the report's ``processing``)."""

    regions: int = 0
    first_windows: int = 0
    continuation_windows: int = 0
    skipped_windows: int = 0       # continuation windows the block maxima showed useless
    cells_read: int = 0
    largest_window: int = 0

    def add(self, other: Figures) -> None:
        for k in ("regions", "first_windows", "continuation_windows", "skipped_windows",
                  "cells_read"):
            setattr(self, k, getattr(self, k) + getattr(other, k))
        self.largest_window = max(self.largest_window, other.largest_window)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


class ValueStats:
    """Minimum, mean and maximum of the valid (not NaN) values of a product, window by window
    (the reports' figures of skyview and horizon)."""

    def __init__(self):
        self.lo, self.total, self.count, self.hi = math.inf, 0.0, 0, -math.inf

    def add(self, a: np.ndarray) -> None:
        v = a[~np.isnan(a)]
        if v.size:
            self.lo = min(self.lo, float(v.min()))
            self.hi = max(self.hi, float(v.max()))
            self.total += float(v.sum(dtype=np.float64))
            self.count += int(v.size)

    def merge(self, part) -> None:
        """Add a Dask task's (min, sum, count, max)."""
        lo, total, count, hi = part
        self.lo, self.total, self.count = min(self.lo, lo), self.total + total, self.count + count
        self.hi = max(self.hi, hi)

    def as_dict(self) -> dict:
        return {"min": self.lo if self.count else None,
                "mean": self.total / self.count if self.count else None,
                "max": self.hi if self.count else None}


@dataclass
class HorizonJob:
    """What the windows of a horizon or skyview run share (picklable: a Dask task gets it).

    ``azimuths`` and ``curvatures`` (the curvature coefficient (1 - k)/2R of each direction's
    rays, 0 when flat: the in-memory run's ``Shader.curvature_used_for``) give the rays;
    ``zrange`` the raster's lowest and highest heights; ``invert``: march the inverted terrain
    -z (negative openness); ``stats``: the statistics pass's block ranges;
    ``height_above_ground``: the observer stands that many metres above each cell
    (--height-above-ground; ``lift``: as the march takes it)."""

    source: object
    azimuths: list
    curvatures: list
    zrange: tuple
    stats: object
    invert: bool = False
    sample_spacing: int = 1
    max_distance: float = math.inf
    window_cells: int = 0       # a window's cells at most (at least WINDOW_FACTOR x a region's)
    gpu: object = None          # gpu.GpuDem (the class) to march on the device
    pyramid: bool = True
    height_above_ground: float = 0.0

    @property
    def lift(self) -> float:
        """The observer's height over the terrain marched: H, or -H over the inverted -z (the
        observer at z + H is at -(z + H) there)."""
        return -self.height_above_ground if self.invert else self.height_above_ground

    @property
    def zmax(self) -> float:
        """The highest height of the terrain marched (of -z when inverted)."""
        return -self.zrange[0] if self.invert else self.zrange[1]

    def rays(self, i: int, rows: tuple[int, int]):
        """Direction ``i``'s rays of raster rows ``rows`` (what the in-memory run's rays hold
        for those rows)."""
        from ..model.geometry import sun_rays
        from ..engine.windows import window_grid
        g = window_grid(self.source.grid, (rows[0], rows[1], 0, self.source.shape[1]))
        return sun_rays(g, self.azimuths[i], 45.0, self.curvatures[i])

    def _highest(self, window) -> float:
        lo, hi = self.stats.range_over(window)
        return -lo if self.invert else hi

    def _read(self, rd, window) -> np.ndarray:
        r0, r1, c0, c1 = window
        z = np.empty((r1 - r0, c1 - c0), np.float32)
        rd.read(window, z)
        if self.invert:
            np.negative(z, out=z)
        return z

    def region(self, rd, region, on_direction, want_distance: bool = False,
               on_window=None) -> Figures:
        """March every direction's rays from the cells of ``region`` (r0, r1, c0, c1) through
        the windows (module docstring), reading through ``rd`` (``DemSource.reader()``); calls
        ``on_window(z, window, inner)`` once with the first window's heights (not inverted; the
        region at ``inner`` in it: what Dozier's normals need) and then, per direction,
        ``on_direction(i, azimuth, angles, distances or None)`` with the region's angles
        (float32 degrees, NaN voids, -90 nothing ahead) and distances (float32 metres, NaN
        where there is none). Returns the figures."""
        from ..algorithms.horizon import Marches, ScanWindow
        shape = self.source.shape
        r0, r1, c0, c1 = region
        fig = Figures(regions=1)
        cap = max(self.window_cells, WINDOW_FACTOR * (r1 - r0) * (c1 - c0))
        sp = int(self.sample_spacing)
        n = len(self.azimuths)
        own = (max(0, r0 - MARGIN), min(shape[0], r1 + MARGIN), max(0, c0 - MARGIN),
               min(shape[1], c1 + MARGIN))
        reach = [RegionRays(self.rays(i, (r0, r1)), region, shape, sp, self.max_distance)
                 for i in range(n)]

        def first(k):
            w = own
            for rr in reach:
                w = _union(w, rr.span(sp, min(k, max(sp, rr.last))))
            return w
        top = max(sp, max(rr.last for rr in reach))
        if _cells(first(top)) <= cap:
            k0 = top
        else:
            lo, hi = sp, top
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if _cells(first(mid)) <= cap:
                    lo = mid
                else:
                    hi = mid
            k0 = lo
        w0 = first(k0)
        z0 = self._read(rd, w0)
        fig.first_windows += 1
        fig.cells_read += _cells(w0)
        fig.largest_window = max(fig.largest_window, _cells(w0))
        inner = (slice(r0 - w0[0], r1 - w0[0]), slice(c0 - w0[2], c1 - w0[2]))
        if on_window is not None:
            on_window(-z0 if self.invert else z0, w0, inner)
        h0 = np.ascontiguousarray(z0[inner])
        sw0 = ScanWindow(z0, w0, shape, self.pyramid, self.gpu)
        for i, a in enumerate(self.azimuths):
            m = Marches(h0, region, reach[i].rays, shape, self.zmax, sp, self.max_distance,
                        self.lift)
            m.march(sw0)
            self._carry_on(rd, m, reach[i], cap, fig)
            dist = np.empty(h0.shape, np.float32) if want_distance else None
            on_direction(i, a, m.angles(dist), dist)
        return fig

    def _carry_on(self, rd, m, rr, cap, fig) -> None:
        """Continuation windows until every ray of ``m`` is closed."""
        from ..algorithms.horizon import ScanWindow
        while True:
            o = m.open()
            if not o.any():
                return
            ka = int(m.nextk[o].min())
            if ka > rr.last:
                return            # every sample left is off the raster or beyond the distance
            kb = rr.reach(ka, cap)
            win = rr.span(ka, kb)
            if win is None:
                return
            if not m.can_rise(self._highest(win), ka, kb):
                m.skip_to(kb)
                fig.skipped_windows += 1
                continue
            m.march(ScanWindow(self._read(rd, win), win, self.source.shape, self.pyramid,
                               self.gpu))
            fig.continuation_windows += 1
            fig.cells_read += _cells(win)
            fig.largest_window = max(fig.largest_window, _cells(win))


def windows_phrase(processing: dict) -> str:
    """How a horizon or sky-view run went, for its summary line: nothing in memory, else
    ", N windows" (and " on Dask")."""
    if processing["mode"] in ("in memory", "all nodata"):
        return ""
    return f", {processing['regions']} windows" + (" on Dask" if processing["mode"] == "dask"
                                                   else "")


def plan_regions(shape, limit: int | None, window_shape) -> tuple[list, dict]:
    """(the regions, the memory figures) of a windowed horizon run: ``window_shape``
    (--window-size) or regions as large as ``limit`` bytes (--max-memory) allow."""
    from ..engine.windows import window_budget
    if window_shape is not None:
        rshape, mem = region_shape(shape, 0, window_shape), None
    else:
        budget, mem = window_budget(limit, BYTES_PER_REGION_CELL)
        rshape = region_shape(shape, budget)
    return regions(shape, rshape), mem



# ---------------------------------------------------------------------------------------------
# what a region makes: the horizon's bands, or a skyview definition's result

@dataclass
class Product:
    """What the windows make of their regions' horizons (picklable): ``kind`` "horizon" (the
    "angles" output, one band per direction, and with ``distance`` the "distance" output) or
    "skyview" (the "result" output, one band: ``definition``'s, ``complement``: 1 - it)."""

    kind: str = "horizon"
    distance: bool = False
    definition: str = "zaksek"
    complement: bool = False
    radians: bool = False          # the "angles" written in radians (their figures in degrees)

    def outputs(self, n: int) -> dict:
        """Output name -> bands."""
        if self.kind == "horizon":
            return {"angles": n, **({"distance": n} if self.distance else {})}
        return {"result": 1}


def in_unit(beta, angle_unit: str):
    """The angles ``beta`` (float32 degrees, NaN voids) in ``angle_unit``: themselves, or
    times float32(pi / 180) for "radians" (r.horizon's unit without -d; a new array, NaN stays
    NaN)."""
    if angle_unit == "radians":
        return beta * np.float32(math.pi / 180.0)
    return beta


def region_outputs(job: HorizonJob, rd, region, product: Product, put) -> Figures:
    """March ``region`` (``HorizonJob.region``) and hand each of its outputs to
    ``put(name, band, array)`` (band 0-based; float32, NaN where nodata) as it is made."""
    if product.kind == "horizon":
        def on_direction(i, a, beta, dist):
            put("angles", i, beta)
            if dist is not None:
                put("distance", i, dist)
        return job.region(rd, region, on_direction, product.distance)
    from ..algorithms.skyview import Sum
    from ..engine.windows import window_grid
    sums = []

    def on_window(z, window, inner):
        sums.append(Sum(product.definition, z, window_grid(job.source.grid, window), *inner))

    def on_direction(i, a, beta, dist):
        sums[0].add(a, beta)
    fig = job.region(rd, region, on_direction, False, on_window)
    out = sums[0].result()
    if product.complement:
        out = (1.0 - out).astype(np.float32)
    put("result", 0, out)
    return fig


# ---------------------------------------------------------------------------------------------
# regions as Dask tasks (--scheduler)

_TASK_LOCK = None


@dataclass
class RegionPart:
    """What a Dask task (``region_task``) hands back of its region (picklable): the marches'
    figures, each output's part (output name -> the GeoTIFF of the region), the result's
    statistics (min, sum, count of its valid cells), the preview's share ((every-n-th cells,
    (row, col) where they go) or None) and the region (r0, r1, c0, c1)."""

    figures: Figures
    paths: dict
    stats: list
    shade: tuple | None
    region: tuple


def _task_lock():
    """One numba computation at a time per worker process (numba parallelises inside)."""
    global _TASK_LOCK
    if _TASK_LOCK is None:
        import threading
        _TASK_LOCK = threading.Lock()
    return _TASK_LOCK


def region_task(job: HorizonJob, region, product: Product, folder: str,
                stride: int | None = None) -> RegionPart:
    """The Dask task: march ``region``, write each output's part (a GeoTIFF of the region's
    shape, a band per direction, -9999 nodata) in ``folder``; returns the figures, the parts'
    paths, the result's statistics (min, sum, count, max of valid cells) and, with ``stride``, the
    every-``stride``-th cells of the first direction's preview shade."""
    import warnings

    import rasterio
    from affine import Affine
    from rasterio.errors import NotGeoreferencedWarning

    from ..io import DEFLATE_LEVEL, atomic_path, gdal_checked
    from ..pictures.preview import every_nth
    from ..engine.windows import GDAL_CACHE_MB

    r0, r1, c0, c1 = region
    src = job.source
    n = len(job.azimuths)
    paths = {name: os.path.join(folder, f"{name}_r{r0}_c{c0}.tif")
             for name in product.outputs(n)}
    prof = dict(driver="GTiff", width=c1 - c0, height=r1 - r0, dtype="float32", nodata=-9999.0,
                compress="deflate", zlevel=DEFLATE_LEVEL, predictor=3, tiled=True,
                blockxsize=256, blockysize=256, interleave="band")
    if src.crs is not None:
        prof["crs"] = src.crs
    if src.transform is not None:
        prof["transform"] = src.transform @ Affine.translation(c0, r0)
    stats = [math.inf, 0.0, 0, -math.inf]
    shade = []
    with contextlib.ExitStack() as stack:
        stack.enter_context(warnings.catch_warnings())
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        dsts = {}
        for name, count in product.outputs(n).items():
            # overwrite: a task run again (its worker died) writes the same part again
            tmp = stack.enter_context(atomic_path(paths[name], ".tif", overwrite=True))
            stack.enter_context(gdal_checked(paths[name]))
            dsts[name] = stack.enter_context(rasterio.open(tmp, "w", count=count, **prof))

        def put(name, band, arr):
            if name in ("result", "angles"):     # the figures of the product itself
                v = arr[~np.isnan(arr)]
                if v.size:
                    stats[0] = min(stats[0], float(v.min()))
                    stats[1] += float(v.sum(dtype=np.float64))
                    stats[2] += int(v.size)
                    stats[3] = max(stats[3], float(v.max()))
            if stride and name == "angles" and band == 0:
                sub, at = every_nth(np.clip(np.nan_to_num(arr, nan=0.0) / 30.0, 0.0, 1.0), r0,
                                    c0, stride)
                shade.append((sub.copy(), at))
            if name == "angles" and product.radians:
                arr = in_unit(arr, "radians")
            dsts[name].write(np.where(np.isnan(arr), np.float32(-9999.0), arr)[np.newaxis],
                             [band + 1])
        with rasterio.Env(GDAL_CACHEMAX=GDAL_CACHE_MB), src.reader() as rd, _task_lock():
            fig = region_outputs(job, rd, region, product, put)
    return RegionPart(fig, paths, stats, shade[0] if shade else None, tuple(region))


def run_on_dask(scheduler, job: HorizonJob, regs, product: Product, outputs: dict,
                quiet: bool, share=None, stride: int | None = None,
                progress_mode: str = "bar",
                worker_timeout: float | None = None) -> tuple[Figures, list, dict]:
    """Every region as a task; then each output (``outputs``: name -> a function of the VRT
    document of its parts that writes it) assembled through a VRT. Returns (the figures, the
    results' statistics per region, what the report says of the scheduler). The parts' folder
    beside the first output is removed, also when the run fails; the cluster's failures are
    one-line errors (``run.dask.DaskSession``, ``worker_timeout`` its bound)."""
    from dataclasses import replace

    from ..io.vrt import VrtSource
    from .report import progress_total
    from .dask import DaskSession

    first = next(iter(outputs.values()))
    with DaskSession(scheduler, first.path, worker_timeout) as session:
        client, folder = session.client, session.folder
        workers = session.workers()
        light = replace(job, stats=replace(job.stats, preview=None))    # nothing large
        futures = session.futures
        futures += [client.submit(region_task, light, reg, product, folder, stride,
                                  pure=False) for reg in regs]
        fig, results = Figures(), []
        bar = progress_total(len(futures), quiet, "hillshade-rt (dask)", "window",
                             progress_mode)
        with bar:
            for _, res in session.completed(futures):
                fig.add(res.figures)
                results.append(res)
                if share is not None and res.shade is not None:
                    sub, (a, b) = res.shade
                    share[a:a + sub.shape[0], b:b + sub.shape[1]] = sub
                bar.update(1)
        n = len(job.azimuths)
        for name, out in outputs.items():
            bands = [[VrtSource(res.paths[name], i + 1, (res.region[0], res.region[2]),
                                (res.region[1] - res.region[0], res.region[3] - res.region[2]))
                      for res in results] for i in range(product.outputs(n)[name])]
            out.write(bands)
        return fig, [r.stats for r in results], session.info(workers)


@dataclass
class VrtOutput:
    """One output of a Dask run: where it goes and how (``io.copy_vrt``), its bands'
    descriptions and tags."""

    path: str
    shape: tuple
    transform: object
    crs: object
    descriptions: list
    tags: dict
    band_tags: list | None = None
    resampling: str = "nearest"
    overwrite: bool = False
    fmt: str | None = None
    co: dict | None = None          # --co: creation options

    def write(self, bands) -> None:
        from ..io import copy_vrt
        from ..io.vrt import vrt_xml
        doc = vrt_xml(self.shape, self.transform, self.crs, bands, "Float32", -9999.0,
                      self.descriptions, {k: str(v) for k, v in self.tags.items()},
                      self.band_tags)
        copy_vrt(doc, self.path, "float32", False, self.resampling, self.overwrite, self.fmt,
                 self.co)
