"""GPU benchmarks (``make bench-gpu``): every algorithm on the CUDA backend.

For fractal terrains of 1024², 4096², 8192², 16384² (float32, 30 m cells) and the bundled real
DEMs, at low and mid sun (3° and 15°, azimuth 203.7°):
  * kernel ms per sun position: CUDA events around the algorithm's kernels (median of --repeat,
    after one warm-up run that compiles), the DEM already on the device;
  * end-to-end ms per sun: the same call timed on the host, mask copied back included;
  * the CPU backend on the same DEM in the same run (--cpu-max cells at most: brute on 16384² on a
    CPU takes many minutes), and the GPU's speed-up over it;
  * a time series: --series sun positions (azimuth 90°..270°, elevation 5°..60°) with the DEM
    uploaded once, end to end (upload, every kernel, every mask back), per algorithm.
GPU masks are compared with the CPU's wherever the CPU ran (brute/smap/horizon must be equal).

Prints a markdown table with the GPU model (and writes it with --out). Needs a CUDA GPU and
``pip install 'hillshade-rt[gpu]'``: without one it says what is missing and exits 1.
"""

import argparse
import os
import platform
import statistics
import sys
import time

import numpy as np

from hillshade_rt.engine import gpu
from hillshade_rt import read_dem
from hillshade_rt.algorithms import ALGORITHMS
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import SMALL_REAL_DEMS, fractal_terrain, real_dems

EXACT = ("auto", "brute", "smap", "horizon")


def med(xs):
    return statistics.median(xs)


def bench_dem(name, z, grid, algorithms, elevations, repeat, cpu_max, rows):
    g = gpu.GpuDem(z)
    for el in elevations:
        rays = sun_rays(grid, 203.7, el)
        for alg in algorithms:
            g.shadow_mask(rays, alg)               # compile, warm up
            kms, e2e = [], []
            for _ in range(repeat):
                k0 = g.stats["kernel_ms"]
                t = time.perf_counter()
                m = g.shadow_mask(rays, alg)
                e2e.append(1e3 * (time.perf_counter() - t))
                kms.append(g.stats["kernel_ms"] - k0)
            cpu_ms = same = None
            if z.size <= cpu_max:
                ALGORITHMS[alg](z[:64, :64].copy(), sun_rays(Grid.uniform(64, 64, 30.0), 203.7,
                                                             el), g.zmax, None)
                t = time.perf_counter()
                ref = ALGORITHMS[alg](z, rays, g.zmax, None)
                cpu_ms = 1e3 * (time.perf_counter() - t)
                same = int(np.count_nonzero(ref != m))
                if alg in EXACT and same:
                    print(f"MISMATCH {name} {alg} {el}: {same} cells differ from the CPU",
                          file=sys.stderr)
            rows.append((name, f"{z.shape[1]}x{z.shape[0]}", el, alg, med(kms), med(e2e), cpu_ms,
                         same))
            print(rows[-1], file=sys.stderr, flush=True)


def bench_series(z, grid, algorithms, n, out):
    azs = np.linspace(90.0, 270.0, n)
    els = 5.0 + 55.0 * np.sin(np.linspace(0.0, np.pi, n))
    for alg in algorithms:
        gpu.GpuDem(z[:64, :64].copy()).shadow_mask(sun_rays(Grid.uniform(64, 64, 30.0), 100.0,
                                                            10.0), alg)
        t = time.perf_counter()
        g = gpu.GpuDem(z)
        for az, el in zip(azs, els):
            g.shadow_mask(sun_rays(grid, float(az), float(el)), alg)
        total = time.perf_counter() - t
        out.append((alg, n, total, g.stats["kernel_ms"], g.stats["transfer_ms"],
                    g.stats["h2d_bytes"], g.stats["d2h_bytes"]))
        print(out[-1], file=sys.stderr, flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", default="1024,4096,8192,16384")
    ap.add_argument("--elevations", default="3,15")
    ap.add_argument("--algorithms", default="auto,brute,smap,horizon,sweep")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--cpu-max", type=int, default=4096 * 4096)
    ap.add_argument("--series", type=int, default=100)
    ap.add_argument("--series-size", type=int, default=4096)
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    ok, what = gpu.status()
    if not ok or gpu.simulator_enabled():
        print(f"bench-gpu: {what if not ok else 'the CUDA simulator is on'}: no GPU to measure",
              file=sys.stderr)
        return 1
    algs = a.algorithms.split(",")
    els = [float(e) for e in a.elevations.split(",")]
    rows: list = []
    for n in (int(s) for s in a.sizes.split(",")):
        z = fractal_terrain(n, n, 7, 800.0, 6)
        bench_dem(f"fractal {n}", z, Grid.uniform(n, n, 30.0), algs, els, a.repeat, a.cpu_max,
                  rows)
    for path, _ in real_dems(SMALL_REAL_DEMS):
        d = read_dem(path)
        bench_dem(os.path.basename(path).split("_")[0], d.heights, d.grid, algs, els, a.repeat,
                  a.cpu_max, rows)
    series: list = []
    n = a.series_size
    bench_series(fractal_terrain(n, n, 7, 800.0, 6), Grid.uniform(n, n, 30.0), algs, a.series,
                 series)

    lines = [f"GPU: {what}; host: {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores. Median of {a.repeat} runs after a warm-up.", "",
             "| DEM | size | sun el | algorithm | GPU kernels ms | GPU end-to-end ms | CPU ms | "
             "CPU / GPU e2e | cells != CPU |", "|---|---|---|---|---|---|---|---|---|"]
    for name, size, el, alg, kms, e2e, cpu_ms, same in rows:
        lines.append(f"| {name} | {size} | {el:g}° | {alg} | {kms:.3f} | {e2e:.2f} | "
                     + (f"{cpu_ms:.1f} | {cpu_ms / e2e:.1f}× | {same}" if cpu_ms else "- | - | -")
                     + " |")
    lines += ["", f"Time series, {a.series} sun positions on {n}x{n}, DEM uploaded once:", "",
              "| algorithm | positions | end-to-end s | kernels ms | transfers ms | H→D MB | "
              "D→H MB |", "|---|---|---|---|---|---|---|"]
    for alg, cnt, total, kms, tms, h2d, d2h in series:
        lines.append(f"| {alg} | {cnt} | {total:.3f} | {kms:.1f} | {tms:.1f} | {h2d / 1e6:.1f} | "
                     f"{d2h / 1e6:.1f} |")
    text = "\n".join(lines)
    print(text)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
