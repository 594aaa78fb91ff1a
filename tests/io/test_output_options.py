"""GDAL's output conventions (issue 23 item 1): --co NAME=VALUE creation options over the tool's
defaults, -f/--format any GDAL driver that writes, --bidx; every COG the runs write passes
rio-cogeo's validator.

--co reaches the file published whatever the path: in memory, in windows, --output-pattern,
Dask parts put together through a VRT, --cog. GDAL only warns on an unknown option or value: the
run refuses them (exit 1, one line, nothing written) before any work."""

import os

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.testing import (LUNAR_SOUTH_POLAR_STEREO, data_path, fractal_terrain,
                                  read_band, repo_root, toy_lunar_subsolar, write_geotiff,
                                  write_subsolar_csv)

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
# larger than 512 x 512: its COGs have overviews
BIG = os.path.join(repo_root(), "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif")
SUN = ["--azimuth", "203.7", "--elevation", "12"]
TWO_TIMES = ["--time", "2026-03-02T08:10-06:00", "--time", "2026-03-02T16:40-06:00"]
UTM = CRS.from_epsg(32611)


def one_line_error(r, code=1):
    assert r.exit_code == code, (r.exit_code, r.output)
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hillshade-rt: error:"), r.stderr
    return lines[0]


def structure(path) -> dict:
    with rasterio.open(path) as ds:
        return dict(ds.tags(ns="IMAGE_STRUCTURE"), block=ds.block_shapes[0], driver=ds.driver,
                    count=ds.count)


def is_bigtiff(path) -> bool:
    with open(path, "rb") as fh:
        return fh.read(4) in (b"II+\x00", b"MM\x00+")


def cog_valid(path, what):
    """rio-cogeo's verdict on ``path``: valid, no errors; its warnings listed in the test's
    output."""
    from rio_cogeo.cogeo import cog_validate
    ok, errors, warnings = cog_validate(str(path), quiet=True)
    print(f"cog_validate {what}: valid={ok} errors={errors} warnings={warnings}")
    assert ok and errors == [], (what, errors, warnings)
    return warnings


# ---------------------------------------------------------------------------------------------
# --co on the command line

@pytest.mark.parametrize("how", ["in memory", "window-size", "max-memory"])
def test_co_in_memory_and_in_windows(tmp_path, runner, how):
    """ZSTD, horizontal differencing, 512-px tiles and BigTIFF as asked, in memory and in
    windows (forced, or from a --max-memory the DEM does not fit); the values those of the
    default file."""
    import json

    from hillshade_rt.engine import windows as tiling
    ref, out, rep = tmp_path / "ref.tif", tmp_path / "out.tif", tmp_path / "r.json"
    assert runner.invoke(cli, ["shadow", LIDAR, str(ref), "-q"] + SUN).exit_code == 0
    # room for the process, GDAL's cache and about 1 MB of windows: the DEM needs more
    limit = tiling.process_rss() + ((tiling.GDAL_CACHE_MB + 32 + 1) << 20)
    extra = {"in memory": [], "window-size": ["--window-size", "96x128"],
             "max-memory": ["--max-memory", str(limit)]}[how]
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "-q", "--co", "COMPRESS=ZSTD",
                            "--co", "PREDICTOR=2", "--co", "blockxsize=512",
                            "--co", "BLOCKYSIZE=512", "--co", "BIGTIFF=YES",
                            "--report", str(rep)] + SUN + extra)
    assert r.exit_code == 0, r.output
    doc = json.loads(rep.read_text())["processing"]
    assert (doc["mode"] == "tiled" and doc["windows"] > 1) == (how != "in memory"), doc
    rep.unlink()
    s, d = structure(out), structure(ref)
    assert s["COMPRESSION"] == "ZSTD" and s.get("PREDICTOR") == "2" and s["block"] == (512, 512)
    assert d["COMPRESSION"] == "DEFLATE" and d["block"] == (256, 256)     # defaults unchanged
    assert is_bigtiff(out) and not is_bigtiff(ref)
    np.testing.assert_array_equal(read_band(out), read_band(ref))
    assert sorted(os.listdir(tmp_path)) == ["out.tif", "ref.tif"]


