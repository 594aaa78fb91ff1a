"""Benchmarks that look like Earth: every algorithm and the peers on real DEMs and spectral fractals.

Terrains (hillshade_rt.testing): the real DEMs of the repo (UTM, geographic SRTM, NZTM with sea,
the Moon), power-law fractals (2-D power spectrum ~ k^-beta, beta 2.4 and 3.2, 2 km relief on
30 m cells) at each --sizes, and the old smooth facet fractal (testing.smooth_facets)
as a labelled "smooth (facets)" case. Suns: every --azimuths x --elevations, flat Earth.

Compute stage only: each algorithm is called on the arrays and rays directly (no reading, no
writing). numba compiles before any timing (every algorithm at every azimuth, on a small
uniform and a small geographic grid), then the tools are timed in turn, alternated, --repeat
times, and each figure is the median. Ratios (x brute: brute's time / the tool's time, > 1 is
faster) are measured within this one run, on the same terrain and sun.

Columns: Mpix/s of the plain march (brute --no-pyramid, brute as it was before issue 18: the
reference), then each tool's Mpix/s and its speed relative to the plain march; auto against
doshade (doshade's time ÷ auto's: >= 1 is the issue's target); what auto ran; the share of cells
bounds left to the pyramid march, smap's Black fraction, sweep's unsure fraction, and the share
of valid cells in which the approximate tools (sweep, the peers) differ from the exact mask.
Every exact tool (auto, bounds, brute over the pyramid, smap, horizon scan) is checked against
the plain march cell for cell: a difference is printed as an error and the run exits 1.

Peers where installed (``make bench-peers`` installs them): insolation's doshade (square cells:
a geographic DEM gets the geometric mean of its middle row's spacings) and whitebox-workflows'
horizon_angle (slow: run at --whitebox-suns only, once).

    python benchmarks/bench_real.py --quick          # a few minutes on 2 cores
    python benchmarks/bench_real.py                  # 1024, 2048, 4096; all 18 suns
    python benchmarks/bench_real.py --sizes 8192 --no-real --no-smooth
"""

import argparse
import datetime
import math
import os
import platform
import shlex
import statistics
import sys
import time

import numba
import numpy as np

from hillshade_rt import read_dem
from hillshade_rt.algorithms import auto, bounds, brute, horizon, smap, sweep
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import (peer_doshade, peer_whitebox, real_dems, roughness,
                                  smooth_facets, spectral, tiled)

AZIMUTHS = "20,120,203.7,250,290,330"
ELEVATIONS = "3,8,20"
QUICK_AZIMUTHS = "203.7,290"
CELL = 30.0
RELIEF = 2000.0

OURS = {
    # the plain march (brute before issue 18, now --no-pyramid): the reference of every ratio
    "plain": lambda z, r, zmax, st: brute.shadow_mask(z, r, zmax, stats=st, pyramid=False),
    "auto": lambda z, r, zmax, st: auto.shadow_mask(z, r, zmax, stats=st),
    "bounds": lambda z, r, zmax, st: bounds.shadow_mask(z, r, zmax, stats=st),
    "brute": lambda z, r, zmax, st: brute.shadow_mask(z, r, zmax, stats=st),
    "smap": lambda z, r, zmax, st: smap.shadow_mask(z, r, zmax, stats=st),
    "horizon": lambda z, r, zmax, st: horizon.shadow_mask(z, r, zmax, stats=st, method="scan"),
    "sweep": lambda z, r, zmax, st: sweep.shadow_mask(z, r, zmax, stats=st),
}
EXACT = ("auto", "bounds", "brute", "smap", "horizon")
SHOWN = ("auto", "bounds", "brute", "smap", "horizon", "sweep")


def warm_up(azimuths, elevations, log):
    """Compile every kernel specialisation the timed runs will use: each algorithm at each
    azimuth (the octant frames are views with their own strides) on a uniform grid and on a
    geographic one (per-row spacing), and the peers' own compilation."""
    t0 = time.perf_counter()
    small = spectral(96, 3.0, seed=7)
    small[40:44, 50:60] = np.nan
    geo = read_dem(real_dems()[-1][0])    # Jacksboro: EPSG:4326, per-row spacing
    grids = [(small, Grid.uniform(96, 96, CELL)),
             (np.ascontiguousarray(geo.heights[:80, :90]), None)]
    # a geographic grid for the crop: the same per-row spacing as the file's first 80 rows
    g = geo.grid
    grids[1] = (grids[1][0], Grid(80, 90, g.dx[:80].copy(), g.dy[:80].copy(), g.col_sign,
                                  g.row_sign, g.method))
    for z, grid in grids:
        zmax = float(np.nanmax(z))
        for az in azimuths:
            for el in elevations:
                rays = sun_rays(grid, az, el)
                for fn in OURS.values():
                    fn(z, rays, zmax, {})
    for az in azimuths:
        _, run = peer_doshade(small, CELL, az, 8.0)
        if not isinstance(run, str):
            run()
    log(f"(warm-up: {time.perf_counter() - t0:.1f} s)")


