"""The ``horizon`` run: the horizon angle toward one azimuth (or N) of every cell of a DEM
(float32 degrees above the horizontal, -9999 nodata), in memory or, for a DEM larger than
``--max-memory`` or with ``--window-size``, in windows (``run.horizon_windows``: exact, the same bits).
Returns the report."""

from __future__ import annotations

import contextlib
import math
import os
from dataclasses import dataclass, field

from .. import __version__
from ..errors import AllNodata, HillshadeError, UsageProblem
from .config import HorizonConfig, parse_window_size
from .runner import RunContext

# bytes per cell of a run in memory: heights, the pyramid, one direction's angles and distances
# and their copies on the way to the file
BYTES_PER_CELL = 24


def check_max_distance(max_distance) -> float:
    """--max-distance as a number of metres (inf when not given); a usage error unless > 0."""
    if max_distance is None:
        return math.inf
    try:
        m = float(max_distance)
    except (TypeError, ValueError):
        m = math.nan
    if not (m > 0.0 and math.isfinite(m)):
        raise UsageProblem(f"--max-distance must be a positive number of metres, got "
                           f"{max_distance}")
    return m


def check_height(height) -> float:
    """--height-above-ground as metres (finite, >= 0; a usage error otherwise): the observer
    of every cell stands that high above it (``run.config.check_lift``)."""
    from .config import check_lift
    check_lift(height, "brute", False)
    return float(height)


def memory_limit(max_memory) -> int:
    """--max-memory in bytes (default: half of this machine's memory)."""
    from ..engine.windows import default_max_memory, parse_size
    try:
        return parse_size(max_memory) if max_memory is not None else default_max_memory()
    except HillshadeError as exc:
        raise UsageProblem(f"--max-memory: {exc}") from None


def distance_tag(max_distance: float) -> str:
    return (f"{max_distance:g} m (ground distance along each ray)" if math.isfinite(max_distance)
            else "none (to the raster's edge)")


@dataclass(frozen=True)
class Plan:
    """A ``horizon`` run's options, checked: the azimuths of the bands, --max-distance in
    metres (inf: none), --window-size as (rows, cols) or None, --max-memory in bytes."""

    azimuths: list
    max_distance: float
    wshape: tuple | None
    limit: int


@dataclass
class Made:
    """What the making of a ``horizon`` run left for its report: the raster whose shape and
    path it reports (the DEM, or the ``--context`` tile), whether the Earth's curvature was
    on, the algorithm's figures, how it was processed (the report's ``processing``), the notes
    said before the summary."""

    geom: object
    curved: bool
    stats: dict
    processing: dict
    notes: list = field(default_factory=list)
    angles: object = None      # horizon_windows.ValueStats of the angles written (None: none)


def horizon(cfg: HorizonConfig) -> dict:
    """Write the horizon angles of ``cfg`` (and the distances to the horizon points); returns
    the report."""
    plan = _check(cfg)
    ctx = _start(cfg, plan)
    made = _make(cfg, plan, ctx)
    return ctx.finish(_report(cfg, plan, ctx, made), _lines(cfg, plan, ctx, made))


def _check(cfg: HorizonConfig) -> Plan:
    """The options checked, before anything is claimed or read (usage errors)."""
    method = cfg.method
    azimuths = cfg.azimuths()
    cfg.read.check_context(cfg.dem, **{"--scheduler": cfg.scheduler is not None,
                                       "--preview": cfg.run.preview is not None,
                                       "--method hull": method == "hull"})
    if method == "hull" and cfg.sample_spacing != 1:
        raise UsageProblem("--sample-spacing applies to --method scan only")
    if method == "hull" and cfg.distance is not None:
        raise UsageProblem("--distance comes from --method scan only (the hull keeps no "
                           "horizon point)")
    max_distance = check_max_distance(cfg.max_distance)
    cfg.height_above_ground = check_height(cfg.height_above_ground)
    if method == "hull" and math.isfinite(max_distance):
        raise UsageProblem("--max-distance applies to --method scan only (the hull keeps the "
                           "whole line ahead)")
    return Plan(azimuths, max_distance, parse_window_size(cfg.window_size),
                memory_limit(cfg.max_memory))


