"""The ``irradiance`` run: beam, diffuse, reflected and global irradiance per cell of a DEM over
a period (Wh/m², or the mean W/m²), four float32 bands; the formulas are
``hillshade_rt.engine.irradiance``'s (the user's page: docs/irradiance.md).

The sun is sampled as ``sun-hours`` samples it (every step, each sample at the middle of its
interval, weighted by the interval's hours; per tile on large rasters; nights skipped), the same
suns light the cast shadows (``shading.render``) and feed the clear-sky model. The DEM is held
in memory, or made region by region when it would need more than --max-memory, with
--window-size or --scheduler (``run.irradiance_windows``: the same bits, written as the
regions are made, or a Dask task per region); with ``--context`` the DEM is a tile of a larger
raster (``run.context``): the
cast shadows and the incidence come from the context's windows
(``engine.windows.WindowLighting``, the regions cut to the tile), the sky view from the
windowed horizon march (``run.horizon_windows``, the rays to the context's edge), so that every
cell gets the bits the whole context's run gives it.

Dozier's Vd is computed (the pyramid and Horn's normals of the DEM computed once and shared with
every sun's shadows and sums), or read with ``--sky-view`` from a file that ``skyview
--definition dozier`` or ``--sky-view-out`` wrote, checked against the DEM and the run's
settings (``run.sky_view_file``): the same output bytes either way.

The open sky is one per sample for the whole DEM, unless --linke-turbidity, --beam-index or
--diffuse-index are rasters (r.sun's linke, coeff_bh, coeff_dh maps): then it is each cell's
(:func:`open_sky_cells`, ``engine.irradiance.CellSky``), in memory, with --context, for
instants, and in windows and on Dask (``run.irradiance_windows.open_sky_grids``: the rasters
resampled to the grid once, each region cutting its cells).

The run's steps, between the shared preamble and tail (``run.runner.RunContext``): what the
command line asks (the period, the place, the ``--ghi`` series), the DEM read, the samples (the
suns of the period at the DEM's place and the open sky at each), the light (the sky view and
the sums of every sun's beam, diffuse and reflected light), the output written, the report.
The lighting settings travel as one ``engine.lighting.Lighting``
(:meth:`IrradianceConfig.lighting`).
"""

from __future__ import annotations

import os
import datetime as _dt
from dataclasses import dataclass

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import IrradianceConfig
from .runner import RunContext


# formats that cannot hold the four float32 bands (pictures; ASCII and Surfer grids, one band)
ONE_BAND_FORMATS = ("PNG", "JPEG", "WEBP", "BMP", "GIF", "AAIGrid", "XYZ", "GSAG", "GSBG",
                    "GS7BG")


@dataclass
class _Asked:
    """What the command line says of the period and the sky, checked before the DEM is read:
    the step, the place (``SunRequest``), the days (``--date [--end-date]``) or the span
    (``--start``/``--end``: (t0, t1, times, weights); None with ``--tz auto``, sampled again
    in the DEM's zone), the ``--ghi`` series read (None: none, or read in the DEM's zone)."""

    step: _dt.timedelta
    req: object
    first: _dt.date | None = None
    last: _dt.date | None = None
    span: tuple | None = None
    series: tuple | None = None


@dataclass
class _Samples:
    """The period sampled at the DEM's place: its text and hours, the times and their weights
    (hours), the suns (``sun_info`` for the report), those with light (``work``), the open
    sky at each."""

    site: object
    period: str
    hours: float
    times: object
    weights: object
    suns: list
    sun_info: dict | None
    work: list
    sky: object             # engine.irradiance.Sky (None until the grid is known, where the
    #                         sky differs from cell to cell: cells)
    tz: object = None       # the zone of the samples' local time (None: local mean solar)
    cells: object = None    # engine.irradiance.CellSky: the open sky per cell (open_sky_cells)


@dataclass
class _Bands:
    """The four bands (``engine.irradiance.BANDS``: float32, NaN voids), Dozier's sky view,
    the curvature's report, and (``--context``, windows) the report's ``processing``; where the
    sky view came from (``vd_from``: "computed" or "read") and the tags of the file read (or
    None)."""

    bands: dict
    vd: object
    curvature: dict
    processing: dict | None = None
    vd_from: str = "computed"
    vd_tags: dict | None = None
    months: list | None = None      # --monthly: ((year, month), hours, global band) each
    figures: dict | None = None     # in windows (bands and vd None, written already): the
    #                                 bands' and "sky_view"'s min, mean, max


def irradiance(cfg: IrradianceConfig) -> dict:
    """Write the four irradiance bands of ``cfg.dem`` to ``cfg.output``; returns the report.
    (``--time`` and ``--instant`` are ``run.irradiance_instant``'s: ``irradiance_or_instants``
    runs either.)"""
    if cfg.instants():
        raise UsageProblem("--time and --instant are run.irradiance_instant's run")
    from .irradiance_windows import asked_windows
    from .period_cube import use_period_cube
    ro = cfg.run
    cfg.check()
    cfg.read.check_context(cfg.dem, **{"--preview": ro.preview is not None,
                                       "--scheduler": cfg.scheduler is not None})
    limit, wshape = asked_windows(cfg)
    # (the --ghi series and the context are inputs)
    ctx = RunContext.start(ro, inputs=[cfg.dem, cfg.ghi, cfg.sky_view] + cfg.read.inputs()
                           + cfg.sky_inputs(),
                           outputs=[(cfg.output, "OUTPUT"),
                                    (cfg.sky_view_out, "--sky-view-out")],
                           algorithm=cfg.algorithm,
                           note=False)     # the note once the command line is checked
    if not use_period_cube(cfg):     # (OUTPUT.nc, OUTPUT.zarr: a CF dataset, run.period_cube)
        _check_format(cfg)
    asked = _asked(cfg)
    ctx.compile_note(cfg.algorithm, True)
    lighting = cfg.lighting(ctx.backend)
    area, d, windows = _read(cfg, ctx, lighting, limit, wshape)
    if d is None:       # every cell nodata (a tile of the sea)
        return _all_nodata(cfg, ctx)
    try:
        return _run(cfg, ctx, lighting, asked, d, area, (limit, wshape) if windows else None)
    finally:
        if area is not None:
            area.close()
        elif windows:
            d.close()


