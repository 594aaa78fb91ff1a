"""Horizons in N directions and the sky view factor (issue 20): their cost against one exact
shadow mask, and the peers' sky view factor against ours, same DEM, same directions, same radius,
same run.

Part 1 (target: ``horizon --directions 32`` and ``skyview --directions 32`` each <= 32x one
exact shadow mask): on the real DEMs of the repository and on spectral fractals, one ``auto`` mask
(the median over 8 of the same azimuths at 8 deg), the horizon in every direction (negative angles kept,
one maximum-height pyramid shared), and the sky view factor (Zaksek, the same scan with the
angles floored at the horizontal, which is all the definition reads). Flat Earth throughout (the
peers have no curvature).

Part 2 (target: >= 5x faster than rvt-py's SVF at the same directions and radius, with equal or
better agreement to the exact model): ``rvt.vis.sky_view_factor`` (Zaksek et al.'s own code:
nearest-cell shifts, mirrored padding at the edges) and whitebox-workflows' ``sky_view_factor``
against ``arrays.sky_view(..., max_distance=R cells)``. Agreement: mean and 99th percentile of
|SVF - exact SVF of the model within the same radius| over the cells at least R from the edge
(ours is that model: its row shows 0 when it is), and against the exact SVF without a radius.

    python benchmarks/bench_horizon.py [--size 1024] [--directions 32] [--radius 10]
                                       [--peers rvt,whitebox] [--out FILE]
"""

import argparse
import os
import platform
import sys
import time

import numba
import numpy as np

from hillshade_rt import read_dem
from hillshade_rt.algorithms import horizon as hz
from hillshade_rt.algorithms.pyramid import MaxPyramid
from hillshade_rt.engine.arrays import shadow_mask, sky_view
from hillshade_rt.model.geometry import Grid, equal_azimuths, sun_rays
from hillshade_rt.testing import peer_svf_rvt, peer_svf_whitebox, real_dems, spectral

CELL = 30.0


def terrains(size, names):
    for path, label in real_dems():
        if names and not any(n in label for n in names):
            continue
        d = read_dem(path)
        yield label, d.heights, d.grid
    for beta in (2.4, 3.2):
        if names and f"β {beta}" not in names:
            continue
        yield f"spectral β {beta} {size}² at {CELL:g} m", spectral(size, beta, seed=1), \
            Grid.uniform(size, size, CELL)


def seconds(fn):
    t = time.perf_counter()
    out = fn()
    return time.perf_counter() - t, out


def part1(z, grid, n, lines):
    azimuths = equal_azimuths(360.0 / n)
    # warm (compile, first touch) on the same arrays
    r0, c0 = z.shape[0] // 2 - 32, z.shape[1] // 2 - 32       # warm on the middle (voids)
    small = Grid(64, 64, grid.dx[r0:r0 + 64], grid.dy[r0:r0 + 64], grid.col_sign,
                 grid.row_sign, grid.method)
    zs = z[r0:r0 + 64, c0:c0 + 64].copy()
    shadow_mask(z, azimuths[1], 8.0, grid, curvature=False)   # compile, first touch
    t_masks = [seconds(lambda: shadow_mask(z, a, 8.0, grid, curvature=False))[0]
               for a in azimuths[::max(1, n // 8)]]
    t_mask = float(np.median(t_masks))
    pyr = MaxPyramid(z)
    hz.horizon_angles(zs, sun_rays(small, 10.0, 45.0))
    sky_view(zs, small, 8, curvature=False)
    t_hor, _ = seconds(lambda: [hz.horizon_angles(z, sun_rays(grid, a, 45.0), pyramid=pyr)
                                for a in azimuths])
    t_svf, _ = seconds(lambda: sky_view(z, grid, n, curvature=False))
    return t_mask, t_hor, t_svf


def exact_svf(z, grid, n, radius_m):
    kw = {} if radius_m is None else {"max_distance": radius_m}
    return sky_view(z, grid, n, curvature=False, **kw)


PEERS = {"rvt": peer_svf_rvt, "whitebox": peer_svf_whitebox}


def part2(label, z, grid, n, r, peers, lines, notes):
    cell = float(np.mean(grid.centre_spacing()))
    inner = (slice(r, -r), slice(r, -r))
    valid = np.isfinite(z)[inner]
    t_ours, ours = seconds(lambda: exact_svf(z, grid, n, r * cell))
    full = exact_svf(z, grid, n, None)
    rows = [("hillshade-rt skyview (exact, radius)", t_ours, ours)]
    for p in peers:
        name, run = PEERS[p](z, cell, n, r)
        if isinstance(run, str):
            notes.append(f"{name}: {run}")
            continue
        try:
            run_small = PEERS[p](z[:64, :64].copy(), cell, n, r)[1]
            run_small()                                   # warm
            t, svf = seconds(run)
        except Exception as e:     # a peer failing must not stop the others
            notes.append(f"{name}: failed on {label} ({type(e).__name__}: {e})")
            continue
        rows.append((name, t, svf))
    for name, t, svf in rows:
        d_r = np.abs(svf[inner] - ours[inner])[valid]
        d_f = np.abs(svf[inner] - full[inner])[valid]
        d_r, d_f = d_r[np.isfinite(d_r)], d_f[np.isfinite(d_f)]
        row = (f"| {label} | {n} | {r} | {name} | {t:.2f} | {t / t_ours:.1f} | "
               f"{d_r.mean():.4f} / {np.percentile(d_r, 99):.4f} | "
               f"{d_f.mean():.4f} / {np.percentile(d_f, 99):.4f} |")
        lines.append(row)
        print(row, flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=1024, help="side of the spectral fractals")
    ap.add_argument("--directions", type=int, default=32)
    ap.add_argument("--radius", type=int, default=10, help="peers' radius, cells (rvt: 10)")
    ap.add_argument("--peers", default="rvt,whitebox")
    ap.add_argument("--only", default="", help="terrain labels containing these (comma list)")
    ap.add_argument("--skip-part1", action="store_true")
    ap.add_argument("--skip-part2", action="store_true")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    names = [s for s in a.only.split(",") if s]
    peers = [p for p in a.peers.split(",") if p]
    n, r = a.directions, a.radius
    lines = [f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}, numba {numba.__version__}; {n} directions; flat "
             "Earth", ""]
    if not a.skip_part1:
        lines += ["| terrain | one auto mask s (8°) | horizon ×N s | × one mask | skyview s | "
                  "× one mask |", "|---|---|---|---|---|---|"]
        print("\n".join(lines), flush=True)
        for label, z, grid in terrains(a.size, names):
            t_mask, t_hor, t_svf = part1(z, grid, n, lines)
            row = (f"| {label} | {t_mask:.4f} | {t_hor:.2f} | {t_hor / t_mask:.0f} | "
                   f"{t_svf:.2f} | {t_svf / t_mask:.0f} |")
            lines.append(row)
            print(row, flush=True)
    if a.skip_part2:
        if a.out:
            with open(a.out, "w") as fh:
                fh.write("\n".join(lines) + "\n")
        return 0
    head = ["", "| terrain | directions | radius cells | tool | s | × ours | "
            "Δ exact (radius) mean / p99 | Δ exact (no radius) mean / p99 |",
            "|---|---|---|---|---|---|---|---|"]
    lines += head
    print("\n".join(head), flush=True)
    notes: list = []
    for label, z, grid in terrains(a.size, names):
        part2(label, z, grid, n, r, peers, lines, notes)
    for note in dict.fromkeys(notes):
        lines.append(f"\nNote: {note}")
        print(f"Note: {note}", flush=True)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
