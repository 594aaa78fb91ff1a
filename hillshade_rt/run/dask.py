"""Windows and times as Dask tasks (``--scheduler``; needs ``pip install 'hillshade-rt[dask]'``).

Each task gets the small :class:`~hillshade_rt.engine.windows.WindowLighting` (the DEM's source,
the run's ``engine.lighting.Lighting`` whole, the body and the whole raster's range) and one
:class:`~hillshade_rt.engine.windows.PlannedWindow`; it opens the DEM itself (the path, or a mosaic's VRT
document, must be readable by the workers), reads the piece's window with its halo, lights it and
writes its region to a GeoTIFF of its own in a folder beside the output. Nothing large passes
through the scheduler: a task returns counts, timings and a few preview cells. When every task is
done the parts are put together through a VRT into the output (GeoTIFF or COG, GDAL streaming
block by block, written to a temporary file and renamed; a time cube part by part), and the
folder is removed, also when the run fails or is interrupted.

numba parallelises inside a task over the worker's cores; tasks of one worker process run one at
a time (a lock), so give workers one thread each (``dask worker --nthreads 1``); ``local:N``
starts such a cluster here.

When the cluster fails the run fails in one line naming the cause (``DaskSession.completed``):
the scheduler lost or silent, no worker for ``--worker-timeout`` seconds (none at the start, or
every one lost; a worker that comes back in time takes over, and a task run again rewrites its
part), a task Dask gave up on after its workers kept dying, tasks cancelled on the scheduler.
Every wait on the cluster is bounded.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import threading
import time

import numpy as np

from ..errors import HillshadeError

_LOCK = threading.Lock()   # one numba computation at a time per worker process


def client_for(scheduler):
    """(client, cluster or None) for ``scheduler``: a ``distributed.Client``, an address, or
    'local' / 'local:N' (N worker processes of one thread on this machine)."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise HillshadeError("--scheduler needs Dask: pip install 'hillshade-rt[dask]'") from None
    if not isinstance(scheduler, str):
        return scheduler, None
    if scheduler == "local" or scheduler.startswith("local:"):
        try:
            n = int(scheduler.split(":", 1)[1]) if ":" in scheduler else max(1, os.cpu_count() // 2)
        except ValueError:
            raise HillshadeError(f"--scheduler {scheduler!r}: use local or local:N") from None
        if n < 1:
            raise HillshadeError(f"--scheduler {scheduler!r}: N must be 1 or more")
        threads = max(1, (os.cpu_count() or 1) // n)
        import logging
        import warnings
        with warnings.catch_warnings():
            # the scheduler's HTTP server (no dashboard) moves off a busy port: nothing to say
            warnings.filterwarnings("ignore", message="Port .* is already in use")
            # the workers' logs (a task's failure, a restart) go to this run's stderr: the
            # run says what failed, in one line
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.CRITICAL,
                                   env={"NUMBA_NUM_THREADS": str(threads)})
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout="20s"), None
    except (OSError, TimeoutError, ValueError) as exc:
        raise HillshadeError(f"--scheduler {scheduler}: cannot connect "
                             f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
                             ) from None


# how long one question to the scheduler (its worker count; at most --worker-timeout) and
# closing the client may take, and the longest wait for anything between two looks at the
# cluster
PROBE_SECONDS = 10.0
POLL_SECONDS = 1.0
# the reason the client gives the futures it cancels when its connection to the scheduler breaks
# (distributed.Client._reconnect)
SCHEDULER_LOST = "scheduler-connection-lost"
# a result's fetch that fails on a closed connection: tried this many times (the client's own
# gather reschedules a result whose worker died), each after waiting this long for the client
# to say whether the scheduler is gone
COMM_RETRIES = 3
SETTLE_SECONDS = 2.0