def _run(cfg, ctx: RunContext, lighting, asked: _Asked, d, area, windows=None) -> dict:
    """The run once the DEM (``d``: in memory; with ``area``, the context opened for windows;
    with ``windows``, (--max-memory in bytes, --window-size), opened for windows) is open: the
    samples and the sky, the light (sky view, sums), the output, the report."""
    import numpy as np

    from ..errors import AllNodata
    from ..model.earth import dem_body
    from .report import progress
    from .sun_hours_windows import windows_phrase
    ro = ctx.ro
    with ctx.timer("prepare"):
        sampled = _samples(cfg, asked, d)
        if sampled.sky is None and windows is not None:   # the rasters on the grid once,
            from .irradiance_windows import open_sky_grids  # beside OUTPUT (removed at its end)
            sampled.sky, sampled.cells = open_sky_grids(cfg, sampled, d, area,
                                                        open_sky_inputs)
        elif sampled.sky is None:     # the open sky per cell, on the grid of the output
            geom, valid = _grid_of(d, area)
            sampled.sky, sampled.cells = open_sky_cells(
                cfg, sampled.times, sampled.suns, sampled.site, sampled.tz, geom, valid)
        body = dem_body(d, asked.req.lat)
        if area is None and windows is None:
            shader = _prepare(d, lighting, body, sampled)
    algo_stats: dict = {}
    tags = _tags(cfg, lighting, asked.req, sampled, area)

    def bar(it):
        return progress(it, ro.quiet, "hillshade-rt irradiance", "sun", mode=ro.progress)
    if windows is not None:       # region by region, written as they are made
        try:
            lit = _in_windows(cfg, ctx, d, lighting, body, sampled, tags, area, *windows)
        except AllNodata:          # (before the output is opened)
            return _all_nodata(cfg, ctx)
        algo_stats = lit.figures.pop("algorithm_stats")
        geom = d if area is None else area.tile
    elif area is None:
        lit = _light(cfg, ctx, d, shader, lighting, body, sampled, algo_stats, bar)
        geom = d
    else:
        lit = _light_in_context(cfg, ctx, area, lighting, body, sampled, algo_stats, bar)
        geom = area.tile
    if lit.bands is not None:
        if cfg.mean or cfg.daily_mean:     # W/m² (÷ hours), or Wh/m² a day (÷ days)
            per = 1.0 if cfg.mean else 24.0
            lit.bands = {k: (v / np.float32(sampled.hours / per)).astype(np.float32)
                         for k, v in lit.bands.items()}
            if lit.months is not None:
                lit.months = [(key, hours, (v / np.float32(hours / per)).astype(np.float32))
                              for key, hours, v in lit.months]
        _write(cfg, ctx, geom, d, lit, tags)
    rep = _report(cfg, ctx, geom, sampled, lit, algo_stats, area)
    sec, g, unit = rep["seconds"], rep["bands"]["global"], rep["units"]
    sv = (" read from " + cfg.sky_view if lit.vd_from == "read" else "") + \
        f" {sec.get('sky view', 0.0):.2f} s"
    how = windows_phrase(lit.processing) if windows is not None else ""
    return ctx.finish(rep, [(
        "summary", f"hillshade-rt: {cfg.output}: {geom.shape[1]}x{geom.shape[0]}, "
                   f"{sampled.period}, {len(sampled.work)} of {len(sampled.suns)} samples with "
                   f"the sun up; global {g['min']:.1f} .. {g['max']:.1f} {unit} (mean "
                   f"{g['mean']:.1f}); shadows {sec.get('shadows', 0.0):.2f} s, sky view"
                   f"{sv}, total {sec['total']:.2f} s{how}")])


def in_memory(cfg: IrradianceConfig, d) -> dict:
    """The period's sums of ``cfg`` on the DEM ``d`` (an ``io.Dem`` in memory) as
    :func:`irradiance` makes them, nothing written (``xarray.accessor.irradiance``): "bands"
    (``engine.irradiance.BANDS``: float32, NaN voids, in "units"), "months" (``monthly``:
    ((year, month), hours, global band) each, else None), "period", "hours", "samples",
    "samples_with_sun", "sky", "turbidity"."""
    import numpy as np

    from ..model.earth import dem_body
    if cfg.instants():
        raise UsageProblem("--time and --instant are run.irradiance_instant's run")
    cfg.check()
    ctx = RunContext.start(cfg.run, algorithm=cfg.algorithm, note=False)
    asked = _asked(cfg)
    lighting = cfg.lighting(ctx.backend)
    sampled = _samples(cfg, asked, d)
    body = dem_body(d, asked.req.lat)
    shader = _prepare(d, lighting, body, sampled)
    lit = _light(cfg, ctx, d, shader, lighting, body, sampled, {}, lambda it: it)
    bands, months = lit.bands, lit.months
    if cfg.mean or cfg.daily_mean:      # as _run's: ÷ hours, or ÷ days (24 h)
        per = 1.0 if cfg.mean else 24.0
        bands = {k: (v / np.float32(sampled.hours / per)).astype(np.float32)
                 for k, v in bands.items()}
        if months is not None:
            months = [(key, hours, (v / np.float32(hours / per)).astype(np.float32))
                      for key, hours, v in months]
    return {"bands": bands, "months": months, "period": sampled.period,
            "hours": sampled.hours, "samples": len(sampled.suns),
            "samples_with_sun": len(sampled.work), "sky": sampled.sky.source,
            "turbidity": sampled.sky.turbidity, "units": _unit(cfg)}


