"""Timing reports: a JSON document for scripts and a one-line summary for people."""

from __future__ import annotations

import datetime as _dt
import os
import time
from contextlib import contextmanager

from .. import __version__


class Timer:
    """Wall-clock seconds per named stage (``with timer("read"): ...``)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._t0 = time.perf_counter()

    @contextmanager
    def __call__(self, stage: str, exclude: str | None = None):
        """Time the block as ``stage``; ``exclude``: a stage timed inside the block (e.g. the
        writes of a window's compute), whose seconds there are not counted twice."""
        t = time.perf_counter()
        inner = self.seconds.get(exclude, 0.0) if exclude else 0.0
        try:
            yield
        finally:
            took = time.perf_counter() - t
            if exclude:
                took -= self.seconds.get(exclude, 0.0) - inner
            self.seconds[stage] = self.seconds.get(stage, 0.0) + max(0.0, took)

    def total(self) -> float:
        return time.perf_counter() - self._t0


def build_report(*, dem, output: str, azimuth: float, elevation: float, algorithm: str,
                 backend: str, threads: int, seconds: dict, stats: dict,
                 height_range: tuple[float, float], options: dict | None = None,
                 algorithm_stats: dict | None = None, backend_requested: str | None = None,
                 gpu: dict | None = None) -> dict:
    """The report of one ``shadow`` run. Keys documented in docs/usage.md stay stable.

    ``height_range`` is the (min, max) the run already computed: no second pass over the DEM.
    ``gpu`` (GPU runs): device name, kernel milliseconds (CUDA events; None on the simulator),
    transfer milliseconds, host->device and device->host bytes."""
    from ..io import input_label
    rows, cols = dem.shape
    dx, dy = dem.grid.centre_spacing()
    compute = seconds.get("compute", 0.0)
    zmin, zmax = height_range
    return {
        "input": input_label(dem.path),
        "output": None if output is None else os.path.abspath(output),
        "shape": [rows, cols],
        "spacing_m": [dx, dy],
        "spacing_method": dem.grid.method,
        "crs": dem.crs_string(),
        "sun": {"azimuth": azimuth, "elevation": elevation},
        "algorithm": algorithm,
        "algorithm_options": dict(options or {}),
        "algorithm_stats": dict(algorithm_stats or {}),
        "backend": backend,
        "backend_requested": backend_requested or backend,
        "gpu": dict(gpu) if gpu else None,
        "threads": threads,
        "seconds": {k: seconds.get(k, 0.0) for k in ("read", "prepare", "compute", "write", "total")},
        "mpix_per_s": (rows * cols / 1e6 / compute) if compute > 0 else None,
        "shadow_fraction": stats["shadow_fraction"],
        "cells": {"valid": stats.get("valid_cells", (stats["shadow_cells"] or 0)
                                     + (stats["lit_cells"] or 0)),
                  "shadow": stats["shadow_cells"], "nodata": stats["nodata_cells"]},
        "height_range_m": [zmin, zmax],
        "version": __version__,
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }


def percent(frac: float) -> str:
    """A fraction as a percentage for people: 2 decimals, but never "0.00%" for a fraction that
    is not 0 nor "100.00%" for one that is not 1 ("<0.01%", ">99.99%"); exactly 0 and 1 are
    "0%" and "100%"."""
    if frac <= 0.0:
        return "0%"
    if frac >= 1.0:
        return "100%"
    if frac < 0.00005:
        return "<0.01%"
    if frac >= 0.99995:
        return ">99.99%"
    return f"{100 * frac:.2f}%"


def shown_paths(paths: list[str]) -> str:
    """Files written, for a summary line: all of them when few, else the first and the last and
    how many."""
    if len(paths) <= 2:
        return ", ".join(paths)
    return f"{paths[0]} .. {paths[-1]} ({len(paths)} files)"


def area_text(m2: float) -> str:
    """An area in square metres for people: whole m2 below a square kilometre, else km2 to 4
    significant digits."""
    if m2 < 1e6:
        return f"{m2:.0f} m2"
    return f"{m2 / 1e6:.4g} km2"


def vector_text(vector: dict) -> str:
    """The shadow polygons of a run (``run.shade``'s report ``vector``) for its summary line:
    their count, their area (a series: the mean of its times), the file (``shown``: as the
    user named it; None when the line names it already)."""
    n, m2, times = vector["polygons"], vector.get("area_m2"), vector.get("times")
    text = f"{n} shadow polygon{'' if n == 1 else 's'}"
    if m2 is not None:
        text += (f" ({area_text(m2 / len(times))} a time)" if times
                 else f" ({area_text(m2)})")
    if vector.get("shown"):
        text += f" in {vector['shown']}"
    return text


def summary_line(report: dict, shown: str | None = None, vector: dict | None = None) -> str:
    """One line for stderr. ``shown``: what to name the output(s) as (the paths as the user gave
    them; default the report's absolute output). ``vector``: the shadow polygons written
    (:func:`vector_text`)."""
    rows, cols = report["shape"]
    frac = report["shadow_fraction"]
    mpx = report["mpix_per_s"]
    gpu = report.get("gpu")
    algo = report["algorithm"]
    chose = ((report.get("algorithm_stats") or {}).get("auto") or {}).get("chose")
    if algo == "auto" and chose:    # what auto ran: "auto:bounds", or "auto:bounds+brute"
        algo = "auto:" + "+".join(sorted(chose, key=lambda k: -chose[k]))
    if gpu:
        kms = gpu.get("kernel_ms")
        where = (f"{algo}/gpu ({gpu['device']}"
                 + (f", kernels {kms:.2f} ms" if kms is not None else "") + ")")
    else:
        where = f"{algo}/{report['backend']} x{report['threads']}"
    times = report.get("times") or []
    sun = report.get("sun")
    if len(times) > 1:
        what = f"{len(times)} suns ({times[0].get('time', '')} .. {times[-1].get('time', '')})"
    elif sun and sun.get("time"):
        what = (f"sun at {sun['time']}: az {sun['azimuth']:.2f} el {sun['elevation']:.2f}"
                + (" (night)" if sun.get("night") else ""))
    else:
        what = f"sun az {report['sun']['azimuth']:g} el {report['sun']['elevation']:g}"
    share = ("" if frac is None else
             f"{percent(frac)} of valid cells in shadow" + (" (mean)" if len(times) > 1 else "")
             + "; ")
    if vector is not None:
        share += vector_text(vector) + "; "
    return (f"hillshade-rt: {report['output'] if shown is None else shown}: {cols}x{rows}, {what}, {where}: {share}"
            f"compute {report['seconds']['compute']:.3f} s"
            + (f" ({mpx * max(1, len(times)):.1f} Mpix/s)" if mpx else "")
            + f", total {report['seconds']['total']:.2f} s")


PROGRESS_MODES = ("bar", "json")    # --progress: tqdm's bar, or lines of JSON for programs


class JsonProgress:
    """Progress for a program reading stderr (--progress json): after each step a line
    ``{"progress": F}``, F the fraction done (0 < F <= 1, increasing, 1.0 last), flushed at
    once; a line only when F (to 3 decimals) changes. Iterates like tqdm over ``items``, or
    counts ``update(n)`` toward ``total``; a context manager like tqdm's bars."""

    def __init__(self, items=None, total: int | None = None, stream=None) -> None:
        self.items = items
        self.total = len(items) if total is None else int(total)
        self.done = 0
        self.said = 0.0
        self.stream = stream

    def __len__(self) -> int:
        return self.total

    def __iter__(self):
        for item in self.items:
            yield item
            self.update(1)

    def update(self, n: int = 1) -> None:
        import json
        import sys
        self.done += n
        frac = 1.0 if self.total <= 0 else round(min(self.done / self.total, 1.0), 3)
        if frac > self.said:
            self.said = frac
            stream = self.stream or sys.stderr
            stream.write(json.dumps({"progress": frac}) + "\n")
            stream.flush()

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def progress(items, quiet: bool, desc: str, unit: str = "time", mode: str = "bar"):
    """A tqdm bar on stderr over ``items`` (off with ``quiet``, and when stderr is no terminal);
    with ``mode`` "json" (--progress json) lines of JSON instead, whatever ``quiet`` says
    (:class:`JsonProgress`)."""
    items = list(items)
    if mode == "json":
        return JsonProgress(items)
    from tqdm import tqdm
    return tqdm(items, desc=desc, unit=unit, disable=True if quiet or len(items) < 2 else None,
                leave=False)


def progress_total(total: int, quiet: bool, desc: str, unit: str, mode: str = "bar"):
    """:func:`progress` counted by ``update(n)`` toward ``total`` instead of over items."""
    if mode == "json":
        return JsonProgress(total=total)
    from tqdm import tqdm
    return tqdm(total=total, desc=desc, unit=unit, leave=False,
                disable=True if quiet or total < 2 else None)
