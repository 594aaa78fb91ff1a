"""The ``shadow`` / ``hillshade`` run: one DEM (or a mosaic of several), one or more suns, one
output per sun (bands of OUTPUT, or files of --output-pattern). In memory when the run fits
--max-memory, else in windows (``run.local.shade_in_windows``), on Dask workers with a scheduler. The command
line and ``api.shade`` both call :func:`shade` with a :class:`~.config.ShadeConfig`; it returns the
report (what ``--report`` writes).
"""

from __future__ import annotations

import contextlib
import os

from ..errors import HillshadeError, UsageProblem
from .config import ShadeConfig, inputs_and_output, parse_window_size, set_threads

def shade(cfg: ShadeConfig) -> dict:
    """Run ``cfg``; returns the report. Bad input raises ``HillshadeError`` (``UsageProblem``
    for a bad combination of options) before anything is written."""
    import numba

    from ..io.write import Claims, reset
    from ..engine.shader import choose_backend
    from ..model.sun import SunRequest
    from ..engine.windows import bytes_per_cell, default_max_memory, parse_size
    from .local import needs_windows
    from .outputs import OutputPattern
    from .report import Timer
    from .stac import check_item_output, sun_from_item

    cfg.check()
    kind, soft, algorithm, options = cfg.kind, cfg.soft, cfg.algorithm, cfg.options
    ro = cfg.run
    timer = Timer()
    # --sun-from-stac: the item's sun (a bad item fails the run, exit status 1)
    sun, scene = sun_from_item(cfg.sun, ro.quiet, ro.say)
    try:     # a bad sun is the command line's fault (exit status 2)
        req = SunRequest.from_options(**sun, default_sun=cfg.default_sun)
    except UsageProblem:
        raise
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    inputs, output = inputs_and_output(cfg.files, cfg.output, cfg.output_pattern)
    pattern = cfg.output_pattern
    reset()
    wshape = parse_window_size(cfg.window_size)
    try:
        limit = (parse_size(cfg.max_memory) if cfg.max_memory is not None
                 else default_max_memory())
    except HillshadeError as exc:
        raise UsageProblem(f"--max-memory: {exc}") from None
    item_in = [cfg.sun["sun_from_stac"]] if cfg.sun.get("sun_from_stac") else []
    cfg.read.check_context(inputs, **{"--scheduler": cfg.scheduler is not None,
                                      "--preview": ro.preview is not None})
    claims = Claims(inputs + item_in + cfg.read.inputs(), ro.overwrite)   # every path written:
    if output is not None:                            # no input, no two the same
        claims.claim(output, "OUTPUT")
    check_item_output(cfg.stac_item, output, pattern, claims)
    for extra, what in ((ro.report_path, "--report"), (ro.preview, "--preview")):
        if extra is not None:
            claims.claim(extra, what)
    if pattern is not None:
        pattern = OutputPattern(pattern)
    set_threads(ro)
    ran_on = choose_backend(ro.backend, algorithm, options)
    per_cell = bytes_per_cell(algorithm, kind, soft, cfg.self_shadow)
    if cfg.read.context is not None:    # a tile of the context: its windows, in the context
        with timer("read"):
            area = cfg.read.open_area(inputs)
        with area:
            return _shade(cfg, area.source, True, inputs, output, req, pattern, wshape, limit,
                          claims, ran_on, per_cell, timer, scene, area)
    forced = cfg.scheduler is not None or wshape is not None or len(inputs) > 1
    with timer("read"):     # opened (not read) once, for its size and then its values
        src = cfg.read.open(inputs, windows=forced)
    with src:
        return _shade(cfg, src, forced or needs_windows(src, limit, per_cell), inputs, output,
                      req, pattern, wshape, limit, claims, ran_on, per_cell, timer, scene)