def _check_format(cfg: IrradianceConfig) -> None:
    """The output's format holds four float32 bands (a picture or a one-grid format: no)."""
    from ..engine import irradiance as ir
    from ..io import check_output_format, output_driver
    ro, output = cfg.run, cfg.output
    driver = output_driver(output, ro.fmt)
    if driver in ONE_BAND_FORMATS:
        raise HillshadeError(f"{output}: {driver} holds one band of integers or one grid; "
                             f"irradiance writes {len(ir.BANDS)} float32 bands "
                             f"({', '.join(ir.BANDS)}): write a GeoTIFF (.tif)")
    check_output_format(output, driver, "float32", len(ir.BANDS), True, ro.creation_options)


def _asked(cfg: IrradianceConfig) -> _Asked:
    """The step, the place and the period of the command line (a bad one: a usage error, exit
    status 2), and the ``--ghi`` series (a bad file fails the run, exit status 1, before the
    DEM is read; with ``--tz auto`` once it is, in its zone)."""
    from ..engine import irradiance as ir
    from ..model.sun import SunRequest
    from ..model.times import UTC, parse_date, parse_step
    asked = None
    try:
        step = parse_step(cfg.step)
        req = SunRequest.at_place([], **cfg.place)
        if cfg.date is not None:
            first = parse_date(cfg.date, "--date")
            last = parse_date(cfg.end_date, "--end-date") if cfg.end_date is not None else first
            if last < first:
                raise HillshadeError("--end-date is before --date")
            asked = _Asked(step, req, first, last)
        else:   # --tz auto: checked with UTC standing in, read again in the DEM's zone
            span = _period(cfg, req.tz or (UTC if req.auto_tz else None), step)
            asked = _Asked(step, req, span=None if req.auto_tz else span)
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    if cfg.ghi is not None and not req.auto_tz:
        asked.series = ir.read_series(cfg.ghi, req.tz)
    return asked


def _read(cfg: IrradianceConfig, ctx: RunContext, lighting, limit: int, wshape) -> tuple:
    """(area, DEM, windows): in memory (area None), or with ``--context`` the tile's area
    opened and the DEM its context's source (the place, the suns, the body: the context's);
    ``windows``: the DEM (or the tile) is made region by region (``run.irradiance_windows``:
    larger than ``limit`` bytes, or --window-size, --scheduler; a tile with --window-size or
    --max-memory), the DEM opened, not read; (None, None, False) when every cell of the DEM
    is nodata."""
    from ..errors import AllNodata
    from .irradiance_windows import memory_per_cell, windowed
    from .local import needs_windows
    with ctx.timer("read"):
        if cfg.read.context is not None:     # a tile: the heights are the context's
            area = cfg.read.open_area(cfg.dem)
            try:
                area.check_valid()
            except AllNodata:
                area.close()
                return None, None, False
            return area, area.source, wshape is not None or cfg.max_memory is not None
        forced = windowed(cfg)
        src = cfg.read.open(cfg.dem, windows=forced)
        if forced or needs_windows(src, limit, memory_per_cell(lighting)):
            return None, src, True
        try:
            with src:
                return None, src.read(), False
        except AllNodata:     # every band all nodata, a note (a tile of the sea)
            return None, None, False


def _samples(cfg: IrradianceConfig, asked: _Asked, d) -> _Samples:
    """The period sampled at the place of ``d`` (each sample at the middle of its interval,
    weighted by its hours), the suns, those with light, the open sky at each."""
    import numpy as np

    from ..engine import irradiance as ir
    from ..model.times import day_samples, iso
    req, series, span = asked.req, asked.series, asked.span
    site = req.site(d, "irradiance computes the Earth's sun only")
    if req.auto_tz:          # the DEM's zone is known now
        if cfg.ghi is not None:
            series = ir.read_series(cfg.ghi, req.tz)
        if cfg.date is None:
            span = _period(cfg, req.tz, asked.step)
    if cfg.date is not None:
        first, last = asked.first, asked.last
        try:
            times, weights = day_samples(first, last, cfg.step, req.tz, site.lon)
        except HillshadeError as exc:   # too many samples for the dates and the step
            raise UsageProblem(str(exc)) from None
        day = (f"midnight to midnight, {req.tz.key}" if req.tz is not None
               else f"local mean solar time at longitude {site.lon:.4f}")
        period = (f"{first.isoformat()}" + (f" to {last.isoformat()}" if last > first
                                              else "") + f" ({day})")
    else:
        t0, t1, times, weights = span
        period = f"{iso(t0)} to {iso(t1)}"
    req.times = times
    suns, sun_info = req.suns(d, site)
    return _Samples(site, period, float(np.sum(weights)), times, weights, suns, sun_info,
                    [s for s in suns if not ir.is_dark(s, cfg.soft)],
                    None if cfg.sky_per_cell() else open_sky(cfg, times, suns, site, series,
                                                             req.tz), req.tz)


