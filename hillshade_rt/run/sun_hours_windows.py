"""Sun hours of rasters larger than memory: the sums of ``engine.sun_sums`` region by region,
each region written into OUTPUT as it is made, or each region a Dask task (``--scheduler``) that
writes its part, put together through a VRT at the end (as ``run.dask`` does for shadows). Every
cell gets the bits a run in memory gives it (the same float32 additions, in the same order).
With ``--monthly`` each region adds every sample's term to its month's float32 sum too
(``engine.sun_sums.region_sums``), written as bands 2 on, as in memory.

Used by ``run.sun_hours`` for a DEM larger than ``--max-memory``, with ``--window-size`` or
``--scheduler``, and for a ``--context`` tile (its regions cut to the tile, their windows read
from the context)."""

from __future__ import annotations

import math
import os
import threading
from dataclasses import dataclass, field

import numpy as np

from ..errors import HillshadeError

DESCRIPTION = "hours of direct sun"
# r.sun's name of the same product: its insol_time, hours of direct sun over one day (mode 2)
RSUN_NAME = "insol_time"


def description(tags: dict) -> str:
    """The band's description: r.sun's name (``RSUN_NAME``) for the hours of one day (the tags'
    DAYS 1: r.sun's product), ``DESCRIPTION`` for the sum over several days."""
    return RSUN_NAME if int(tags.get("DAYS", 0)) == 1 else DESCRIPTION
_TASK_LOCK = threading.Lock()     # one numba computation at a time per Dask worker process


def memory_per_cell(lighting, months: int = 0) -> int:
    """Bytes per cell of a run in memory: what lighting the DEM whole needs
    (``engine.windows.bytes_per_cell``, product "sun"), the hours and one sun's weighted term,
    and with --monthly each of the ``months``' float32 sums."""
    from ..engine.windows import bytes_per_cell
    return (bytes_per_cell(lighting.algorithm, "sun", lighting.soft, lighting.self_shadow) + 8
            + 4 * months)


@dataclass
class WindowedHours:
    """What a windowed sun-hours run made: the hours' figures (``horizon_windows.ValueStats``),
    the curvature as applied, the algorithm's figures, how it ran (the report's
    ``processing``), for ``--preview`` (heights, grid, hours) on every n-th cell, and with
    --monthly each month's ((year, month), ``ValueStats``)."""

    values: object
    curvature: dict | None
    algo_stats: dict
    processing: dict
    preview: tuple | None = None
    months: list | None = None


@dataclass
class Tally:
    """Figures of the windows: regions, pieces lit, windows read, cells and bytes read."""

    regions: int = 0
    windows: int = 0
    reads: int = 0
    cells_read: int = 0
    largest: tuple = (0, 0)
    bytes_read: int = 0
    bytes_carried: int = 0
    extra: dict = field(default_factory=dict)

    def plan(self, regs) -> None:
        self.regions = len(regs)
        for rs in regs:
            for g in rs.groups:
                r0, r1, c0, c1 = g.window
                self.reads += 1
                self.cells_read += (r1 - r0) * (c1 - c0)
                if (r1 - r0) * (c1 - c0) > self.largest[0] * self.largest[1]:
                    self.largest = (r1 - r0, c1 - c0)
            self.windows += rs.pieces

    def take(self, res: dict, used: set, algo_stats: dict, preview) -> None:
        """A Dask task's result ``res`` (a region's ``region_task``) counted: its bytes read
        and carried, the curvature it applied (into ``used``), its algorithm figures (the
        first of each kind, into ``algo_stats``), and its preview cells put into ``preview``
        (the every-n-th-cell raster, or None)."""
        used |= res["curvature_used"]
        for k, v in res["algorithm_stats"].items():
            algo_stats.setdefault(k, v)
        self.bytes_read += res["bytes_read"]
        self.bytes_carried += res["bytes_carried"]
        if preview is not None and res["shade"] is not None:
            sub, (a, b) = res["shade"]
            preview[a:a + sub.shape[0], b:b + sub.shape[1]] = sub

    def processing(self, mode: str, cells: int, itemsize: int, memory, window_shape,
                   stats_bytes: int) -> dict:
        """The report's ``processing`` of a run of ``cells`` output cells (``itemsize`` bytes a
        height): ``mode`` ("tiled", "dask", ...), the memory figures, --window-size, the
        statistics pass's bytes and these figures."""
        return {"mode": mode, "cells": cells, "memory": memory,
                "window_shape_requested": list(window_shape) if window_shape else None,
                "regions": self.regions, "windows": self.windows, "windows_read": self.reads,
                "largest_window": list(self.largest), "cells_read": self.cells_read,
                "bytes_read": self.bytes_read, "bytes_carried": self.bytes_carried,
                "dem_reads": self.bytes_read / max(1, cells * itemsize),
                "statistics_pass_bytes": stats_bytes, **self.extra}


