"""``hillshade-rt irradiance``: options -> ``run.irradiance.IrradianceConfig`` ->
``run.irradiance``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from ..run.config import PLACE_KEYS
from .options import (SectionedCommand, command_line, context_option, each_pattern_options,
                      algorithm_option, backend_option, clear_sky_index_options,
                      dem_options, format_option,
                      height_above_ground_option, max_memory_option, monthly_option,
                      overwrite_option,
                      physics_options, place_options, preview_option, quiet_option,
                      progress_option, report_option, scheduler_option, threads_option,
                      to_read_options, to_run_options, window_size_option)


@click.command(cls=SectionedCommand)
@click.argument("files", metavar="DEM OUTPUT | DEM... --each", nargs=-1, required=True,
                type=click.Path())
@click.option("--date", "date_", default=None, metavar="YYYY-MM-DD",
              help="The day (or first day), midnight to midnight in --tz (else local mean "
                   "solar time).")
@click.option("--end-date", default=None, metavar="YYYY-MM-DD",
              help="Last day of a range (included).")
@click.option("--start", default=None, metavar="ISO8601",
              help="Or the period from this time (with --end), e.g. 2026-06-21T06:00+02:00.")
@click.option("--end", default=None, metavar="ISO8601", help="End of the period (with --start).")
@click.option("--step", default="15min", show_default=True, metavar="DURATION",
              help="Sampling interval; each sample (at its middle) stands for its interval.")
@click.option("--time", "time", multiple=True, metavar="ISO8601",
              help="Instead of a period: the irradiance (W/m2) and incidence angle at this "
                   "instant, 5 bands (repeat for more; r.sun's mode 1).")
@click.option("--instant", is_flag=True,
              help="The instants of --start..--end every --step (or of --date's samples), 5 "
                   "bands each, instead of the period's sums.")
@click.option("--clear-sky", type=click.Choice(["ineichen", "haurwitz"]), default=None,
              help="pvlib's clear-sky model (default ineichen; haurwitz gives GHI only, split "
                   "into DNI and DHI by Erbs).")
@click.option("--linke-turbidity", default=None, metavar="T|T1,...,T12|FILE|PATTERN",
              help="Linke turbidity for ineichen (1..10): a number, 12 monthly numbers "
                   "(January first; each sample its month's), a raster (each cell's clear sky "
                   "with its own value) or 12 monthly rasters, as --albedo; default: pvlib's "
                   "climatological monthly value at the place.")
@click.option("--albedo", default="0.2", show_default=True,
              metavar="A|A1,...,A12|FILE|PATTERN",
              help="Ground reflectance (0..1) of the terrain the cell sees: a number, 12 "
                   "monthly numbers, a raster (bilinear to the DEM's grid; it must cover the "
                   "DEM), or 12 monthly rasters named by a pattern with {month} (1..12) or "
                   "{month:02d} (01..12).")
@clear_sky_index_options
@click.option("--ghi", "ghi", type=click.Path(dir_okay=False), default=None, metavar="FILE.csv",
              help="A measured sky instead: CSV with columns time, ghi (and dni, dhi; else "
                   "split by Erbs), W/m2, interpolated in time.")
@click.option("--mean", is_flag=True, help="Mean W/m2 over the period instead of Wh/m2.")
@click.option("--daily-mean", is_flag=True,
              help="Wh/m2 per day (the energy divided by the period's days; each month's by "
                   "its own) instead of Wh/m2.")
@monthly_option("the global energy")
@click.option("--perez", is_flag=True,
              help="Perez (1990) anisotropic sky (circumsolar part shadowed with the beam) "
                   "instead of the isotropic one.")
@click.option("--skyview-directions", type=click.IntRange(4, 360), default=32, show_default=True,
              metavar="N", help="Azimuths of the sky view factor (computed once).")
@click.option("--sky-view", "sky_view", type=click.Path(dir_okay=False), default=None,
              metavar="FILE", help="Read the sky view factor from FILE (hillshade-rt skyview "
                                   "DEM FILE --definition dozier, same grid and settings) "
                                   "instead of computing it.")
@click.option("--sky-view-out", "sky_view_out", type=click.Path(dir_okay=False), default=None,
              metavar="FILE", help="Also write the sky view factor computed to FILE, for "
                                   "later runs' --sky-view.")
@place_options("irradiance")
@algorithm_option
@physics_options
@height_above_ground_option("The receiving surface of every cell stands this many metres "
                            "above it (a panel): the beam's cast shadows and the sky view "
                            "are seen from there; its tilt stays the cell's slope and aspect.")
@preview_option("Also write a quick-look PNG: the relief coloured by the global band "
                "(purple low, yellow high).")
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
def irradiance(files, date_, end_date, start, end, step, time, instant, clear_sky,
               linke_turbidity, albedo, beam_index, diffuse_index, ghi, mean, daily_mean,
               monthly, perez,
               skyview_directions, sky_view, sky_view_out, tz, lat, lon, pressure, temperature,
               no_refraction, sun_tolerance, algorithm, curvature, refraction_k, soft,
               height_above_ground, preview,
               backend, threads, report_path, max_memory, window_size, scheduler, overwrite,
               quiet, progress, fmt,
               creation_options, each, output_pattern, **read_opts):
    """Write the beam, diffuse, reflected and global irradiance on every cell of DEM over a
    period to OUTPUT: 4 float32 bands, Wh/m2 (W/m2 with --mean), -9999 nodata. Beam: DNI on
    the tilted surface, in cast shadow 0; diffuse: DHI times the sky view factor; reflected:
    GHI times albedo times the terrain's view factor. A DEM larger than --max-memory (or any,
    with --window-size or --scheduler) is computed in windows, with the same result. With
    --time or --instant: at each instant, the four in W/m2 and the sun's angle above each
    cell's surface, 5 bands per time."""
    from ..run.config import IrradianceConfig
    from ..run.irradiance_instant import irradiance_or_instants as run_irradiance
    from ..run.batch import split_files, irradiance_each
    dem, output = split_files(files, each, output_pattern, "irradiance")
    kw = dict(tz=tz, lat=lat, lon=lon, pressure=pressure, temperature=temperature,
              no_refraction=no_refraction, sun_tolerance=sun_tolerance, preview=preview,
              backend=backend, threads=threads, report_path=report_path, overwrite=overwrite,
              quiet=quiet, progress=progress, fmt=fmt, creation_options=creation_options,
              **read_opts)
    place = {k: kw.pop(k) for k in PLACE_KEYS}
    cfg = IrradianceConfig(
        dem=dem, output=output, date=date_, end_date=end_date, start=start, end=end, step=step,
        clear_sky=clear_sky, linke_turbidity=linke_turbidity, albedo=albedo, ghi=ghi,
        beam_index=beam_index, diffuse_index=diffuse_index,
        mean=mean, daily_mean=daily_mean, monthly=monthly, soft=soft, perez=perez,
        skyview_directions=skyview_directions, place=place,
        algorithm=algorithm, curvature=curvature, refraction_k=refraction_k,
        read=to_read_options(kw), run=to_run_options(kw, say),
        height_above_ground=height_above_ground, sky_view=sky_view, sky_view_out=sky_view_out,
        max_memory=max_memory, window_size=window_size, scheduler=scheduler,
        times=tuple(time), instant=instant, command=command_line())
    if each:
        irradiance_each(cfg, dem, output_pattern)
    else:
        run_irradiance(cfg)
