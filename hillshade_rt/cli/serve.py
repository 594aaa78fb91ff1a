"""``hillshade-rt serve start|stop|status``: this install's warm server for batches (``server.py``
its master, ``worker.py`` its workers, ``client.py`` how ``hillshade-rt`` reaches it)."""

from __future__ import annotations

import os
import sys
import time

import click

from . import client

START_WAIT = 600.0        # serve start: the first worker's imports and kernels (a first
                          # compile of the kernels on a slow machine: a few minutes)


def _seconds(s: float) -> str:
    return f"{s:g} s"


def _running_line(st: dict) -> str:
    w = st["workers"]
    return (f"hillshade-rt server running: pid {st['pid']}, {st['size']} worker(s) "
            f"({w['idle']} ready, {w['busy']} busy, {w['starting']} starting), "
            f"idle timeout {_seconds(st['idle_timeout'])}")


@click.group("serve")
def serve():
    """A warm server for batches: this user's server of this install keeps the imports and the
    kernels loaded, and `hillshade-rt COMMAND ...` hands it its command line, working folder,
    environment and standard streams (its output and exit status are the same; a call costs
    tens of milliseconds instead of most of a second).

    HILLSHADE_RT_SERVER=auto starts one on demand (that call runs in its own process);
    unset, calls use a server that runs; off, never. Whenever the server cannot be reached,
    a call runs in its own process, silently. The socket lies in a folder of this user's only
    ($XDG_RUNTIME_DIR/hillshade-rt, else /tmp/hillshade-rt-UID, mode 0700): docs/usage.md,
    "A warm server for batches"."""


@serve.command("start")
@click.option("--idle-timeout", type=click.FloatRange(min=0), default=None, metavar="SECONDS",
              help="Stop after this long without a job; 0: never.  [default: "
                   "$HILLSHADE_RT_SERVER_IDLE, else 600]")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes, each running one job at a time.  [default: "
                   "$HILLSHADE_RT_SERVER_WORKERS, else the CPUs, at most 4]")
@click.option("--queue-wait", type=click.FloatRange(min=0), default=None, metavar="SECONDS",
              help="How long a call waits for a busy server's next free worker before it runs "
                   "in its own process.  [default: 0.5]")
@click.option("--foreground", is_flag=True,
              help="Run in this process, logging to stderr, until stopped (Ctrl-C).")
def start(idle_timeout, workers, queue_wait, foreground):
    """Start the server (it stays until idle for --idle-timeout) and wait until it serves."""
    where = client.paths(os.environ)
    st = client.request(where["socket"], {"type": "status"})
    if st is not None:
        click.echo(f"{_running_line(st)}; already running")
        return
    options = []
    for flag, value in (("--idle-timeout", idle_timeout), ("--workers", workers),
                        ("--queue-wait", queue_wait)):
        if value is not None:
            options += [flag, str(value)]
    if foreground:
        from .server import main as master
        sys.exit(master([*options, "--foreground"]))
    problem = client.make_folder(where["folder"])
    if problem:
        raise click.ClickException(f"cannot start the server: {problem}")
    proc = client.start_in_background(os.environ, where, options)
    if proc is None:
        raise click.ClickException("cannot start the server (python -m hillshade_rt.cli.server)")
    t0 = time.monotonic()
    deadline = t0 + START_WAIT
    said = False
    while time.monotonic() < deadline:
        st = client.request(where["socket"], {"type": "status"})
        if st is not None and st["workers"]["idle"] + st["workers"]["busy"] > 0:
            click.echo(f"{_running_line(st)}; socket {st['socket']}")
            return
        code = proc.poll()
        if code is not None and code != 0:
            raise click.ClickException(f"the server did not start (status {code}); "
                                       f"see {where['log']}")
        if code == 0 and st is None:
            raise click.ClickException(f"the server stopped as it started; see {where['log']}")
        if not said and st is not None and time.monotonic() - t0 > 3:
            click.echo("hillshade-rt: the server's workers are loading the kernels (compiling "
                       "them once if numba's cache lacks them) ...", err=True)
            said = True
        time.sleep(0.1)
    raise click.ClickException(f"the server was not ready after {START_WAIT:g} s; "
                               f"see {where['log']}")


@serve.command("stop")
def stop():
    """Stop the server (jobs running finish first)."""
    where = client.paths(os.environ)
    st = client.request(where["socket"], {"type": "stop"})
    if st is None:
        click.echo(f"no hillshade-rt server running (socket {where['socket']})")
        return
    pid = st["pid"]
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            break
        except PermissionError:
            break
        time.sleep(0.05)
    else:
        raise click.ClickException(f"the server (pid {pid}) is still stopping after 10 s")
    click.echo(f"stopped the hillshade-rt server (pid {pid}) after {st['jobs']} job(s)")


@serve.command("status")
def status():
    """Whether the server runs: its pid, socket, version, idle timeout, workers, jobs served
    (exit status 3 when none runs)."""
    where = client.paths(os.environ)
    st = client.request(where["socket"], {"type": "status"})
    if st is None:
        click.echo(f"no hillshade-rt server running (socket {where['socket']})")
        sys.exit(3)
    w = st["workers"]
    click.echo(f"running: pid {st['pid']}")
    click.echo(f"socket: {st['socket']}")
    click.echo(f"version: hillshade-rt {st['version']} ({st['install']}, {st['python']})")
    click.echo(f"idle timeout: {_seconds(st['idle_timeout'])} (idle for "
               f"{_seconds(st['idle_for'])}; up {_seconds(st['uptime'])})")
    click.echo(f"workers: {st['size']} ({w['idle']} ready, {w['busy']} busy, "
               f"{w['starting']} starting); pids {' '.join(map(str, st['worker_pids']))}")
    click.echo(f"jobs served: {st['jobs']}")
    click.echo(f"log: {st['log']}")