def test_co_float_product_and_strips(tmp_path, runner):
    """Soft shadows (float32) with LZW and strips (TILED=NO): the default floating-point
    predictor stays with LZW; the values are the default file's."""
    ref, out = tmp_path / "ref.tif", tmp_path / "out.tif"
    assert runner.invoke(cli, ["shadow", LIDAR, str(ref), "--soft", "-q"] + SUN).exit_code == 0
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "--soft", "-q", "--co", "COMPRESS=LZW",
                            "--co", "TILED=NO"] + SUN)
    assert r.exit_code == 0, r.output
    s = structure(out)
    assert s["COMPRESSION"] == "LZW" and s["PREDICTOR"] == "3" and s["block"][1] == 400
    np.testing.assert_array_equal(read_band(out), read_band(ref))


@pytest.mark.parametrize("args,code,words", [
    (["--co", "FOO"], 2, "--co FOO: expected NAME=VALUE"),
    (["--co", "=1"], 2, "expected NAME=VALUE"),
    (["--co", "FOO=1"], 1, "--co FOO=1: driver GTiff does not support creation option FOO"),
    (["--co", "BIGTIFF=MAYBE"], 1, "'MAYBE' is an unexpected value for BIGTIFF"),
    (["--co", "ZLEVEL=x"], 1, "--co ZLEVEL=x"),
    (["--co", "BLOCKXSIZE=100"], 1, "16"),               # tiles: multiples of 16
    (["--co", "PREDICTOR=7"], 1, "PREDICTOR=7"),
    (["--co", "COMPRESS=JPEG"], 1, "lossy"),             # a mask: lossless only
    (["--soft", "--co", "COMPRESS=JPEG"], 1, "JPEG"),    # float32: GDAL's JPEG refuses it
    (["--cog", "--co", "BLOCKXSIZE=512"], 1, "COG takes BLOCKSIZE"),
    (["-f", "COG", "--co", "ZLEVEL=9"], 1, "COG takes LEVEL"),
    (["-f", "PNG", "--co", "FOO=1"], 1, "driver PNG does not support creation option FOO"),
    # Dask: refused before the workers start, not when the parts are put together
    (["--scheduler", "local:2", "--window-size", "200", "--co", "FOO=1"], 1, "--co FOO=1"),
    (["--output-pattern", "p_{index}.tif", "--co", "FOO=1"], 1, "--co FOO=1"),
])
def test_bad_co_one_line_nothing_written(tmp_path, runner, args, code, words):
    args = [str(tmp_path / a) if a.startswith("p_") else a for a in args]
    out = [] if "--output-pattern" in args else [str(tmp_path / "out.tif")]
    r = runner.invoke(cli, ["shadow", LIDAR, *out, "-q"] + SUN + args)
    line = one_line_error(r, code)
    assert words in line, line
    assert os.listdir(tmp_path) == []


def test_bad_co_refused_before_the_run(tmp_path, runner):
    """An option GDAL refuses stops a long series before its first sun (no compile note, no
    report, nothing beside the output)."""
    out, rep = tmp_path / "o.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "--start", "2026-03-02T06:00-06:00",
                            "--end", "2026-03-02T18:00-06:00", "--step", "10min",
                            "--report", str(rep), "--co", "NUM_THREADS=lots"])
    one_line_error(r, 1)
    assert os.listdir(tmp_path) == []