def _shade(cfg, src, windowed, inputs, output, req, pattern, wshape, limit, claims, ran_on,
           per_cell, timer, scene=None, area=None):
    """``shade`` once the DEM is open: in memory or in windows, then the report. ``area``: the
    tile of ``src`` a ``--context`` run lights (``run.context.Area``)."""
    import numba

    from ..io import check_output_format, input_label, output_driver, write_json, write_png
    from ..engine.products import product
    from ..errors import AllNodata
    from .context import nodata_note
    from .local import (all_nodata, bounded_gdal_cache, mean_stats, shade_in_memory,
                        shade_in_windows)
    from .notes import compile_note, note_to_show
    from .outputs import Outputs
    from .report import build_report, shown_paths, summary_line

    kind, soft, algorithm, options = cfg.kind, cfg.soft, cfg.algorithm, cfg.options
    ro = cfg.run
    prod = product(kind, soft)
    dtype, nodata = prod.dtype, prod.nodata
    out = Outputs(prod, algorithm, output, pattern, claims, cfg.cog, ro.preview is not None,
                  cfg.ambient, ro.fmt, ro.creation_options)
    if cfg.height_above_ground:     # the observer's height, in every output's tags
        out.base_tags["HEIGHT_ABOVE_GROUND_M"] = f"{float(cfg.height_above_ground):g}"
    if scene is not None:           # the sun of a STAC item: which item, in every output's tags
        from .stac import note_if_apart, scene_tags, to_grid_north
        req = to_grid_north(req, scene, src)      # its azimuth from true north
        out.base_tags.update(scene_tags(scene))
        if not ro.quiet:
            note_if_apart(scene, src, ro.say)
    # Dask's parts are put together by GDAL (no 16-bit encoding of soft shadows on the way)
    out.via_vrt = cfg.scheduler is not None
    if output is not None:   # the format can hold the product (before any work)
        check_output_format(output, output_driver(output, ro.fmt, cfg.cog), dtype,
                            len(req.times) if req.from_time else 1,
                            out.continuous and not out.via_vrt, ro.creation_options,
                            out.resampling)
    if not ro.quiet:
        note = compile_note(algorithm, ran_on, cfg.self_shadow or kind != "shadow")
        if note:
            ro.say("compile", note)
    empty = None
    try:
        with (bounded_gdal_cache() if windowed else contextlib.nullcontext()):
            try:
                if area is not None:
                    area.check_valid()
                run = (shade_in_windows if windowed else shade_in_memory)(
                    inputs, src, cfg.scale, req, out, timer, algorithm, options, ran_on,
                    cfg.curvature, cfg.refraction_k, soft, cfg.self_shadow, cfg.ambient,
                    ro.quiet, limit=limit, window_shape=wshape, scheduler=cfg.scheduler,
                    per_cell=per_cell, lift=cfg.height_above_ground, progress_mode=ro.progress,
                    worker_timeout=ro.worker_timeout,
                    **({} if area is None else {"area": area}))
            except AllNodata:      # (raised before any output is opened): all nodata then
                empty = (src if area is None else area.tile).path
                run = all_nodata(inputs, src, req, out, timer, area)
    finally:
        out.cleanup()
    d, suns, records = run["dem"], run["suns"], run["records"]
    if ro.preview is not None:
        with timer("write"):
            day = [s for s in suns if not s.night]
            s0 = day[0] if day else suns[0]
            write_png(ro.preview, run["relief"](s0.azimuth, s0.elevation), ro.overwrite)
    seconds = dict(timer.seconds, total=timer.total())
    first = suns[0]
    rep = build_report(dem=d, output=output or pattern.pattern, azimuth=first.azimuth,
                       elevation=first.elevation, algorithm=algorithm, backend=ran_on,
                       backend_requested=ro.backend, threads=numba.get_num_threads(),
                       seconds=seconds, stats=mean_stats(records, run["stats"]),
                       height_range=run["zrange"], options=options,
                       algorithm_stats=run["algo_stats"], gpu=run.get("gpu"))
    rep["sun"] = records[0] if len(records) == 1 else None
    rep["sun_source"] = "time" if req.from_time else "given"
    rep["sun_from_stac"] = scene.as_dict() if scene is not None else None
    if run["sun_info"] is not None:
        rep.update(run["sun_info"])
    if len(records) > 1 or req.from_time:
        rep["times"] = records
    rep["night_count"] = sum(1 for s in suns if s.night)
    rep["product"] = {"kind": kind, "soft": soft, "self_shadow": cfg.self_shadow,
                      "dtype": dtype, "nodata": nodata, "bands": len(suns) if output else 1,
                      "cog": cfg.cog}
    if kind == "hillshade":
        rep["product"].update(ambient=cfg.ambient, scale=cfg.scale)
    rep["curvature"] = run["curvature"]
    rep["height_above_ground_m"] = float(cfg.height_above_ground)
    rep["inputs"] = [input_label(p) for p in inputs]
    rep["processing"] = run["processing"]
    if ro.preview is not None:
        rep["preview"] = os.path.abspath(ro.preview)
    if cfg.stac_item is not None:   # once the raster is whole (its checksum), before the report
        from .stac import write_item
        with timer("write"):
            write_item(cfg.stac_item, output, suns, scene, kind=kind, algorithm=algorithm,
                       command=cfg.command, overwrite=ro.overwrite)
        rep["stac_item"] = os.path.abspath(cfg.stac_item)
    if ro.report_path is not None:
        write_json(ro.report_path, rep, ro.overwrite)
    if empty is not None and not ro.quiet:     # (-q: the report and the EMPTY tag keep it)
        ro.say("note", nodata_note(empty))
    if not ro.quiet:
        # the outputs named as the user gave them (as every command does), a pattern's files
        ro.say("summary", summary_line(rep, output if output is not None
                                       else shown_paths(pattern.planned) or pattern.pattern))
        note = note_to_show(run["algo_stats"], algorithm, options, cfg.algorithm_explicit)
        if note:
            ro.say("note", note)
        if rep["night_count"]:
            ro.say("note", f"the sun is below the horizon at {rep['night_count']} of "
                           f"{len(suns)} time(s): all shadow there")
    return rep
