"""``irradiance --time T`` / ``--instant``: the irradiance at instants (GRASS r.sun's mode 1)
instead of a period's sums. For each time, five float32 bands: beam, diffuse, reflected and
global irradiance in W/m², and the sun's elevation above each cell's surface in degrees (r.sun's
incidout; ``engine.irradiance.surface_elevation``), -9999 nodata. An OUTPUT named ``*.nc`` or
``*.zarr`` is one CF-1.8 time cube instead (``io.cube``): the five quantities as data variables
on (time, y, x) under r.sun's names (beam_rad, diff_rad, refl_rad, glob_rad, incidout), the
same float32 values, the sun and the open sky per time.

The physics are the period run's (``engine.irradiance.instant``: one sample of
``accumulate``'s sums, alone, with weight 1: its contribution in W/m²), on the same Shader,
Horn normals and Dozier sky view (computed once, or read with ``--sky-view``), the same suns
(the SPA per tile) and the same open sky (pvlib's clear sky or the ``--ghi`` series). So the
period run's Wh/m² is the sum over its sample times of these bands times each sample's hours
(``--instant --date D`` writes the instants at exactly those sample times).

The times: ``--time`` (repeated), or with ``--instant`` the series ``--start``,
``--start + --step``, ... up to ``--end`` (included when a step lands on it; as the shadow
command's series), or ``--date [--end-date]``'s sample times (the middle of each step, as the
period run samples them). The DEM is held in memory (``--context`` is not taken).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import IrradianceConfig
from .runner import RunContext


@dataclass
class _Asked:
    """The command line's instants, checked before the DEM is read: the sun request (its
    ``times`` the instants of --time or --start/--end/--step, read again in the DEM's zone with
    --tz auto), the days of ``--instant --date`` (None otherwise), the ``--ghi`` series."""

    req: object
    first: object = None
    last: object = None
    series: tuple | None = None


def irradiance_or_instants(cfg: IrradianceConfig) -> dict:
    """The run ``cfg`` asks for: the instants of ``--time`` or ``--instant``
    (:func:`irradiance_instant`), else the period's sums (``run.irradiance.irradiance``)."""
    if cfg.instants():
        return irradiance_instant(cfg)
    from .irradiance import irradiance
    return irradiance(cfg)


def irradiance_instant(cfg: IrradianceConfig) -> dict:
    """Write each instant's five bands (``engine.irradiance.INSTANT_BANDS``) of ``cfg.dem`` to
    ``cfg.output``; returns the report."""
    from ..engine import irradiance as ir
    ro = cfg.run
    cfg.check()
    cube = use_cube(cfg)
    cfg.read.check_context(cfg.dem, **{"--time or --instant": True})
    ctx = RunContext.start(ro, inputs=[cfg.dem, cfg.ghi, cfg.sky_view] + cfg.read.inputs()
                           + cfg.sky_inputs(),
                           outputs=[(cfg.output, "OUTPUT"),
                                    (cfg.sky_view_out, "--sky-view-out")],
                           algorithm=cfg.algorithm, note=False)
    asked = _asked(cfg)
    if not cube:
        _check_format(cfg, len(ir.INSTANT_BANDS) * max(1, len(asked.req.times)))
    ctx.compile_note(cfg.algorithm, True)
    lighting = cfg.lighting(ctx.backend)
    with ctx.timer("read"):
        d = cfg.read.read(cfg.dem)      # (AllNodata: a DEM of nodata has no instant to write)
    return _run(cfg, ctx, lighting, asked, d, cube)