def _start(cfg: HorizonConfig, plan: Plan) -> RunContext:
    """The run begun (``RunContext.start``: OUTPUT, --preview, --distance claimed; threads;
    backend; the compile note) and the outputs' format checked."""
    from ..io import check_output_format, output_driver
    ro = cfg.run
    ctx = RunContext.start(ro, inputs=[cfg.dem] + cfg.read.inputs(),
                           outputs=[(cfg.output, "OUTPUT")], algorithm="horizon",
                           options={"method": cfg.method})
    if cfg.distance is not None:
        ctx.claim(cfg.distance, "--distance")
    for path in [cfg.output] + ([cfg.distance] if cfg.distance is not None else []):
        check_output_format(path, output_driver(path, ro.fmt), "float32", len(plan.azimuths),
                            False, ro.creation_options)
    return ctx


def _make(cfg: HorizonConfig, plan: Plan, ctx: RunContext) -> Made:
    """The DEM opened and its horizons written: in memory, or in windows (a DEM larger than
    --max-memory, --window-size, --scheduler, a --context tile); all -9999 for a DEM with no
    valid cell."""
    from .local import needs_windows
    if cfg.read.context is not None:    # a tile of the context: its windows, in the context
        with ctx.timer("read"):
            area = cfg.read.open_area(cfg.dem)
        with area:
            try:
                area.check_valid()
            except AllNodata:
                return _all_nodata(cfg, plan, ctx, area.tile)
            return _in_windows(cfg, plan, ctx, area.source, area=area)
    forced = plan.wshape is not None or cfg.scheduler is not None
    with ctx.timer("read"):    # opened (not read) once, for its size and then its values
        src = cfg.read.open(cfg.dem, windows=forced)
    with src:
        windowed = forced or needs_windows(src, plan.limit, BYTES_PER_CELL)
        if windowed and cfg.method == "hull":
            raise UsageProblem("--method hull runs in memory only (its hulls are as long as a "
                               "line): use --method scan for a DEM in windows")
        run = _in_windows if windowed else _in_memory
        try:
            return run(cfg, plan, ctx, src)
        except AllNodata:       # (raised before any output is opened)
            return _all_nodata(cfg, plan, ctx, src)


def _no_terrain(cfg) -> str:
    """The value written where no terrain lies ahead: -90 degrees, or -pi/2 in radians."""
    import numpy as np
    from .horizon_windows import in_unit
    if cfg.angle_unit == "radians":
        return f"{float(in_unit(np.float32(-90.0), 'radians')):.9g} (-pi/2)"
    return "-90"


def _convention(cfg, azimuths) -> str:
    """How the bands' azimuths were chosen, for the AZIMUTH_CONVENTION tag."""
    head = "degrees clockwise from north (grid north), "
    series = cfg.series()
    if series is None:
        return head + "band i at i * 360 / N"
    start, end, step = series
    return (head + f"band i at {start:g} + i * {step:g} (mod 360) for i < floor(({end:g} - "
            f"{start:g}) / {step:g}) = {len(azimuths)} (r.horizon's start/end/step; r.horizon "
            "counts counter-clockwise from east: its angle is 90 - ours, mod 360)")


def _tags(cfg, azimuths, curved, k, radius, max_distance):
    """(the output's tags, the distance raster's tags, band tags per direction or None)."""
    many = cfg.many()
    units = ("radians above the horizontal" if cfg.angle_unit == "radians"
             else "degrees above the horizontal")
    base = {"HILLSHADE_RT_VERSION": __version__, "METHOD": cfg.method,
            "SAMPLE_SPACING": cfg.sample_spacing, "UNITS": units,
            "MAX_DISTANCE": distance_tag(max_distance),
            "HEIGHT_ABOVE_GROUND_M": float(cfg.height_above_ground)}
    dist_tags = {"HILLSHADE_RT_VERSION": __version__, "UNITS": "metres (ground distance along "
                 "the ray to the horizon point)", "NODATA": "-9999 (a void, or nothing ahead)",
                 "MAX_DISTANCE": distance_tag(max_distance)}
    if not many:
        az = azimuths[0]
        tags = {**base, "AZIMUTH": az,
                "EARTH_CURVATURE": f"on, R {radius:.0f} m, k {k:g}" if curved else "off"}
        return tags, {**dist_tags, "AZIMUTH": az}
    series = {"DIRECTIONS": len(azimuths), "AZIMUTHS": ",".join(f"{a:g}" for a in azimuths),
              "AZIMUTH_CONVENTION": _convention(cfg, azimuths)}
    if cfg.series() is not None:
        series.update(zip(("START", "END", "STEP"), (f"{v:g}" for v in cfg.series())))
    tags = {**base, "NODATA": "-9999 (a void)", "NO_TERRAIN_AHEAD": _no_terrain(cfg), **series,
            "EARTH_CURVATURE": f"on, k {k:g}" if curved else "off"}
    return tags, {**dist_tags, **series}


