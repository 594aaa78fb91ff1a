"""How the command line fails: one line on stderr, never a traceback; exit status 1 for a failed
run, 2 for a malformed command line, 128 + the signal's number when interrupted; and how it
speaks (``say``: the run's messages for people on stderr)."""

from __future__ import annotations

import contextlib
import functools
import os
import re
import sys

import click

from ..errors import HillshadeError, UsageProblem


def _signal_name(signum: int) -> str:
    import signal
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def _complete_note() -> str:
    """What this run has written whole, for a message about a failed or interrupted run."""
    from ..io.write import completed, is_virtual
    # what is still there: scratch files published and removed again (a mosaic cut into its
    # tiles, Dask's parts) are no outputs
    names = [p for p in completed if is_virtual(p) or os.path.lexists(p)]
    if not names:
        return ""
    shown = ", ".join(names) if len(names) <= 4 else f"{names[0]}, {names[1]} ... {names[-1]}"
    return f"; {len(names)} output(s) complete and kept: {shown}"


@contextlib.contextmanager
def signals_stop_runs():
    """While a command runs: SIGINT, SIGTERM and SIGHUP stop it like Ctrl-C (``io.write``'s
    handler: the unfinished output removed); the previous handlers restored afterwards."""
    import signal
    import threading

    from ..io import write as writes
    writes.reset()
    previous = {}
    if threading.current_thread() is threading.main_thread():
        for s in writes.SIGNALS:
            with contextlib.suppress(OSError, ValueError):
                previous[s] = signal.signal(s, writes.on_signal)
    try:
        yield
    finally:
        for s, h in previous.items():
            with contextlib.suppress(OSError, ValueError, TypeError):
                signal.signal(s, h)


@contextlib.contextmanager
def one_line_errors():
    """Every way out of the block but success, ``SystemExit`` and click's ``Exit`` (``--help``,
    ``--version``) becomes one line on stderr and ``sys.exit`` with its status: 2 for a bad
    command line, 1 for a failed run, 128 + the signal's number when interrupted."""
    try:
        yield
    except (SystemExit, click.exceptions.Exit):
        raise
    except BaseException as exc:   # noqa: BLE001 -- every way out is one line
        _exit_one_line(exc)


def _exit_one_line(exc: BaseException):
    from ..io.write import caught
    if caught or isinstance(exc, (KeyboardInterrupt, click.exceptions.Abort)):
        signum = caught[0] if caught else 2
        done = _complete_note()
        click.echo(f"hillshade-rt: interrupted ({_signal_name(signum)}); "
                   + (done[2:] + ", the unfinished output removed" if done
                      else "no output written"), err=True)
        sys.exit(128 + signum)
    if isinstance(exc, click.exceptions.NoArgsIsHelpError):  # click >= 8.2: bare group
        click.echo(exc.ctx.get_help(), err=True)
        sys.exit(2)
    if isinstance(exc, click.ClickException):
        msg = exc.format_message()
        if isinstance(exc, click.UsageError) and exc.ctx is not None:
            msg += f" (see '{exc.ctx.command_path} --help')"
        elif exc.exit_code == 1:
            msg += _complete_note()
        click.echo(f"hillshade-rt: error: {msg}", err=True)
        sys.exit(exc.exit_code)
    if isinstance(exc, BrokenPipeError):
        sys.exit(1)
    if isinstance(exc, OSError):
        where = f"{exc.filename}: " if exc.filename else ""
        click.echo(f"hillshade-rt: error: {where}{exc.strerror or exc}"
                   f"{_complete_note()}", err=True)
        sys.exit(1)
    if os.environ.get("HILLSHADE_RT_DEBUG"):
        raise exc
    first = str(exc).splitlines()[0] if str(exc) else ""
    click.echo(f"hillshade-rt: error: internal error ({type(exc).__name__}"
               f"{': ' + first if first else ''}); please report it, "
               f"HILLSHADE_RT_DEBUG=1 shows the traceback{_complete_note()}", err=True)
    sys.exit(1)


_SITE = re.compile(r"\S*[/\\](?:site|dist)-packages[/\\](\S+)")


