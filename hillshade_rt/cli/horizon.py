"""``hillshade-rt horizon``: options -> ``run.HorizonConfig`` -> ``run.horizon``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from .options import (InternalOption, SectionedCommand, context_option, each_pattern_options,
                      backend_option, dem_options, finite, format_option,
                      height_above_ground_option, horizon_physics_options, max_distance_option,
                      max_memory_option, overwrite_option, preview_option, quiet_option,
                      progress_option, report_option,
                      scheduler_option, threads_option, to_read_options, to_run_options,
                      window_size_option)


@click.command(cls=SectionedCommand)
@click.argument("files", metavar="DEM OUTPUT | DEM... --each", nargs=-1, required=True,
                type=click.Path())
@click.option("--azimuth", type=float, default=None, callback=finite,
              help="Azimuth along which to look, degrees clockwise from north (one band).")
@click.option("--directions", type=click.IntRange(8, 360), default=None, metavar="N",
              help="N equally spaced azimuths clockwise from north, 0 first (8..360): one band "
                   "per direction, its description the azimuth.")
@click.option("--start", type=float, default=None, callback=finite, metavar="DEG",
              help="With --step: the first azimuth, degrees clockwise from north (default 0; "
                   "r.horizon's start, which counts counter-clockwise from east: ours is 90 - "
                   "its, mod 360).")
@click.option("--end", type=float, default=None, callback=finite, metavar="DEG",
              help="With --step: azimuths before this one (default --start + 360; at most one "
                   "turn after --start).")
@click.option("--step", type=float, default=None, callback=finite, metavar="DEG",
              help="One band every DEG degrees clockwise from --start, before --end: "
                   "floor((end - start) / step) bands, as r.horizon; each band's description "
                   "its azimuth. Not with --azimuth or --directions.")
@click.option("--angle-unit", type=click.Choice(["degrees", "radians"]), default="degrees",
              show_default=True,
              help="The unit of the angles written (r.horizon writes radians, degrees with -d).")
@click.option("--distance", "distance", type=click.Path(dir_okay=False), default=None,
              metavar="DIST.tif",
              help="Also write the ground distance in metres to each cell's horizon point "
                   "(the same bands; -9999 on voids and where nothing lies ahead; the scan).")
@click.option("--method", type=click.Choice(["scan", "hull"]), default="scan", show_default=True,
              help="scan: exact per-cell march; hull: convex-hull approximation, much faster.")
@click.option("--sample-spacing", type=click.IntRange(min=1), default=1, show_default=True,
              cls=InternalOption, help="scan: use every N-th sample only (the paper's sp; faster, approximate).")
@max_distance_option
@horizon_physics_options
@height_above_ground_option("The observer of every cell stands this many metres above it (a "
                            "person, a panel): its horizon is seen from there.")
@preview_option("Also write a quick-look PNG (relief, high horizons tinted).")
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
def horizon(files, azimuth, directions, start, end, step, angle_unit, distance, method,
            sample_spacing, max_distance, curvature, refraction_k, height_above_ground, preview,
            backend, threads, report_path,
            max_memory,
            window_size, scheduler, overwrite, quiet, progress, fmt,
            creation_options, each, output_pattern, **read_opts):
    """Write the horizon angle toward --azimuth (or toward each of --directions N azimuths, or
    of --start/--end/--step's, one band each) of every cell of DEM to OUTPUT.

    Float32 degrees (or --angle-unit radians) above the horizontal (negative: the cell looks
    down on everything ahead; -90: no terrain ahead inside the raster, or within
    --max-distance); nodata -9999. A cell is
    lit by a sun at this azimuth iff its angle <= the sun's elevation. A DEM larger than
    --max-memory (or any, with --window-size) is computed in windows, with the same result."""
    from ..run import HorizonConfig, horizon as run_horizon
    from ..run.batch import split_files, horizon_each
    dem, output = split_files(files, each, output_pattern, "horizon")
    kw = dict(preview=preview, backend=backend, threads=threads, report_path=report_path,
              overwrite=overwrite,
              quiet=quiet, progress=progress, fmt=fmt, creation_options=creation_options,
              **read_opts)
    cfg = HorizonConfig(dem=dem, output=output, azimuth=azimuth, method=method,
                        sample_spacing=sample_spacing, curvature=curvature,
                        refraction_k=refraction_k, read=to_read_options(kw),
                        run=to_run_options(kw, say), directions=directions, distance=distance,
                        max_distance=max_distance, max_memory=max_memory,
                        window_size=window_size, scheduler=scheduler,
                        height_above_ground=height_above_ground, start=start, end=end,
                        step=step, angle_unit=angle_unit)
    if each:
        horizon_each(cfg, dem, output_pattern)
    else:
        run_horizon(cfg)
