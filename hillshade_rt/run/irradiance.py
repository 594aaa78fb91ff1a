"""The ``irradiance`` run: beam, diffuse, reflected and global irradiance per cell of a DEM over
a period (Wh/m², or the mean W/m²), four float32 bands; the formulas are
``hillshade_rt.engine.irradiance``'s (the user's page: docs/irradiance.md).

The sun is sampled as ``sun-hours`` samples it (every step, each sample at the middle of its
interval, weighted by the interval's hours; per tile on large rasters; nights skipped), the same
suns light the cast shadows (``shading.render``) and feed the clear-sky model. The DEM is held
in memory; with ``--context`` the DEM is a tile of a larger raster (``run.context``): the
cast shadows and the incidence come from the context's windows (``engine.windows.WindowLighting``, the regions
cut to the tile), the sky view from the windowed horizon march (``run.horizon_windows``, the rays to the
context's edge), so that every cell gets the bits the whole context's run gives it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import ReadOptions, RunOptions, set_threads


# formats that cannot hold the four float32 bands (pictures; ASCII and Surfer grids, one band)
ONE_BAND_FORMATS = ("PNG", "JPEG", "WEBP", "BMP", "GIF", "AAIGrid", "XYZ", "GSAG", "GSBG",
                    "GS7BG")


@dataclass(kw_only=True)
class IrradianceConfig:
    """An ``irradiance`` run. The period: ``date`` (and ``end_date``), or ``start`` and
    ``end``; the open sky: ``clear_sky`` (None: ineichen) with ``linke_turbidity``, or the
    measured series of the CSV file ``ghi``."""

    dem: str
    output: str
    date: str | None = None
    end_date: str | None = None
    start: str | None = None
    end: str | None = None
    step: str = "15min"
    clear_sky: str | None = None          # None: "ineichen" (and not with ``ghi``)
    linke_turbidity: float | None = None  # None: pvlib's climatological lookup
    albedo: float = 0.2
    ghi: str | None = None                # a CSV: time, ghi[, dni, dhi]
    mean: bool = False                    # mean W/m² over the period instead of Wh/m²
    soft: bool = False
    perez: bool = False
    skyview_directions: int = 32
    place: dict = field(default_factory=dict)    # PLACE_KEYS: tz, lat, lon, pressure, ...
    algorithm: str = "auto"
    curvature: object = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    height_above_ground: float = 0.0      # metres: the receiving surface stands this high

    def check(self):
        """The options' combinations and values (UsageProblem: exit status 2)."""
        from ..engine.irradiance import CLEAR_SKY_MODELS, check_options
        by_date = self.date is not None or self.end_date is not None
        by_time = self.start is not None or self.end is not None
        if by_date == by_time:
            raise UsageProblem("give the period one way: --date [--end-date], or --start and "
                               "--end")
        if by_date and self.date is None:
            raise UsageProblem("--end-date goes with --date")
        if by_time and (self.start is None or self.end is None):
            raise UsageProblem("--start and --end go together")
        if self.clear_sky is not None and self.clear_sky not in CLEAR_SKY_MODELS:
            raise UsageProblem(f"--clear-sky must be one of {', '.join(CLEAR_SKY_MODELS)}, got "
                               f"{self.clear_sky!r}")
        if self.ghi is not None and (self.clear_sky is not None
                                     or self.linke_turbidity is not None):
            raise UsageProblem("--ghi gives the sky measured: --clear-sky and "
                               "--linke-turbidity do not go with it")
        if self.linke_turbidity is not None and self.clear_sky == "haurwitz":
            raise UsageProblem("--linke-turbidity is Ineichen's: Haurwitz takes none")
        from .config import check_lift     # auto -> the algorithm that marches the lift
        self.algorithm = check_lift(self.height_above_ground, self.algorithm, self.soft)
        try:
            check_options(self.albedo, self.linke_turbidity, self.skyview_directions)
        except HillshadeError as exc:
            raise UsageProblem(str(exc)) from None


