"""Fuzzing the command line (issue 16): whatever the input file and the options, a run ends

* with exit status 0 and valid outputs (each opens with rasterio, has the input's shape, the
  product's dtype and only values in its documented range; nothing else new on disk), or
* with exit status 1 or 2, exactly one line on stderr beginning ``hillshade-rt: error:``, and
  nothing new on disk (no output, no hidden ``.o.tif.*.part.tif`` or ``.scratch`` files);
  a command line that is malformed on its own (an option value or combination that no input
  could make right, e.g. ``--pixel-size 0``, ``--lat 95``, ``--band 0``) exits 2,

and never with a traceback.

Inputs: random bytes (.tif .hgt .raw .png), small real GeoTIFFs/PNGs truncated or with bytes
overwritten, raw grids with random --raw-shape/--raw-dtype/--raw-byteorder, two-tile mosaics, and
random option values for shadow, hillshade, horizon, info and sun-hours.

Every command (``test_fuzz_every_command``) is also run with random sets of its own options
(a table per command: well-formed values, and in a third of the cases malformed ones) and side
files, judged by the generic property: exit 0/1/2/130/143, one error line, no traceback, no
half-written (.part) file, no output unless exit 0, a bounded run time. The viewer's endpoints
get random query strings and JSON bodies (``test_fuzz_viewer_*``): 200, 400 or 404, never 500.

Each run is in-process (click's CliRunner) but made to look like a fresh process on stderr:
Python warnings shown as a fresh interpreter shows them, log records with no handler printed by
logging's last resort (as tifffile's are in a real run), and anything written to file
descriptor 2 (GDAL's own messages) counted as stderr too.

In the suite: a few hundred examples, derandomized (reproducible). A long run:
``HILLSHADE_FUZZ_EXAMPLES=3000 pytest tests/cli/test_fuzz.py`` (the number is shared among the tests).
``HILLSHADE_FUZZ_COLLECT=dir`` records every violation (JSON lines, with the input files)
instead of failing at the first one, to survey a long run.
"""

from __future__ import annotations

import contextlib
import functools
import json
import logging
import os
import re
import shutil
import sys
import tempfile
import warnings
from dataclasses import dataclass, field

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from hillshade_rt.testing import fractal_terrain

pytestmark = pytest.mark.filterwarnings("ignore")

_TOTAL = int(os.environ.get("HILLSHADE_FUZZ_EXAMPLES", "0") or 0)
_COLLECT = os.environ.get("HILLSHADE_FUZZ_COLLECT")


def _examples(default: int, share: float) -> int:
    return max(1, int(_TOTAL * share)) if _TOTAL else default


def _settings(default: int, share: float):
    return settings(max_examples=_examples(default, share), deadline=None, derandomize=True,
                    database=None, print_blob=False,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.filter_too_much])


# ---------------------------------------------------------------------------------------------
# a case: files to write, a command line, what a success must produce

IN, OUT = "@IN/", "@OUT/"   # placeholders in argv for the input and output folders


@dataclass
class Case:
    command: str
    argv: list[str]
    files: dict[str, bytes] = field(default_factory=dict)      # name in IN -> content
    recipe: list[str] = field(default_factory=list)           # how the files were made
    malformed: list[str] = field(default_factory=list)        # why the command line is bad alone
    shape: tuple[int, int] | None = None                       # the input's (rows, cols) if known
    product: str = ""            # shadow, classes, soft, hillshade, horizon, sun-hours, info
    bands: int | None = 1        # bands of the output (None: not known in advance)
    outputs: list[str] = field(default_factory=list)          # files in OUT a success writes
    report: str | None = None    # name in OUT
    preview: str | None = None   # name in OUT
    info_json: bool = False

    def shell(self) -> str:
        import shlex
        args = [a.replace(IN, "in/").replace(OUT, "out/") for a in self.argv]
        return "hillshade-rt " + " ".join(shlex.quote(a) for a in args)

    def __repr__(self):   # what hypothesis prints for a falsifying example
        return f"Case({self.shell()!r}; files: {'; '.join(self.recipe) or 'none'})"


# ---------------------------------------------------------------------------------------------
# input files

_GEO = {
    "utm": ((30.0, 0.0, 400000.0, 0.0, -30.0, 3800000.0), "EPSG:32611"),
    "geographic": ((1 / 1200, 0.0, -84.0, 0.0, -1 / 1200, 36.5), "EPSG:4326"),
    "south-up": ((30.0, 0.0, 400000.0, 0.0, 30.0, 3790000.0), "EPSG:32611"),
    "rotated": ((29.5, 5.2, 400000.0, 5.2, -29.5, 3800000.0), "EPSG:32611"),
    "none": (None, None),
}
_NODATA = {"int16": [None, -32768, -9999], "uint16": [None, 0, 65535], "uint8": [None, 0, 255],
           "int32": [None, -9999], "float32": [None, -9999.0, float("nan")],
           "float64": [None, -9999.0, -3.4028234663852886e38]}


def _heights(rows, cols, dtype, seed, voids, nodata):
    z = fractal_terrain(rows, cols, seed, relief=150.0) + (20.0 if dtype.startswith("u") else 500.0)
    if dtype == "uint8":
        z = z * (200.0 / 650.0)
    z = z.astype(dtype)
    if voids:
        rng = np.random.default_rng(seed + 1)
        holes = rng.random((rows, cols)) < voids
        if nodata is not None:
            z[holes] = nodata
        elif dtype.startswith("float"):
            z[holes] = np.nan
    return z


@functools.lru_cache(maxsize=512)
def raster_bytes(driver, rows, cols, dtype, geo, nodata, seed, voids, bands, compress):
    """A small real raster (GTiff or PNG) as bytes."""
    import rasterio
    from affine import Affine
    from rasterio.io import MemoryFile

    z = np.stack([_heights(rows, cols, dtype, seed + b, voids, nodata) for b in range(bands)])
    prof = dict(driver=driver, width=cols, height=rows, count=bands, dtype=dtype, nodata=nodata)
    if driver == "GTiff":
        tr, crs = _GEO[geo]
        if tr is not None:
            prof.update(transform=Affine(*tr), crs=crs)
        if compress:
            prof.update(compress=compress, tiled=True, blockxsize=16, blockysize=16)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with MemoryFile() as mf:
            with mf.open(**prof) as dst:
                dst.write(z)
            return bytes(mf.read())


@st.composite
def real_raster(draw, driver=None):
    """(bytes, recipe, shape, georeferenced, extension) of a valid small GeoTIFF or PNG."""
    driver = driver or draw(st.sampled_from(["GTiff"] * 5 + ["PNG"]))
    rows, cols = draw(st.integers(12, 40)), draw(st.integers(12, 40))
    if driver == "PNG":
        dtype, geo, compress = draw(st.sampled_from(["uint8", "uint16"])), "none", None
    else:
        dtype = draw(st.sampled_from(["float32", "int16", "float32", "uint16", "float64",
                                      "int32", "uint8"]))
        geo = draw(st.sampled_from(["utm", "utm", "geographic", "south-up", "none", "rotated"]))
        compress = draw(st.sampled_from([None, None, "deflate", "lzw"]))
    nodata = draw(st.sampled_from(_NODATA[dtype]))
    voids = draw(st.sampled_from([0.0, 0.0, 0.05, 0.5, 1.0]))
    bands = draw(st.sampled_from([1, 1, 1, 2])) if driver == "GTiff" else 1
    seed = draw(st.integers(0, 5))
    data = raster_bytes(driver, rows, cols, dtype, geo, nodata, seed, voids, bands, compress)
    ext = ".tif" if driver == "GTiff" else ".png"
    recipe = (f"{driver} {rows}x{cols} {dtype} geo={geo} nodata={nodata} voids={voids} "
              f"bands={bands} compress={compress} (tests/cli/test_fuzz.py::raster_bytes seed {seed})")
    return data, recipe, (rows, cols), geo not in ("none",), ext


@st.composite
def damaged_input(draw):
    """Random bytes, or a real raster truncated or with some bytes overwritten."""
    how = draw(st.sampled_from(["random", "truncated", "truncated", "flipped", "flipped"]))
    if how == "random":
        ext = draw(st.sampled_from([".tif", ".hgt", ".raw", ".png"]))
        magic = draw(st.sampled_from([b"", b"II*\x00", b"MM\x00*", b"II+\x00",
                                      b"\x89PNG\r\n\x1a\n"]))
        body = draw(st.binary(min_size=0, max_size=3000))
        data = magic + body
        return data, f"random bytes: magic {magic!r} + {len(body)} random bytes", None, False, ext
    data, recipe, shape, georef, ext = draw(real_raster())
    if how == "truncated":
        n = draw(st.integers(0, len(data) - 1))
        return data[:n], f"{recipe}, truncated to {n} of {len(data)} bytes", None, georef, ext
    buf = bytearray(data)
    k = draw(st.integers(1, 8))
    edits = []
    for _ in range(k):
        head = draw(st.booleans())
        pos = draw(st.integers(0, min(len(buf), 600) - 1 if head else len(buf) - 1))
        val = draw(st.integers(0, 255))
        buf[pos] = val
        edits.append((pos, val))
    return bytes(buf), f"{recipe}, bytes overwritten (pos, value): {edits}", None, georef, ext


_RAW = {"int16": 2, "uint16": 2, "int32": 4, "float32": 4, "float64": 8}


