"""The ``skyview`` run: the sky view factor (or the openness) of every cell from its horizon in
N directions.

* ``zaksek`` (Zakšek, Oštir & Kokalj 2011 [1]_; HORAYZON's "visible sky fraction"): 1 - mean over
  the directions of sin(γ), γ the horizon elevation clipped at the horizontal (the sky is the upper
  hemisphere: terrain below the horizontal hides none of it). A flat plane: 1; a plane of slope S:
  1 - S/π (S in radians, continuous directions).
* ``dozier`` (Dozier & Frew 1990 [2]_; Dozier 2022 [3]_, eq. for Vd): the cosine-weighted view of
  the sky from the tilted surface, (1/2π) ∫ [cos S sin² H + sin S cos(φ - A) (H - sin H cos H)] dφ,
  H the horizon's zenith angle (π/2 - γ), S and A the cell's slope and aspect (Horn's normals, as
  the hillshade's): a plane of slope S gives (1 + cos S)/2, the rest, (1 - cos S)/2, being the
  terrain it faces: ``terrain_configuration`` writes that share, 1 - Vd (the view factor of the
  terrain, for reflected light).
* ``--openness positive`` (Yokoyama, Shirasawa & Pike 2002 [4]_): the mean over the directions of
  the horizon's zenith angle 90° - β, β NOT clipped (a cell that looks down on everything ahead has
  a horizon below the horizontal, an openness above 90°); ``negative``: the same of the inverted
  terrain -z, 90° + the angle down to the lowest terrain ahead (high in valleys and pits). Degrees.
  Yokoyama's L is ``--max-distance`` (default: the whole raster). Directions with no terrain ahead
  (within L) are left out of the mean; a cell with none at all is nodata.

Each direction is the ``horizon`` scan (exact on the model, curvature as for ``horizon``,
``--max-distance`` as there), accumulated as it is made (one direction's angles in memory at a
time). At the raster's edge there is no terrain beyond it: a border cell sees open sky toward the
outside (a larger DEM around the area of interest fixes that). Distances are ground metres
throughout (per row on geographic DEMs). A DEM larger than ``--max-memory``, or any DEM with
``--window-size``, is computed in windows (``run.horizon_windows``): the same bits.

References
----------
.. [1] K. Zakšek, K. Oštir, Ž. Kokalj, "Sky-View Factor as a Relief Visualization Technique,"
       Remote Sensing, vol. 3, no. 2, pp. 398-415, 2011. :doi:`10.3390/rs3020398`
.. [2] J. Dozier, J. Frew, "Rapid calculation of terrain parameters for radiation modeling from
       digital elevation data," IEEE Trans. Geosci. Remote Sens., vol. 28, no. 5, pp. 963-969,
       1990. :doi:`10.1109/36.58986`
.. [3] J. Dozier, "Revisiting Topographic Horizons in the Era of Big Data and Parallel Computing,"
       IEEE Geosci. Remote Sens. Lett., vol. 19, art. 8024605, 2022.
       :doi:`10.1109/LGRS.2021.3125278`
.. [4] R. Yokoyama, M. Shirasawa, R. J. Pike, "Visualizing topography by openness: A new
       application of image processing to digital elevation models," Photogramm. Eng. Remote Sens.,
       vol. 68, no. 3, pp. 257-265, 2002.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from .. import __version__
from ..errors import UsageProblem
from .config import parse_window_size
from .config import SkyviewConfig
from .horizon_windows import ValueStats as _Stats
from .runner import RunContext

from ..algorithms.skyview import DEFINITIONS, OPENNESS  # (the definitions, once)

# bytes per cell of a run in memory: heights and pyramid (twice for negative openness: -z),
# one direction's angles, the sums (Dozier: cos S and sin S cos(φ - A) too), the result
BYTES_PER_CELL = 48


def _check(cfg: SkyviewConfig) -> str:
    """The definition's name (``algorithms.skyview.definition_of``), the options checked."""
    from ..algorithms.skyview import definition_of
    if cfg.definition not in DEFINITIONS:
        raise UsageProblem(f"--definition must be one of {', '.join(DEFINITIONS)}, got "
                           f"{cfg.definition!r}")
    if cfg.openness is not None:
        if cfg.openness not in OPENNESS:
            raise UsageProblem(f"--openness must be one of {', '.join(OPENNESS)}, got "
                               f"{cfg.openness!r}")
        if cfg.definition != "zaksek" or cfg.terrain_configuration:
            raise UsageProblem("--openness is a product of its own: give it without "
                               "--definition and --terrain-configuration")
    if cfg.terrain_configuration and cfg.definition != "dozier":
        raise UsageProblem("--terrain-configuration is 1 - Dozier's view factor: give "
                           "--definition dozier")
    if not 4 <= int(cfg.directions) <= 360:
        raise UsageProblem(f"--directions must be between 4 and 360, got {cfg.directions}")
    return definition_of(cfg.definition, cfg.openness)