def open_sky(cfg: IrradianceConfig, times, suns, site, series, tz=None, *, linke=None,
             indices=None):
    """The open sky at each sample: the clear-sky model's, or the ``--ghi`` series
    interpolated in time; times the clear-sky indices (--beam-index, --diffuse-index: r.sun's
    real sky, ``engine.irradiance.real_sky``); with ``--perez`` its Perez coefficients.
    ``linke``, ``indices``: the samples' Linke turbidity and (beam, diffuse) indices instead of
    the options' numbers (where they are rasters: :func:`open_sky_cells`)."""
    from ..engine import irradiance as ir
    sky = _clear_sky(cfg, times, suns, site, series, tz, linke)
    if indices is None:
        indices = (_per_sample(cfg.beam_input, times, tz, site),
                   _per_sample(cfg.diffuse_input, times, tz, site))
    if indices[0] is not None or indices[1] is not None:
        sky = ir.real_sky(sky, *indices)
    if cfg.perez:
        import numpy as np
        ir.with_perez(sky, times, np.array([s.zenith for s in suns], np.float64))
    return sky


def _per_sample(v, times, tz, site):
    """A number or twelve monthly numbers (``run.sky_inputs.SkyValue``) per sample: the number
    itself, or each sample's month's (None: not given)."""
    import numpy as np
    if v is None:
        return None
    if v.monthly is None:
        return v.number
    from .sky_inputs import local_months
    return np.array(v.monthly, np.float64)[local_months(times, tz, site.lon) - 1]


def _clear_sky(cfg, times, suns, site, series, tz, linke=None):
    """The clear sky (or the measured one) at each sample, before the indices."""
    import numpy as np

    from ..engine import irradiance as ir
    zen = np.array([s.zenith for s in suns], np.float64)
    if series is None:
        lt = linke if linke is not None else _per_sample(cfg.linke_input, times, tz, site)
        return ir.clear_sky(times, zen, site.lat, site.lon, site.height,
                            cfg.clear_sky or "ineichen", lt)
    unix, *cols = series
    ghi, dni, dhi = ir.series_at(times, unix, *cols, path=cfg.ghi)
    return ir.measured_sky(times, zen, ghi, dni, dhi,
                           f"measured: {os.path.basename(cfg.ghi)} (interpolated in time)")


def open_sky_cells(cfg: IrradianceConfig, times, suns, site, tz, geom, valid):
    """(the open sky, ``engine.irradiance.CellSky`` or None): with --linke-turbidity,
    --beam-index or --diffuse-index as rasters, each month's raster on the grid of ``geom``
    (its cells ``valid``; a raster of one value there is that number, the number's bits); where
    some vary over the cells, the open sky per cell of each sample (its month's rasters, read
    again as the samples reach each month: one month's held at a time), and the open sky of
    the report, the tags and the shadows' choice at each month's mean over the DEM. Else
    (None) :func:`open_sky`'s. (:func:`open_sky_inputs` with the rasters on the grid.)"""
    import numpy as np
    grid = (geom.transform, geom.crs, tuple(geom.shape), valid)

    def summarize(v, m):
        r = v.resolved(m, *grid)
        if isinstance(r, np.ndarray):
            inside = r if valid is None else r[valid]
            return (float(np.mean(inside)), True, float(np.min(inside)),
                    float(np.max(inside)))
        return r, False, r, r
    sky, inputs = open_sky_inputs(cfg, times, suns, site, tz, summarize)
    if inputs is None:
        return sky, None
    given = (cfg.linke_input, cfg.beam_input, cfg.diffuse_input)
    return sky, inputs.cells(lambda i, m: given[i].resolved(m, *grid))


def open_sky_inputs(cfg: IrradianceConfig, times, suns, site, tz, summarize):
    """(the open sky, ``run.sky_inputs.CellInputs`` or None) of :func:`open_sky_cells`,
    ``summarize(v, month)`` giving each raster's (its value or its mean over the DEM's valid
    cells, whether it varies there, min, max) (a run in windows: from the rasters resampled to
    its grid once, ``run.irradiance_windows.SkyGrids``)."""
    import numpy as np

    from ..engine import irradiance as ir
    from .sky_inputs import CellInputs, local_months
    if not cfg.sky_per_cell():
        return open_sky(cfg, times, suns, site, None, tz), None
    months = local_months(times, tz, site.lon) if len(times) else np.zeros(0, np.int64)
    inputs = (cfg.linke_input, cfg.beam_input, cfg.diffuse_input)
    summary = {}               # (input, month): (the value or the raster's mean, varies, lo, hi)
    for i, v in enumerate(inputs):
        if v is None or not v.rasters:
            continue
        for m in sorted(set(int(x) for x in months)) if v.by_month else [1]:
            summary[i, m] = summarize(v, m)

    def per_sample(i):
        v = inputs[i]
        if v is None or not v.rasters:
            return _per_sample(v, times, tz, site)
        vals = np.array([summary[i, int(m) if v.by_month else 1][0] for m in months],
                        np.float64)
        return float(vals[0]) if vals.size and np.all(vals == vals[0]) else vals
    per_cell = any(x[1] for x in summary.values())
    lt, kb, kd = per_sample(0), per_sample(1), per_sample(2)
    if not per_cell:
        return open_sky(cfg, times, suns, site, None, tz, linke=lt, indices=(kb, kd)), None
    raw = _clear_sky(cfg, times, suns, site, None, tz, lt)
    sky = ir.real_sky(raw, kb, kd) if kb is not None or kd is not None else raw
    zen = np.array([s.zenith for s in suns], np.float64)
    if cfg.perez:
        ir.with_perez(sky, times, zen)
    lv = cfg.linke_input
    if lv is not None and lv.rasters and any(x[1] for (i, _), x in summary.items() if i == 0):
        lo = min(x[2] for (i, _), x in summary.items() if i == 0)
        hi = max(x[3] for (i, _), x in summary.items() if i == 0)
        sky.turbidity = (f"{lv.describe()}: each cell its own, {lo:.2f}..{hi:.2f} over the "
                         f"DEM (the open sky of the report at the DEM's mean"
                         + (f", {float(np.mean(lt)):.2f})" if np.size(lt) else ")"))
    am, extra, cosz, consts = ir.ineichen_terms(times, zen, site.lat, site.lon, site.height)
    z, am_rel = ir.perez_terms(times, zen)
    return sky, CellInputs(months, tuple(bool(v is not None and v.by_month) for v in inputs),
                           frozenset(k for k, x in summary.items() if x[1]), (lt, kb, kd),
                           ir.SampleSky(raw.ghi, raw.dni, raw.dhi, am, extra, cosz, consts, z,
                                        am_rel))


