"""The ``sun-hours`` run: hours of direct sun per cell of a DEM over a day (or a range of days),
like WhiteboxTools' TimeInDaylight or GRASS r.sun's insolation time: the sun every step, each lit
sample counting for the part of its interval with the sun's centre up at the DEM's place
(``solar.daylight_samples``: never more than the day length there). Returns the report."""

from __future__ import annotations

import os

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import SunHoursConfig, set_threads


def sun_hours(cfg: SunHoursConfig) -> dict:
    import numba
    import numpy as np

    from ..engine.shader import Shader, render

    from ..model.earth import dem_body
    from ..io import (check_output_format, input_label, output_driver, write_json, write_png,
                      write_raster)
    from ..pictures.preview import relief_rgb
    from ..engine.shader import choose_backend
    from ..model.solar import SUN_RADIUS_DEG, daylight_samples
    from ..model.sun import SunRequest
    from ..model.times import parse_date, parse_step
    from ..io.write import Claims
    from ..errors import AllNodata
    from .context import nodata_note
    from .notes import compile_note
    from .report import Timer, progress

    cfg.check()
    ro, output, soft, self_shadow = cfg.run, cfg.output, cfg.soft, cfg.self_shadow
    algorithm, step = cfg.algorithm, cfg.step
    lift = float(cfg.height_above_ground)
    timer = Timer()
    claims = Claims([cfg.dem] + cfg.read.inputs(), ro.overwrite)
    for path, what in ((output, "OUTPUT"), (ro.report_path, "--report"),
                       (ro.preview, "--preview")):
        if path is not None:
            claims.claim(path, what)
    check_output_format(output, output_driver(output, ro.fmt), "float32", 1, False,
                        ro.creation_options)
    try:    # the command line alone decides these: a bad one is a usage error (exit 2)
        first = parse_date(cfg.date, "--date")
        last = parse_date(cfg.end_date, "--end-date") if cfg.end_date is not None else first
        parse_step(step)
        req = SunRequest.at_place([], **cfg.place)
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    if last < first:
        raise UsageProblem("--end-date is before --date")
    set_threads(ro)
    ran_on = choose_backend(ro.backend, algorithm, {})
    if not ro.quiet:
        note = compile_note(algorithm, ran_on, self_shadow)
        if note:
            ro.say("compile", note)
    cfg.read.check_context(cfg.dem, **{"--preview": ro.preview is not None})

    def samples(d):
        """(site, suns, sun_info, the suns with some light and their weights) over ``d``."""
        site = req.site(d, "sun-hours computes the Earth's sun only (light a DEM of another "
                           "body with shadow or hillshade, which take the sun's direction)")
        try:
            req.times, weights = daylight_samples(first, last, step, req.tz, site,
                                                  req.atmosphere)
        except HillshadeError as exc:   # too many samples for the dates and the step
            raise UsageProblem(str(exc)) from None
        suns, sun_info = req.suns(d, site)

        def dark(s):
            top = max([r.elevation for r in s.tiles] if s.tiles else [s.elevation])
            return top + (SUN_RADIUS_DEG if soft else 0.0) <= 0.0
        return site, suns, sun_info, [(s, w) for s, w in zip(suns, weights)
                                      if w > 0 and not dark(s)]

    algo_stats: dict = {}
    empty = None
    if cfg.read.context is not None:
        with timer("read"):
            area = cfg.read.open_area(cfg.dem)
        with area:
            d = area.tile          # the output's grid; the heights are the context's
            try:
                area.check_valid()
            except AllNodata:
                empty = d.path
            site, suns, sun_info, work = samples(area.source)
            if empty is None:
                hours, zrange, curv = _in_context(cfg, area, work, ran_on, req, timer,
                                                  algo_stats)
    else:
        with timer("read"):
            try:
                d = cfg.read.read(cfg.dem)
            except AllNodata:
                d = cfg.read.open(cfg.dem)
                d.close()
                empty = d.path
        with timer("prepare"):
            site, suns, sun_info, work = samples(d)
            if empty is None:
                zmin, zmax = zrange = d.height_range()
                shader = Shader(d.heights, d.grid, algorithm, {}, ran_on,
                                "auto" if cfg.curvature is None else cfg.curvature,
                                cfg.refraction_k, dem_body(d, req.lat), (zmin, zmax),
                                survey=d.survey(), lift=lift)
                if work:
                    shader.warm_up(work[0][0].azimuth, max(work[0][0].elevation, 1.0),
                                   soft=soft, incidence=self_shadow,
                                   field=any(s.fieldwise for s, _ in work))
                hours = np.where(np.isnan(d.heights), np.float32(np.nan), np.float32(0.0))
        if empty is None:
            with timer("compute"):
                for s, w in progress(work, ro.quiet, "hillshade-rt sun-hours", unit="sun",
                                         mode=ro.progress):
                    hours += np.float32(w) * render(shader, s, "sun", soft=soft,
                                                    self_shadow=self_shadow, stats=algo_stats)
            curv = shader.report()
    if empty is not None:
        hours, curv = np.full(d.shape, np.nan, np.float32), None
    days = (last - first).days + 1
    tags = {"HILLSHADE_RT_VERSION": __version__, "UNITS": "hours of direct sun",
            "DATE_FIRST": first.isoformat(), "DATE_LAST": last.isoformat(), "DAYS": days,
            "STEP": step, "ALGORITHM": algorithm, "SOFT": soft, "SELF_SHADOW": self_shadow,
            "HEIGHT_ABOVE_GROUND_M": lift,
            "DAY": f"midnight to midnight, {req.tz.key}" if req.tz is not None
            else f"local mean solar time at longitude {site.lon:.4f}"}
    with timer("write"):
        write_raster(output, np.where(np.isnan(hours), np.float32(-9999.0), hours), d,
                     nodata=-9999.0, description="hours of direct sun", tags=tags,
                     overwrite=ro.overwrite, fmt=ro.fmt, co=ro.creation_options)
        if ro.preview is not None and empty is None:
            top = float(np.nanmax(hours)) if np.isfinite(hours).any() else 0.0
            write_png(ro.preview, relief_rgb(d.heights, d.grid,
                                             warm=hours / top if top > 0 else np.zeros_like(hours)),
                      ro.overwrite)
    valid = hours[~np.isnan(hours)]
    rep = {"input": input_label(d.path), "output": os.path.abspath(output),
           "shape": list(d.shape), "algorithm": algorithm, "backend": ran_on,
           "dates": [first.isoformat(), last.isoformat()], "days": days, "step": step,
           "samples": len(suns), "samples_with_sun": len(work), "day_definition": tags["DAY"],
           "soft": soft, "self_shadow": self_shadow, "height_above_ground_m": lift,
           "hours": {"min": float(valid.min()) if valid.size else None,
                     "mean": float(valid.mean()) if valid.size else None,
                     "max": float(valid.max()) if valid.size else None},
           "curvature": curv, "algorithm_stats": algo_stats,
           "seconds": dict(timer.seconds, total=timer.total()), "version": __version__}
    rep.update(sun_info or {})
    if cfg.read.context is not None:
        rep["context"] = area.report()
    if ro.report_path is not None:
        write_json(ro.report_path, rep, ro.overwrite)
    if empty is not None and not ro.quiet:
        ro.say("note", nodata_note(empty))
    elif not ro.quiet:
        h = rep["hours"]
        ro.say("summary", f"hillshade-rt: {output}: {d.shape[1]}x{d.shape[0]}, {days} day(s) from "
                          f"{first.isoformat()}, {len(work)} of {len(suns)} samples with the sun "
                          f"up; sun hours {h['min']:.2f} .. {h['max']:.2f} (mean "
                          f"{h['mean']:.2f}); compute {timer.seconds['compute']:.2f} s")
    return rep


