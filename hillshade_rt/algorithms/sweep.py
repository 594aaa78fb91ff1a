"""``sweep``: the flag-map propagation ("Faster Ray Traced Terrain Shadow Maps", seed 001).

The tutorial's idea: process cells from the sun's side and let every cell store what its own ray
met, so that a later ray reaching an already visited cell reuses that instead of marching on.
What each cell stores here is the **left-over height** of its ray, in absolute form: ``S``, the
lowest height at the cell's position from which a ray toward the sun clears every sample ahead
(``S - h`` is the most by which the cell's own ray passes under the terrain, negative when it
clears, ``-inf`` when it never meets terrain). It obeys an exact recurrence along a ray:

    S(cell) = max( T_1 - rise , S(first sample point) - rise )

where ``T_1`` is the model's sample on the next grid line toward the sun. The first sample point
lies between two cells of that line, whose ``S`` are already known: it is interpolated linearly
between them (the tutorial's interpolation of stored values; one line needs only the next line, so
two line buffers suffice, not a flag map of the whole DEM). A cell is shadowed iff ``S > h``
(strict, as in the model). O(1) per cell, no ray marching at all.

Fixes of the published code: no restart of the inner loop at a wrong index (the loops here run
over canonical lines and positions, ``frames``); no ±0.5 epsilon around an interpolated "never
hit" flag of -1 (``-inf`` is kept apart from real heights: when one of the two stored values is
``-inf``, i.e. that neighbour's ray left the raster, the cell marches on exactly instead); no square
root per pixel (the k-th sample is ``k`` steps on);
parallel over the cells of a line (independent), lines in order from the sun's edge.

**Approximate.** On the axes and diagonals the first sample is a cell centre and ``sweep`` equals
``brute`` (tests). Elsewhere the interpolated ``S`` is a blend of two neighbouring rays' horizons,
not the horizon of the ray between them; it errs near shadow edges. Measured against ``brute`` on
the real DEMs of the project (docs/algorithms.md): see the table there; the figures are repeated in
``ERROR_SUMMARY`` below.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..geometry import SunRays
from .frames import frame_of, uniform_rays
from .raymath import line_position, terrain_on_line

EXACT_STEPS = 8   # samples marched exactly before the stored values are used

ERROR_SUMMARY = (
    "measured against brute on 7 real DEMs x 8 suns (benchmarks/accuracy.py, docs/algorithms.md)")


@njit(cache=True)
def _stored(ring, row, i0, f):
    """Stored S interpolated at fraction f between cells i0 and i0+1 of a ring-buffer row; NaN
    when one of them is -inf (its ray left the raster: not representative of this one)."""
    a = ring[row, i0]
    if f == 0.0:
        return a
    b = ring[row, i0 + 1]
    if a == -np.inf or b == -np.inf:
        return np.nan
    return a + f * (b - a)


@njit(parallel=True, cache=True)
def _sweep_kernel(Z, s_arr, rise_arr, per_line, K, out):
    """Lines from the sun's edge; S of the last K lines kept in a ring buffer. Each cell marches
    its first K samples exactly and takes the stored S interpolated at the K-th sample point."""
    L, P = Z.shape
    ring = np.full((K + 1, P), -np.inf)
    for v in range(L - 1, -1, -1):
        row = v % (K + 1)
        for pp in prange(P):
            p = np.int64(pp)   # prange indices may be unsigned; keep integer arithmetic integral
            i = np.int64(v) if per_line else p
            s = s_arr[i]
            rise = rise_arr[i]
            S = -np.inf
            k = 1
            march_on = False   # set when the stored values cannot be used: march to the end
            while (k <= K or march_on) and v + k < L:
                x = line_position(p + k * s, P)
                if x < 0.0:
                    break
                t = terrain_on_line(Z, False, v + k, x)
                if t - k * rise > S:   # NaN (void) compares false
                    S = t - k * rise
                if k == K:
                    i0 = int(math.floor(x))
                    sn = _stored(ring, (v + k) % (K + 1), i0, x - i0)
                    if math.isnan(sn):
                        march_on = True
                    elif sn - k * rise > S:
                        S = sn - k * rise
                k += 1
            ring[row, p] = S
            h = Z[v, p]
            if math.isnan(h):
                out[v, p] = 255
            elif S > h:
                out[v, p] = 1
            else:
                out[v, p] = 0


def _per_cell_rays(rays: SunRays):
    """Frame of the centre row, and s / rise of every row expressed in that frame.

    With per-row spacing (geographic CRS) each row keeps its own direction; a row whose own
    dominant axis differs (sun near a diagonal) is re-expressed in the frame's axis (|s| > 1)."""
    f = frame_of(rays, len(rays.rise) // 2)
    same = rays.dom_col.astype(bool) == f.dom_col
    so = np.abs(rays.step_other)
    s = np.where(same, so, 1.0 / np.maximum(so, 1e-300))
    rise = np.where(same, rays.rise, rays.rise / np.maximum(so, 1e-300))
    return f, s.astype(np.float64), rise.astype(np.float64)


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None,
                stats: dict | None = None, exact_steps: int = EXACT_STEPS) -> np.ndarray:
    """Approximate shadow mask by the flag-map sweep: uint8 1 shadow / 0 lit / 255 void."""
    out = np.empty(z.shape, np.uint8)
    if not math.isfinite(float(rays.rise[0])):   # sun at the zenith
        out[...] = np.where(np.isnan(z), 255, 0)
        return out
    if uniform_rays(rays):
        f = frame_of(rays)
        Z = f.view(z)
        per_line = True
        s = np.full(Z.shape[0], f.s)
        rise = np.full(Z.shape[0], f.rise)
    else:
        f, s_rows, rise_rows = _per_cell_rays(rays)
        Z = f.view(z)
        # canonical index that runs over the DEM's rows: lines when lines are rows, else positions
        per_line = not f.dom_col
        s = s_rows[::-1].copy() if (f.flip_line if per_line else f.flip_pos) else s_rows
        rise = rise_rows[::-1].copy() if (f.flip_line if per_line else f.flip_pos) else rise_rows
    _sweep_kernel(Z, s, rise, per_line, np.int64(max(1, int(exact_steps))), f.view(out))
    return out