@st.composite
def raw_input(draw):
    """(files, recipe, options, shape or None, malformed) of a raw grid with random options."""
    dtype = draw(st.sampled_from(sorted(_RAW)))
    order = draw(st.sampled_from(["little", "big"]))
    hgt = draw(st.integers(0, 5)) == 0
    rows = draw(st.integers(12, 40))
    cols = rows if hgt else draw(st.integers(12, 40))
    content = draw(st.sampled_from(["terrain", "terrain", "random"]))
    if content == "terrain":
        z = _heights(rows, cols, dtype, draw(st.integers(0, 5)), 0.0, None)
        data = z.astype(np.dtype(dtype).newbyteorder("<" if order == "little" else ">")).tobytes()
    else:
        data = draw(st.binary(min_size=rows * cols * _RAW[dtype], max_size=rows * cols * _RAW[dtype]))
    cut = draw(st.sampled_from([0, 0, 0, 1, 3, -1]))   # bytes removed (-1: one added)
    data = data[:len(data) - cut] if cut > 0 else data + (b"\x00" if cut < 0 else b"")
    name = ("N36W084.hgt" if hgt else
            "grid" + draw(st.sampled_from([".raw", ".bin", ".f32", ".r16", ".dem", ".dat"])))
    opts, malformed = [], []
    shape_opt = draw(st.sampled_from(["match", "match", "swapped", "wrong", "garbage", "none"]))
    if shape_opt == "match":
        opts += ["--raw-shape", f"{rows}x{cols}"]
    elif shape_opt == "swapped":
        opts += ["--raw-shape", f"{cols}X{rows}"]
    elif shape_opt == "wrong":
        opts += ["--raw-shape", f"{rows},{cols + draw(st.integers(1, 5))}"]
    elif shape_opt == "garbage":
        g = draw(st.sampled_from(["abc", "0x5", "12", "12x", "-3x4", "x", "1e3x2", "", "12x0"]))
        opts += ["--raw-shape", g]
        malformed.append(f"--raw-shape {g!r}")
    dt_opt = draw(st.sampled_from(["match", "match", "other", "none", "bad"]))
    if dt_opt == "match":
        opts += ["--raw-dtype", dtype]
    elif dt_opt == "other":
        opts += ["--raw-dtype", draw(st.sampled_from(sorted(_RAW)))]
    elif dt_opt == "bad":
        bad = draw(st.sampled_from(["int8", "float16", "f4"]))
        opts += ["--raw-dtype", bad]
        malformed.append(f"--raw-dtype {bad}")
    bo = draw(st.sampled_from(["match", "other", "none", "none", "bad"]))
    if bo == "match":
        opts += ["--raw-byteorder", order]
    elif bo == "other":
        opts += ["--raw-byteorder", "big" if order == "little" else "little"]
    elif bo == "bad":
        opts += ["--raw-byteorder", "middle"]
        malformed.append("--raw-byteorder middle")
    recipe = (f"raw {name}: {rows}x{cols} {dtype} {order}-endian {content} values "
              f"({len(data)} bytes; {cut} removed, -1 = one added)")
    shape = (rows, cols) if shape_opt == "match" and cut == 0 else None
    return {name: data}, recipe, opts, name, shape, malformed, hgt


# ---------------------------------------------------------------------------------------------
# option values

_FLOAT_EDGES = ["nan", "inf", "-inf", "-0.0", "0", "1e308", "-1e308", "1e-300", "5e-324"]


def _num(x) -> str:
    return x if isinstance(x, str) else repr(float(x))


def floats_text(lo, hi):
    """A float option value as text: mostly in [lo, hi], sometimes an edge or any float."""
    return st.one_of(st.floats(lo, hi).map(_num), st.floats(lo, hi).map(_num),
                     st.sampled_from(_FLOAT_EDGES),
                     st.floats(allow_nan=True, allow_infinity=True).map(_num))


def _as_float(text):
    try:
        return float(text)
    except ValueError:
        return None


def _finite(text) -> bool:
    v = _as_float(text)
    return v is not None and np.isfinite(v)


def pick(draw, wild, good, bad=()):
    """A value from ``good`` (a list or a strategy), or with ``wild`` now and then from ``bad``
    (values no input could make right, or anything at all)."""
    src = good
    if wild and bad and draw(st.integers(0, 2)) == 0:
        src = bad
    return draw(src if isinstance(src, st.SearchStrategy) else st.sampled_from(list(src)))


def often(draw, n) -> bool:
    """True with probability 1/n."""
    return draw(st.integers(0, n - 1)) == 0


_TIMES = ["2026-06-21T12:00:00+00:00", "2026-06-21T19:30Z", "2026-06-21T07:30-07:00",
          "2026-12-21T20:00:00+00:00", "2026-06-21T08:00Z", "2026-06-21T14:30+02:00"]
_LOCAL_TIMES = ["2026-06-21T14:30", "2026-06-21", "2026-03-29T02:30", "2026-11-01T01:30"]
_BAD_TIMES = ["noon", "2026-13-45T99:00Z", "", "T12:00Z", "2026-06-21T12:00+25:00",
              "2026-06-21 18:00 UTC", "1e3"]
_ZONES = ["UTC", "Europe/Zurich", "America/Los_Angeles", "America/New_York"]
_BAD_ZONES = ["Mars/Olympus_Mons", "", "Nowhere/Special", "../etc/passwd"]


def _time_ok(text, tz) -> bool | None:
    """True: a well-formed instant; False: malformed whatever the DEM; None: not decided here
    (a date without a time, a local time a zone skips or repeats)."""
    import datetime as dt
    try:
        t = dt.datetime.fromisoformat(text.strip().replace("z", "Z"))
    except ValueError:
        return False
    if t.tzinfo is None and tz is None:
        return False
    if "T" not in text or t.tzinfo is None:
        return None     # date only (issue 16 item 12), or local: may not exist in the zone
    return True


@st.composite
def sun_options(draw, command, wild):
    """The sun options of shadow / hillshade: (argv, malformed, number of suns or None)."""
    argv, bad = [], []
    way = pick(draw, wild, ["given"] * 6 + ["time"] * 2 + ["series"] +
               (["none"] if command == "hillshade" else []), ["both", "half", "none"])
    nsuns = 1
    if way in ("given", "both", "half"):
        az = pick(draw, wild, st.one_of(st.floats(-720, 720).map(_num),
                                        st.sampled_from(["0", "90", "180", "203.7", "1e300"])),
                  st.one_of(floats_text(-720, 720), st.sampled_from(["west", "1e400", "nan"])))
        el = pick(draw, wild, st.one_of(st.floats(0.5, 89.0).map(_num),
                                        st.sampled_from(["90", "1e-300", "0.01"])),
                  st.one_of(floats_text(-100, 200), st.sampled_from(["91", "0", "low", "nan"])))
        argv += ["--azimuth", az]
        if way != "half":
            argv += ["--elevation", el]
        else:
            bad.append("--azimuth without --elevation")
        if _as_float(az) is None:
            bad.append(f"--azimuth {az!r} not a number")
        elif not _finite(az):
            bad.append(f"--azimuth {az}")
        elif way != "half":
            v = _as_float(el)
            if v is None or not (np.isfinite(v) and 0 < v <= 90):
                bad.append(f"--elevation {el}")
    tz = None
    if way in ("time", "series", "both") and draw(st.booleans()):
        tz = pick(draw, wild, _ZONES, _BAD_ZONES)
        argv += ["--tz", tz]
        if tz in _BAD_ZONES:
            bad.append(f"--tz {tz!r}")
    if way in ("time", "both"):
        times = draw(st.lists(st.just(None), min_size=1, max_size=3))
        times = [pick(draw, wild, _TIMES + (_LOCAL_TIMES if tz else []), _BAD_TIMES + _LOCAL_TIMES)
                 for _ in times]
        for t in times:
            argv += ["--time", t]
            if _time_ok(t, None if tz in _BAD_ZONES else tz) is False:
                bad.append(f"--time {t!r}" + ("" if tz else " without --tz"))
        nsuns = len(times)
    if way == "series":
        start = pick(draw, wild, ["2026-06-21T18:00Z", "2026-06-21T10:00-07:00"], ["soon"])
        end = pick(draw, wild, ["2026-06-21T19:00Z", "2026-06-21T18:00Z"],
                   ["later", "2026-06-21T17:00Z"])
        step = pick(draw, wild, ["30min", "1h", "PT20M"], ["0s", "abc", "-5min", "1 fortnight"])
        argv += ["--start", start, "--end", end, "--step", step]
        nsuns = None
        if start == "soon" or end == "later":
            bad.append("--start/--end not a time")
        elif step in ("0s", "abc", "-5min", "1 fortnight"):
            bad.append(f"--step {step!r}")
        elif start == "2026-06-21T18:00Z" and end == "2026-06-21T17:00Z":
            bad.append("--end before --start")
    if way == "both":
        bad.append("--azimuth/--elevation with --time")
    if way == "none" and command == "shadow":
        bad.append("no sun given")
    if way in ("time", "series") and often(draw, 4):
        lat = pick(draw, wild, ["36.3", "-89.9", "90"], ["95", "-91", "nan", "inf"])
        with_lon = not (wild and often(draw, 4))
        argv += ["--lat", lat]
        lon = None
        if with_lon:
            lon = pick(draw, wild, ["-84.1", "200", "-540"], ["nan", "inf"])
            argv += ["--lon", lon]
        v = float(lat)
        if not with_lon:
            bad.append("--lat without --lon")
        elif not (np.isfinite(v) and -90 <= v <= 90) or not _finite(lon):
            bad.append(f"--lat {lat} --lon {lon}")
    if way in ("given", "both") and wild and often(draw, 10):
        argv += ["--tz", "UTC"]
        bad.append("--tz with --azimuth/--elevation")
    return argv, bad, nsuns


@st.composite
def dem_options(draw, georef: bool, raw: bool, wild: bool):
    argv, bad = [], []
    if often(draw, 10):
        b = pick(draw, wild, ["1", "2"], ["0", "-1", "x"])
        argv += ["--band", b]
        if b in ("0", "-1", "x"):
            bad.append(f"--band {b}")
    if often(draw, 7):
        nd = pick(draw, wild, st.one_of(st.floats(-40000, 70000).map(_num),
                                        st.sampled_from(["-32768", "nan", "0"])),
                  st.one_of(floats_text(-1e40, 1e40), st.sampled_from(["none"])))
        argv += ["--nodata", nd]
        if _as_float(nd) is None:
            bad.append(f"--nodata {nd!r}")
    if often(draw, 7):
        zf = pick(draw, wild, st.one_of(st.sampled_from(["0.3048", "-1", "1e30", "1e-30", "3"]),
                                        st.floats(-1000, 1000).filter(bool).map(_num)),
                  floats_text(-1000, 1000))
        argv += ["-z", zf]
        v = _as_float(zf)
        if v is None or not np.isfinite(v) or v == 0:
            bad.append(f"--z-factor {zf}")
    if (raw or not georef) and not (wild and often(draw, 5)) or often(draw, 10):
        ps = pick(draw, wild, ["30", "30", "1,2", " 30 , 30 ", "1e-300", "1e300", "0.5"],
                  ["0", "-1", "nan", "inf", "1,2,3", "abc", "", "30,0"])
        argv += ["--pixel-size", ps]
        try:
            vals = [float(p) for p in ps.split(",")]
            ok = len(vals) in (1, 2) and all(np.isfinite(v) and v > 0 for v in vals)
        except ValueError:
            ok = False
        if not ok:
            bad.append(f"--pixel-size {ps!r}")
    return argv, bad


