"""CPU benchmarks: every algorithm on real DEMs and fractal terrains at high, mid and low sun.

The fractal here is hillshade_rt.testing.smooth_facets, labelled "smooth (facets)": a few noise
octaves upsampled bilinearly, far smoother than any real DEM. Rough terrain (spectral fractals,
more real DEMs, 18 suns, the peers) is in bench_real.py (``make bench-real``).

Prints a markdown table (and writes it with --out). Each figure is the median of --repeat runs
after one warm-up (compilation excluded). Ratios are measured within this one run:
  * floor ratio: algorithm time / time of one elementwise pass (``z > mean``) over the same
    array: how far the algorithm is from the memory-bound limit;
  * thread speed-up: the same algorithm with 1 thread vs all threads;
  * peak memory: the most resident memory the call added above what the process held before it
    (Linux: the peak is reset through /proc/self/clear_refs, read from VmHWM), in bytes per cell.
"""

import argparse
import os
import platform

import numba
import numpy as np

from hillshade_rt import read_dem
from hillshade_rt.algorithms import ALGORITHMS
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import SMALL_REAL_DEMS, median_seconds, real_dems, smooth_facets


def _status_kb(key):
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key + ":"):
                return int(line.split()[1])
    raise KeyError(key)


def peak_extra_bytes(fn):
    """Peak resident memory added by one call of fn (None where Linux's counters are missing)."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")     # reset VmHWM to the current RSS
        before = _status_kb("VmRSS")
        fn()
        return 1024 * (_status_kb("VmHWM") - before)
    except (OSError, KeyError):
        return None


def cases(sizes):
    for p, _ in real_dems(SMALL_REAL_DEMS):
        d = read_dem(p)
        yield os.path.basename(p), d.heights, d.grid
    for n in sizes:
        # 1.5 km relief on 30 m cells, float32 like every DEM the tool reads
        z = smooth_facets(n)
        yield f"smooth (facets) fractal {n}²", z, Grid.uniform(n, n, 30.0)
    n = sizes[0] if sizes else 512
    z = smooth_facets(n, seed=n + 1)
    z[z < np.percentile(z, 50)] = np.nan   # islands in a nodata sea (half the cells are voids)
    yield f"smooth (facets) islands {n}² (half nodata)", z, Grid.uniform(n, n, 30.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="512,2048", help="fractal sizes, comma-separated")
    ap.add_argument("--elevations", default="45,15,3")
    ap.add_argument("--azimuth", type=float, default=203.7)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default=None, help="also write the table to this file")
    a = ap.parse_args()
    sizes = [int(s) for s in a.sizes.split(",") if s]
    els = [float(e) for e in a.elevations.split(",")]
    nthreads = numba.get_num_threads()
    lines = [f"Machine: {platform.machine()}, {os.cpu_count()} cores, {platform.python_version()}, "
             f"numba {numba.__version__}, {nthreads} threads; azimuth {a.azimuth}; median of "
             f"{a.repeat}", "",
             "| DEM | cells | elev | algorithm | compute s | Mpix/s | × brute (speed-up) | × floor "
             "| 1-thread / all | peak extra B/cell |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    print("\n".join(lines), flush=True)
    for name, z, grid in cases(sizes):
        zmax = float(np.nanmax(z))
        thr = float(np.nanmean(z))
        floor = median_seconds(lambda: np.greater(z, thr), a.repeat)
        for el in els:
            rays = sun_rays(grid, a.azimuth, el)
            t_brute = None
            # brute first: every row's speed-up is against it (auto came first in the table
            # and divided by None)
            for alg, fn in sorted(ALGORITHMS.items(), key=lambda kv: kv[0] != "brute"):
                fn(z, rays, zmax)  # warm-up / compile
                t = median_seconds(lambda: fn(z, rays, zmax), a.repeat)
                numba.set_num_threads(1)
                t1 = median_seconds(lambda: fn(z, rays, zmax), 1)
                numba.set_num_threads(nthreads)
                mem = peak_extra_bytes(lambda: fn(z, rays, zmax))
                mem = "–" if mem is None else f"{mem / z.size:.2f}"
                if alg == "brute":
                    t_brute = t
                row = (f"| {name} | {z.size / 1e6:.2f} M | {el:g}° | {alg} | {t:.3f} | "
                       f"{z.size / 1e6 / t:.1f} | {t_brute / t:.1f} | {t / floor:.0f} | "
                       f"{t1 / t:.2f} | {mem} |")
                lines.append(row)
                print(row, flush=True)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