def _asked(cfg: IrradianceConfig) -> _Asked:
    """The instants and the place of the command line (a bad one: a usage error, exit status
    2), and the ``--ghi`` series (a bad file fails the run, exit status 1)."""
    from ..engine import irradiance as ir
    from ..model.sun import SunRequest
    from ..model.times import parse_date, parse_step
    try:
        parse_step(cfg.step)
        if cfg.date is not None:
            first = parse_date(cfg.date, "--date")
            last = parse_date(cfg.end_date, "--end-date") if cfg.end_date is not None else first
            if last < first:
                raise HillshadeError("--end-date is before --date")
            asked = _Asked(SunRequest.at_place([], **cfg.place), first, last)
        else:
            by_time = bool(cfg.times)
            asked = _Asked(SunRequest.from_options(
                time=cfg.times, start=None if by_time else cfg.start,
                end=None if by_time else cfg.end, step=None if by_time else cfg.step,
                **cfg.place))
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    if cfg.ghi is not None and not asked.req.auto_tz:
        asked.series = ir.read_series(cfg.ghi, asked.req.tz)
    return asked


def _check_format(cfg: IrradianceConfig, bands: int) -> None:
    """The output's format holds ``bands`` float32 bands (not a picture, not a one-grid
    format)."""
    from ..io import check_output_format, output_driver
    from .irradiance import ONE_BAND_FORMATS
    ro, output = cfg.run, cfg.output
    driver = output_driver(output, ro.fmt)
    if driver in ONE_BAND_FORMATS:
        raise HillshadeError(f"{output}: {driver} holds one band of integers or one grid; "
                             f"irradiance --time/--instant writes {bands} float32 bands (5 per "
                             "time): write a GeoTIFF (.tif)")
    check_output_format(output, driver, "float32", bands, True, ro.creation_options)


def _times(cfg: IrradianceConfig, asked: _Asked, site) -> list:
    """The instants at the DEM's place: --time's or the series' (the request's, read in the
    DEM's zone with --tz auto), or the sample times of --date's days."""
    if cfg.date is None:
        return list(asked.req.times)
    from ..model.times import day_samples
    try:
        times, _ = day_samples(asked.first, asked.last, cfg.step, asked.req.tz, site.lon)
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    return times


def _run(cfg: IrradianceConfig, ctx: RunContext, lighting, asked: _Asked, d,
         cube: bool = False) -> dict:
    """The suns and the sky at each instant, the sky view, each instant's bands written as
    they are made, the report."""
    import numpy as np

    from ..algorithms.irradiance import normals
    from ..engine import irradiance as ir
    from ..model.earth import dem_body
    from .irradiance import open_sky, open_sky_cells, read_sky_view, write_sky_view
    from .report import progress
    ro, req, timer = ctx.ro, asked.req, ctx.timer
    with timer("prepare"):
        site = req.site(d, "irradiance computes the Earth's sun only")
        if req.auto_tz and cfg.ghi is not None:       # the DEM's zone is known now
            asked.series = ir.read_series(cfg.ghi, req.tz)
        times = _times(cfg, asked, site)
        req.times = times
        suns, sun_info = req.suns(d, site)
        cells = None
        if cfg.sky_per_cell():       # the open sky per cell (rasters): on the DEM's grid
            sky, cells = open_sky_cells(cfg, times, suns, site, req.tz, d, ~np.isnan(d.heights))
        else:
            sky = open_sky(cfg, times, suns, site, asked.series, req.tz)
        body = dem_body(d, req.lat)
        shader = lighting.shader(d.heights, d.grid, body=body, zrange=d.height_range(),
                                 survey=d.survey())
        work = [s for s in suns if not ir.is_dark(s, cfg.soft)]
        if work:
            shader.warm_up(work[0].azimuth, max(work[0].elevation, 1.0), soft=lighting.soft,
                           incidence=True, field=any(s.fieldwise for s in work))
        nrm = normals(d.heights, d.grid)      # Horn's normals once: the sky view's and the suns'
    vd, vd_tags = _sky_view(cfg, ctx, d, shader, lighting, body, nrm, read_sky_view,
                            write_sky_view)
    tags = _tags(cfg, lighting, req, times, sky)
    texts = band_texts(times)
    stats: dict = {}
    summaries = {k: None for k in ir.INSTANT_BANDS}
    per_time = []
    preview = None
    n = len(ir.INSTANT_BANDS)
    loop = progress(range(len(times)), ro.quiet, "hillshade-rt irradiance", "instant",
                    mode=ro.progress)
    with _writer(cfg, d, times, suns, sky, tags, cube) as w:
        albedo_of = _albedo_of(cfg, d, times, req.tz, site.lon)
        for k in loop:
            with timer("compute"):
                bands = ir.instant(shader, suns[k], sky, k, vd, albedo_of(k), soft=lighting.soft,
                                   perez=cfg.perez, stats=stats, timer=timer, normals=nrm,
                                   cells=cells)
            per_time.append(_instant_report(times[k], suns[k], sky, k, bands["global"]))
            for q, v in bands.items():
                summaries[q] = _merge(summaries[q], v)
            up = not ir.is_dark(suns[k], cfg.soft)
            if ro.preview is not None and (preview is None or (up and not preview[0])):
                preview = (up, bands["global"])     # the first instant with the sun up
            with timer("write"):
                for j, q in enumerate(ir.INSTANT_BANDS):
                    text, btags = texts[k * n + j]
                    v = bands[q]
                    w.write(k * n + j + 1, np.where(np.isnan(v), np.float32(-9999.0), v), text,
                            btags)
    if ro.preview is not None:
        from ..io import write_png
        from ..pictures.preview import relief_rgb, scaled
        with timer("write"):
            write_png(ro.preview, relief_rgb(d.heights, d.grid, ramp=scaled(preview[1])),
                      ro.overwrite)
    rep = _report(cfg, ctx, d, times, work, sky, vd, vd_tags, stats, summaries, per_time,
                  shader, sun_info)
    sec, g = rep["seconds"], rep["bands"]["global"]
    span = times[0].isoformat() if len(times) == 1 else \
        f"{times[0].isoformat()} .. {times[-1].isoformat()}"
    gtext = (f"global {g['min']:.1f} .. {g['max']:.1f} W/m2" if g["min"] is not None
             else "no valid cell")
    return ctx.finish(rep, [(
        "summary", f"hillshade-rt: {cfg.output}: {d.shape[1]}x{d.shape[0]}, {len(times)} "
                   f"instant{'s' if len(times) != 1 else ''} ({span}), {len(work)} with the sun "
                   f"up; {gtext}; shadows {sec.get('shadows', 0.0):.2f} s, sky view "
                   f"{sec.get('sky view', 0.0):.2f} s, total {sec['total']:.2f} s")])


