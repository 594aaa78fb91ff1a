"""Compile, once per install, every kernel the commands use: ``python -m hillshade_rt.warm``
(``make install`` runs it), so that no command compiles at a user's first run.

How: the commands themselves are run, in this process's children, on small DEMs written to a
temporary folder (a projected int16 DEM with nodata, a geographic float32 one with voids, uint16
and float64 copies, a lunar polar one), with their defaults and the common options (every
algorithm, curvature on and off, soft shadows, classes, a point light, subsolar suns, windows,
time series, sun hours, horizons, sky view, irradiance, query, profile, illumination, animate);
what they compile lands in numba's cache (``~/.cache/hillshade-rt/numba/<digest>``, in the
subfolder numba gives this install's source folder). The scenarios are shared among
``os.cpu_count()`` processes (compiling is single-threaded), the ones that share kernels in one
process so that no kernel is compiled twice.

When every kernel of this install is already cached (:func:`all_cached`: numba's own index of
each kernel, read from the folder this install loads, with the stamp of this install's
source), nothing runs. ``--check`` says which kernels are missing (exit 1 when any is);
``--force`` runs the scenarios whatever the cache holds.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

#: The command lines, in groups: a group's scenarios run in order in one process (they share
#: kernels), the groups in parallel processes. DEM names are those of ``_write_dems``.
GROUPS: dict[str, list[list[str]]] = {
    # the default (auto: bounds and brute over the pyramid), what a first run needs
    "default": [
        ["shadow", "{utm}", "{out}/a.tif", "--azimuth", "203.7", "--elevation", "10"],
        ["shadow", "{geo}", "{out}/b.tif", "--azimuth", "163", "--elevation", "12"],
        ["shadow", "{u16}", "{out}/c.tif", "--azimuth", "290", "--elevation", "8"],
        ["shadow", "{f64}", "{out}/d.tif", "--azimuth", "290", "--elevation", "8"],
        ["shadow", "{utm}", "{out}/e.tif", "--azimuth", "203.7", "--elevation", "10",
         "--earth-curvature"],
        ["shadow", "{utm}", "{out}/e.tif", "--azimuth", "203.7", "--elevation", "10",
         "--no-earth-curvature"],
        ["shadow", "{geo}", "{out}/e.tif", "--azimuth", "203.7", "--elevation", "10",
         "--no-earth-curvature"],
        ["shadow", "{utm}", "{out}/f.tif", "--azimuth", "203.7", "--elevation", "10",
         "--classes"],
        ["shadow", "{utm}", "{out}/f.tif", "--azimuth", "203.7", "--elevation", "10",
         "--self-shadow"],
        ["shadow", "{utm}", "{out}/g.tif", "--azimuth", "203.7", "--elevation", "10",
         "--soft"],
        ["shadow", "{geo}", "{out}/g.tif", "--azimuth", "203.7", "--elevation", "10",
         "--soft"],
        ["shadow", "{utm}", "{out}/h.tif", "--azimuth", "203.7", "--elevation", "10",
         "--window-size", "64", "--preview", "{out}/h.png"],
        ["shadow", "{geo}", "{out}/h.tif", "--azimuth", "203.7", "--elevation", "10",
         "--window-size", "64"],
        ["shadow", "{big}", "{out}/d.tif", "--azimuth", "203.7", "--elevation", "10"],
        ["shadow", "{geo}", "{out}/i.tif", "--time", "2026-06-21T16:00Z",
         "--sun-tolerance", "0.001"],
        ["shadow", "{geo}", "{out}/i.tif", "--time", "2026-06-21T16:00Z",
         "--sun-tolerance", "0.001", "--no-earth-curvature"],
        ["shadow", "{utm}", "{out}/i.tif", "--start", "2026-06-21T08:00", "--end",
         "2026-06-21T12:00", "--step", "2h", "--tz", "America/Los_Angeles"],
        ["shadow", "{utm}", "{out}/j.tif", "--azimuth", "203.7", "--elevation", "10",
         "--height-above-ground", "2"],
        ["shadow", "{geo}", "{out}/j.tif", "--azimuth", "203.7", "--elevation", "10",
         "--height-above-ground", "2", "--soft"],
        ["hillshade", "{utm}", "{out}/k.tif", "--azimuth", "203.7", "--elevation", "10"],
        ["hillshade", "{geo}", "{out}/k.tif", "--azimuth", "203.7", "--elevation", "10",
         "--soft"],
        ["hillshade", "{utm}", "{out}/k.tif", "--azimuth", "203.7", "--elevation", "10",
         "--window-size", "64"],
        # a tile of a larger raster (--context): the windowed runs cut to the tile
        ["shadow", "{tile}", "{out}/w.tif", "--azimuth", "203.7", "--elevation", "10",
         "--context", "{utm}"],
        ["shadow", "{tile}", "{out}/w.tif", "--azimuth", "203.7", "--elevation", "10",
         "--context", "{utm}", "--soft"],
        ["hillshade", "{tile}", "{out}/w.tif", "--azimuth", "203.7", "--elevation", "10",
         "--context", "{utm}"],
        ["sun-hours", "{tile}", "{out}/w.tif", "--date", "2026-06-21", "--step", "3h",
         "--context", "{utm}"],
        ["horizon", "{tile}", "{out}/w.tif", "--directions", "8", "--context", "{utm}"],
        ["skyview", "{tile}", "{out}/w.tif", "--directions", "8", "--context", "{utm}"],
        ["irradiance", "{tile}", "{out}/w.tif", "--date", "2026-06-21", "--step", "3h",
         "--skyview-directions", "8", "--context", "{utm}"],
        ["animate", "{utm}", "{out}/l.gif", "--start", "2026-06-21T08:00", "--end",
         "2026-06-21T10:00", "--step", "1h", "--tz", "America/Los_Angeles", "--size", "32"],
        ["query", "{utm}", "--at-xy", "{utm_xy}", "--azimuth", "203.7", "--elevation", "10",
         "-o", "{out}/m.csv"],
        ["query", "{geo}", "--at", "{geo_lonlat}", "--time", "2026-06-21T16:00Z",
         "--irradiance", "-o", "{out}/m.csv"],
    ],
    # the other algorithms of the registry
    "algorithms": [
        [*cmd, "--algorithm", algo, *extra]
        for algo, extra in (("bounds", []), ("brute", []), ("brute", ["--no-pyramid"]),
                            ("smap", []), ("horizon", []),
                            ("smap", ["--nextv", "binary"]), ("smap", ["--nextv", "quad"]),
                            ("smap", ["--better-nextv"]), ("smap", ["--window-size", "64"]),
                            ("horizon", ["--horizon-method", "hull"]), ("sweep", []))
        for cmd in (["shadow", "{utm}", "{out}/n.tif", "--azimuth", "203.7", "--elevation", "10"],
                    ["shadow", "{geo}", "{out}/n.tif", "--azimuth", "163", "--elevation", "12"],
                    ["shadow", "{utm}", "{out}/n.tif", "--azimuth", "290", "--elevation", "8",
                     "--no-earth-curvature"])
    ] + [
        ["sun-hours", "{utm}", "{out}/o.tif", "--date", "2026-06-21", "--step", "3h",
         "--tz", "America/Los_Angeles"],
        ["sun-hours", "{geo}", "{out}/o.tif", "--date", "2026-06-21", "--step", "3h"],
        ["sun-hours", "{geo}", "{out}/o.tif", "--date", "2026-06-21", "--step", "3h",
         "--sun-tolerance", "0.001"],
        ["sun-hours", "{utm}", "{out}/o.tif", "--date", "2026-06-21", "--step", "3h",
         "--soft"],
        ["sun-hours", "{utm}", "{out}/o.tif", "--date", "2026-06-21", "--step", "3h",
         "--height-above-ground", "2"],
    ],
    # horizons, sky view, irradiance
    "horizons": [
        ["horizon", "{utm}", "{out}/p.tif", "--azimuth", "203.7"],
        ["horizon", "{geo}", "{out}/p.tif", "--azimuth", "163"],
        ["horizon", "{utm}", "{out}/p.tif", "--directions", "8", "--distance", "{out}/p2.tif"],
        ["horizon", "{geo}", "{out}/p.tif", "--directions", "8", "--max-distance", "300"],
        ["horizon", "{utm}", "{out}/p.tif", "--azimuth", "203.7", "--method", "hull"],
        ["horizon", "{utm}", "{out}/p.tif", "--directions", "8", "--window-size", "64"],
        ["horizon", "{utm}", "{out}/p.tif", "--directions", "8", "--window-size", "64",
         "--max-distance", "300"],
        ["horizon", "{utm}", "{out}/p.tif", "--directions", "8", "--height-above-ground", "2",
         "--no-earth-curvature"],
        ["skyview", "{utm}", "{out}/q.tif", "--directions", "8"],
        ["skyview", "{geo}", "{out}/q.tif", "--directions", "8", "--definition", "dozier"],
        ["skyview", "{utm}", "{out}/q.tif", "--directions", "8", "--openness", "positive",
         "--max-distance", "300"],
        ["skyview", "{utm}", "{out}/q.tif", "--directions", "8", "--openness", "negative"],
        ["skyview", "{utm}", "{out}/q.tif", "--directions", "8", "--window-size", "64"],
        ["skyview", "{utm}", "{out}/q.tif", "--directions", "8", "--height-above-ground", "2"],
        ["irradiance", "{utm}", "{out}/r.tif", "--date", "2026-06-21", "--step", "3h",
         "--tz", "America/Los_Angeles", "--skyview-directions", "8"],
        ["irradiance", "{geo}", "{out}/r.tif", "--date", "2026-06-21", "--step", "3h",
         "--skyview-directions", "8", "--perez", "--mean"],
        ["irradiance", "{utm}", "{out}/r.tif", "--date", "2026-06-21", "--step", "3h",
         "--skyview-directions", "8", "--soft"],
        ["irradiance", "{utm}", "{out}/r.tif", "--date", "2026-06-21", "--step", "3h",
         "--skyview-directions", "8", "--perez", "--window-size", "64"],
        ["irradiance", "{utm}", "{out}/r.tif", "--time", "2026-06-21T19:00Z",
         "--skyview-directions", "8"],
        ["irradiance", "{utm}", "{out}/r.tif", "--date", "2026-06-21", "--step", "3h",
         "--skyview-directions", "8", "--perez", "--linke-turbidity", "{linke}",
         "--beam-index", "{index}"],
        ["profile", "{utm}", "--at-xy", "{utm_xy}", "-o", "{out}/s.csv"],
        ["profile", "{geo}", "--at", "{geo_lonlat}", "-o", "{out}/s.csv"],
    ],
    # lights that are not a distant sun: a point light, subsolar points on a body
    "lights": [
        ["shadow", "{utm}", "{out}/t.tif", "--light-position", "{utm_light}"],
        ["shadow", "{geo}", "{out}/t.tif", "--light-lonlat", "{geo_light}"],
        ["hillshade", "{utm}", "{out}/t.tif", "--light-position", "{utm_light}"],
        ["hillshade", "{utm}", "{out}/t.png", "-f", "PNG", "--light-position", "{utm_light}",
         "--falloff", "inverse-square", "--bits", "16"],
        ["query", "{utm}", "--at-xy", "{utm_xy}", "--light-position", "{utm_light}",
         "-o", "{out}/t.csv"],
        ["shadow", "{moon}", "{out}/u.tif", "--subsolar", "-1.5,40", "--body", "moon"],
        ["shadow", "{moon}", "{out}/u.tif", "--subsolar", "-1.5,40", "--body", "moon", "--soft"],
        ["shadow", "{moon}", "{out}/u.tif", "--subsolar-file", "{subsolar}", "--body", "moon"],
        ["shadow", "{geo}", "{out}/u.tif", "--subsolar", "20,-100"],
        ["illumination", "{moon}", "{out}/v.tif", "--subsolar-file", "{subsolar}",
         "--body", "moon"],
        ["illumination", "{moon}", "{out}/v.tif", "--subsolar-file", "{subsolar}",
         "--body", "moon", "--soft"],
        ["illumination", "{moon}", "{out}/v.tif", "--subsolar-file", "{subsolar}",
         "--body", "moon", "--window-size", "64"],
        ["illumination", "{moon}", "{out}/v.tif", "--subsolar-file", "{subsolar}",
         "--body", "moon", "--window-size", "64", "--no-earth-curvature"],
    ],
}

def _view(values: dict) -> None:
    """The viewer's requests (``hillshade-rt view``): pictures of every kind, a point, an edit
    and its undo, a download."""
    from .io import read_dem
    from .run.viewer import Viewer
    viewer = Viewer(read_dem(values["utm"]))
    try:
        for q in ({"az": "203.7", "el": "10"}, {"az": "163", "el": "12", "soft": "1"},
                  {"time": "2026-06-21T16:00Z"}, {"sunhours": "2026-06-21"},
                  {"az": "290", "el": "8", "algorithm": "brute"}):
            viewer.render(dict(q, w="64", h="64"))
        viewer.point({"x": "40.5", "y": "30.5", "az": "203.7", "el": "10"})
        for shape in ("disk", "flat"):
            viewer.edit({"x": 40.5, "y": 30.5, "radius": 90, "delta": 50, "shape": shape})
            viewer.render({"az": "203.7", "el": "10", "w": "64", "h": "64"})
        viewer.undo()
        viewer.reset()
        viewer.download({"az": "203.7", "el": "10"})
    finally:
        viewer.close()


def _points(values: dict) -> None:
    """``arrays.is_shadowed``: points tested against SMap's tables."""
    import numpy as np

    from .engine.arrays import is_shadowed
    from .io import read_dem
    dem = read_dem(values["utm"])
    is_shadowed(dem, np.array([[10.5, 20.25, 1800.0]]), 203.7, 10.0)