def _writers(cfg, dem, azimuths, tags, dist_tags):
    """The BandWriters of OUTPUT and --distance (None without it): one band with the
    dataset's tags, or N bands of averaged overviews."""
    from ..io import BandWriter
    ro = cfg.run
    n = len(azimuths)
    many = cfg.many()
    resampling = "average" if many else "nearest"
    w = BandWriter(cfg.output, dem, n, "float32", -9999.0, tags, overview_resampling=resampling,
                   overwrite=ro.overwrite, fmt=ro.fmt, co=ro.creation_options)
    wd = (None if cfg.distance is None else
          BandWriter(cfg.distance, dem, n, "float32", -9999.0, dist_tags,
                     overview_resampling=resampling, overwrite=ro.overwrite, fmt=ro.fmt,
                     co=ro.creation_options))
    return w, wd


def _band_text(cfg, a):
    """(description of the angle band, of the distance band, band tags) toward ``a``."""
    if not cfg.many():
        return "horizon angle", "distance to the horizon point", None
    return (f"horizon angle toward azimuth {a:g}",
            f"distance to the horizon point toward azimuth {a:g}", {"AZIMUTH": f"{a:g}"})


def _report(cfg: HorizonConfig, plan: Plan, ctx: RunContext, made: Made) -> dict:
    """The run's report (``--report``)."""
    from ..io import input_label
    many = cfg.many()
    rows, cols = made.geom.shape
    azimuths = plan.azimuths
    return {"input": input_label(made.geom.path), "output": os.path.abspath(cfg.output),
            "shape": [rows, cols],
            "distance": None if cfg.distance is None else os.path.abspath(cfg.distance),
            "azimuth": azimuths[0] if not many else None, "azimuths": azimuths,
            "method": cfg.method, "sample_spacing": cfg.sample_spacing,
            "height_above_ground_m": float(cfg.height_above_ground),
            "max_distance": plan.max_distance if cfg.max_distance is not None else None,
            "angle_unit": cfg.angle_unit,
            "series": (None if cfg.series() is None else
                       dict(zip(("start", "end", "step"), cfg.series()))),
            "backend": ctx.backend, "threads": ctx.threads, "curvature": made.curved,
            "algorithm_stats": made.stats, "seconds": ctx.phase_seconds(),
            "processing": made.processing,
            "angle_deg": (made.angles.as_dict() if made.angles is not None else
                          {"min": None, "mean": None, "max": None}),
            "version": __version__}


def _lines(cfg: HorizonConfig, plan: Plan, ctx: RunContext, made: Made) -> list:
    """The lines for people at the end: the making's notes, the summary, the algorithm's
    note."""
    azimuths, processing = plan.azimuths, made.processing
    rows, cols = made.geom.shape
    series = cfg.series()
    toward = (f"toward az {azimuths[0]:g}" if not cfg.many() else
              f"toward {len(azimuths)} directions ({360.0 / len(azimuths):g} deg apart)"
              if series is None else
              f"toward {len(azimuths)} directions (az {series[0]:g} to {series[1]:g} every "
              f"{series[2]:g} deg)")
    from .horizon_windows import windows_phrase
    where = windows_phrase(processing)
    summary = (f"hillshade-rt: {cfg.output}: {cols}x{rows}, horizon {toward} "
               f"({cfg.method}, {ctx.backend}{where}), compute "
               f"{ctx.timer.seconds.get('compute', 0.0):.3f} s")
    return ([("note", n) for n in made.notes] + [("summary", summary)]
            + [("note", made.stats.get("note"))])


