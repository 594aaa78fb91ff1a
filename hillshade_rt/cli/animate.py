"""``hillshade-rt animate``: options -> ``run.animate.AnimateConfig`` -> ``run.animate``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from ..run.config import PLACE_KEYS
from .options import (SectionedCommand, algorithm_option, animation_options, backend_option,
                      curvature_options, dem_options, overwrite_option, place_options,
                      progress_option, quiet_option, report_option,
                      threads_option, to_read_options, to_run_options)


@click.command("animate", cls=SectionedCommand)
@click.argument("dem", type=click.Path())
@click.argument("output", type=click.Path())
@animation_options
@place_options("animate")
@algorithm_option
@curvature_options
@backend_option
@threads_option
@report_option
@overwrite_option("Replace OUTPUT (and the report) if they exist.")
@quiet_option("No progress bar or summary on stderr.")
@progress_option
@dem_options
@errors_to_click
def animate(dem, output, date_, start, end, step, fps, size, label, tz, lat, lon, pressure,
            temperature, no_refraction, sun_tolerance, algorithm, curvature, refraction_k,
            backend, threads, report_path, overwrite, quiet, progress, **read_opts):
    """Write an animation of the shadows on DEM over a day (--date) or a series of times
    (--start/--end/--step) to OUTPUT: a looping GIF, or an MP4 (needs the video extra: pip
    install 'hillshade-rt[video]'). Each frame is the shaded relief, lit by that time's sun, with
    the cast shadows tinted blue (the shadow command's mask for that time, at every n-th cell),
    dark at night, and the date and local time in the top-left corner (--no-label: none)."""
    from ..run.config import AnimateConfig
    from ..run.animate import animate as run_animate
    kw = dict(tz=tz, lat=lat, lon=lon, pressure=pressure, temperature=temperature,
              no_refraction=no_refraction, sun_tolerance=sun_tolerance, backend=backend,
              threads=threads, report_path=report_path, overwrite=overwrite, quiet=quiet,
              progress=progress,
              **read_opts)
    place = {k: kw.pop(k) for k in PLACE_KEYS}
    run_animate(AnimateConfig(dem=dem, output=output, date=date_, start=start, end=end,
                              step=step, place=place, fps=fps, size=size, label=label,
                              algorithm=algorithm, curvature=curvature,
                              refraction_k=refraction_k, read=to_read_options(kw),
                              run=to_run_options(kw, say)))
