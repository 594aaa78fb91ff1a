"""Quick-look pictures (``--preview out.png``): shaded relief with the shadows tinted blue.

For people who would rather look than read: at most ``max_side`` pixels on the long side (every
n-th cell), relief lit by the run's sun (or from the north-west at 45 degrees), shadows, or the
share of times in shadow, tinted, voids white.
"""

from __future__ import annotations

import math

import numpy as np

from .geometry import Grid

TINT = np.array([0.30, 0.42, 0.85], np.float32)   # what a cell fully in shadow is multiplied by
SUN = np.array([1.0, 0.86, 0.45], np.float32)     # warm tint for sun hours


def relief_rgb(z: np.ndarray, grid: Grid, azimuth: float = 315.0, elevation: float = 45.0,
               shade: np.ndarray | None = None, warm: np.ndarray | None = None,
               max_side: int = 2048) -> np.ndarray:
    """(rows', cols', 3) uint8 picture of ``z`` (subsampled to ``max_side``).

    shade: 0..1 per cell (1 = in shadow), tinted blue; warm: 0..1 per cell (e.g. sun hours over
    their maximum), from dark to warm. Both full-size; NaN is treated as a void."""
    from .algorithms.relief import incidence

    rows, cols = z.shape
    n = max(1, math.ceil(max(rows, cols) / max_side))
    zs = np.ascontiguousarray(z[::n, ::n])
    g = Grid(zs.shape[0], zs.shape[1], grid.dx[::n] * n, grid.dy[::n] * n, grid.col_sign,
             grid.row_sign, grid.method)
    cosi = incidence(zs, g, azimuth, max(elevation, 5.0))
    gray = 0.25 + 0.75 * np.clip(np.nan_to_num(cosi, nan=0.0), 0.0, 1.0)
    rgb = np.repeat(gray[..., None], 3, axis=2).astype(np.float32)
    if shade is not None:
        s = np.clip(np.nan_to_num(shade[::n, ::n].astype(np.float32), nan=0.0), 0.0, 1.0)
        rgb *= 1.0 - s[..., None] * (1.0 - TINT)
    if warm is not None:
        w = np.clip(np.nan_to_num(warm[::n, ::n].astype(np.float32), nan=0.0), 0.0, 1.0)
        rgb *= (0.25 + 0.75 * w[..., None]) * SUN
    out = np.rint(255.0 * np.clip(rgb, 0.0, 1.0)).astype(np.uint8)
    out[np.isnan(zs)] = 255
    return out


def every_nth(arr: np.ndarray, r0: int, c0: int, n: int):
    """The cells of ``arr`` (a part of a raster starting at row ``r0``, column ``c0``) whose
    raster row and column are multiples of ``n``, and where they start in the raster's
    every-``n``-th grid: ``(sub, (row, col))``. Windows put their parts of a preview together."""
    rs, cs = (-r0) % n, (-c0) % n
    return arr[rs::n, cs::n], ((r0 + rs) // n, (c0 + cs) // n)