def _dynamic(values: dict) -> None:
    """Dynamic terrain: ``Shader.update`` and ``render(previous=...)`` re-shading an edit's
    halo, a small one (one thread) and a large one (the parallel march)."""
    import numpy as np

    from .model.geometry import Grid
    from .engine.shader import Shader, render
    from .model.sun import SunOver
    i = np.arange(300)
    z = (300.0 * np.add.outer(np.sin(0.37 * i), np.cos(0.53 * i)) + 1500.0).astype(np.float32)
    sh = Shader(z, Grid.uniform(300, 300, 30.0), "auto", {}, "cpu", True)
    for el, top in ((30.0, 20.0), (2.0, 2000.0)):
        sun = SunOver(None, 203.7, el)
        mask, version = render(sh, sun), sh.version
        sh.update((280, 20), z[280:290, 20:30] + top)     # the anti-sun side: north-east
        render(sh, sun, previous=(mask, version))


GROUPS["lights"] += [_view, _points, _dynamic]

# the DEMs' size: big enough that no kernel is skipped (rough terrain, every method of auto)
_N = 96


def _write_dems(folder: str) -> dict:
    """The small DEMs and files the scenarios use, and the values of their placeholders."""
    import numpy as np
    import rasterio
    from rasterio.transform import from_origin

    i = np.arange(_N)
    z = (300.0 * np.add.outer(np.sin(0.37 * i), np.cos(0.53 * i))
         + 40.0 * np.add.outer(np.cos(1.7 * i), np.sin(2.3 * i)) + 1500.0)
    names = {}

    def write(name, array, transform, crs, nodata):
        path = os.path.join(folder, name)
        with rasterio.open(path, "w", driver="GTiff", width=array.shape[1],
                           height=array.shape[0], count=1,
                           dtype=array.dtype, crs=crs, transform=transform,
                           nodata=nodata) as dst:
            dst.write(array, 1)
        return path

    utm_t = from_origin(380000.0, 3800000.0, 30.0, 30.0)
    zi = z.astype(np.int16)
    zi[3, 4] = -32768
    names["utm"] = write("utm.tif", zi, utm_t, "EPSG:32611", -32768)
    names["u16"] = write("u16.tif", z.astype(np.uint16), utm_t, "EPSG:32611", 0)
    names["tile"] = write("tile.tif", zi[:64, :64], utm_t, "EPSG:32611", -32768)
    zd = z.astype(np.float64)
    zd[5, 6] = np.nan
    names["f64"] = write("f64.tif", zd, utm_t, "EPSG:32611", None)
    zf = z.astype(np.float32)
    zf[7, 8] = np.nan
    deg = 1.0 / 3600.0
    names["geo"] = write("geo.tif", zf, from_origin(-118.3, 34.4, deg, deg), "EPSG:4326", None)
    moon = "+proj=stere +lat_0=-90 +lon_0=0 +k=1 +x_0=0 +y_0=0 +R=1737400 +units=m +no_defs"
    big = np.tile(zf, (3, 3))      # 288²: float32 heights this large are cleaned in one pass
    names["big"] = write("big.tif", big, from_origin(-118.3, 34.4, deg, deg), "EPSG:4326", None)
    names["moon"] = write("moon.tif", (z - 1500.0).astype(np.float32),
                          from_origin(-720.0, 720.0, 30.0, 30.0), moon, None)
    # a Linke turbidity raster and a clear-sky index raster on the projected DEM's grid
    names["linke"] = write("linke.tif", 2.0 + np.add.outer(i, i) / (2.0 * _N), utm_t,
                           "EPSG:32611", None)
    names["index"] = write("index.tif", 0.4 + np.add.outer(i, i) / (4.0 * _N), utm_t,
                           "EPSG:32611", None)
    names["subsolar"] = os.path.join(folder, "subsolar.csv")
    with open(names["subsolar"], "w") as fh:
        fh.write("time,lat,lon\n")
        for k in range(3):
            fh.write(f"2027-01-0{k + 1}T00:00:00+00:00,{-1.5 + 0.2 * k},{40.0 - 12.2 * k}\n")
        fh.write("2027-01-04T00:00:00+00:00,1.5,0.0\n")      # dark everywhere
    c = _N // 2
    names["utm_xy"] = f"{380000.0 + 30.0 * c + 15.0},{3800000.0 - 30.0 * c - 15.0}"
    names["utm_light"] = f"{380000.0 + 30.0 * 10},{3800000.0 - 30.0 * 12},2600"
    names["geo_lonlat"] = f"{-118.3 + c * deg},{34.4 - c * deg}"
    names["geo_light"] = f"{-118.3 + 10 * deg},{34.4 - 12 * deg},2600"
    return names


