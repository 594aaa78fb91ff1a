"""Timing reports: a JSON document for scripts and a one-line summary for people."""

from __future__ import annotations

import datetime as _dt
import os
import time
from contextlib import contextmanager

import numpy as np

from . import __version__


class Timer:
    """Wall-clock seconds per named stage (``with timer("read"): ...``)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._t0 = time.perf_counter()

    @contextmanager
    def __call__(self, stage: str):
        t = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[stage] = self.seconds.get(stage, 0.0) + time.perf_counter() - t

    def total(self) -> float:
        return time.perf_counter() - self._t0


def mask_stats(mask: np.ndarray) -> dict:
    """Counts of shadow / lit / nodata cells of a uint8 mask (1 / 0 / 255)."""
    counts = np.bincount(mask.ravel(), minlength=256)
    shadow, lit, nodata = int(counts[1]), int(counts[0]), int(counts[255])
    valid = shadow + lit
    return {"shadow_cells": shadow, "lit_cells": lit, "nodata_cells": nodata,
            "shadow_fraction": (shadow / valid) if valid else None}


def build_report(*, dem, output: str, azimuth: float, elevation: float, algorithm: str,
                 backend: str, threads: int, seconds: dict, stats: dict,
                 height_range: tuple[float, float], options: dict | None = None,
                 algorithm_stats: dict | None = None, backend_requested: str | None = None,
                 gpu: dict | None = None) -> dict:
    """The report of one ``shadow`` run. Keys documented in docs/usage.md stay stable.

    ``height_range`` is the (min, max) the run already computed: no second pass over the DEM.
    ``gpu`` (GPU runs): device name, kernel milliseconds (CUDA events; None on the simulator),
    transfer milliseconds, host->device and device->host bytes."""
    rows, cols = dem.shape
    dx, dy = dem.grid.centre_spacing()
    compute = seconds.get("compute", 0.0)
    zmin, zmax = height_range
    return {
        "input": os.path.abspath(dem.path),
        "output": os.path.abspath(output),
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
        "cells": {"valid": stats["shadow_cells"] + stats["lit_cells"],
                  "shadow": stats["shadow_cells"], "nodata": stats["nodata_cells"]},
        "height_range_m": [zmin, zmax],
        "version": __version__,
        "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
    }


def summary_line(report: dict) -> str:
    """One line for stderr."""
    rows, cols = report["shape"]
    frac = report["shadow_fraction"]
    mpx = report["mpix_per_s"]
    gpu = report.get("gpu")
    if gpu:
        kms = gpu.get("kernel_ms")
        where = (f"{report['algorithm']}/gpu ({gpu['device']}"
                 + (f", kernels {kms:.2f} ms" if kms is not None else "") + ")")
    else:
        where = f"{report['algorithm']}/{report['backend']} x{report['threads']}"
    return (f"hillshade-rt: {report['output']}: {cols}x{rows}, sun az {report['sun']['azimuth']:g} "
            f"el {report['sun']['elevation']:g}, {where}: "
            f"{100 * frac:.2f}% of valid cells in shadow; "
            f"compute {report['seconds']['compute']:.3f} s"
            + (f" ({mpx:.1f} Mpix/s)" if mpx else "")
            + f", total {report['seconds']['total']:.2f} s")