class DaskSession:
    """One run's tasks on ``scheduler``: the client (and the local cluster ``client_for``
    started), a folder for the parts beside ``dest``, the futures the run submits
    (``futures``). ``completed`` yields their results as they come and turns the cluster's
    failures into one-line errors: the scheduler lost, no worker for ``worker_timeout`` seconds
    (none at the start, or every one lost), a window whose workers kept dying, tasks cancelled
    by someone else. Leaving it on a failure or an interruption cancels the futures; leaving it
    in any case removes the folder and closes the client and cluster it started (a client
    given by the caller stays open). Shared by the shadow runs, the horizon runs
    (``run.horizon_windows``) and the illumination runs."""

    def __init__(self, scheduler, dest: str, worker_timeout: float | None = None):
        from .config import DEFAULT_WORKER_TIMEOUT
        self.scheduler = scheduler
        self.worker_timeout = float(worker_timeout or DEFAULT_WORKER_TIMEOUT)
        # one question to the scheduler: never beyond the bound either
        self.probe = min(PROBE_SECONDS, self.worker_timeout)
        # tagged with this process (io.write.scratch_folder): a later run into the folder
        # removes it where this run was killed
        from ..io.write import scratch_folder
        self.folder = scratch_folder(dest, "parts")
        try:
            self.client, self.cluster = client_for(scheduler)
        except BaseException:
            _remove(self.folder)
            raise
        self.owned = self.client is not scheduler        # ours to close
        # a cluster's failures are this run's one line: what distributed logs about them on
        # the way (a gather rescheduled, a reconnection given up, a worker restarted, its
        # loop's unretrieved task errors) is not said too; a caller's own client keeps its logs
        self._muted = _dask_logs_muted(self.client) if self.owned else contextlib.nullcontext()
        self._muted.__enter__()
        try:
            self.address = self.client.scheduler.address
        except AttributeError:
            self.address = str(scheduler)
        self.futures: list = []
        self._none_since = None       # when the scheduler was first seen without a worker
        self._mute_since = None       # when it first did not answer
        self._had_workers = False

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None and self.futures:
            with contextlib.suppress(Exception):
                # a message to the scheduler (batched), never a wait: it may be gone
                self.client.cancel(self.futures)
        _remove(self.folder)
        try:
            if self.owned:
                with contextlib.suppress(Exception):
                    self.client.close(timeout=PROBE_SECONDS)
            if self.cluster is not None:
                with contextlib.suppress(Exception):
                    self.cluster.close()
        finally:
            self._muted.__exit__(None, None, None)
        return False

    def workers(self) -> int:
        """The scheduler's workers now (0 when it cannot say)."""
        n = self._workers_now()
        return n or 0

    def info(self, workers: int) -> dict:
        """What the report says of the scheduler."""
        return {"scheduler": (self.scheduler if isinstance(self.scheduler, str)
                              else str(self.client)),
                "workers": workers, "tasks": len(self.futures)}

    # -- the results, and the cluster's failures as one line each --------------------------------

    def completed(self, futures, what: str = "windows"):
        """(future, result) of each of ``futures`` as it finishes, in any order. Raises
        ``HillshadeError`` (one line, ``what`` done so far) when the scheduler is lost, when it
        has had no worker for ``worker_timeout`` seconds, when Dask gave up on a task whose
        workers kept dying or cancelled the tasks; a task's own ``HillshadeError`` is raised as
        it is, and any other exception of a task too (a bug)."""
        import queue
        arrived: queue.SimpleQueue = queue.SimpleQueue()
        for f in futures:
            f.add_done_callback(arrived.put)     # called in a thread of the client's
        left = {f.key for f in futures}
        total, done = len(left), 0
        poll = min(POLL_SECONDS, self.worker_timeout / 4)
        self._check(done, total, what)
        while left:
            try:
                f = arrived.get(timeout=poll)
            except queue.Empty:
                self._check(done, total, what)
                continue
            if f.key not in left:
                continue
            res = self._result(f, done, total, what, poll)
            left.discard(f.key)
            done += 1
            yield f, res

    def _result(self, f, done: int, total: int, what: str, poll: float):
        """``f``'s result; the wait bounded as the cluster's health is (its result's worker
        may die before it is fetched: Dask then computes it again)."""
        comm_errors = 0
        while True:
            try:
                return f.result(timeout=poll)
            except HillshadeError:
                raise
            except Exception as exc:    # noqa: BLE001 -- the cluster's failure, or a task's
                own = f.status in ("error", "cancelled")      # the task's outcome
                # distributed.TimeoutError is TimeoutError: the wait's, unless the task raised it
                if isinstance(exc, TimeoutError) and not own:
                    self._check(done, total, what)
                    continue
                # a connection closed while fetching (CommClosedError is an OSError): the
                # scheduler's, which the client notices at once, or a worker's, tried again
                if isinstance(exc, OSError) and not own:
                    comm_errors += 1
                    self._settle()
                    if self.client.status == "running" and comm_errors < COMM_RETRIES:
                        self._check(done, total, what)
                        continue
                err = self._failure(f, exc, done, total, what)
                if err is exc:
                    raise
                raise err from exc

    def _failure(self, f, exc, done: int, total: int, what: str) -> BaseException:
        """The exception to raise for ``exc`` out of ``f.result()``: one line naming the
        cluster's failure, or ``exc`` itself (a task's own error)."""
        from distributed import CancelledError, KilledWorker
        from distributed.comm import CommClosedError
        tail = f"; {done} of {total} {what} done"
        if isinstance(exc, CancelledError) or f.cancelled():
            reason = getattr(exc, "reason", None)
            if reason == SCHEDULER_LOST or self.client.status != "running":
                return HillshadeError(f"lost the Dask scheduler at {self.address}{tail}")
            said = f" ({reason})" if reason and reason != "unknown" else ""
            return HillshadeError(f"the Dask tasks of this run were cancelled on the scheduler "
                                  f"at {self.address}{said}{tail}")
        if isinstance(exc, KilledWorker):
            last = getattr(getattr(exc, "last_worker", None), "address", None)
            n = getattr(exc, "allowed_failures", None)
            times = (("once" if n == 0 else f"{n + 1} times") if isinstance(n, int)
                     else "repeatedly")
            return HillshadeError(
                f"Dask gave up on a task: the worker running it died {times}"
                f"{f' (last {last})' if last else ''}, killed or out of memory "
                f"(see the workers' logs; distributed.scheduler.allowed-failures){tail}")
        if f.status == "error":             # raised by the task on its worker
            if isinstance(exc, ImportError) and _importable_here(exc):
                return HillshadeError(f"a Dask worker cannot import what the task needs "
                                      f"({_first_line(exc)}): install hillshade-rt where the "
                                      f"workers run{tail}")
            if isinstance(exc, MemoryError):
                return HillshadeError(f"a Dask worker ran out of memory (give the workers more, "
                                      f"or smaller --window-size){tail}")
            return exc
        if isinstance(exc, (CommClosedError, OSError)):   # fetching the result
            if self.client.status != "running":
                return HillshadeError(f"lost the Dask scheduler at {self.address}{tail}")
            return HillshadeError(f"lost the connection to the Dask cluster at {self.address} "
                                  f"({_first_line(exc)}){tail}")
        return exc

    def _settle(self) -> None:
        """Give the client a moment to notice that its connection to the scheduler broke (it
        then stops 'running')."""
        deadline = time.monotonic() + SETTLE_SECONDS
        while self.client.status == "running" and time.monotonic() < deadline:
            time.sleep(0.05)

    def _workers_now(self) -> int | None:
        """How many workers the scheduler has (None: it did not answer in time)."""
        if self.client.status != "running":
            return None
        try:
            ident = self.client.sync(self.client.scheduler.identity, n_workers=0,
                                     callback_timeout=self.probe)
            return int(ident["n_workers"])
        except (OSError, RuntimeError, KeyError, TypeError):    # TimeoutError is an OSError
            return None

    def _check(self, done: int, total: int, what: str) -> None:
        """Fail when the scheduler is gone, or has been silent or without a worker for longer
        than ``worker_timeout``."""
        tail = f"; {done} of {total} {what} done"
        if self.client.status != "running":
            raise HillshadeError(f"lost the Dask scheduler at {self.address}{tail}")
        asked = time.monotonic()
        n = self._workers_now()
        now = time.monotonic()
        if n is None:
            if self.client.status != "running":
                raise HillshadeError(f"lost the Dask scheduler at {self.address}{tail}")
            self._mute_since = self._mute_since or asked
            if now - self._mute_since >= self.worker_timeout:
                raise HillshadeError(f"lost the Dask scheduler at {self.address} (no answer "
                                     f"for {now - self._mute_since:.0f} s){tail}")
            return
        self._mute_since = None
        if n > 0:
            self._none_since, self._had_workers = None, True
            return
        self._none_since = self._none_since or now
        if now - self._none_since >= self.worker_timeout:
            if self._had_workers or done:
                raise HillshadeError(f"no Dask worker left at {self.address} (none for "
                                     f"{self.worker_timeout:g} s, --worker-timeout){tail}")
            raise HillshadeError(f"no Dask worker at {self.address} (none joined in "
                                 f"{self.worker_timeout:g} s, --worker-timeout){tail}")