def hours_in_windows(cfg, ctx, src, lighting, req, work, tags, *, limit, window_shape,
                     scheduler=None, area=None, months=None) -> WindowedHours:
    """Write the sun hours of ``src`` (``io.DemSource`` opened for windows; with ``area``, a
    ``run.context.Area``: its tile only) to ``cfg.output``: ``work`` the lit samples
    ``[(sun, hours)]`` in order, ``tags`` the output's. ``limit``: --max-memory in bytes;
    ``window_shape``: --window-size; ``scheduler``: --scheduler. ``months`` (--monthly): (the
    months' (year, month) in order, each sample of ``work``'s month index): a band per month
    after the total, each month's own float32 sum of its samples' terms, as in memory
    (``engine.sun_sums.region_sums``). Raises ``AllNodata`` (before anything is written) for a
    DEM of voids only, ``HillshadeError`` for a memory limit too small for one window (naming
    the smallest that would do)."""
    from ..engine.sun_sums import BYTES_PER_GROUP_CELL, region_sums, weighted_light
    from ..engine.windows import WindowCache, WindowLighting, block_stats, bytes_per_cell
    from ..model.earth import curvature_report, dem_body
    from ..pictures.preview import every_nth
    from .horizon_windows import ValueStats
    from .period_cube import period_writer
    from .report import progress_total

    ro, timer = cfg.run, ctx.timer
    rows, cols = src.shape
    suns, weights = [s for s, _ in work], [w for _, w in work]
    keys, group_of = months if months is not None else ([], None)
    per_cell = (bytes_per_cell(lighting.algorithm, "sun", lighting.soft, lighting.self_shadow)
                + BYTES_PER_GROUP_CELL + 4 * len(keys))
    tally = Tally()
    with timer("prepare"):   # one pass for the height ranges; the plan; compilation
        if area is None:
            bstats = block_stats(src, preview_side=2048 if ro.preview is not None else None)
            stats_bytes = rows * cols * src.itemsize
        else:
            bstats = area.block_stats()
            stats_bytes = area.statistics["bytes_read"]
        dx, dy = src.grid.centre_spacing()
        job = WindowLighting(src, lighting, dem_body(src, req.lat), (bstats.zmin, bstats.zmax),
                             math.hypot(cols * dx, rows * dy), "sun")
        whole = (memory_per_cell(lighting, len(keys)) if window_shape is None
                 and scheduler is None and area is None else None)
        regs, mem = plan_sums(job, suns, bstats, limit, per_cell, window_shape, area, whole)
        tally.plan(regs)
        if suns:
            job.warm_up(suns[0])
    geom = src if area is None else area.tile
    n = bstats.stride
    pv = bstats.preview if area is None else None
    pv_hours = np.full(pv.shape, np.nan, np.float32) if pv is not None else None
    values, algo_stats, used = ValueStats(), {}, set()
    month_values = [ValueStats() for _ in keys]
    if scheduler is not None:
        with timer("compute"):
            _on_dask(cfg, scheduler, job, regs, weights, tags, values, algo_stats, used,
                     tally, pv_hours, n, keys, group_of, month_values)
        mode = "dask"
    else:
        bar = progress_total(tally.windows, ro.quiet, "hillshade-rt sun-hours", "window",
                             ro.progress)
        w = period_writer(cfg, geom, tags, keys)
        with w, src.reader() as rd, bar:
            cache = WindowCache(rd)
            term = weighted_light(job, weights, algo_stats, used)
            for rs in regs:
                with timer("compute"):
                    acc, per = region_sums(cache.get, rs, term, lambda p: bar.update(1),
                                           group_of, len(keys))
                    values.add(acc)
                    for vs, v in zip(month_values, per):
                        vs.add(v)
                if pv_hours is not None:
                    sub, (a, b) = every_nth(acc, rs.region[0], rs.region[2], n)
                    pv_hours[a:a + sub.shape[0], b:b + sub.shape[1]] = sub
                at = rs.region if area is None else area.local(rs.region)
                with timer("write"):
                    for i, (v, (text, btags)) in enumerate(
                            zip([acc] + per, band_texts(tags, keys)), 1):
                        v[np.isnan(v)] = -9999.0
                        w.write(i, v, text, btags, window=at)
                del acc, per
            tally.bytes_read, tally.bytes_carried = rd.bytes_read, cache.carried_bytes
            with timer("write"):     # the close compresses the last blocks
                w.finish()
        mode = "tiled"
    cells = geom.shape[0] * geom.shape[1]
    processing = tally.processing(mode, cells, src.itemsize, mem, window_shape, stats_bytes)
    if area is not None:
        processing["context"] = area.report()
    preview = None
    if pv is not None:
        from ..model.geometry import Grid
        g = Grid(pv.shape[0], pv.shape[1], src.grid.dx[::n] * n, src.grid.dy[::n] * n,
                 src.grid.col_sign, src.grid.row_sign, src.grid.method)
        preview = (pv, g, pv_hours)
    return WindowedHours(values, curvature_report(job.curvature, used, job.body, job.k),
                         algo_stats, processing, preview,
                         list(zip(keys, month_values)) if months is not None else None)


