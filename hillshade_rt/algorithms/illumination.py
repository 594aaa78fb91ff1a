"""The illumination run's per-position accumulators: every subsolar position
of a series lights the DEM once (``subsolar.shadow_mask`` / ``soft_fraction`` into reused
buffers) and these kernels fold its mask into per-cell sums, in time order:

* ``lit``: hours lit (the sample's interval when the mask is 0);
* ``soft``: hours x the visible fraction of the solar disk (``--soft``);
* the longest run of shadow, kept so that two stretches of time combine (``combine``):
  ``start`` the shadow hours before the first lit sample, ``end`` the shadow hours since the
  last lit sample, ``longest`` the longest run inside, ``dark`` 1 while never lit.

Voids (mask 255, NaN heights) are left as they are. ``any_sun_up``: whether the sun's centre is
above the horizon of any valid cell (else the whole position is dark: no march).
"""

import math

import numpy as np
from numba import prange

from ._jitcache import njit
from .subsolar import cell_sun


@njit(parallel=True, cache=True)
def accumulate(mask, dt, lit, start, end, longest, dark):
    """Fold one position's mask (1 shadow, 0 lit, 255 void) of ``dt`` hours into the sums."""
    rows, cols = mask.shape
    for r in prange(rows):
        for c in range(cols):
            m = mask[r, c]
            if m == 0:
                lit[r, c] += dt
                end[r, c] = 0.0
                dark[r, c] = 0
            elif m == 1:
                e = end[r, c] + dt
                end[r, c] = e
                if e > longest[r, c]:
                    longest[r, c] = e
                if dark[r, c]:
                    start[r, c] += dt


@njit(parallel=True, cache=True)
def accumulate_dark(z, dt, start, end, longest, dark):
    """A position dark everywhere (the sun below every cell's horizon): every valid cell of
    heights ``z`` in shadow for ``dt`` hours."""
    rows, cols = z.shape
    for r in prange(rows):
        for c in range(cols):
            if math.isnan(z[r, c]):
                continue
            e = end[r, c] + dt
            end[r, c] = e
            if e > longest[r, c]:
                longest[r, c] = e
            if dark[r, c]:
                start[r, c] += dt


@njit(parallel=True, cache=True)
def accumulate_soft(frac, dt, soft):
    """``soft`` += ``frac`` x ``dt`` where ``frac`` is not NaN."""
    rows, cols = frac.shape
    for r in prange(rows):
        for c in range(cols):
            f = frac[r, c]
            if not math.isnan(f):
                soft[r, c] += f * dt


@njit(parallel=True, cache=True)
def any_sun_up(z, slat, clat, slon, clon, a, e2, sx, sy, sz, lift):
    """How many valid cells see the sun's centre above their horizon (0: a dark position)."""
    rows = z.shape[0]
    n = np.zeros(rows, np.int64)
    for r in prange(rows):
        n[r] = _row_sun_up(z, r, slat, clat, slon, clon, a, e2, sx, sy, sz, lift)
    return n.sum()


@njit(cache=True)
def _row_sun_up(z, r, slat, clat, slon, clon, a, e2, sx, sy, sz, lift):
    """How many valid cells of row ``r`` see the sun's centre above their horizon (a function
    of its own: numba's parfor analysis of Python >= 3.12 bytecode fails on a counter in a loop
    nested in a prange: https://github.com/numba/numba/issues/10132)."""
    k = 0
    for c in range(z.shape[1]):
        h = z[r, c]
        if math.isnan(h):
            continue
        e, nn, u = cell_sun(float(slat[r, c]), float(clat[r, c]), float(slon[r, c]),
                            float(clon[r, c]), a, e2, sx, sy, sz, float(h) + lift)
        if u > 0.0:
            k += 1
    return k


@njit(parallel=True, cache=True)
def lowest_elevation_tan(z, slat, clat, slon, clon, a, e2, sx, sy, sz, lift, best):
    """``best`` (per row) lowered to the smallest positive tan(elevation) of the sun's centre
    over the valid cells of the row (cells whose sun is below their horizon march no ray)."""
    rows, cols = z.shape
    for r in prange(rows):
        b = best[r]
        for c in range(cols):
            h = z[r, c]
            if math.isnan(h):
                continue
            e, nn, u = cell_sun(float(slat[r, c]), float(clat[r, c]), float(slon[r, c]),
                                float(clon[r, c]), a, e2, sx, sy, sz, float(h) + lift)
            if u > 0.0:
                t = u / math.sqrt(e * e + nn * nn) if e * e + nn * nn > 0.0 else math.inf
                if t < b:
                    b = t
        best[r] = b


def combine(a, b):
    """Two stretches' sums (dicts of arrays: lit, soft or None, start, end, longest, dark), ``a``
    before ``b``, as one (associative; numpy, whole arrays)."""
    da, db = a["dark"].astype(bool), b["dark"].astype(bool)
    out = {"lit": a["lit"] + b["lit"],
           "soft": None if a["soft"] is None else a["soft"] + b["soft"],
           "start": np.where(da, a["start"] + b["start"], a["start"]),
           "end": np.where(db, a["end"] + b["end"], b["end"]),
           "longest": np.maximum(np.maximum(a["longest"], b["longest"]), a["end"] + b["start"]),
           "dark": (da & db).astype(np.uint8)}
    return out