def _grid_of(d, area):
    """(the grid of the output, its valid cells): the DEM in memory, or the --context tile (its
    heights read from the context)."""
    import numpy as np
    if area is None:
        return d, ~np.isnan(d.heights)
    z = np.empty(area.shape, np.float32)
    with area.source.reader() as rd:
        rd.read(area.bounds, z)
    return area.tile, ~np.isnan(z)


def _prepare(d, lighting, body, sampled: _Samples):
    """The Shader of the DEM in memory, warmed up for the first sun with light."""
    shader = lighting.shader(d.heights, d.grid, body=body, zrange=d.height_range(),
                             survey=d.survey())
    work = sampled.work
    if work:
        shader.warm_up(work[0].azimuth, max(work[0].elevation, 1.0), soft=lighting.soft,
                       incidence=True, field=any(s.fieldwise for s in work))
    return shader


def _light(cfg, ctx: RunContext, d, shader, lighting, body, sampled: _Samples, algo_stats,
           bar) -> _Bands:
    """The four bands of the DEM in memory: Dozier's sky view, then each sun's cast shadows
    and incidence summed with the sky (``engine.irradiance.accumulate``)."""
    from ..algorithms.irradiance import normals
    from ..engine import irradiance as ir
    from ..engine.shader import horizon_shader
    with ctx.timer("prepare"):   # Horn's normals once: the sky view's and every sun's
        nrm = normals(d.heights, d.grid)
    # the sky view's curvature and refraction, as dozier_view's (from the shape, no heights)
    hs = horizon_shader(d.heights, d.grid, lighting.backend, lighting.curvature,
                        lighting.refraction_k, body)
    with ctx.timer("sky view"):
        if cfg.sky_view is not None:
            vd, vd_tags = read_sky_view(cfg, d, hs, None, d.heights)
        else:
            # one pyramid for the sky view and every sun's shadows (the Shader's, built once)
            pyramid = shader.pyramid(shader.z, True) if lighting.backend == "cpu" else None
            vd, vd_tags = ir.dozier_view(d.heights, d.grid, cfg.skyview_directions,
                                         lighting.backend, lighting.curvature,
                                         lighting.refraction_k, body, lighting.lift,
                                         pyramid=pyramid, normals=nrm), None
    if cfg.sky_view_out is not None:
        write_sky_view(cfg, ctx, d, vd, hs, None, d.heights)
    with ctx.timer("prepare"):
        albedo, groups, keys = _albedo_groups(cfg, sampled, d, None)
    with ctx.timer("compute"):
        bands = ir.accumulate(shader, sampled.suns, sampled.weights, sampled.sky, vd,
                              albedo, soft=lighting.soft, perez=cfg.perez, stats=algo_stats,
                              timer=ctx.timer, progress=bar, normals=nrm, groups=groups,
                              cells=sampled.cells)
    return _Bands(bands, vd, shader.report(), vd_from="computed" if vd_tags is None else "read",
                  vd_tags=vd_tags, months=_months(cfg, sampled, bands, groups, keys))


def _albedo_groups(cfg, sampled: _Samples, geom, valid):
    """(the albedo of the whole period: a number or a raster on the grid of ``geom``; the
    samples' groups (``engine.irradiance.Groups``: their months) where --monthly or a monthly
    albedo needs them, else None; the groups' (year, month))."""
    import numpy as np

    from ..engine import irradiance as ir
    from .sky_inputs import month_keys
    a = cfg.albedo_input
    shape = geom.shape
    if valid is None and a.rasters:
        valid = ~np.isnan(geom.heights)

    def on(month):
        return a.on_grid(month, geom.transform, geom.crs, shape, valid)
    if not (cfg.monthly or a.by_month):
        return on(1), None, None
    keys = month_keys(sampled.times, sampled.tz, sampled.site.lon)
    order = list(dict.fromkeys(keys))
    index = np.array([order.index(k) for k in keys], np.int64) if keys else np.zeros(0, np.int64)
    per = [on(m) for _, m in order] if a.by_month else None
    return (None if a.by_month else on(1)), ir.Groups(index, per, bool(cfg.monthly)), order


def _months(cfg, sampled: _Samples, bands: dict, groups, keys) -> list | None:
    """--monthly: ((year, month), the month's hours, its global band) each (``groups``, ``keys``:
    :func:`_albedo_groups`')."""
    import numpy as np
    if not cfg.monthly:
        bands.pop("groups", None)
        return None
    hours = np.bincount(groups.index, weights=np.asarray(sampled.weights, np.float64),
                        minlength=len(keys))
    return [(k, float(h), v) for k, h, v in zip(keys, hours, bands.pop("groups"))]


def _want(cfg, hs, area, heights) -> dict:
    """The tags of the run's sky view (``sky_view_file.dozier_tags``): ``hs`` the horizon
    Shader (its curvature, refraction coefficient and body), ``area`` the --context tile (or
    None), ``heights`` the DEM's when it is read whole (for the digest; None in windows)."""
    from .sky_view_file import dozier_tags
    return dozier_tags(cfg.skyview_directions, curved=bool(hs.curvature), k=hs.k, body=hs.body,
                       height_above_ground=float(cfg.height_above_ground), area=area,
                       heights=heights)