def describe(cfg: SkyviewConfig, definition: str) -> str:
    """What the output holds, in words (its description and the summary's)."""
    if definition.startswith("openness"):
        return f"{cfg.openness} openness (Yokoyama)"
    if cfg.terrain_configuration:
        return "terrain configuration factor (1 - Vd, dozier)"
    return f"sky view factor ({cfg.definition})"


@dataclass(frozen=True)
class Plan:
    """A ``skyview`` run's options, checked: the definition's name
    (``algorithms.skyview.definition_of``), --max-distance in metres (inf: none),
    --window-size as (rows, cols) or None, --max-memory in bytes."""

    definition: str
    max_distance: float
    wshape: tuple | None
    limit: int


@dataclass
class Made:
    """What the making of a ``skyview`` run left: the raster whose shape and path it reports
    (the DEM, or the ``--context`` tile), the result's statistics, how it was processed (the
    report's ``processing``), whether the Earth's curvature was on, the relief of the
    --preview (heights, Grid; None: none to draw), the notes said before the summary."""

    geom: object
    stats: _Stats
    processing: dict
    curved: bool
    relief: tuple | None = None
    notes: list = field(default_factory=list)


def skyview(cfg: SkyviewConfig) -> dict:
    """Write the sky view factor (or openness) of ``cfg``; returns the report."""
    plan = _plan(cfg)
    ctx = _start(cfg, plan)
    made = _make(cfg, plan, ctx)
    if cfg.run.preview is not None and made.relief is not None:
        with ctx.timer("write"):
            _preview(cfg, *made.relief)
    return ctx.finish(_report(cfg, plan, ctx, made), _lines(cfg, plan, ctx, made))


def _plan(cfg: SkyviewConfig) -> Plan:
    """The options checked, before anything is claimed or read (usage errors)."""
    from .horizon import check_height, check_max_distance, memory_limit
    definition = _check(cfg)
    max_distance = check_max_distance(cfg.max_distance)
    cfg.height_above_ground = check_height(cfg.height_above_ground)
    plan = Plan(definition, max_distance, parse_window_size(cfg.window_size),
                memory_limit(cfg.max_memory))
    cfg.read.check_context(cfg.dem, **{"--scheduler": cfg.scheduler is not None,
                                       "--preview": cfg.run.preview is not None})
    return plan


def _start(cfg: SkyviewConfig, plan: Plan) -> RunContext:
    """The run begun (``RunContext.start``: OUTPUT and --preview claimed; threads; the
    horizon scan's backend) and the output's format checked."""
    from ..io import check_output_format, output_driver
    ro = cfg.run
    ctx = RunContext.start(ro, inputs=[cfg.dem] + cfg.read.inputs(),
                           outputs=[(cfg.output, "OUTPUT")], algorithm="horizon",
                           options={"method": "scan"}, note=False)
    check_output_format(cfg.output, output_driver(cfg.output, ro.fmt), "float32", 1, True,
                        ro.creation_options)
    return ctx


