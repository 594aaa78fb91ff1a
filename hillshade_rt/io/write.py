"""How files are written: whole under their final name, or not at all.

Every file a run writes (rasters, the JSON report, PNG previews, scratch mosaics) goes through
:func:`atomic_path`: a hidden temporary file in the destination's folder, closed and checked
(GDAL's write errors, ``fsync``), then published under its final name by a rename that does not
replace a file that appeared meanwhile unless the run may overwrite (``os.link``, else Linux's
``renameat2(RENAME_NOREPLACE)``, else a last look before the rename). A path that is a symbolic
link is written through to its target (atomically, in the target's folder); devices, pipes and
sockets are refused. On any failure or interruption the temporary file is removed. A folder
(a Zarr store) goes the same way through :func:`atomic_folder`.

:class:`Claims` checks, before any work, that no path a run writes is one of its inputs (the same
file, through symbolic or hard links) or another of its outputs. :data:`completed` lists what this
run has published, so that an error or an interruption can say exactly which outputs are whole.

GDAL reports some write failures (a full disk while flushing blocks at close) only through its
error handler: :func:`gdal_checked` collects them (rasterio logs them) together with what GDAL's
TIFF library prints on the process's stderr, and turns them into one :class:`HillshadeError`.
"""

from __future__ import annotations

import contextlib
import contextvars
import ctypes
import errno
import json
import logging
import os
import re
import shutil
import signal
import socket
import sys
import tempfile
import threading

from ..errors import HillshadeError, Interrupted, UsageProblem

# what this process has published since the last reset() (final paths, in order)
completed: list[str] = []

# /vsimem/ outputs: for the Python API (api.shade sets it); the command line writes local files
virtual_outputs = contextvars.ContextVar("virtual_outputs", default=False)

SIGNALS = tuple(s for s in (getattr(signal, "SIGINT", None), getattr(signal, "SIGTERM", None),
                             getattr(signal, "SIGHUP", None)) if s is not None)


def reset() -> None:
    """Start a new run's list of published outputs."""
    completed.clear()
    caught.clear()
    _swept.clear()
    _deferral.update(depth=0, pending=None)


def is_virtual(path: str) -> bool:
    """A GDAL virtual file system path (/vsimem/, /vsizip/, ...) or a URL-like one."""
    p = os.fspath(path)
    return p.startswith("/vsi") or "://" in p


def target_of(path: str) -> str:
    """The file that writing ``path`` replaces: ``path`` itself, or the end of its chain of
    symbolic links (which may not exist yet). Devices, pipes, sockets and /dev, /proc paths are
    refused: a raster is never written over them."""
    path = os.fspath(path)
    if is_virtual(path):
        return path
    given, real = os.path.abspath(path), os.path.realpath(path)
    # /dev/stdout and the like name whatever the process's streams are (a terminal, a pipe, or a
    # file a shell redirected them to): never written over; /dev/shm is a file system like others
    if (given in ("/dev/stdout", "/dev/stderr", "/dev/stdin", "/dev/tty")
            or given.startswith(("/dev/fd/", "/proc/", "/sys/"))
            or real.startswith(("/proc/", "/sys/"))):
        raise HillshadeError(f"{path}: is a device or system file, not a file to write a "
                             "raster to; give a file name")
    if os.path.exists(real) and not os.path.isfile(real):
        what = "a folder" if os.path.isdir(real) else "not a regular file (a device, pipe or socket)"
        raise HillshadeError(f"{path}: is {what}; give a file name")
    return real


def same_file(a: str, b: str) -> bool:
    """Whether paths ``a`` and ``b`` name one file (through symbolic and hard links)."""
    if is_virtual(a) or is_virtual(b):
        return a == b
    try:
        if os.path.exists(a) and os.path.exists(b):
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.realpath(a) == os.path.realpath(b)


# the claims of a batch of runs (run.batch, ``--each``): while set, every run's Claims also
# checks its paths against the batch's inputs and the outputs of the batch's other runs
batch_claims = contextvars.ContextVar("batch_claims", default=None)


