"""Golden outputs: every command line of the warm-up (``hillshade_rt.warm.GROUPS``: every
command and mode on small DEMs) plus Dask and GPU-simulator runs, each into a folder of its own;
the outputs' contents recorded as digests, so that a refactoring can prove it changed no byte.

    python benchmarks/golden.py record golden.json     # before
    python benchmarks/golden.py compare golden.json    # after: exit 1 and the differences

A raster's digest covers its pixels (every band), type, nodata, size, transform, CRS and tags
(timestamps and the version dropped); a JSON report's its values with times, durations and
versions dropped; any other file (CSV, GIF, MP4, PNG) its bytes. The viewer's, the points' and
dynamic terrain's scenarios are functions, not command lines: not recorded.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import sys
import tempfile

os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")
os.environ["HILLSHADE_RT_SERVER"] = "off"

# words of keys whose values change from run to run (times taken, versions, paths of temp files)
VOLATILE = re.compile(r"(seconds|_s$|_ms$|time|elapsed|duration|version|date|started|finished|"
                      r"host|path|file|dir|pid|cpu|threads_used|memory|rss|created|why|chose)", re.I)
# tags: timestamps and the version
VOLATILE_TAGS = re.compile(r"(DATETIME|VERSION|SOFTWARE|CREATED|DATE|TIME)", re.I)


def extra_scenarios() -> list[list[str]]:
    """Runs the warm-up does not make: Dask's windows and the GPU backend (the simulator)."""
    return [
        ["shadow", "{utm}", "{out}/x.tif", "--azimuth", "203.7", "--elevation", "10",
         "--window-size", "64", "--scheduler", "local:1"],
        ["sun-hours", "{utm}", "{out}/x.tif", "--date", "2026-06-21", "--step", "3h",
         "--scheduler", "local:1"],
        ["shadow", "{tile}", "{out}/y.tif", "--azimuth", "163", "--elevation", "12",
         "--backend", "gpu", "--algorithm", "brute"],
        ["shadow", "{utm}", "{out}/z.tif", "--azimuth", "290", "--elevation", "8",
         "--report", "{out}/z.json"],
        ["shadow", "{utm}", "--output-pattern", "{out}/z_{{index}}.tif", "--start",
         "2026-06-21T08:00", "--end", "2026-06-21T12:00", "--step", "2h", "--tz",
         "America/Los_Angeles"],
    ]


def scenarios() -> list[list[str]]:
    from hillshade_rt.warm import GROUPS
    out = [args for group in GROUPS.values() for args in group if not callable(args)]
    return out + extra_scenarios()


def _clean(value):
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in sorted(value.items()) if not VOLATILE.search(str(k))}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    return value


def digest(path: str) -> dict:
    """What is recorded of one output file."""
    name = os.path.basename(path)
    if name.endswith(".json"):
        with open(path) as fh:
            return {"json": _clean(json.load(fh))}
    if name.endswith((".tif", ".tiff", ".vrt", ".img")):
        import rasterio
        with rasterio.open(path) as ds:
            h = hashlib.sha256()
            for b in range(1, ds.count + 1):
                h.update(ds.read(b).tobytes())
            tags = {k: v for k, v in ds.tags().items() if not VOLATILE_TAGS.search(k)}
            band_tags = [ds.tags(b) for b in range(1, ds.count + 1)]
            return {"pixels": h.hexdigest(), "dtypes": list(ds.dtypes),
                    "nodata": None if ds.nodata is None else repr(float(ds.nodata)),
                    "shape": [ds.count, ds.height, ds.width],
                    "transform": list(ds.transform)[:6],
                    "crs": ds.crs.to_string() if ds.crs else None,
                    "tags": tags, "band_tags": band_tags,
                    "descriptions": list(ds.descriptions)}
    with open(path, "rb") as fh:
        return {"bytes": hashlib.sha256(fh.read()).hexdigest()}


def run_all(work: str) -> dict:
    from hillshade_rt.cli import cli
    from hillshade_rt.warm import _write_dems
    values = _write_dems(work)
    result = {}
    for k, args in enumerate(scenarios()):
        out = os.path.join(work, f"s{k:03d}")
        os.mkdir(out)
        argv = [a.format(**dict(values, out=out)) for a in args] + ["-q"]
        try:
            code = cli.main(args=argv, prog_name="hillshade-rt", standalone_mode=False)
        except SystemExit as exc:
            code = exc.code
        except Exception as exc:             # noqa: BLE001 -- recorded as the outcome
            code = f"{type(exc).__name__}: {exc}"
        files = {}
        for root, _, names in os.walk(out):
            for n in sorted(names):
                p = os.path.join(root, n)
                files[os.path.relpath(p, out)] = digest(p)
        key = " ".join(args)
        result[key] = {"exit": code or 0, "files": files}
        print(f"{k:3d} {code or 0} {key}", file=sys.stderr, flush=True)
    return result


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("action", choices=["record", "compare"])
    ap.add_argument("manifest")
    a = ap.parse_args()
    # one fixed folder: outputs that name their inputs (CSV, reports) name the same paths
    work = os.path.join(tempfile.gettempdir(), "hillshade-rt-golden")
    shutil.rmtree(work, ignore_errors=True)
    os.mkdir(work)
    try:
        now = run_all(work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if a.action == "record":
        with open(a.manifest, "w") as fh:
            json.dump(now, fh, indent=1, sort_keys=True)
        print(f"{len(now)} command lines recorded in {a.manifest}")
        return 0
    with open(a.manifest) as fh:
        before = json.load(fh)
    bad = 0
    for key in sorted(set(before) | set(now)):
        if before.get(key) != now.get(key):
            bad += 1
            b, n = before.get(key) or {}, now.get(key) or {}
            what = [f for f in sorted(set(b.get("files", {})) | set(n.get("files", {})))
                    if b.get("files", {}).get(f) != n.get("files", {}).get(f)]
            print(f"DIFFERS: {key}: exit {b.get('exit')} -> {n.get('exit')}; files {what}")
    print(f"{len(now)} command lines, {bad} differ")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
