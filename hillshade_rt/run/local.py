"""A lighting run on this machine: the whole DEM in memory, or in windows read and written
through GDAL (each with its halo toward the sun), or on Dask (``run.dask``) when a scheduler is
given. Both take the run's inputs, the DEM opened once, the sun request, ``Outputs`` and the
lighting (``engine.lighting.Lighting``, whole), and return a :class:`ShadeResult`: what
``run.shade`` puts in the report and draws in the preview.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

from ..errors import HillshadeError
from .config import apply_scale


@dataclass(kw_only=True)
class ShadeResult:
    """What a lighting run did, for its report and its preview.

    Attributes
    ----------
    dem : Dem or DemSource
        What the outputs are georeferenced like (the DEM read, the source opened, or a
        ``--context`` run's tile).
    suns : list of SunOver
        The suns, one output (band or file) each.
    sun_info : dict or None
        The report's keys about the suns' place and times (``SunRequest.suns``).
    records : list of dict
        Each sun's record (``Outputs.record``): its statistics, seconds, marching.
    stats : dict or None
        The product's statistics of the last sun.
    algo_stats : dict
        The algorithm's figures (its note, ...).
    zrange : tuple
        (lowest, highest) height of the DEM, m ((None, None): all nodata).
    curvature : dict or None
        Earth curvature as applied (``Shader.report``, ``model.earth.curvature_report``).
    gpu : dict or None
        The GPU's figures of a run in memory on the GPU.
    processing : dict
        How it ran (``mode``: in memory, tiled, dask, all nodata; cells, windows, bytes).
    preview_heights : numpy.ndarray or None
        The heights the preview draws (every n-th cell in windows; None: nothing lit).
    preview_grid : Grid or None
        Their grid.
    preview_shade : numpy.ndarray or None
        The product's shade (0 lit .. 1 shadow) over the suns, mean, on the preview's cells.
    """

    dem: object
    suns: list
    sun_info: dict | None
    records: list
    stats: dict | None
    algo_stats: dict
    zrange: tuple
    curvature: dict | None
    gpu: dict | None
    processing: dict
    preview_heights: object = None
    preview_grid: object = None
    preview_shade: object = None

    def relief(self, azimuth: float, elevation: float):
        """The preview: the relief lit from (``azimuth``, ``elevation``), degrees, tinted by the
        shade (``pictures.preview.relief_rgb``); black for a run that lit nothing."""
        import numpy as np
        if self.preview_heights is None:
            return np.zeros(tuple(self.dem.shape) + (3,), np.uint8)
        from ..pictures.preview import relief_rgb
        return relief_rgb(self.preview_heights, self.preview_grid, azimuth, elevation,
                          shade=self.preview_shade)


def bounded_gdal_cache():
    """GDAL's block cache held to ``engine.windows.GDAL_CACHE_MB`` (its default, 5 % of the machine's
    memory, would break --max-memory on its own)."""
    import rasterio
    from ..engine.windows import GDAL_CACHE_MB
    return rasterio.Env(GDAL_CACHEMAX=GDAL_CACHE_MB)


def needs_windows(src, limit, per_cell) -> bool:
    """Whether shading the opened DEM ``src`` whole would need more than ``limit`` bytes (a
    DEM that can be read whole only, from standard input or a TIFF only tifffile reads, is
    read whole, as before)."""
    from ..engine.windows import window_budget
    if src.whole_only is not None:
        return False
    try:
        budget = window_budget(limit, per_cell)[0]
    except HillshadeError:
        return True   # too small even for a window: the windowed run says what would do
    rows, cols = src.shape
    return rows * cols > budget


def shade_in_memory(inputs, source, scale, req, out, timer, lighting, quiet, *,
                    progress_mode="bar", **_) -> ShadeResult:
    """``source``: the DEM already opened (``ReadOptions.open``; read here, not opened again),
    lit as ``lighting`` says (``engine.lighting.Lighting``: one ``Shader`` of it, its lift
    --height-above-ground)."""
    import numpy as np

    from ..engine.shader import render

    from ..model.earth import dem_body
    from .outputs import sun_tags
    from .report import progress

    kind = out.kind
    soft, self_shadow, ambient = lighting.soft, lighting.self_shadow, lighting.ambient
    with timer("read"):
        d = source.read()
        if scale is not None:
            apply_scale(d, scale)
    with timer("prepare"):   # solar positions; numba compilation on a first run; GPU upload
        suns, sun_info = req.suns(d)
        out.plan(suns, inputs)
        zmin, zmax = d.height_range()
        shader = lighting.shader(d.heights, d.grid, body=dem_body(d, req.lat),
                                 zrange=(zmin, zmax), survey=d.survey())
        day = [s for s in suns if not s.night]
        if day:
            shader.warm_up(day[0].azimuth, day[0].elevation, soft=soft,
                           incidence=self_shadow or kind != "shadow",
                           field=any(s.fieldwise for s in day))
    records, algo_stats = [], {}
    share, st = None, None
    with out.writer(d, len(suns)) as writer:
        for i, sun in enumerate(progress(suns, quiet, "hillshade-rt", mode=progress_mode)):
            t0 = timer.seconds.get("compute", 0.0)
            with timer("compute"):
                arr = render(shader, sun, kind, soft=soft, self_shadow=self_shadow,
                             ambient=ambient, stats=algo_stats)
            seconds = timer.seconds["compute"] - t0
            with timer("compute"):      # the product's statistics (counts over the raster)
                st = out.product.stats(arr)
            if out.preview:
                sh = out.product.shade(arr, ambient)
                share = sh / len(suns) if share is None else share + sh / len(suns)
            if soft:
                arr = np.where(np.isnan(arr), np.float32(out.nodata), arr).astype(np.float32)
            with timer("write"):
                if writer is not None:
                    writer.write(i + 1, arr, description=out.description(sun), tags=sun_tags(sun))
                else:
                    with out.file_writer(d, i, sun) as w:
                        w.write(1, arr, description=out.description(sun))
            records.append(out.record(sun, i, st, seconds, shader.field_ok(sun, soft)))
        if writer is not None:
            with timer("write"):     # the close compresses the last blocks
                writer.finish()
    return ShadeResult(dem=d, suns=suns, sun_info=sun_info, records=records, stats=st,
                       algo_stats=algo_stats, zrange=(zmin, zmax), curvature=shader.report(),
                       gpu=shader.gpu_report(),
                       processing={"mode": "in memory", "cells": int(d.heights.size)},
                       preview_heights=d.heights, preview_grid=d.grid, preview_shade=share)


def shade_in_windows(inputs, source, scale, req, out, timer, lighting, quiet, *, limit,
                     window_shape, scheduler, per_cell, area=None, progress_mode="bar",
                     worker_timeout=None) -> ShadeResult:
    """``source``: the DEM already opened for windows (``ReadOptions.open``), lit as
    ``lighting`` says (``engine.lighting.Lighting``, held by the run's
    ``windows.WindowLighting``; its lift shortens the halos). ``worker_timeout``:
    --worker-timeout of a Dask run (``run.dask.DaskSession``). ``area``: a tile of ``source``
    (``run.context.Area``, ``--context``): only its cells are lit and written, on the tile's
    grid, their windows read from ``source``."""
    import math

    import numpy as np

    from ..model.earth import dem_body
    from ..model.geometry import Grid
    from ..model.earth import curvature_report
    from ..pictures.preview import every_nth
    from ..engine.products import merge_stats
    from .outputs import sun_tags
    from ..engine.windows import (
        MIN_WINDOW_CELLS, WindowLighting, MemoryTooSmall, WindowedRunStats, WindowCache, block_stats, format_size,
        marched_per_cell, memory_needed, window_budget
    )

    kind = out.kind
    soft, ambient = lighting.soft, lighting.ambient
    with timer("read"):
        src = source
        if scale is not None:
            apply_scale(src, scale)
    rows, cols = src.shape
    geom = src if area is None else area.tile      # what the outputs are georeferenced like
    bounds = None if area is None else area.bounds
    tally = WindowedRunStats()
    with timer("prepare"):   # one pass for the height ranges; solar positions; compilation
        if area is None:
            bstats = block_stats(src, preview_side=2048 if out.preview else None)
            tally.stats_pass_bytes = rows * cols * src.itemsize
        else:       # (the context's, kept between runs)
            bstats = area.block_stats()
            tally.stats_pass_bytes = area.statistics["bytes_read"]
        zrange = (bstats.zmin, bstats.zmax)
        suns, sun_info = req.suns(src)
        out.plan(suns, inputs, src.tiles if area is None else None)
        dx, dy = src.grid.centre_spacing()
        job = WindowLighting(src, lighting, dem_body(src, req.lat), zrange,
                             math.hypot(cols * dx, rows * dy), kind)
        # a limit too small: measured now, after the preparation (the process has grown), the
        # error says the smallest --max-memory that would do: room for the largest window the
        # plan needs, or for the whole DEM where it could be shaded in memory
        try:
            budget, mem = window_budget(limit, per_cell)
            small = None
        except HillshadeError as exc:
            budget, mem, small = 0, None, exc
        try:
            plans = [job.pieces(s, bstats, budget, window_shape, in_order=scheduler is None,
                                area=bounds) for s in suns]
        except MemoryTooSmall as exc:
            small, cells = small or exc, exc.cells
        else:
            cells = max((p.cells for ps in plans for p in ps), default=0)
        if small is not None:
            least = memory_needed(per_cell, max(cells, MIN_WINDOW_CELLS))
            if len(inputs) == 1 and window_shape is None and scheduler is None:
                least = min(least, memory_needed(per_cell, rows * cols))
            said = str(small).split("; give")[0].replace(": raise --max-memory", "")
            raise HillshadeError(f"{said}; give at least --max-memory {format_size(least, up=True)}")
        day = [s for s in suns if not s.night]
        if day:
            job.warm_up(day[0])
    n = bstats.stride
    share = (np.zeros(bstats.preview.shape, np.float32) if out.preview else None)
    records, algo_stats, used = [], {}, set()
    st = None
    if scheduler is not None:
        from .dask import run_on_dask
        with timer("compute"):
            records, st, extra = run_on_dask(scheduler, job, suns, plans, out, share, n, quiet,
                                             algo_stats, used, tally, progress_mode,
                                             worker_timeout)
    else:
        from .report import progress_total
        bar = progress_total(sum(len(p) for p in plans), quiet, "hillshade-rt", "window",
                             progress_mode)
        with out.writer(geom, len(suns)) as writer, src.reader() as rd, bar:
            cache = WindowCache(rd)
            carry = job.carrier(plans)
            for i, (sun, pieces) in enumerate(zip(suns, plans)):
                t0 = timer.seconds.get("compute", 0.0)
                with (out.file_writer(geom, i, sun) if writer is None
                      else contextlib.nullcontext(writer)) as w:
                    band = 1 if writer is None else i + 1
                    st = None
                    for p in pieces:
                        with timer("compute"):
                            z = cache.get(p.window)
                            arr = job.light(z, p, algo_stats, used, carry)
                        tally.add(p)
                        with timer("compute"):      # the window's statistics
                            st = merge_stats(st, out.product.stats(arr))
                        if share is not None:
                            sub, (a, b) = every_nth(out.product.shade(arr, ambient),
                                                    p.region[0], p.region[2], n)
                            share[a:a + sub.shape[0], b:b + sub.shape[1]] += sub / len(suns)
                        if soft:
                            arr = np.where(np.isnan(arr), np.float32(out.nodata), arr).astype(
                                np.float32)
                        with timer("write"):
                            w.write(band, arr, window=p.region if area is None
                                    else area.local(p.region))
                        bar.update(1)
                    w.describe(band, out.description(sun),
                               sun_tags(sun) if writer is not None else None)
                    if writer is None:      # this sun's file: closed and published now
                        with timer("write"):
                            w.finish()
                out.finish(i, sun, src)
                records.append(out.record(sun, i, st, timer.seconds.get("compute", 0.0) - t0,
                                          marched_per_cell(plans[i])))
            tally.bytes_read = rd.bytes_read
            tally.bytes_carried = cache.carried_bytes
            tally.carry = carry
            if writer is not None:
                with timer("write"):     # the close compresses the last blocks
                    writer.finish()
        extra = {}
    curv = curvature_report(job.curvature, used, job.body, job.k)
    processing = {"mode": "tiled" if scheduler is None else "dask",
                  "cells": rows * cols if area is None else area.shape[0] * area.shape[1],
                  "memory": mem, "window_shape_requested": list(window_shape) if window_shape
                  else None, **tally.as_dict(src.itemsize), **extra}
    if area is not None:
        processing["context"] = area.report()
    if src.tiles:
        from ..io import input_label
        processing["mosaic"] = [{"path": input_label(t["path"]), "window": list(t["window"])}
                                for t in src.tiles]
    pv, g = bstats.preview, None      # the preview's heights: every n-th cell, their grid
    if pv is not None:
        g = Grid(pv.shape[0], pv.shape[1], src.grid.dx[::n] * n, src.grid.dy[::n] * n,
                 src.grid.col_sign, src.grid.row_sign, src.grid.method)
    return ShadeResult(dem=geom, suns=suns, sun_info=sun_info, records=records, stats=st,
                       algo_stats=algo_stats, zrange=zrange, curvature=curv, gpu=None,
                       processing=processing, preview_heights=pv, preview_grid=g,
                       preview_shade=share)


def all_nodata(inputs, source, req, out, timer, area=None, **_) -> ShadeResult:
    """The run of a DEM (or a ``--context`` tile) whose every cell is nodata: every output
    written all nodata (its bands and tags as a run that lights them), nothing lit. The suns
    are those of ``source`` (the context's, with ``area``)."""
    import numpy as np

    from .outputs import sun_tags
    geom = source if area is None else area.tile
    with timer("prepare"):
        suns, sun_info = req.suns(source)
        out.plan(suns, inputs, source.tiles if area is None else None)
    nan = np.full(geom.shape, np.nan, np.float32)
    arr = np.full(geom.shape, out.nodata, out.dtype)
    st = out.product.stats(nan if out.soft else arr)
    records = []
    with timer("write"), out.writer(geom, len(suns)) as writer:
        for i, sun in enumerate(suns):
            if writer is not None:
                writer.write(i + 1, arr, description=out.description(sun), tags=sun_tags(sun))
            else:
                with out.file_writer(geom, i, sun) as w:
                    w.write(1, arr, description=out.description(sun))
                out.finish(i, sun, source)
            records.append(out.record(sun, i, st, 0.0))
        if writer is not None:
            writer.finish()
    return ShadeResult(dem=geom, suns=suns, sun_info=sun_info, records=records, stats=st,
                       algo_stats={}, zrange=(None, None), curvature=None, gpu=None,
                       processing={"mode": "all nodata", "cells": int(arr.size)})


def mean_stats(records, last):
    fr = [r["shadow_fraction"] for r in records if r["shadow_fraction"] is not None]
    out = dict(last)
    out["shadow_fraction"] = (sum(fr) / len(fr)) if fr else None
    return out
