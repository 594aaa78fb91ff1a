"""The ``hillshade-rt`` command line: one small module per command in the manner of rasterio's
``rio`` (``shadow`` and ``hillshade``, ``sun_hours``, ``horizon``, ``info``), every option declared
once (``options``), failures as one line (``errors``). A command turns its options into a config
(``run.config``) and makes one library call (``run``); no run logic lives here. Option names follow
GDAL where GDAL has one (``-b/--band``, ``-z/--z-factor``, ``--overwrite``). Every error is one
line on stderr and a non-zero exit status: 1 for bad input, 2 for a bad command line, 130 when
interrupted.
"""

from __future__ import annotations

import contextlib
import os
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


def main():
    """Console-script entry point (and ``python -m hillshade_rt``).

    The process ends with ``os._exit`` once the command is done and stdout and stderr are
    flushed: the interpreter's teardown of numba's and LLVM's objects took 0.2-0.3 s of every
    run (a fifth of a 10000² shadow run end to end) and has nothing left to do, every output
    being closed and in place by then. Where another thread or a child process is still alive
    (nothing of ours leaves one), the ordinary exit, which waits for them."""
    try:
        cli(prog_name="hillshade-rt")
        code = 0
    except SystemExit as exc:
        code = exc.code
    if code is None:
        code = 0
    elif not isinstance(code, int):
        print(code, file=sys.stderr)
        code = 1
    if _nothing_left_running():
        if "logging" in sys.modules:
            import logging
            logging.shutdown()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)
    sys.exit(code)


def _nothing_left_running() -> bool:
    """No other live non-daemon thread and no child process (``main``'s fast exit)."""
    import threading
    if any(t.is_alive() and not t.daemon and t is not threading.main_thread()
           for t in threading.enumerate()):
        return False
    if "multiprocessing" in sys.modules:
        import multiprocessing
        if multiprocessing.active_children():
            return False
    return True