def _sky_view(cfg, ctx, d, shader, lighting, body, nrm, read_vd, write_vd):
    """(Dozier's Vd, the tags of the file it was read from or None), as the period run has it:
    read with --sky-view, or computed on the Shader's pyramid and the normals (and written with
    --sky-view-out)."""
    from ..engine import irradiance as ir
    from ..engine.shader import horizon_shader
    hs = horizon_shader(d.heights, d.grid, lighting.backend, lighting.curvature,
                        lighting.refraction_k, body)
    with ctx.timer("sky view"):
        if cfg.sky_view is not None:
            return read_vd(cfg, d, hs, None, d.heights)
        pyramid = shader.pyramid(shader.z, True) if lighting.backend == "cpu" else None
        vd = ir.dozier_view(d.heights, d.grid, cfg.skyview_directions, lighting.backend,
                            lighting.curvature, lighting.refraction_k, body, lighting.lift,
                            pyramid=pyramid, normals=nrm)
    if cfg.sky_view_out is not None:
        write_vd(cfg, ctx, d, vd, hs, None, d.heights)
    return vd, None


def band_texts(times) -> list[tuple[str, dict]]:
    """Each band's description and tags, 5 per time in ``INSTANT_BANDS``' order: r.sun's name
    and the time (these are r.sun's mode 1 products: W/m² at an instant, the incidence angle
    in degrees), the tags NAME (ours), RSUN_NAME, TIME and UNITS."""
    from ..engine import irradiance as ir
    from ..model.times import iso
    out = []
    for t in times:
        for q in ir.INSTANT_BANDS:
            units = "degrees" if q == "incidence" else "W/m2"
            out.append((f"{ir.RSUN_NAMES[q]} {iso(t)}",
                        {"NAME": q, "RSUN_NAME": ir.RSUN_NAMES[q], "TIME": iso(t),
                         "UNITS": units}))
    return out


