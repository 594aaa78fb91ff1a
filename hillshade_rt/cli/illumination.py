"""``hillshade-rt illumination``: options -> ``run.illumination.IllumConfig`` ->
``run.illumination.illumination``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from .options import (SectionedCommand, backend_option, dem_options, format_option, height_above_ground_option,
                      max_memory_option, overwrite_option, physics_options, preview_option,
                      quiet_option, progress_option,
                      report_option, scheduler_option, subsolar_series_options, threads_option,
                      to_read_options, to_run_options, window_size_option)


@click.command("illumination", cls=SectionedCommand)
@click.argument("dem", type=click.Path())
@click.argument("output", type=click.Path())
@subsolar_series_options
@height_above_ground_option("Light a point this many metres above every cell (a lander, a "
                            "rover's panel): its ray starts there.")
@physics_options
@preview_option("Also write a quick-look PNG (relief coloured by the fraction of the time lit, "
                "least purple to most yellow).")
@max_memory_option
@window_size_option
@scheduler_option
@backend_option
@threads_option
@report_option
@overwrite_option("Replace OUTPUT (and the report) if they exist.")
@quiet_option("No progress bar or summary on stderr.")
@progress_option
@format_option
@dem_options
@errors_to_click
def illumination(dem, output, subsolar_file, sun_distance, body, height_above_ground, curvature,
                 refraction_k, soft, preview, max_memory, window_size, scheduler, backend,
                 threads, report_path, overwrite, quiet, progress, fmt, creation_options,
                 **read_opts):
    """Write the illumination of DEM over a subsolar series to OUTPUT (float32 GeoTIFF, NaN
    nodata), every cell with its own sun on the body: band 1 the fraction of the time lit
    (each time weighted by its interval), [2 with --soft: the mean visible fraction of the solar
    disk], then the longest continuous shadow (hours) and permanently shadowed (1 never lit in
    the series, 0 otherwise)."""
    from ..run.config import IllumConfig
    from ..run.illumination import illumination as run_illumination
    kw = dict(preview=preview, backend=backend, threads=threads, report_path=report_path,
              overwrite=overwrite, quiet=quiet, progress=progress, fmt=fmt,
              creation_options=creation_options,
              **read_opts)
    read = to_read_options(kw)
    run_illumination(IllumConfig(files=[dem, output], subsolar_file=subsolar_file, body=body,
                                 sun_distance=sun_distance,
                                 height_above_ground=height_above_ground, soft=soft,
                                 curvature=curvature, refraction_k=refraction_k,
                                 window_size=window_size, max_memory=max_memory,
                                 scheduler=scheduler, read=read, run=to_run_options(kw, say)))