class Claims:
    """The paths one run will write, checked before any work against its inputs and each
    other; ``what`` names the option in messages ("OUTPUT", "--report", ...). Inside a batch
    (:data:`batch_claims`) also against the batch's inputs and its other runs' outputs."""

    def __init__(self, inputs=(), overwrite: bool = False):
        self.inputs = [os.fspath(p) for p in inputs if p is not None]
        self.overwrite = overwrite
        self.paths: list[tuple[str, str]] = []
        self.batch = batch_claims.get()
        if self.batch is not None:
            self.inputs += [p for p in self.batch.inputs if p not in self.inputs]

    def claim(self, path: str, what: str) -> str:
        """Check ``path`` (see :func:`check_output_path`) and that it is no input and no other
        output of the run; returns it."""
        path = os.fspath(path)
        check_output_path(path, self.overwrite)
        for p in self.inputs:
            if p != "-" and same_file(path, p):
                raise UsageProblem(f"{path}: {what} is also an input ({p}); give another path")
        for q, other in self.paths:
            if same_file(path, q):
                msg = (f"{path}: given twice as {what}" if other == what and path == q else
                       f"{path}: {what} and {other} name the same file; give different paths")
                raise UsageProblem(msg)
        if self.batch is not None:
            self.batch.claim(path, what)
        self.paths.append((path, what))
        return path


def is_stdout(path: str) -> bool:
    """Standard output as the command line spells it (``-``) or as GDAL does
    (``/vsistdout/``, ``/vsistdout_redirect/...``): refused alike, as a usage error."""
    return path == "-" or path.startswith("/vsistdout")


def check_output_path(path: str, overwrite: bool) -> str:
    """Fail early (before any computing) when ``path`` cannot be written."""
    path = os.fspath(path)
    if is_stdout(path):
        raise UsageProblem(f"{path!r} (standard output) is not supported for outputs: rasters "
                           "need a file they can seek in; give a file name")
    if is_virtual(path):
        if path.startswith("/vsimem/") and virtual_outputs.get():
            return path
        raise HillshadeError(f"{path}: outputs go to local files (or /vsimem/ from Python); "
                             "write here, then copy")
    if os.path.isdir(path):
        if not path.rstrip("/\\").lower().endswith(".zarr"):
            raise HillshadeError(f"{path}: is a folder")
        # a Zarr store (io.cube) is a folder: replaced by --overwrite, if it is one
        if not overwrite:
            raise HillshadeError(f"{path}: already exists (use --overwrite to replace it)")
        if not is_zarr_store(path):
            raise HillshadeError(f"{path}: is a folder that holds no Zarr store; not replaced")
        parent = os.path.dirname(os.path.abspath(path.rstrip("/\\")))
        if not os.access(parent, os.W_OK):
            raise HillshadeError(f"{path}: output folder {parent} is not writable")
        return path
    real = target_of(path)
    folder = os.path.dirname(real)
    if not os.path.isdir(folder):
        raise HillshadeError(f"{path}: output folder {os.path.dirname(os.path.abspath(path))} "
                             "does not exist")
    if os.path.lexists(path) and os.path.exists(real) and not overwrite:
        raise HillshadeError(f"{path}: already exists (use --overwrite to replace it)")
    if not os.access(folder, os.W_OK):
        raise HillshadeError(f"{path}: output folder {folder} is not writable")
    return path


def is_zarr_store(path: str) -> bool:
    """Whether the folder ``path`` holds a Zarr store (v2 or v3 metadata at its top): the only
    kind of folder an output (a time cube, ``io.cube``) replaces."""
    return any(os.path.isfile(os.path.join(path, n))
               for n in ("zarr.json", ".zgroup", ".zarray", ".zmetadata"))