MONTH_TAGS = {"UNITS": "hours of direct sun"}


def band_texts(tags: dict, months=()) -> list:
    """Each band's (description, tags): the hours (:func:`description`, no tags of its own),
    then with --monthly each month's (``YYYY-MM``, ``MONTH_TAGS``), as the run in memory
    writes them."""
    return [(description(tags), None)] + [(f"{y}-{m:02d}", MONTH_TAGS) for y, m in months]


def plan_sums(job, suns, bstats, limit: int, per_cell: int, window_shape, area=None,
              whole_per_cell: int | None = None) -> tuple[list, dict | None]:
    """(the regions with their suns in groups, ``engine.sun_sums.plan_regions``; the memory
    figures) of a run of sums over ``suns`` in windows of ``per_cell`` bytes a cell under
    ``limit`` bytes (--max-memory), regions of ``window_shape`` (--window-size) or the cheapest
    that fit, of ``area``'s tile only (``--context``). A limit too small for one window is one
    ``HillshadeError`` naming the smallest --max-memory that would do (or, with
    ``whole_per_cell``, the bytes a cell of a run in memory needs, the DEM whole in memory
    where that needs less)."""
    from ..engine.sun_sums import plan_regions
    from ..engine.windows import (MIN_WINDOW_CELLS, MemoryTooSmall, format_size,
                                  memory_needed, window_budget)
    try:
        budget, mem = window_budget(limit, per_cell)
        small = None
    except HillshadeError as exc:
        budget, mem, small = 0, None, exc
    try:
        regs = plan_regions(job, suns, bstats, budget, window_shape,
                            None if area is None else area.bounds)
    except MemoryTooSmall as exc:
        small, cells = small or exc, exc.cells
    else:
        cells = max(g.cells for rs in regs for g in rs.groups)
    if small is not None:
        least = memory_needed(per_cell, max(cells, MIN_WINDOW_CELLS))
        if whole_per_cell is not None:      # or the whole DEM in memory, where that needs less
            rows, cols = job.source.shape
            least = min(least, memory_needed(whole_per_cell, rows * cols))
        said = str(small).split("; give")[0].replace(": raise --max-memory", "")
        raise HillshadeError(f"{said}; give at least --max-memory "
                             f"{format_size(least, up=True)}")
    return regs, mem


def windows_phrase(processing: dict) -> str:
    """How the run went, for its summary line: nothing in memory, else ", N windows" (the
    regions; " on Dask")."""
    if processing["mode"] in ("in memory", "all nodata"):
        return ""
    return f", {processing['regions']} windows" + (" on Dask" if processing["mode"] == "dask"
                                                   else "")