def test_co_output_pattern_and_multiband(tmp_path, runner):
    """--co reaches every file of --output-pattern and every band of one OUTPUT."""
    r = runner.invoke(cli, ["shadow", LIDAR, "--output-pattern", str(tmp_path / "p_{index}.tif"),
                            "-q", "--co", "COMPRESS=ZSTD", "--co", "ZSTD_LEVEL=9"] + TWO_TIMES)
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.tif"), "-q",
                            "--co", "COMPRESS=LZW", "--co", "INTERLEAVE=PIXEL"] + TWO_TIMES)
    assert r.exit_code == 0, r.output
    assert sorted(os.listdir(tmp_path)) == ["m.tif", "p_0.tif", "p_1.tif"]
    m = structure(tmp_path / "m.tif")
    assert m["COMPRESSION"] == "LZW" and m["INTERLEAVE"] == "PIXEL" and m["count"] == 2
    for i in range(2):
        assert structure(tmp_path / f"p_{i}.tif")["COMPRESSION"] == "ZSTD"
        np.testing.assert_array_equal(read_band(tmp_path / f"p_{i}.tif"),
                                      read_band(tmp_path / "m.tif", i + 1))


@pytest.mark.slow
def test_co_dask_parts_through_vrt(tmp_path, runner):
    """--scheduler: the parts keep the defaults, the file put together from them gets --co
    (GeoTIFF, and COG with its own options); no part left."""
    ref = tmp_path / "ref.tif"
    assert runner.invoke(cli, ["shadow", LIDAR, str(ref), "-q"] + SUN).exit_code == 0
    out, cog = tmp_path / "d.tif", tmp_path / "dcog.tif"
    dask = ["--scheduler", "local:2", "--window-size", "200", "-q"]
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "--co", "COMPRESS=ZSTD",
                            "--co", "BLOCKXSIZE=128", "--co", "BLOCKYSIZE=128"] + SUN + dask)
    assert r.exit_code == 0, r.output
    s = structure(out)
    assert s["COMPRESSION"] == "ZSTD" and s["block"] == (128, 128)
    np.testing.assert_array_equal(read_band(out), read_band(ref))
    r = runner.invoke(cli, ["shadow", LIDAR, str(cog), "--cog", "--co", "COMPRESS=ZSTD",
                            "--co", "BLOCKSIZE=256"] + SUN + dask)
    assert r.exit_code == 0, r.output
    s = structure(cog)
    assert s["COMPRESSION"] == "ZSTD" and s["LAYOUT"] == "COG" and s["block"] == (256, 256)
    np.testing.assert_array_equal(read_band(cog), read_band(ref))
    cog_valid(cog, "dask --cog --co COMPRESS=ZSTD BLOCKSIZE=256")
    assert sorted(os.listdir(tmp_path)) == ["d.tif", "dcog.tif", "ref.tif"]


# ---------------------------------------------------------------------------------------------
# COGs: --cog, -f COG, with --co; rio-cogeo validates each

@pytest.mark.parametrize("name,args", [
    ("mem", ["--cog"]),
    ("fcog", ["-f", "COG"]),
    ("win", ["--cog", "--window-size", "200x256"]),
    ("zstd", ["--cog", "--co", "COMPRESS=ZSTD", "--co", "LEVEL=9"]),
    ("zstd_win", ["-f", "COG", "--co", "COMPRESS=ZSTD", "--window-size", "256"]),
    ("block", ["--cog", "--co", "BLOCKSIZE=256", "--co", "OVERVIEW_RESAMPLING=NEAREST"]),
    ("soft", ["--cog", "--soft", "--co", "COMPRESS=LZW"]),
    ("bands", ["--cog"] + TWO_TIMES),
    ("bands_win", ["--cog", "--window-size", "256", "--co", "COMPRESS=ZSTD"] + TWO_TIMES),
])
def test_cog_outputs_valid(tmp_path, runner, name, args):
    out = tmp_path / f"{name}.tif"
    r = runner.invoke(cli, ["shadow", BIG, str(out), "-q"] +
                      ([] if "--time" in args else SUN) + args)
    assert r.exit_code == 0, r.output
    s = structure(out)
    assert s["LAYOUT"] == "COG"
    if "COMPRESS=ZSTD" in args:
        assert s["COMPRESSION"] == "ZSTD"
    if "BLOCKSIZE=256" in args:
        assert s["block"] == (256, 256)
    with rasterio.open(out) as ds:
        assert ds.overviews(1)      # 1197 x 643: overviews
    warnings = cog_valid(out, name)
    assert not any("overview" in w.lower() for w in warnings)
    assert os.listdir(tmp_path) == [out.name]


