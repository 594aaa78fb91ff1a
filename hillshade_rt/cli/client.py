"""The command line's way to a warm server (``hillshade-rt serve``): what ``main`` tries before
it imports click, the commands or numpy, so that a call the server takes costs an interpreter's
start and a socket (docs/usage.md, "A warm server for batches").

Standard library only: this module runs on every call of ``hillshade-rt`` and in the server's
master process (``server.py``), which never imports numpy, numba or GDAL.

The setting ``HILLSHADE_RT_SERVER``: ``auto`` (use this install's server, start one in the
background when there is none: that call runs here), unset (use a running server, start none;
``hillshade-rt serve start`` started it), ``off`` (never). A server is found at
``$XDG_RUNTIME_DIR/hillshade-rt/<key>.sock`` (else ``/tmp/hillshade-rt-<uid>/``), in a folder
that must be a real folder (not a link) of this user's with mode 0700; ``<key>`` is a digest of
this version, this install, this Python and the settings read once at import (NUMBA_*, GDAL_*,
CPL_*, PROJ_*, the locale, the kernel cache's location): a server serves only calls that would
run the same code the same way. Any failure to hand the call over (no server, a stale socket, a
server of another key, a refusal, a full server, a timeout, a server gone before the job was
accepted) returns None: the call runs in this process, as if there were no server, and says
nothing about it.

One call: connect; send the request (command line, environment, umask); the server's master
answers ``busy``/``refused`` or passes the call to a worker, which answers ``accepted``; this
process answers ``go`` with the descriptors of its working folder, stdin, stdout and stderr
(SCM_RIGHTS: the job writes to this terminal or pipe itself, isatty as here; they are sent only
to a worker that has just answered, never left in a wedged server's queue, where they would keep
a pipe of this process's open after it ended). From ``go`` on the job is the server's (it is
never run twice) and this process waits for ``status``. SIGINT, SIGTERM and SIGHUP are
passed on as ``cancel`` (the job stops as it would here: 130, 143, 129, its unfinished output
removed); a worker that ends without a status (killed, crashed) ends the call with one line
and status 1 (atomic outputs: nothing half-written is left under its name).
"""

from __future__ import annotations

import json
import os
import select
import signal
import socket
import stat
import struct
import sys
import time

PROTOCOL = 1
SETTING = "HILLSHADE_RT_SERVER"
# commands that never go to a server: the server itself, the interactive viewer (a web server
# of its own that runs until stopped)
LOCAL_COMMANDS = frozenset({"serve", "view"})
CONNECT_TIMEOUT = 1.0        # connect() to the socket
REPLY_TIMEOUT = 3.0          # the master's or worker's answer to a request, the worker's "go"
CANCEL_WAIT = 10.0           # after passing a signal on: how long the job may take to stop
SUN_PATH_MAX = 107           # sockaddr_un's path, less its terminating NUL
# the settings a process reads once (at an import, at the first use) and that change what the
# run does: a server serves only callers that have the same ones
_KEY_PREFIXES = ("NUMBA_", "GDAL_", "CPL_", "PROJ_", "CUDA_", "PYTHON", "LC_")
_KEY_NAMES = ("HOME", "XDG_CACHE_HOME", "LANG", "LANGUAGE", "TMPDIR", "LD_LIBRARY_PATH",
              "LD_PRELOAD", "VIRTUAL_ENV")


def mode(environ=os.environ) -> str:
    """``off``, ``running`` (the default: use a server that runs, start none) or ``auto``."""
    value = environ.get(SETTING, "").strip().lower()
    if value in ("", "running", "default"):
        return "running"
    if value in ("auto", "on", "1", "yes", "true"):
        return "auto"
    return "off"            # off, 0, no, false, and anything not understood


def runtime_dir(environ=os.environ) -> str:
    """The folder of this user's server sockets."""
    base = environ.get("XDG_RUNTIME_DIR", "")
    if base and os.path.isabs(base):
        return os.path.join(base, "hillshade-rt")
    return os.path.join("/tmp", f"hillshade-rt-{os.getuid()}")