# ------------------------------------------------------------------------------------------
# which kernels this install has, and which of them are cached

def kernels() -> list:
    """Every numba kernel of the package (the dispatchers of ``_jitcache.njit``, all in
    ``algorithms/``), its modules imported."""
    import importlib
    import pkgutil

    from . import algorithms
    from .algorithms import _jitcache
    for info in pkgutil.iter_modules(algorithms.__path__):
        if not info.name.startswith("_"):
            importlib.import_module(f"{algorithms.__name__}.{info.name}")
    return [k for k in _jitcache.KERNELS if _jitcache.compiled_alone(k)]


def missing() -> list[str]:
    """The kernels with no entry in numba's cache that this install loads: numba's index file
    of each, in the folder numba's locator gives this install's sources, written for these very
    sources (its stamp) and holding at least one compiled signature for this machine."""
    from .algorithms._jitcache import loadable
    return [f"{k.py_func.__module__}.{k.py_func.__qualname__}" for k in kernels()
            if not loadable(k)]


def all_cached() -> bool:
    """Whether every kernel has an entry this install loads (``missing()`` is empty)."""
    try:
        return not missing()
    except Exception:        # noqa: BLE001 -- a cache we cannot read is one to fill
        return False


# ------------------------------------------------------------------------------------------

class CompileCounter:
    """numba's compilations while it is entered (numba's ``numba:compile`` events, which a
    kernel loaded from the cache does not raise): ``names`` the kernels compiled."""

    def __init__(self):
        self.names: list[str] = []

    def __enter__(self):
        from numba.core import event

        class Listener(event.Listener):
            def on_start(_, ev):
                self.names.append(str(ev.data["dispatcher"].py_func.__qualname__))

            def on_end(_, ev):
                pass
        self._cm = event.install_listener("numba:compile", Listener())
        self._cm.__enter__()
        return self

    def __exit__(self, *exc):
        return self._cm.__exit__(*exc)


