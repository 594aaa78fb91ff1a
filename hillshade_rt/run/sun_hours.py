"""The ``sun-hours`` run: hours of direct sun per cell of a DEM over a day (or a range of days),
like WhiteboxTools' TimeInDaylight or GRASS r.sun's insolation time: the sun every step, each lit
sample counting for the part of its interval with the sun's centre up at the DEM's place
(``solar.daylight_samples``: never more than the day length there). Returns the report.

The run's steps, between the shared preamble and tail (``run.runner.RunContext``): the days
(the command line's dates, step and place), the DEM opened, and read whole when the run fits
--max-memory, the samples (the suns of the days at the DEM's place, those with some light and
their weights), the light (each sample's lit cells added, weighted), the output written, the
report. A DEM larger than --max-memory, --window-size, --scheduler and a ``--context`` tile go
through ``run.sun_hours_windows`` instead (the same sums, region by region, written as they are
made): the same bits.
"""

from __future__ import annotations

import datetime as _dt
import os
from dataclasses import dataclass, field

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import SunHoursConfig, parse_window_size
from .runner import RunContext


@dataclass
class _Days:
    """What the command line says of the sun: the first and last day, the step, the place."""

    first: _dt.date
    last: _dt.date
    step: str
    req: object             # model.sun.SunRequest (at the place; its times once sampled)

    @property
    def count(self) -> int:
        return (self.last - self.first).days + 1


@dataclass
class _Samples:
    """The suns of the days at the DEM's place: every sample (``suns``, ``sun_info`` for the
    report) and those with some light with their weights in hours (``work``)."""

    site: object            # model.site.Site
    suns: list
    sun_info: dict | None
    work: list              # [(sun, hours)]
    tz: object = None       # the days' zone (None: local mean solar time)


@dataclass
class _Hours:
    """The hours of direct sun per cell (float32, NaN nodata) and how they were lit (in
    memory, or in windows: then written already, their figures only)."""

    hours: object           # numpy array (None: written window by window)
    curvature: dict | None  # the curvature's report (None: every cell nodata)
    processing: dict = field(default_factory=lambda: {"mode": "in memory"})
    values: dict | None = None   # min, mean, max of the hours written in windows
    algo_stats: dict | None = None   # the windows' algorithm figures
    preview: tuple | None = None     # in windows: (heights, grid, hours) of every n-th cell
    months: list | None = None       # --monthly: ((year, month), hours) each (in windows:
    #                                  the hours' min, mean, max, written already)