def folder_problem(path: str, uid: int | None = None) -> str | None:
    """Why ``path`` is no private folder of the user ``uid`` (None when it is one): it must be a
    folder itself (lstat: a symbolic link is refused), owned by ``uid``, readable and writable
    by nobody else."""
    uid = os.getuid() if uid is None else uid
    try:
        st = os.lstat(path)
    except OSError as exc:
        return f"{path}: {exc.strerror}"
    if stat.S_ISLNK(st.st_mode):
        return f"{path} is a symbolic link"
    if not stat.S_ISDIR(st.st_mode):
        return f"{path} is not a folder"
    return _not_private(path, st, uid, "700")


def _not_private(path: str, st, uid: int, mode: str) -> str | None:
    """Why ``st`` (``path``'s lstat) is not the user ``uid``'s alone (None when it is)."""
    if st.st_uid != uid:
        return f"{path} is owned by uid {st.st_uid}, not {uid}"
    if st.st_mode & 0o077:
        return f"{path} has mode {stat.S_IMODE(st.st_mode):o}, not {mode}"
    return None


def socket_problem(path: str, uid: int | None = None) -> str | None:
    """Why ``path`` is no socket of the user ``uid`` with mode 0600 (None when it is one)."""
    uid = os.getuid() if uid is None else uid
    try:
        st = os.lstat(path)
    except OSError as exc:
        return f"{path}: {exc.strerror}"
    if not stat.S_ISSOCK(st.st_mode):
        return f"{path} is not a socket"
    return _not_private(path, st, uid, "600")


def make_folder(path: str) -> str | None:
    """Create the private folder if it is missing (0700); why it is unusable, or None."""
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    except OSError as exc:
        return f"{path}: {exc.strerror}"
    return folder_problem(path)


def package_dir() -> str:
    return os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def server_key(environ=os.environ) -> str:
    """What a server must share with its callers, as a digest: the protocol, this version, this
    install, this Python, and the settings read once per process (``_KEY_PREFIXES``,
    ``_KEY_NAMES``; not ``HILLSHADE_RT_SERVER*``)."""
    import hashlib

    from .. import __version__
    settings = sorted((k, v) for k, v in environ.items()
                      if k.startswith(_KEY_PREFIXES) or k in _KEY_NAMES)
    what = [PROTOCOL, __version__, os.path.realpath(package_dir()), sys.executable, sys.prefix,
            sys.version, settings]
    return hashlib.sha256(json.dumps(what).encode("utf-8", "surrogateescape")).hexdigest()[:24]


def paths(environ=os.environ, key: str | None = None) -> dict:
    """The folder and this key's socket, lock and log files."""
    folder = runtime_dir(environ)
    key = key or server_key(environ)
    base = os.path.join(folder, key)
    return {"folder": folder, "key": key, "socket": base + ".sock", "lock": base + ".lock",
            "log": base + ".log"}


# ------------------------------------------------------------------------------------------
# frames: a 4-byte length, then JSON (the first frame of a request carries the descriptors)

def send_frame(sock, obj, fds=()) -> None:
    data = json.dumps(obj).encode("utf-8", "surrogateescape")
    frame = struct.pack("!I", len(data)) + data
    if fds:
        sent = socket.send_fds(sock, [frame], list(fds))
        frame = frame[sent:]
    if frame:
        sock.sendall(frame)


