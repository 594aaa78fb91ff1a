"""The public entry point: one function that dispatches to the chosen algorithm."""

from __future__ import annotations

import numpy as np

from .algorithms import REGISTRY, lookup
from .errors import HillshadeError
from .geometry import Grid, heights_and_grid, sun_rays


def warm_up(algorithm: str, grid: Grid | None = None, azimuth: float = 203.7,
            elevation: float = 10.0, backend: str = "cpu", **options) -> None:
    """Compile (or load from numba's cache) the kernels that a run of ``algorithm`` on ``grid``
    with this sun will use, on a 4x4 grid with the same orientation and spacing pattern (same
    array layouts and argument types), so that a timed run measures computing, not compiling.
    ``backend`` "gpu": the CUDA kernels (compiled for this process's device)."""
    z = np.zeros((4, 4), np.float32)
    if grid is None:
        small = Grid.uniform(4, 4, 1.0)
    else:
        idx = np.linspace(0, grid.rows - 1, 4).astype(int)
        small = Grid(4, 4, grid.dx[idx], grid.dy[idx], grid.col_sign, grid.row_sign, grid.method)
    rays = sun_rays(small, azimuth, elevation)
    if backend == "gpu":
        from .gpu import GpuDem
        z[0, 0] = 1.0    # a non-flat DEM, so that no kernel is skipped
        GpuDem(z).shadow_mask(rays, algorithm, None, None, **options)
    else:
        REGISTRY[algorithm].cpu(z, rays, 0.0, None, **options)


def shadow_mask(heights: np.ndarray, azimuth: float, elevation: float,
                spacing: float | tuple[float, float] | Grid = 1.0,
                algorithm: str = "auto", stats: dict | None = None, backend: str = "auto",
                **options) -> np.ndarray:
    """Cast-shadow mask of a DEM: uint8, 1 = shadow, 0 = lit, 255 = nodata.

    heights: 2-D array, row 0 the northern edge (NaN = nodata). Converted to float32 once if it
    is not float32 already; a float32 array is used in place, never copied.
    azimuth, elevation: degrees (clockwise from north; above the horizon, 0 < E <= 90).
    spacing: ground metres per cell, ``d``, ``(dx, dy)`` or a :class:`Grid` (per-row spacing,
    orientation) such as ``read_dem(...).grid``.
    algorithm: one of ``algorithms.REGISTRY``: ``auto`` (default: the fastest exact method),
    ``bounds``, ``brute`` (exact reference), ``smap`` (exact), ``horizon`` (exact with its
    default ``method="scan"``), ``sweep`` (approximate).
    stats: optional dict that receives the algorithm's figures (e.g. smap's ``black_fraction``);
    on the GPU also ``stats["gpu"]`` (device, kernel and transfer times, bytes moved).
    backend: ``"cpu"``, ``"gpu"`` or ``"auto"`` (the GPU when numba-cuda finds a CUDA device and
    the options have a GPU kernel, else the CPU). To keep a DEM on the GPU for many suns, use
    :class:`hillshade_rt.gpu.GpuDem`.
    options: passed to the algorithm (smap: ``nextv``, ``better_nextv``; horizon: ``method``,
    ``sample_spacing``; sweep: ``exact_steps``).
    """
    z, spacing = heights_and_grid(heights, spacing)
    spec = lookup(algorithm)
    rays = sun_rays(spacing, azimuth, elevation)
    if choose_backend(backend, algorithm, options) == "gpu":
        from .gpu import GpuDem
        g = GpuDem(z)
        out = g.shadow_mask(rays, algorithm, None, stats, **options)
        if stats is not None:
            stats["gpu"] = g.report()
        return out
    zmax = float(np.nanmax(z)) if np.isfinite(z).any() else np.nan
    if np.isnan(zmax):
        return np.full(z.shape, 255, dtype=np.uint8)
    return spec.cpu(z, rays, zmax, stats, **options)


def choose_backend(backend: str, algorithm: str, options: dict) -> str:
    """'cpu' or 'gpu' for a request: ``auto`` takes the GPU only when there is a real device and
    the options have GPU kernels; ``gpu`` with options that have none is an error."""
    from .algorithms import gpu_unsupported
    from .gpu import resolve_backend
    why = gpu_unsupported(algorithm, options)
    if backend == "gpu" and why:
        raise HillshadeError(f"{why}; use --backend cpu")
    chosen = resolve_backend(backend)
    return "cpu" if why else chosen


def horizon_angles(heights: np.ndarray, azimuth: float,
                   spacing: float | tuple[float, float] | Grid = 1.0, method: str = "scan",
                   sample_spacing: int = 1, backend: str = "auto") -> np.ndarray:
    """Horizon angle (degrees, float32) of every cell toward ``azimuth``: lit by a sun at that
    azimuth iff angle <= its elevation. NaN on voids, -90 where no terrain lies ahead.
    ``method="scan"`` is exact on the model; ``"hull"`` is the faster approximation."""
    from .algorithms import horizon as hz
    z, grid = heights_and_grid(heights, spacing)
    rays = sun_rays(grid, azimuth, 45.0)
    if choose_backend(backend, "horizon", {"method": method}) == "gpu":
        from .gpu import GpuDem
        return hz.horizon_angles_gpu(GpuDem(z), rays, method, sample_spacing)
    return hz.horizon_angles(z, rays, method=method, sample_spacing=sample_spacing)


def is_shadowed(heights: np.ndarray, points, azimuth: float, elevation: float,
                spacing: float | tuple[float, float] | Grid = 1.0) -> np.ndarray:
    """For 3-D points ``(row, col, height)`` in array coordinates (cell centres at whole row/col,
    heights in the DEM's units; above, on or off the terrain), whether the ray toward the sun
    passes strictly below the terrain. Uses an SMap; build ``algorithms.smap.SMap`` yourself to
    query one sun many times."""
    from .algorithms.smap import SMap
    z, grid = heights_and_grid(heights, spacing)
    return SMap(z, azimuth, elevation, grid).is_shadowed(points)