def _in_memory(cfg: HorizonConfig, plan: Plan, ctx: RunContext, src) -> Made:
    """The horizons of the DEM read whole, one direction at a time, each band written as it
    is made."""
    import numpy as np

    from ..algorithms import horizon as hz
    from ..model.earth import dem_body
    from ..model.geometry import Grid, sun_rays
    from ..io import write_png
    from ..pictures.preview import relief_rgb
    from ..engine.shader import horizon_shader, warm_up

    ro, method, sample_spacing = cfg.run, cfg.method, cfg.sample_spacing
    azimuths, max_distance = plan.azimuths, plan.max_distance
    timer, ran_on = ctx.timer, ctx.backend
    lift = float(cfg.height_above_ground)
    az = azimuths[0]
    with timer("read"):
        d = src.read()
    stats: dict = {}
    md = max_distance if math.isfinite(max_distance) else None
    with timer("prepare"):  # numba compilation on a first run
        # the elevation does not enter the angles; curvature "auto" looks at the raster's size
        shader = horizon_shader(d.heights, d.grid, ran_on, cfg.curvature, cfg.refraction_k,
                                dem_body(d), method)
        small = sun_rays(Grid.uniform(4, 4, *d.grid.centre_spacing(), d.grid.col_sign,
                                      d.grid.row_sign), az, 45.0)
        gpu_dem = None
        if ran_on == "gpu":
            from ..engine.gpu import GpuDem
            hz.horizon_angles_gpu(GpuDem(np.eye(4, dtype=np.float32)), small, method,
                                  sample_spacing)
            gpu_dem = GpuDem(d.heights)
        else:
            warm_up("horizon", d.grid, az, 45.0, method=method, sample_spacing=sample_spacing)
            hz.horizon_angles(np.zeros((4, 4), np.float32), small, method=method,
                              sample_spacing=sample_spacing)

    # one pyramid for every direction (built at the first march)
    pyramid = None if gpu_dem is not None else shader.pyramid(d.heights, True)

    def angles(a):
        """(the horizon angles toward azimuth ``a``: float32 degrees, NaN on voids; the
        distances to the horizon points, -9999 where there is none, or None)."""
        rays = shader.rays(d.grid, a, 45.0)
        dist = None if cfg.distance is None else np.empty(d.shape, np.float32)
        with timer("compute"):
            if gpu_dem is not None:
                beta = hz.horizon_angles_gpu(gpu_dem, rays, method, sample_spacing,
                                             distance=dist, max_distance=md, lift=lift)
            else:
                beta = hz.horizon_angles(d.heights, rays, method=method,
                                         sample_spacing=sample_spacing, stats=stats,
                                         pyramid=pyramid, distance=dist, max_distance=md,
                                         lift=lift)
            if dist is not None:
                dist[np.isnan(dist)] = -9999.0
        return beta, dist

    curved = shader.curvature_for(az, 45.0) > 0     # the same for every direction
    tags, dist_tags = _tags(cfg, azimuths, curved, shader.k, shader.body.radius(az),
                            max_distance)
    from .horizon_windows import ValueStats, in_unit
    shade = None
    vals = ValueStats()
    # one band per direction, written as it is made (N bands never all in memory)
    w, wd = _writers(cfg, d, azimuths, tags, dist_tags)
    with w, (contextlib.nullcontext() if wd is None else wd):
        for i, a in enumerate(azimuths):
            beta, dist = angles(a)
            vals.add(beta)
            if ro.preview and i == 0:
                shade = np.clip(np.nan_to_num(beta, nan=0.0) / 30.0, 0.0, 1.0)
            beta = in_unit(beta, cfg.angle_unit)
            beta[np.isnan(beta)] = -9999.0
            text, dtext, btags = _band_text(cfg, a)
            with timer("write"):
                w.write(i + 1, beta, description=text, tags=btags)
                if wd is not None:
                    wd.write(i + 1, dist, description=dtext, tags=btags)
        with timer("write"):
            w.finish()
            if wd is not None:
                wd.finish()
    if ro.preview is not None:
        with timer("write"):
            write_png(ro.preview, relief_rgb(d.heights, d.grid, az, 45.0, shade=shade),
                      ro.overwrite)
    return Made(d, curved, stats, {"mode": "in memory", "cells": int(d.heights.size)},
                angles=vals)