@st.composite
def algorithm_options(draw, wild):
    argv, bad = [], []
    algo = pick(draw, wild, ["smap", "smap", "brute", "horizon", "sweep", None], ["quick"])
    if algo == "quick":
        bad.append("--algorithm quick")
    if algo is not None:
        argv += ["--algorithm", algo]
    algo = algo or "smap"
    owners = {"--nextv": "smap", "--better-nextv": "smap", "--horizon-method": "horizon",
              "--sample-spacing": "horizon", "--exact-steps": "sweep"}
    for opt, owner in owners.items():
        if not often(draw, 6) or (owner != algo and not wild):
            continue
        if opt == "--better-nextv":
            argv.append(opt)
        elif opt == "--nextv":
            argv += [opt, draw(st.sampled_from(["scan", "binary", "quad"]))]
        elif opt == "--horizon-method":
            argv += [opt, draw(st.sampled_from(["scan", "hull"]))]
        else:
            n = pick(draw, wild, ["1", "2", "5"], ["0", "-3", "two"])
            argv += [opt, n]
            if n in ("0", "-3", "two"):
                bad.append(f"{opt} {n}")
        if owner != algo and algo in ("smap", "brute", "horizon", "sweep"):
            bad.append(f"{opt} with --algorithm {algo}")
    return argv, bad


@st.composite
def run_options(draw, command, nsuns, wild):
    """Outputs and the run's other options: (argv, bad, report, preview, pattern?)."""
    argv, bad = [], []
    report = preview = None
    if often(draw, 4):
        report = "r.json"
        argv += ["--report", OUT + report]
    if often(draw, 5):
        preview = "p.png"
        argv += ["--preview", OUT + preview]
    if often(draw, 10):
        argv.append("--cog")
    if draw(st.booleans()):
        argv.append("-q")
    if often(draw, 6):
        mm = pick(draw, wild, ["4GB", "512MiB", "300MB", "2 GB", "64GB", "1kB"],
                  ["0", "abc", "1e9", "-1GB", "0.0001kB"])
        argv += ["--max-memory", mm]
        if mm in ("0", "abc", "1e9", "-1GB", "0.0001kB"):
            bad.append(f"--max-memory {mm!r}")
    if often(draw, 5):
        ws = pick(draw, wild, ["8", "16x32", "13,7", "64", "5"],
                  ["0", "abc", "-5", "8x0", "", "1e3"])
        argv += ["--window-size", ws]
        if not re.fullmatch(r"\s*(\d+)\s*(?:[xX,]\s*(\d+))?\s*", ws) or \
                any(int(g) < 1 for g in re.findall(r"\d+", ws)):
            bad.append(f"--window-size {ws!r}")
    if often(draw, 8):
        # creation options: GDAL's verdict (exit 0, or 1 with nothing written), malformed: 2
        co = pick(draw, wild, ["COMPRESS=ZSTD", "predictor=2", "BLOCKXSIZE=512", "FOO=1",
                               "BIGTIFF=MAYBE"], ["FOO", "=1", "COMPRESS=", "A B=1"])
        argv += ["--co", co]
        if co in ("FOO", "=1", "COMPRESS=", "A B=1"):
            bad.append(f"--co {co!r}")
    if often(draw, 10):
        th = pick(draw, wild, ["1", "2"], ["0"])
        argv += ["--threads", th]
        if th == "0":
            bad.append("--threads 0")
    pattern = nsuns is not None and often(draw, 8)
    return argv, bad, report, preview, pattern


# ---------------------------------------------------------------------------------------------
# whole cases

@st.composite
def input_file(draw, kinds=("real", "damaged", "raw")):
    """(files, recipe, dem argv, shape or None, georef, extra dem options, malformed, raw)."""
    kind = draw(st.sampled_from(kinds))
    if kind == "raw":
        files, recipe, opts, name, shape, bad, hgt = draw(raw_input())
        return files, [recipe], [IN + name], shape, hgt, opts, bad, True
    data, recipe, shape, georef, ext = draw(real_raster() if kind == "real" else damaged_input())
    name = "dem" + ext
    files = {name: data}
    dems = [IN + name]
    if kind == "real" and re.search(r"geo=(utm|geographic|south-up) ", recipe) and often(draw, 8):
        # a mosaic: a second tile beside the first (east of it), perhaps damaged
        second, r2, _, _, _ = draw(real_raster("GTiff"))
        mode = draw(st.sampled_from(["beside", "damaged", "random"]))
        if mode == "damaged":
            second = second[:draw(st.integers(0, len(second) - 1))]
        elif mode == "random":
            second = draw(st.binary(max_size=2000))
        files["dem2.tif"] = _shifted(data, shape) if mode == "beside" else second
        recipe += "; dem2.tif: " + ("dem.tif shifted east by its width" if mode == "beside"
                                    else f"{mode}: {r2}")
        dems.append(IN + "dem2.tif")
        shape = (shape[0], 2 * shape[1]) if mode == "beside" else None
    return files, [recipe], dems, shape, georef, [], [], False


def _shifted(data: bytes, shape) -> bytes:
    """The raster ``data`` moved east by its own width (a tile of a mosaic)."""
    import rasterio
    from rasterio.io import MemoryFile
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with MemoryFile(data) as src_f, src_f.open() as src:
            prof = src.profile
            z = src.read()
            t = src.transform
            prof["transform"] = rasterio.Affine(t.a, t.b, t.c + t.a * shape[1], t.d, t.e, t.f)
            with MemoryFile() as mf:
                with mf.open(**prof) as dst:
                    dst.write(z)
                return bytes(mf.read())


def _lighting_case(draw, command, inp, wild):
    files, recipe, dems, shape, georef, dem_extra, bad, raw = inp
    sun, sbad, nsuns = draw(sun_options(command, wild))
    dopt, dbad = draw(dem_options(georef, raw, wild))
    run, rbad, report, preview, pattern = draw(run_options(command, nsuns, wild))
    argv, bad = [command] + dems + sun, bad + sbad + dbad + rbad
    product = "hillshade" if command == "hillshade" else "shadow"
    if command == "shadow":
        aopt, abad = draw(algorithm_options(wild))
        argv += aopt
        bad += abad
        soft, classes = often(draw, 5), often(draw, 6)
        if classes and soft and not wild:
            soft = False
        if soft:
            argv.append("--soft")
            product = "soft"
        if classes:
            argv.append("--classes")
            product = "classes"
            if soft:
                bad.append("--classes with --soft")
        if often(draw, 5):
            argv.append("--self-shadow")
    else:
        if often(draw, 5):
            argv += ["--algorithm", draw(st.sampled_from(["smap", "brute", "horizon", "sweep"]))]
        if often(draw, 6):
            argv.append("--soft")
        if often(draw, 5):
            amb = pick(draw, wild, ["0", "0.5", "1"], ["1.5", "-0.1", "nan"])
            argv += ["--ambient", amb]
            if amb in ("1.5", "-0.1", "nan"):
                bad.append(f"--ambient {amb}")
        if often(draw, 7) and (wild or "--pixel-size" not in dopt):
            sc = pick(draw, wild, ["1", "111120"], ["0", "-1", "nan", "inf"])
            argv += ["--scale", sc]
            if sc in ("0", "-1", "nan", "inf"):
                bad.append(f"--scale {sc}")
            elif "--pixel-size" in dopt:
                bad.append("--scale with --pixel-size")
    if often(draw, 10):
        argv.append(draw(st.sampled_from(["--earth-curvature", "--no-earth-curvature"])))
    if often(draw, 12):
        argv += ["--refraction-coefficient", draw(st.sampled_from(["0.13", "0", "-1", "2"]))]
    if pattern:
        argv += ["--output-pattern", OUT + "o_{index}.tif"]
        outputs, bands = [f"o_{i}.tif" for i in range(nsuns)], 1
    elif often(draw, 12):
        argv += ["-o", OUT + "o.tif"]
        outputs, bands = ["o.tif"], nsuns
    else:
        argv.append(OUT + "o.tif")
        outputs, bands = ["o.tif"], nsuns
    argv += run + dem_extra + dopt
    return Case(command, argv, files, recipe, bad, shape, product, bands, outputs, report,
                preview)


def _horizon_case(draw, inp, wild):
    files, recipe, dems, shape, georef, dem_extra, bad, raw = inp
    argv = ["horizon", dems[0], OUT + "o.tif"]
    if len(dems) > 1:
        bad.append("horizon takes one DEM")   # click: "Got unexpected extra argument"
        argv = ["horizon"] + dems + [OUT + "o.tif"]
    az = pick(draw, wild, st.floats(-720, 720).map(_num),
              st.one_of(floats_text(-720, 720), st.sampled_from(["north"])))
    argv += ["--azimuth", az]
    if not _finite(az):
        bad.append(f"--azimuth {az}")
    method = draw(st.sampled_from([None, "scan", "hull"]))
    if method:
        argv += ["--method", method]
    if often(draw, 4):
        n = pick(draw, wild, ["1", "3"], ["0"])
        argv += ["--sample-spacing", n]
        if n == "0":
            bad.append("--sample-spacing 0")
        elif method == "hull" and n != "1":
            bad.append("--sample-spacing with --method hull")
    if often(draw, 6):
        argv.append(draw(st.sampled_from(["--earth-curvature", "--no-earth-curvature"])))
    preview = None
    if often(draw, 5):
        preview = "p.png"
        argv += ["--preview", OUT + preview]
    dopt, dbad = draw(dem_options(georef, raw, wild))
    argv += dem_extra + dopt
    return Case("horizon", argv, files, recipe, bad + dbad, shape, "horizon", 1, ["o.tif"],
                None, preview)