# ---------------------------------------------------------------------------------------------
# regions as Dask tasks (--scheduler)

def region_task(job, rs, weights, path: str, stride: int | None = None, group_of=None,
                groups: int = 0) -> dict:
    """The Dask task: the sums of region ``rs`` (``engine.sun_sums.region_sums``, its windows
    read here; with ``group_of``, each sample's month, the ``groups`` months' sums too, bands
    2 on), written to ``path`` (a GeoTIFF of the region, -9999 nodata). Returns its figures:
    (min, sum, count, max) of the hours (and of each month's, "months"), the algorithm's
    figures, the curvature used, bytes read and carried, and the every-``stride``-th hours for
    a preview."""
    import rasterio

    from ..engine.sun_sums import region_sums, weighted_light
    from ..engine.windows import GDAL_CACHE_MB, WindowCache
    from ..pictures.preview import every_nth
    from .dask import write_part
    from .horizon_windows import ValueStats

    stats: dict = {}
    used: set = set()
    with rasterio.Env(GDAL_CACHEMAX=GDAL_CACHE_MB), job.source.reader() as rd, _TASK_LOCK:
        cache = WindowCache(rd)
        acc, per = region_sums(cache.get, rs, weighted_light(job, weights, stats, used), None,
                               group_of, groups)
        nread, carried = rd.bytes_read, cache.carried_bytes

    def figures(v):
        vals = ValueStats()
        vals.add(v)
        return vals.lo, vals.total, vals.count, vals.hi
    r0, r1, c0, c1 = rs.region
    shade = None
    if stride:
        sub, at = every_nth(acc, r0, c0, stride)
        shade = (sub.copy(), at)
    values, months = figures(acc), [figures(v) for v in per]
    out = np.stack([acc] + per) if per else acc
    out[np.isnan(out)] = -9999.0
    write_part(path, out.astype(np.float32, copy=False), job.source, r0, c0, -9999.0,
               predictor=3)
    return {"values": values, "months": months, "algorithm_stats": stats,
            "curvature_used": used, "bytes_read": nread, "bytes_carried": carried,
            "shade": shade}


def _on_dask(cfg, scheduler, job, regs, weights, tags, values, algo_stats, used, tally,
             pv_hours, stride, months=(), group_of=None, month_values=()) -> None:
    """Every region a task (:func:`region_task`); their parts put together through a VRT into
    ``cfg.output`` (``horizon_windows.VrtOutput``, as the in-memory run's file: one float32
    band, with --monthly one per month of ``months`` after it, -9999 nodata, the same tags and
    descriptions)."""
    from ..io.vrt import VrtSource
    from .dask import DaskSession
    from .period_cube import period_parts
    from .report import progress_total

    ro = cfg.run
    src = job.source
    with DaskSession(scheduler, cfg.output, ro.worker_timeout) as session:
        client, folder = session.client, session.folder
        workers = session.workers()
        paths = {}
        for rs in regs:
            path = os.path.join(folder, f"hours_r{rs.region[0]}_c{rs.region[2]}.tif")
            f = client.submit(region_task, job, rs, weights, path,
                              stride if pv_hours is not None else None, group_of,
                              len(months), pure=False)
            paths[f.key] = (rs, path)
            session.futures.append(f)
        parts = []
        bar = progress_total(len(session.futures), ro.quiet, "hillshade-rt sun-hours (dask)",
                             "window", ro.progress)
        with bar:
            for f, res in session.completed(session.futures):
                rs, path = paths[f.key]
                parts.append((rs.region, path))
                values.merge(res["values"])
                for vs, v in zip(month_values, res["months"]):
                    vs.merge(v)
                tally.take(res, used, algo_stats, pv_hours)
                bar.update(1)
        texts = band_texts(tags, months)
        out = period_parts(cfg, src, [d for d, _ in texts], tags,
                           [t or {} for _, t in texts] if months else None, months)
        out.write([[VrtSource(path, b, (r[0], r[2]), (r[1] - r[0], r[3] - r[2]))
                    for r, path in parts] for b in range(1, len(texts) + 1)])
        tally.extra = session.info(workers)