def sun_hours(cfg: SunHoursConfig) -> dict:
    """Write the hours of direct sun of ``cfg.dem`` to ``cfg.output``; returns the report. In
    memory when the run fits --max-memory, else in windows (``run.sun_hours_windows``; with
    --window-size, --scheduler or --context too): the same bits either way."""
    from ..errors import AllNodata
    from ..io import check_output_format, output_driver
    from .context import nodata_note
    from .horizon import memory_limit
    from .local import bounded_gdal_cache, needs_windows
    from .period_cube import use_period_cube
    from .sun_hours_windows import memory_per_cell, windows_phrase

    cfg.check()
    ro = cfg.run
    wshape = parse_window_size(cfg.window_size)
    limit = memory_limit(cfg.max_memory)
    ctx = RunContext.start(ro, inputs=[cfg.dem] + cfg.read.inputs(),
                           outputs=[(cfg.output, "OUTPUT")], algorithm=cfg.algorithm,
                           note=False)     # the note once the command line is checked
    if not use_period_cube(cfg):     # (OUTPUT.nc, OUTPUT.zarr: a CF dataset, run.period_cube)
        check_output_format(cfg.output, output_driver(cfg.output, ro.fmt), "float32", 1, False,
                            ro.creation_options)
    days = _days(cfg)
    ctx.compile_note(cfg.algorithm, cfg.self_shadow)
    cfg.read.check_context(cfg.dem, **{"--scheduler": cfg.scheduler is not None,
                                       "--preview": ro.preview is not None})
    lighting = cfg.lighting(ctx.backend)
    algo_stats: dict = {}
    area, lit = None, None
    tags = None
    if cfg.read.context is not None:
        with ctx.timer("read"):
            area = cfg.read.open_area(cfg.dem)
        with area:
            d = area.tile          # the output's grid; the heights are the context's
            try:
                area.check_valid()
                valid = True
            except AllNodata:
                valid = False
            samples = _samples(days, area.source, lighting.soft)
            tags = _tags(cfg, days, samples)
            if valid:
                with bounded_gdal_cache():
                    lit = _in_windows(cfg, ctx, area.source, lighting, days, samples,
                                      tags, limit, wshape, area)
    else:
        forced = wshape is not None or cfg.scheduler is not None
        with ctx.timer("read"):     # opened (not read) once, for its size and then its values
            src = cfg.read.open(cfg.dem, windows=forced)
        with src:
            windowed = forced or needs_windows(
                src, limit, memory_per_cell(lighting, len(_months(days)) if cfg.monthly else 0))
            d = src
            if windowed:
                with ctx.timer("prepare"):
                    samples = _samples(days, src, lighting.soft)
                tags = _tags(cfg, days, samples)
                try:
                    with bounded_gdal_cache():
                        lit = _in_windows(cfg, ctx, src, lighting, days, samples, tags,
                                          limit, wshape)
                except AllNodata:   # (raised before the output is opened)
                    lit = None
            else:
                with ctx.timer("read"):
                    try:
                        d, valid = src.read(), True
                    except AllNodata:
                        valid = False
                with ctx.timer("prepare"):
                    samples = _samples(days, d, lighting.soft)
                    if valid:
                        shader, hours = _prepare(d, lighting, days.req, samples)
                if valid:
                    lit = _light(shader, hours, lighting, samples, ctx, algo_stats,
                                 _months(days) if cfg.monthly else None)
    if tags is None:
        tags = _tags(cfg, days, samples)
    figures = _write(cfg, ctx, d, lit, tags)
    rep = _report(cfg, ctx, d, days, samples, tags, figures, lit, algo_stats, area)
    if lit is None:
        return ctx.finish(rep, [("note", nodata_note(d.path))])
    h = rep["hours"]
    return ctx.finish(rep, [(
        "summary", f"hillshade-rt: {cfg.output}: {d.shape[1]}x{d.shape[0]}, {days.count} "
                   f"day(s) from {days.first.isoformat()}, {len(samples.work)} of "
                   f"{len(samples.suns)} samples with the sun up; sun hours {h['min']:.2f} .. "
                   f"{h['max']:.2f} (mean {h['mean']:.2f}); compute "
                   f"{ctx.timer.seconds['compute']:.2f} s{windows_phrase(rep['processing'])}")])


def _days(cfg: SunHoursConfig) -> _Days:
    """The dates, the step and the place of the command line (a bad one: a usage error, exit
    status 2, before the DEM is read)."""
    from ..model.sun import SunRequest
    from ..model.times import parse_date, parse_step
    try:
        first = parse_date(cfg.date, "--date")
        last = parse_date(cfg.end_date, "--end-date") if cfg.end_date is not None else first
        parse_step(cfg.step)
        req = SunRequest.at_place([], **cfg.place)
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    if last < first:
        raise UsageProblem("--end-date is before --date")
    return _Days(first, last, cfg.step, req)


def _samples(days: _Days, d, soft: bool) -> _Samples:
    """The suns of the days at the place of ``d`` (``solar.daylight_samples``), and those with
    some light (the top of the sun's disc, ``soft``, or its centre up somewhere) with their
    weights."""
    from ..model.solar import SUN_RADIUS_DEG, daylight_samples
    req = days.req
    site = req.site(d, "sun-hours computes the Earth's sun only (light a DEM of another "
                       "body with shadow or hillshade, which take the sun's direction)")
    try:
        req.times, weights = daylight_samples(days.first, days.last, days.step, req.tz, site,
                                              req.atmosphere)
    except HillshadeError as exc:   # too many samples for the dates and the step
        raise UsageProblem(str(exc)) from None
    suns, sun_info = req.suns(d, site)

    def dark(s):
        top = max([r.elevation for r in s.tiles] if s.tiles else [s.elevation])
        return top + (SUN_RADIUS_DEG if soft else 0.0) <= 0.0
    return _Samples(site, suns, sun_info,
                    [(s, w) for s, w in zip(suns, weights) if w > 0 and not dark(s)], req.tz)