class Frames:
    """The frames arriving on a stream socket, one at a time, each read by a deadline."""

    def __init__(self, sock, want_fds: int = 0):
        self.sock = sock
        self.buf = b""
        self.want_fds = want_fds
        self.fds: list[int] = []

    def read(self, timeout: float | None, wake: int | None = None):
        """The next frame's object; None at the end of the stream; TimeoutError past
        ``timeout`` seconds; InterruptedError when ``wake`` (a descriptor) becomes readable
        first (a signal arrived)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            if len(self.buf) >= 4:
                n = struct.unpack("!I", self.buf[:4])[0]
                if len(self.buf) >= 4 + n:
                    data, self.buf = self.buf[4:4 + n], self.buf[4 + n:]
                    return json.loads(data.decode("utf-8", "surrogateescape"))
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise TimeoutError("no answer in time")
            watched = [self.sock] if wake is None else [self.sock, wake]
            ready = select.select(watched, [], [], left)[0]
            if wake is not None and wake in ready:
                raise InterruptedError
            if self.sock not in ready:
                continue
            if self.want_fds:
                data, fds, _, _ = socket.recv_fds(self.sock, 1 << 16, self.want_fds)
                self.want_fds = 0
                for fd in fds:
                    os.set_inheritable(fd, False)
                self.fds += fds
            else:
                data = self.sock.recv(1 << 16)
            if not data:
                return None
            self.buf += data


def peer_uid(sock) -> int:
    """The user of the process at the other end of a Unix socket (SO_PEERCRED)."""
    creds = sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i"))
    return struct.unpack("3i", creds)[1]


def connect(path: str, timeout: float = CONNECT_TIMEOUT):
    """A connection to the server at ``path`` (a socket of this user's in a private folder,
    the server's process this user's too), or None."""
    if len(os.fsencode(path)) > SUN_PATH_MAX:
        return None
    if folder_problem(os.path.dirname(path)) or socket_problem(path):
        return None
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.settimeout(timeout)
        sock.connect(path)
        if peer_uid(sock) != os.getuid():
            raise ConnectionRefusedError
    except OSError:
        sock.close()
        return None
    return sock


def request(path: str, req: dict, timeout: float = REPLY_TIMEOUT) -> dict | None:
    """A control request (``status``, ``stop``) to the server at ``path``: its answer, or None
    when there is no server there to answer."""
    sock = connect(path)
    if sock is None:
        return None
    try:
        send_frame(sock, dict(req, proto=PROTOCOL))
        return Frames(sock).read(timeout)
    except (OSError, ValueError):
        return None
    finally:
        sock.close()


# ------------------------------------------------------------------------------------------
# handing a command line over

def goes_to_server(argv, environ=os.environ) -> bool:
    """Whether this command line may go to a server: a command (not --help or --version of the
    program itself, nor shell completion), not one of ``LOCAL_COMMANDS``."""
    return (bool(argv) and not argv[0].startswith("-") and argv[0] not in LOCAL_COMMANDS
            and "_HILLSHADE_RT_COMPLETE" not in environ)


def hand_over(argv, environ=os.environ) -> int | None:
    """Run the command line ``argv`` on this install's server: its exit status, or None when it
    is to run in this process (no usable server; nothing said)."""
    how = mode(environ)
    if how == "off" or not goes_to_server(argv, environ):
        return None
    try:
        if how == "running" and folder_problem(runtime_dir(environ)):
            return None      # no server can be there (one lstat: a plain call's whole cost)
        where = paths(environ)
        sock = connect(where["socket"])
    except Exception:        # noqa: BLE001 -- anything here means: run in this process
        return None
    if sock is None:
        if how == "auto":
            start_in_background(environ, where)
        return None
    with sock:
        return _Call(sock, where["key"], argv, environ).run()


def start_in_background(environ=os.environ, where: dict | None = None, options=()) -> object:
    """Start this install's server, detached (its own session, no terminal, stdio to
    /dev/null: its log is ``<key>.log``), and return its process (``subprocess.Popen``) or
    None when it could not be started. A server already running makes the new one exit."""
    try:
        where = where or paths(environ)
        if make_folder(where["folder"]):
            return None
        import subprocess
        return subprocess.Popen(
            [sys.executable, "-m", "hillshade_rt.cli.server", "--key", where["key"], *options],
            cwd="/", env=dict(environ), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL, start_new_session=True, close_fds=True)
    except Exception:        # noqa: BLE001 -- the call runs here all the same
        return None


def _signal_name(signum: int) -> str:
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


class _Call:
    """One command line handed to the server (``hand_over``)."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

    def __init__(self, sock, key, argv, environ):
        self.sock, self.key, self.argv, self.environ = sock, key, list(argv), environ
        self.caught: list[int] = []
        self.frames = Frames(sock)

    def _on_signal(self, signum, frame):
        self.caught.append(signum)

    def run(self) -> int | None:
        try:
            cwd = os.open(".", os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        except OSError:
            return None
        try:
            for fd in (0, 1, 2):
                os.fstat(fd)     # a closed standard stream: run here, where Python knows it
        except OSError:
            os.close(cwd)
            return None
        wake_r, wake_w = os.pipe2(os.O_NONBLOCK | os.O_CLOEXEC)
        previous = {}
        try:
            for s in self.SIGNALS:
                previous[s] = signal.signal(s, self._on_signal)
            old_wake = signal.set_wakeup_fd(wake_w)
        except (OSError, ValueError):      # not the main thread: no signals of our own
            for s, h in previous.items():
                signal.signal(s, h)
            os.close(cwd)
            os.close(wake_r)
            os.close(wake_w)
            return None
        try:
            return self._exchange(cwd, wake_r)
        finally:
            signal.set_wakeup_fd(old_wake)
            for s, h in previous.items():
                signal.signal(s, h)
            for fd in (cwd, wake_r, wake_w):
                os.close(fd)

    def _interrupted_before(self) -> int:
        """A signal before the server took the job: nothing ran; as the command line says."""
        signum = self.caught[0]
        sys.stderr.write(f"hillshade-rt: interrupted ({_signal_name(signum)}); "
                         "no output written\n")
        return 128 + signum

    def _exchange(self, cwd: int, wake: int) -> int | None:
        umask = os.umask(0o022)
        os.umask(umask)
        req = {"type": "job", "proto": PROTOCOL, "key": self.key, "argv": self.argv,
               "env": dict(self.environ), "umask": umask}
        try:
            send_frame(self.sock, req)
            deadline = time.monotonic() + REPLY_TIMEOUT
            while True:       # the master's answer, or the worker's
                try:
                    answer = self.frames.read(max(deadline - time.monotonic(), 0.0), wake)
                except InterruptedError:
                    _drain(wake)
                    if self.caught:
                        return self._interrupted_before()
                    continue
                break
            if not isinstance(answer, dict) or answer.get("type") != "accepted":
                return None        # busy, refused, gone, or something else: run here
            pid = answer.get("pid")
            send_frame(self.sock, {"type": "go"}, [cwd, 0, 1, 2])
        except (OSError, ValueError, TimeoutError):
            return None
        except Exception:        # noqa: BLE001 -- not yet committed: run here
            return None
        return self._wait(pid, wake)

    def _wait(self, pid, wake: int) -> int:
        """The job is the server's now: its status, signals passed on, a lost worker said."""
        passed = None
        deadline = None
        while True:
            if self.caught and passed is None:
                passed = self.caught[0]
                try:
                    send_frame(self.sock, {"type": "cancel", "signal": passed})
                except OSError:
                    pass
                deadline = time.monotonic() + CANCEL_WAIT
            if passed is not None and (len(self.caught) > 1
                                       or time.monotonic() >= deadline):
                sys.stderr.write(f"hillshade-rt: interrupted ({_signal_name(passed)}); the "
                                 f"server (worker pid {pid}) is still stopping the run, which "
                                 "removes its unfinished output\n")
                return 128 + passed
            try:
                left = None if deadline is None else max(deadline - time.monotonic(), 0.0)
                msg = self.frames.read(left, wake)
            except InterruptedError:
                _drain(wake)
                continue
            except TimeoutError:
                continue
            except (OSError, ValueError):
                msg = None
            if isinstance(msg, dict) and msg.get("type") == "status":
                code = msg.get("code")
                return code if isinstance(code, int) else 1
            if msg is None:
                sys.stderr.write(f"hillshade-rt: error: the server's worker (pid {pid}) ended "
                                 "during the run without finishing it; outputs it had not "
                                 "completed were not written\n")
                return 1


def _drain(fd: int) -> None:
    try:
        while os.read(fd, 512):
            pass
    except OSError:
        pass
