"""``hillshade-rt sun-hours``: options -> ``run.SunHoursConfig`` -> ``run.sun_hours``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from ..run.config import PLACE_KEYS
from .options import (SectionedCommand, context_option, algorithm_option, backend_option, dem_options,
                      command_line, each_pattern_options, format_option,
                      height_above_ground_option, max_memory_option, monthly_option,
                      overwrite_option,
                      physics_options, place_options, preview_option, quiet_option,
                      progress_option, report_option, scheduler_option, threads_option,
                      to_read_options, to_run_options, window_size_option)


@click.command("sun-hours", cls=SectionedCommand)
@click.argument("files", metavar="DEM OUTPUT | DEM... --each", nargs=-1, required=True,
                type=click.Path())
@click.option("--date", "date_", required=True, metavar="YYYY-MM-DD", help="The day (or first day).")
@click.option("--end-date", default=None, metavar="YYYY-MM-DD",
              help="Last day of a range (included); the hours are the total over the range.")
@monthly_option("the hours")
@click.option("--step", default="10min", show_default=True, metavar="DURATION",
              help="Sampling interval; each sample stands for the interval around it.")
@place_options("sun-hours")
@algorithm_option
@physics_options
@height_above_ground_option("The sun hours of a point this many metres above every cell (a "
                            "person, a panel): its ray starts there; brute marches it (auto "
                            "runs brute).")
@click.option("--self-shadow/--no-self-shadow", default=None,
              help="Count no direct sun on surfaces facing away from the sun (default: on, "
                   "off with --height-above-ground > 0: the observer is not on the surface).")
@preview_option("Also write a quick-look PNG (relief tinted by sun hours).")
@backend_option
@threads_option
@report_option
@max_memory_option
@window_size_option
@scheduler_option
@overwrite_option("Replace outputs if they exist.")
@quiet_option("No progress bar or summary on stderr.")
@progress_option
@format_option
@each_pattern_options
@dem_options
@context_option
@errors_to_click
def sun_hours(files, date_, end_date, monthly, step, tz, lat, lon, pressure, temperature,
              no_refraction, sun_tolerance, algorithm, curvature, refraction_k, soft,
              height_above_ground, self_shadow, preview, backend, threads, report_path,
              max_memory, window_size, scheduler, overwrite, quiet, progress, fmt,
              creation_options, each, output_pattern, **read_opts):
    """Write the hours of direct sun per cell of DEM over a day (or a range of days) to OUTPUT
    (float32 hours, -9999 nodata), like WhiteboxTools' TimeInDaylight or GRASS r.sun's insolation
    time: the sun every --step, each lit sample counting for its interval. A DEM larger than
    --max-memory (or any, with --window-size or --scheduler) is computed in windows, with the
    same result. Several DEMs: --each --output-pattern 'out/{stem}_hours.tif', each with its
    own place's sun."""
    from ..run import SunHoursConfig, sun_hours as run_sun_hours
    from ..run.batch import split_files, sun_hours_each
    dem, output = split_files(files, each, output_pattern, "sun-hours")
    kw = dict(tz=tz, lat=lat, lon=lon, pressure=pressure, temperature=temperature,
              no_refraction=no_refraction, sun_tolerance=sun_tolerance, preview=preview,
              backend=backend, threads=threads, report_path=report_path, overwrite=overwrite,
              quiet=quiet, progress=progress, fmt=fmt, creation_options=creation_options,
              **read_opts)
    place = {k: kw.pop(k) for k in PLACE_KEYS}
    cfg = SunHoursConfig(dem=dem, output=output, date=date_, end_date=end_date, step=step,
                         place=place, algorithm=algorithm, curvature=curvature,
                         refraction_k=refraction_k, soft=soft, self_shadow=self_shadow,
                         read=to_read_options(kw), run=to_run_options(kw, say),
                         height_above_ground=height_above_ground, max_memory=max_memory,
                         window_size=window_size, scheduler=scheduler, monthly=monthly,
                         command=command_line())
    if each:
        sun_hours_each(cfg, dem, output_pattern)
    else:
        run_sun_hours(cfg)