def _sun_hours_case(draw, inp, wild):
    files, recipe, dems, shape, georef, dem_extra, bad, raw = inp
    argv = ["sun-hours", dems[0], OUT + "o.tif"]
    if len(dems) > 1:
        bad.append("sun-hours takes one DEM")
        argv = ["sun-hours"] + dems + [OUT + "o.tif"]
    date = pick(draw, wild, ["2026-06-21", "2026-12-21", "2026-03-29"],
                ["21/06/2026", "", "2026-06-21T12:00"])
    argv += ["--date", date]
    if date in ("21/06/2026", "", "2026-06-21T12:00"):
        bad.append(f"--date {date!r}")
    step = pick(draw, wild, ["1h", "2h", "90min", "6h"], ["0s", "abc"])
    argv += ["--step", step]
    if step in ("0s", "abc"):
        bad.append(f"--step {step!r}")
    if often(draw, 4):
        tz = pick(draw, wild, _ZONES, _BAD_ZONES)
        argv += ["--tz", tz]
        if tz in _BAD_ZONES:
            bad.append(f"--tz {tz!r}")
    if often(draw, 5):
        lat = pick(draw, wild, ["36.3", "-45"], ["95", "nan"])
        argv += ["--lat", lat]
        if not (wild and often(draw, 3)):
            argv += ["--lon", "-84.1"]
            if lat in ("95", "nan"):
                bad.append(f"--lat {lat}")
        else:
            bad.append("--lat without --lon")
    if often(draw, 5):
        argv.append("--soft")
    if often(draw, 5):
        argv.append("--no-self-shadow")
    report = preview = None
    if often(draw, 4):
        report = "r.json"
        argv += ["--report", OUT + report]
    if often(draw, 5):
        preview = "p.png"
        argv += ["--preview", OUT + preview]
    dopt, dbad = draw(dem_options(georef, raw, wild))
    argv += dem_extra + dopt
    return Case("sun-hours", argv, files, recipe, bad + dbad, shape, "sun-hours", 1, ["o.tif"],
                report, preview)


def _info_case(draw, inp, wild):
    files, recipe, dems, shape, georef, dem_extra, bad, raw = inp
    argv = ["info", dems[0]]
    if len(dems) > 1:
        bad.append("info takes one DEM")
        argv = ["info"] + dems
    as_json = draw(st.booleans())
    if as_json:
        argv.append("--json")
    preview = None
    if often(draw, 5):
        preview = "p.png"
        argv += ["--preview", OUT + preview]
    dopt, dbad = draw(dem_options(georef, raw, wild))
    argv += dem_extra + dopt
    return Case("info", argv, files, recipe, bad + dbad, shape, "info", None, [], None, preview,
                info_json=as_json)


_BUILDERS = {"shadow": _lighting_case, "hillshade": _lighting_case, "info": _info_case, "horizon": _horizon_case, "sun-hours": _sun_hours_case}


@st.composite
def cases(draw, kinds, weights=(5, 2, 3, 1, 1), wild=0.5):
    """Any command on an input of ``kinds``; ``weights``: shadow, hillshade, info, horizon,
    sun-hours; ``wild``: the share of cases whose options may be malformed (the others have
    well-formed options only, so that the input decides)."""
    names = [n for n, w in zip(_BUILDERS, weights) for _ in range(w)]
    command = draw(st.sampled_from(names))
    is_wild = draw(st.floats(0, 1)) < wild
    inp = draw(input_file(kinds))
    if command in ("shadow", "hillshade"):
        return _lighting_case(draw, command, inp, is_wild)
    return _BUILDERS[command](draw, inp, is_wild)


# ---------------------------------------------------------------------------------------------
# running a case and judging its outcome

@contextlib.contextmanager
def _fd2_captured(sink: list):
    """Whatever is written to file descriptor 2 (C libraries such as GDAL) while inside."""
    sys.stderr.flush()
    with tempfile.TemporaryFile() as tmp:
        saved = os.dup(2)
        os.dup2(tmp.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            sink.append(tmp.read().decode("utf-8", "replace"))


def _show_on_stderr(message, category, filename, lineno, file=None, line=None):
    sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


@contextlib.contextmanager
def _like_a_fresh_process():
    """Warnings and log records reach stderr as they would in ``hillshade-rt`` run from a shell
    (pytest would otherwise collect them silently); numba's thread count restored afterwards."""
    import numba
    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    root.handlers = []
    root.setLevel(logging.WARNING)
    try:
        with warnings.catch_warnings():
            warnings.resetwarnings()
            warnings.simplefilter("default")
            for cat in (DeprecationWarning, PendingDeprecationWarning, ImportWarning,
                        ResourceWarning):
                warnings.simplefilter("ignore", cat)
            warnings.showwarning = _show_on_stderr
            yield
    finally:
        root.handlers, root.level = handlers, level
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)


def _tree(folder) -> dict[str, int]:
    out = {}
    for dirpath, dirnames, filenames in os.walk(folder):
        for n in dirnames + filenames:
            p = os.path.join(dirpath, n)
            out[os.path.relpath(p, folder)] = os.path.getsize(p) if os.path.isfile(p) else -1
    return out


def _open_raster(path):
    import rasterio
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with rasterio.open(path) as ds:
            return ds.driver, ds.count, ds.shape, ds.dtypes, ds.read()


def _input_shape(case, in_dir):
    """The input's shape: known from the recipe, else what rasterio reads of a damaged file."""
    if case.shape is not None:
        return case.shape
    names = [a[len(IN):] for a in case.argv if a.startswith(IN)]
    if len(names) != 1:
        return None
    try:
        return _open_raster(os.path.join(in_dir, names[0]))[2]
    except Exception:  # noqa: BLE001 -- unknown: not checked
        return None


_RANGES = {  # product: (dtype, test of the values)
    "shadow": ("uint8", lambda v: np.isin(v, [0, 1, 255]).all()),
    "classes": ("uint8", lambda v: np.isin(v, [0, 1, 2, 255]).all()),
    "soft": ("float32", lambda v: (((v >= 0) & (v <= 1)) | (v == -9999)).all()),
    "hillshade": ("uint8", lambda v: True),
    "horizon": ("float32", lambda v: (((v >= -90) & (v <= 90)) | (v == -9999)).all()),
    "sun-hours": ("float32", lambda v: (((v >= 0) & (v <= 25.0)) | (v == -9999)).all()),
}


def _check_success(case, r, in_dir, out_dir, new_out) -> list[str]:
    bad = []
    expected = set(case.outputs) | {p for p in (case.report, case.preview) if p}
    if set(new_out) != expected:
        bad.append(f"exit 0: files in the output folder {sorted(new_out)}, expected "
                   f"{sorted(expected)}")
    shape = _input_shape(case, in_dir)
    for name in case.outputs:
        path = os.path.join(out_dir, name)
        if not os.path.exists(path):
            continue
        try:
            driver, count, oshape, dtypes, values = _open_raster(path)
        except Exception as exc:  # noqa: BLE001
            bad.append(f"exit 0 but {name} does not open: {type(exc).__name__}: {exc}")
            continue
        dtype, in_range = _RANGES[case.product]
        if driver != "GTiff":
            bad.append(f"{name}: driver {driver}, expected GTiff")
        if set(dtypes) != {dtype}:
            bad.append(f"{name}: dtype {dtypes}, expected {dtype}")
        if shape is not None and tuple(oshape) != tuple(shape):
            bad.append(f"{name}: shape {oshape}, the input's is {shape}")
        if case.bands is not None and count != case.bands:
            bad.append(f"{name}: {count} bands, expected {case.bands}")
        if not in_range(values):
            vals = np.unique(values)
            bad.append(f"{name}: values outside the {case.product} range: "
                       f"{vals[:8].tolist()}{' ...' if vals.size > 8 else ''}")
    if case.report and os.path.exists(os.path.join(out_dir, case.report)):
        try:
            with open(os.path.join(out_dir, case.report), encoding="utf-8") as fh:
                json.load(fh)
        except ValueError as exc:
            bad.append(f"the report is not JSON: {exc}")
    if case.preview and os.path.exists(os.path.join(out_dir, case.preview)):
        try:
            driver, count, _, dtypes, _ = _open_raster(os.path.join(out_dir, case.preview))
            if driver != "PNG" or count not in (3, 4) or set(dtypes) != {"uint8"}:
                bad.append(f"the preview is {driver} with {count} bands {dtypes}")
        except Exception as exc:  # noqa: BLE001
            bad.append(f"the preview does not open: {type(exc).__name__}: {exc}")
    if case.command == "info":
        if not r.stdout.strip():
            bad.append("info: exit 0 and nothing on stdout")
        elif case.info_json:
            try:
                doc = json.loads(r.stdout)
                if shape is not None and tuple(doc["shape"]) != tuple(shape):
                    bad.append(f"info --json: shape {doc['shape']}, the input's is {shape}")
            except (ValueError, KeyError, TypeError) as exc:
                bad.append(f"info --json: not the JSON document ({exc})")
    return bad


@contextlib.contextmanager
def _invoked(case: Case, env: dict | None = None, before=None):
    """``case`` run through the CLI in a temporary folder (its side files in ``in/``, outputs
    to ``out/``): yields (result, stderr, in_dir, out_dir, new files in out/, new files in in/,
    seconds), the folder still there. ``before(tmp, env)``: set up ``env`` inside the folder."""
    import time

    from click.testing import CliRunner

    from hillshade_rt.cli import cli

    with tempfile.TemporaryDirectory(prefix="hsfuzz-") as tmp:
        in_dir, out_dir = os.path.join(tmp, "in"), os.path.join(tmp, "out")
        os.mkdir(in_dir)
        os.mkdir(out_dir)
        for name, data in case.files.items():
            with open(os.path.join(in_dir, name), "wb") as fh:
                fh.write(data)
        before_in = _tree(in_dir)
        argv = [a.replace(IN, in_dir + os.sep).replace(OUT, out_dir + os.sep) for a in case.argv]
        env = dict(env or {})
        if before is not None:
            before(tmp, env)
        fd2: list[str] = []
        t0 = time.monotonic()
        with _like_a_fresh_process(), _fd2_captured(fd2):
            r = CliRunner(env=env).invoke(cli, argv, prog_name="hillshade-rt")
        took = time.monotonic() - t0
        stderr = r.stderr + fd2[0]
        new_out = sorted(_tree(out_dir))
        new_in = sorted(set(_tree(in_dir)) - set(before_in))
        yield r, stderr, in_dir, out_dir, new_out, new_in, took