def run_group(name: str, compiled: list | None = None) -> int:
    """Run one group's scenarios in this process; 0 when all ran. ``compiled``: a list to which
    the names of the kernels numba compiled (not loaded) are added."""
    from .cli import cli
    failed = 0
    counter = CompileCounter().__enter__()
    with tempfile.TemporaryDirectory(prefix="hillshade-rt-warm-") as tmp:
        values = _write_dems(tmp)
        out = os.path.join(tmp, "out")
        os.mkdir(out)
        values["out"] = out
        for args in GROUPS[name]:
            if callable(args):
                try:
                    args(values)
                except Exception as exc:      # noqa: BLE001 -- said, and the group goes on
                    print(f"hillshade-rt: warm-up of {args.__name__} failed: {exc}",
                          file=sys.stderr)
                    failed += 1
                continue
            argv = [a.format(**values) for a in args] + ["--overwrite", "-q"]
            try:
                code = cli.main(args=argv, prog_name="hillshade-rt", standalone_mode=False)
            except SystemExit as exc:
                code = exc.code
            except Exception as exc:          # noqa: BLE001 -- said, and the group goes on
                code = getattr(exc, "exit_code", 1)     # click's Exit and usage errors
                if code:
                    print(f"hillshade-rt: warm-up scenario {' '.join(args)} failed: {exc}",
                          file=sys.stderr)
            if code:
                failed += 1
    counter.__exit__(None, None, None)
    if compiled is not None:
        compiled += counter.names
    return 1 if failed else 0


