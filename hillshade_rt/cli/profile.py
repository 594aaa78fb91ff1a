"""``hillshade-rt profile``: options -> ``run.profile.ProfileConfig`` -> ``run.profile``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from .options import (dem_options, height_above_ground_option, horizon_physics_options,
                      overwrite_option, point_options, preview_option, quiet_option, report_option,
                      to_read_options,
                      to_run_options)


@click.command()
@click.argument("dem", type=click.Path())
@point_options
@height_above_ground_option("The observer's height above the terrain at the point, metres "
                            "(a panel, a mast).")
@click.option("--step", type=float, default=1.0, show_default=True, metavar="DEG",
              help="Degrees between azimuths, clockwise from north, north first.")
@click.option("--format", "fmt", type=click.Choice(["csv", "json", "pvlib", "pvgis", "grass",
                                                    "geojson"]),
              default="csv", show_default=True,
              help="csv/json/geojson: any number of points; pvlib (a Series CSV), pvgis "
                   "(userhorizon), grass (r.horizon's azimuths, counter-clockwise from east): "
                   "one point. Each file states its convention.")
@click.option("-o", "--output", default=None, type=click.Path(dir_okay=False),
              help="Write here (default: standard output).")
@horizon_physics_options
@preview_option("Also write a PNG panorama of the first point's horizon (north at the left, "
                "east a quarter across; sky above the line, terrain below).")
@report_option
@overwrite_option("Replace the output (and the report) if it exists.")
@quiet_option()
@dem_options
@errors_to_click
def profile(dem, at, at_xy, points, height_above_ground, step, fmt, output, curvature,
            refraction_k, preview, report_path, overwrite, quiet, **read_opts):
    """Write the horizon profile of points on DEM: the horizon elevation (and the distance to
    it) every --step degrees of azimuth, for PV siting (pvlib, PVGIS), GRASS, GIS (GeoJSON)."""
    from ..run.config import ProfileConfig
    from ..run.profile import parse_pair, profile as run_profile
    kw = dict(preview=preview, report_path=report_path, overwrite=overwrite, quiet=quiet,
              **read_opts)
    run_profile(ProfileConfig(dem=dem, at=[parse_pair(a, "--at") for a in at],
                              at_xy=[parse_pair(a, "--at-xy") for a in at_xy], points=points,
                              height_above_ground=height_above_ground, step=step, fmt=fmt,
                              output=output, curvature=curvature, refraction_k=refraction_k,
                              read=to_read_options(kw), run=to_run_options(kw, say)))