def horizon_job(src, azimuths, ran_on, curvature, refraction_k, method, bstats, invert=False,
                sample_spacing=1, max_distance=math.inf, height_above_ground=0.0, body=None):
    """(the ``reach.HorizonJob`` of a windowed run, its horizon Shader): the rays and curvature
    an in-memory run of the same DEM would use (its shader decides from the raster's shape and
    spacing, never its heights); the observer ``height_above_ground`` metres above each cell.
    ``body``: the run's (default: the DEM's, ``earth.dem_body``)."""
    import numpy as np

    from ..model.earth import dem_body
    from ..engine.shader import horizon_shader
    from .horizon_windows import HorizonJob
    # the Shader looks at the raster's shape only: a zero-stride stand-in, no memory
    shader = horizon_shader(np.broadcast_to(np.float32(0.0), src.shape), src.grid, ran_on,
                            curvature, refraction_k, dem_body(src) if body is None else body,
                            method)
    curvs = [shader.curvature_used_for(a, 45.0) for a in azimuths]
    gpu = None
    if ran_on == "gpu":
        from ..engine.gpu import GpuDem
        gpu = GpuDem
    return HorizonJob(src, list(azimuths), curvs, (bstats.zmin, bstats.zmax), bstats, invert,
                      int(sample_spacing), float(max_distance), 0, gpu,
                      height_above_ground=float(height_above_ground)), shader


def prepare_windows(src, job, limit, wshape, timer, area=None):
    """The regions of a windowed run (``reach.plan_regions``) with the kernels compiled.
    ``area`` (``run.context.Area``, ``--context``): the regions of that tile of ``src``."""
    import numpy as np

    from ..algorithms.horizon import Marches, ScanWindow
    from ..model.geometry import Grid, sun_rays
    from .horizon_windows import plan_regions
    regs, mem = plan_regions(src.shape if area is None else area.shape, limit, wshape)
    if area is not None:
        regs = area.regions(regs)
    with timer("prepare"):     # compile (or load) the window kernels: a 4 x 4 march
        z = np.zeros((4, 4), np.float32)
        rays = sun_rays(Grid.uniform(4, 4, *src.grid.centre_spacing(), src.grid.col_sign,
                                     src.grid.row_sign), 203.7, 45.0)
        m = Marches(z, (0, 4, 0, 4), rays, (4, 4), 0.0, job.sample_spacing)
        m.march(ScanWindow(z, (0, 4, 0, 4), (4, 4), job.pyramid, job.gpu))
        m.angles(np.empty((4, 4), np.float32))
    return regs, mem