@contextlib.contextmanager
def _dask_logs_muted(client):
    """distributed's loggers silent for the block, and the exceptions of tasks that ``client``'s
    event loop would report (asyncio's "Task exception was never retrieved"); both restored
    after."""
    import logging
    names = ["distributed"] + [n for n in list(logging.root.manager.loggerDict)
                               if n.startswith("distributed.")]
    levels = {n: logging.getLogger(n).level for n in names}
    for n in names:
        logging.getLogger(n).setLevel(logging.CRITICAL + 1)
    loop = previous = None
    with contextlib.suppress(Exception):
        loop = client.loop.asyncio_loop
        previous = loop.get_exception_handler()
        loop.set_exception_handler(lambda loop, context: None)
    try:
        yield
    finally:
        for n, level in levels.items():
            logging.getLogger(n).setLevel(level)
        if loop is not None:
            with contextlib.suppress(Exception):
                loop.set_exception_handler(previous)


def _importable_here(exc: ImportError) -> bool:
    """Whether the module a worker could not import is there for this process (the workers'
    environment lacks it), not missing everywhere (a bug)."""
    import importlib.util
    name = getattr(exc, "name", None)
    if not name:
        return False
    try:
        return importlib.util.find_spec(name.split(".")[0]) is not None
    except (ImportError, ValueError):
        return False


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