def _violations_of_any_run(r, stderr, new_in) -> list[str]:
    """What no run may do: raise, print a traceback or an internal error, write beside its
    inputs."""
    bad = []
    if r.exception is not None and not isinstance(r.exception, SystemExit):
        import traceback
        tb = "".join(traceback.format_exception(r.exception)).strip().splitlines()
        bad.append(f"exception {type(r.exception).__name__}: {r.exception} "
                   f"(raised at {tb[-3].strip() if len(tb) > 2 else '?'})")
    if "Traceback" in stderr or "Traceback" in r.stdout:
        bad.append("a traceback printed")
    if "internal error" in stderr:   # a bug, reported in one line (HILLSHADE_RT_DEBUG=1)
        bad.append(f"an internal error: {stderr.strip().splitlines()[-1]}")
    if new_in:
        bad.append(f"new files beside the input: {new_in}")
    return bad


def _violations_of_a_failure(r, stderr, new_out) -> list[str]:
    """A failed run: one error line, nothing new in the output folder."""
    bad = []
    lines = stderr.strip().splitlines()
    if len(lines) != 1 or not lines[0].startswith("hillshade-rt: error:"):
        bad.append(f"stderr is not one error line: {stderr.strip()[:1000]!r}")
    if new_out:
        bad.append(f"exit {r.exit_code} but new files in the output folder: {new_out}")
    return bad


def _collect(case, r, stderr, bad, in_dir, *outcome) -> None:
    """With HILLSHADE_FUZZ_COLLECT: the case's violations and outcome written down."""
    if bad:
        _record(case, r, stderr, bad, in_dir)
    os.makedirs(_COLLECT, exist_ok=True)
    with open(os.path.join(_COLLECT, "outcomes.jsonl"), "a", encoding="utf-8") as fh:
        fh.write(json.dumps([case.command, r.exit_code, *outcome,
                             (stderr.strip().splitlines() or [""])[-1][:200]]) + "\n")


def _assert_no_violation(case, bad, r, stderr) -> None:
    if _COLLECT:
        return
    assert not bad, (f"\n{case.shell()}\ninput: {'; '.join(case.recipe)}\nexit {r.exit_code}\n"
                     f"stderr: {stderr.strip()[:2000]}\nviolations:\n  " + "\n  ".join(bad))


def run_case(case: Case) -> list[str]:
    """Run ``case`` through the CLI; the list of ways its outcome breaks the property."""
    with _invoked(case) as (r, stderr, in_dir, out_dir, new_out, new_in, _):
        bad = _violations_of_any_run(r, stderr, new_in)
        if r.exit_code == 0:
            bad += _check_success(case, r, in_dir, out_dir, new_out)
            if case.malformed:
                bad.append(f"exit 0 although the command line is malformed: {case.malformed}")
        else:
            if r.exit_code not in (1, 2):
                bad.append(f"exit status {r.exit_code}")
            bad += _violations_of_a_failure(r, stderr, new_out)
            if case.malformed and r.exit_code != 2:
                bad.append(f"exit {r.exit_code} for a malformed command line "
                           f"({'; '.join(case.malformed)}), expected 2")
        if _COLLECT:
            _collect(case, r, stderr, bad, in_dir)
        return bad, r, stderr


_RECORDED = [0]


def _record(case, r, stderr, bad, in_dir):
    os.makedirs(_COLLECT, exist_ok=True)
    _RECORDED[0] += 1
    n = f"{os.getpid()}-{_RECORDED[0]}"
    keep = os.path.join(_COLLECT, "inputs", n)
    shutil.copytree(in_dir, keep)
    with open(os.path.join(_COLLECT, "violations.jsonl"), "a", encoding="utf-8") as fh:
        fh.write(json.dumps({"id": n, "command": case.command, "shell": case.shell(),
                             "argv": case.argv, "recipe": case.recipe,
                             "malformed": case.malformed, "exit": r.exit_code,
                             "stderr": stderr[-3000:], "violations": bad,
                             "exception": type(r.exception).__name__ if r.exception else None})
                 + "\n")


def check(case: Case):
    bad, r, stderr = run_case(case)
    _assert_no_violation(case, bad, r, stderr)


# ---------------------------------------------------------------------------------------------
# the tests

@_settings(120, 0.4)
@given(case=cases(("damaged",), weights=(5, 2, 4, 1, 1), wild=0.2))
def test_fuzz_damaged_inputs(case):
    """Random bytes, truncated and overwritten rasters, with sane or random options."""
    check(case)


@_settings(80, 0.25)
@given(case=cases(("raw",), weights=(4, 1, 3, 1, 1), wild=0.2))
def test_fuzz_raw_grids(case):
    """Raw grids and .hgt tiles with random --raw-shape/--raw-dtype/--raw-byteorder."""
    check(case)


@_settings(120, 0.35)
@given(case=cases(("real",), wild=0.5))
def test_fuzz_options(case):
    """Real small rasters (GeoTIFF in several CRSs and types, PNG, two-tile mosaics) with random
    option values for every command."""
    check(case)


def test_fuzz_harness_sees_a_traceback_and_leftovers(monkeypatch):
    """The judge itself: a crash inside a run, and a part file left behind, are both caught."""
    from hillshade_rt.errors import HillshadeError
    from hillshade_rt.run import local as run_local
    data = raster_bytes("GTiff", 12, 12, "float32", "utm", None, 0, 0.0, 1, None)
    case = Case("shadow", ["shadow", IN + "dem.tif", OUT + "o.tif", "--azimuth", "10",
                           "--elevation", "20"], {"dem.tif": data}, ["a valid GeoTIFF"],
                shape=(12, 12), product="shadow", outputs=["o.tif"])
    assert run_case(case)[0] == []

    def boom(*a, **k):
        raise ZeroDivisionError("planted")
    monkeypatch.setattr(run_local, "shade_in_memory", boom)
    bad = run_case(case)[0]
    assert any("ZeroDivisionError" in b for b in bad), bad

    def leave_part(inputs, *a, **k):
        out_dir = os.path.dirname(a[3].output)
        open(os.path.join(out_dir, ".o.tif.x.part.tif"), "wb").close()
        raise HillshadeError("planted")
    monkeypatch.setattr(run_local, "shade_in_memory", leave_part)
    bad = run_case(case)[0]
    assert any("new files in the output folder" in b for b in bad), bad


# ---------------------------------------------------------------------------------------------
# every command: random option sets from a table of each command's options, on small real or
# damaged rasters; judged by the generic property (an exit status of 0/1/2/130/143, one line on
# an error, no traceback, nothing half-written, no output unless exit 0, a bounded run time)

_RUN_BOUND_S = 120.0      # one run's wall time at most (the slowest draw takes a few seconds)
_BAD_NUM = ["nan", "inf", "-1", "0", "abc", "", "1e400"]
_SUBSOLAR_CSV = {
    "good": b"time,lat,lon\n2027-01-01T00:00Z,1.2,-35.2\n2027-01-01T06:00Z,1.2,-38.3\n"
            b"2027-01-01T12:00Z,1.2,-41.3\n",
    "au": b"time,lat,lon,distance_au\n2027-01-01T00:00Z,1.2,-35.2,0.98\n"
          b"2027-01-01T06:00Z,1.2,-38.3,0.98\n",
    "decreasing": b"time,lat,lon\n2027-01-02T00:00Z,1.2,-35.2\n2027-01-01T06:00Z,1.2,-38.3\n",
    "no-offset": b"time,lat,lon\n2027-01-01T00:00,1.2,-35.2\n2027-01-01T06:00,1.2,-38.3\n",
    "bad-lat": b"time,lat,lon\n2027-01-01T00:00Z,95,-35.2\n2027-01-01T06:00Z,nan,-38.3\n",
    "header-only": b"time,lat,lon\n",
    "empty": b"",
    "garbage": b"\x00\xff\xfe not a csv at all,,,\n\n",
    "one-row": b"time,lat,lon\n2027-01-01T00:00Z,1.2,-35.2\n",
}
_GHI_CSV = {
    "good": b"time,ghi\n2026-06-21T00:00Z,0\n2026-06-21T12:00Z,900\n2026-06-22T00:00Z,0\n",
    "dni-dhi": b"time,ghi,dni,dhi\n2026-06-21T00:00Z,0,0,0\n2026-06-22T00:00Z,500,600,100\n",
    "negative": b"time,ghi\n2026-06-21T00:00Z,-5\n2026-06-22T00:00Z,nan\n",
    "no-ghi": b"time,x\n2026-06-21T00:00Z,1\n",
    "garbage": b"\xff\xfe\x00,;\n",
    "empty": b"",
}
_POINTS = {
    "lonlat.csv": b"id,lon,lat\na,-118.1,34.3\nb,-84.0,36.49\n",
    "xy.csv": b"name,x,y\np,400300,3799700\n",
    "bad.csv": b"lon,lat\nabc,def\n",
    "empty.csv": b"",
    "points.geojson": b'{"type":"FeatureCollection","features":[{"type":"Feature","geometry":'
                      b'{"type":"Point","coordinates":[-84.0,36.49]},"properties":{}}]}',
    "bad.geojson": b'{"type":"FeatureCollection","features":[{"geometry":null}]}',
    "broken.geojson": b"{not json",
}
# irradiance's sky inputs as rasters (IN + "sky_<kind>.tif", or a pattern with {month} naming
# 12 of them): on the DEM's grid, values from low to high across it (out of range for another
# kind's option); a damaged DEM's on a UTM grid of its own
_SKY_RASTERS = {"albedo": (0.1, 0.6), "linke": (2.2, 5.3), "kb": (0.35, 0.9),
                "kd": (0.95, 0.45), "svf": (0.5, 1.0)}
_MONTHLY12 = {"linke": "2.1,2.4,2.9,3.3,3.5,3.6,3.7,3.6,3.2,2.8,2.4,2.1",
              "albedo": "0.2,0.2,0.18,0.15,0.15,0.15,0.15,0.15,0.15,0.15,0.18,0.6",
              "index": "0.5,0.55,0.6,0.65,0.7,0.75,0.8,0.75,0.7,0.6,0.5,0.45"}


def _sky_file(kind: str, month=None):
    """IN + a sky raster's name (``month``: a pattern's format, ``{month}`` or
    ``{month:02d}``)."""
    return IN + f"sky_{kind}" + (f"_{month}" if month else "") + ".tif"