def run_all(jobs: int | None = None, times: dict | None = None) -> int:
    """Every group, ``jobs`` processes at a time (default: the CPU count); 0 when all ran.
    ``times``: filled with each group's seconds."""
    jobs = max(1, jobs or os.cpu_count() or 1)
    # the longest groups first: the default's kernels are the biggest
    pending = list(GROUPS)
    running: list[tuple[str, subprocess.Popen, float]] = []
    failed = []
    env = dict(os.environ, NUMBA_NUM_THREADS="1")     # compiling is single-threaded anyway
    while pending or running:
        while pending and len(running) < jobs:
            name = pending.pop(0)
            running.append((name, subprocess.Popen(
                [sys.executable, "-m", "hillshade_rt.warm", "--group", name], env=env),
                time.perf_counter()))
        time.sleep(0.1)
        for item in list(running):
            if item[1].poll() is not None:
                running.remove(item)
                if times is not None:
                    times[item[0]] = time.perf_counter() - item[2]
                if item[1].returncode:
                    failed.append(item[0])
    if failed:
        print(f"hillshade-rt: the warm-up of {', '.join(failed)} failed", file=sys.stderr)
        return 1
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m hillshade_rt.warm", description=__doc__.split(
        "\n\n")[0])
    p.add_argument("--check", action="store_true",
                   help="list the kernels not cached for this install; exit 1 when any")
    p.add_argument("--force", action="store_true", help="run the scenarios whatever is cached")
    p.add_argument("--jobs", type=int, default=None, help="processes (default: CPU count)")
    p.add_argument("--times", action="store_true", help="say each group's seconds")
    p.add_argument("--group", choices=sorted(GROUPS), help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.group:
        return run_group(args.group)
    from .algorithms._jitcache import cache_dir
    if args.check:
        gone = missing()
        for name in gone:
            print(name)
        return 1 if gone else 0
    if not args.force and all_cached():
        return 0
    print(f"hillshade-rt: compiling the kernels once for this install (cached in "
          f"{cache_dir()}; about a minute)", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    times: dict = {}
    code = run_all(args.jobs, times)
    if args.times:
        print("hillshade-rt: " + ", ".join(f"{k} {v:.0f} s" for k, v in times.items()),
              file=sys.stderr)
    gone = missing()
    if gone:
        print(f"hillshade-rt: {len(gone)} kernels were not compiled by the warm-up: "
              f"{', '.join(gone)}", file=sys.stderr)
        code = 1
    print(f"hillshade-rt: kernels ready ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    _stale_hint()
    return code


def _stale_hint() -> None:
    """After compiling a new version's kernels, the older versions' folders are what a user
    may want gone: say so, with their size (removing them is ``hillshade-rt cache --prune``'s
    to do: another environment may still use one)."""
    from .algorithms._jitcache import survey
    others = survey()["other_versions"]
    if others:
        size = sum(s for _, s in others) / 1e6
        print(f"hillshade-rt: {len(others)} other versions' compiled kernels ({size:.0f} MB) "
              f"are cached too; 'hillshade-rt cache --prune' removes them", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
