"""A DEM larger than the memory it may use: 20000 x 20000 float32 (1.6 GB), shaded with
``--max-memory 1GB``; the peak resident memory of the run (the whole process, from the kernel's
rusage of the child) is measured against the limit, and the mask is compared with an in-memory
run on a crop (the crop plus every cell that can shadow it, read whole and lit by the same code).

The DEM is synthetic (written in bands, never whole in memory): 1 m cells in UTM 11N, ridges of a
few wavelengths with ~520 m of relief, so that the sun's halo is long (2.4 km at 12 deg).

    python benchmarks/bigdem.py [--size 20000] [--max-memory 1GB] [--workdir DIR]
"""

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from hillshade_rt.testing import write_ridges_dem

BIN = os.path.join(os.path.dirname(sys.executable), "hillshade-rt")


def run_measured(args):
    """Run a command; (seconds, peak RSS of the child in bytes, return code)."""
    t = time.perf_counter()
    p = subprocess.Popen(args)
    _, status, usage = os.wait4(p.pid, 0)
    return time.perf_counter() - t, usage.ru_maxrss * 1024, os.waitstatus_to_exitcode(status)


def crop_reference(dem, crop, azimuth, elevation, pad):
    """In-memory mask of ``crop`` (r0, r1, c0, c1): the crop and ``pad`` cells around it read
    whole, lit by the engine (no tiling code), the crop cut out."""
    import rasterio
    from rasterio.windows import Window

    from hillshade_rt.engine.shader import Shader, render

    from hillshade_rt.model.earth import dem_body
    from hillshade_rt.model.sun import SunOver
    r0, r1, c0, c1 = crop
    with rasterio.open(dem) as ds:
        a0, a1 = max(0, r0 - pad), min(ds.height, r1 + pad)
        b0, b1 = max(0, c0 - pad), min(ds.width, c1 + pad)
        z = ds.read(1, window=Window(b0, a0, b1 - b0, a1 - a0))
    from hillshade_rt.io import open_dem
    from hillshade_rt.engine.windows import window_grid
    g = window_grid(open_dem(dem).grid, (a0, a1, b0, b1))   # the DEM's own spacing (UTM)
    sh = Shader(z, g, "smap", {}, "cpu", False)
    m = render(sh, SunOver(None, azimuth, elevation), "shadow")
    return m[r0 - a0:r1 - a0, c0 - b0:c1 - b0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=20000)
    ap.add_argument("--max-memory", default="1GB")
    ap.add_argument("--azimuth", type=float, default=203.7)
    ap.add_argument("--elevation", type=float, default=12.0)
    ap.add_argument("--workdir", default=None, help="keep the DEM here between runs")
    args = ap.parse_args()
    from hillshade_rt.engine.windows import format_size, parse_size

    work = args.workdir or tempfile.mkdtemp(prefix="hillshade-bigdem-")
    os.makedirs(work, exist_ok=True)
    dem = os.path.join(work, f"synthetic_{args.size}.tif")
    if not os.path.exists(dem):
        t = time.perf_counter()
        write_ridges_dem(dem, args.size)
        print(f"wrote {dem} ({format_size(os.path.getsize(dem))}) in {time.perf_counter() - t:.0f} s")
    out, rep = os.path.join(work, "mask.tif"), os.path.join(work, "mask.json")
    cmd = [BIN, "shadow", dem, out, "--azimuth", str(args.azimuth), "--elevation",
           str(args.elevation), "--max-memory", args.max_memory, "--no-earth-curvature",
           "--overwrite", "--report", rep, "-q"]
    secs, peak, rc = run_measured(cmd)
    if rc != 0:
        sys.exit(f"run failed ({rc}): {' '.join(cmd)}")
    doc = json.load(open(rep))
    proc = doc["processing"]
    limit = parse_size(args.max_memory)
    print(f"{args.size} x {args.size} float32 ({format_size(args.size ** 2 * 4)}), "
          f"--max-memory {args.max_memory}: peak RSS {format_size(peak)} "
          f"({100 * peak / limit:.0f} % of the limit) -> {'OK' if peak <= limit else 'OVER'}")
    if "windows" not in proc:       # it fitted in memory (a small --size)
        print(f"  mode {proc['mode']}: the DEM fitted in --max-memory, no windows")
    else:
        print(f"  mode {proc['mode']}, {proc['windows']} windows, largest "
              f"{proc['largest_window']}, halo cells {100 * proc['halo_cells_fraction']:.1f} %, "
              f"read beyond the output {100 * proc['bytes_read_beyond_output_fraction']:.1f} %, "
              f"carried {format_size(proc['bytes_carried'])}"
              + (f", SMap cells coloured beyond the output "
                 f"{100 * proc['smap_coloured_beyond_output_fraction']:.1f} %"
                 if "smap_coloured_beyond_output_fraction" in proc else ""))
    print(f"  wall {secs:.1f} s; stages {json.dumps({k: round(v, 1) for k, v in doc['seconds'].items()})}; "
          f"{doc['mpix_per_s']:.1f} Mpix/s in compute")
    # compare a crop with an in-memory run that holds every cell able to shadow it
    n = args.size
    crop = (n // 2 - 1000, n // 2 + 1000, n // 2 - 1000, n // 2 + 1000)
    pad = int(math.ceil((doc["height_range_m"][1] - doc["height_range_m"][0])
                        / math.tan(math.radians(args.elevation)))) + 8
    ref = crop_reference(dem, crop, args.azimuth, args.elevation, pad)
    import rasterio
    from rasterio.windows import Window
    with rasterio.open(out) as ds:
        got = ds.read(1, window=Window(crop[2], crop[0], crop[3] - crop[2], crop[1] - crop[0]))
    diff = int(np.count_nonzero(got != ref))
    print(f"  crop {crop}: {diff} cells differ from the in-memory run "
          f"({100 * np.mean(ref == 1):.1f} % shadow) -> {'OK' if diff == 0 else 'DIFFERENT'}")
    if peak > limit or diff:
        sys.exit(1)


if __name__ == "__main__":
    main()
