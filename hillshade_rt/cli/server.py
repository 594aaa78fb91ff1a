"""The server's master process (``python -m hillshade_rt.cli.server``; ``hillshade-rt serve
start`` and ``HILLSHADE_RT_SERVER=auto`` start it): the socket, a pool of worker processes
(``worker.py``), the idle timeout. Standard library only, like ``client.py``: it imports
neither numpy nor numba, so its workers are fresh processes (spawned, never forked from a
process that ran a kernel), each running one job at a time (numba's default threading layer
runs one parallel kernel at a time per process).

The master accepts every connection (the peer must be this user: SO_PEERCRED), reads its
request and answers ``status`` and ``stop`` itself; a job whose key is not the server's is
``refused``; a job goes to an idle worker with the connection (the worker receives the
caller's working folder and standard streams itself, with the caller's ``go``), or waits for one at most ``--queue-wait`` seconds and
is then answered ``busy`` (the caller runs it itself: a full server never makes a call wait
longer than that). A worker reports ``ready`` once its imports are done and its kernels loaded
(or compiled: until then the callers run in their own processes), and ``done`` after each job;
one that ends is replaced. The server stops after ``--idle-timeout`` seconds without a job, on
``stop``, on SIGTERM, SIGINT or SIGHUP, and when the package's sources change under it.

Files, in the private folder (``client.runtime_dir``): ``<key>.sock`` (0600), ``<key>.lock``
(held with flock while a master runs: a second one exits), ``<key>.log``.
"""

from __future__ import annotations

import argparse
import fcntl
import os
import selectors
import signal
import socket
import subprocess
import sys
import time

from . import client

DEFAULT_IDLE = 600.0
DEFAULT_QUEUE_WAIT = 0.5
STARTUP_FAILURES = 3       # workers in a row that end before they are ready: the master stops


def default_workers() -> int:
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:
        n = os.cpu_count() or 1
    return max(1, min(n, 4))


def _number(environ, name, default, kind=float):
    try:
        value = kind(environ[name])
        return value if value >= 0 else default
    except (KeyError, ValueError):
        return default


def log(message: str) -> None:
    print(f"{time.strftime('%Y-%m-%d %H:%M:%S')} [{os.getpid()}] {message}", file=sys.stderr,
          flush=True)


def _sources_stamp() -> tuple:
    """The package's sources as they are now (names, sizes, times): a server whose sources
    changed serves nothing more and stops."""
    root = client.package_dir()
    found = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if not d.startswith((".", "__pycache__"))]
        for f in files:
            if f.endswith(".py"):
                try:
                    st = os.stat(os.path.join(folder, f))
                except OSError:
                    continue
                found.append((folder, f, st.st_size, st.st_mtime_ns))
    return tuple(sorted(found))


# seconds the idle timeout waits at least while no caller has seen a worker ready (a `serve
# start` descheduled on a loaded machine still finds its server)
SEEN_GRACE = 30.0

class Worker:
    def __init__(self, master: "Master", check_kernels: bool = False):
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.channel = ours
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "hillshade_rt.cli.worker", str(theirs.fileno())]
            + (["--check-kernels"] if check_kernels else []),
            pass_fds=[theirs.fileno()], cwd="/", stdin=subprocess.DEVNULL,
            env=dict(master.environ))
        theirs.close()
        self.state = "starting"
        self.jobs = 0
        self.since = time.monotonic()


