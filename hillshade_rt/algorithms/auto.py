"""``auto`` (the default): the fastest exact method for this DEM, sun and backend.

Every exact method gives the same mask, so the choice is only about time. The cost model,
fitted to ``make bench-real`` (docs/benchmarks.md, 2 cores):

* ``bounds`` pays a fixed sweep over every cell (about 3-10 ns per cell on 2 cores) and then
  marches the few cells it leaves open; ``brute`` (over the pyramid) pays per *valid* cell a
  march whose length grows with the **reach** of a ray: the steps it takes to rise over the
  DEM's relief, ``(zmax - zmin) / rise``, at most the raster's extent along the ray.
* So ``auto`` estimates both costs (ns per cell on 2 cores, ``make bench-real-quick``): bounds
  ``BOUNDS_NS`` per valid cell and ``BOUNDS_NS_VOID`` per void on one ray for the raster
  (``BOUNDS_NS_PER_ROW``... on per-row rays, geographic), divided by the share of threads its
  wavefront can use (one strip per 64 positions); brute per *valid* cell ``BRUTE_NS_FIXED``
  plus ``BRUTE_NS_PER_STEP`` per step of the reach, at most ``BRUTE_NS_LONG``, and the
  pyramid's build per cell (``BUILD_NS``, voids too); rays under ``PYRAMID_REACH`` steps the
  plain march, ``PLAIN_NS_FIXED`` + ``PLAIN_NS_PER_STEP`` per step. It runs the cheaper:
  brute on gentle terrain under a high sun and on New Zealand's 1 km DEM (83 % sea as
  nodata) at 20 deg; bounds on the mountain DEMs, the fractals and New Zealand at 3-8 deg.
* On the GPU: ``brute`` over the pyramid (one thread per cell; the bounds sweep has no GPU
  kernel).

``smap``, ``horizon`` and ``sweep`` are never picked: SMap (over the pyramid) is slower than
bounds at every benchmark sun, the horizon scan computes more than a mask, and sweep is
approximate. The choice and the figures behind it go to the report (``algorithm_stats.auto``).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..model.geometry import SunRays
from . import bounds, brute
from .counts import valid_range
from .pyramid import BUILD_NS   # the pyramid's build, per cell of the raster (voids too)
from .frames import reach, uniform_rays

# the cost model, ns per cell on 2 cores (make bench-real-quick and spectral probes,
# 2026-12-02, after bounds' passes vectorised: 17.5 and 25 ns a cell before)
BOUNDS_NS = 7.0              # bounds, one ray for the raster, per valid cell ...
BOUNDS_NS_VOID = 3.0         # ... and per void (its sweep carries the bounds, nothing to decide)
BOUNDS_NS_PER_ROW = 10.0     # bounds, per-row rays (geographic), per valid cell ...
BOUNDS_NS_PER_ROW_VOID = 4.0  # ... and per void
BRUTE_NS_FIXED = 9.2         # brute over the pyramid, per valid cell: a march's fixed cost
BRUTE_NS_PER_STEP = 0.7      # ... and per step of the reach
BRUTE_NS_LONG = 65.0         # ... at most (long rays skip over the pyramid's blocks)
PLAIN_NS_FIXED = 4.5         # brute's plain march (rays shorter than PYRAMID_REACH), per cell
PLAIN_NS_PER_STEP = 1.1      # ... and per step
PYRAMID_REACH = 16           # brute marches over the pyramid from rays of this many steps
BRUTE_TILE_WINDOW_NS = 6.0   # brute on a tile of a varying sun, per cell of its window


def survey(z: np.ndarray) -> tuple[float, float, float]:
    """(valid fraction, lowest, highest valid height) of ``z``: what ``choose`` needs of a DEM."""
    n, lo, hi = valid_range(z)
    return n / max(1, z.size), float(lo), float(hi)


def pyramid_pays(shape: tuple[int, int], zrange: tuple[float, float], rays: SunRays) -> bool:
    """Whether brute's march should take the pyramid: not on rays of a few steps, where it
    rarely skips a block and building it costs more than the march saves (New Zealand's 1 km
    DEM at 20 deg, 10 steps: 10.0 ms with a new pyramid, 7.4 without)."""
    return reach(shape, zrange, rays) >= PYRAMID_REACH


def brute_ns(steps: float, valid: float = 1.0) -> float:
    """Estimated ns (2 cores) per cell of brute's march where a ``valid`` share of the cells
    march rays of ``steps`` steps: the plain march below ``PYRAMID_REACH`` steps
    (``pyramid_pays``), else over the pyramid, whose build every cell pays (voids too: New
    Zealand's 83 % sea made a valid cell's march cost 45 ns at 26 steps)."""
    if steps < PYRAMID_REACH:
        return valid * (PLAIN_NS_FIXED + PLAIN_NS_PER_STEP * steps)
    return valid * min(BRUTE_NS_LONG, BRUTE_NS_FIXED + BRUTE_NS_PER_STEP * steps) + BUILD_NS


def bounds_ns(uniform: bool, valid: float = 1.0) -> float:
    """Estimated ns (2 cores) of bounds' sweep per cell (a ``valid`` share of them valid): one
    ray for the raster, or per row."""
    if uniform:
        return valid * BOUNDS_NS + (1.0 - valid) * BOUNDS_NS_VOID
    return valid * BOUNDS_NS_PER_ROW + (1.0 - valid) * BOUNDS_NS_PER_ROW_VOID


def tile_by_brute(window_cells: int, tile_cells: int, zrange: tuple[float, float],
                  rays: SunRays) -> bool:
    """Whether a tile of a sun that varies across the raster is cheaper marched by brute over
    its own cells than by bounds over its window (tile and halo): the same cost model as
    ``choose``. A 61 km DEM at 4.8 deg: 39 of 50 tiles went to brute by a fixed ratio of 3
    window cells per tile cell, 0.37 s; by the model none, 0.31 s (brute on a tile also pays
    per window cell: its scratch mask and the window's pyramid)."""
    # the reach over the relief (brute's cost saturates long before a window's cell count)
    steps = reach((window_cells, window_cells), zrange, rays)
    return (tile_cells * brute_ns(steps)
            + window_cells * BRUTE_TILE_WINDOW_NS < window_cells * bounds_ns(uniform_rays(rays)))


def choose(shape: tuple[int, int], valid_fraction: float, zrange: tuple[float, float],
           rays: SunRays, backend: str = "cpu") -> tuple[str, str]:
    """(algorithm, why) for these heights and rays on ``backend``: the one with the higher
    estimated rate (module docstring)."""
    if backend == "gpu":
        return "brute", "GPU: the pyramid march (one thread per cell)"
    rise = float(np.min(rays.rise))
    mid = len(rays.rise) // 2
    dom_col = bool(rays.dom_col[mid])
    P = shape[0] if dom_col else shape[1]
    if not math.isfinite(rise) or rise <= 0 or valid_fraction == 0 or min(shape) < 2:
        return "brute", "sun at the zenith, no valid cell or a single line"
    steps = reach(shape, zrange, rays)
    uniform = uniform_rays(rays)
    threads = max(1, numba.get_num_threads())
    strips = bounds.strip_count(P, abs(float(rays.step_other[mid])), bounds.EXACT_STEPS)
    ns_bounds = bounds_ns(uniform, valid_fraction) / min(1.0, strips / threads)
    ns_brute = brute_ns(steps, valid_fraction)
    rate_bounds, rate_brute = 1000.0 / ns_bounds, 1000.0 / ns_brute
    name = "bounds" if rate_bounds > rate_brute else "brute"
    why = (f"estimated {rate_bounds:.0f} Mcells/s for bounds ({'one ray' if uniform else 'per-row rays'}"
           f", {strips} of {threads} threads) vs {rate_brute:.0f} for brute (valid "
           f"{valid_fraction:.0%}, reach {steps:.0f} steps)")
    return name, why


def record(stats: dict | None, name: str, why: str) -> None:
    """Count the choice in ``stats['auto']`` (a series makes one per sun)."""
    if stats is None:
        return
    a = stats.setdefault("auto", {"chose": {}, "rule": "the exact method of the higher "
                                  "estimated rate: bounds or brute (docs/algorithms.md); GPU: "
                                  "brute"})
    a["chose"][name] = a["chose"].get(name, 0) + 1
    a["why"] = why


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None,
                stats: dict | None = None, pyramid=True) -> np.ndarray:
    """The mask by the method ``choose`` picks (exact: brute's mask)."""
    frac, lo, hi = survey(z)
    name, why = choose(z.shape, frac, (lo, hi if zmax is None else zmax), rays)
    record(stats, name, why)
    if name == "bounds":
        return bounds.shadow_mask(z, rays, zmax, stats, pyramid=pyramid, zrange=(lo, hi))
    if not pyramid_pays(z.shape, (lo, hi), rays):
        pyramid = False
    # the survey's highest height: brute need not find it again (two passes, 0.8 ms of New
    # Zealand's 6 ms at 20 deg, where auto took 0.93x the plain march)
    return brute.shadow_mask(z, rays, hi if zmax is None else zmax, stats, pyramid=pyramid)


def shadow_mask_gpu(g, rays: SunRays, zmax: float, stats: dict | None = None) -> np.ndarray:
    name, why = choose(g.shape, 1.0, (g.zmin, zmax), rays, "gpu")
    record(stats, name, why)
    return brute.shadow_mask_gpu(g, rays, zmax, stats)