def temp_beside(path: str, suffix: str) -> str:
    """A new empty file in the folder ``path`` is written to (through links), hidden, named
    after it and after the process writing it (:func:`owner_tag`):
    ``.NAME.<random>~<owner>.part.EXT``. The temporaries of dead runs in that folder are
    removed first (:func:`sweep_dead`)."""
    real = target_of(path)
    folder = os.path.dirname(real)
    sweep_dead(folder)
    suffix = "~" + owner_tag() + suffix
    name = os.path.basename(real)
    room = 255 - 10 - len(os.fsencode(suffix))     # a file name's bytes (the random part: 8)
    while len(os.fsencode(name)) > max(room, 1):
        name = name[:-1]
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix="." + name + ".", suffix=suffix)
    except OSError as exc:
        raise os_error(path, exc) from None
    os.close(fd)
    return tmp


# --------------------------------------------------------------------------------------------
# the temporaries of dead runs (SIGKILL, power loss)
#
# A temporary's name says who wrote it: ``~PID-START-BOOT-PIDNS@HOST`` before its suffix
# (``.part.EXT``, ``.scratch.EXT`` and the side-cars GDAL puts beside them): the process id,
# its start time (clock ticks since boot, /proc/PID/stat), the first 8 characters of the
# kernel's boot id, the inode of its pid namespace and the host name (characters other than
# letters, digits and '-' as '_'). A run writing into a folder removes the temporaries whose
# writer is provably dead: the same host and pid namespace, and another boot, or no process
# with that id, or one that started at another time (the id reused). Those of another host or
# namespace, of a live process, or without a tag (older versions) are kept. Folders are removed
# only where they are a Zarr store in the making (``.zarr``) or a run's scratch folder
# (``.scratch.dir``: :func:`scratch_folder`).

_TAGGED = re.compile(r"^\..+\.[A-Za-z0-9_]+~(?P<pid>\d+)-(?P<start>\d+)-(?P<boot>[0-9a-f]*)-"
                     r"(?P<ns>\d+)@(?P<host>[A-Za-z0-9_-]+)\.(?:part|scratch)(?:\..*)?$")
_swept: set[str] = set()        # folders swept during this run (reset() forgets them)


def _host() -> str:
    return re.sub(r"[^A-Za-z0-9-]", "_", socket.gethostname() or "localhost")[:64]


