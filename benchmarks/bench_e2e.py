"""End to end against the floor (issue 18, item 7): ``hillshade-rt shadow`` on an N x N float32
GeoTIFF (a spectral fractal, beta 3.2, 30 m cells, 2 km relief; default 10000²) at 8 deg, against
the least any tool must do: read it with rasterio, one elementwise pass, write a uint8 DEFLATE
GeoTIFF. The command runs as users run it (a new process, the default algorithm, the report);
its stages come from the report, and the time outside them ("unnamed") is total minus their sum.
Each figure is the median of --repeat runs, floor and command alternated.

    python benchmarks/bench_e2e.py [--size 10000] [--repeat 3]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from hillshade_rt.testing import spectral, tiled


def floor(src: str, dst: str) -> float:
    import rasterio
    t0 = time.perf_counter()
    with rasterio.open(src) as r:
        z = r.read(1)
        prof = r.profile
    m = (z > np.float32(z.mean())).astype(np.uint8)
    prof.update(dtype="uint8", nodata=255, compress="deflate", tiled=True, predictor=1)
    with rasterio.open(dst, "w", **prof) as w:
        w.write(m, 1)
    return time.perf_counter() - t0


def command(src: str, dst: str, report: str) -> tuple[float, dict]:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "hillshade_rt", "shadow", src, dst, "--azimuth",
                    "203.7", "--elevation", "8", "--overwrite", "-q", "--report", report],
                   check=True)
    wall = time.perf_counter() - t0
    with open(report) as fh:
        return wall, json.load(fh)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=10000)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    import rasterio
    from rasterio.transform import from_origin
    with tempfile.TemporaryDirectory(dir=os.environ.get("TMPDIR", "/tmp")) as tmp:
        src = os.path.join(tmp, "dem.tif")
        z = tiled(spectral(min(a.size, 4096), 3.2, seed=5, relief=2000.0), a.size)
        with rasterio.open(src, "w", driver="GTiff", width=a.size, height=a.size, count=1,
                           dtype="float32", crs="EPSG:32611", tiled=True,
                           transform=from_origin(400000, 3800000, 30, 30)) as w:
            w.write(z, 1)
        del z
        command(src, os.path.join(tmp, "warm.tif"), os.path.join(tmp, "warm.json"))  # compile
        fl, runs = [], []
        for _ in range(a.repeat):
            fl.append(floor(src, os.path.join(tmp, "floor.tif")))
            runs.append(command(src, os.path.join(tmp, "out.tif"), os.path.join(tmp, "r.json")))
        f = statistics.median(fl)
        wall = statistics.median(w for w, _ in runs)
        rep = sorted(runs, key=lambda x: x[0])[len(runs) // 2][1]
        sec = rep["seconds"]
        named = sum(v for k, v in sec.items() if k != "total")
        print(f"`python benchmarks/bench_e2e.py --size {a.size}`: {a.size}² float32 GeoTIFF, "
              f"8°, {rep['algorithm']} ({', '.join(rep['algorithm_stats'].get('auto', {}).get('chose', {}))}), "
              f"median of {a.repeat}\n")
        print("| | seconds | × floor |")
        print("|---|---|---|")
        print(f"| floor: read + one pass + write uint8 DEFLATE | {f:.2f} | 1.00 |")
        print(f"| hillshade-rt shadow, wall clock (process start to exit) | {wall:.2f} | "
              f"{wall / f:.2f} |")
        print(f"| report total | {sec['total']:.2f} | {sec['total'] / f:.2f} |")
        for k in ("read", "prepare", "compute", "write"):
            print(f"| stage {k} | {sec[k]:.2f} | |")
        print(f"| outside the named stages (total − their sum) | {sec['total'] - named:.2f} "
              f"({100 * (sec['total'] - named) / sec['total']:.0f} %) | |")
        print(f"| before the report's clock (imports, start-up: wall − total) | "
              f"{wall - sec['total']:.2f} | |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
