"""Windows and times as Dask tasks (``--scheduler``; needs ``pip install 'hillshade-rt[dask]'``).

Each task gets the small :class:`~hillshade_rt.run.plan.Job` and one
:class:`~hillshade_rt.run.plan.Piece`; it opens the DEM itself (the path, or a mosaic's VRT
document, must be readable by the workers), reads the piece's window with its halo, lights it and
writes its region to a GeoTIFF of its own in a folder beside the output. Nothing large passes
through the scheduler: a task returns counts, timings and a few preview cells. When every task is
done the parts are put together through a VRT into the output (GeoTIFF or COG, GDAL streaming
block by block, written to a temporary file and renamed), and the folder is removed, also when
the run fails or is interrupted.

numba parallelises inside a task over the worker's cores; tasks of one worker process run one at
a time (a lock), so give workers one thread each (``dask worker --nthreads 1``); ``local:N``
starts such a cluster here.
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
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=None, env={"NUMBA_NUM_THREADS": str(threads)})
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout="20s"), None
    except (OSError, TimeoutError, ValueError) as exc:
        raise HillshadeError(f"--scheduler {scheduler}: cannot connect "
                             f"({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})"
                             ) from None


class DaskSession:
    """One run's tasks on ``scheduler``: the client (and the local cluster ``client_for``
    started), a folder for the parts beside ``dest``, the futures the run submits
    (``futures``). Leaving it on a failure or an interruption cancels them; leaving it in any
    case removes the folder and closes a local cluster. Shared by the shadow runs and the
    horizon runs (``run.reach``)."""

    def __init__(self, scheduler, dest: str):
        self.scheduler = scheduler
        self.client, self.cluster = client_for(scheduler)
        self.folder = tempfile.mkdtemp(dir=os.path.dirname(os.path.abspath(dest)),
                                       prefix="." + os.path.basename(dest) + ".parts-")
        self.futures: list = []

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None:
            with contextlib.suppress(Exception):
                self.client.cancel(self.futures)
        shutil.rmtree(self.folder, ignore_errors=True)
        if self.cluster is not None:
            with contextlib.suppress(Exception):
                self.client.close()
                self.cluster.close()
        return False

    def workers(self) -> int:
        return len(self.client.scheduler_info().get("workers", {}))

    def info(self, workers: int) -> dict:
        """What the report says of the scheduler."""
        return {"scheduler": (self.scheduler if isinstance(self.scheduler, str)
                              else str(self.client)),
                "workers": workers, "tasks": len(self.futures)}


def shade_piece(job, piece, path: str, nodata, stride: int | None = None) -> dict:
    """The task: read ``piece``'s window, light it, write its region to ``path`` (GeoTIFF).
    Returns the product's cell counts, the algorithm's figures, bytes read, seconds, and the
    every-``stride``-th cells of its shade for a preview (with where they go there)."""
    import rasterio
    from affine import Affine
    from rasterio.errors import NotGeoreferencedWarning

    from ..io import DEFLATE_LEVEL, atomic_path, gdal_checked
    from ..preview import every_nth
    from ..products import product
    from .plan import GDAL_CACHE_MB
    import warnings

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
    prod = product(job.kind, job.soft)
    st = prod.stats(arr)
    shade = None
    if stride:
        sub, at = every_nth(prod.shade(arr, job.ambient), piece.region[0],
                            piece.region[2], stride)
        shade = (sub.copy(), at)
    if job.soft:
        arr = np.where(np.isnan(arr), np.float32(nodata), arr).astype(np.float32)
    g0, g1, h0, h1 = piece.region
    src = job.source
    prof = dict(driver="GTiff", width=h1 - h0, height=g1 - g0, count=1, dtype=arr.dtype.name,
                nodata=nodata, compress="deflate", zlevel=DEFLATE_LEVEL, tiled=True,
                blockxsize=256, blockysize=256)
    if src.crs is not None:
        prof["crs"] = src.crs
    if src.transform is not None:
        prof["transform"] = src.transform @ Affine.translation(h0, g0)
    with atomic_path(path, ".tif") as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with gdal_checked(path), rasterio.open(tmp, "w", **prof) as dst:
            dst.write(arr, 1)
    return {"stats": st, "algorithm_stats": stats, "curvature_used": used, "bytes_read": nread,
            "seconds": time.perf_counter() - t0, "shade": shade}


def run_on_dask(scheduler, job, suns, plans, out, share, stride, quiet, algo_stats, used, tally,
                progress_mode="bar"):
    """Run every (sun, piece) as a task and assemble the outputs; returns (records, last stats,
    report figures). ``out`` is the command's output description (bands or files)."""
    from ..products import merge_stats
    from .outputs import sun_tags
    from .report import progress_total
    from ..io import copy_vrt
    from ..io.vrt import VrtSource, vrt_xml
    from .plan import marched_per_cell

    dest = out.output or (out.tile_paths[0][0] if out.tile_paths else out.paths[0])
    with DaskSession(scheduler, dest) as session:
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
        from distributed import as_completed
        per_sun = [dict(stats=None, seconds=0.0) for _ in suns]
        bar = progress_total(len(futures), quiet, "hillshade-rt (dask)", "window",
                             progress_mode)
        with bar:
            for f in as_completed(futures):
                res = f.result()
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
        if out.output is not None:
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