def _start_time(pid) -> int:
    """The process's start time in clock ticks since boot (field 22 of /proc/PID/stat); 0
    where there is no /proc; None when there is no such process."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            text = fh.read().decode("ascii", "replace")
    except FileNotFoundError:
        return None
    except OSError:
        return 0
    try:
        return int(text.rsplit(")", 1)[1].split()[19])
    except (IndexError, ValueError):
        return 0


def _boot_id() -> str:
    try:
        with open("/proc/sys/kernel/random/boot_id", encoding="ascii") as fh:
            return fh.read().strip().replace("-", "")[:8].lower()
    except OSError:
        return ""


def _pid_ns() -> int:
    try:
        return os.stat("/proc/self/ns/pid").st_ino
    except OSError:
        return 0


_OWNER: dict = {}


def owner_tag() -> str:
    """``PID-START-BOOT-PIDNS@HOST`` of this process (computed once per process)."""
    pid = os.getpid()
    if _OWNER.get("pid") != pid:        # a forked child is another writer
        _OWNER.update(pid=pid, tag=f"{pid}-{_start_time(pid) or 0}-{_boot_id()}-{_pid_ns()}"
                                   f"@{_host()}")
    return _OWNER["tag"]


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:         # another user's process
        return True
    except OSError:
        return True
    return True


def writer_dead(name: str) -> bool:
    """Whether the temporary file ``name`` (a base name) was written by a process that is
    provably dead: see above. False for names without the tag."""
    m = _TAGGED.match(name)
    if m is None or m["host"] != _host():
        return False
    if int(m["ns"]) != _pid_ns():
        return False
    if m["boot"] and _boot_id() and m["boot"] != _boot_id():
        return True                 # written before this machine last started
    pid = int(m["pid"])
    if not _alive(pid):
        return True
    start, now = int(m["start"]), _start_time(pid)
    return bool(start and now and now != start)     # the id now belongs to another process


def sweep_dead(folder: str) -> list[str]:
    """Remove the temporaries of dead runs in ``folder`` (files, and the folders of Zarr
    stores in the making, ``*.zarr``: ``io.cube``) once per folder per run; returns
    their paths. Never fails: an unreadable folder or a file gone meanwhile is passed over."""
    key = os.path.abspath(folder)
    if key in _swept:
        return []
    _swept.add(key)
    removed = []
    try:
        names = os.listdir(folder)
    except OSError:
        return removed
    for name in names:
        if not name.startswith(".") or "~" not in name or not writer_dead(name):
            continue
        p = os.path.join(folder, name)
        with contextlib.suppress(OSError):
            if os.path.isfile(p) and not os.path.islink(p):
                os.remove(p)
                removed.append(p)
            elif (name.endswith(".zarr") or name.endswith(SCRATCH_DIR)) and \
                    os.path.isdir(p) and not os.path.islink(p):
                shutil.rmtree(p)    # a Zarr store in the making (io.cube), a scratch folder
                removed.append(p)
    return removed


def os_error(path: str, exc: OSError) -> HillshadeError:
    """``exc`` as one line naming ``path`` (a full disk says so)."""
    reason = os.strerror(exc.errno).lower() if exc.errno else (str(exc) or type(exc).__name__)
    return HillshadeError(f"{path}: cannot write ({reason})")


# signals: the command line installs on_signal for SIGINT, SIGTERM and SIGHUP
caught: list[int] = []          # the signals this run received (the first one stops it)
_deferral = {"depth": 0, "pending": None}


def on_signal(signum, frame):
    """Stop the run: raise :class:`Interrupted` (a KeyboardInterrupt), so that every temporary
    file is removed on the way out; held back inside :func:`signals_deferred`; later signals
    are ignored while the run cleans up."""
    if caught or _deferral["pending"] is not None:
        return
    if _deferral["depth"]:
        _deferral["pending"] = signum
        return
    caught.append(signum)
    raise Interrupted(signum)


@contextlib.contextmanager
def signals_deferred():
    """A signal arriving inside the block stops the run only at its end: a publish (rename,
    side-cars, the list of what is complete) or a redirection of stderr is never cut in half.
    (Python runs signal handlers in the main thread between bytecodes whichever thread the
    system delivered the signal to, so masking it per thread would not do.)"""
    _deferral["depth"] += 1
    try:
        yield
    finally:
        _deferral["depth"] -= 1
        pending = _deferral["pending"]
        if _deferral["depth"] == 0 and pending is not None:
            _deferral["pending"] = None
            caught.append(pending)
            raise Interrupted(pending)


def _fsync(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


_RENAME_NOREPLACE = 1
_AT_FDCWD = -100


def _rename_noreplace(src: str, dst: str) -> bool:
    """Linux renameat2(RENAME_NOREPLACE); False where the system or file system lacks it."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        fn = libc.renameat2
    except (OSError, AttributeError):
        return False
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    if fn(_AT_FDCWD, os.fsencode(src), _AT_FDCWD, os.fsencode(dst), _RENAME_NOREPLACE) == 0:
        return True
    err = ctypes.get_errno()
    if err in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(err, os.strerror(err), dst)


def _appeared(path: str) -> HillshadeError:
    return HillshadeError(f"{path}: appeared while this run was writing it (another run?); kept "
                          "it and discarded this run's file (use --overwrite to replace it)")


def publish(tmp: str, final: str, overwrite: bool, shown: str | None = None) -> None:
    """Move the finished ``tmp`` to ``final`` (same folder). Without ``overwrite`` a file that
    exists at ``final`` by now is kept and :class:`HillshadeError` raised."""
    shown = shown or final
    if overwrite:
        os.replace(tmp, final)
        return
    try:
        os.link(tmp, final)
    except FileExistsError:
        raise _appeared(shown) from None
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.EOPNOTSUPP, errno.ENOSYS, errno.EXDEV,
                             errno.EMLINK, errno.EACCES, errno.EINVAL):
            raise
        try:
            if _rename_noreplace(tmp, final):
                return
        except FileExistsError:
            raise _appeared(shown) from None
        if os.path.lexists(final):      # a last look: the best a file system without links has
            raise _appeared(shown) from None
        os.rename(tmp, final)
        return
    os.remove(tmp)