@functools.lru_cache(maxsize=64)
def sky_raster_bytes(dem: bytes, kind: str, month: int = 0) -> bytes:
    """A float64 sky raster of ``kind`` (``_SKY_RASTERS``) on ``dem``'s grid (or, when that does
    not open, on a 40 x 40 UTM grid), a month's shifted a little."""
    import rasterio
    from affine import Affine
    from rasterio.io import MemoryFile
    low, high = _SKY_RASTERS[kind]
    prof = dict(driver="GTiff", width=40, height=40, crs="EPSG:32611",
                transform=Affine(*_GEO["utm"][0]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            with MemoryFile(dem) as mf, mf.open() as src:
                prof = dict(driver="GTiff", width=src.width, height=src.height, crs=src.crs,
                            transform=src.transform)
        except Exception:  # noqa: BLE001 -- a damaged DEM: a grid of its own
            pass
        y, x = np.mgrid[0:prof["height"], 0:prof["width"]]
        t = (x + 2 * y) / max(1, prof["width"] + 2 * prof["height"] - 3)
        z = low + (high - low) * t * (1 - 0.02 * month)
        with MemoryFile() as mf:
            with mf.open(count=1, dtype="float64", **prof) as dst:
                dst.write(z, 1)
            return bytes(mf.read())


def _sky_files(name: str, dem: bytes) -> dict[str, bytes]:
    """The file(s) a sky option's value ``name`` (in IN) stands for: one raster, or the 12 of
    a {month} pattern."""
    m = re.fullmatch(r"sky_([a-z]+)(?:_(\{month(?::02d)?\}))?\.tif", name)
    if m is None or m.group(1) not in _SKY_RASTERS:
        return {}
    if m.group(2) is None:
        return {name: sky_raster_bytes(dem, m.group(1))}
    return {name.replace(m.group(2), m.group(2).format(month=k)):
            sky_raster_bytes(dem, m.group(1), k) for k in range(1, 13)}


_TIME_VALUES = _TIMES + _LOCAL_TIMES + _BAD_TIMES
_DATES = ["2026-06-21", "2026-12-21", "2026-03-29", "21/06/2026", "", "2026-02-30", "0001-01-01",
          "9999-12-31", "2026-06-21T12:00"]
_STEPS = ["1h", "2h", "90min", "6h", "PT20M", "0s", "abc", "-5min", "1 fortnight", "1e9h", "1s"]


def _v(good, bad=()):
    """An option's values: (well-formed ones, malformed ones)."""
    return (list(good), list(bad))


_SUN_TABLE = [
    (["--azimuth"], _v(["203.7", "0", "-720", "1e300"], ["nan", "west"]), 15),
    (["--elevation"], _v(["12", "45", "90", "1e-300"], ["0", "-5", "91", "nan"]), 15),
    (["--time"], _v(_TIMES, _LOCAL_TIMES + _BAD_TIMES), 15),
    (["--tz"], _v(_ZONES + ["auto"], _BAD_ZONES), 5),
    (["--lat"], _v(["36.3", "-89.9", "90"], ["95", "nan"]), 10),
    (["--lon"], _v(["-84.1", "200"], ["nan"]), 10),
    (["--pressure"], _v(["1013", "600"], ["0", "-5", "nan", "1e9"]), 10),
    (["--temperature"], _v(["12", "-40"], ["-300", "nan", "1e9"]), 10),
    (["--no-refraction"], None, 10),
    (["--sun-tolerance"], _v(["0.05", "1e-9", "5"], ["0", "-1", "nan"]), 10),
]
_READ_TABLE = [
    (["--band"], _v(["1"], ["2", "0", "x"]), 12),
    (["--nodata"], _v(["-9999", "nan", "0"], ["none", "1e40"]), 10),
    (["-z"], _v(["0.3048", "-1", "1e30"], ["0", "nan"]), 10),
    (["--pixel-size"], _v(["30", "1,2"], ["0", "-1", "nan", "abc", "30,0"]), 10),
]
_OUT_TABLE = [
    (["--preview"], _v([OUT + "p.png"]), 6),
    (["--report"], _v([OUT + "r.json"]), 6),
    (["-q"], None, 2),
    (["--overwrite"], None, 8),
    (["--threads"], _v(["1", "2"], ["0"]), 10),
    (["--co"], _v(["COMPRESS=ZSTD", "FOO=1"], ["FOO", "=1"]), 12),
    (["-f"], _v(["GTiff", "PNG"], ["NOPE", "MEM"]), 12),
]
_PHYS_TABLE = [
    (["--earth-curvature", "--no-earth-curvature"], None, 10),
    (["--refraction-coefficient"], _v(["0.13", "0", "-1", "2"], ["nan"]), 12),
]
_POINT_TABLE = [
    (["--at"], _v(["-118.1,34.3", "-84.0,36.49", "0,0"], ["200,95", "abc", "1,2,3", "nan,nan"]),
     5),
    (["--at-xy"], _v(["@CENTRE", "400300,3799700", "0,0"], ["x,y", "inf,1"]), 5),
    (["--points"], _v([IN + n for n in _POINTS], [IN + "missing.csv"]), 5),
    (["--height-above-ground"], _v(["0", "1.7", "1e9"], ["-1", "nan"]), 6),
]
_SERIES = ["--start", "2026-06-21T18:00Z", "--end", "2026-06-21T19:00Z", "--step", "30min"]
# command -> (positional arguments, base option sets (one drawn: a well-formed run), table of
# other options: (flags, values or None for a flag, 1 / the share of draws that add it))
_COMMANDS = {
    "shadow": (["DEM", "OUT"], [["--azimuth", "203.7", "--elevation", "12"],
                                ["--time", "2026-06-21T18:00Z"], _SERIES],
               _SUN_TABLE + _READ_TABLE + _OUT_TABLE + _PHYS_TABLE + [
        (["--algorithm"], _v(["auto", "smap", "brute", "bounds", "horizon", "sweep"], ["quick"]),
         4),
        (["--soft"], None, 6), (["--classes"], None, 6), (["--self-shadow"], None, 6),
        (["--height-above-ground"], _v(["0", "2"], ["-1", "nan"]), 8),
        (["--nextv"], _v(["scan", "quad", "binary"]), 12),
        (["--exact-steps"], _v(["1", "4"], ["0"]), 12),
        (["--sample-spacing"], _v(["1", "3"], ["0"]), 12), (["--no-pyramid"], None, 12),
        (["--window-size"], _v(["64", "64x80"], ["0", "abc", "8"]), 8),
        (["--max-memory"], _v(["4GB", "1kB"], ["0", "abc"]), 10),
        (["--light-position"], _v(["400300,3799700,900"], ["1,2", "nan,1,2"]), 12),
        (["--subsolar"], _v(["10,20", "-30,100"], ["95,0", "abc"]), 12),
        (["--body"], _v(["moon", "mars", "earth", "1000"], ["-1", "pluto"]), 14),
        (["--output-pattern"], _v([OUT + "o_{index}.tif"], [OUT + "o_{nope}.tif"]), 12),
        (["--cog"], None, 12),
        (["--vector"], _v([OUT + "s.gpkg", OUT + "s.geojson", OUT + "s.fgb"],
                          [OUT + "s.shp", OUT + "s.txt"]), 8),
        (["--vector-connectivity"], _v(["4", "8"], ["6"]), 10),
    ]),
    "hillshade": (["DEM", "OUT"], [[], ["--azimuth", "315", "--elevation", "45"],
                                   ["--time", "2026-06-21T18:00Z"]],
                  _SUN_TABLE + _READ_TABLE + _OUT_TABLE + _PHYS_TABLE + [
        (["--ambient"], _v(["0", "0.5", "1"], ["1.5", "nan"]), 6),
        (["-s"], _v(["1", "111120"], ["0", "nan"]), 8),
        (["--soft"], None, 6),
        (["--light-position"], _v(["400300,3799700,900"], ["1,2"]), 12),
        (["--falloff"], _v(["none", "inverse-square"]), 12), (["--bits"], _v(["8", "16"]), 12),
    ]),
    "sun-hours": (["DEM", "OUT"], [["--date", "2026-06-21", "--step", "2h"]],
                  _READ_TABLE + _OUT_TABLE[:4] + _PHYS_TABLE + _SUN_TABLE[3:] + [
        (["--date"], _v(["2026-12-21", "2026-03-29"], _DATES[3:]), 6),
        (["--end-date"], _v(["2026-06-22"], ["2026-06-20", "abc"]), 8),
        (["--step"], _v(["3h", "90min", "PT20M"], ["0s", "abc", "-5min", "1 fortnight"]), 6),
        (["--soft"], None, 6), (["--no-self-shadow"], None, 6),
        (["--height-above-ground"], _v(["0", "2"], ["-1"]), 8),
        (["--window-size"], _v(["64", "64x80"], ["0", "8"]), 8),
        (["--monthly"], None, 6),
    ]),
    "horizon": (["DEM", "OUT"], [["--azimuth", "163"], ["--directions", "8"],
                                 ["--step", "45"]],
                _READ_TABLE + _OUT_TABLE[:1] + _OUT_TABLE[2:4] + _PHYS_TABLE + [
        (["--azimuth"], _v(["-720", "1e300"], ["nan", "north"]), 8),
        (["--distance"], _v([OUT + "d.tif"]), 6),
        (["--max-distance"], _v(["100", "1e9"], ["0", "-1", "nan"]), 6),
        (["--method"], _v(["scan", "hull"]), 4), (["--sample-spacing"], _v(["1", "3"], ["0"]), 6),
        (["--height-above-ground"], _v(["0", "2"], ["-1"]), 8),
        (["--window-size"], _v(["64", "64x80"], ["0", "8"]), 8),
        (["--start"], _v(["10", "-30", "350.5"], ["nan", "east"]), 6),
        (["--end"], _v(["200", "370"], ["nan", "1e9"]), 6),
        (["--step"], _v(["30", "90"], ["0", "-5", "nan"]), 8),
        (["--angle-unit"], _v(["degrees", "radians"], ["grads"]), 6),
    ]),
    "skyview": (["DEM", "OUT"], [["--directions", "8"], ["--directions", "4"]],
                _READ_TABLE + _OUT_TABLE[:1] + _OUT_TABLE[2:4] + _PHYS_TABLE + [
        (["--directions"], _v(["16"], ["3", "0", "1000"]), 8),
        (["--definition"], _v(["zaksek", "dozier"], ["other"]), 4),
        (["--terrain-configuration"], None, 6),
        (["--openness"], _v(["positive", "negative"]), 6),
        (["--max-distance"], _v(["100", "1e9"], ["0", "nan"]), 6),
        (["--height-above-ground"], _v(["0", "2"], ["-1"]), 8),
        (["--window-size"], _v(["64", "64x80"], ["0", "8"]), 8),
    ]),
    "irradiance": (["DEM", "OUT"], [["--date", "2026-06-21", "--step", "3h",
                                     "--skyview-directions", "4"],
                                    ["--start", "2026-06-21T06:00Z", "--end",
                                     "2026-06-21T12:00Z", "--step", "2h",
                                     "--skyview-directions", "4"]],
                   _READ_TABLE + _OUT_TABLE + _PHYS_TABLE + _SUN_TABLE[3:] + [
        (["--date"], _v(["2026-12-21"], _DATES[3:]), 10),
        (["--end-date"], _v(["2026-06-22"], ["2026-06-20", "abc"]), 8),
        (["--step"], _v(["4h"], ["0s", "abc", "-5min"]), 8),
        (["--clear-sky"], _v(["ineichen", "haurwitz"]), 6),
        (["--linke-turbidity"], _v(["3", _MONTHLY12["linke"], _sky_file("linke"),
                                    _sky_file("linke", "{month:02d}")],
                                   ["0", "-1", "nan", "1e9", "3,4", _sky_file("albedo"),
                                    _sky_file("kb", "{moon}"), IN + "missing.tif"]), 6),
        (["--albedo"], _v(["0.2", "0", "1", _MONTHLY12["albedo"], _sky_file("albedo"),
                           _sky_file("albedo", "{month}")],
                          ["-0.5", "2", "nan", "0.1,0.2", _sky_file("linke")]), 6),
        (["--beam-index"], _v(["0.7", "0", "1", _MONTHLY12["index"], _sky_file("kb"),
                               _sky_file("kb", "{month:02d}")],
                              ["-0.1", "1.5", "nan", _sky_file("linke")]), 6),
        (["--diffuse-index"], _v(["0.4", "1", _MONTHLY12["index"], _sky_file("kd"),
                                  _sky_file("kd", "{month}")],
                                 ["2", "nan", "0.5,0.5", _sky_file("linke")]), 6),
        (["--ghi"], _v([IN + "ghi_" + n + ".csv" for n in _GHI_CSV], [IN + "missing.csv"]), 5),
        (["--mean"], None, 6), (["--perez"], None, 6), (["--soft"], None, 8),
        (["--daily-mean"], None, 7), (["--monthly"], None, 6),
        (["--time"], _v(_TIMES[:3], _BAD_TIMES[:3] + _LOCAL_TIMES[:1]), 10),
        (["--instant"], None, 10),
        (["--sky-view"], _v([_sky_file("svf")], [IN + "missing.tif", _sky_file("linke")]), 10),
        (["--sky-view-out"], _v([OUT + "svf.tif"], [OUT + "o.tif"]), 10),
        (["--skyview-directions"], _v(["8"], ["3", "0"]), 8),
        (["--algorithm"], _v(["auto", "smap", "brute"]), 8),
        (["--window-size"], _v(["64", "64x80"], ["0", "8"]), 8),
    ]),
    "query": (["DEM"], [["--at-xy", "@CENTRE", "--azimuth", "203.7", "--elevation", "12"],
                        ["--at-xy", "@CENTRE", "--time", "2026-06-21T18:00Z"],
                        ["--at", "-84.0,36.49"] + _SERIES],
              _SUN_TABLE + _READ_TABLE[:3] + _POINT_TABLE + _PHYS_TABLE + [
        (["--irradiance"], None, 6),
        (["--format"], _v(["csv", "json", "geojson"]), 4),
        (["-o"], _v([OUT + "q.csv", OUT + "q.json", OUT + "q.geojson", OUT + "q.txt"]), 3),
        (["--light-position"], _v(["400300,3799700,900"], ["1,2"]), 12),
    ]),
    "profile": (["DEM"], [["--at-xy", "@CENTRE", "--step", "10"], ["--at", "-84.0,36.49"]],
                _READ_TABLE[:3] + _POINT_TABLE + _PHYS_TABLE + [
        (["--step"], _v(["1", "45", "0.5"], ["0", "-1", "nan", "400"]), 3),
        (["--format"], _v(["csv", "json", "pvlib", "pvgis", "grass", "geojson"]), 3),
        (["-o"], _v([OUT + "h.csv", OUT + "h.json"]), 3),
        (["--preview"], _v([OUT + "p.png"]), 8),
    ]),
    "illumination": (["DEM", "OUT"], [["--subsolar-file", IN + "sun_good.csv", "--body", "moon"],
                                      ["--subsolar-file", IN + "sun_au.csv"]],
                     _READ_TABLE + _OUT_TABLE + _PHYS_TABLE + [
        (["--subsolar-file"], _v([IN + "sun_" + n + ".csv" for n in _SUBSOLAR_CSV],
                                 [IN + "missing.csv"]), 4),
        (["--sun-distance"], _v(["1.5e11"], ["0", "-1", "nan"]), 8),
        (["--body"], _v(["moon", "mars", "earth", "1737400"], ["-1", "pluto"]), 5),
        (["--height-above-ground"], _v(["0", "2"], ["-1"]), 8),
        (["--soft"], None, 6),
        (["--window-size"], _v(["64", "64x80"], ["0", "8"]), 8),
    ]),
    "animate": (["DEM", "OUT:a.gif"], [["--date", "2026-06-21", "--step", "3h", "--size", "16"],
                                       ["--start", "2026-06-21T18:00Z", "--end",
                                        "2026-06-21T20:00Z", "--step", "1h", "--size", "16"]],
                _READ_TABLE + _OUT_TABLE[1:4] + _PHYS_TABLE + _SUN_TABLE[3:] + [
        (["--date"], _v(["2026-12-21"], _DATES[3:]), 10),
        (["--step"], _v(["2h", "4h"], ["0s", "abc"]), 8),
        (["--fps"], _v(["12", "50"], ["0", "-1", "51", "nan"]), 6),
        (["--size"], _v(["20", "64"], ["15", "0"]), 6),
        (["--no-label"], None, 6),
        (["--algorithm"], _v(["auto", "smap", "brute"]), 8),
    ]),
    "info": (["DEM"], [[], ["--json"]], _READ_TABLE + [
        (["--preview"], _v([OUT + "p.png"]), 6), (["--overwrite"], None, 8),
    ]),
    "cache": ([], [[], ["--prune"]], []),
}


_OTHER_SUNS = {"--azimuth", "--elevation", "--time", "--light-position", "--subsolar", "--body"}
_TIMED = {"--tz", "--lat", "--lon", "--pressure", "--temperature", "--no-refraction"}


@st.composite
def command_case(draw, command):
    """A Case of ``command``: one of its well-formed base option sets, random others of its
    options (in wild cases now and then malformed values, or an unknown option), on a small
    raster (real, now and then damaged), with the side files its options name. The choices
    come from a generator seeded by hypothesis (reproducible with derandomize): its own draws
    lean toward the first values, which would put every option in every case."""
    import random
    rng = random.Random(draw(st.integers(0, 2 ** 32 - 1)))
    positional, bases, table = _COMMANDS[command]
    wild = rng.random() < 0.35
    files: dict[str, bytes] = {}
    recipe = []
    argv = [command]
    centre = "1,1"
    if "DEM" in positional:
        if rng.random() < 0.2:
            data, r, _, _, ext = draw(damaged_input())
        else:
            data, r, shape, _, ext = draw(real_raster("GTiff"))
            centre = f"{400000 + 15 * shape[1]},{3800000 - 15 * shape[0]}"
        files["dem" + ext] = data
        recipe.append(r)
        argv.append(IN + "dem" + ext)
    for p in positional:
        if p.startswith("OUT"):
            argv.append(OUT + (p.split(":")[1] if ":" in p else "o.tif"))
    argv += rng.choice(bases)
    base = set(argv)
    for flags, values, share in table:
        if rng.random() >= 1.0 / share:
            continue
        flag = rng.choice(flags)
        if not wild and command in ("shadow", "hillshade", "query") and (
                flag in _OTHER_SUNS or flag in _TIMED and "--azimuth" in base):
            continue          # well-formed cases: one sun, the base's
        if values is None:
            argv.append(flag)
            continue
        good, bad = values
        pool = bad if wild and bad and rng.random() < 0.5 else good
        argv += [flag, rng.choice(pool)]
    if wild and rng.random() < 0.15:     # an unknown option, now and then
        argv.append(rng.choice(["--frobnicate", "-Z", "--elevation="]))
    argv = [a.replace("@CENTRE", centre) for a in argv]
    dem = next(iter(files.values()), b"")
    for a in argv:
        name = a[len(IN):] if a.startswith(IN) else None
        if name and name.startswith("sky_"):
            files.update(_sky_files(name, dem))
        if name in _POINTS:
            files[name] = _POINTS[name]
        elif name and name.startswith("sun_") and name[4:-4] in _SUBSOLAR_CSV:
            files[name] = _SUBSOLAR_CSV[name[4:-4]]
        elif name and name.startswith("ghi_") and name[4:-4] in _GHI_CSV:
            files[name] = _GHI_CSV[name[4:-4]]
    return Case(command, argv, files, recipe)


_LEFTOVER = re.compile(r"\.part|\.scratch|\.tmp", re.I)


def _cache_folders(case: Case):
    """The cache command looks at (and --prune empties) a folder of this run, never the
    user's kernel cache; the --context statistics stay in the run's folder too."""
    def before(tmp, env):
        env["HILLSHADE_RT_STATS_DIR"] = os.path.join(tmp, "stats")
        if case.command == "cache":
            env["NUMBA_CACHE_DIR"] = os.path.join(tmp, "numba")
            os.makedirs(os.path.join(tmp, "numba", "0123456789abcdef"))
    return before


def run_generic(case: Case) -> list[str]:
    """Run ``case``; the ways its outcome breaks the generic property."""
    with _invoked(case, before=_cache_folders(case)) as (r, stderr, in_dir, _, new_out, new_in,
                                                         took):
        bad = _violations_of_any_run(r, stderr, new_in)
        if any(_LEFTOVER.search(n) for n in new_out):
            bad.append(f"half-written files left: {new_out}")
        if took > _RUN_BOUND_S:
            bad.append(f"the run took {took:.0f} s (bound {_RUN_BOUND_S:.0f} s)")
        if r.exit_code not in (0, 1, 2, 130, 143):
            bad.append(f"exit status {r.exit_code}")
        if r.exit_code != 0:
            bad += _violations_of_a_failure(r, stderr, new_out)
        if _COLLECT:
            _collect(case, r, stderr, bad, in_dir, round(took, 2), case.shell())
        return bad, r, stderr


def check_generic(case: Case):
    bad, r, stderr = run_generic(case)
    _assert_no_violation(case, bad, r, stderr)


_GENERIC_EXAMPLES = {"shadow": 50, "hillshade": 30, "sun-hours": 25, "horizon": 30,
                     "skyview": 25, "irradiance": 25, "query": 40, "profile": 30,
                     "illumination": 30, "animate": 20, "info": 20, "cache": 4}


@pytest.mark.parametrize("command", sorted(_GENERIC_EXAMPLES))
def test_fuzz_every_command(command):
    """Each command with random sets of its options (good, edge and malformed values, side
    files good and corrupt), on small rasters, some damaged."""
    @_settings(_GENERIC_EXAMPLES[command], 0.02)
    @given(case=command_case(command))
    def run(case):
        check_generic(case)
    run()


# ---------------------------------------------------------------------------------------------
# what the fuzzing found, kept as plain cases

def test_fuzz_found_a_nodata_outside_the_heights_type():
    """--nodata 1e40 on int16 heights: a value the type cannot hold matches no cell, without
    numpy's RuntimeWarning on stderr (the error line was the second line)."""
    data = raster_bytes("GTiff", 12, 12, "int16", "utm", None, 0, 0.0, 1, None)
    case = Case("horizon", ["horizon", IN + "dem.tif", OUT + "o.tif", "--directions", "8",
                            "--nodata", "1e40", "-q", "--refraction-coefficient", "nan"],
                {"dem.tif": data}, ["int16 12x12"])
    bad, r, stderr = run_generic(case)
    assert not bad and r.exit_code == 1, (bad, stderr)
    from hillshade_rt.io.dem import heights_into
    z = np.arange(12, dtype=np.int16).reshape(3, 4)
    out = np.empty(z.shape, np.float32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        heights_into(z, 1e40, out)
    assert np.array_equal(out, z.astype(np.float32))


def test_fuzz_irradiance_sky_inputs_plain():
    """irradiance's sky inputs as the table draws them, kept as plain cases (the derandomized
    draws seldom reach them whole): Linke, index and albedo rasters and patterns with --monthly
    and --sky-view-out succeed with every output, in memory and in windows with the same bits;
    an index with --ghi (a measured sky) and a Linke raster out of range are refused, exit 2, one line, nothing
    written; each judged by the generic property too."""
    import rasterio
    dem = raster_bytes("GTiff", 16, 21, "float32", "utm", -9999.0, 2, 0.05, 1, None)
    base = ["irradiance", IN + "dem.tif", OUT + "o.tif", "--date", "2026-06-21", "--step", "3h",
            "--skyview-directions", "4", "-q"]
    sky = ["--linke-turbidity", _sky_file("linke", "{month:02d}"), "--beam-index",
           _sky_file("kb"), "--diffuse-index", _MONTHLY12["index"], "--albedo",
           _sky_file("albedo", "{month}")]

    def case(*extra):
        argv = base + list(extra)
        files = {"dem.tif": dem, "ghi_good.csv": _GHI_CSV["good"]}
        for a in argv:
            if a.startswith(IN + "sky_"):
                files.update(_sky_files(a[len(IN):], dem))
        return Case("irradiance", argv, files, ["float32 16x21 utm, 5% voids"])

    bands = []
    for windows in ([], ["--window-size", "64"]):      # in memory, then in windows
        good = case(*sky, "--monthly", "--sky-view-out", OUT + "svf.tif", *windows)
        assert len(good.files) == 2 + 12 + 1 + 12
        with _invoked(good, before=_cache_folders(good)) as (r, stderr, _, out_dir, new_out,
                                                              new_in, _t):
            assert r.exit_code == 0 and not stderr.strip(), stderr
            assert not _violations_of_any_run(r, stderr, new_in)
            assert new_out == ["o.tif", "svf.tif"]
            with rasterio.open(os.path.join(out_dir, "o.tif")) as ds:
                assert ds.count == 5 and ds.descriptions[4] == "2026-06"
                assert ds.tags()["BEAM_INDEX"].startswith("raster sky_kb.tif")
                bands.append(ds.read())
    assert bands[0].tobytes() == bands[1].tobytes()       # windows: the bits of memory
    refused = {"--ghi": case(*sky, "--ghi", IN + "ghi_good.csv"),
               "--linke-turbidity": case("--linke-turbidity", _sky_file("albedo"))}
    for words, c in refused.items():
        bad, r, stderr = run_generic(c)
        assert not bad and r.exit_code == 2, (c, bad, stderr)
        assert words in stderr, stderr


# ---------------------------------------------------------------------------------------------
# the viewer's HTTP endpoints: random query strings and JSON bodies against a Viewer on a small
# DEM answer 200, 400 or 404, never 500, with one line on an error, and the server goes on

_Q_VALUES = ["0", "1", "-1", "5.5", "12", "90", "91", "-0.0", "nan", "inf", "-inf", "1e308",
             "1e-300", "abc", "", "0,0,10,10", "1,2", "5,5,1,1", "-1e9,-1e9,1e9,1e9",
             "2026-06-21T12:00Z", "2026-06-21T14:30", "2026-06-21", "2026-13-45", "auto",
             "smap", "brute", "quick", "true", "yes", "%00", "%ff", "\u00e9", "1" * 400]
_Q_KEYS = ["bbox", "w", "h", "az", "el", "time", "algorithm", "soft", "sunhours", "x", "y",
           "date", "junk"]
_PATHS = ["/api/render", "/api/point", "/api/download", "/api/sunpath", "/api/info",
          "/api/nothing", "/static/../../etc/passwd", "/"]
_JSON = st.recursive(st.none() | st.booleans() | st.integers(-10 ** 20, 10 ** 20)
                     | st.floats(allow_nan=True, allow_infinity=True)
                     | st.sampled_from(_Q_VALUES),
                     lambda inner: st.lists(inner, max_size=3)
                     | st.dictionaries(st.sampled_from(["x", "y"]), inner, max_size=2),
                     max_leaves=4)
_EDIT_KEYS = ["x", "y", "radius", "delta", "shape", "map_x", "map_y", "lon", "lat"]


@pytest.fixture(scope="module")
def fuzz_viewer(tmp_path_factory):
    """A viewer (in a thread, on a free port) of a 24 x 24 UTM DEM with voids."""
    from hillshade_rt.io import read_dem
    from hillshade_rt.run.viewer import Viewer
    from hillshade_rt.testing import serving
    path = tmp_path_factory.mktemp("view") / "dem.tif"
    path.write_bytes(raster_bytes("GTiff", 24, 24, "float32", "utm", -9999.0, 0, 0.05, 1, None))
    with serving(Viewer(read_dem(str(path)), backend="cpu")) as srv:
        yield srv


def _ask(srv, method, path, body=None):
    import http.client
    conn = http.client.HTTPConnection(*srv.server_address[:2], timeout=60)
    try:
        conn.request(method, path, body=body,
                     headers={"Content-Type": "application/json"} if body is not None else {})
        r = conn.getresponse()
        return r.status, r.read()
    finally:
        conn.close()


def _judge_http(srv, method, path, body=None):
    status, data = _ask(srv, method, path, body)
    assert status in (200, 400, 404), (method, path, body, status, data[:300])
    if status != 200:
        text = data.decode("utf-8", "replace").strip()
        assert text and "\n" not in text and "Traceback" not in text, (path, text[:300])
    assert _ask(srv, "GET", "/api/info")[0] == 200       # the server goes on


@_settings(60, 0.05)
@given(path=st.sampled_from(_PATHS),
       query=st.lists(st.tuples(st.sampled_from(_Q_KEYS), st.sampled_from(_Q_VALUES)),
                      max_size=6),
       raw=st.sampled_from(["", "&&==", "a=%zz", "bbox", "=1", "x=1&x=2&y=3"]))
def test_fuzz_viewer_get(fuzz_viewer, path, query, raw):
    """GET endpoints with random query strings: 200, 400 or 404, never 500."""
    from urllib.parse import quote
    q = "&".join(f"{k}={quote(v, safe='%,:')}" for k, v in query)
    if "w" not in dict(query) and path == "/api/render":
        q += "&w=32&h=32"          # small pictures: the default 512² is slow for nothing
    _judge_http(fuzz_viewer, "GET", path + "?" + q + ("&" + raw if raw else ""))


@_settings(50, 0.05)
@given(path=st.sampled_from(["/api/edit"] * 4 + ["/api/undo", "/api/reset", "/api/nothing"]),
       body=st.one_of(
           st.dictionaries(st.sampled_from(_EDIT_KEYS), _JSON, max_size=6),
           st.fixed_dictionaries({"x": st.sampled_from(["3", "12.5", "-1", "nan", "1e308"]),
                                  "y": st.sampled_from(["3", "23.9", "24", "inf"]),
                                  "radius": st.sampled_from(["0", "30", "1e6", "-1", "abc"]),
                                  "delta": st.sampled_from(["5", "-20", "1e5", "1e300", "nan"]),
                                  "shape": st.sampled_from(["disk", "flat", "cone", ""])}),
           _JSON),
       raw=st.one_of(st.none(), st.binary(max_size=40)))
def test_fuzz_viewer_edit(fuzz_viewer, path, body, raw):
    """POST /api/edit (undo, reset) with random JSON bodies or bytes: 200, 400 or 404."""
    data = raw if raw is not None else json.dumps(body).encode()
    _judge_http(fuzz_viewer, "POST", path, data)