def _tags(cfg: IrradianceConfig, lighting, req, times, sky) -> dict:
    """The output's metadata."""
    from ..engine import irradiance as ir
    from ..model.times import iso
    from .irradiance import sky_input_tags
    sky_model = "perez" if cfg.perez else "isotropic"
    tags = {"HILLSHADE_RT_VERSION": __version__,
            "UNITS": "W/m2 at each instant (beam, diffuse, reflected, global); incidence: "
                     "degrees",
            "MODE": "instants (r.sun mode 1), not a period's sums",
            "TIMES": ",".join(iso(t) for t in times), "INSTANTS": len(times),
            "BANDS_PER_TIME": ",".join(ir.INSTANT_BANDS),
            "BAND_ORDER": f"band 5 k + j + 1: time k (0-based), quantity j of "
                          f"{','.join(ir.INSTANT_BANDS)}",
            "SKY": sky.source, "SKY_MODEL": sky_model, "ALBEDO": cfg.albedo_input.describe(),
            **sky_input_tags(cfg),
            "SKYVIEW_DIRECTIONS": cfg.skyview_directions, "SOFT": cfg.soft,
            "ALGORITHM": cfg.algorithm, "HEIGHT_ABOVE_GROUND_M": lighting.lift,
            "DEFINITIONS": ir.definitions(sky_model, cfg.skyview_directions, cfg.soft)
                           + "; incidence = 90 - i = asin(cos i), the sun's elevation above the "
                             "cell's surface (r.sun's incidout; here also in cast shadow and "
                             "negative behind the surface)",
            "SUN": "NREL SPA (pvlib.spa) at the DEM's centre, per tile where it varies; "
                   + ("apparent (refracted) elevation" if req.atmosphere.refraction
                      else "true elevation (--no-refraction)"),
            "EDGE": "no terrain beyond the raster: border cells see open sky outward"}
    if cfg.ghi is None:
        tags["CLEAR_SKY"] = cfg.clear_sky or "ineichen"
        tags["TURBIDITY"] = sky.turbidity or "none (Haurwitz takes none)"
    if sky.split:
        tags["SPLIT"] = sky.split
    return tags


def _merge(acc, v):
    """min, sum, count, max of the valid cells of ``v`` added to ``acc`` (None: nothing yet)."""
    import numpy as np
    ok = v[~np.isnan(v)]
    if not ok.size:
        return acc
    one = (float(ok.min()), float(ok.sum(dtype=np.float64)), int(ok.size), float(ok.max()))
    if acc is None:
        return one
    return (min(acc[0], one[0]), acc[1] + one[1], acc[2] + one[2], max(acc[3], one[3]))


def _as_summary(acc) -> dict:
    if acc is None:
        return {"min": None, "mean": None, "max": None}
    return {"min": acc[0], "mean": acc[1] / acc[2], "max": acc[3]}


def _instant_report(t, sun, sky, k, glob) -> dict:
    """One instant in the report: its time, the sun at the DEM's centre, the open sky, the
    global band's figures."""
    from ..model.times import iso
    return {"time": iso(t), "sun": {"azimuth": float(sun.azimuth),
                                    "elevation": float(sun.elevation)},
            "open_sky": {"dni_w_m2": float(sky.dni[k]), "dhi_w_m2": float(sky.dhi[k]),
                         "ghi_w_m2": float(sky.ghi[k])},
            "global": _as_summary(_merge(None, glob))}


