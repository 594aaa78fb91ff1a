"""What a Makefile of tiles costs (``make bench-batch``): the repository's real DEMs cut into
256² and 512² tiles, one ``make`` run per way of shading them, in one run so that the ratios
compare:

* ``gdaldem``: ``gdaldem hillshade`` per tile (the peer: a C program, 0.07 s a call);
* ``standalone``: ``hillshade-rt shadow`` per tile, a fresh process each (no server);
* ``server``: the same rule with the warm server (``HILLSHADE_RT_SERVER=auto``, started before
  the clock);
* ``context``: standalone with ``--context all.vrt`` (exact at the tiles' edges);
* ``context+server``: both;
* ``one call``: one ``hillshade-rt shadow tiles/*.tif --output-pattern 'out/{tile}.tif'`` over
  all tiles (a mosaic: exact, one process).

Each mask is compared with the whole DEM's mask: cells that differ (the shadows a tile loses
at its edges without its neighbours). Then the start-up phases of one 256² ``shadow`` process
(interpreter, imports, numba's start, GDAL open and read, prepare, compute, write, report,
exit), and, unless ``--no-cache``, the first and second run of each command after the warm-up
on an empty kernel cache and on one another checkout filled (the first within 1.3x the second:
nothing compiled at a first run).

    .venv/bin/python benchmarks/bench_batch.py [--sizes 256,512] [--dems NAME,...] [--jobs 1]

Run it with nothing else running (2 shared cores). Figures go to docs/benchmarks.md.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

from hillshade_rt.testing import real_dems

HERE = os.path.dirname(os.path.abspath(__file__))
BIN = os.path.dirname(sys.executable)
HRT = os.path.join(BIN, "hillshade-rt")
SUN = ["--azimuth", "203.7", "--elevation", "10"]
DEMS = ("bigtujunga_srtm30m_utm11n_1197x643.tif", "everest_srtm3_N27E086_voids_1201.tif")


def cut_tiles(dem: str, size: int, folder: str) -> list[str]:
    """``dem`` cut into ``size``² GeoTIFF tiles (the last row and column of tiles smaller)."""
    import rasterio
    from rasterio.windows import Window
    os.makedirs(folder, exist_ok=True)
    paths = []
    with rasterio.open(dem) as src:
        prof = src.profile
        for r in range(0, src.height, size):
            for c in range(0, src.width, size):
                w = Window(c, r, min(size, src.width - c), min(size, src.height - r))
                p = dict(prof, width=int(w.width), height=int(w.height),
                         transform=src.window_transform(w), tiled=False)
                p.pop("blockxsize", None)
                p.pop("blockysize", None)
                path = os.path.join(folder, f"t_{r:05d}_{c:05d}.tif")
                with rasterio.open(path, "w", **p) as dst:
                    dst.write(src.read(1, window=w), 1)
                paths.append(path)
    return paths


MAKEFILE = """\
TILES := $(wildcard tiles/*.tif)
OUT := $(patsubst tiles/%.tif,{out}/%.tif,$(TILES))
all: $(OUT)
{out}/%.tif: tiles/%.tif
\t@mkdir -p {out}
\t@{rule}
"""

RULES = {
    "gdaldem": "gdaldem hillshade -q -az 203.7 -alt 10 $< $@",
    "standalone": f"{HRT} shadow $< $@ {' '.join(SUN)} -q --overwrite",
    "server": f"{HRT} shadow $< $@ {' '.join(SUN)} -q --overwrite",
    "context": f"{HRT} shadow $< $@ {' '.join(SUN)} -q --overwrite --context all.vrt",
    "context+server": f"{HRT} shadow $< $@ {' '.join(SUN)} -q --overwrite --context all.vrt",
}
SERVED = {"server", "context+server"}


def env_for(way: str, home: str) -> dict:
    env = dict(os.environ, HILLSHADE_RT_SERVER="auto" if way in SERVED else "off")
    env["XDG_RUNTIME_DIR"] = home          # the server's socket folder: this run's own
    return env


def make_run(folder: str, way: str, jobs: int, home: str) -> float:
    out = "out_" + way.replace("+", "_")
    shutil.rmtree(os.path.join(folder, out), ignore_errors=True)
    with open(os.path.join(folder, f"Makefile.{out}"), "w") as fh:
        fh.write(MAKEFILE.format(out=out, rule=RULES[way]))
    t0 = time.perf_counter()
    subprocess.run(["make", "-s", f"-j{jobs}", "-f", f"Makefile.{out}"], cwd=folder, check=True,
                   env=env_for(way, home))
    return time.perf_counter() - t0


def one_call(folder: str, tiles: list[str]) -> float:
    out = os.path.join(folder, "out_one_call")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    t0 = time.perf_counter()
    subprocess.run([HRT, "shadow", *tiles, "--output-pattern", os.path.join(out, "{tile}.tif"),
                    *SUN, "-q"], check=True, env=dict(os.environ, HILLSHADE_RT_SERVER="off"))
    return time.perf_counter() - t0


def wrong_cells(folder: str, way: str, whole: str) -> int | None:
    """Cells of the tiles' masks that differ from the whole DEM's mask (nodata aside)."""
    import rasterio
    from rasterio.windows import from_bounds
    out = os.path.join(folder, "out_" + way.replace("+", "_").replace(" ", "_"))
    if way == "gdaldem" or not os.path.isdir(out):
        return None
    n = 0
    with rasterio.open(whole) as w:
        ref = w.read(1)
        for name in os.listdir(out):
            with rasterio.open(os.path.join(out, name)) as t:
                win = from_bounds(*t.bounds, transform=w.transform).round_offsets().round_lengths()
                part = ref[win.row_off:win.row_off + win.height, win.col_off:win.col_off + win.width]
                a = t.read(1)
                ok = (a != 255) & (part != 255)
                n += int((a[ok] != part[ok]).sum())
    return n


def server(cmd: str, home: str) -> None:
    subprocess.run([HRT, "serve", cmd], env=env_for("server", home), check=False,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=120)


def makefiles(sizes, dems, jobs) -> list[dict]:
    rows = []
    have_gdaldem = shutil.which("gdaldem") is not None
    for path, label in real_dems(dems):
        for size in sizes:
            folder = tempfile.mkdtemp(prefix=f"hrt-batch-{size}-")
            home = tempfile.mkdtemp(prefix="hrt-run-")
            os.chmod(home, 0o700)
            tiles = cut_tiles(path, size, os.path.join(folder, "tiles"))
            subprocess.run(["gdalbuildvrt", "-q", os.path.join(folder, "all.vrt"),
                            *sorted(tiles)], check=True)
            whole = os.path.join(folder, "whole.tif")
            subprocess.run([HRT, "shadow", path, whole, *SUN, "-q"], check=True)
            row = {"dem": label, "size": size, "tiles": len(tiles), "seconds": {},
                   "wrong": {}}
            server("start", home)
            ways = [w for w in RULES if have_gdaldem or w != "gdaldem"]
            for way in ways:         # once untimed: the page cache, the server's kernels
                make_run(folder, way, jobs, home)
            for way in ways:
                row["seconds"][way] = make_run(folder, way, jobs, home)
                row["wrong"][way] = wrong_cells(folder, way, whole)
            server("stop", home)
            row["seconds"]["one call"] = one_call(folder, tiles)
            row["wrong"]["one call"] = wrong_cells(folder, "one call", whole)
            rows.append(row)
            shutil.rmtree(folder, ignore_errors=True)
            shutil.rmtree(home, ignore_errors=True)
            g = row["seconds"].get("gdaldem")
            print(f"\n{label}, {size}² tiles ({len(tiles)}), make -j{jobs}:")
            for way, s in row["seconds"].items():
                ratio = f"{s / g:5.1f}x gdaldem" if g else ""
                wrong = row["wrong"].get(way)
                print(f"  {way:15s} {s:7.2f} s  {s / len(tiles) * 1000:6.0f} ms/tile  {ratio}"
                      f"  {'' if wrong is None else f'{wrong} cells differ from the whole mask'}",
                      flush=True)
    return rows


# ------------------------------------------------------------------------------------------
# the phases of one process

PHASES = r"""
import sys, time, json
t = {"start": time.perf_counter()}
import numpy; t["numpy"] = time.perf_counter()
import rasterio; t["rasterio"] = time.perf_counter()
import pyproj; t["pyproj"] = time.perf_counter()
import numba; t["numba"] = time.perf_counter()
import click; t["click"] = time.perf_counter()
from hillshade_rt.cli import cli; t["hillshade_rt.cli"] = time.perf_counter()
from hillshade_rt import _preload
_preload.start_numba(); t["numba start"] = time.perf_counter()
cli.main(args=sys.argv[1:], prog_name="hillshade-rt", standalone_mode=False)
t["run"] = time.perf_counter()
print(json.dumps(t))
"""


def phases(tile: str, repeat: int = 5) -> dict:
    out = os.path.join(tempfile.mkdtemp(), "m.tif")
    report = out + ".json"
    args = ["shadow", tile, out, *SUN, "-q", "--overwrite", "--report", report]
    env = dict(os.environ, HILLSHADE_RT_SERVER="off")
    subprocess.run([HRT, *args], check=True, env=env)
    walls, interp, rows = [], [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        interp.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        subprocess.run([HRT, *args], check=True, env=env)
        walls.append(time.perf_counter() - t0)
        p = subprocess.run([sys.executable, "-c", PHASES, *args], check=True, env=env,
                           capture_output=True, text=True)
        t = json.loads(p.stdout)
        with open(report) as fh:
            sec = json.load(fh)["seconds"]
        keys = list(t)
        row = {k: t[k] - t[keys[i - 1]] for i, k in enumerate(keys) if i}
        row.pop("run")
        row.update({f"run: {k}": v for k, v in sec.items() if k != "total"})
        row["run: other (options, open, report)"] = (t["run"] - t["numba start"]) - sum(
            v for k, v in sec.items() if k != "total")
        rows.append(row)
    med = {k: statistics.median(r[k] for r in rows) for k in rows[0]}
    med = {"interpreter (python -c pass)": statistics.median(interp), **med}
    print(f"\nOne 256² shadow process, median of {repeat}: {statistics.median(walls):.3f} s "
          f"wall (min {min(walls):.3f})")
    for k, v in med.items():
        print(f"  {k:40s} {v * 1000:7.1f} ms")
    return {"wall": statistics.median(walls), "phases": med}


# ------------------------------------------------------------------------------------------
# the first run after the warm-up

COMMANDS = {
    "shadow": ["shadow", "{dem}", "{out}/a.tif", *SUN],
    "shadow --algorithm smap": ["shadow", "{dem}", "{out}/a.tif", *SUN, "--algorithm", "smap"],
    "shadow --no-earth-curvature": ["shadow", "{dem}", "{out}/a.tif", *SUN,
                                    "--no-earth-curvature"],
    "hillshade": ["hillshade", "{dem}", "{out}/b.tif", *SUN],
    "sun-hours": ["sun-hours", "{dem}", "{out}/c.tif", "--date", "2026-06-21", "--step", "1h"],
    "horizon": ["horizon", "{dem}", "{out}/d.tif", "--azimuth", "203.7"],
    "skyview": ["skyview", "{dem}", "{out}/e.tif", "--directions", "16"],
    "irradiance": ["irradiance", "{dem}", "{out}/f.tif", "--date", "2026-06-21", "--step", "2h",
                   "--skyview-directions", "16"],
}


def first_and_second(env: dict, dem: str) -> dict:
    out = tempfile.mkdtemp()
    res = {}
    for name, args in COMMANDS.items():
        argv = [HRT, *[a.format(dem=dem, out=out) for a in args], "-q", "--overwrite"]
        times = []
        for _ in range(2):
            t0 = time.perf_counter()
            subprocess.run(argv, check=True, env=env)
            times.append(time.perf_counter() - t0)
        res[name] = times
    return res


def cache_check(dem: str) -> dict:
    results = {}
    root = tempfile.mkdtemp(prefix="hrt-cache-")
    env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(root, "numba"),
               HILLSHADE_RT_SERVER="off")
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "hillshade_rt.warm"], check=True, env=env)
    results["warm, empty cache"] = time.perf_counter() - t0
    results["runs, empty cache"] = first_and_second(env, dem)
    # another checkout of the same version, its cache folder filled by the one above
    import hillshade_rt
    other = os.path.join(root, "other")
    shutil.copytree(os.path.dirname(hillshade_rt.__file__), os.path.join(other, "hillshade_rt"),
                    ignore=shutil.ignore_patterns("__pycache__"))
    env2 = dict(env, PYTHONPATH=other)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "hillshade_rt.warm"], check=True, env=env2, cwd=other)
    results["warm, another checkout's cache"] = time.perf_counter() - t0
    results["runs, another checkout's cache"] = first_and_second(env2, dem)
    shutil.rmtree(root, ignore_errors=True)
    for key in ("empty cache", "another checkout's cache"):
        print(f"\nAfter the warm-up on {key} ({results['warm, ' + key]:.0f} s): first and "
              f"second run on the example DEM")
        for name, (a, b) in results["runs, " + key].items():
            print(f"  {name:30s} first {a:6.2f} s  second {b:6.2f} s  ratio {a / b:4.2f}")
    return results


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="256,512")
    p.add_argument("--dems", default=",".join(DEMS))
    p.add_argument("--jobs", type=int, default=1, help="make -jN (default 1)")
    p.add_argument("--no-cache", action="store_true", help="skip the warm-up/first-run check")
    p.add_argument("--json", help="also write the figures here")
    a = p.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}; {os.cpu_count()} CPUs")
    sizes = [int(s) for s in a.sizes.split(",")]
    res = {"makefiles": makefiles(sizes, a.dems.split(","), a.jobs)}
    with tempfile.TemporaryDirectory() as tmp:
        tile = cut_tiles(real_dems([DEMS[0]])[0][0], 256, tmp)[0]
        res["phases"] = phases(tile)
    if not a.no_cache:
        res["cache"] = cache_check(real_dems([DEMS[0]])[0][0])
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1, default=float)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