def irradiance(cfg: IrradianceConfig) -> dict:
    import numba

    from ..engine import irradiance as ir
    from ..io import check_output_format, output_driver
    from ..io.write import Claims
    from ..engine.shader import choose_backend
    from ..model.sun import SunRequest
    from ..model.times import UTC, parse_date, parse_step
    from .notes import compile_note
    from .report import Timer

    ro, output = cfg.run, cfg.output
    cfg.check()
    lift = float(cfg.height_above_ground)
    timer = Timer()
    cfg.read.check_context(cfg.dem, **{"--preview": ro.preview is not None})
    # (the --ghi series and the context are inputs)
    claims = Claims([cfg.dem, cfg.ghi] + cfg.read.inputs(), ro.overwrite)
    for path, what in ((output, "OUTPUT"), (ro.report_path, "--report"),
                       (ro.preview, "--preview")):
        if path is not None:
            claims.claim(path, what)
    driver = output_driver(output, ro.fmt)
    if driver in ONE_BAND_FORMATS:
        raise HillshadeError(f"{output}: {driver} holds one band of integers or one grid; "
                             f"irradiance writes {len(ir.BANDS)} float32 bands "
                             f"({', '.join(ir.BANDS)}): write a GeoTIFF (.tif)")
    check_output_format(output, driver, "float32", len(ir.BANDS), True, ro.creation_options)
    try:    # the command line alone decides these: a bad one is a usage error (exit 2)
        step = parse_step(cfg.step)
        req = SunRequest.at_place([], **cfg.place)
        if cfg.date is not None:
            first = parse_date(cfg.date, "--date")
            last = parse_date(cfg.end_date, "--end-date") if cfg.end_date is not None else first
            if last < first:
                raise HillshadeError("--end-date is before --date")
        else:   # --tz auto: checked with UTC standing in, read again in the DEM's zone
            t0, t1, times, weights = _period(cfg, req.tz or (UTC if req.auto_tz else None),
                                             step)
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    series = None
    if cfg.ghi is not None and not req.auto_tz:   # a bad file fails the run (exit 1) before
        series = ir.read_series(cfg.ghi, req.tz)  # the DEM is read (--tz auto: once it is)
    set_threads(ro)
    ran_on = choose_backend(ro.backend, cfg.algorithm, {})
    if not ro.quiet:
        note = compile_note(cfg.algorithm, ran_on, True)
        if note:
            ro.say("compile", note)
    from ..errors import AllNodata
    area = None
    with timer("read"):
        if cfg.read.context is not None:     # a tile: the heights are the context's
            area = cfg.read.open_area(cfg.dem)
            try:
                area.check_valid()
            except AllNodata:
                area.close()
                return _all_nodata(cfg, timer)
            d = area.source          # the place, the suns, the body: the context's
        else:
            try:
                d = cfg.read.read(cfg.dem)
            except AllNodata:     # every band all nodata, a note (a tile of the sea)
                return _all_nodata(cfg, timer)
    try:
        return _run(cfg, d, area, req, step, series, ran_on, lift, timer,
                    first if cfg.date is not None else None,
                    last if cfg.date is not None else None,
                    None if cfg.date is not None or req.auto_tz else (t0, t1, times, weights))
    finally:
        if area is not None:
            area.close()


