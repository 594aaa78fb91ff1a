"""The public entry point: one function that dispatches to the chosen algorithm."""

from __future__ import annotations

import numpy as np

from .algorithms import ALGORITHMS
from .errors import HillshadeError
from .geometry import Grid, sun_rays


def warm_up(algorithm: str) -> None:
    """Compile (or load from numba's cache) the kernel of ``algorithm`` on a 2x2 grid, so that a
    timed run measures computing, not compiling. Same argument types as a real run."""
    z = np.zeros((2, 2), np.float32)
    ALGORITHMS[algorithm](z, sun_rays(Grid.uniform(2, 2, 1.0), 203.7, 10.0), 0.0)


def shadow_mask(heights: np.ndarray, azimuth: float, elevation: float,
                spacing: float | tuple[float, float] | Grid = 1.0,
                algorithm: str = "brute") -> np.ndarray:
    """Cast-shadow mask of a DEM: uint8, 1 = shadow, 0 = lit, 255 = nodata.

    heights: 2-D array, row 0 the northern edge (NaN = nodata). Converted to float32 once if it
    is not float32 already; a float32 array is used in place, never copied.
    azimuth, elevation: degrees (clockwise from north; above the horizon, 0 < E <= 90).
    spacing: ground metres per cell, ``d``, ``(dx, dy)`` or a :class:`Grid` (per-row spacing,
    orientation) such as ``read_dem(...).grid``.
    algorithm: one of ``ALGORITHMS`` (``brute`` is the exact reference).
    """
    z = np.asarray(heights)
    if z.ndim != 2 or z.size == 0:
        raise HillshadeError(f"heights must be a non-empty 2-D array, got shape {z.shape}")
    if z.dtype != np.float32:
        z = z.astype(np.float32)
    if not isinstance(spacing, Grid):
        dx, dy = (spacing, spacing) if np.isscalar(spacing) else spacing
        spacing = Grid.uniform(z.shape[0], z.shape[1], float(dx), float(dy))
    elif (spacing.rows, spacing.cols) != z.shape:
        raise HillshadeError(f"grid is {spacing.rows}x{spacing.cols} but heights are {z.shape}")
    try:
        kernel = ALGORITHMS[algorithm]
    except KeyError:
        raise HillshadeError(
            f"unknown algorithm {algorithm!r}; choose one of {', '.join(ALGORITHMS)}") from None
    zmax = float(np.nanmax(z)) if np.isfinite(z).any() else np.nan
    if np.isnan(zmax):
        return np.full(z.shape, 255, dtype=np.uint8)
    return kernel(z, sun_rays(spacing, azimuth, elevation), zmax)
