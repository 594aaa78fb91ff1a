"""numba's one-off start-up cost, paid while GDAL reads the DEM.

The first kernel a process loads from numba's cache costs 0.2-0.45 s more than the others:
numba imports its typing and lowering registries then (``BaseContext.refresh``), Python work
that holds the GIL. GDAL reads a raster with the GIL released. So ``while_numba_starts`` runs
a read in a thread while the calling thread does numba's start-up (under numba's compiler lock,
as its first compilation would): the two overlap (a 10000² DEM: the read stage 0.54 s ->
0.33-0.40 s). The calling thread does the start-up itself: no kernel ever runs on another
thread.
"""

from __future__ import annotations

import threading

_done = False


def start_numba() -> None:
    """numba's registries loaded now (once per process), not at the first kernel."""
    global _done
    if _done:
        return
    _done = True
    try:
        from numba.core.compiler_lock import global_compiler_lock
        from numba.core.registry import cpu_target
        with global_compiler_lock:
            cpu_target.target_context.refresh()
    except Exception:      # an internal API moved: the first kernel pays the cost, as before
        pass


def while_numba_starts(read):
    """``read()`` (I/O that releases the GIL) in a thread while this thread starts numba; its
    result, or its exception raised here."""
    if _done:
        return read()
    box = {}

    def run():
        try:
            box["value"] = read()
        except BaseException as exc:       # raised in the caller's thread below
            box["error"] = exc

    t = threading.Thread(target=run, name="hillshade-rt-read", daemon=True)
    t.start()
    start_numba()
    t.join()
    if "error" in box:
        raise box["error"]
    return box["value"]
