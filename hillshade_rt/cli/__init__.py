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


def __getattr__(name):
    """``cli`` (the click group) imported when first asked for: ``main`` hands a command line
    to a running server (``client.hand_over``) before it imports click and the commands."""
    if name == "cli":
        from .group import cli
        globals()["cli"] = cli
        return cli
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main():
    """Console-script entry point (and ``python -m hillshade_rt``).

    First the server: when this install's server runs (``hillshade-rt serve``,
    ``HILLSHADE_RT_SERVER``), the command line runs there and this process only waits for its
    exit status (``client.hand_over``: the standard library only, no click, numpy or numba);
    otherwise, or whenever it cannot be reached, the command runs here (``group.run``).

    The process ends with ``os._exit`` once the command is done and stdout and stderr are
    flushed: the interpreter's teardown of numba's and LLVM's objects took 0.2-0.3 s of every
    run (a fifth of a 10000² shadow run end to end) and has nothing left to do, every output
    being closed and in place by then. Where another thread or a child process is still alive
    (nothing of ours leaves one), the ordinary exit, which waits for them."""
    from .client import hand_over
    code = hand_over(sys.argv[1:])
    if code is None:
        from .group import run
        code = run()
    if nothing_left_running():
        if "logging" in sys.modules:
            import logging
            logging.shutdown()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)
    sys.exit(code)


def nothing_left_running() -> bool:
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