def _in_windows(cfg: HorizonConfig, plan: Plan, ctx: RunContext, src, area=None) -> Made:
    """The horizons in windows (``run.horizon_windows``), written window by window or made as
    Dask tasks (--scheduler). ``area``: the tile of ``src`` to make (``--context``; its
    windows read from ``src``)."""
    import numpy as np

    from ..model.geometry import Grid
    from ..io import write_png
    from ..pictures.preview import every_nth, relief_rgb
    from .local import bounded_gdal_cache
    from ..engine.windows import block_stats
    from .horizon_windows import Figures, Product, ValueStats, in_unit, region_outputs

    ro = cfg.run
    azimuths, max_distance = plan.azimuths, plan.max_distance
    timer, ran_on = ctx.timer, ctx.backend
    wshape, limit = plan.wshape, plan.limit
    az = azimuths[0]
    product = Product("horizon", distance=cfg.distance is not None,
                      radians=cfg.angle_unit == "radians")
    with bounded_gdal_cache():
        with timer("prepare"):    # one pass: the block height ranges (and the preview)
            bstats = (block_stats(src, preview_side=2048 if ro.preview else None)
                      if area is None else area.block_stats())
        job, shader = horizon_job(src, azimuths, ran_on, cfg.curvature, cfg.refraction_k,
                                  cfg.method, bstats, False, cfg.sample_spacing, max_distance,
                                  cfg.height_above_ground)
        regs, mem = prepare_windows(src, job, limit, wshape, timer, area)
        curved = job.curvatures[0] > 0
        tags, dist_tags = _tags(cfg, azimuths, curved, shader.k, shader.body.radius(az),
                                max_distance)
        geom = src if area is None else area.tile
        n = bstats.stride
        share = np.zeros(bstats.preview.shape, np.float32) if ro.preview else None
        extra = {}
        vals = ValueStats()
        if cfg.scheduler is not None:
            from .horizon_windows import run_on_dask
            with timer("compute"):
                fig, parts, extra = run_on_dask(cfg.scheduler, job, regs, product,
                                            _vrt_outputs(cfg, src, azimuths, tags, dist_tags),
                                            ro.quiet, share, n if ro.preview else None,
                                            progress_mode=ro.progress,
                                            worker_timeout=ro.worker_timeout)
            for part in parts:
                vals.merge(part)
        else:
            fig = Figures()
            w, wd = _writers(cfg, geom, azimuths, tags, dist_tags)
            from .report import progress_total
            bar = progress_total(len(regs), ro.quiet, "hillshade-rt", "window", ro.progress)
            with w, (contextlib.nullcontext() if wd is None else wd), src.reader() as rd, bar:
                for reg in regs:
                    out_reg = reg if area is None else area.local(reg)

                    def put(name, i, arr, reg=reg, out_reg=out_reg):
                        a = azimuths[i]
                        text, dtext, btags = _band_text(cfg, a)
                        if name == "angles" and share is not None and i == 0:
                            sub, (p, q) = every_nth(np.clip(np.nan_to_num(arr, nan=0.0) / 30.0,
                                                            0.0, 1.0), reg[0], reg[2], n)
                            share[p:p + sub.shape[0], q:q + sub.shape[1]] = sub
                        if name == "angles":
                            vals.add(arr)
                            arr = in_unit(arr, cfg.angle_unit)
                        arr[np.isnan(arr)] = -9999.0
                        with timer("write"):
                            if name == "angles":
                                w.write(i + 1, arr, description=text, tags=btags,
                                        window=out_reg)
                            else:
                                wd.write(i + 1, arr, description=dtext, tags=btags,
                                         window=out_reg)
                    with timer("compute", exclude="write"):    # put's writes apart
                        fig.add(region_outputs(job, rd, reg, product, put))
                    bar.update(1)
                with timer("write"):
                    w.finish()
                    if wd is not None:
                        wd.finish()
    if ro.preview is not None:
        pv = bstats.preview
        g = Grid(pv.shape[0], pv.shape[1], src.grid.dx[::n] * n, src.grid.dy[::n] * n,
                 src.grid.col_sign, src.grid.row_sign, src.grid.method)
        with timer("write"):
            write_png(ro.preview, relief_rgb(pv, g, az, 45.0, shade=share), ro.overwrite)
    processing = {"mode": "windows" if cfg.scheduler is None else "dask",
                  "cells": geom.shape[0] * geom.shape[1], "memory": mem,
                  "window_shape_requested": list(wshape) if wshape else None,
                  **fig.as_dict(), **extra}
    if area is not None:
        processing["context"] = area.report()
    return Made(geom, curved, {}, processing, angles=vals)


def _all_nodata(cfg: HorizonConfig, plan: Plan, ctx: RunContext, geom) -> Made:
    """A DEM (or ``--context`` tile) whose every cell is nodata: every band -9999, a note."""
    import numpy as np

    from .context import nodata_note
    azimuths = plan.azimuths
    tags, dist_tags = _tags(cfg, azimuths, False, 0.0, 0.0, plan.max_distance)
    w, wd = _writers(cfg, geom, azimuths, tags, dist_tags)
    arr = np.full(geom.shape, -9999.0, np.float32)
    with ctx.timer("write"), w, (contextlib.nullcontext() if wd is None else wd):
        for i, a in enumerate(azimuths):
            text, dtext, btags = _band_text(cfg, a)
            w.write(i + 1, arr, description=text, tags=btags)
            if wd is not None:
                wd.write(i + 1, arr, description=dtext, tags=btags)
        w.finish()
        if wd is not None:
            wd.finish()
    return Made(geom, False, {}, {"mode": "all nodata", "cells": int(arr.size)},
                [nodata_note(geom.path)])


def _vrt_outputs(cfg, src, azimuths, tags, dist_tags) -> dict:
    """The outputs of a run on Dask (``reach.VrtOutput``), as ``_writers`` writes them."""
    from .horizon_windows import VrtOutput
    ro = cfg.run
    many = cfg.many()
    texts = [_band_text(cfg, a) for a in azimuths]
    band_tags = [t[2] for t in texts] if many else None
    common = dict(shape=src.shape, transform=src.transform, crs=src.crs,
                  resampling="average" if many else "nearest", overwrite=ro.overwrite,
                  fmt=ro.fmt, co=ro.creation_options, band_tags=band_tags)
    out = {"angles": VrtOutput(cfg.output, descriptions=[t[0] for t in texts], tags=tags,
                               **common)}
    if cfg.distance is not None:
        out["distance"] = VrtOutput(cfg.distance, descriptions=[t[1] for t in texts],
                                    tags=dist_tags, **common)
    return out