def _make(cfg: SkyviewConfig, plan: Plan, ctx: RunContext) -> Made:
    """The DEM opened and its result written: in memory, or in windows (a DEM larger than
    --max-memory, --window-size, --scheduler, a --context tile); all -9999 for a DEM with no
    valid cell."""
    from ..errors import AllNodata
    from .local import needs_windows
    if cfg.read.context is not None:    # a tile of the context: its windows, in the context
        with ctx.timer("read"):
            area = cfg.read.open_area(cfg.dem)
        with area:
            try:
                area.check_valid()
                return _in_windows(cfg, plan, ctx, area.source, area=area)
            except AllNodata:
                return _all_nodata(cfg, plan, ctx, area.tile)
    forced = plan.wshape is not None or cfg.scheduler is not None
    with ctx.timer("read"):
        src = cfg.read.open(cfg.dem, windows=forced)
    with src:
        windowed = forced or needs_windows(src, plan.limit, BYTES_PER_CELL)
        run = _in_windows if windowed else _in_memory
        try:
            return run(cfg, plan, ctx, src)
        except AllNodata:    # (raised before the output is opened)
            return _all_nodata(cfg, plan, ctx, src)


def _tags(cfg, definition, n, curved, max_distance, made=None):
    """The output's tags; ``made``: how the horizons were made (``sky_view_file.provenance``:
    the refraction coefficient, the body, the context, the heights' digest)."""
    from .horizon import distance_tag
    from ..algorithms.skyview import units
    opn = definition.startswith("openness")
    return {"HILLSHADE_RT_VERSION": __version__,
            "DEFINITION": definition if opn else cfg.definition,
            "PRODUCT": describe(cfg, definition), "DIRECTIONS": n, "UNITS": units(definition),
            "MAX_DISTANCE": distance_tag(max_distance),
            "HEIGHT_ABOVE_GROUND_M": float(cfg.height_above_ground),
            "EDGE": ("no terrain beyond the raster: directions with no terrain ahead (within "
                     "MAX_DISTANCE) are left out of the mean; none at all: nodata" if opn else
                     "no terrain beyond the raster: border cells see open sky outward"),
            "EARTH_CURVATURE": "on" if curved else "off", **(made or {})}


def _writer(cfg, dem, definition, n, curved, max_distance, made=None):
    from ..io import BandWriter
    ro = cfg.run
    return BandWriter(cfg.output, dem, 1, "float32", -9999.0,
                      _tags(cfg, definition, n, curved, max_distance, made),
                      overview_resampling="average", overwrite=ro.overwrite, fmt=ro.fmt,
                      co=ro.creation_options)


def _in_memory(cfg: SkyviewConfig, plan: Plan, ctx: RunContext, src) -> Made:
    """The result of the DEM read whole, the directions accumulated as they are made."""
    from ..algorithms import horizon as hz
    from ..algorithms.skyview import Sum, floor_deg, inverted
    from ..model.earth import dem_body
    from ..model.geometry import equal_azimuths
    from ..engine.shader import horizon_shader
    from .sky_view_file import provenance

    definition, max_distance, timer = plan.definition, plan.max_distance, ctx.timer
    with timer("read"):
        d = src.read()
    shader = horizon_shader(d.heights, d.grid, ctx.backend, cfg.curvature, cfg.refraction_k,
                            dem_body(d))
    z = d.heights
    if inverted(definition):     # negative openness: the horizons of -z (a copy: -z whole)
        z = np.negative(d.heights)
    gpu_dem = None
    if ctx.backend == "gpu":
        from ..engine.gpu import GpuDem
        gpu_dem = GpuDem(z)
    n = int(cfg.directions)
    azimuths = equal_azimuths(360.0 / n)
    md = max_distance if math.isfinite(max_distance) else None
    pyramid = None if gpu_dem is not None else shader.pyramid(z, True)  # one for all
    floor = floor_deg(definition)
    # the observer at z + H; over the inverted -z (negative openness) at -(z + H)
    lift = -cfg.height_above_ground if inverted(definition) else cfg.height_above_ground

    def angles_of(a):
        rays = shader.rays(d.grid, a, 45.0)
        if gpu_dem is not None:
            return hz.horizon_angles_gpu(gpu_dem, rays, max_distance=md, floor_deg=floor,
                                         lift=lift)
        return hz.horizon_angles(z, rays, pyramid=pyramid, max_distance=md, floor_deg=floor,
                                 lift=lift)

    with timer("compute"):
        s = Sum(definition, d.heights, d.grid)
        for a in azimuths:
            s.add(a, angles_of(a))
        out = s.result()
        if cfg.terrain_configuration:     # the rest of the surface's hemisphere: terrain
            out = (1.0 - out).astype(np.float32)
    st = _Stats()
    st.add(out)
    with timer("write"):
        made = provenance(k=shader.k, body=shader.body, heights=d.heights)
        with _writer(cfg, d, definition, n, bool(shader.curvature), max_distance, made) as w:
            w.write(1, np.where(np.isnan(out), np.float32(-9999.0), out),
                    description=describe(cfg, definition))
    return Made(d, st, {"mode": "in memory", "cells": int(d.heights.size)},
                bool(shader.curvature), (d.heights, d.grid))


