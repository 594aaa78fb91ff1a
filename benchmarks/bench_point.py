"""The point light (issue 21, item 1) against the directional mask of the same family, in one run
(``make bench-point``).

For each terrain (a power-law spectral fractal, beta 3.2, 30 m cells, 2 km of relief, at
--sizes, and the real DEMs of benchmarks/data) and each light:

* **high lamp**: over the raster (row 0.37, column 0.58 of it), twice the relief above the
  highest cell;
* **low lamp**: 20 m over the ground inside the raster (row 0.61, column 0.27): lower than many
  cells, whose rays descend;
* **low, near sun**: far off the raster toward azimuth 203.7, at 7 deg over the centre (about
  5-10 deg over most cells);
* **off-raster**: just beyond the north-east corner, 30 % of the relief over the highest cell;

the point light over the pyramid (``algorithms.point_light``, the default) is timed against ``brute``
over the pyramid (``algorithms.brute``, the directional mask of the same family: one exact ray
per cell) for the light's **equivalent sun**: its azimuth from the raster's centre and the
median, over the cells, of its elevation seen from each cell. Both build their pyramid in the
call, as a single mask does. The two alternate ``--repeat`` rounds (medians); the plain march
of the point light (``pyramid=False``) is timed once after them (ratio to the pyramid march).
Issue 21's target: point light <= 2x the directional mask on 4096².

    python benchmarks/bench_point.py                 # 4096² and the real DEMs, ~10 min on 2 cores
    python benchmarks/bench_point.py --sizes 1024 --no-plain   # a quick look
"""

import argparse
import datetime
import math
import os
import platform
import statistics
import sys
import time

import numba
import numpy as np

from hillshade_rt import read_dem
from hillshade_rt.algorithms import brute, point_light
from hillshade_rt.algorithms.horizon import bilinear
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import real_dems, spectral

CELL = 30.0


def lights(z, dx, dy):
    """[(label, row, col, height)] of the module's lights over heights ``z``."""
    rows, cols = z.shape
    lo, hi = float(np.nanmin(z)), float(np.nanmax(z))
    relief = hi - lo
    out = [("high lamp", 0.37 * rows, 0.58 * cols, hi + 2 * relief)]
    r, c = 0.61 * rows, 0.27 * cols
    g = bilinear(z, r, c)
    out.append(("low lamp", r, c, (g if np.isfinite(g) else lo) + 20.0))
    dist = 3.0 * math.hypot(rows * dy, cols * dx)            # metres from the centre
    a = math.radians(203.7)
    zc = float(np.nanmedian(z))
    out.append(("low, near sun", (rows - 1) / 2 - dist * math.cos(a) / dy,
                (cols - 1) / 2 + dist * math.sin(a) / dx, zc + dist * math.tan(math.radians(7))))
    out.append(("off-raster", -0.1 * rows, 1.15 * cols, hi + 0.3 * relief))
    return out


def equivalent_sun(z, dx, dy, row, col, height):
    """(azimuth from the centre, median elevation over every 16th cell) of a light, degrees."""
    rows, cols = z.shape
    rr, cc = np.mgrid[0:rows:16, 0:cols:16]
    h = z[rr, cc]
    ok = np.isfinite(h)
    dist = np.hypot((row - rr[ok]) * dy, (col - cc[ok]) * dx)
    el = float(np.median(np.degrees(np.arctan2(height - h[ok], dist))))
    north, east = ((rows - 1) / 2 - row) * dy, (col - (cols - 1) / 2) * dx
    az = math.degrees(math.atan2(east, north)) % 360.0 if math.hypot(north, east) > 1.0 \
        else 203.7
    return az, min(max(el, 0.5), 89.0)


def alternated(fns: dict, repeat: int) -> dict:
    t = {k: [] for k in fns}
    for _ in range(repeat):
        for k, f in fns.items():
            t0 = time.perf_counter()
            f()
            t[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in t.items()}


def terrains(sizes, with_real):
    for n in sizes:
        yield f"spectral β 3.2 {n}² ({CELL:g} m)", spectral(n, 3.2, seed=5, relief=2000.0), \
            Grid.uniform(n, n, CELL)
    if with_real:
        for path, label in real_dems():
            d = read_dem(path)
            yield f"{label} {d.shape[1]}x{d.shape[0]}", d.heights, d.grid


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="4096")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-real", action="store_true", help="the fractals only")
    ap.add_argument("--no-plain", action="store_true", help="skip the plain march")
    a = ap.parse_args(argv)
    sizes = [int(s) for s in a.sizes.split(",") if s]
    print(f"`python benchmarks/bench_point.py {' '.join(argv or sys.argv[1:])}` — "
          f"{datetime.date.today().isoformat()}; {platform.machine()}, "
          f"{numba.config.NUMBA_NUM_THREADS} threads ({os.cpu_count()} cores), "
          f"numba {numba.__version__}; medians of {a.repeat} alternated rounds, compute only "
          "(pyramids built in each call)\n")
    warm = spectral(64, 3.2, seed=1)
    point_light.shadow_mask(warm, 10.0, 20.0, 3000.0)
    point_light.shadow_mask(warm, 10.0, 20.0, 3000.0, pyramid=False)
    brute.shadow_mask(warm, sun_rays(Grid.uniform(64, 64, CELL), 203.7, 7.0, 0.0))
    print("| terrain | light | equivalent sun (az, el) | shadow % | point light (s) | "
          "brute, same sun (s) | point / brute | plain march (s) | plain / point |")
    print("|---|---|---|---|---|---|---|---|---|")
    worst = {}
    for label, z, grid in terrains(sizes, not a.no_real):
        dx, dy = grid.centre_spacing()
        for name, row, col, height in lights(z, dx, dy):
            az, el = equivalent_sun(z, dx, dy, row, col, height)
            rays = sun_rays(grid, az, el, 0.0)
            t = alternated({"point": lambda: point_light.shadow_mask(z, row, col, height),
                            "brute": lambda: brute.shadow_mask(z, rays)}, a.repeat)
            m = point_light.shadow_mask(z, row, col, height)
            share = 100.0 * float((m == 1).sum()) / max(1, int((m != 255).sum()))
            if a.no_plain:
                plain = "–"
                ratio = "–"
            else:
                t0 = time.perf_counter()
                p = point_light.shadow_mask(z, row, col, height, pyramid=False)
                tp = time.perf_counter() - t0
                assert np.array_equal(p, m), (label, name)      # the same mask
                plain, ratio = f"{tp:.3f}", f"{tp / t['point']:.1f}x"
            r = t["point"] / t["brute"]
            worst[label] = max(worst.get(label, 0.0), r)
            print(f"| {label} | {name} | {az:.1f}, {el:.1f} | {share:.1f} | {t['point']:.3f} | "
                  f"{t['brute']:.3f} | {r:.2f} | {plain} | {ratio} |", flush=True)
    print()
    for label, r in worst.items():
        print(f"- {label}: worst point / brute {r:.2f}x (target <= 2x on 4096²)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
