"""The command line: success paths, the report, and every error as one line with no output."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, fractal_terrain, read_band, write_geotiff

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
REPORT_KEYS = {"input", "output", "shape", "spacing_m", "crs", "sun", "algorithm", "backend",
               "threads", "seconds", "mpix_per_s", "shadow_fraction", "version"}


def test_shadow_with_report(tmp_path, runner):
    out, rep = tmp_path / "m.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "--azimuth", "163", "--elevation", "5",
                            "--report", str(rep)])
    assert r.exit_code == 0, r.output
    doc = json.loads(rep.read_text())
    assert REPORT_KEYS <= set(doc)
    assert doc["shape"] == [400, 400] and doc["crs"] == "EPSG:26915"
    assert doc["sun"]["azimuth"] == 163.0 and doc["sun"]["elevation"] == 5.0
    assert doc["sun"]["night"] is False and doc["sun_source"] == "given"
    assert doc["algorithm"] == "auto" and doc["backend"] == "cpu" and doc["threads"] >= 1
    auto = doc["algorithm_stats"]["auto"]          # which exact method auto ran, and why
    assert sum(auto["chose"].values()) == 1 and set(auto["chose"]) <= {"bounds", "brute"}
    assert "reach" in auto["why"] and "auto:" in r.output
    assert set(doc["seconds"]) == {"read", "prepare", "compute", "write", "total"}
    assert doc["spacing_m"][0] == pytest.approx(1.0, rel=1e-3)
    m = read_band(out)
    assert doc["shadow_fraction"] == pytest.approx((m == 1).sum() / (m != 255).sum())
    assert 0 < doc["shadow_fraction"] < 1
    assert "in shadow" in r.stderr  # the one-line summary


def test_quiet_prints_nothing(tmp_path, runner):
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.tif"), "--azimuth", "10",
                            "--elevation", "30", "-q"])
    assert r.exit_code == 0 and r.output == ""


def test_overwrite(tmp_path, runner):
    out = tmp_path / "m.tif"
    args = ["shadow", LIDAR, str(out), "--azimuth", "10", "--elevation", "5", "-q"]
    assert runner.invoke(cli, args).exit_code == 0
    before = out.read_bytes()
    r = runner.invoke(cli, args[:3] + ["--azimuth", "200", "--elevation", "5", "-q"])
    assert r.exit_code == 1 and "already exists" in r.stderr
    assert out.read_bytes() == before
    assert runner.invoke(cli, args + ["--overwrite"]).exit_code == 0


def test_real_subprocess(tmp_path):
    out = tmp_path / "m.tif"
    exe = [sys.executable, "-m", "hillshade_rt"]
    p = subprocess.run(exe + ["shadow", LIDAR, str(out), "--azimuth", "203.7", "--elevation",
                              "3", "--threads", "1"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert out.exists() and "in shadow" in p.stderr and p.stdout == ""
    p = subprocess.run(exe + ["shadow", "missing.tif", str(tmp_path / "x.tif"), "--azimuth", "1",
                              "--elevation", "5"], capture_output=True, text=True)
    assert p.returncode == 1
    assert p.stderr.strip().count("\n") == 0 and "missing.tif" in p.stderr
    assert "Traceback" not in p.stderr


def test_subprocess_exit_keeps_status_and_flushes_output(tmp_path):
    """``cli.main`` ends the process with os._exit (no interpreter teardown): what the command
    printed must still arrive through pipes, and the exit status be the command's."""
    exe = [sys.executable, "-m", "hillshade_rt"]
    p = subprocess.run(exe + ["info", LIDAR, "--json"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["shape"] == [400, 400]
    p = subprocess.run(exe + ["shadow"], capture_output=True, text=True)     # usage error
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.strip().count("\n") == 0 and "Missing argument" in p.stderr


def _bad_inputs(tmp_path):
    """(name, argv, expected text in the error) for every input error the issue lists."""
    txt = tmp_path / "notes.txt"
    txt.write_text("not a raster\n")
    empty = tmp_path / "empty.bin"
    empty.write_bytes(b"")
    rotated = write_geotiff(tmp_path / "rot.tif", fractal_terrain(8, 8, 1),
                            Affine(29.5, 5.2, 400000, 5.2, -29.5, 3800000), CRS.from_epsg(32611))
    raw = tmp_path / "g.f32"
    np.zeros((10, 10), "<f4").tofile(raw)
    ok = ["--azimuth", "10", "--elevation", "20"]
    return [
        ("missing file", [str(tmp_path / "nope.tif")], ok, "no such file"),
        ("not a raster", [str(txt)], ok, "cannot read"),
        ("empty raster", [str(empty), "--raw-shape", "1x1", "--raw-dtype", "float32",
                          "--pixel-size", "1"], ok, "empty"),
        ("raw wrong shape", [str(raw), "--raw-shape", "10x11", "--raw-dtype", "float32",
                             "--pixel-size", "1"], ok, "10x11"),
        ("raw wrong dtype size", [str(raw), "--raw-shape", "7x7", "--raw-dtype", "float64",
                                  "--pixel-size", "1"], ok, "raw-shape"),
        ("raw no dtype", [str(raw), "--raw-shape", "10x10", "--pixel-size", "1"], ok,
         "--raw-dtype"),
        ("raw bad dtype", [str(raw), "--raw-shape", "10x10", "--raw-dtype", "int8",
                           "--pixel-size", "1"], ok, "int8"),
        ("raw without pixel size", [str(raw), "--raw-shape", "10x10", "--raw-dtype", "float32"],
         ok, "--pixel-size"),
        ("elevation 0", [LIDAR], ["--azimuth", "10", "--elevation", "0"], "elevation"),
        ("elevation 91", [LIDAR], ["--azimuth", "10", "--elevation", "91"], "elevation"),
        ("elevation negative", [LIDAR], ["--azimuth", "10", "--elevation", "-3"], "elevation"),
        ("azimuth not a number", [LIDAR], ["--azimuth", "west", "--elevation", "3"], "azimuth"),
        ("rotated transform", [rotated], ok, "rotated"),
        ("bad band", [LIDAR, "--band", "2"], ok, "band"),
    ]


def test_every_input_error_is_one_line_and_leaves_nothing(tmp_path, runner):
    outdir = tmp_path / "out"
    outdir.mkdir()
    for name, pre, sun, text in _bad_inputs(tmp_path):
        out = outdir / "mask.tif"
        r = runner.invoke(cli, ["shadow", pre[0], str(out)] + pre[1:] + sun
                          + ["--report", str(outdir / "r.json")])
        assert r.exit_code in (1, 2), (name, r.exit_code, r.output)
        assert r.exception is None or isinstance(r.exception, SystemExit), (name, r.exception)
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("hillshade-rt: error:"), (name, r.stderr)
        assert text.lower() in lines[0].lower(), (name, lines[0])
        assert os.listdir(outdir) == [], (name, os.listdir(outdir))


def test_all_nodata_dem_is_no_error(tmp_path, runner):
    """A DEM whose every cell is nodata (a tile of the sea) writes an all-nodata mask, says so
    in one note and exits 0: a Makefile does not stop at the coast."""
    allnd = write_geotiff(tmp_path / "allnd.tif", np.full((5, 5), -9999, np.int16),
                          Affine(1, 0, 400000, 0, -1, 3800000), CRS.from_epsg(32611), -9999)
    out = tmp_path / "mask.tif"
    r = runner.invoke(cli, ["shadow", allnd, str(out), "--azimuth", "10", "--elevation", "20",
                            "--report", str(tmp_path / "r.json")])
    assert r.exit_code == 0, r.output
    notes = [ln for ln in r.stderr.splitlines() if "note:" in ln]
    assert len(notes) == 1 and "every cell is nodata" in notes[0]
    import rasterio
    with rasterio.open(out) as ds:
        assert ds.nodata == 255 and (ds.read(1) == 255).all()
    assert json.loads((tmp_path / "r.json").read_text())["processing"]["mode"] == "all nodata"


def test_output_folder_missing(tmp_path, runner):
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "no" / "m.tif"), "--azimuth", "1",
                            "--elevation", "5"])
    assert r.exit_code == 1 and "does not exist" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1