def cases(a):
    """(label, heights, grid, kind) for every benchmark terrain."""
    if a.real:
        for path, label in real_dems():
            d = read_dem(path)
            yield f"{label} ({os.path.basename(path)})", d.heights, d.grid, "real"
    for n in a.sizes:
        for beta in a.betas:
            if a.tile_from and a.tile_from < n:
                # the same surface as the tile_from² case, repeated
                z = tiled(spectral(a.tile_from, beta, seed=int(10 * beta) + a.tile_from,
                                   relief=RELIEF), n)
                label = f"spectral β {beta:g} {a.tile_from}² tiled to {n}²"
            else:
                z = spectral(n, beta, seed=int(10 * beta) + n, relief=RELIEF)
                label = f"spectral β {beta:g} {n}²"
            yield label, z, Grid.uniform(n, n, CELL), "spectral"
    if a.smooth:
        n = a.sizes[0] if a.sizes else 1024
        yield (f"smooth (facets) {n}², testing.smooth_facets", smooth_facets(n),
               Grid.uniform(n, n, CELL), "smooth")


def square_cell(grid):
    """One cell size for tools that take square cells: the middle row's geometric mean."""
    i = grid.rows // 2
    return float(math.sqrt(grid.dx[i] * grid.dy[i]))


def alternated(tools, repeat):
    """Run every tool in turn, ``repeat`` rounds; median seconds, first mask and stats of each."""
    times = {t: [] for t in tools}
    masks, stats = {}, {}
    for _ in range(repeat):
        for name, (fn, reps) in tools.items():
            if len(times[name]) >= reps:
                continue
            st = {}
            t0 = time.perf_counter()
            m = fn(st)
            times[name].append(time.perf_counter() - t0)
            if name not in masks:
                masks[name], stats[name] = m, st
    return {t: statistics.median(v) for t, v in times.items()}, masks, stats


def _load():
    try:
        return "/".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "n/a"