def _virtual_remove(path: str) -> None:
    import rasterio.shutil
    with contextlib.suppress(Exception):
        rasterio.shutil.delete(path)


def _sidecars_of(tmp: str) -> list[str]:
    """Files GDAL wrote beside the temporary dataset ``tmp`` (x.aux.xml, x.prj, x.pgw, ...):
    named after it without its extension."""
    folder, name = os.path.split(tmp)
    stem = os.path.splitext(name)[0] + "."
    with contextlib.suppress(OSError):
        return [os.path.join(folder, f) for f in os.listdir(folder)
                if f.startswith(stem) and f != name]
    return []


@contextlib.contextmanager
def atomic_path(path: str, suffix: str = "", overwrite: bool = False, sidecars: bool = False):
    """Yield a temporary path beside ``path`` (beside its target when it is a link); when the
    block succeeds, the file is synced and published onto ``path`` (:func:`publish`); on any
    failure it is removed. ``sidecars``: files GDAL wrote next to the dataset (``.aux.xml``,
    ``.prj``, world files) are published with it, renamed after ``path``. /vsimem/ paths (the
    Python API) are written in place and deleted on failure."""
    path = os.fspath(path)
    if is_virtual(path):
        try:
            yield path
        except BaseException:
            _virtual_remove(path)
            raise
        completed.append(path)
        return
    final = target_of(path)
    tmp = temp_beside(path, ".part" + suffix)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; give the file the usual permissions
    stem, final_stem = os.path.splitext(tmp)[0], os.path.splitext(final)[0]
    try:
        yield tmp
        try:
            _fsync(tmp)
            with signals_deferred():
                publish(tmp, final, overwrite, path)
                for extra in (_sidecars_of(tmp) if sidecars else ()):
                    os.replace(extra, final_stem + extra[len(stem):])
                completed.append(path)
        except OSError as exc:
            raise os_error(path, exc) from None
    except BaseException:
        for p in [tmp] + (_sidecars_of(tmp) if sidecars else []):
            with contextlib.suppress(OSError):
                os.remove(p)
        raise


# --------------------------------------------------------------------------------------------
# a folder written whole or not at all (a time cube's Zarr store, io.cube)

