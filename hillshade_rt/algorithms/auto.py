"""``auto`` (the default): the fastest exact method for this DEM, sun and backend.

Every exact method gives the same mask, so the choice is only about time. The cost model,
fitted to ``make bench-real`` (docs/benchmarks.md, 2 cores):

* ``bounds`` pays a fixed sweep over every cell (about 15-25 ns per cell on 2 cores) and then
  marches the few cells it leaves open; ``brute`` (over the pyramid) pays per *valid* cell a
  march whose length grows with the **reach** of a ray: the steps it takes to rise over the
  DEM's relief, ``(zmax - zmin) / rise``, at most the raster's extent along the ray.
* So brute wins where rays are short or most cells are voids (a high sun on gentle terrain, a
  coastline with the sea as nodata), bounds everywhere else. The rule: ``bounds`` when
  ``valid fraction * min(reach, extent) >= BOUNDS_MIN_STEPS``, else ``brute``. On New Zealand's
  1 km DEM with 83 % sea this picks brute at every sun; on every mountain DEM and fractal of the
  benchmark set at 3-20 deg it picks bounds.
* On the GPU: ``brute`` over the pyramid (one thread per cell; the bounds sweep has no GPU
  kernel).

``smap``, ``horizon`` and ``sweep`` are never picked: on real terrain SMap is slower than the
pyramid march at every benchmark sun, the horizon scan computes more than a mask, and sweep is
approximate. The choice and the figures behind it go to the report (``algorithm_stats.auto``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..geometry import SunRays
from . import bounds, brute

BOUNDS_MIN_STEPS = 64.0


@njit(cache=True)
def _valid_range(z):
    """(valid cells, lowest, highest valid height) in one pass."""
    n = 0
    lo = np.inf
    hi = -np.inf
    for r in range(z.shape[0]):
        for h in z[r]:
            if h == h:
                n += 1
                lo = min(lo, h)
                hi = max(hi, h)
    return n, lo, hi


def survey(z: np.ndarray) -> tuple[float, float, float]:
    """(valid fraction, lowest, highest valid height) of ``z``: what ``choose`` needs of a DEM."""
    n, lo, hi = _valid_range(z)
    return n / max(1, z.size), float(lo), float(hi)


def choose(shape: tuple[int, int], valid_fraction: float, zrange: tuple[float, float],
           rays: SunRays, backend: str = "cpu") -> tuple[str, str]:
    """(algorithm, why) for these heights and rays on ``backend``."""
    if backend == "gpu":
        return "brute", "GPU: the pyramid march (one thread per cell)"
    rise = float(np.min(rays.rise))
    L = shape[1] if bool(rays.dom_col[len(rays.rise) // 2]) else shape[0]
    if not math.isfinite(rise) or rise <= 0 or valid_fraction == 0:
        return "brute", "sun at the zenith or no valid cell"
    reach = min(max(0.0, zrange[1] - zrange[0]) / rise, float(L))
    steps = valid_fraction * reach
    if steps >= BOUNDS_MIN_STEPS and min(shape) > 1:
        return "bounds", (f"valid {valid_fraction:.0%} x reach {reach:.0f} steps = {steps:.0f} "
                          f">= {BOUNDS_MIN_STEPS:.0f}")
    return "brute", (f"valid {valid_fraction:.0%} x reach {reach:.0f} steps = {steps:.0f} "
                     f"< {BOUNDS_MIN_STEPS:.0f}: short rays")


def record(stats: dict | None, name: str, why: str) -> None:
    """Count the choice in ``stats['auto']`` (a series makes one per sun)."""
    if stats is None:
        return
    a = stats.setdefault("auto", {"chose": {}, "rule": f"bounds when valid fraction x "
                                  f"min(reach, extent) >= {BOUNDS_MIN_STEPS:.0f} steps, else "
                                  f"brute; GPU: brute"})
    a["chose"][name] = a["chose"].get(name, 0) + 1
    a["why"] = why


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None,
                stats: dict | None = None, pyramid=True) -> np.ndarray:
    """The mask by the method ``choose`` picks (exact: brute's mask)."""
    frac, lo, hi = survey(z)
    name, why = choose(z.shape, frac, (lo, hi if zmax is None else zmax), rays)
    record(stats, name, why)
    fn = bounds.shadow_mask if name == "bounds" else brute.shadow_mask
    return fn(z, rays, zmax, stats, pyramid=pyramid)


def shadow_mask_gpu(g, rays: SunRays, zmax: float, stats: dict | None = None) -> np.ndarray:
    name, why = choose(g.shape, 1.0, (g.zmin, zmax), rays, "gpu")
    record(stats, name, why)
    return brute.shadow_mask_gpu(g, rays, zmax, stats)