def _all_nodata(cfg: SkyviewConfig, plan: Plan, ctx: RunContext, geom) -> Made:
    """A DEM (or ``--context`` tile) whose every cell is nodata: the output all -9999, a
    note."""
    from .context import nodata_note
    with ctx.timer("write"), _writer(cfg, geom, plan.definition, int(cfg.directions), False,
                                     plan.max_distance) as w:
        w.write(1, np.full(geom.shape, -9999.0, np.float32),
                description=describe(cfg, plan.definition))
        w.finish()
    return Made(geom, _Stats(), {"mode": "all nodata", "cells": geom.shape[0] * geom.shape[1]},
                False, None, [nodata_note(geom.path)])


def _in_windows(cfg: SkyviewConfig, plan: Plan, ctx: RunContext, src, area=None) -> Made:
    """The result in windows (``run.horizon_windows``), written window by window or made as
    Dask tasks (--scheduler). ``area``: the tile of ``src`` to make (``--context``; its
    windows read from ``src``)."""
    from ..algorithms.skyview import inverted
    from ..model.geometry import equal_azimuths
    from .horizon import horizon_job, prepare_windows
    from .local import bounded_gdal_cache
    from ..engine.windows import block_stats
    from .horizon_windows import Figures, Product, VrtOutput, region_outputs, run_on_dask
    from .sky_view_file import provenance

    ro = cfg.run
    definition, max_distance, timer = plan.definition, plan.max_distance, ctx.timer
    n = int(cfg.directions)
    azimuths = equal_azimuths(360.0 / n)
    product = Product("skyview", definition=definition, complement=cfg.terrain_configuration)
    st, fig, extra = _Stats(), Figures(), {}
    with bounded_gdal_cache():
        with timer("prepare"):
            bstats = (block_stats(src, preview_side=2048 if ro.preview else None)
                      if area is None else area.block_stats())
        job, shader = horizon_job(src, azimuths, ctx.backend, cfg.curvature, cfg.refraction_k,
                                  "scan", bstats, inverted(definition), 1, max_distance,
                                  cfg.height_above_ground)
        regs, mem = prepare_windows(src, job, plan.limit, plan.wshape, timer, area)
        curved = bool(shader.curvature)
        made = provenance(k=shader.k, body=shader.body, area=area)
        geom = src if area is None else area.tile
        if cfg.scheduler is not None:
            out = VrtOutput(cfg.output, src.shape, src.transform, src.crs,
                            [describe(cfg, definition)],
                            _tags(cfg, definition, n, curved, max_distance, made),
                            resampling="average", overwrite=ro.overwrite, fmt=ro.fmt,
                      co=ro.creation_options)
            with timer("compute"):
                fig, parts, extra = run_on_dask(cfg.scheduler, job, regs, product,
                                                {"result": out}, ro.quiet,
                                                progress_mode=ro.progress,
                                                worker_timeout=ro.worker_timeout)
            for part in parts:
                st.merge(part)
        else:
            from .report import progress_total
            bar = progress_total(len(regs), ro.quiet, "hillshade-rt", "window", ro.progress)
            with _writer(cfg, geom, definition, n, curved, max_distance, made) as w, \
                    src.reader() as rd, bar:
                for reg in regs:
                    out_reg = reg if area is None else area.local(reg)

                    def put(name, band, out, reg=out_reg):
                        st.add(out)
                        with timer("write"):
                            w.write(1, np.where(np.isnan(out), np.float32(-9999.0), out),
                                    description=describe(cfg, definition), window=reg)
                    with timer("compute", exclude="write"):    # put's writes apart
                        fig.add(region_outputs(job, rd, reg, product, put))
                    bar.update(1)
                with timer("write"):
                    w.finish()
    processing = {"mode": "windows" if cfg.scheduler is None else "dask",
                  "cells": geom.shape[0] * geom.shape[1], "memory": mem,
                  "window_shape_requested": list(plan.wshape) if plan.wshape else None,
                  **fig.as_dict(), **extra}
    if area is not None:
        processing["context"] = area.report()
    relief = None
    if ro.preview is not None:     # the every-n-th heights of the statistics pass
        from ..model.geometry import Grid
        n, pv = bstats.stride, bstats.preview
        relief = (pv, Grid(pv.shape[0], pv.shape[1], src.grid.dx[::n] * n,
                           src.grid.dy[::n] * n, src.grid.col_sign, src.grid.row_sign,
                           src.grid.method))
    return Made(geom, st, processing, curved, relief)