def _fsync_tree(folder: str) -> None:
    for root, dirs, files in os.walk(folder):
        for n in files:
            fd = os.open(os.path.join(root, n), os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        with contextlib.suppress(OSError):     # (not every system syncs folders)
            fd = os.open(root, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)


def _publish_folder(tmp: str, final: str, overwrite: bool, shown: str) -> None:
    """Rename the finished folder ``tmp`` onto ``final``: without ``overwrite`` only where
    nothing is there (renameat2's RENAME_NOREPLACE, else a last look); with it an existing Zarr
    store is renamed aside, the new one into place, then the old removed."""
    if os.path.lexists(final):
        if not overwrite:
            raise _appeared(shown)
        if os.path.isdir(final) and not os.path.islink(final):
            if not is_zarr_store(final):
                raise HillshadeError(f"{shown}: is a folder that holds no Zarr store; not "
                                     "replaced")
            old = tempfile.mkdtemp(dir=os.path.dirname(final),
                                   prefix="." + os.path.basename(final) + ".",
                                   suffix="~" + owner_tag() + ".scratch.zarr")
            os.rename(final, os.path.join(old, "store"))
            try:
                os.rename(tmp, final)
            except OSError:
                os.rename(os.path.join(old, "store"), final)     # the old store back
                raise
            finally:
                shutil.rmtree(old, ignore_errors=True)
            return
        os.remove(final)
    try:
        if _rename_noreplace(tmp, final):
            return
    except FileExistsError:
        raise _appeared(shown) from None
    if os.path.lexists(final):
        raise _appeared(shown)
    os.rename(tmp, final)


SCRATCH_DIR = ".scratch.dir"       # the end of a run's scratch folder's name (scratch_folder)


def scratch_folder(path: str, kind: str) -> str:
    """A new hidden folder beside ``path`` for a run's scratch files (never published: the run
    removes it), named after ``path``, ``kind`` and the process (:func:`owner_tag`):
    ``.NAME.KIND.<random>~<owner>.scratch.dir``, so that a later run into that folder removes
    it (:func:`sweep_dead`) where this one was killed. The temporaries of dead runs there are
    removed first."""
    real = target_of(os.path.abspath(path))
    folder = os.path.dirname(real)
    sweep_dead(folder)
    suffix = "~" + owner_tag() + SCRATCH_DIR
    name = os.path.basename(real)[:120] + "." + kind + "."
    try:
        return tempfile.mkdtemp(dir=folder, prefix="." + name, suffix=suffix)
    except OSError as exc:
        raise os_error(path, exc) from None


@contextlib.contextmanager
def atomic_folder(path: str, suffix: str, overwrite: bool):
    """Yield a new hidden temporary folder beside ``path`` (``.NAME.<random>~<owner>.part
    .zarr``); when the block succeeds its files are synced and it is published onto ``path``
    (:func:`_publish_folder`); on any failure it is removed."""
    final = os.path.abspath(os.fspath(path).rstrip("/\\"))
    if os.path.islink(final):
        final = target_of(final) if not os.path.isdir(final) else os.path.realpath(final)
    folder = os.path.dirname(final)
    sweep_dead(folder)
    try:
        tmp = tempfile.mkdtemp(dir=folder, prefix="." + os.path.basename(final)[:200] + ".",
                               suffix="~" + owner_tag() + ".part" + suffix)
    except OSError as exc:
        raise os_error(path, exc) from None
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)   # mkdtemp makes 0700; the usual permissions
        yield tmp
        try:
            _fsync_tree(tmp)
            with signals_deferred():
                _publish_folder(tmp, final, overwrite, path)
                completed.append(path)
        except OSError as exc:
            raise os_error(path, exc) from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def write_json(path: str, obj: dict, overwrite: bool = False) -> None:
    """Write ``obj`` as JSON (temporary file, checked close, then rename)."""
    text = json.dumps(obj, indent=2) + "\n"
    with atomic_path(path, overwrite=overwrite) as tmp:
        try:
            with open(tmp, "w", encoding="utf-8") as fh:
                fh.write(text)
        except OSError as exc:
            raise os_error(path, exc) from None


# --------------------------------------------------------------------------------------------
# GDAL's write errors

class GdalRecords(logging.Handler):
    """Collects the failures GDAL signals in this thread while a block runs (rasterio logs them,
    in the thread that made the GDAL call)."""

    def __init__(self):
        super().__init__(logging.DEBUG)
        self.messages: list[str] = []
        self.thread = threading.get_ident()

    def emit(self, record):
        if record.thread != self.thread:
            return
        msg = record.getMessage()
        if msg.startswith("GDAL signalled an error") or record.levelno >= logging.ERROR:
            # "GDAL signalled an error: err_no=1, msg='...'"
            text = msg.split("msg=", 1)[-1].strip("'\"") if "msg=" in msg else msg
            self.messages.append(text)