def _prepare(d, lighting, req, samples: _Samples):
    """The Shader of the DEM in memory (warmed up for the first lit sample) and the hours at
    zero (NaN on nodata)."""
    import numpy as np

    from ..model.earth import dem_body
    shader = lighting.shader(d.heights, d.grid, body=dem_body(d, req.lat),
                             zrange=d.height_range(), survey=d.survey())
    work = samples.work
    if work:
        shader.warm_up(work[0][0].azimuth, max(work[0][0].elevation, 1.0), soft=lighting.soft,
                       incidence=lighting.self_shadow, field=any(s.fieldwise for s, _ in work))
    return shader, np.where(np.isnan(d.heights), np.float32(np.nan), np.float32(0.0))


def _light(shader, hours, lighting, samples: _Samples, ctx: RunContext, algo_stats,
           months=None) -> _Hours:
    """Each lit sample's lit cells (product "sun") added to ``hours``, weighted by its hours;
    with ``months`` ((year, month) of every day of the period, in order; --monthly) also to
    its month's own float32 sum (the total keeps its bits)."""
    import numpy as np

    from ..engine.shader import render
    from .report import progress
    from .sky_inputs import month_keys
    ro = ctx.ro
    per = None
    if months is not None:
        per = {k: hours.copy() for k in months}        # 0, NaN on nodata
        keys = month_keys([s.time for s, _ in samples.work], samples.tz, samples.site.lon)
    with ctx.timer("compute"):
        for i, (s, w) in enumerate(progress(samples.work, ro.quiet, "hillshade-rt sun-hours",
                                            unit="sun", mode=ro.progress)):
            lit = render(shader, s, "sun", soft=lighting.soft,
                         self_shadow=lighting.self_shadow, stats=algo_stats)
            hours += np.float32(w) * lit
            if per is not None:
                per[keys[i]] += np.float32(w) * lit
    return _Hours(hours, shader.report(),
                  months=None if per is None else list(per.items()))


def _months(days: _Days) -> list:
    """(year, month) of every month the period's days touch, in order."""
    out, d = [], days.first
    while d <= days.last:
        if (d.year, d.month) not in out:
            out.append((d.year, d.month))
        d += _dt.timedelta(days=1)
    return out


def _in_windows(cfg: SunHoursConfig, ctx: RunContext, src, lighting, days: _Days,
                samples: _Samples, tags: dict, limit: int, wshape, area=None) -> _Hours:
    """The hours in windows (``run.sun_hours_windows``: the same float32 sums as in memory,
    with --monthly each month's too), written to OUTPUT as they are made. ``area``: a
    ``--context`` tile of ``src``."""
    from .sun_hours_windows import hours_in_windows
    months = None
    if cfg.monthly:       # the months' keys, each lit sample's month (as _light adds them)
        import numpy as np

        from .sky_inputs import month_keys
        keys = _months(days)
        of = month_keys([s.time for s, _ in samples.work], samples.tz, samples.site.lon)
        months = (keys, np.array([keys.index(k) for k in of], np.int64))
    win = hours_in_windows(cfg, ctx, src, lighting, days.req, samples.work, tags, limit=limit,
                           window_shape=wshape, scheduler=cfg.scheduler, area=area,
                           months=months)
    return _Hours(None, win.curvature, processing=win.processing, values=win.values.as_dict(),
                  algo_stats=win.algo_stats, preview=win.preview,
                  months=None if win.months is None else
                  [(k, v.as_dict()) for k, v in win.months])


def _tags(cfg: SunHoursConfig, days: _Days, samples: _Samples) -> dict:
    """The output's metadata."""
    req = days.req
    from .sun_hours_windows import DESCRIPTION, RSUN_NAME
    return {"HILLSHADE_RT_VERSION": __version__, "UNITS": "hours of direct sun",
            "NAME": DESCRIPTION, "RSUN_NAME": RSUN_NAME,
            "DATE_FIRST": days.first.isoformat(), "DATE_LAST": days.last.isoformat(),
            "DAYS": days.count, "STEP": days.step, "ALGORITHM": cfg.algorithm,
            "SOFT": cfg.soft, "SELF_SHADOW": cfg.self_shadow,
            "HEIGHT_ABOVE_GROUND_M": float(cfg.height_above_ground),
            "DAY": f"midnight to midnight, {req.tz.key}" if req.tz is not None
            else f"local mean solar time at longitude {samples.site.lon:.4f}"}


