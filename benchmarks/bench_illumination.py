"""The illumination run (issue 21, item 4) end to end: ``hillshade-rt illumination`` on 1000
subsolar positions of ``testing.toy_lunar_subsolar`` (6-hour steps: 250 days, the sun circling
the south pole within ~1.5 deg of the horizon) over

* a 2048^2 spectral fractal (beta 2.2, ~3 km of relief, 20 m cells) on the lunar south polar
  stereographic grid (``testing.LUNAR_SOUTH_POLAR_STEREO``) centred on the pole;
* the real Kepler crater LOLA crop of benchmarks/data (804^2, 47.7 m) relocated to the south
  pole: its heights on a south polar stereographic grid of the same spacing centred on the
  pole (real lunar relief at a pretend place).

Issue 21's target: 1000 positions on a 2048^2 polar DEM in under 10 minutes on this 2-core
machine. Prints the seconds (total, per position) and the report's figures; --n and --size for
a quicker look::

    python benchmarks/bench_illumination.py                  # the full figure (~minutes)
    python benchmarks/bench_illumination.py --n 50 --size 1024
    python benchmarks/bench_illumination.py --backend gpu     # on a machine with a GPU
"""

import argparse
import json
import os
import platform
import sys
import tempfile
import time

import numba
import numpy as np
import rasterio
from affine import Affine

from hillshade_rt.run.config import IllumConfig

from hillshade_rt.run.illumination import illumination
from hillshade_rt.testing import (LUNAR_SOUTH_POLAR_STEREO, repo_root, spectral,
                                  toy_lunar_subsolar, write_geotiff, write_subsolar_csv)

KEPLER = "moon_kepler_crater_lola_ortho_804x804.tif"


def polar(folder, z, cell, name):
    n_r, n_c = z.shape
    tr = Affine(cell, 0, -n_c / 2 * cell, 0, -cell, n_r / 2 * cell)
    return write_geotiff(os.path.join(folder, name), z.astype(np.float32), tr,
                         LUNAR_SOUTH_POLAR_STEREO)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=1000, help="subsolar positions (default 1000)")
    ap.add_argument("--step-h", type=float, default=6.0)
    ap.add_argument("--size", type=int, default=2048)
    ap.add_argument("--soft", action="store_true", help="also the --soft band")
    ap.add_argument("--skip-fractal", action="store_true")
    ap.add_argument("--skip-kepler", action="store_true")
    ap.add_argument("--backend", default="cpu", choices=["cpu", "gpu"],
                    help="gpu: the CUDA twins (issue 21's GPU target: under 30 s)")
    args = ap.parse_args()
    print(f"# bench_illumination: {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, numba {numba.__version__} ({numba.get_num_threads()} "
          f"threads), {args.n} positions every {args.step_h:g} h")
    with tempfile.TemporaryDirectory() as tmp:
        csv = write_subsolar_csv(os.path.join(tmp, "sun.csv"),
                                 toy_lunar_subsolar(args.n, args.step_h, phase_deg=270.0))
        dems = []
        if not args.skip_fractal:
            z = spectral(args.size, 2.2, seed=7, relief=3000.0)
            dems.append((f"spectral {args.size}^2, 20 m, south pole", polar(tmp, z, 20.0,
                                                                            "fractal.tif")))
        with rasterio.open(os.path.join(repo_root(), "benchmarks", "data", KEPLER)) as ds:
            zk = ds.read(1).astype(np.float32)
            cell = abs(ds.transform.a)
        if not args.skip_kepler:
            dems.append((f"Kepler LOLA {zk.shape[0]}^2, {cell:.1f} m, relocated to the south pole",
                         polar(tmp, zk, cell, "kepler_polar.tif")))
        # compile once (numba's cache) on a small DEM so that the timings are of the run
        small = polar(tmp, zk[:64, :64], cell, "warm.tif")
        illumination(IllumConfig(files=[small, os.path.join(tmp, "warm_out.tif")],
                                 subsolar_file=csv, soft=args.soft,
                                 run=_quiet(backend=args.backend)))
        for label, dem in dems:
            out = os.path.join(tmp, "out.tif")
            t0 = time.perf_counter()
            rep = illumination(IllumConfig(files=[dem, out], subsolar_file=csv, soft=args.soft,
                                           run=_quiet(overwrite=True, backend=args.backend)))
            wall = time.perf_counter() - t0
            print(f"{label}: {wall:.1f} s total, {1000 * wall / args.n:.1f} ms a position "
                  f"(compute {rep['seconds']['compute']:.1f} s); positions marched "
                  f"{rep['positions']['marched']}, dark everywhere "
                  f"{rep['positions']['dark_everywhere']}; mean fraction lit "
                  f"{rep['mean']['fraction_lit']:.3f}; never lit "
                  f"{100 * rep['permanently_shadowed_cells'] / rep['valid_cells']:.2f}% of cells"
                  + ("; target 600 s: " + ("met" if wall < 600 else "MISSED")
                     if args.size == 2048 and args.n == 1000 and "spectral" in label else ""))
            sys.stdout.flush()
        print(json.dumps({"seconds": rep["seconds"]}, indent=None))


def _quiet(overwrite=False, backend="cpu"):
    from hillshade_rt.run.config import RunOptions
    return RunOptions(quiet=True, overwrite=overwrite, backend=backend)


if __name__ == "__main__":
    main()
