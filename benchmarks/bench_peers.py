"""Peers in the same harness: other tools' shadow masks against ours, same DEM, same sun, same run.

Each peer runs where it is installed (``make bench-peers`` installs them into the venv) and is
skipped with a note where it is not:

* ``insolation``'s ``doshade`` (Corripio's scan lines from the sun-side edges, nearest neighbour,
  numba-parallel);
* ``whitebox-workflows``' ``horizon_angle`` (shadow = horizon angle > sun elevation; the DEM goes
  through a GeoTIFF, only the tool call is timed);
* ``topocalc``'s ``hor1d``-based horizon (shadow = horizon tangent > tan(elevation)).

For every tool: compute time (median of --repeat after a warm-up), the ratio to ``doshade``
measured in the same run, and the share of valid cells whose mask differs from ``brute``.

    python benchmarks/bench_peers.py [--sizes 2048,4096] [--elevations 15,3] [--out FILE]
"""

import argparse
import os
import platform
import sys

import numba
import numpy as np

from hillshade_rt import read_dem
from hillshade_rt.algorithms import brute, horizon, smap, sweep
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import (median_seconds, peer_doshade, peer_topocalc, peer_whitebox,
                                  real_dems, smooth_facets)

EXAMPLE = real_dems(["bigtujunga_srtm30m_utm11n_1197x643.tif"])[0][0]
CELL = 30.0


def timed(fn, repeat):
    """The median of ``repeat`` runs, after one warm-up call (compilation, first-touch)."""
    return median_seconds(fn, repeat, warm_up=True)


# peers (hillshade_rt.testing): each returns (name, callable giving a 0/1 shadow mask) or
# (name, reason skipped)
PEERS = {"doshade": peer_doshade, "whitebox": peer_whitebox, "topocalc": peer_topocalc}

OURS = {
    "brute": lambda z, r, zmax: brute.shadow_mask(z, r, zmax),
    "smap": lambda z, r, zmax: smap.shadow_mask(z, r, zmax),
    "horizon (hull)": lambda z, r, zmax: horizon.shadow_mask(z, r, zmax, method="hull"),
    "sweep": lambda z, r, zmax: sweep.shadow_mask(z, r, zmax),
}


def cases(sizes):
    d = read_dem(EXAMPLE)
    yield os.path.basename(EXAMPLE), d.heights, d.grid, float(d.grid.dx[0])
    for n in sizes:
        z = smooth_facets(n)
        yield f"fractal {n}²", z, Grid.uniform(n, n, CELL), CELL


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="2048,4096")
    ap.add_argument("--elevations", default="15,3")
    ap.add_argument("--azimuth", type=float, default=203.7)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--peers", default=",".join(PEERS),
                    help="peers to run, comma-separated (whitebox takes ~70 s per 2048² call)")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    peers = [PEERS[p] for p in a.peers.split(",") if p]
    sizes = [int(s) for s in a.sizes.split(",") if s]
    lines = [f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}, numba {numba.__version__}; azimuth {a.azimuth}; "
             f"median of {a.repeat}", "",
             "| DEM | elev | tool | compute s | × doshade (speed-up) | cells ≠ brute % |",
             "|---|---|---|---|---|---|"]
    print("\n".join(lines), flush=True)
    notes = []
    for name, z, grid, cell in cases(sizes):
        zmax = float(np.nanmax(z))
        valid = ~np.isnan(z)
        nvalid = max(1, int(valid.sum()))
        for el in [float(e) for e in a.elevations.split(",")]:
            rays = sun_rays(grid, a.azimuth, el)
            ref = None
            rows = []
            for tool, fn in OURS.items():
                reps = 1 if tool == "brute" else a.repeat
                t = timed(lambda: fn(z, rays, zmax), reps)
                m = fn(z, rays, zmax)
                if ref is None:
                    ref = m
                rows.append((tool, t, 100.0 * np.count_nonzero((m != ref) & valid) / nvalid))
            for peer in peers:
                tool, run = peer(z, cell, a.azimuth, el)
                if isinstance(run, str):
                    notes.append(f"{tool}: {run}")
                    continue
                try:
                    t = timed(run, a.repeat)
                    m = run()
                except Exception as e:  # a peer failing must not stop the others
                    notes.append(f"{tool}: failed on {name} ({type(e).__name__}: {e})")
                    continue
                rows.append((tool, t, 100.0 * np.count_nonzero((m != ref) & valid) / nvalid))
            t_dos = next((t for tool, t, _ in rows if tool.endswith("doshade")), None)
            for tool, t, wrong in rows:
                ratio = f"{t_dos / t:.2f}" if t_dos else "–"
                row = f"| {name} | {el:g}° | {tool} | {t:.3f} | {ratio} | {wrong:.3f} |"
                lines.append(row)
                print(row, flush=True)
    for n in dict.fromkeys(notes):
        lines.append(f"\nNote: {n}")
        print(f"Note: {n}", flush=True)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
