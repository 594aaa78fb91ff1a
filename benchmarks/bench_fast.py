"""Issue 18's other targets for the default exact method, measured in one run (``make bench-fast``):

* **curvature**: the default (Earth curvature and refraction on, as the command line runs it)
  against the flat run, through the engine (``Shader``: the curvature pass included), on the real
  DEMs and a spectral fractal, at 3, 8 and 20 deg; target <= 1.2x;
* **O(N)**: Mpix/s of the default on the same rough terrain (a spectral fractal, beta 3.2,
  2048², repeated seamlessly) at 2048², 4096², 8192²; target: 8192² >= 0.7 x the smallest;
* **a sun from a time** over a 61 km DEM: per tile (the default) and every cell's own sun
  (``Shader(sun_field=True)``) against one vector for the whole raster; target <= 1.3x;
* **geographic vs projected**: the Everest SRTM tile (geographic, per-row spacing) against the
  same heights on a uniform grid of its middle row's spacing (what a UTM copy would have).

Compute stage only, after a warm-up; the median of --repeat runs, the cases alternated.

    python benchmarks/bench_fast.py            # about 2 minutes on 2 cores
"""

import argparse
import itertools
import datetime
import os
import platform
import statistics
import sys
import time

import numba
import numpy as np

from hillshade_rt import read_dem
from hillshade_rt.model.earth import dem_body
from hillshade_rt.engine.shader import Shader
from hillshade_rt.model.geometry import Grid
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import real_dems, spectral, tiled


def timed(fns: dict, repeat: int) -> dict:
    """Median seconds of each function, the functions alternated ``repeat`` rounds."""
    t = {k: [] for k in fns}
    for _ in range(repeat):
        for k, f in fns.items():
            t0 = time.perf_counter()
            f()
            t[k].append(time.perf_counter() - t0)
    return {k: statistics.median(v) for k, v in t.items()}


def cast(z, grid, curvature, az, el, body=None):
    sh = Shader(z, grid, "auto", {}, "cpu", curvature, None, body)
    sh.cast(SunOver(None, az, el).regions(z.shape)[0], {})   # warm: pyramid, kernels
    return lambda: sh.cast(SunOver(None, az, el).regions(z.shape)[0], {})


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sizes", default="2048,4096,8192")
    a = ap.parse_args(argv)
    print(f"`python benchmarks/bench_fast.py` — {datetime.date.today().isoformat()}; "
          f"{platform.machine()}, {os.cpu_count()} cores, numba {numba.__version__}, "
          f"{numba.get_num_threads()} threads; compute stage, median of {a.repeat}\n")

    print("### Curvature on (the default) vs off, auto, az 290\n")
    print("| terrain | el | flat s | curved s | curved ÷ flat |")
    print("|---|---|---|---|---|")
    cases = [(label, read_dem(path)) for path, label in real_dems()]
    spec = spectral(2048, 3.2, seed=7, relief=2000.0)
    for label, d in cases + [("spectral β 3.2 2048², 30 m", None)]:
        z, grid = (spec, Grid.uniform(2048, 2048, 30.0)) if d is None else (d.heights, d.grid)
        body = dem_body(d) if d is not None else None
        for el in (3.0, 8.0, 20.0):
            t = timed({"flat": cast(z, grid, False, 290.0, el, body),
                       "curved": cast(z, grid, True, 290.0, el, body)}, a.repeat)
            print(f"| {label} | {el:g} | {t['flat']:.3f} | {t['curved']:.3f} | "
                  f"{t['curved'] / t['flat']:.2f} |", flush=True)

    print("\n### Cost against size: spectral β 3.2 2048² repeated, auto, flat, 8°\n")
    print("| size | az | s | Mpix/s | × the smallest's Mpix/s |")
    print("|---|---|---|---|---|")
    first = {}
    for n in (int(x) for x in a.sizes.split(",")):
        z = tiled(spec, n)
        grid = Grid.uniform(n, n, 30.0)
        for az in (203.7, 290.0):
            t = timed({"x": cast(z, grid, False, az, 8.0)}, a.repeat)["x"]
            mp = n * n / 1e6 / t
            first.setdefault(az, mp)
            print(f"| {n}² | {az:g} | {t:.3f} | {mp:.1f} | {mp / first[az]:.2f} |", flush=True)
        del z

    print("\n### A sun from a time over a 61 km DEM: per tile and every cell's own sun vs one "
          "vector\n")
    print("(spectral β 3.2 2048² at 30 m in UTM 11N at 34° N, auto, curvature as given; one "
          "vector: the same instant with the tolerance raised so that one vector serves)\n")
    print("| time (local) | curvature | el | deviation across the DEM ° | tiles | one vector s | "
          "per tile s (sun_field=False) | per cell s (the default) | per tile ÷ one vector | "
          "per cell ÷ one vector |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    import tempfile
    import rasterio
    from rasterio.transform import from_origin
    from hillshade_rt.engine.shader import render
    from hillshade_rt.model.site import dem_site
    from hillshade_rt.model.sun import sun_over
    from hillshade_rt.model.times import parse_time
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "d.tif")
        with rasterio.open(path, "w", driver="GTiff", width=2048, height=2048, count=1,
                           dtype="float32", crs="EPSG:32611",
                           transform=from_origin(400000, 3800000, 30, 30)) as w:
            w.write(spec, 1)
        d = read_dem(path)
    site = dem_site(d)
    for when, curv in itertools.product(
            ("2026-06-21T06:10-07:00", "2026-06-21T08:30-07:00", "2026-12-21T15:40-08:00"),
            ("auto", False)):
        t = parse_time(when)
        [var] = sun_over(site, d.shape, [t])
        [one] = sun_over(site, d.shape, [t], tolerance=10.0)
        sh = Shader(d.heights, d.grid, "auto", {}, "cpu", curv, None, dem_body(d),
                    sun_field=False)
        shf = Shader(d.heights, d.grid, "auto", {}, "cpu", curv, None, dem_body(d))
        for s_, v_ in ((sh, one), (sh, var), (shf, var)):
            render(s_, v_, "shadow")
        tt = timed({"one": lambda: render(sh, one, "shadow"),
                    "tiles": lambda: render(sh, var, "shadow"),
                    "var": lambda: render(shf, var, "shadow")}, a.repeat)
        print(f"| {when} | {'on (the default)' if curv else 'off'} | {one.elevation:.1f} | "
              f"{var.deviation_deg:.3f} | "
              f"{len(var.tiles or [])} | {tt['one']:.3f} | {tt['tiles']:.3f} | {tt['var']:.3f} | "
              f"{tt['tiles'] / tt['one']:.2f} | {tt['var'] / tt['one']:.2f} |", flush=True)

    print("\n### Geographic vs the same heights on one uniform spacing (Everest SRTM 3″ tile)\n")
    print("| az | el | geographic s | uniform s | geographic ÷ uniform |")
    print("|---|---|---|---|---|")
    d = read_dem(real_dems()[1][0])
    i = d.grid.rows // 2
    uni = Grid.uniform(d.grid.rows, d.grid.cols, float(d.grid.dx[i]), float(d.grid.dy[i]),
                       d.grid.col_sign, d.grid.row_sign)
    for az in (203.7, 290.0):
        for el in (3.0, 8.0, 20.0):
            t = timed({"geo": cast(d.heights, d.grid, False, az, el),
                       "uni": cast(d.heights, uni, False, az, el)}, a.repeat)
            print(f"| {az:g} | {el:g} | {t['geo']:.3f} | {t['uni']:.3f} | "
                  f"{t['geo'] / t['uni']:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
