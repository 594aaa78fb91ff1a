"""``hillshade-rt query``: options -> ``run.query.QueryConfig`` -> ``run.query``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from ..run.config import SUN_KEYS
from .options import (SectionedCommand, curvature_options, dem_options, height_above_ground_option,
                      light_options, overwrite_option, point_options, quiet_option,
                      report_option, sun_options,
                      to_read_options, to_run_options)


@click.command(cls=SectionedCommand)
@click.argument("dem", type=click.Path())
@point_options
@sun_options("query")
@height_above_ground_option("The observer's height above the terrain at the point, metres "
                            "(a person, a panel).")
@click.option("--irradiance", is_flag=True,
              help="Also the clear-sky direct normal irradiance (pvlib, Ineichen) and the "
                   "direct beam on a horizontal surface (DNI x sin(elevation) x lit); needs "
                   "suns from times.")
@click.option("--format", "fmt", type=click.Choice(["csv", "json", "geojson"]), default=None,
              help="csv: one row per point and time; json: the same rows with the conventions; "
                   "geojson: one Point feature per point with its series (default: from -o's "
                   "extension, else csv).")
@click.option("-o", "--output", default=None, type=click.Path(dir_okay=False),
              help="Write here (default: standard output).")
@curvature_options
@light_options
@report_option
@overwrite_option("Replace the output (and the report) if it exists.")
@quiet_option()
@dem_options
@errors_to_click
def query(dem, at, at_xy, points, height_above_ground, irradiance, fmt, output, curvature,
          refraction_k, light_position, light_lonlat, report_path, overwrite, quiet, **kw):
    """Whether the sun reaches points on DEM: for each point and each sun, lit or shadowed, the
    sun's azimuth and elevation, the horizon toward the sun, the margin between them (lit iff
    the sun is up and the margin >= 0) and the observer's height. The sun: --azimuth/--elevation,
    or --time (repeatable) or --start/--end/--step at the DEM's place (as `shadow`). With a
    point light (--light-position/--light-lonlat) instead: whether it reaches each point, its
    azimuth, elevation and distance, and its incidence on the surface there."""
    from ..run.points import parse_pair
    from ..run.config import QueryConfig
    from ..run.query import query as run_query
    sun = {k: kw.pop(k) for k in SUN_KEYS}
    kw.update(report_path=report_path, overwrite=overwrite, quiet=quiet)
    run_query(QueryConfig(dem=dem, at=[parse_pair(a, "--at") for a in at],
                          at_xy=[parse_pair(a, "--at-xy") for a in at_xy], points=points,
                          sun=sun, height_above_ground=height_above_ground,
                          irradiance=irradiance, fmt=fmt, output=output, curvature=curvature,
                          refraction_k=refraction_k, read=to_read_options(kw),
                          run=to_run_options(kw, say), light_position=light_position,
                          light_lonlat=light_lonlat))