def _remove(folder: str) -> None:
    """Remove the parts' folder; again if a worker still finishing a task wrote into it."""
    for _ in range(5):
        shutil.rmtree(folder, ignore_errors=True)
        if not os.path.lexists(folder):
            return
        time.sleep(0.2)


def write_part(path: str, arr, source, r0: int, c0: int, nodata, **profile) -> None:
    """A task's part of the output: ``arr`` (one band, or bands first: (bands, rows, cols)),
    whose first cell is the source's (r0, c0), as a tiled, deflated GeoTIFF at ``path`` in the
    source's CRS, written atomically. Overwrites: Dask runs a task again when its worker died
    before saying it was done, and the part it wrote then is the same. ``profile``: more
    creation options (a predictor)."""
    import warnings

    import rasterio
    from affine import Affine
    from rasterio.errors import NotGeoreferencedWarning

    from ..io import DEFLATE_LEVEL, atomic_path, gdal_checked
    arr3 = arr if arr.ndim == 3 else arr[np.newaxis]
    prof = dict(driver="GTiff", width=arr3.shape[2], height=arr3.shape[1], count=arr3.shape[0],
                dtype=arr.dtype.name, nodata=nodata, compress="deflate", zlevel=DEFLATE_LEVEL,
                tiled=True, blockxsize=256, blockysize=256, **profile)
    if source.crs is not None:
        prof["crs"] = source.crs
    if source.transform is not None:
        prof["transform"] = source.transform @ Affine.translation(c0, r0)
    with atomic_path(path, ".tif", overwrite=True) as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with gdal_checked(path), rasterio.open(tmp, "w", **prof) as dst:
            dst.write(arr3)


def shade_piece(job, piece, path: str, nodata, stride: int | None = None) -> dict:
    """The task: read ``piece``'s window, light it, write its region to ``path`` (GeoTIFF).
    Returns the product's cell counts, the algorithm's figures, bytes read, seconds, and the
    every-``stride``-th cells of its shade for a preview (with where they go there)."""
    import rasterio

    from ..pictures.preview import every_nth
    from ..engine.products import product
    from ..engine.windows import GDAL_CACHE_MB

    t0 = time.perf_counter()
    r0, r1, c0, c1 = piece.window
    z = np.empty((r1 - r0, c1 - c0), np.float32)
    stats: dict = {}
    used: set = set()
    with rasterio.Env(GDAL_CACHEMAX=GDAL_CACHE_MB), job.source.reader() as rd:
        rd.read(piece.window, z)
        nread = rd.bytes_read
    with _LOCK:
        arr = job.light(z, piece, stats, used)
    del z
    lighting = job.lighting       # the run's settings, whole (``engine.lighting.Lighting``)
    prod = product(job.kind, lighting.soft)
    st = prod.stats(arr)
    shade = None
    if stride:
        sub, at = every_nth(prod.shade(arr, lighting.ambient), piece.region[0],
                            piece.region[2], stride)
        shade = (sub.copy(), at)
    if lighting.soft:
        arr = np.where(np.isnan(arr), np.float32(nodata), arr).astype(np.float32)
    write_part(path, arr, job.source, piece.region[0], piece.region[2], nodata)
    return {"stats": st, "algorithm_stats": stats, "curvature_used": used, "bytes_read": nread,
            "seconds": time.perf_counter() - t0, "shade": shade}


