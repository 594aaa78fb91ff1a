"""``hillshade-rt view``: options -> ``run.view.ViewConfig`` -> ``run.view.view``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from .options import algorithm_option, backend_option, dem_options, to_read_options, view_options


@click.command()
@click.argument("dem", type=click.Path())
@view_options
@algorithm_option
@backend_option
@dem_options
@errors_to_click
def view(dem, port, no_browser, tz, algorithm, backend, **read_opts):
    """Look at DEM's shadows in a browser: a local server on 127.0.0.1 (Ctrl-C stops it)
    with the sun dragged on a compass or set by date and time, pan and zoom."""
    from ..run.config import ViewConfig
    from ..run.view import view as run_view
    run_view(ViewConfig(dem=dem, read=to_read_options(dict(read_opts)), port=port,
                        open_browser=not no_browser, algorithm=algorithm, backend=backend,
                        tz=tz, say=say))