class _StderrCapture:
    """The process's stderr (file descriptor 2) read into memory while a block runs: GDAL's TIFF
    library prints its I/O errors there ("_tiffWriteProc: No space left on device.")."""

    def __init__(self):
        self.text = ""
        self._saved = None

    def __enter__(self):
        try:
            with signals_deferred():
                return self._start()
        except BaseException:
            # a signal held back while stderr was being redirected stops the run here, before
            # the with-block: put stderr back first, or the run's last line would go into the
            # pipe and be lost (seen: exit 130 with nothing on stderr)
            self._stop()
            raise

    def _start(self):
        try:
            sys.stderr.flush()
        except (OSError, ValueError, AttributeError):
            pass
        try:
            r, w = os.pipe()
            self._saved = os.dup(2)
        except OSError:
            self._saved = None
            return self
        os.dup2(w, 2)
        os.close(w)
        chunks = []

        def drain():
            while True:
                try:
                    b = os.read(r, 65536)
                except OSError:
                    break
                if not b:
                    break
                chunks.append(b)
            os.close(r)
        self._chunks = chunks
        self._thread = threading.Thread(target=drain, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc):
        with signals_deferred():
            return self._stop()

    def _stop(self):
        if self._saved is None:
            return False
        os.dup2(self._saved, 2)      # closes the pipe's write end: the reader sees EOF
        os.close(self._saved)
        self._thread.join(5)
        self.text = b"".join(self._chunks).decode("utf-8", "replace")
        return False

    def replay(self):
        if self.text:
            with contextlib.suppress(OSError, ValueError):
                sys.stderr.write(self.text)
                sys.stderr.flush()


_CAPTURE = threading.Lock()


@contextlib.contextmanager
def stderr_dropped():
    """What GDAL's libraries print on the process's stderr while a block runs, dropped (a
    probe's expected failures, :func:`.raster.check_creation`); one thread at a time (another
    thread's block prints as usual)."""
    if not _CAPTURE.acquire(blocking=False):
        yield
        return
    try:
        with _StderrCapture():
            yield
    finally:
        _CAPTURE.release()


def disk_full(path: str) -> bool:
    with contextlib.suppress(OSError):
        st = os.statvfs(os.path.dirname(os.path.abspath(path)) or ".")
        return st.f_bavail * st.f_frsize < 64 * 1024
    return False


@contextlib.contextmanager
def gdal_checked(path: str, what: str = "cannot write"):
    """Run a block of GDAL writes (opening, writing, closing a dataset) so that every failure
    GDAL signals, even one it only prints, raises one :class:`HillshadeError` naming ``path``
    (a full disk says "no space left on device")."""
    import rasterio
    from rasterio._err import CPLE_BaseError
    from rasterio.errors import RasterioError

    rec = GdalRecords()
    log = logging.getLogger("rasterio._env")
    level = log.level
    log.addHandler(rec)
    if log.getEffectiveLevel() > logging.INFO:
        log.setLevel(logging.INFO)
    # stderr is the process's: one thread at a time reads it (another thread's writes go
    # without, their failures still come through rasterio's log)
    cap = _StderrCapture() if _CAPTURE.acquire(blocking=False) else contextlib.nullcontext()
    err = None
    try:
        with rasterio.Env(), cap:
            try:
                yield
            except (RasterioError, CPLE_BaseError) as exc:
                err = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            except OSError as exc:
                raise os_error(path, exc) from None
    finally:
        log.removeHandler(rec)
        log.setLevel(level)
        if isinstance(cap, _StderrCapture):
            _CAPTURE.release()
    printed = cap.text.lower() if isinstance(cap, _StderrCapture) else ""
    io_error = any(t in printed for t in ("no space left on device", "quota exceeded",
                                          "input/output error"))
    if err is None and not rec.messages and not io_error:
        if isinstance(cap, _StderrCapture):
            cap.replay()
        return
    full = ("no space left on device" in printed or disk_full(path)
            or any("no space" in m.lower() for m in rec.messages))
    if full:
        reason = "no space left on device"
    elif "quota" in printed:
        reason = "disk quota exceeded"
    elif "input/output error" in printed:
        reason = "input/output error"
    else:
        msgs = [m for m in rec.messages if m] or ([err] if err else [])
        useful = [m for m in msgs if "see previous exception" not in m.lower()]
        reason = (useful or msgs or ["GDAL write error"])[0]
    raise HillshadeError(f"{path}: {what} ({reason})")
