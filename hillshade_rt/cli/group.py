"""The ``hillshade-rt`` group: every command added, and ``run``, one command line run in this
process to its exit status (``cli.main`` in-process; a server's worker for each job)."""

from __future__ import annotations

import sys

import click

from .animate import animate
from .cache import cache
from .errors import OneLineErrors
from .horizon import horizon
from .illumination import illumination
from .info import info
from .irradiance import irradiance
from .profile import profile
from .query import query
from .serve import serve
from .shadow import hillshade, shadow
from .skyview import skyview
from .sun_hours import sun_hours
from .version import version_option
from .view import view


@click.group(cls=OneLineErrors, context_settings={"help_option_names": ["-h", "--help"]})
@version_option
def cli():
    """Terrain cast-shadow masks from digital elevation models."""


for _command in (shadow, hillshade, sun_hours, horizon, profile, query, skyview, info):
    cli.add_command(_command)
cli.add_command(irradiance)
cli.add_command(animate)
cli.add_command(view)
cli.add_command(illumination)
cli.add_command(cache)
cli.add_command(serve)


def run(args=None) -> int:
    """Run one command line (``args``, else ``sys.argv[1:]``): its exit status (0, 1 failed, 2
    malformed, 128 + signal). A status that is no number is said on stderr: 1."""
    try:
        cli.main(args=args, prog_name="hillshade-rt")
        code = 0
    except SystemExit as exc:
        code = exc.code
    if code is None:
        code = 0
    elif not isinstance(code, int):
        print(code, file=sys.stderr)
        code = 1
    return code