def run_on_dask(scheduler, job, suns, plans, out, share, stride, quiet, algo_stats, used, tally,
                progress_mode="bar", worker_timeout=None):
    """Run every (sun, piece) as a task and assemble the outputs; returns (records, last stats,
    report figures). ``out`` is the command's output description (bands or files);
    ``worker_timeout``: ``DaskSession``'s."""
    from ..engine.products import merge_stats
    from .outputs import sun_tags
    from .report import progress_total
    from ..io import copy_vrt
    from ..io.vrt import VrtSource, vrt_xml
    from ..engine.windows import marched_per_cell

    dest = out.output or (out.tile_paths[0][0] if out.tile_paths else out.paths[0])
    with DaskSession(scheduler, dest, worker_timeout) as session:
        client, folder, futures = session.client, session.folder, session.futures
        workers = session.workers()
        keys = {}
        for i, pieces in enumerate(plans):
            for p in pieces:
                path = os.path.join(folder, f"b{i:05d}_r{p.region[0]}_c{p.region[2]}.tif")
                f = client.submit(shade_piece, job, p, path, out.nodata,
                                  stride if share is not None else None, pure=False)
                keys[f.key] = (i, p, path)
                futures.append(f)
        per_sun = [dict(stats=None, seconds=0.0) for _ in suns]
        bar = progress_total(len(futures), quiet, "hillshade-rt (dask)", "window",
                             progress_mode)
        with bar:
            for f, res in session.completed(futures):
                i, p, _ = keys[f.key]
                per_sun[i]["stats"] = merge_stats(per_sun[i]["stats"], res["stats"])
                per_sun[i]["seconds"] += res["seconds"]
                tally.add(p)
                tally.bytes_read += res["bytes_read"]
                used |= res["curvature_used"]
                for k, v in res["algorithm_stats"].items():
                    algo_stats.setdefault(k, v)
                if share is not None and res["shade"] is not None:
                    sh, (a, b) = res["shade"]
                    share[a:a + sh.shape[0], b:b + sh.shape[1]] += sh / len(suns)
                bar.update(1)
        # put the parts together: one VRT per output, copied (streaming) into place
        dtype = {"uint8": "Byte", "float32": "Float32"}[out.dtype]
        src = job.source

        def band_sources(i):
            return [VrtSource(path, 1, (p.region[0], p.region[2]),
                              (p.region[1] - p.region[0], p.region[3] - p.region[2]))
                    for (j, p, path) in keys.values() if j == i]
        if out.output is not None and out.cube is not None:    # a time cube: window by window
            import rasterio
            with out.writer(src, len(suns)) as w:
                for i, p, path in sorted(keys.values(), key=lambda k: (k[0], k[1].region)):
                    with rasterio.open(path) as part:
                        w.write(i + 1, part.read(1), window=p.region)
        elif out.output is not None:
            doc = vrt_xml(src.shape, src.transform, src.crs,
                          [band_sources(i) for i in range(len(suns))], dtype, out.nodata,
                          [out.description(s) for s in suns], out.base_tags,
                          [sun_tags(s) for s in suns])
            copy_vrt(doc, out.output, out.dtype, out.cog, out.resampling, out.overwrite, out.fmt,
                     out.co)
        else:
            for i, s in enumerate(suns):
                doc = vrt_xml(src.shape, src.transform, src.crs, [band_sources(i)], dtype,
                              out.nodata, [out.description(s)], {**out.base_tags, **sun_tags(s)})
                scratch = out.tile_paths is not None   # a mosaic cut into tiles: GeoTIFF
                copy_vrt(doc, out.target(i), out.dtype, out.file_cog, out.resampling,
                         out.overwrite or scratch, None if scratch else out.fmt,
                         None if scratch else out.co)
                out.finish(i, s, src)
        records = [out.record(s, i, per_sun[i]["stats"], per_sun[i]["seconds"],
                              marched_per_cell(plans[i]))
                   for i, s in enumerate(suns)]
        info = session.info(workers)
        return records, per_sun[-1]["stats"], info