def read_sky_view(cfg, geom, hs, area, heights):
    """(Vd, the file's tags) of --sky-view, checked against the grid of ``geom`` and the
    run's settings."""
    from .sky_view_file import read_vd
    return read_vd(cfg.sky_view, geom, _want(cfg, hs, area, heights))


def write_sky_view(cfg, ctx, geom, vd, hs, area, heights) -> None:
    """--sky-view-out: the Vd computed, as skyview writes it (its tags too)."""
    from .sky_view_file import write_vd
    with ctx.timer("write"):
        write_vd(cfg.sky_view_out, geom, vd, _want(cfg, hs, area, heights), ctx.ro)


def _light_in_context(cfg, ctx: RunContext, area, lighting, body, sampled: _Samples,
                      algo_stats, bar) -> _Bands:
    """The four bands of the tile of ``area`` (``--context``): each sun's cast shadows and
    incidence from the context's windows (``engine.windows.WindowLighting``, product "sun",
    the regions cut to the tile), Dozier's sky view from the windowed horizon march
    (``run.horizon_windows``: the rays to the context's edge), the slopes from the tile and a
    cell around it; then the same sums, cell by cell, as a run of the whole context in memory
    (``irradiance.sums``). The pieces are ``run.irradiance_windows``' (a tile held whole;
    --window-size or --max-memory make it region by region there)."""
    import numpy as np

    from ..engine import irradiance as ir
    from ..engine.windows import (
        WindowCache, bytes_per_cell, default_max_memory, window_budget
    )
    from ..model.earth import curvature_report
    from .horizon import memory_limit, prepare_windows
    from .horizon_windows import Figures
    from .irradiance_windows import add_direct, lighting_job, region_vd, sky_view_job, surface
    from .local import bounded_gdal_cache

    src, timer, work = area.source, ctx.timer, sampled.work
    r0, r1, c0, c1 = area.bounds
    fig = Figures()
    with bounded_gdal_cache():
        with timer("prepare"):
            bstats = area.block_stats()     # (the context's, kept between runs)
            job = lighting_job(src, lighting, body, bstats)
            budget = window_budget(default_max_memory(),
                                   bytes_per_cell(lighting.algorithm, "sun", lighting.soft))[0]
            if work:
                job.warm_up(work[0])
            hjob, hs = sky_view_job(src, lighting, body, bstats, cfg.skyview_directions)
        vd_tags = None
        if cfg.sky_view is not None:
            with timer("sky view"):
                vd, vd_tags = read_sky_view(cfg, area.tile, hs, area, None)
        else:
            regs, _ = prepare_windows(src, hjob, memory_limit(None), None, timer, area)
        with src.reader() as rd:
            def heights(m):
                z = np.empty((m[1] - m[0], m[3] - m[2]), np.float32)
                rd.read(m, z)
                return z
            # the tile's voids, and its slopes (Horn's normals) for Perez
            void, slopes = surface(heights, src.grid, src.shape, area.bounds)
            if vd_tags is None:
                with timer("sky view"):   # Dozier's Vd of the tile's regions, as skyview's
                    vd = np.empty(area.shape, np.float32)
                    for reg in regs:
                        a0, a1, b0, b1 = area.local(reg)
                        vd[a0:a1, b0:b1], f = region_vd(hjob, rd, reg)
                        fig.add(f)
                if cfg.sky_view_out is not None:
                    write_sky_view(cfg, ctx, area.tile, vd, hs, area, None)
            cache, used = WindowCache(rd), set()
            read = {"windows": 0, "cells": 0}

            def direct(s, timed):
                """max(cos i, 0) * lit over the tile, window by window of the sun's plan."""
                out = np.empty(area.shape, np.float32)
                with timed("shadows"):
                    pieces = job.pieces(s, bstats, budget, area=area.bounds)
                    carry = job.carrier([pieces])
                    for p in pieces:
                        add_direct(job, out, (r0, c0), p, cache.get(p.window), algo_stats,
                                   used, carry)
                        read["windows"] += 1
                        read["cells"] += p.cells
                return out
            with timer("prepare"):
                albedo, groups, keys = _albedo_groups(cfg, sampled, area.tile, ~void)
            with timer("compute"):
                bands = ir.sums(direct, void, slopes, sampled.suns, sampled.weights,
                                sampled.sky, vd, albedo, soft=lighting.soft,
                                perez=cfg.perez, stats=algo_stats, timer=timer, progress=bar,
                                groups=groups, cells=sampled.cells)
    processing = {"mode": "windows", "cells": area.shape[0] * area.shape[1],
                  "shadow_windows": read["windows"], "shadow_window_cells": read["cells"],
                  "sky_view": fig.as_dict()}
    return _Bands(bands, vd, curvature_report(job.curvature, used, job.body, job.k),
                  processing, "computed" if vd_tags is None else "read", vd_tags,
                  _months(cfg, sampled, bands, groups, keys))


def _sky_model(cfg: IrradianceConfig) -> str:
    return "perez" if cfg.perez else "isotropic"


def _unit(cfg: IrradianceConfig) -> str:
    return "W/m2" if cfg.mean else "Wh/m2/day" if cfg.daily_mean else "Wh/m2"