def _run(cfg, d, area, req, step, series, ran_on, lift, timer, first, last, period_given):
    """The run once the DEM (``d``: in memory; with ``area``, the context opened for windows)
    is open: the suns, the sky, the sky view, the sums, the output and the report."""
    import numpy as np

    from ..engine import irradiance as ir
    from ..model.earth import dem_body
    from ..io import BandWriter, input_label, write_json, write_png
    from ..pictures.preview import relief_rgb, scaled
    from ..engine.shader import Shader
    from ..model.times import day_samples, iso
    from .report import progress

    ro, output = cfg.run, cfg.output
    if period_given is not None:
        t0, t1, times, weights = period_given
    with timer("prepare"):
        site = req.site(d, "irradiance computes the Earth's sun only")
        if req.auto_tz:          # the DEM's zone is known now
            if cfg.ghi is not None:
                series = ir.read_series(cfg.ghi, req.tz)
            if cfg.date is None:
                t0, t1, times, weights = _period(cfg, req.tz, step)
        if cfg.date is not None:
            try:
                times, weights = day_samples(first, last, cfg.step, req.tz, site.lon)
            except HillshadeError as exc:   # too many samples for the dates and the step
                raise UsageProblem(str(exc)) from None
            day = (f"midnight to midnight, {req.tz.key}" if req.tz is not None
                   else f"local mean solar time at longitude {site.lon:.4f}")
            period = (f"{first.isoformat()}" + (f" to {last.isoformat()}" if last > first
                                                  else "") + f" ({day})")
        else:
            period = f"{iso(t0)} to {iso(t1)}"
        hours = float(np.sum(weights))
        req.times = times
        suns, sun_info = req.suns(d, site)
        zen = np.array([s.zenith for s in suns], np.float64)
        if series is None:
            sky = ir.clear_sky(times, zen, site.lat, site.lon, site.height,
                               cfg.clear_sky or "ineichen", cfg.linke_turbidity)
        else:
            unix, *cols = series
            ghi, dni, dhi = ir.series_at(times, unix, *cols, path=cfg.ghi)
            sky = ir.measured_sky(times, zen, ghi, dni, dhi,
                                  f"measured: {os.path.basename(cfg.ghi)} (interpolated in "
                                  "time)")
        if cfg.perez:
            ir.with_perez(sky, times, zen)
        curvature = "auto" if cfg.curvature is None else cfg.curvature
        body = dem_body(d, req.lat)
        work = [s for s in suns if not ir.is_dark(s, cfg.soft)]
        if area is None:
            shader = Shader(d.heights, d.grid, cfg.algorithm, {}, ran_on, curvature,
                            cfg.refraction_k, body, d.height_range(), survey=d.survey(),
                            lift=lift)
            if work:
                shader.warm_up(work[0].azimuth, max(work[0].elevation, 1.0), soft=cfg.soft,
                               incidence=True, field=any(s.fieldwise for s in work))
    algo_stats: dict = {}
    bar = lambda it: progress(it, ro.quiet, "hillshade-rt irradiance", "sun",
                                mode=ro.progress)  # noqa: E731
    if area is None:
        with timer("sky view"):
            vd = ir.dozier_view(d.heights, d.grid, cfg.skyview_directions, ran_on, curvature,
                                cfg.refraction_k, body, lift)
        with timer("compute"):
            bands = ir.accumulate(shader, suns, weights, sky, vd, cfg.albedo, soft=cfg.soft,
                                  perez=cfg.perez, stats=algo_stats, timer=timer,
                                  progress=bar)
        curv = shader.report()
        geom = d
    else:
        bands, vd, curv, processing = _in_context(cfg, area, suns, weights, sky, work, ran_on,
                                                  curvature, body, lift, timer, algo_stats,
                                                  bar)
        geom = area.tile
    if cfg.mean:
        bands = {k: (v / np.float32(hours)).astype(np.float32) for k, v in bands.items()}
    units = ("W/m2, mean over the period" if cfg.mean
             else "Wh/m2, energy over the period")
    sky_model = "perez" if cfg.perez else "isotropic"
    tags = {"HILLSHADE_RT_VERSION": __version__, "UNITS": units, "PERIOD": period,
            "PERIOD_HOURS": f"{hours:g}", "STEP": cfg.step, "SAMPLES": len(suns),
            "SKY": sky.source, "SKY_MODEL": sky_model, "ALBEDO": f"{cfg.albedo:g}",
            "SKYVIEW_DIRECTIONS": cfg.skyview_directions, "SOFT": cfg.soft,
            "ALGORITHM": cfg.algorithm, "HEIGHT_ABOVE_GROUND_M": lift,
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
    unit = "W/m2" if cfg.mean else "Wh/m2"
    with timer("write"):
        with BandWriter(output, geom, len(ir.BANDS), "float32", -9999.0, tags,
                        overview_resampling="average", overwrite=ro.overwrite,
                        fmt=ro.fmt, co=ro.creation_options) as w:
            for i, k in enumerate(ir.BANDS, 1):
                v = bands[k]
                w.write(i, np.where(np.isnan(v), np.float32(-9999.0), v), k, {"UNITS": unit})
        if ro.preview is not None:     # the global band over the relief, 2nd..98th percentile
            write_png(ro.preview, relief_rgb(d.heights, d.grid, ramp=scaled(bands["global"])),
                      ro.overwrite)

    def summary(v):
        ok = v[~np.isnan(v)]
        return ({"min": float(ok.min()), "mean": float(ok.mean()), "max": float(ok.max())}
                if ok.size else {"min": None, "mean": None, "max": None})
    sec = dict(timer.seconds, total=timer.total())
    with_shadows = algo_stats.pop("samples_with_shadows", 0)
    algo_stats.pop("samples", None)
    rep = {"input": input_label(geom.path), "output": os.path.abspath(output),
           "shape": list(geom.shape), "algorithm": cfg.algorithm, "backend": ran_on,
           "period": period, "period_hours": hours, "step": cfg.step, "units": unit,
           "samples": len(suns), "samples_with_sun": len(work),
           "samples_with_shadows": with_shadows,
           "sky": sky.source, "sky_model": sky_model, "turbidity": sky.turbidity,
           "split": sky.split, "albedo": cfg.albedo,
           "skyview_directions": cfg.skyview_directions, "soft": cfg.soft,
           "height_above_ground_m": lift,
           "sky_view": summary(vd),
           "open_sky": {"dni_wh_m2": float(np.sum(np.asarray(weights) * sky.dni)),
                        "dhi_wh_m2": float(np.sum(np.asarray(weights) * sky.dhi)),
                        "ghi_wh_m2": float(np.sum(np.asarray(weights) * sky.ghi))},
           "bands": {k: summary(bands[k]) for k in ir.BANDS},
           "curvature": curv, "algorithm_stats": algo_stats,
           "seconds": sec, "version": __version__}
    rep.update(sun_info or {})
    if area is not None:
        rep["context"] = area.report()
        rep["processing"] = processing
    if ro.report_path is not None:
        write_json(ro.report_path, rep, ro.overwrite)
    if not ro.quiet:
        g = rep["bands"]["global"]
        ro.say("summary", f"hillshade-rt: {output}: {geom.shape[1]}x{geom.shape[0]}, {period}, "
                          f"{len(work)} of {len(suns)} samples with the sun up; global "
                          f"{g['min']:.1f} .. {g['max']:.1f} {unit} (mean {g['mean']:.1f}); "
                          f"shadows {sec.get('shadows', 0.0):.2f} s, sky view "
                          f"{sec['sky view']:.2f} s, total {sec['total']:.2f} s")
    return rep


def _in_context(cfg, area, suns, weights, sky, work, ran_on, curvature, body, lift, timer,
                algo_stats, bar):
    """The four bands of the tile of ``area`` (``--context``): each sun's cast shadows and
    incidence from the context's windows (``engine.windows.WindowLighting``, product "sun", the regions cut to
    the tile), Dozier's sky view from the windowed horizon march (``run.horizon_windows``: the rays to
    the context's edge), the slopes from the tile and a cell around it; then the same sums,
    cell by cell, as a run of the whole context in memory (``irradiance.sums``). Returns
    (bands, Vd, the curvature's report, the report's ``processing``)."""
    import math

    import numpy as np

    from ..engine import irradiance as ir
    from ..algorithms.relief import incidence
    from ..model.earth import curvature_report
    from ..model.geometry import equal_azimuths
    from .horizon import horizon_job, memory_limit, prepare_windows
    from .local import bounded_gdal_cache
    from ..engine.lighting import Lighting
    from ..engine.windows import (
        WindowLighting, WindowCache, bytes_per_cell, default_max_memory, window_budget, window_grid
    )
    from .horizon_windows import Figures, Product, region_outputs

    src = area.source
    rows, cols = src.shape
    r0, r1, c0, c1 = area.bounds
    fig = Figures()
    with bounded_gdal_cache():
        with timer("prepare"):
            bstats = area.block_stats()     # (the context's, kept between runs)
            dx, dy = src.grid.centre_spacing()
            lighting = Lighting(algorithm=cfg.algorithm, backend=ran_on, curvature=curvature,
                                refraction_k=cfg.refraction_k, soft=cfg.soft, lift=lift)
            job = WindowLighting(src, lighting, body, (bstats.zmin, bstats.zmax),
                                 math.hypot(cols * dx, rows * dy), "sun")
            budget = window_budget(default_max_memory(),
                                   bytes_per_cell(cfg.algorithm, "sun", cfg.soft))[0]
            if work:
                job.warm_up(work[0])
            azimuths = equal_azimuths(360.0 / int(cfg.skyview_directions))
            hjob, _ = horizon_job(src, azimuths, ran_on, curvature, cfg.refraction_k, "scan",
                                  bstats, False, 1, math.inf, lift, body=body)
        regs, _ = prepare_windows(src, hjob, memory_limit(None), None, timer, area)
        with src.reader() as rd:
            # the tile and a cell around it: its voids, and its slopes (Horn's normals) for
            # Perez
            m = (max(0, r0 - 1), min(rows, r1 + 1), max(0, c0 - 1), min(cols, c1 + 1))
            zm = np.empty((m[1] - m[0], m[3] - m[2]), np.float32)
            rd.read(m, zm)
            inner = (slice(r0 - m[0], r1 - m[0]), slice(c0 - m[2], c1 - m[2]))
            void = np.isnan(zm[inner])

            def slopes():
                cos_s = incidence(zm, window_grid(src.grid, m), 0.0, 90.0,
                                  *inner).astype(np.float64)
                return cos_s, np.sqrt(np.maximum(1.0 - cos_s * cos_s, 0.0))
            with timer("sky view"):       # Dozier's Vd of the tile's regions, as skyview's
                vd = np.empty(area.shape, np.float32)
                product = Product("skyview", definition="dozier")
                for reg in regs:
                    a0, a1, b0, b1 = area.local(reg)

                    def put(name, band, out, a0=a0, a1=a1, b0=b0, b1=b1):
                        vd[a0:a1, b0:b1] = out
                    fig.add(region_outputs(hjob, rd, reg, product, put))
            cache, used = WindowCache(rd), set()
            read = {"windows": 0, "cells": 0}

            def direct(s, timed):
                """max(cos i, 0) * lit over the tile, window by window of the sun's plan."""
                out = np.empty(area.shape, np.float32)
                with timed("shadows"):
                    pieces = job.pieces(s, bstats, budget, area=area.bounds)
                    carry = job.carrier([pieces])
                    for p in pieces:
                        lit, cosi = job.light_incidence(cache.get(p.window), p, algo_stats,
                                                        used, carry)
                        a0, a1, b0, b1 = area.local(p.region)
                        out[a0:a1, b0:b1] = np.maximum(cosi, np.float32(0.0)) * lit
                        read["windows"] += 1
                        read["cells"] += p.cells
                return out
            with timer("compute"):
                bands = ir.sums(direct, void, slopes, suns, weights, sky, vd, cfg.albedo,
                                soft=cfg.soft, perez=cfg.perez, stats=algo_stats, timer=timer,
                                progress=bar)
    processing = {"mode": "windows", "cells": area.shape[0] * area.shape[1],
                  "shadow_windows": read["windows"], "shadow_window_cells": read["cells"],
                  "sky_view": fig.as_dict()}
    return bands, vd, curvature_report(job.curvature, used, job.body, job.k), processing


def _all_nodata(cfg, timer) -> dict:
    """A DEM whose every cell is nodata: the four bands all -9999, a note; the report."""
    import numpy as np

    from ..engine import irradiance as ir
    from ..io import BandWriter, input_label, write_json
    from .context import nodata_note
    ro = cfg.run
    src = cfg.read.open(cfg.dem)
    src.close()
    tags = {"HILLSHADE_RT_VERSION": __version__, "NODATA": "-9999 (every cell of the DEM is "
            "nodata)"}
    with timer("write"), BandWriter(cfg.output, src, len(ir.BANDS), "float32", -9999.0, tags,
                                    overview_resampling="average", overwrite=ro.overwrite,
                                    fmt=ro.fmt, co=ro.creation_options) as w:
        arr = np.full(src.shape, -9999.0, np.float32)
        for i, k in enumerate(ir.BANDS, 1):
            w.write(i, arr, k)
    rep = {"input": input_label(src.path), "output": os.path.abspath(cfg.output),
           "shape": list(src.shape), "all_nodata": True,
           "bands": {k: {"min": None, "mean": None, "max": None} for k in ir.BANDS},
           "seconds": dict(timer.seconds, total=timer.total()), "version": __version__}
    if ro.report_path is not None:
        write_json(ro.report_path, rep, ro.overwrite)
    if not ro.quiet:
        ro.say("note", nodata_note(src.path))
    return rep


def _period(cfg, tz, step):
    """(t0, t1, times, weights) of --start..--end, local times in ``tz``, shown in it."""
    from ..engine import irradiance as ir
    from ..model.times import parse_time
    t0, t1 = parse_time(cfg.start, tz, "--start"), parse_time(cfg.end, tz, "--end")
    if tz is not None:     # shown in the zone of --tz
        t0, t1 = t0.astimezone(tz), t1.astimezone(tz)
    return (t0, t1, *ir.period_samples(t0, t1, step))