def _preview(cfg, z, grid) -> None:
    """--preview: the relief coloured by the product (read back from the output at the
    relief's size; low purple, high yellow, stretched between the 2nd and 98th percentiles)."""
    from ..io import read_decimated, write_png
    from ..pictures.preview import relief_rgb, scaled
    values = read_decimated(cfg.output, z.shape)
    write_png(cfg.run.preview, relief_rgb(z, grid, ramp=scaled(values)), cfg.run.overwrite)


def _report(cfg: SkyviewConfig, plan: Plan, ctx: RunContext, made: Made) -> dict:
    """The run's report (``--report``)."""
    from ..io import input_label
    ro, definition, max_distance = cfg.run, plan.definition, plan.max_distance
    rows, cols = made.geom.shape
    opn = definition.startswith("openness")
    rep = {"input": input_label(made.geom.path), "output": os.path.abspath(cfg.output),
           "shape": [rows, cols], "definition": definition if opn else cfg.definition,
           "openness": cfg.openness, "directions": int(cfg.directions),
           "max_distance": max_distance if math.isfinite(max_distance) else None,
           "height_above_ground_m": float(cfg.height_above_ground),
           "backend": ctx.backend, "threads": ctx.threads, "curvature": made.curved,
           ("openness_deg" if opn else "svf"): made.stats.as_dict(),
           "processing": made.processing,
           "seconds": ctx.phase_seconds(), "version": __version__}
    if ro.preview is not None:
        rep["preview"] = os.path.abspath(ro.preview)
    return rep


def _lines(cfg: SkyviewConfig, plan: Plan, ctx: RunContext, made: Made) -> list:
    """The lines for people at the end: the making's notes, the summary."""
    definition, processing = plan.definition, made.processing
    rows, cols = made.geom.shape
    opn = definition.startswith("openness")
    mean = made.stats.as_dict()["mean"]
    shown = f"{mean:.3f}" if mean is not None else "nan"
    from .horizon_windows import windows_phrase
    where = windows_phrase(processing)
    summary = (f"hillshade-rt: {cfg.output}: {cols}x{rows}, {describe(cfg, definition)}, "
               f"{int(cfg.directions)} directions{where}, mean {shown}{' deg' if opn else ''}; "
               f"compute {ctx.timer.seconds.get('compute', 0.0):.2f} s")
    return [("note", n) for n in made.notes] + [("summary", summary)]