def _tags(cfg: IrradianceConfig, lighting, req, sampled: _Samples, area) -> dict:
    """The output's metadata."""
    from ..engine import irradiance as ir
    from ..io import input_label
    sky, sky_model = sampled.sky, _sky_model(cfg)
    units = ("W/m2, mean over the period" if cfg.mean
             else "Wh/m2 per day, the energy over the period divided by its days"
             if cfg.daily_mean else "Wh/m2, energy over the period")
    tags = {"HILLSHADE_RT_VERSION": __version__, "UNITS": units, "PERIOD": sampled.period,
            "PERIOD_HOURS": f"{sampled.hours:g}", "STEP": cfg.step,
            "SAMPLES": len(sampled.suns), "SKY": sky.source, "SKY_MODEL": sky_model,
            "ALBEDO": cfg.albedo_input.describe(),
            **sky_input_tags(cfg),
            "SKYVIEW_DIRECTIONS": cfg.skyview_directions,
            "SOFT": cfg.soft, "ALGORITHM": cfg.algorithm,
            "HEIGHT_ABOVE_GROUND_M": lighting.lift,
            "DEFINITIONS": ir.definitions(sky_model, cfg.skyview_directions, cfg.soft),
            "SUN": "NREL SPA (pvlib.spa) at the DEM's centre, per tile where it varies; "
                   + ("apparent (refracted) elevation" if req.atmosphere.refraction
                      else "true elevation (--no-refraction)"),
            "EDGE": "no terrain beyond the raster: border cells see open sky outward"
                    if area is None else
                    f"the tile's cells in the context {input_label(area.source.path)} "
                    f"(rows {area.bounds[0]}..{area.bounds[1]}, columns "
                    f"{area.bounds[2]}..{area.bounds[3]}): its terrain casts the shadows and "
                    "bounds the sky view; no terrain beyond the context"}
    if cfg.ghi is None:
        tags["CLEAR_SKY"] = cfg.clear_sky or "ineichen"
        tags["TURBIDITY"] = sky.turbidity or "none (Haurwitz takes none)"
    if sky.split:
        tags["SPLIT"] = sky.split
    if cfg.monthly:
        tags["MONTHS"] = ("bands 5 on: the global energy of each month of the period (its "
                          "description YYYY-MM; months in "
                          + (f"{sampled.tz.key}" if sampled.tz is not None
                             else "local mean solar time") + "), in the bands' units")
    return tags


def sky_input_tags(cfg: IrradianceConfig) -> dict:
    """The tags of --linke-turbidity, --beam-index and --diffuse-index where given (as the
    ALBEDO tag: ``run.sky_inputs.SkyValue.describe``)."""
    tags = {}
    for key, v, what in (("LINKE_TURBIDITY", cfg.linke_input, ""),
                         ("BEAM_INDEX", cfg.beam_input,
                          " (r.sun's coeff_bh: the real sky's beam is the clear sky's times it)"),
                         ("DIFFUSE_INDEX", cfg.diffuse_input,
                          " (r.sun's coeff_dh: the real sky's diffuse is the clear sky's times "
                          "it)")):
        if v is not None:
            tags[key] = v.describe() + what
    return tags


def sky_input_report(cfg: IrradianceConfig) -> dict:
    """The report's entries of the clear-sky indices: ``beam_index``, ``diffuse_index`` (a
    number, or its description; None: not given, the clear sky)."""
    def of(v):
        return None if v is None else v.number if v.number is not None else v.describe()
    return {"beam_index": of(cfg.beam_input), "diffuse_index": of(cfg.diffuse_input)}


def one_day(cfg: IrradianceConfig) -> bool:
    """Whether the bands are r.sun's mode 2 product: the sums over one day (``--date`` without
    a later ``--end-date``), Wh/m² per day, not ``--mean``'s W/m²."""
    from ..model.times import parse_date
    return (cfg.date is not None and not cfg.mean
            and (cfg.end_date is None or parse_date(cfg.end_date, "--end-date")
                 == parse_date(cfg.date)))


def band_texts(cfg: IrradianceConfig) -> list[tuple[str, dict]]:
    """The four bands' descriptions and tags: r.sun's names (beam_rad, diff_rad, refl_rad,
    glob_rad) where the band is r.sun's product (:func:`one_day`), ours (beam, diffuse,
    reflected, global) otherwise; the tags NAME (ours, always), RSUN_NAME and UNITS."""
    from ..engine import irradiance as ir
    rsun = one_day(cfg)
    return [(ir.RSUN_NAMES[k] if rsun else k,
             {"UNITS": _unit(cfg), "NAME": k, "RSUN_NAME": ir.RSUN_NAMES[k]}) for k in ir.BANDS]


def _write(cfg: IrradianceConfig, ctx: RunContext, geom, d, lit: _Bands, tags: dict) -> None:
    """The four bands (-9999 nodata) on the grid of ``geom``, and the --preview (the global
    band over the relief of ``d``, 2nd..98th percentile)."""
    import numpy as np

    from ..engine import irradiance as ir
    from ..io import write_png
    from ..pictures.preview import relief_rgb, scaled
    from .period_cube import period_writer
    ro = ctx.ro
    with ctx.timer("write"):
        months = lit.months or []
        with period_writer(cfg, geom, tags, [(k, h) for k, h, _ in months], dem=d,
                           resampling="average") as w:
            for i, (k, (text, btags)) in enumerate(zip(ir.BANDS, _band_meta(cfg)), 1):
                v = lit.bands[k]
                w.write(i, np.where(np.isnan(v), np.float32(-9999.0), v), text, btags)
            for i, ((year, month), hours, v) in enumerate(months, len(ir.BANDS) + 1):
                w.write(i, np.where(np.isnan(v), np.float32(-9999.0), v), f"{year}-{month:02d}",
                        {"UNITS": _unit(cfg), "NAME": "global", "HOURS": f"{hours:g}"})
        if ro.preview is not None:
            write_png(ro.preview, relief_rgb(d.heights, d.grid,
                                             ramp=scaled(lit.bands["global"])),
                      ro.overwrite)


def _summary(v) -> dict:
    """min, mean, max of the valid cells of ``v`` (None where there are none)."""
    import numpy as np
    ok = v[~np.isnan(v)]
    return ({"min": float(ok.min()), "mean": float(ok.mean()), "max": float(ok.max())}
            if ok.size else {"min": None, "mean": None, "max": None})