def _origin(filename: str) -> str:
    """The installed package a warning came from, by its file (``pvlib``, ``rasterio``; never
    a path); "" for any other file."""
    parts = re.split(r"[/\\]", filename or "")
    for marker in ("site-packages", "dist-packages"):
        if marker in parts and parts.index(marker) + 1 < len(parts):
            return parts[parts.index(marker) + 1].removesuffix(".py")
    return ""       # ours, or numpy's arithmetic warnings (they name the caller's file)


def warning_line(message, category, filename: str) -> str:
    """A warning as the tool's one line: its message's first line (paths into installed
    packages cut to the package's part) and, for another package's warning, its kind and
    origin: ``Deltat is unknown ... (UserWarning from pvlib)``, ``invalid value encountered in
    divide (RuntimeWarning)``."""
    from ..errors import HillshadeWarning
    text = str(message).strip()
    text = _SITE.sub(r"\1", text.splitlines()[0].strip() if text else "") or category.__name__
    if issubclass(category, HillshadeWarning):
        return text
    origin = _origin(filename)
    return f"{text} ({category.__name__}{' from ' + origin if origin else ''})"


@contextlib.contextmanager
def warnings_one_line():
    """While a command runs, every warning that Python's filters let through (pvlib's,
    rasterio's, numpy's, pyproj's, ours) is said as one line, ``hillshade-rt: warning: ...``,
    each distinct one once: never the raw multi-line text with a path into site-packages.
    (``-W error`` and PYTHONWARNINGS still decide which warnings are shown or raised.)"""
    import warnings
    seen: set[str] = set()

    def show(message, category, filename, lineno, file=None, line=None):
        text = warning_line(message, category, filename)
        if text in seen:
            return
        seen.add(text)
        with contextlib.suppress(Exception):
            click.echo(f"hillshade-rt: warning: {text}", err=True)

    with warnings.catch_warnings():
        warnings.showwarning = show
        if not sys.warnoptions:
            # deprecations are notices to the developers of the code that raised them (here
            # another package's use of a third one's API), not to the user of a command: as
            # Python's default filters have it outside __main__ (pytest shows them)
            for category in (DeprecationWarning, PendingDeprecationWarning):
                warnings.filterwarnings("ignore", category=category)
        yield


class OneLineErrors(click.Group):
    """A group whose errors (usage errors included) print as a single line, never a traceback;
    SIGINT, SIGTERM and SIGHUP stop a run like Ctrl-C (exit 130, 143, 129); warnings are one
    line each (:func:`warnings_one_line`)."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        with signals_stop_runs(), warnings_one_line():
            with one_line_errors():
                rv = super().main(args=args, prog_name=prog_name, complete_var=complete_var,
                                  standalone_mode=False, **extra)
        if not standalone_mode:
            return rv
        sys.exit(rv if isinstance(rv, int) else 0)


class InAnotherGroup:
    """A command of ours as another program's subcommand (``rio shadow``): the other group
    parses and invokes it (``make_context``, ``invoke``), never its ``main``, so its failures
    are made one line here; and signals stop its run as they do in ``hillshade-rt``. A mixin
    before the command's own class (``cli.rio.in_rio``)."""

    def make_context(self, info_name, args, parent=None, **extra):
        with one_line_errors():
            return super().make_context(info_name, args, parent=parent, **extra)

    def invoke(self, ctx):
        with signals_stop_runs(), warnings_one_line():
            with one_line_errors():
                return super().invoke(ctx)


def errors_to_click(f):
    @functools.wraps(f)
    def wrapper(*args, **kwargs):
        try:
            return f(*args, **kwargs)
        except UsageProblem as exc:
            raise click.UsageError(str(exc)) from None
        except HillshadeError as exc:
            raise click.ClickException(str(exc)) from None
        except MemoryError:
            raise click.ClickException("out of memory (the DEM is too large for this machine)") from None
    return wrapper


def stderr_is_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError, OSError):
        return False


def say(kind: str, message: str) -> None:
    """The run's messages on stderr (``run.RunOptions.say``): the summary as it is, notes as
    ``note:`` lines, and numba's "compiling" line on a terminal only, like the progress bar
    (logs and pipelines keep their one summary line)."""
    if kind == "compile":
        if stderr_is_terminal():
            click.echo(f"hillshade-rt: {message}", err=True)
    elif kind == "note":
        click.echo(f"hillshade-rt: note: {message}", err=True)
    else:
        click.echo(message, err=True)
