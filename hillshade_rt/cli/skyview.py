"""``hillshade-rt skyview``: options -> ``run.skyview.SkyviewConfig`` -> ``run.skyview``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from .options import (SectionedCommand, context_option, each_pattern_options,
                      backend_option, dem_options, format_option,
                      height_above_ground_option, horizon_physics_options,
                      max_distance_option, max_memory_option, overwrite_option,
                      preview_option, quiet_option, progress_option, report_option, scheduler_option,
                      threads_option, to_read_options, to_run_options,
                      window_size_option)


@click.command(cls=SectionedCommand)
@click.argument("files", metavar="DEM OUTPUT | DEM... --each", nargs=-1, required=True,
                type=click.Path())
@click.option("--directions", type=click.IntRange(4, 360), default=32, show_default=True,
              metavar="N", help="Equally spaced azimuths, clockwise from north (4..360).")
@click.option("--definition", type=click.Choice(["zaksek", "dozier"]), default="zaksek",
              show_default=True,
              help="zaksek: 1 - mean sin of the horizon elevation (RVT, HORAYZON); dozier: "
                   "the cosine-weighted sky seen by the tilted surface (Dozier & Frew 1990).")
@click.option("--terrain-configuration", is_flag=True,
              help="Write 1 - Vd instead (with --definition dozier): the share of the tilted "
                   "surface's hemisphere that is terrain, for reflected light.")
@click.option("--openness", type=click.Choice(["positive", "negative"]), default=None,
              help="Write Yokoyama's openness instead (degrees): positive, the mean over the "
                   "directions of 90 - the horizon's elevation (not clipped at the "
                   "horizontal); negative, the same of the inverted terrain (90 + the angle "
                   "down to the lowest terrain). Directions with nothing ahead are left out.")
@max_distance_option
@horizon_physics_options
@height_above_ground_option("The observer of every cell stands this many metres above it (a "
                            "person, a panel): the sky it sees from there (the surface's slope "
                            "and aspect stay the cell's for --definition dozier).")
@preview_option("Also write a quick-look PNG: the relief coloured by the result (low purple, "
                "high yellow).")
@backend_option
@threads_option
@report_option
@max_memory_option
@window_size_option
@scheduler_option
@overwrite_option()
@quiet_option()
@progress_option
@format_option
@each_pattern_options
@dem_options
@context_option
@errors_to_click
def skyview(files, directions, definition, terrain_configuration, openness, max_distance,
            curvature, refraction_k, height_above_ground, preview, backend, threads, report_path,
            max_memory,
            window_size, scheduler, overwrite, quiet, progress, fmt,
            creation_options, each, output_pattern, **read_opts):
    """Write the sky view factor of every cell of DEM to OUTPUT (float32 0..1, -9999 nodata)
    from its exact horizon in --directions azimuths, or its openness (--openness, degrees).
    A DEM larger than --max-memory (or any, with --window-size) is computed in windows, with
    the same result."""
    from ..run.config import SkyviewConfig
    from ..run.skyview import skyview as run_skyview
    from ..run.batch import split_files, skyview_each
    dem, output = split_files(files, each, output_pattern, "skyview")
    kw = dict(preview=preview, backend=backend, threads=threads, report_path=report_path,
              overwrite=overwrite,
              quiet=quiet, progress=progress, fmt=fmt,
              creation_options=creation_options,
              **read_opts)
    cfg = SkyviewConfig(dem=dem, output=output, directions=directions, definition=definition,
                        terrain_configuration=terrain_configuration, curvature=curvature,
                        refraction_k=refraction_k, read=to_read_options(kw),
                        run=to_run_options(kw, say), openness=openness,
                        max_distance=max_distance, max_memory=max_memory,
                        window_size=window_size, scheduler=scheduler,
                        height_above_ground=height_above_ground)
    if each:
        skyview_each(cfg, dem, output_pattern)
    else:
        run_skyview(cfg)