def test_cog_output_pattern_valid(tmp_path, runner):
    r = runner.invoke(cli, ["shadow", BIG, "--output-pattern", str(tmp_path / "c_{index}.tif"),
                            "--cog", "--co", "COMPRESS=ZSTD", "-q"] + TWO_TIMES)
    assert r.exit_code == 0, r.output
    assert sorted(os.listdir(tmp_path)) == ["c_0.tif", "c_1.tif"]
    for i in range(2):
        assert structure(tmp_path / f"c_{i}.tif")["COMPRESSION"] == "ZSTD"
        cog_valid(tmp_path / f"c_{i}.tif", f"output-pattern {i}")


# ---------------------------------------------------------------------------------------------
# -f/--format: any GDAL driver that writes

def _readback(path):
    with rasterio.open(path) as ds:
        return ds.driver, ds.read(1)


@pytest.mark.parametrize("fmt,name,co", [
    ("GTiff", "a.tif", []),
    ("PNG", "a.png", ["--co", "ZLEVEL=9"]),
    ("HFA", "a.img", ["--co", "COMPRESSED=YES"]),
    ("ENVI", "a.bil", ["--co", "INTERLEAVE=BIL"]),
    ("AAIGrid", "a.asc", []),
    ("netCDF", "a.nc", ["--co", "FORMAT=NC4", "--co", "COMPRESS=DEFLATE"]),
    ("RST", "a.rst", []),
])
def test_format_any_writing_driver(tmp_path, runner, fmt, name, co):
    """The mask in each format reads back as the GeoTIFF's (a format GDAL lacks here is
    skipped: netCDF is optional in GDAL builds)."""
    with rasterio.Env() as env:
        if fmt not in env.drivers():
            pytest.skip(f"this GDAL has no {fmt} driver")
    ref = tmp_path / "ref.tif"
    assert runner.invoke(cli, ["shadow", LIDAR, str(ref), "-q"] + SUN).exit_code == 0
    out = tmp_path / name
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "-f", fmt, "-q"] + SUN + co)
    assert r.exit_code == 0, r.output
    drv, band = _readback(out)
    assert drv == fmt
    np.testing.assert_array_equal(band, read_band(ref))
    assert not [f for f in os.listdir(tmp_path) if ".part" in f or ".scratch" in f]


@pytest.mark.parametrize("args,words", [
    (["-f", "HDF5"], "HDF5 driver reads only"),
    (["-f", "NoSuchDriver"], "not a GDAL raster driver"),
    (["-f", "AAIGrid"] + TWO_TIMES, "band"),            # one band only
    (["-f", "XPM", "--soft"], "XPM"),                   # float32 into 8-bit-only: GDAL says no
    (["-f", "PNG", "--classes", "--co", "ZLEVEL=99"], "ZLEVEL"),
    (["-f", "VRT"], "VRT only points at other files"),
])
def test_format_refusals_one_line(tmp_path, runner, args, words):
    with rasterio.Env() as env:
        if args[1] in ("HDF5", "XPM") and args[1] not in env.drivers():
            pytest.skip(f"this GDAL has no {args[1]} driver")
    out = tmp_path / "o.out"
    sun = [] if "--time" in args else SUN
    line = one_line_error(runner.invoke(cli, ["shadow", LIDAR, str(out), "-q"] + sun + args))
    assert words in line, line
    assert os.listdir(tmp_path) == []


def test_float_product_into_png_refused(tmp_path, runner):
    line = one_line_error(runner.invoke(cli, ["sun-hours", LIDAR, str(tmp_path / "h.png"),
                                              "--date", "2026-06-21", "-q"]))
    assert "PNG holds integers" in line and os.listdir(tmp_path) == []