def _write(cfg: SunHoursConfig, ctx: RunContext, d, lit: _Hours | None, tags: dict) -> dict:
    """The hours (-9999 nodata; all of it for a DEM of nodata) and the --preview (in windows:
    the hours are written already, the preview from every n-th cell); returns the min, mean and
    max of the hours written."""
    import numpy as np

    from ..io import write_png, write_raster
    from ..pictures.preview import relief_rgb
    from .period_cube import use_period_cube
    from .sun_hours_windows import description
    ro = ctx.ro
    if lit is not None and lit.hours is None:       # written in windows
        v = lit.values
        if ro.preview is not None and lit.preview is not None:
            pv, grid, pvh = lit.preview
            top = v["max"] if v["max"] is not None else 0.0
            with ctx.timer("write"):
                write_png(ro.preview, relief_rgb(pv, grid, warm=pvh / top if top > 0
                                                 else np.zeros_like(pvh)), ro.overwrite)
        return v
    hours = np.full(d.shape, np.nan, np.float32) if lit is None else lit.hours
    with ctx.timer("write"):
        months = lit.months if cfg.monthly and lit is not None else None
        if months is not None or use_period_cube(cfg):
            from .period_cube import period_writer
            with period_writer(cfg, d, tags, [k for k, _ in months or []]) as w:
                w.write(1, np.where(np.isnan(hours), np.float32(-9999.0), hours),
                        description(tags))
                for i, ((year, month), v) in enumerate(months or [], 2):
                    w.write(i, np.where(np.isnan(v), np.float32(-9999.0), v),
                            f"{year}-{month:02d}", {"UNITS": "hours of direct sun"})
        else:
            write_raster(cfg.output, np.where(np.isnan(hours), np.float32(-9999.0), hours), d,
                         nodata=-9999.0, description=description(tags), tags=tags,
                         overwrite=ro.overwrite, fmt=ro.fmt, co=ro.creation_options)
        if ro.preview is not None and lit is not None:
            top = float(np.nanmax(hours)) if np.isfinite(hours).any() else 0.0
            write_png(ro.preview, relief_rgb(d.heights, d.grid,
                                             warm=hours / top if top > 0 else np.zeros_like(hours)),
                      ro.overwrite)
    from .horizon_windows import ValueStats
    values = ValueStats()           # (the mean summed in float64, as in windows)
    values.add(hours)
    return values.as_dict()


def _report(cfg: SunHoursConfig, ctx: RunContext, d, days: _Days, samples: _Samples,
            tags: dict, figures: dict, lit: _Hours | None, algo_stats: dict, area) -> dict:
    """The run's report (``--report``: docs/usage.md's keys)."""
    from ..io import input_label
    if lit is not None and lit.algo_stats is not None:
        algo_stats = lit.algo_stats
    processing = (lit.processing if lit is not None else
                  {"mode": "all nodata", "cells": int(d.shape[0] * d.shape[1])})
    if processing.get("mode") == "in memory":
        processing = {"mode": "in memory", "cells": int(d.shape[0] * d.shape[1])}
    rep = {"input": input_label(d.path), "output": os.path.abspath(cfg.output),
           "shape": list(d.shape), "algorithm": cfg.algorithm, "backend": ctx.backend,
           "dates": [days.first.isoformat(), days.last.isoformat()], "days": days.count,
           "step": days.step, "samples": len(samples.suns),
           "samples_with_sun": len(samples.work), "day_definition": tags["DAY"],
           "soft": cfg.soft, "self_shadow": cfg.self_shadow,
           "height_above_ground_m": float(cfg.height_above_ground),
           "hours": figures,
           **({"months": [{"month": f"{y}-{m:02d}",
                           "hours": v if isinstance(v, dict) else _stats(v)}
                          for (y, m), v in lit.months]}
              if lit is not None and lit.months is not None else {}),
           "curvature": None if lit is None else lit.curvature,
           "algorithm_stats": algo_stats, "processing": processing,
           "seconds": ctx.seconds(), "version": __version__}
    rep.update(samples.sun_info or {})
    if area is not None:
        rep["context"] = area.report()
    return rep


def _stats(v) -> dict:
    """min, mean, max of the valid cells of ``v`` (the mean summed in float64)."""
    from .horizon_windows import ValueStats
    values = ValueStats()
    values.add(v)
    return values.as_dict()
