"""``hillshade-rt info``: what hillshade-rt understood of a DEM, as text or JSON
(``run.describe``)."""

from __future__ import annotations

import json

import click

from .errors import errors_to_click
from .options import dem_options, to_read_options


@click.command()
@click.argument("dem", type=click.Path())
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@click.option("--preview", type=click.Path(dir_okay=False), default=None,
              help="Also write a quick-look PNG of the DEM (shaded relief, lit from the NW).")
@click.option("--overwrite", is_flag=True, help="Replace the preview if it exists.")
@dem_options
@errors_to_click
def info(dem, as_json, preview, overwrite, **read_opts):
    """Print what hillshade-rt understood of DEM: size, spacing, CRS, nodata, heights."""
    from ..run import describe
    doc, d = describe(dem, to_read_options(dict(read_opts)), preview, overwrite)
    if as_json:
        click.echo(json.dumps(doc, indent=2))
        return
    rows, cols = d.shape
    dx, dy = doc["spacing_m"]["centre"]
    zmin, zmax = doc["height_range_m"]
    click.echo(f"{d.path}")
    click.echo(f"  reader        {d.kind} ({d.driver}), band {d.band}, {d.source_dtype}")
    click.echo(f"  size          {cols} x {rows} (cols x rows), {d.heights.size:,} cells")
    click.echo(f"  crs           {doc['crs_name'] or 'none'}"
               + (f" ({doc['crs']})" if doc['crs'] and doc['crs'].startswith('EPSG') else ""))
    click.echo(f"  orientation   {doc['orientation']}")
    click.echo(f"  spacing (m)   dx {dx:.4f}  dy {dy:.4f} at the centre row")
    if d.grid.dx[0] != d.grid.dx[-1] or d.grid.dy[0] != d.grid.dy[-1]:
        click.echo(f"                dx {d.grid.dx[0]:.4f} .. {d.grid.dx[-1]:.4f}, "
                   f"dy {d.grid.dy[0]:.4f} .. {d.grid.dy[-1]:.4f} from first to last row")
    click.echo(f"                ({d.grid.method})")
    click.echo(f"  nodata        {d.nodata if d.nodata is not None else 'none'}"
               f"; {100 * doc['nodata_fraction']:.2f}% of cells are nodata")
    click.echo(f"  heights (m)   {zmin:.2f} .. {zmax:.2f}")
