"""Dynamic terrain (issue 22, item 3): a small edit re-shaded against a full render, in one run
(``make bench-update``).

For each terrain (a power-law spectral fractal, beta 3.2, 30 m cells, 2 km of relief, at
--size; the real DEMs of --dems) and each sun (azimuths 163, 203.7 and 290 deg at 3, 8 and
20 deg), one ``shading.Shader`` (``--algorithm``, default auto; CPU; curvature "auto" as the
command line has it) is lit once, then rounds alternate:

* **update + re-render**: ``Shader.update`` of a 20 x 20 window (raised by 40 m, somewhere new
  each round) and ``render(..., previous=(mask, version))``: the window's anti-sun halo only;
* **full render**: ``render`` of the same (edited) Shader: every cell, the pyramid, survey and
  height range kept by the Shader (what a viewer would otherwise do per edit).

Medians of --repeat rounds of each; the ratio full / update is measured in the same rounds. The
cells re-shaded per edit (``stats["rerendered_cells"]``) are shown as a share of the raster;
the first round's two masks are compared (they must be equal).

    python benchmarks/bench_update.py                      # 2048² and two real DEMs
    python benchmarks/bench_update.py --size 1024 --dems   # a quick look
"""

import argparse
import os
import platform
import statistics
import time

import numpy as np

from hillshade_rt import read_dem
from hillshade_rt.model.geometry import Grid
from hillshade_rt.engine.shader import Shader, render
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import real_dems, spectral

SUNS = [(163.0, 3.0), (203.7, 8.0), (290.0, 20.0)]
EDIT = 20


def terrains(size, dems):
    out = [(f"spectral {size}² (beta 3.2, 30 m)", spectral(size, 3.2, seed=4),
            Grid.uniform(size, size, 30.0))]
    for path, label in real_dems(dems) if dems else []:
        d = read_dem(path)
        out.append((label, d.heights, d.grid))
    return out


def bench(label, z, grid, algorithm, repeat, rng):
    lines = []
    rows, cols = z.shape
    for az, el in SUNS:
        sh = Shader(z.copy(), grid, algorithm, {}, "cpu", "auto")
        sun = SunOver(None, az, el)
        mask = render(sh, sun)                       # compiled, pyramid and survey made
        t_up, t_full, cells = [], [], []
        for k in range(repeat):
            r0, c0 = int(rng.integers(0, rows - EDIT)), int(rng.integers(0, cols - EDIT))
            new = sh.z[r0:r0 + EDIT, c0:c0 + EDIT] + np.float32(40.0)
            since, stats = sh.version, {}
            t = time.perf_counter()
            sh.update((r0, c0), new)
            mask = render(sh, sun, previous=(mask, since), stats=stats)
            t_up.append(time.perf_counter() - t)
            cells.append(stats.get("rerendered_cells", rows * cols))
            t = time.perf_counter()
            full = render(sh, sun)
            t_full.append(time.perf_counter() - t)
            if k == 0 and not np.array_equal(full, mask):
                raise SystemExit(f"{label} {az}/{el}: the re-rendered mask differs")
        up, fu = statistics.median(t_up), statistics.median(t_full)
        share = statistics.median(cells) / (rows * cols)
        lines.append(f"| {label} | {az:g} / {el:g} | {1e3 * up:.2f} | {1e3 * fu:.1f} | "
                     f"{fu / up:.0f}x | {100 * share:.3f} % |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=2048)
    ap.add_argument("--dems", nargs="*", default=["bigtujunga_srtm30m_utm11n_1197x643.tif",
                                                  "everest_srtm3_N27E086_voids_1201.tif"],
                    help="real DEMs (file names of benchmarks/data); none: the fractal only")
    ap.add_argument("--algorithm", default="auto")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    rng = np.random.default_rng(22)
    print(f"{platform.node()} {os.cpu_count()} cores, algorithm {args.algorithm}, CPU, "
          f"{EDIT}x{EDIT} edits, median of {args.repeat} alternating rounds")
    print()
    print("| terrain | sun az / el | update + re-render ms | full render ms | ratio | "
          "cells re-shaded |")
    print("|---|---|---|---|---|---|")
    for label, z, grid in terrains(args.size, args.dems):
        for line in bench(label, z, grid, args.algorithm, args.repeat, rng):
            print(line, flush=True)


if __name__ == "__main__":
    main()