def _in_windows(cfg: IrradianceConfig, ctx: RunContext, src, lighting, body,
                sampled: _Samples, tags: dict, area, limit: int, wshape) -> _Bands:
    """The four bands made and written region by region (``run.irradiance_windows``: the
    same bits as in memory), of ``area``'s tile only with ``--context``."""
    from .irradiance_windows import bands_in_windows
    win = bands_in_windows(cfg, ctx, src, lighting, body, sampled, tags, _band_meta(cfg),
                           lambda hs: _want(cfg, hs, area, None), limit=limit,
                           window_shape=wshape, scheduler=cfg.scheduler, area=area)
    return _Bands(None, None, win.curvature, win.processing, win.vd_from, win.vd_tags,
                  months=win.months,      # (in windows: each month's figures, not its band)
                  figures={"bands": win.values, "sky_view": win.vd_values,
                           "algorithm_stats": win.algo_stats})


def _band_meta(cfg: IrradianceConfig) -> list:
    """Each band's (description, tags), in ``engine.irradiance.BANDS``' order
    (:func:`band_texts`)."""
    return band_texts(cfg)


def _report(cfg: IrradianceConfig, ctx: RunContext, geom, sampled: _Samples, lit: _Bands,
            algo_stats: dict, area) -> dict:
    """The run's report (``--report``)."""
    import numpy as np

    from ..engine import irradiance as ir
    from ..io import input_label
    sky, weights = sampled.sky, np.asarray(sampled.weights)
    with_shadows = algo_stats.pop("samples_with_shadows", 0)
    algo_stats.pop("samples", None)
    rep = {"input": input_label(geom.path), "output": os.path.abspath(cfg.output),
           "shape": list(geom.shape), "algorithm": cfg.algorithm, "backend": ctx.backend,
           "period": sampled.period, "period_hours": sampled.hours, "step": cfg.step,
           "units": _unit(cfg), "samples": len(sampled.suns),
           "samples_with_sun": len(sampled.work), "samples_with_shadows": with_shadows,
           "sky": sky.source, "sky_model": _sky_model(cfg), "turbidity": sky.turbidity,
           "split": sky.split,
           "albedo": (cfg.albedo_input.number if cfg.albedo_input.number is not None
                      else cfg.albedo_input.describe()),
           **sky_input_report(cfg),
           "skyview_directions": cfg.skyview_directions, "soft": cfg.soft,
           "height_above_ground_m": float(cfg.height_above_ground),
           "sky_view": (_summary(lit.vd) if lit.figures is None
                        else lit.figures["sky_view"]), "sky_view_from": lit.vd_from,
           "sky_view_file": (os.path.abspath(cfg.sky_view) if cfg.sky_view is not None else
                             os.path.abspath(cfg.sky_view_out) if cfg.sky_view_out is not None
                             else None),
           "open_sky": {"dni_wh_m2": float(np.sum(weights * sky.dni)),
                        "dhi_wh_m2": float(np.sum(weights * sky.dhi)),
                        "ghi_wh_m2": float(np.sum(weights * sky.ghi))},
           "bands": ({k: _summary(lit.bands[k]) for k in ir.BANDS} if lit.figures is None
                     else lit.figures["bands"]),
           "curvature": lit.curvature, "algorithm_stats": algo_stats,
           "seconds": ctx.seconds(), "version": __version__}
    rep.update(sampled.sun_info or {})
    if lit.months is not None:
        rep["months"] = [{"month": f"{y}-{m:02d}", "hours": h,
                          "global": v if isinstance(v, dict) else _summary(v)}
                         for (y, m), h, v in lit.months]
    if lit.vd_tags is not None:      # the version that made the file read
        rep["sky_view_made_by"] = lit.vd_tags.get("HILLSHADE_RT_VERSION")
    if area is not None:
        rep["context"] = area.report()
    rep["processing"] = (lit.processing if lit.processing is not None else
                         {"mode": "in memory", "cells": int(geom.shape[0] * geom.shape[1])})
    return rep


def _all_nodata(cfg: IrradianceConfig, ctx: RunContext) -> dict:
    """A DEM whose every cell is nodata: the four bands all -9999, a note; the report."""
    import numpy as np

    from ..engine import irradiance as ir
    from ..io import input_label
    from .context import nodata_note
    from .period_cube import period_writer
    src = cfg.read.open(cfg.dem)
    src.close()
    tags = {"HILLSHADE_RT_VERSION": __version__, "NODATA": "-9999 (every cell of the DEM is "
            "nodata)"}
    with ctx.timer("write"), period_writer(cfg, src, tags, resampling="average") as w:
        arr = np.full(src.shape, -9999.0, np.float32)
        for i, (text, btags) in enumerate(band_texts(cfg), 1):
            w.write(i, arr, text, btags)
    rep = {"input": input_label(src.path), "output": os.path.abspath(cfg.output),
           "shape": list(src.shape), "all_nodata": True,
           "bands": {k: {"min": None, "mean": None, "max": None} for k in ir.BANDS},
           "seconds": ctx.seconds(), "version": __version__}
    return ctx.finish(rep, [("note", nodata_note(src.path))])


def _period(cfg, tz, step):
    """(t0, t1, times, weights) of --start..--end, local times in ``tz``, shown in it."""
    from ..engine import irradiance as ir
    from ..model.times import parse_time
    t0, t1 = parse_time(cfg.start, tz, "--start"), parse_time(cfg.end, tz, "--end")
    if tz is not None:     # shown in the zone of --tz
        t0, t1 = t0.astimezone(tz), t1.astimezone(tz)
    return (t0, t1, *ir.period_samples(t0, t1, step))
