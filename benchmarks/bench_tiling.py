"""Throughput in memory vs in windows vs on a Dask LocalCluster of 2 workers, same DEM, same sun.

Each figure is a whole command-line run (read, statistics pass, compute, write), the median of
--repeat runs after a warm-up, on a synthetic DEM (``hillshade_rt.testing.ridges``, 1 m cells, ~520 m of
relief) of --size x --size cells. The windowed run gets --max-memory so that its windows hold
about a quarter of the DEM each (what the planner makes of that is reported: windows, window
cells beyond the output, and for SMap the elements coloured beyond the output: its tables are
carried along strips of windows, so a strip's halo is coloured once); the Dask run plans
independent windows (nothing carried) on ``--scheduler local:2`` (two worker processes, each with
half of the cores). Ratios are within this one run.

    python benchmarks/bench_tiling.py [--size 6000] [--repeat 2]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

BIN = os.path.join(os.path.dirname(sys.executable), "hillshade-rt")


def run(args, report):
    t = time.perf_counter()
    subprocess.run(args + ["--report", report, "--overwrite", "-q"], check=True)
    wall = time.perf_counter() - t
    return wall, json.load(open(report))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=6000)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--algorithm", default="smap")
    ap.add_argument("--elevations", default="20,12")
    args = ap.parse_args()
    from hillshade_rt.testing import write_ridges_dem
    from hillshade_rt.engine.windows import GDAL_CACHE_MB, bytes_per_cell, format_size

    work = tempfile.mkdtemp(prefix="hillshade-bench-tiling-")
    dem = os.path.join(work, "dem.tif")
    write_ridges_dem(dem, args.size)
    cells = args.size ** 2
    # room for the process (~0.3 GB), GDAL's cache, and windows of about a quarter of the DEM
    limit = int(0.35e9) + (GDAL_CACHE_MB << 20) + cells * bytes_per_cell(args.algorithm) // 4
    out, rep = os.path.join(work, "m.tif"), os.path.join(work, "r.json")
    print(f"DEM {args.size} x {args.size} ({cells / 1e6:.0f} Mpix), {args.algorithm}, "
          f"azimuth 203.7, windowed runs with --max-memory {format_size(limit)}, "
          f"median of {args.repeat}")
    print("| sun elevation | mode | windows | window cells beyond output | SMap cells coloured "
          "beyond output | wall s | Mpix/s (wall) | compute Mpix/s | vs in memory |")
    print("|---|---|---|---|---|---|---|---|---|")
    for el in [float(e) for e in args.elevations.split(",")]:
        base = [BIN, "shadow", dem, out, "--azimuth", "203.7", "--elevation", str(el),
                "--algorithm", args.algorithm]
        modes = [("in memory", base),
                 ("windows", base + ["--max-memory", str(limit)]),
                 ("dask local:2", base + ["--max-memory", str(limit), "--scheduler", "local:2"])]
        ref = None
        for name, cmd in modes:
            run(cmd, rep)                      # warm-up (numba cache, page cache)
            walls, docs = [], []
            for _ in range(args.repeat):
                w, d = run(cmd, rep)
                walls.append(w)
                docs.append(d)
            wall = statistics.median(walls)
            d = docs[-1]
            p = d["processing"]
            ref = wall if ref is None else ref
            comp = d["seconds"]["compute"]
            col = p.get("smap_coloured_beyond_output_fraction")
            col = "–" if col is None else f"{100 * col:.0f} %"
            print(f"| {el:g} | {name} | {p.get('windows', 1)} | "
                  f"{100 * p.get('halo_cells_fraction', 0.0):.0f} % | {col} | {wall:.1f} | "
                  f"{cells / 1e6 / wall:.1f} | {cells / 1e6 / comp:.1f} | {wall / ref:.2f} |")


if __name__ == "__main__":
    main()