def test_interrupted_write_leaves_no_file(tmp_path, monkeypatch):
    """A failure while writing (here: Ctrl-C) removes the temporary file; OUTPUT never appears."""
    import rasterio
    from hillshade_rt import io as hio

    real_open = rasterio.open

    class Boom:
        def __init__(self, *a, **k):
            self.ds = real_open(*a, **k)
        def __enter__(self):
            return self
        def __exit__(self, *exc):
            self.ds.close()
        def write(self, *a, **k):
            raise KeyboardInterrupt
        def __getattr__(self, name):
            return getattr(self.ds, name)

    monkeypatch.setattr(rasterio, "open", Boom)
    d = hio.read_dem(LIDAR)
    with pytest.raises(KeyboardInterrupt):
        hio.write_raster(str(tmp_path / "m.tif"), np.zeros(d.shape, np.uint8), d, 255)
    assert os.listdir(tmp_path) == []


def test_version_and_help(runner):
    r = runner.invoke(cli, ["--version"])
    assert r.exit_code == 0 and "hillshade-rt" in r.output
    r = runner.invoke(cli, ["shadow", "--help"])
    assert r.exit_code == 0 and "--azimuth" in r.output


def test_cli_offers_every_registered_algorithm():
    from hillshade_rt.algorithms import ALGORITHMS

    opt = next(p for p in cli.commands["shadow"].params if p.name == "algorithm")
    assert list(opt.type.choices) == list(ALGORITHMS)
