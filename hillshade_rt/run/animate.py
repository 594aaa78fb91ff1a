"""The ``animate`` run: the shadows of a DEM over a day (or any series of times) as a GIF or an
MP4, shaded relief with the cast shadows tinted and the local time written on each frame
(``animation``: the frames and their encoding). Returns the report.

The shadows are computed at the DEM's full resolution, one ``shading.Shader`` prepared once and
rendered per time (the ``shadow`` command's mask for that time, cell for cell), and the picture
takes every n-th cell of the DEM and of each mask (at most ``size`` pixels on the long side).
Shadows computed on a decimated DEM would be cheaper for a big DEM but different: ridges lower,
thin shadows lost or widened; the animation shows the masks the tool writes. The DEM is read
whole (in memory); the frames are kept (one byte per pixel) until they are encoded.

The run's steps, between the shared preamble and tail (``run.runner.RunContext``): the times,
the DEM read, the suns at its place, the Shader prepared (``AnimateConfig.lighting``, passed
whole), the picture's cells, the frames, the encoding, the report.
"""

from __future__ import annotations

import datetime as _dt
import os
from dataclasses import dataclass

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import AnimateConfig
from .runner import RunContext

DEFAULT_STEP = "30min"
MAX_FRAMES = 2000


def times_of(cfg: AnimateConfig):
    """The SunRequest with its times (a series), or without (a day: :func:`day_times` fills
    them in once the DEM's place is known); too many frames refused before the DEM is read."""
    from ..model.sun import SunRequest
    from ..model.times import AUTO_ZONE, parse_date, parse_step
    step = cfg.step or DEFAULT_STEP
    # the labels' local time: --tz, else the zone of the DEM's centre (--tz auto)
    place = dict(cfg.place)
    if place.get("tz") is None:
        place["tz"] = AUTO_ZONE
    try:
        if cfg.date is not None:
            parse_date(cfg.date, "--date")
            count = -(-_dt.timedelta(hours=23) // parse_step(step))    # at least, before the
            req = SunRequest.at_place([], **place)                     # place is known
        else:
            req = SunRequest.from_options(start=cfg.start, end=cfg.end, step=step, **place)
            count = len(req.times)
    except HillshadeError as exc:     # the command line alone decides these: exit 2
        raise UsageProblem(str(exc)) from None
    check_count(count)
    return req


def check_count(count: int) -> None:
    if count > MAX_FRAMES:
        raise UsageProblem(f"{count} frames: more than {MAX_FRAMES}; use a longer --step or a "
                           "shorter series")


def day_times(day: _dt.date, step: str, tz, lon: float) -> list[_dt.datetime]:
    """Local midnight of ``day``, then every ``step`` (elapsed time) before the next midnight:
    in zone ``tz`` (a day of a clock change has 23 or 25 hours), or in local mean solar time at
    ``lon`` when ``tz`` is None (UTC instants)."""
    from ..model.times import UTC, day_start, parse_step
    dt = parse_step(step)
    one = _dt.timedelta(days=1)
    if tz is not None:
        t0, t1 = day_start(day, tz), day_start(day + one, tz)
    else:
        t0 = _dt.datetime.combine(day, _dt.time(0), UTC) - _dt.timedelta(hours=lon / 15.0)
        t1 = t0 + one
    n = -((t0 - t1) // dt)        # ceil((t1 - t0) / dt)
    return [(t0 + i * dt).astimezone(tz) if tz is not None else t0 + i * dt for i in range(n)]


@dataclass
class _Picture:
    """What every frame shares: every ``n``-th cell of the DEM (``zs`` on ``grid``, its voids
    ``void``) and the relief's levels at night (lit from the north-west)."""

    n: int
    zs: object
    grid: object
    void: object
    night_levels: object


@dataclass
class _Frames:
    """The frames (palette indices, one byte a pixel) and each time's record for the report."""

    frames: list
    records: list


def animate(cfg: AnimateConfig) -> dict:
    """Write the animation of ``cfg.dem``'s shadows to ``cfg.output``; returns the report."""
    ro = cfg.run
    fmt = cfg.check()
    ctx = RunContext.start(ro, inputs=[cfg.dem], outputs=[(cfg.output, "OUTPUT")],
                           algorithm=cfg.algorithm, note=False)
    req = times_of(cfg)
    lighting = cfg.lighting(ctx.backend)
    with ctx.timer("read"):
        d = cfg.read.read(cfg.dem)
    with ctx.timer("prepare"):
        site, suns, sun_info = _suns(cfg, req, d)
        shader = _prepare(ctx, d, lighting, req, suns)
        picture = _picture(d, cfg.size)
    lmt = site.lon if req.tz is None and cfg.date is not None else None
    algo_stats: dict = {}
    made = _frames(cfg, ctx, shader, suns, picture, lmt, algo_stats)
    _encode(cfg, ctx, fmt, made.frames)
    rep = _report(cfg, ctx, fmt, d, req, lmt, picture, made, shader, algo_stats, sun_info)
    sec = ctx.timer.seconds
    rows, cols = rep["picture"]
    return ctx.finish(rep, [(
        "summary", f"hillshade-rt: {cfg.output}: {rep['frames']} frames "
                   f"({rep['night_frames']} at night) of {cols}x{rows} from "
                   f"{d.shape[1]}x{d.shape[0]}, {cfg.fps:g} fps; shadows "
                   f"{sec.get('compute', 0.0):.2f} s, frames {sec.get('frames', 0.0):.2f} s, "
                   f"encoding {sec['encode']:.2f} s")])


def _suns(cfg: AnimateConfig, req, d) -> tuple:
    """(site, suns, sun_info): the suns of the times at the DEM's place (a day's times once
    its place is known)."""
    from ..model.times import parse_date
    site = req.site(d, "animate computes the Earth's sun from times (light a DEM of "
                       "another body with shadow, which takes the sun's direction)")
    if cfg.date is not None:
        req.times = day_times(parse_date(cfg.date), cfg.step or DEFAULT_STEP, req.tz,
                              site.lon)
    check_count(len(req.times))
    suns, sun_info = req.suns(d, site)
    return site, suns, sun_info


def _prepare(ctx: RunContext, d, lighting, req, suns):
    """The Shader of the DEM, warmed up for the first sun of the day (the compile note
    first)."""
    from ..model.earth import dem_body
    shader = lighting.shader(d.heights, d.grid, body=dem_body(d, req.lat),
                             zrange=d.height_range(), survey=d.survey())
    day = [s for s in suns if not s.night]
    if day:
        ctx.compile_note(lighting.algorithm)
        shader.warm_up(day[0].azimuth, day[0].elevation, field=any(s.fieldwise for s in day))
    return shader


def _picture(d, size: int) -> _Picture:
    """Every n-th cell of the DEM, at most ``size`` pixels on the long side."""
    import numpy as np

    from ..pictures.animation import relief_levels, step_of, subsample
    n = step_of(d.shape, size)
    zs, gs = subsample(d.heights, d.grid, n)
    return _Picture(n, zs, gs, np.isnan(zs), relief_levels(zs, gs, 315.0, 45.0))


def _frames(cfg: AnimateConfig, ctx: RunContext, shader, suns, pic: _Picture, lmt,
            algo_stats: dict) -> _Frames:
    """A frame per sun: the relief lit by it with its cast shadows (``render``, the shadow
    command's mask) tinted, dark at night, the local time written (``lmt``: the longitude of
    local mean solar time, else the times' zone)."""
    from ..engine.shader import render
    from ..pictures.animation import draw_label, frame_indices, label_text, relief_levels
    from .report import progress
    ro, timer, n = ctx.ro, ctx.timer, pic.n
    frames, records = [], []
    for sun in progress(suns, ro.quiet, "hillshade-rt animate", unit="frame",
                        mode=ro.progress):
        with timer("compute"):
            mask = None if sun.night else render(shader, sun, "shadow", stats=algo_stats)
        with timer("frames"):
            if mask is None:
                idx = frame_indices(pic.night_levels, None, pic.void)
            else:
                levels = relief_levels(pic.zs, pic.grid, sun.azimuth, sun.elevation)
                idx = frame_indices(levels, mask[::n, ::n], pic.void)
            if cfg.label:
                idx = draw_label(idx, label_text(sun.time, sun.night, lmt))
        frames.append(idx)
        rec = {"time": sun.time.isoformat(timespec="seconds"), "azimuth": sun.azimuth,
               "elevation": sun.elevation, "night": sun.night}
        if mask is not None:
            valid = mask != 255
            rec["shadow_fraction"] = (float((mask[valid] == 1).mean()) if valid.any() else None)
        records.append(rec)
    return _Frames(frames, records)


def _encode(cfg: AnimateConfig, ctx: RunContext, fmt: str, frames: list) -> None:
    """The frames encoded as a GIF or an MP4 (atomically: a failed encoding leaves nothing)."""
    from ..io.write import atomic_path
    from ..pictures.animation import write_gif, write_mp4
    with ctx.timer("encode"):
        with atomic_path(cfg.output, fmt, overwrite=ctx.ro.overwrite) as tmp:
            try:
                (write_gif if fmt == ".gif" else write_mp4)(tmp, frames, cfg.fps)
            except (OSError, RuntimeError, ValueError) as exc:
                msg = str(exc).strip().splitlines()
                raise HillshadeError(f"{cfg.output}: cannot write the animation "
                                     f"({msg[0] if msg else type(exc).__name__})") from None


def _report(cfg: AnimateConfig, ctx: RunContext, fmt: str, d, req, lmt, pic: _Picture,
            made: _Frames, shader, algo_stats: dict, sun_info) -> dict:
    """The run's report (``--report``)."""
    from ..io import input_label
    rows, cols = made.frames[0].shape
    rep = {"input": input_label(d.path), "output": os.path.abspath(cfg.output),
           "format": fmt[1:], "shape": list(d.shape), "picture": [rows, cols],
           "every_nth_cell": pic.n, "frames": len(made.frames),
           "night_frames": sum(1 for r in made.records if r["night"]), "fps": cfg.fps,
           "label": cfg.label,
           "label_time": ("local mean solar time" if lmt is not None else
                          (getattr(req.tz, "key", str(req.tz)) if req.tz is not None
                           else "the times' own offsets")
                          + (" (the DEM's zone)" if req.auto_tz and req.tz is not None
                             else "")),
           "algorithm": cfg.algorithm, "backend": ctx.backend, "times": made.records,
           "curvature": shader.report(), "algorithm_stats": algo_stats,
           "seconds": ctx.seconds(), "version": __version__}
    rep.update(sun_info or {})
    return rep