class Master:
    def __init__(self, where: dict, idle_timeout: float, workers: int, queue_wait: float,
                 environ):
        self.where, self.idle_timeout, self.size = where, idle_timeout, workers
        self.queue_wait, self.environ = queue_wait, dict(environ)
        self.sel = selectors.DefaultSelector()
        self.workers: list[Worker] = []
        self.pending: list[tuple] = []      # (deadline, conn, fds, request)
        self.jobs = 0
        self.failures = 0
        self.started = time.time()
        self.last = time.monotonic()
        # whether a caller has seen a worker ready (a status answer with one, or a job): until
        # then the idle timeout waits at least SEEN_GRACE s, so that `serve start` on a busy
        # machine does not find a server already stopped idle before it could look
        self.seen = False
        self.stopping = None
        self.stamp = _sources_stamp()
        self.stamp_checked = time.monotonic()
        self.listener = None
        self.inode = None
        self.kernels_checked = False

    # -- the socket -------------------------------------------------------------------------
    def bind(self) -> None:
        path = self.where["socket"]
        if os.path.lexists(path):        # a stale socket (we hold the lock: no server runs)
            os.unlink(path)
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        old = os.umask(0o177)
        try:
            sock.bind(path)
        finally:
            os.umask(old)
        os.chmod(path, 0o600)
        self.inode = os.lstat(path).st_ino
        sock.listen(128)
        sock.setblocking(False)
        self.listener = sock
        self.sel.register(sock, selectors.EVENT_READ, ("listen", None))

    def unbind(self) -> None:
        if self.listener is None:
            return
        self.sel.unregister(self.listener)
        self.listener.close()
        self.listener = None
        try:      # ours only: never another server's socket
            if os.lstat(self.where["socket"]).st_ino == self.inode:
                os.unlink(self.where["socket"])
        except OSError:
            pass

    # -- workers ----------------------------------------------------------------------------
    def spawn(self) -> None:
        try:
            # the first worker makes sure this install's kernels are all cached (once)
            w = Worker(self, check_kernels=not self.kernels_checked)
        except OSError as exc:
            log(f"cannot start a worker: {exc}")
            self.failures += 1
            return
        self.kernels_checked = True
        self.workers.append(w)
        self.sel.register(w.channel, selectors.EVENT_READ, ("worker", w))
        log(f"worker {w.proc.pid} starting")

    def from_worker(self, w: Worker) -> None:
        try:
            msg = w.channel.recv(256)
        except OSError:
            msg = b""
        if not msg:
            self.ended(w)
            return
        words = msg.decode("ascii", "replace").split()
        if words[0] == "ready":
            log(f"worker {w.proc.pid} ready ({time.monotonic() - w.since:.1f} s)")
            w.state = "idle"
            self.failures = 0
            self.last = time.monotonic()     # idle counts from when there is a worker to serve
        elif words[0] == "done":
            w.jobs += 1
            self.jobs += 1
            self.last = time.monotonic()
            clean = len(words) > 2 and words[2] == "1"
            w.state = "idle" if clean else "ending"
            if not clean:
                log(f"worker {w.proc.pid} ends after a job with status {words[1]}")
        elif words[0] == "skipped":           # the caller went away before "go"
            w.state = "idle"
        self.assign()

    def ended(self, w: Worker) -> None:
        self.sel.unregister(w.channel)
        w.channel.close()
        self.workers.remove(w)
        try:
            code = w.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            w.proc.kill()
            code = w.proc.wait()
        if w.state == "starting":
            self.failures += 1
            log(f"worker {w.proc.pid} ended before it was ready (status {code}); see above")
        if self.stopping is None:
            if self.failures >= STARTUP_FAILURES:
                log(f"{self.failures} workers in a row failed to start: stopping")
                self.stop("workers fail to start")
            else:
                self.spawn()

    def assign(self) -> None:
        now = time.monotonic()
        while self.pending:
            idle = next((w for w in self.workers if w.state == "idle"), None)
            if idle is None:
                break
            _, conn, fds, req = self.pending.pop(0)
            try:
                client.send_frame(idle.channel, req, [conn.fileno(), *fds])
                idle.state = "busy"
                self.last = now
            except OSError as exc:
                log(f"cannot pass a job to worker {idle.proc.pid}: {exc}")
                self.answer(conn, {"type": "busy"})
                idle.state = "ending"
            finally:
                self.close_job(conn, fds)
        keep = []
        for item in self.pending:
            if item[0] <= now or self.stopping is not None:
                self.answer(item[1], {"type": "busy"})
                self.close_job(item[1], item[2])
            else:
                keep.append(item)
        self.pending = keep

    @staticmethod
    def close_job(conn, fds) -> None:
        conn.close()
        for fd in fds:
            try:
                os.close(fd)
            except OSError:
                pass

    @staticmethod
    def answer(conn, obj) -> None:
        try:
            conn.settimeout(1.0)
            client.send_frame(conn, obj)
        except OSError:
            pass

    # -- requests ---------------------------------------------------------------------------
    def accept(self) -> None:
        while self.listener is not None:       # (a request may stop the server)
            try:
                conn, _ = self.listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError as exc:
                log(f"accept: {exc}")
                return
            try:
                self.handle(conn)
            except Exception as exc:        # noqa: BLE001 -- one bad request stops nothing
                log(f"a request failed: {type(exc).__name__}: {exc}")
                conn.close()

    def handle(self, conn) -> None:
        conn.setblocking(True)
        if client.peer_uid(conn) != os.getuid():
            conn.close()
            return
        frames = client.Frames(conn)
        try:
            req = frames.read(1.0)
        except (OSError, ValueError, TimeoutError):
            req = None
        fds = frames.fds
        if not isinstance(req, dict):
            self.close_job(conn, fds)
            return
        kind = req.get("type")
        if req.get("proto") != client.PROTOCOL:
            self.answer(conn, {"type": "refused", "why": "protocol"})
        elif kind == "status":
            st = self.status()
            if not self.seen and st["workers"]["idle"] + st["workers"]["busy"] > 0:
                self.seen = True
                self.last = time.monotonic()     # idle counts from when the starter knew
            self.answer(conn, st)
        elif kind == "stop":
            self.answer(conn, dict(self.status(), type="stopping"))
            self.stop("asked to stop")
        elif kind == "job":
            if req.get("key") != self.where["key"]:
                self.answer(conn, {"type": "refused", "why": "another version or setting"})
            elif self.stopping is not None:
                self.answer(conn, {"type": "busy"})
            elif self.sources_changed():
                self.answer(conn, {"type": "refused", "why": "sources changed"})
                self.stop("the package's sources changed")
            else:
                self.last = time.monotonic()
                self.seen = True
                self.pending.append((time.monotonic() + self.queue_wait, conn, fds, req))
                self.assign()
                return
        self.close_job(conn, fds)

    def sources_changed(self) -> bool:
        now = time.monotonic()
        if now - self.stamp_checked < 1.0:
            return False
        self.stamp_checked = now
        return _sources_stamp() != self.stamp

    def status(self) -> dict:
        from .. import __version__
        count = {s: sum(w.state == s for w in self.workers)
                 for s in ("idle", "busy", "starting", "ending")}
        return {"type": "status", "pid": os.getpid(), "socket": self.where["socket"],
                "log": self.where["log"], "version": __version__,
                "install": client.package_dir(), "python": sys.executable,
                "idle_timeout": self.idle_timeout,
                "idle_for": round(time.monotonic() - self.last, 1),
                "uptime": round(time.time() - self.started, 1), "jobs": self.jobs,
                "workers": count, "size": self.size,
                "worker_pids": [w.proc.pid for w in self.workers]}

    # -- the loop ---------------------------------------------------------------------------
    def stop(self, why: str) -> None:
        if self.stopping is None:
            self.stopping = why
            log(f"stopping: {why}")
            self.unbind()

    def idle(self) -> bool:
        return (not self.pending and not any(w.state == "busy" for w in self.workers)
                and self.idle_timeout > 0
                and time.monotonic() - self.last >= (self.idle_timeout if self.seen else
                                                     max(self.idle_timeout, SEEN_GRACE)))

    def run(self) -> int:
        wake_r, wake_w = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
        caught = []
        for s in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
            signal.signal(s, lambda signum, frame: caught.append(signum))
        signal.set_wakeup_fd(wake_w)
        self.sel.register(wake_r, selectors.EVENT_READ, ("wake", None))
        for _ in range(self.size):
            self.spawn()
        while self.stopping is None:
            timeout = 1.0
            if self.pending:
                timeout = max(0.0, min(timeout, min(p[0] for p in self.pending)
                                       - time.monotonic()))
            for keyobj, _ in self.sel.select(timeout):
                what, w = keyobj.data
                if what == "listen" and self.listener is not None:
                    self.accept()
                elif what == "worker" and w in self.workers:
                    self.from_worker(w)
                elif what == "wake":
                    try:
                        os.read(wake_r, 512)
                    except OSError:
                        pass
            self.assign()
            if caught:
                self.stop(f"signal {caught[0]}")
            elif self.idle():
                self.stop(f"idle for {self.idle_timeout:g} s")
        self.shutdown()
        return 0

    def shutdown(self) -> None:
        self.unbind()
        self.assign()                  # pending callers: busy (they run the job themselves)
        for w in self.workers:         # a worker reads the end of its channel and exits once
            w.channel.close()          # its job, if any, is done
        limit = time.monotonic() + 5.0
        for w in self.workers:
            if w.state == "busy":
                continue               # let it finish its job; it exits after
            try:
                w.proc.wait(timeout=max(0.1, limit - time.monotonic()))
            except subprocess.TimeoutExpired:
                w.proc.terminate()
        log(f"stopped after {self.jobs} job(s)")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m hillshade_rt.cli.server")
    p.add_argument("--key", help="start only when this is the key of this process's settings")
    p.add_argument("--idle-timeout", type=float,
                   default=_number(os.environ, "HILLSHADE_RT_SERVER_IDLE", DEFAULT_IDLE))
    p.add_argument("--workers", type=int,
                   default=_number(os.environ, "HILLSHADE_RT_SERVER_WORKERS", default_workers(),
                                   int))
    p.add_argument("--queue-wait", type=float, default=DEFAULT_QUEUE_WAIT)
    p.add_argument("--foreground", action="store_true", help="log to stderr")
    args = p.parse_args(argv)
    where = client.paths(os.environ)
    if args.key and args.key != where["key"]:
        return 3        # the caller's settings are not this process's: serve nobody
    problem = client.make_folder(where["folder"])
    if problem:
        print(f"hillshade-rt serve: {problem}", file=sys.stderr)
        return 1
    if len(os.fsencode(where["socket"])) > client.SUN_PATH_MAX:
        print(f"hillshade-rt serve: {where['socket']}: path too long for a socket",
              file=sys.stderr)
        return 1
    lock = os.open(where["lock"], os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        return 0        # another master of this key runs
    if not args.foreground:
        out = os.open(where["log"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW
                      | os.O_CLOEXEC, 0o600)
        os.dup2(out, 1)
        os.dup2(out, 2)
        os.close(out)
    master = Master(where, args.idle_timeout, max(1, args.workers), args.queue_wait,
                    os.environ)
    master.bind()
    log(f"serving {where['socket']} (idle timeout {args.idle_timeout:g} s, "
        f"{master.size} worker(s))")
    try:
        return master.run()
    finally:
        master.unbind()
        os.close(lock)


if __name__ == "__main__":
    sys.exit(main())