def _report(cfg, ctx, d, times, work, sky, vd, vd_tags, stats, summaries, per_time, shader,
            sun_info) -> dict:
    """The run's report (``--report``)."""
    from ..io import input_label
    from .irradiance import sky_input_report
    rep = {"input": input_label(d.path), "output": os.path.abspath(cfg.output),
           "shape": list(d.shape), "algorithm": cfg.algorithm, "backend": ctx.backend,
           "mode": "instants", "units": "W/m2", "incidence_units": "degrees",
           "instants": len(times), "instants_with_sun": len(work),
           "instants_with_shadows": stats.get("samples_with_shadows", 0),
           "sky": sky.source, "sky_model": "perez" if cfg.perez else "isotropic",
           "turbidity": sky.turbidity, "split": sky.split, "albedo": (cfg.albedo_input.number if cfg.albedo_input.number is not None
                      else cfg.albedo_input.describe()),
           **sky_input_report(cfg),
           "skyview_directions": cfg.skyview_directions, "soft": cfg.soft,
           "height_above_ground_m": float(cfg.height_above_ground),
           "sky_view": _as_summary(_merge(None, vd)),
           "sky_view_from": "computed" if vd_tags is None else "read",
           "sky_view_file": (os.path.abspath(cfg.sky_view) if cfg.sky_view is not None else
                             os.path.abspath(cfg.sky_view_out) if cfg.sky_view_out is not None
                             else None),
           "times": per_time,
           "bands": {k: _as_summary(v) for k, v in summaries.items()},
           "curvature": shader.report(), "seconds": ctx.seconds(), "version": __version__}
    rep.update(sun_info or {})
    if vd_tags is not None:
        rep["sky_view_made_by"] = vd_tags.get("HILLSHADE_RT_VERSION")
    return rep


def _albedo_of(cfg, d, times, tz, lon):
    """The albedo at instant k (``run.sky_inputs``): the number, its month's number, or the
    raster of its month on the DEM's grid (each month's read once)."""
    import numpy as np

    from .sky_inputs import local_months
    a = cfg.albedo_input
    if a.number is not None:
        return lambda k: a.number
    months = local_months(times, tz, lon)
    valid = ~np.isnan(d.heights) if a.rasters else None
    seen: dict = {}

    def of(k):
        m = int(months[k]) if a.by_month else 1
        if m not in seen:
            seen[m] = a.on_grid(m, d.transform, d.crs, d.shape, valid)
        return seen[m]
    return of


# -- OUTPUT.nc / OUTPUT.zarr: the instants as one CF time cube (io.cube) -------------------------

NODATA = -9999.0
# each quantity's variable in a time cube (r.sun's names, ``engine.irradiance.RSUN_NAMES``):
# (long name, CF units)
CUBE_QUANTITIES = {
    "beam": ("beam (direct) irradiance on the cell's surface, 0 in cast shadow", "W m-2"),
    "diffuse": ("diffuse sky irradiance on the cell's surface", "W m-2"),
    "reflected": ("irradiance reflected by the terrain onto the cell's surface", "W m-2"),
    "global": ("global irradiance on the cell's surface (beam + diffuse + reflected)", "W m-2"),
    "incidence": ("the sun's elevation above the cell's surface (90 - angle of incidence; "
                  "negative behind the surface)", "degree"),
}


def use_cube(cfg: IrradianceConfig) -> bool:
    """Whether OUTPUT is a time cube (``io.cube.cube_output``: ``*.nc`` or ``*.zarr`` without
    --format; --co refused then, a missing library named, before any work)."""
    from ..io.cube import cube_output
    return cube_output(cfg.output, cfg.run.fmt, cfg.run.creation_options) is not None


def cube_variables() -> list:
    """The cube's data variables (``io.cube.CubeVariable``), in ``INSTANT_BANDS``' order:
    ``beam_rad``, ``diff_rad``, ``refl_rad``, ``glob_rad`` (W m-2) and ``incidout``
    (degree), float32, -9999 the _FillValue of the voids."""
    from ..engine import irradiance as ir
    from ..io.cube import CubeVariable
    out = []
    for q in ir.INSTANT_BANDS:
        what, units = CUBE_QUANTITIES[q]
        out.append(CubeVariable(ir.RSUN_NAMES[q], "float32", NODATA,
                                {"long_name": what, "units": units, "quantity": q}))
    return out


def sky_variables(sky, count: int) -> dict:
    """The open sky at each instant, a cube's per-time variables (W m-2)."""
    import numpy as np
    return {f"open_sky_{k}": (np.asarray(getattr(sky, k)[:count], np.float64),
                              {"long_name": f"{what} of the open sky at the instant",
                               "units": "W m-2"})
            for k, what in (("ghi", "global horizontal irradiance"),
                            ("dni", "direct normal irradiance"),
                            ("dhi", "diffuse horizontal irradiance"))}