def fmt_tool(t, t_brute, mpix):
    return f"{mpix / t:.2f} ({t_brute / t:.2f}×)"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help=f"sizes 1024, azimuths {QUICK_AZIMUTHS}, elevations {ELEVATIONS}")
    ap.add_argument("--sizes", default=None, help="spectral sizes (default 1024,2048,4096)")
    ap.add_argument("--betas", default="2.4,3.2")
    ap.add_argument("--azimuths", default=None, help=f"default {AZIMUTHS}")
    ap.add_argument("--elevations", default=ELEVATIONS)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--tile-from", type=int, default=0,
                    help="build larger spectral sizes by tiling this size (same terrain)")
    ap.add_argument("--no-real", dest="real", action="store_false")
    ap.add_argument("--no-smooth", dest="smooth", action="store_false")
    ap.add_argument("--peers", default="doshade,whitebox")
    ap.add_argument("--whitebox-suns", default="203.7/8",
                    help="az/el pairs at which whitebox runs (comma-separated; 'all')")
    ap.add_argument("--out", default=None, help="also write the tables to this file")
    a = ap.parse_args(argv)
    a.sizes = [int(s) for s in (a.sizes or ("1024" if a.quick else "1024,2048,4096")).split(",")
               if s]
    a.betas = [float(b) for b in a.betas.split(",") if b]
    azs = [float(x) for x in (a.azimuths or (QUICK_AZIMUTHS if a.quick else AZIMUTHS)).split(",")]
    els = [float(x) for x in a.elevations.split(",")]
    peers = [p for p in a.peers.split(",") if p]
    wb_suns = None if a.whitebox_suns == "all" else {
        tuple(float(v) for v in s.split("/")) for s in a.whitebox_suns.split(",") if s}

    out = []

    def log(s=""):
        print(s, flush=True)
        out.append(s)

    nthreads = numba.get_num_threads()
    cmd = "python benchmarks/bench_real.py " + " ".join(shlex.quote(x) for x in
                                                        (sys.argv[1:] if argv is None else argv))
    log(f"`{cmd.strip()}` — {datetime.date.today().isoformat()}; {platform.machine()}, "
        f"{os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}, "
        f"numba {numba.__version__}, {nthreads} threads; compute stage only, median of "
        f"{a.repeat} alternated runs (whitebox: 1 run); flat Earth; load average at the start "
        f"{_load()}")
    notes = []
    tools_avail = {}
    for p in peers:
        fn = {"doshade": peer_doshade, "whitebox": peer_whitebox}[p]
        name, run = fn(np.zeros((8, 8), np.float32), CELL, 203.7, 8.0)
        tools_avail[p] = not isinstance(run, str)
        if isinstance(run, str):
            notes.append(f"{name}: {run}")
    warm_up(azs, els, lambda s: print(s, flush=True))

    peers = [p for p in ("doshade", "whitebox") if tools_avail.get(p)]
    head = (["terrain", "Mcells", "mean slope °", "az", "el", "plain march Mpix/s"]
            + [f"{n} Mpix/s (× plain)" for n in SHOWN] + peers
            + (["auto ÷ doshade"] if "doshade" in peers else [])
            + ["auto ran", "bounds undecided %", "smap Black %", "sweep unsure %",
               "sweep ≠ exact %"] + [f"{p} ≠ exact %" for p in peers])
    log("")
    log("| " + " | ".join(head) + " |")
    log("|" + "---|" * len(head))
    summary = {}     # terrain -> tool -> [x plain]
    t_start = time.perf_counter()
    for label, z, grid, kind in cases(a):
        zmax = float(np.nanmax(z))
        valid = ~np.isnan(z)
        nvalid = max(1, int(valid.sum()))
        mpix = z.size / 1e6
        i = grid.rows // 2
        slope = roughness(z, float(math.sqrt(grid.dx[i] * grid.dy[i])))["mean_slope"]
        cell = square_cell(grid)
        for el in els:
            for az in azs:
                rays = sun_rays(grid, az, el)
                tools = {n: ((lambda st, f=f: f(z, rays, zmax, st)), a.repeat)
                         for n, f in OURS.items()}
                if tools_avail.get("doshade"):
                    _, run = peer_doshade(z, cell, az, el)
                    tools["doshade"] = ((lambda st, r=run: r()), a.repeat)
                if tools_avail.get("whitebox") and (wb_suns is None or (az, el) in wb_suns):
                    _, run = peer_whitebox(z, cell, az, el)
                    tools["whitebox"] = ((lambda st, r=run: r()), 1)
                try:
                    times, masks, stats = alternated(tools, a.repeat)
                except Exception as e:   # a peer failing must not stop the run
                    notes.append(f"{label} az {az:g} el {el:g}: {type(e).__name__}: {e}")
                    continue
                ref = masks["plain"]

                def wrong(name):
                    if name not in masks:
                        return "–"
                    m = np.asarray(masks[name]).astype(np.uint8)
                    return f"{100.0 * np.count_nonzero((m != ref) & valid) / nvalid:.2f}"
                for n in EXACT:
                    d = int(np.count_nonzero(masks[n] != ref))
                    if d:
                        notes.append(f"ERROR: {n} differs from the plain march in {d} cells on "
                                     f"{label}, az {az:g}, el {el:g}")
                tb = times["plain"]
                row = [label, f"{mpix:.2f}", f"{slope:.0f}", f"{az:g}", f"{el:g}",
                       f"{mpix / tb:.2f}"]
                for n in list(SHOWN) + peers:
                    row.append(fmt_tool(times[n], tb, mpix) if n in times else "–")
                    if n in times:
                        summary.setdefault(label, {}).setdefault(n, []).append(tb / times[n])
                if "doshade" in peers:
                    r = times["doshade"] / times["auto"]
                    row.append(f"{r:.2f}")
                    summary.setdefault(label, {}).setdefault("auto÷doshade", []).append(r)
                row.append(", ".join(stats["auto"].get("auto", {}).get("chose", {})) or "–")
                uf = stats["bounds"].get("undecided_fraction")
                row.append(f"{100 * uf:.1f}" if uf is not None else "–")
                bf = stats["smap"].get("black_fraction")
                row.append(f"{100 * bf:.1f}" if bf is not None else "n/a (falls back to brute)")
                uf = stats["sweep"].get("unsure_fraction")
                row.append(f"{100 * uf:.1f}" if uf is not None else "–")
                row.append(wrong("sweep"))
                for p in peers:
                    row.append(wrong(p))
                log("| " + " | ".join(row) + " |")
                summary.setdefault(label, {}).setdefault("_plain_mpix", []).append(mpix / tb)
    log("")
    log("Summary: speed relative to the plain march (its time ÷ the tool's; > 1 is faster), and "
        "auto's relative to doshade (doshade's time ÷ auto's), min – median – max over the suns "
        "of this run; the plain march's Mpix/s likewise")
    log("")
    names = list(SHOWN) + peers + (["auto÷doshade"] if "doshade" in peers else [])
    log("| terrain | plain Mpix/s | " + " | ".join(
        (n if n == "auto÷doshade" else f"{n} × plain") for n in names) + " |")
    log("|---|---|" + "---|" * len(names))
    for label, d in summary.items():
        cells = []
        for n in ["_plain_mpix"] + names:
            v = d.get(n)
            if not v:
                cells.append("–")
            elif len(v) == 1:
                cells.append(f"{v[0]:.2f}")
            else:
                cells.append(f"{min(v):.2f} – {statistics.median(v):.2f} – {max(v):.2f}")
        log(f"| {label} | " + " | ".join(cells) + " |")
    log("")
    log(f"(timed part: {time.perf_counter() - t_start:.0f} s; load average at the end {_load()}: "
        f"another process on the cores slows the tools unequally, sweep and doshade most)")
    for n in dict.fromkeys(notes):
        log(f"Note: {n}")
    if a.out:
        with open(a.out, "w") as fh:
            fh.write("\n".join(out) + "\n")
    return 1 if any(n.startswith("ERROR") for n in notes) else 0


if __name__ == "__main__":
    sys.exit(main())
