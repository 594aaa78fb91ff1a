"""Quick-look pictures (``--preview out.png``): shaded relief with the shadows tinted blue.

For people who would rather look than read: at most ``max_side`` pixels on the long side (every
n-th cell), relief lit by the run's sun (or from the north-west at 45 degrees), shadows, or the
share of times in shadow, tinted, voids white.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.geometry import Grid

TINT = np.array([0.30, 0.42, 0.85], np.float32)   # what a cell fully in shadow is multiplied by
SUN = np.array([1.0, 0.86, 0.45], np.float32)     # warm tint for sun hours
# a colour ramp for continuous products (sky view, openness, irradiance): viridis's colours at
# 0, 1/4, 1/2, 3/4 and 1, interpolated linearly (perceptually ordered, readable in grey)
RAMP = np.array([[0.267, 0.005, 0.329], [0.231, 0.322, 0.545], [0.129, 0.569, 0.549],
                 [0.369, 0.788, 0.384], [0.993, 0.906, 0.144]], np.float32)


def relief_rgb(z: np.ndarray, grid: Grid, azimuth: float = 315.0, elevation: float = 45.0,
               shade: np.ndarray | None = None, warm: np.ndarray | None = None,
               max_side: int = 2048, ramp: np.ndarray | None = None) -> np.ndarray:
    """(rows', cols', 3) uint8 picture of ``z`` (subsampled to ``max_side``).

    shade: 0..1 per cell (1 = in shadow), tinted blue; warm: 0..1 per cell (e.g. sun hours over
    their maximum), from dark to warm; ramp: 0..1 per cell coloured with ``RAMP`` (low purple,
    high yellow) over the relief. All full-size; NaN is treated as a void."""
    from ..algorithms.relief import incidence

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
    if ramp is not None:
        v = ramp[::n, ::n].astype(np.float32)
        rgb *= 0.35 + 0.65 * ramp_colours(v) / 0.993     # the relief shows through the colour
    out = np.rint(255.0 * np.clip(rgb, 0.0, 1.0)).astype(np.uint8)
    out[np.isnan(zs)] = 255
    return out


def every_nth(arr: np.ndarray, r0: int, c0: int, n: int):
    """The cells of ``arr`` (a part of a raster starting at row ``r0``, column ``c0``) whose
    raster row and column are multiples of ``n``, and where they start in the raster's
    every-``n``-th grid: ``(sub, (row, col))``. Windows put their parts of a preview together."""
    rs, cs = (-r0) % n, (-c0) % n
    return arr[rs::n, cs::n], ((r0 + rs) // n, (c0 + cs) // n)


def ramp_colours(v: np.ndarray) -> np.ndarray:
    """(..., 3) float32 colours of ``v`` (0..1, clipped; NaN as 0) along ``RAMP``."""
    x = np.clip(np.nan_to_num(np.asarray(v, np.float32), nan=0.0), 0.0, 1.0) * (len(RAMP) - 1)
    i = np.minimum(x.astype(np.int64), len(RAMP) - 2)
    f = (x - i)[..., None]
    return RAMP[i] * (1.0 - f) + RAMP[i + 1] * f


def scaled(values: np.ndarray, lo: float | None = None, hi: float | None = None) -> np.ndarray:
    """``values`` mapped to 0..1 between ``lo`` and ``hi`` (default: the 2nd and 98th
    percentiles of the finite values), for ``relief_rgb(ramp=...)``."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return np.zeros(values.shape, np.float32)
    if lo is None or hi is None:
        p2, p98 = np.percentile(finite, [2.0, 98.0])
        lo = p2 if lo is None else lo
        hi = p98 if hi is None else hi
    span = hi - lo if hi > lo else 1.0
    return ((values - lo) / span).astype(np.float32)


def panorama_rgb(azimuths, angles, low: float = -10.0, high: float | None = None,
                 width: int = 720, height: int = 200) -> np.ndarray:
    """(height, width, 3) uint8 picture of one horizon profile, as an observer sees it turning
    from north through east: sky above the horizon line, terrain below, a grey line at the
    horizontal. ``azimuths`` in degrees clockwise from north (increasing), ``angles`` the
    horizon elevations (degrees; -90 where nothing lies ahead)."""
    az = np.asarray(azimuths, np.float64)
    ang = np.asarray(angles, np.float64)
    if high is None:
        high = max(10.0, float(np.nanmax(ang)) + 5.0) if ang.size else 10.0
    x = (np.arange(width) + 0.5) * 360.0 / width
    h = np.interp(x, np.append(az, az[0] + 360.0), np.append(ang, ang[0]), period=360.0)
    y = high - (np.arange(height) + 0.5) * (high - low) / height     # elevation of each row
    sky = y[:, None] > h[None, :]
    top = np.array([0.55, 0.75, 0.95], np.float32)
    ground = np.array([0.45, 0.38, 0.28], np.float32)
    rgb = np.where(sky[..., None], top, ground).astype(np.float32)
    level = int(np.clip(round((high - 0.0) / (high - low) * height), 0, height - 1))
    rgb[level, :] = 0.6
    for a in range(0, 360, 90):      # ticks at N, E, S, W
        rgb[:6, int(a / 360.0 * width)] = 0.0
    return np.rint(255.0 * rgb).astype(np.uint8)