# ---------------------------------------------------------------------------------------------
# the other commands that write rasters

@pytest.fixture(scope="module")
def small(tmp_path_factory):
    d = tmp_path_factory.mktemp("small")
    z = fractal_terrain(64, 80, 4, relief=200.0)
    dem = write_geotiff(d / "dem.tif", z, Affine(10, 0, 400000, 0, -10, 3800000), UTM)
    lunar = write_geotiff(d / "moon.tif", z, Affine(20, 0, -800, 0, -20, 640),
                          LUNAR_SOUTH_POLAR_STEREO)
    csv = write_subsolar_csv(d / "s.csv", toy_lunar_subsolar(4, 12.0, phase_deg=270.0))
    return dem, lunar, csv


@pytest.mark.parametrize("cmd,args", [
    ("hillshade", SUN),
    ("sun-hours", ["--date", "2026-06-21", "--step", "3h"]),
    ("horizon", ["--azimuth", "163"]),
    ("skyview", ["--directions", "4"]),
    ("irradiance", ["--date", "2026-06-21", "--step", "3h", "--tz", "UTC"]),
    ("illumination", None),
])
def test_every_raster_command_takes_co(tmp_path, runner, small, cmd, args):
    dem, lunar, csv = small
    if args is None:                  # illumination: a lunar DEM and a subsolar series
        dem, args = lunar, ["--subsolar-file", csv]
    out = tmp_path / "o.tif"
    line = one_line_error(runner.invoke(cli, [cmd, dem, str(out), "-q", "--co", "FOO=1"] + args))
    assert "--co FOO=1: driver GTiff does not support" in line and os.listdir(tmp_path) == []
    r = runner.invoke(cli, [cmd, dem, str(out), "-q", "--co", "COMPRESS=ZSTD"] + args)
    assert r.exit_code == 0, r.output
    assert structure(out)["COMPRESSION"] == "ZSTD"


# ---------------------------------------------------------------------------------------------
# --bidx, the Python API

def test_bidx_is_band(tmp_path, runner):
    """--bidx 2 (rasterio's spelling) shades the second band, as -b 2 and as that band alone."""
    z1 = fractal_terrain(96, 96, 1, relief=300.0)
    z2 = fractal_terrain(96, 96, 2, relief=300.0)
    tr = Affine(5, 0, 400000, 0, -5, 3800000)
    two = write_geotiff(tmp_path / "two.tif", np.stack([z1, z2]), tr, UTM)
    alone = write_geotiff(tmp_path / "alone.tif", z2, tr, UTM)
    outs = {}
    for name, args in (("bidx", [two, "--bidx", "2"]), ("b", [two, "-b", "2"]),
                       ("alone", [alone]), ("first", [two])):
        outs[name] = tmp_path / f"{name}_out.tif"
        r = runner.invoke(cli, ["shadow", *args, str(outs[name]), "-q"] + SUN)
        assert r.exit_code == 0, r.output
    want = read_band(outs["alone"])
    np.testing.assert_array_equal(read_band(outs["bidx"]), want)
    np.testing.assert_array_equal(read_band(outs["b"]), want)
    assert (read_band(outs["first"]) != want).any()
    r = runner.invoke(cli, ["shadow", two, str(tmp_path / "x.tif"), "--bidx", "0"] + SUN)
    assert r.exit_code == 2


def test_api_creation_options(tmp_path):
    from hillshade_rt import api
    from hillshade_rt.errors import HillshadeError
    out = tmp_path / "a.tif"
    api.shade(LIDAR, str(out), azimuth=203.7, elevation=12,
              creation_options={"compress": "zstd", "predictor": 2})
    assert structure(out)["COMPRESSION"] == "ZSTD"
    with pytest.raises(HillshadeError, match="does not support creation option FOO"):
        api.shade(LIDAR, str(tmp_path / "b.tif"), azimuth=203.7, elevation=12,
                  creation_options=["FOO=1"])
    assert os.listdir(tmp_path) == ["a.tif"]