def _writer(cfg: IrradianceConfig, d, times, suns, sky, tags: dict, cube: bool):
    """OUTPUT's writer, taking the bands in the GeoTIFF's order (5 per time): a GeoTIFF's (or
    --format's) bands (``io.BandWriter``), or one CF time cube of five data variables
    (``io.cube.CubeWriter``, each with its units) with the sun and the open sky per time, the
    GeoTIFF's tags its global attributes but for its band order and units."""
    ro = cfg.run
    if not cube:
        from ..io import BandWriter
        from ..engine.irradiance import INSTANT_BANDS
        return BandWriter(cfg.output, d, len(INSTANT_BANDS) * len(times), "float32", NODATA,
                          tags, overview_resampling="average", overwrite=ro.overwrite,
                          fmt=ro.fmt, co=ro.creation_options)
    from ..io.cube import CubeWriter
    from .outputs import cube_globals, sun_variables
    return CubeWriter(cfg.output, d, times, variables=cube_variables(),
                      time_variables={**sun_variables(suns), **sky_variables(sky, len(times))},
                      global_attrs=cube_globals("hillshade-rt: irradiance at instants",
                                                {k: v for k, v in tags.items()
                                                 if k not in ("UNITS", "BAND_ORDER")},
                                                cfg.command),
                      overwrite=ro.overwrite)


def in_memory(cfg: IrradianceConfig, d) -> dict:
    """The instants of ``cfg`` on the DEM ``d`` (an ``io.Dem`` in memory) as
    :func:`irradiance_instant` makes them, nothing written (``xarray.accessor.irradiance``):
    "bands" ({quantity of ``engine.irradiance.INSTANT_BANDS``: a float32 array per time, NaN
    voids}), "times", "suns" (``model.sun.SunOver``), "sky" (``engine.irradiance.Sky``)."""
    from ..algorithms.irradiance import normals
    from ..engine import irradiance as ir
    from ..model.earth import dem_body
    from .irradiance import open_sky, read_sky_view, write_sky_view
    if not cfg.instants():
        raise UsageProblem("a period's sums are run.irradiance's run")
    cfg.check()
    ctx = RunContext.start(cfg.run, algorithm=cfg.algorithm, note=False)
    asked = _asked(cfg)
    lighting = cfg.lighting(ctx.backend)
    req = asked.req
    site = req.site(d, "irradiance computes the Earth's sun only")
    if req.auto_tz and cfg.ghi is not None:
        asked.series = ir.read_series(cfg.ghi, req.tz)
    times = _times(cfg, asked, site)
    req.times = times
    suns, _ = req.suns(d, site)
    sky = open_sky(cfg, times, suns, site, asked.series, req.tz)
    body = dem_body(d, req.lat)
    shader = lighting.shader(d.heights, d.grid, body=body, zrange=d.height_range(),
                             survey=d.survey())
    work = [s for s in suns if not ir.is_dark(s, cfg.soft)]
    if work:        # (as _run)
        shader.warm_up(work[0].azimuth, max(work[0].elevation, 1.0), soft=lighting.soft,
                       incidence=True, field=any(s.fieldwise for s in work))
    nrm = normals(d.heights, d.grid)
    vd, _ = _sky_view(cfg, ctx, d, shader, lighting, body, nrm, read_sky_view, write_sky_view)
    albedo_of = _albedo_of(cfg, d, times, req.tz, site.lon)
    out: dict = {q: [] for q in ir.INSTANT_BANDS}
    for k in range(len(times)):
        bands = ir.instant(shader, suns[k], sky, k, vd, albedo_of(k), soft=lighting.soft,
                           perez=cfg.perez, stats={}, timer=ctx.timer, normals=nrm)
        for q in ir.INSTANT_BANDS:
            out[q].append(bands[q])
    return {"bands": out, "times": list(times), "suns": list(suns), "sky": sky}