def _in_context(cfg, area, work, ran_on, req, timer, algo_stats):
    """Sun hours of the tile of ``area`` (``--context``): each sun's windows of the context
    (``engine.windows.WindowLighting``, product "sun"), cut to the tile, added in the order of the suns as a
    run in memory adds them (the same float32 sums). (hours, height range, curvature)."""
    import math

    import numpy as np

    from ..model.earth import curvature_report, dem_body
    from .local import bounded_gdal_cache
    from ..engine.windows import (
        WindowLighting, WindowCache, bytes_per_cell, default_max_memory, window_budget
    )
    from .report import progress
    src = area.source
    lift = float(cfg.height_above_ground)
    r0, r1, c0, c1 = area.bounds
    with bounded_gdal_cache():
        with timer("prepare"):
            bstats = area.block_stats()     # (the context's, kept between runs)
            rows, cols = src.shape
            dx, dy = src.grid.centre_spacing()
            job = WindowLighting(src, cfg.lighting(ran_on), dem_body(src, req.lat),
                                 (bstats.zmin, bstats.zmax), math.hypot(cols * dx, rows * dy),
                                 "sun")
            budget = window_budget(default_max_memory(),
                                   bytes_per_cell(cfg.algorithm, "sun", cfg.soft,
                                                  cfg.self_shadow))[0]
            if work:
                job.warm_up(work[0][0])
        with src.reader() as rd:
            z = np.empty((r1 - r0, c1 - c0), np.float32)
            rd.read(area.bounds, z)
            hours = np.where(np.isnan(z), np.float32(np.nan), np.float32(0.0))
            del z
            cache, used = WindowCache(rd), set()
            with timer("compute"):
                for s, w in progress(work, cfg.run.quiet, "hillshade-rt sun-hours",
                                         unit="sun", mode=cfg.run.progress):
                    pieces = job.pieces(s, bstats, budget, area=area.bounds)
                    carry = job.carrier([pieces])
                    for p in pieces:
                        arr = job.light(cache.get(p.window), p, algo_stats, used, carry)
                        a0, a1, b0, b1 = area.local(p.region)
                        hours[a0:a1, b0:b1] += np.float32(w) * arr
    return hours, (bstats.zmin, bstats.zmax), curvature_report(job.curvature, used, job.body,
                                                               job.k)
