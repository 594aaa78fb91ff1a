"""The ``shadow`` / ``hillshade`` run: one DEM (or a mosaic of several), one or more suns, one
output per sun (bands of OUTPUT, or files of --output-pattern). In memory when the run fits
--max-memory, else in windows (``run.local.shade_in_windows``), on Dask workers with a
scheduler. The command line and ``api.shade`` both call :func:`shade` with a
:class:`~.config.ShadeConfig`; it returns the report (what ``--report`` writes).

The run's steps, between the preamble and the tail every run shares (``run.runner.RunContext``:
the claims, the threads, the backend; the report written and the lines said): the sun and the
paths checked (:func:`_plan`), the run started (:func:`_start`), the lighting settings built once
(``ShadeConfig.lighting``, passed whole), the DEM opened and in memory vs windows decided
(:func:`_opened`), the outputs planned (:func:`_outputs`), the terrain lit (:func:`_light`), the
shadow polygons (:func:`_vector`, --vector: traced from the raster written, or from a scratch
raster beside them when no OUTPUT is kept: :func:`_scratch`), the preview (:func:`_preview`),
the report (:func:`_report`), the STAC item (:func:`_stac_item`), then ``RunContext.finish``
with the lines (:func:`_lines`).
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass

from ..errors import HillshadeError, UsageProblem
from .config import ShadeConfig, inputs_and_output, parse_window_size


@dataclass(kw_only=True)
class ShadePlan:
    """What a ``shade`` run has settled before it lights anything.

    Attributes
    ----------
    req : model.sun.SunRequest
        The sun(s) asked for (a STAC item's sun turned to grid north once the DEM is open).
    scene : object or None
        The STAC item the sun came from (``run.stac.sun_from_item``; --sun-from-stac).
    inputs : list of str
        The DEM(s): one, or the tiles of a mosaic.
    output : str or None
        OUTPUT (None with --output-pattern).
    window_shape : tuple or None
        --window-size as (rows, cols).
    limit : int
        --max-memory, bytes.
    pattern : run.outputs.OutputPattern or None
        --output-pattern.
    per_cell : int
        Bytes a lit cell needs (``engine.windows.bytes_per_cell``).
    windowed : bool
        Lit in windows (else in memory).
    area : run.context.Area or None
        The tile of a ``--context`` run.
    scratch : str or None
        The raster written only to be polygonized (--vector without OUTPUT or a pattern): a
        temporary file beside the polygons, removed at the end.
    vector : dict or None
        The polygons written (--vector): the report's ``vector`` (:func:`_vector`).
    """

    req: object
    scene: object
    inputs: list
    output: str | None
    window_shape: tuple | None
    limit: int
    pattern: object = None
    per_cell: int = 0
    windowed: bool = False
    area: object = None
    scratch: str | None = None
    vector: dict | None = None

    @property
    def shown(self) -> str | None:
        """The outputs as the user named them (OUTPUT, or the pattern; None: polygons only)."""
        return self.output or (self.pattern.pattern if self.pattern is not None else None)


def shade(cfg: ShadeConfig) -> dict:
    """Run ``cfg``; returns the report. Bad input raises ``HillshadeError`` (``UsageProblem``
    for a bad combination of options) before anything is written."""
    from ..engine.windows import bytes_per_cell

    cfg.check()
    plan = _plan(cfg)
    ctx = _start(cfg, plan)
    lighting = cfg.lighting(ctx.backend)
    plan.per_cell = bytes_per_cell(lighting.algorithm, cfg.kind, lighting.soft,
                                   lighting.self_shadow)
    with _opened(cfg, ctx, plan) as src, _scratch(cfg, plan):
        out = _outputs(cfg, ctx, plan, lighting, src)
        ctx.compile_note(lighting.algorithm, lighting.self_shadow or cfg.kind != "shadow")
        run, empty = _light(cfg, ctx, plan, lighting, src, out)
        _vector(cfg, ctx, plan, run, out)
        _preview(ctx, run)
        rep = _report(cfg, ctx, plan, lighting, run)
        _stac_item(cfg, ctx, plan, run, rep)
        return ctx.finish(rep, _lines(cfg, plan, rep, run, empty))


def _plan(cfg: ShadeConfig) -> ShadePlan:
    """The sun and the paths checked (a STAC item's sun read), the window size and the memory
    limit parsed, ``--context``'s combinations refused: before any path is claimed."""
    from ..io.write import reset
    from ..engine.windows import default_max_memory, parse_size
    from ..model.sun import SunRequest
    from .stac import sun_from_item

    ro = cfg.run
    # --sun-from-stac: the item's sun (a bad item fails the run, exit status 1)
    sun, scene = sun_from_item(cfg.sun, ro.quiet, ro.say)
    try:     # a bad sun is the command line's fault (exit status 2)
        req = SunRequest.from_options(**sun, default_sun=cfg.default_sun)
    except UsageProblem:
        raise
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    inputs, output = inputs_and_output(cfg.files, cfg.output, cfg.output_pattern,
                                       optional=cfg.vector is not None)
    if output is None and cfg.output_pattern is None:     # --vector alone: no raster kept
        for flag, on in (("-f/--format", ro.fmt is not None), ("--cog", cfg.cog),
                         ("--co", bool(ro.creation_options)),
                         ("--stac-item", cfg.stac_item is not None)):
            if on:
                raise UsageProblem(f"{flag} goes with a raster OUTPUT (--vector alone keeps "
                                   "no raster): give OUTPUT too")
    reset()
    wshape = parse_window_size(cfg.window_size)
    try:
        limit = (parse_size(cfg.max_memory) if cfg.max_memory is not None
                 else default_max_memory())
    except HillshadeError as exc:
        raise UsageProblem(f"--max-memory: {exc}") from None
    cfg.read.check_context(inputs, **{"--scheduler": cfg.scheduler is not None,
                                      "--preview": ro.preview is not None})
    return ShadePlan(req=req, scene=scene, inputs=inputs, output=output, window_shape=wshape,
                     limit=limit)


def _start(cfg: ShadeConfig, plan: ShadePlan):
    """The run started (``RunContext.start``): every path it writes claimed (OUTPUT, the STAC
    item, the report, the preview: no input, no two the same), the threads set, the backend
    chosen; then the pattern parsed. The compile note waits until the outputs are checked."""
    from .outputs import OutputPattern
    from .runner import RunContext
    from .stac import check_item_output

    ro = cfg.run
    item_in = [cfg.sun["sun_from_stac"]] if cfg.sun.get("sun_from_stac") else []
    reads = plan.inputs + item_in + cfg.read.inputs()
    outputs = [(plan.output, "OUTPUT"),     # the STAC item's checks, then its claim
               lambda claims: check_item_output(cfg.stac_item, plan.output,
                                                cfg.output_pattern, claims),
               (cfg.vector, "--vector")]
    ctx = RunContext.start(ro, inputs=reads, outputs=outputs, algorithm=cfg.algorithm,
                           options=cfg.options, note=False)
    if cfg.output_pattern is not None:
        plan.pattern = OutputPattern(cfg.output_pattern)
    return ctx


@contextlib.contextmanager
def _opened(cfg: ShadeConfig, ctx, plan: ShadePlan):
    """The DEM opened (not read) once, for its size and then its values; whether it is lit in
    memory or in windows decided (``plan.windowed``). A ``--context`` tile: the context opened
    with it (``plan.area``), lit in windows, in the context. Yields what is lit."""
    from .local import needs_windows

    if cfg.read.context is not None:    # a tile of the context: its windows, in the context
        with ctx.timer("read"):
            area = cfg.read.open_area(plan.inputs)
        with area:
            plan.windowed, plan.area = True, area
            yield area.source
        return
    forced = cfg.scheduler is not None or plan.window_shape is not None or len(plan.inputs) > 1
    with ctx.timer("read"):
        src = cfg.read.open(plan.inputs, windows=forced)
    with src:
        plan.windowed = forced or needs_windows(src, plan.limit, plan.per_cell)
        yield src


def _outputs(cfg: ShadeConfig, ctx, plan: ShadePlan, lighting, src):
    """The outputs planned (``run.outputs.Outputs``: the product, the files, their tags) and
    checked against their format before any work; a STAC item's sun turned to grid north."""
    from ..io import check_output_format, output_driver
    from ..engine.products import product
    from .outputs import Outputs

    ro = cfg.run
    prod = product(cfg.kind, lighting.soft)
    if plan.scratch is not None:     # a GeoTIFF of the tool's defaults, over the empty scratch
        out = Outputs(prod, lighting.algorithm, plan.scratch, None, ctx.claims, False,
                      ro.preview is not None, lighting.ambient)
        out.overwrite = True
    else:
        out = Outputs(prod, lighting.algorithm, plan.output, plan.pattern, ctx.claims, cfg.cog,
                      ro.preview is not None, lighting.ambient, ro.fmt, ro.creation_options)
    if lighting.lift:     # the observer's height, in every output's tags
        out.base_tags["HEIGHT_ABOVE_GROUND_M"] = f"{lighting.lift:g}"
    if plan.scene is not None:     # the sun of a STAC item: which item, in every output's tags
        from .stac import note_if_apart, scene_tags, to_grid_north
        plan.req = to_grid_north(plan.req, plan.scene, src)      # its azimuth from true north
        out.base_tags.update(scene_tags(plan.scene))
        if not ro.quiet:
            note_if_apart(plan.scene, src, ro.say)
    # Dask's parts are put together by GDAL (no 16-bit encoding of soft shadows on the way)
    out.via_vrt = cfg.scheduler is not None
    out.command = cfg.command
    # a series into OUTPUT.nc / OUTPUT.zarr: one CF time cube (io.cube), not GDAL's bands
    cube = out.use_cube(plan.req.from_time, cfg.cog, cfg.stac_item)
    if plan.output is not None and not cube:   # the format can hold the product (before any work)
        check_output_format(plan.output, output_driver(plan.output, ro.fmt, cfg.cog), prod.dtype,
                            len(plan.req.times) if plan.req.from_time else 1,
                            out.continuous and not out.via_vrt, ro.creation_options,
                            out.resampling)
    return out


def _light(cfg: ShadeConfig, ctx, plan: ShadePlan, lighting, src, out):
    """The terrain lit and the outputs written: in memory or in windows (``run.local``), or
    all nodata when every cell is. Returns (``local.ShadeResult``, the path of the all-nodata
    DEM or None)."""
    from ..errors import AllNodata
    from .local import all_nodata, bounded_gdal_cache, shade_in_memory, shade_in_windows

    ro, area = cfg.run, plan.area
    empty = None
    try:
        with (bounded_gdal_cache() if plan.windowed else contextlib.nullcontext()):
            try:
                if area is not None:
                    area.check_valid()
                run = (shade_in_windows if plan.windowed else shade_in_memory)(
                    plan.inputs, src, cfg.scale, plan.req, out, ctx.timer, lighting, ro.quiet,
                    limit=plan.limit, window_shape=plan.window_shape, scheduler=cfg.scheduler,
                    per_cell=plan.per_cell, progress_mode=ro.progress,
                    worker_timeout=ro.worker_timeout,
                    **({} if area is None else {"area": area}))
            except AllNodata:      # (raised before any output is opened): all nodata then
                empty = (src if area is None else area.tile).path
                run = all_nodata(plan.inputs, src, plan.req, out, ctx.timer, area)
    finally:
        out.cleanup()
    return run, empty


@contextlib.contextmanager
def _scratch(cfg: ShadeConfig, plan: ShadePlan):
    """--vector without OUTPUT or --output-pattern: the raster the polygons are traced from, a
    temporary GeoTIFF beside them (``plan.scratch``; GDAL reads it back block by block, so a
    DEM larger than memory is polygonized too), removed when the run ends, whole or not."""
    if cfg.vector is None or plan.output is not None or plan.pattern is not None:
        yield
        return
    from ..io.write import completed, temp_beside
    plan.scratch = temp_beside(cfg.vector, ".scratch.tif")
    try:
        yield
    finally:
        for p in (plan.scratch, plan.scratch + ".aux.xml", plan.scratch + ".ovr"):
            with contextlib.suppress(OSError):
                os.remove(p)
        while plan.scratch in completed:        # not an output the run tells about
            completed.remove(plan.scratch)


def _rasters_of(plan: ShadePlan, out, i: int) -> list:
    """(path, band) of sun ``i``'s product as written: a band of OUTPUT (or of the scratch
    raster), its file of the pattern, or its files of the pattern's tiles."""
    single = plan.output or plan.scratch
    if single is not None:
        return [(single, i + 1)]
    if out.tile_paths is not None:
        return [(p, 1) for p in out.tile_paths[i]]
    return [(out.paths[i], 1)]


def _vector(cfg: ShadeConfig, ctx, plan: ShadePlan, run, out) -> None:
    """--vector: the polygons of every sun's shadow (the mask's 1; classes 1 and 2, each its
    ``shadow_class``) traced from the rasters written (``io.vector.write_polygons``), one layer
    in the DEM's CRS; each polygon's ``azimuth``, ``elevation`` (degrees; the grid azimuth of
    the raster's SUN_AZIMUTH tag), with a sun from a time its ``time`` (ISO) and
    ``true_azimuth``, in a series its ``index`` (0-based: band index + 1 of OUTPUT, the
    report's ``times[index]``). The count and area go to ``plan.vector`` (the report's)."""
    if cfg.vector is None:
        return
    from ..io.vector import PolygonSource, vector_driver, write_polygons
    from ..model.times import iso

    suns = run.suns
    timed, series = plan.req.from_time, len(suns) > 1
    fields = {"azimuth": "float", "elevation": "float"}
    if timed:
        fields.update(time="str", true_azimuth="float")
    if series:
        fields["index"] = "int"
    if cfg.kind == "classes":
        fields["shadow_class"] = "int"
        values = {1: {"shadow_class": 1}, 2: {"shadow_class": 2}}
    else:
        values = {1: {}}
    sources, owner = [], []
    for i, sun in enumerate(suns):
        attrs = {"azimuth": float(sun.azimuth), "elevation": float(sun.elevation)}
        if timed:
            attrs.update(time=iso(sun.time), true_azimuth=sun.true_azimuth)
        if series:
            attrs["index"] = i
        for path, band in _rasters_of(plan, out, i):
            sources.append(PolygonSource(path=path, band=band, attributes=attrs,
                                         values=values))
            owner.append(i)
    layer = os.path.splitext(os.path.basename(cfg.vector))[0] or "shadow"
    with ctx.timer("write"):
        stats = write_polygons(cfg.vector, sources, fields, overwrite=cfg.run.overwrite,
                               connectivity=cfg.vector_connectivity, layer=layer)
    per_sun = []
    for i in range(len(suns)):
        mine = [k for k, o in enumerate(owner) if o == i]
        m2 = [stats.area_m2[k] for k in mine]
        per_sun.append({"index": i, "polygons": int(sum(stats.polygons[k] for k in mine)),
                        "area": float(sum(stats.area[k] for k in mine)),
                        "area_m2": None if any(a is None for a in m2) else float(sum(m2))})
    plan.vector = {"path": os.path.abspath(cfg.vector), "shown": cfg.vector,
                   "format": vector_driver(cfg.vector), "layer": layer,
                   "connectivity": cfg.vector_connectivity, "fields": list(fields),
                   "polygons": stats.total_polygons, "area": float(sum(stats.area)),
                   "area_m2": stats.total_area_m2, "times": per_sun if series else None}


def _preview(ctx, run) -> None:
    """--preview: the relief lit by the first day sun (the first sun at night), the product's
    shade over it."""
    ro = ctx.ro
    if ro.preview is None:
        return
    from ..io import write_png
    with ctx.timer("write"):
        day = [s for s in run.suns if not s.night]
        s0 = day[0] if day else run.suns[0]
        write_png(ro.preview, run.relief(s0.azimuth, s0.elevation), ro.overwrite)


def _report(cfg: ShadeConfig, ctx, plan: ShadePlan, lighting, run) -> dict:
    """The run's report (``run.report.build_report`` and the lighting run's own keys)."""
    from ..io import input_label
    from ..engine.products import product
    from .local import mean_stats
    from .report import build_report

    ro = cfg.run
    prod = product(cfg.kind, lighting.soft)
    suns, records = run.suns, run.records
    first = suns[0]
    rep = build_report(dem=run.dem, output=plan.shown, azimuth=first.azimuth,
                       elevation=first.elevation, algorithm=lighting.algorithm,
                       backend=ctx.backend, backend_requested=ro.backend, threads=ctx.threads,
                       seconds=ctx.seconds(), stats=mean_stats(records, run.stats),
                       height_range=run.zrange, options=cfg.options,
                       algorithm_stats=run.algo_stats, gpu=run.gpu)
    rep["sun"] = records[0] if len(records) == 1 else None
    rep["sun_source"] = "time" if plan.req.from_time else "given"
    rep["sun_from_stac"] = plan.scene.as_dict() if plan.scene is not None else None
    if run.sun_info is not None:
        rep.update(run.sun_info)
    if len(records) > 1 or plan.req.from_time:
        rep["times"] = records
    rep["night_count"] = sum(1 for s in suns if s.night)
    rep["product"] = {"kind": cfg.kind, "soft": lighting.soft,
                      "self_shadow": lighting.self_shadow, "dtype": prod.dtype,
                      "nodata": prod.nodata, "bands": len(suns) if plan.output else 1,
                      "cog": cfg.cog}
    if cfg.kind == "hillshade":
        rep["product"].update(ambient=lighting.ambient, scale=cfg.scale)
    rep["curvature"] = run.curvature
    rep["height_above_ground_m"] = lighting.lift
    rep["inputs"] = [input_label(p) for p in plan.inputs]
    rep["processing"] = run.processing
    if ro.preview is not None:
        rep["preview"] = os.path.abspath(ro.preview)
    if plan.vector is not None:
        rep["vector"] = {k: v for k, v in plan.vector.items() if k != "shown"}
    return rep


def _stac_item(cfg: ShadeConfig, ctx, plan: ShadePlan, run, rep: dict) -> None:
    """--stac-item: written once the raster is whole (its checksum), before the report."""
    if cfg.stac_item is None:
        return
    from .stac import write_item
    with ctx.timer("write"):
        write_item(cfg.stac_item, plan.output, run.suns, plan.scene, kind=cfg.kind,
                   algorithm=cfg.algorithm, command=cfg.command, overwrite=cfg.run.overwrite)
    rep["stac_item"] = os.path.abspath(cfg.stac_item)


def _lines(cfg: ShadeConfig, plan: ShadePlan, rep: dict, run, empty) -> list:
    """What the run says after its report, in order: the all-nodata note (with ``-q`` the
    report and the EMPTY tag keep it), the summary (the outputs named as the user gave them, as
    every command does: a pattern's files), the algorithm's note, the suns below the horizon."""
    from .context import nodata_note
    from .notes import note_to_show
    from .report import shown_paths, summary_line

    if cfg.run.quiet:
        return []
    lines = []
    if empty is not None:
        lines.append(("note", nodata_note(empty)))
    if plan.output is not None:
        shown = plan.output
    elif plan.pattern is not None:
        shown = shown_paths(plan.pattern.planned) or plan.pattern.pattern
    else:                           # polygons only
        shown = cfg.vector
    vector = None if plan.vector is None else dict(
        plan.vector, shown=None if shown == cfg.vector else cfg.vector)
    lines.append(("summary", summary_line(rep, shown, vector)))
    lines.append(("note", note_to_show(run.algo_stats, cfg.algorithm, cfg.options,
                                       cfg.algorithm_explicit)))
    if rep["night_count"]:
        lines.append(("note", f"the sun is below the horizon at {rep['night_count']} of "
                              f"{len(run.suns)} time(s): all shadow there"))
    return lines
