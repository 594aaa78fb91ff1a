"""A worker of the server (``python -m hillshade_rt.cli.worker FD``, spawned by ``server.py``):
one process that imports the command line, the run layer and numpy, rasterio and numba once,
loads the default kernels (compiling them first when numba's cache lacks them: callers run in
their own processes meanwhile), and then runs one job at a time, each through the same click
command objects as ``hillshade-rt`` in-process (``group.run``).

A job runs in the caller's conditions, restored afterwards: its working folder (``fchdir`` to
the caller's descriptor), its environment (TZ, GDAL_*/AWS_* configuration, HILLSHADE_RT_*),
umask, command line and standard streams (the caller's descriptors on 0, 1 and 2, new
``sys.std*`` objects over them buffered as Python buffers them at start: isatty, progress bars
and pipes behave as in the caller's process); the warning filters and the run's signal handlers
are the command line's own. A thread reads the connection meanwhile: ``cancel`` is the caller's
signal, raised in this process's main thread (the run stops as it would in-process and removes
its unfinished output); the caller gone (its end closed) stops the run like SIGTERM. A job that
was interrupted, failed (status 1 or more than 2) or left a thread or a child process behind
ends the worker after its status is sent (the master starts another): the next job never
inherits a half-finished state.
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
import socket
import sys
import threading
import time
import warnings

from . import client, nothing_left_running

SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
late_signals: list[int] = []       # signals that arrived outside a run's own handlers


def _late(signum, frame):
    late_signals.append(signum)


def log(message: str) -> None:
    print(f"{time.strftime('%Y-%m-%d %H:%M:%S')} [{os.getpid()}] {message}", file=sys.stderr,
          flush=True)


def warm_up(check_kernels: bool) -> None:
    """Import what the commands import and load the default kernels, by running the default
    commands on small DEMs (a projected and a geographic one) in a temporary folder.
    ``check_kernels`` (the master's first worker): the kernels numba's cache lacks are compiled
    first (``python -m hillshade_rt.warm``, said in the log); the workers after it (others of
    the pool, replacements) need not look again."""
    import tempfile

    from .group import run
    if check_kernels:
        import subprocess
        subprocess.run([sys.executable, "-m", "hillshade_rt.warm"], stdin=subprocess.DEVNULL,
                       check=False)
    import numpy as np
    import rasterio
    from rasterio.transform import from_origin
    i = np.arange(32)
    z = (60.0 * np.add.outer(np.sin(0.7 * i), np.cos(1.3 * i)) + 500.0).astype(np.float32)
    with tempfile.TemporaryDirectory(prefix="hillshade-rt-warm-") as tmp:
        for crs, cell, x0, y0 in (("EPSG:32611", 30.0, 380000.0, 3800000.0),
                                  ("EPSG:4326", 0.0003, -118.0, 34.3)):
            dem = os.path.join(tmp, "dem.tif")
            with rasterio.open(dem, "w", driver="GTiff", width=32, height=32, count=1,
                               dtype="float32", crs=crs,
                               transform=from_origin(x0, y0, cell, cell)) as dst:
                dst.write(z, 1)
            for command in ("shadow", "hillshade"):
                out = os.path.join(tmp, f"{command}.tif")
                code = run([command, dem, out, "--azimuth", "203.7", "--elevation", "10",
                            "-q", "--overwrite"])
                if code != 0:
                    raise RuntimeError(f"the warm-up {command} run ended with status {code}")


def _stream(fd: int, mode: str, like) -> io.TextIOWrapper:
    """A new ``sys.std*`` over ``fd``, encoded as ``like`` (the original object) and buffered as
    Python buffers standard streams at start (line-buffered on a terminal, and stderr always)."""
    line = fd == 2 or os.isatty(fd)
    return open(fd, mode, buffering=1 if line else -1, encoding=like.encoding,
                errors=like.errors, closefd=False)


class Watcher(threading.Thread):
    """Reads the caller's connection while its job runs: ``cancel`` raises the caller's signal
    in the main thread; the end of the connection (the caller is gone) raises SIGTERM."""

    def __init__(self, frames: client.Frames):
        super().__init__(name="hillshade-rt-job-watcher", daemon=True)
        self.frames = frames
        self.lock = threading.Lock()
        self.active = True
        self.raised: list[int] = []
        self.main = threading.main_thread().ident

    def _raise(self, signum: int) -> None:
        with self.lock:
            if self.active and not self.raised:
                self.raised.append(signum)
                signal.pthread_kill(self.main, signum)

    def run(self):
        while True:
            try:
                msg = self.frames.read(None)
            except (OSError, ValueError):
                msg = None
            if msg is None:
                self._raise(signal.SIGTERM)
                return
            if isinstance(msg, dict) and msg.get("type") == "cancel":
                signum = msg.get("signal")
                if signum in SIGNALS:
                    self._raise(signum)

    def finish(self) -> None:
        with self.lock:
            self.active = False


def run_job(req: dict, conn: socket.socket) -> tuple[str, int, bool]:
    """One job: ("skipped", 0, True) when the caller did not say go, else ("done", status,
    whether this process is fit for another job)."""
    frames = client.Frames(conn, want_fds=4)
    try:
        conn.settimeout(None)
        client.send_frame(conn, {"type": "accepted", "pid": os.getpid()})
        go = frames.read(client.REPLY_TIMEOUT)
    except (OSError, ValueError, TimeoutError):
        go = None
    try:
        if not (isinstance(go, dict) and go.get("type") == "go" and len(frames.fds) == 4):
            return "skipped", 0, True
        return _run(req, conn, frames)
    finally:
        for fd in frames.fds:
            with contextlib.suppress(OSError):
                os.close(fd)


def _run(req: dict, conn: socket.socket, frames: client.Frames) -> tuple[str, int, bool]:
    from .group import run
    cwd, *std = frames.fds
    argv = [str(a) for a in req.get("argv", [])]
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    saved = {"fds": [os.dup(i) for i in (0, 1, 2)], "env": dict(os.environ),
             "std": (sys.stdin, sys.stdout, sys.stderr), "argv": sys.argv,
             "umask": os.umask(0o022)}
    os.umask(saved["umask"])
    watcher = Watcher(frames)
    late_signals.clear()
    code = 1
    ours = []
    try:
        os.fchdir(cwd)
        os.environ.clear()
        os.environ.update({str(k): str(v) for k, v in req.get("env", {}).items()})
        time.tzset()
        os.umask(int(req.get("umask", 0o022)) & 0o777)
        for i, fd in enumerate(std):
            os.dup2(fd, i)
        ours = [_stream(0, "r", sys.__stdin__ or saved["std"][0]),
                _stream(1, "w", sys.__stdout__ or saved["std"][1]),
                _stream(2, "w", sys.__stderr__ or saved["std"][2])]
        sys.stdin, sys.stdout, sys.stderr = ours
        sys.argv = ["hillshade-rt", *argv]
        watcher.start()
        with warnings.catch_warnings():
            code = run(argv)
    except BaseException as exc:       # noqa: BLE001 -- setting up failed: one line, status 1
        late_signals.append(0)
        with contextlib.suppress(Exception):
            os.write(2, f"hillshade-rt: error: the server could not run the command "
                        f"({type(exc).__name__}: {exc})\n".encode())
    finally:
        watcher.finish()
        for stream in ours[1:]:
            with contextlib.suppress(Exception):
                stream.flush()
        sys.stdin, sys.stdout, sys.stderr = saved["std"]
        for i, fd in enumerate(saved["fds"]):
            os.dup2(fd, i)
            os.close(fd)
        os.chdir("/")
        os.environ.clear()
        os.environ.update(saved["env"])
        time.tzset()
        os.umask(saved["umask"])
        sys.argv = saved["argv"]
    fit = (code in (0, 2) and not watcher.raised and not late_signals
           and nothing_left_running())
    with contextlib.suppress(OSError):
        client.send_frame(conn, {"type": "status", "code": code})
    with contextlib.suppress(OSError):
        conn.shutdown(socket.SHUT_RDWR)
    if watcher.ident is not None:     # (not started when setting up the job failed)
        watcher.join(timeout=1.0)
    return "done", code, fit


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    channel = socket.socket(fileno=int(argv[0]))
    for s in SIGNALS:
        signal.signal(s, _late)
    try:
        warm_up("--check-kernels" in argv[1:])
    except BaseException as exc:        # noqa: BLE001 -- said in the log; the master sees us end
        log(f"warm-up failed: {type(exc).__name__}: {exc}")
        return 1
    late_signals.clear()
    channel.send(b"ready")
    while True:
        try:
            msg, fds, _, _ = socket.recv_fds(channel, 1 << 20, 1)
        except OSError:
            return 0
        if not msg:
            return 0            # the master is gone or stopping
        for fd in fds:
            os.set_inheritable(fd, False)
        if len(fds) != 1:
            for fd in fds:
                os.close(fd)
            continue
        conn = socket.socket(fileno=fds[0])
        try:
            import json
            req = json.loads(msg[4:].decode("utf-8", "surrogateescape"))
            what, code, fit = run_job(req, conn)
        except BaseException as exc:      # noqa: BLE001 -- this process is not fit any more
            log(f"a job failed in the worker: {type(exc).__name__}: {exc}")
            what, code, fit = "done", 1, False
        finally:
            conn.close()
        with contextlib.suppress(OSError):
            channel.send(f"{what} {code} {int(fit)}".encode())
        if not fit:
            log(f"ending after a job with status {code}")
            return 0


if __name__ == "__main__":
    code = main()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)
