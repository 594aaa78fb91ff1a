"""Issue 16, items 8, 12, 13, 14: usage errors exit 2 on every command, messages that fit the
value, summary lines and notes, the smallest --max-memory, the smallest --window-size."""

import os
import re

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

import hillshade_rt as hr
from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError
from hillshade_rt.run import report
from hillshade_rt.testing import data_path, fractal_terrain, write_geotiff, repo_root

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
SRTM = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")       # geographic (EPSG:4326)
UTM13 = CRS.from_epsg(32613)
MOON = ('GEOGCS["Moon 2000",DATUM["D_Moon_2000",SPHEROID["Moon_2000_IAU_IAG",1737400.0,0.0]],'
        'PRIMEM["Greenwich",0],UNIT["Decimal_Degree",0.0174532925199433]]')


@pytest.fixture
def dem(tmp_path):
    return write_geotiff(tmp_path / "dem.tif", fractal_terrain(40, 40, 3).astype(np.float32),
                         Affine(30.0, 0, 476000.0, 0, -30.0, 4400000.0), UTM13)


def _one_line(r, code, msg):
    assert r.exit_code == code, (r.exit_code, r.output)
    assert msg in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "Traceback" not in r.output


def _nothing_new(tmp_path, before):
    assert sorted(os.listdir(tmp_path)) == before


# ---------------------------------------------------------------------------------------------
# item 8: tiny windows

def test_window_size_below_the_minimum_is_a_usage_error(tmp_path, runner, dem):
    before = sorted(os.listdir(tmp_path))
    for size in ("1", "1x1", "8x200", "63"):
        r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif"), "--azimuth", "200",
                                "--elevation", "10", "--window-size", size])
        _one_line(r, 2, "at least 64 cells")
    _nothing_new(tmp_path, before)
    with pytest.raises(HillshadeError, match="at least 64"):
        hr.shade(dem, tmp_path / "o.tif", azimuth=200, elevation=10, window_size=(16, 16))
    _nothing_new(tmp_path, before)
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif"), "--azimuth", "200",
                            "--elevation", "10", "--window-size", "64", "-q"])
    assert r.exit_code == 0, r.output


# ---------------------------------------------------------------------------------------------
# item 12: every malformed command line exits 2

def _command(name, dem, out):
    return {"shadow": ["shadow", dem, out, "--azimuth", "200", "--elevation", "10"],
            "hillshade": ["hillshade", dem, out],
            "sun-hours": ["sun-hours", dem, out, "--date", "2026-06-21", "--step", "6h"],
            "horizon": ["horizon", dem, out, "--azimuth", "200"],
            "info": ["info", dem],
            "animate": ["animate", dem, out[:-4] + ".gif", "--date", "2026-06-21", "--step",
                        "6h"]}[name]


@pytest.mark.parametrize("command", ["shadow", "hillshade", "sun-hours", "horizon", "info",
                                     "animate"])
@pytest.mark.parametrize("bad, msg", [(["--pixel-size", "0"], "--pixel-size"),
                                      (["--pixel-size", "a,b"], "--pixel-size"),
                                      (["--raw-shape", "abc"], "--raw-shape"),
                                      (["--raw-shape", "0x5"], "--raw-shape"),
                                      (["-z", "0"], "--z-factor"),
                                      (["--band", "0"], "--band")])
def test_bad_dem_options_exit_2_on_every_command(tmp_path, runner, dem, command, bad, msg):
    before = sorted(os.listdir(tmp_path))
    r = runner.invoke(cli, _command(command, dem, str(tmp_path / "o.tif")) + bad)
    _one_line(r, 2, msg)
    _nothing_new(tmp_path, before)


@pytest.mark.parametrize("command", ["shadow", "hillshade", "sun-hours", "animate"])
@pytest.mark.parametrize("place, msg", [(["--lat", "95", "--lon", "3"], "--lat must be"),
                                        (["--lat", "nan", "--lon", "3"], "--lat must be"),
                                        (["--lat", "45"], "--lat and --lon go together"),
                                        (["--lon", "7"], "--lat and --lon go together"),
                                        (["--lat", "45", "--lon", "inf"], "--lon must be")])
def test_bad_place_exits_2(tmp_path, runner, dem, command, place, msg):
    out = str(tmp_path / "o.tif")
    args = (["sun-hours", dem, out, "--date", "2026-06-21"] if command == "sun-hours"
            else ["animate", dem, out[:-4] + ".gif", "--date", "2026-06-21"]
            if command == "animate" else [command, dem, out, "--time", "2026-06-21T12:00Z"])
    r = runner.invoke(cli, args + place)
    _one_line(r, 2, msg)
    assert not os.path.exists(out) and not os.path.exists(out[:-4] + ".gif")


def test_api_raises_the_same_messages_in_its_keywords(tmp_path, dem):
    out = tmp_path / "o.tif"
    for kw, msg in [(dict(pixel_size="0"), "pixel_size"), (dict(raw_shape="abc"), "raw_shape"),
                    (dict(times=["2026-06-21T12:00Z"], lat=95, lon=0), "lat must be"),
                    (dict(times=["2026-06-21T12:00Z"], lat=45), "lat and lon go together"),
                    (dict(times=["2026-06-21"]), "date without a time"),
                    (dict(elevation=91), "(0, 90]")]:
        kw = {"azimuth": 200, "elevation": 10, **kw} if "times" not in kw else kw
        with pytest.raises(HillshadeError, match=re.escape(msg)) as e:
            hr.shade(dem, out, **kw)
        assert "--" not in str(e.value), e.value
    assert not out.exists()


@pytest.mark.parametrize("value", ["91", "nan", "inf", "1000"])
def test_elevation_above_the_zenith_or_not_a_number(tmp_path, runner, dem, value):
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif"), "--azimuth", "200",
                            "--elevation", value])
    _one_line(r, 2, "--elevation must be a number of degrees in (0, 90]")
    assert "horizon" not in r.stderr and "lights nothing" not in r.stderr


def test_elevation_at_or_below_the_horizon_keeps_its_reason(tmp_path, runner, dem):
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif"), "--azimuth", "200",
                            "--elevation", "-3"])
    _one_line(r, 2, "lights nothing")


@pytest.mark.parametrize("opts", [["--time", "2026-06-21"],
                                  ["--time", "2026-06-21", "--tz", "UTC"],
                                  ["--start", "2026-06-21", "--end", "2026-06-21T18:00Z",
                                   "--step", "1h"],
                                  ["--start", "2026-06-21T06:00Z", "--end", "2026-06-22",
                                   "--step", "1h"]])
def test_a_date_without_a_time_is_refused(tmp_path, runner, dem, opts):
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif")] + opts)
    _one_line(r, 2, "is a date without a time of day: give a time, e.g. 2026-06-2")
    bad = [o for o, v in zip(opts, opts[1:]) if re.fullmatch(r"\d{4}-\d\d-\d\d", v)][0]
    assert f"{bad} '" in r.stderr
    assert not (tmp_path / "o.tif").exists()


def test_sun_hours_still_takes_dates(tmp_path, runner, dem):
    r = runner.invoke(cli, ["sun-hours", dem, str(tmp_path / "h.tif"), "--date", "2026-06-21",
                            "--step", "3h", "-q"])
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize("flag", [["--output-pattern", "x_{index}.tif"], ["-o", "y.tif"]])
def test_output_together_with_a_pattern_or_o_is_refused(tmp_path, runner, dem, flag, monkeypatch):
    monkeypatch.chdir(tmp_path)
    before = sorted(os.listdir(tmp_path))
    r = runner.invoke(cli, ["shadow", dem, "out.tif", "--azimuth", "200", "--elevation", "10"]
                      + flag)
    _one_line(r, 2, "not both")
    assert "out.tif" in r.stderr and "no such file" not in r.stderr
    _nothing_new(tmp_path, before)
    r = runner.invoke(cli, ["shadow", dem, "--azimuth", "200", "--elevation", "10",
                            "--output-pattern", "p.tif", "-o", "q.tif"])
    _one_line(r, 2, "not both")


def test_sun_hours_on_the_moon_does_not_advise_options_it_lacks(tmp_path, runner):
    moon = write_geotiff(tmp_path / "moon.tif", np.zeros((8, 8), np.float32),
                         Affine(0.01, 0, 0, 0, -0.01, 0), CRS.from_wkt(MOON))
    r = runner.invoke(cli, ["sun-hours", moon, str(tmp_path / "h.tif"), "--date", "2026-06-21"])
    _one_line(r, 1, "not the Earth")
    assert "--azimuth" not in r.stderr and "--elevation" not in r.stderr and "--time" not in r.stderr
    assert "shadow or hillshade" in r.stderr
    # shadow does take --azimuth/--elevation: its advice stays
    r = runner.invoke(cli, ["shadow", moon, str(tmp_path / "s.tif"), "--time", "2026-06-21T12:00Z"])
    _one_line(r, 1, "give --azimuth/--elevation")


def test_docs_say_infinite_heights_are_nodata(tmp_path, runner):
    text = open(os.path.join(repo_root(), "docs", "usage.md"),
                encoding="utf-8").read()
    assert "±inf heights are always nodata" in text
    z = fractal_terrain(20, 20, 1).astype(np.float32)
    z[3, 4], z[5, 6] = np.inf, -np.inf
    p = write_geotiff(tmp_path / "inf.tif", z, Affine(30.0, 0, 476000.0, 0, -30.0, 4400000.0),
                      UTM13)
    r = runner.invoke(cli, ["info", p, "--json"])
    assert r.exit_code == 0 and '"valid_cells": 398' in r.output


# ---------------------------------------------------------------------------------------------
# item 13: summary lines, paths, notes

def test_percent_never_rounds_to_zero_or_all():
    percent, shown_paths, summary_line = report.percent, report.shown_paths, report.summary_line
    assert percent(0.0) == "0%" and percent(1.0) == "100%"
    assert percent(1e-6) == "<0.01%" and percent(0.99999) == ">99.99%"
    assert percent(0.5) == "50.00%" and percent(0.0001) == "0.01%"
    rep = {"shape": [10, 10], "shadow_fraction": 1e-7, "mpix_per_s": None, "output": "/abs/o.tif",
           "algorithm": "smap", "backend": "cpu", "threads": 1, "sun": {"azimuth": 1.0,
                                                                        "elevation": 2.0},
           "seconds": {"compute": 0.1, "total": 0.2}}
    line = summary_line(rep)
    assert "<0.01% of valid cells in shadow" in line and "0.00%" not in line
    assert summary_line(rep, "o.tif").startswith("hillshade-rt: o.tif: ")
    assert shown_paths(["a", "b", "c", "d"]) == "a .. d (4 files)"
    assert shown_paths(["a", "b"]) == "a, b"


def test_every_command_names_outputs_as_given(tmp_path, runner, dem, monkeypatch):
    monkeypatch.chdir(tmp_path)
    runs = {"s.tif": ["shadow", dem, "s.tif", "--azimuth", "200", "--elevation", "10"],
            "h.tif": ["hillshade", dem, "h.tif"],
            "u.tif": ["sun-hours", dem, "u.tif", "--date", "2026-06-21", "--step", "6h"],
            "z.tif": ["horizon", dem, "z.tif", "--azimuth", "200"]}
    for name, args in runs.items():
        r = runner.invoke(cli, args)
        assert r.exit_code == 0, r.output
        assert r.stderr.startswith(f"hillshade-rt: {name}: "), r.stderr
        assert str(tmp_path) not in r.stderr


def test_pattern_runs_name_the_files(tmp_path, runner, dem, monkeypatch):
    monkeypatch.chdir(tmp_path)
    times = [a for h in (8, 10, 12, 14) for a in ("--time", f"2026-06-21T{h:02d}:00-06:00")]
    r = runner.invoke(cli, ["shadow", dem, "--output-pattern", "p_{index}.tif"] + times)
    assert r.exit_code == 0, r.output
    assert r.stderr.startswith("hillshade-rt: p_0.tif .. p_3.tif (4 files): "), r.stderr
    assert "{index}" not in r.stderr
    r = runner.invoke(cli, ["shadow", dem, "--output-pattern", "one_{index}.tif", "--azimuth", "200",
                            "--elevation", "10"])
    assert r.exit_code == 0 and r.stderr.startswith("hillshade-rt: one_0.tif: "), r.stderr


def test_the_per_row_note_names_the_reason_and_only_when_asked(tmp_path, runner):
    sun = ["--azimuth", "203.7", "--elevation", "10"]
    r = runner.invoke(cli, ["shadow", SRTM, str(tmp_path / "a.tif")] + sun)
    assert r.exit_code == 0, r.output
    assert "note:" not in r.stderr and len(r.stderr.strip().splitlines()) == 1   # every SRTM run
    r = runner.invoke(cli, ["shadow", SRTM, str(tmp_path / "b.tif"), "--algorithm", "smap"] + sun)
    assert r.exit_code == 0, r.output
    notes = [ln for ln in r.stderr.splitlines() if "note:" in ln]
    assert len(notes) == 1 and "ground spacing varies per row" in notes[0], r.stderr
    assert "ray direction" not in r.stderr
    r = runner.invoke(cli, ["horizon", SRTM, str(tmp_path / "h.tif"), "--azimuth", "203.7",
                            "--method", "hull"])
    assert r.exit_code == 0, r.output
    notes = [ln for ln in r.stderr.splitlines() if "note:" in ln]
    assert len(notes) == 1 and "hull replaced by scan" in notes[0], r.stderr
    assert "ray direction" not in r.stderr


# ---------------------------------------------------------------------------------------------
# item 14: the smallest --max-memory

def test_max_memory_too_small_says_what_would_do(tmp_path, runner):
    out = tmp_path / "m.tif"
    args = ["shadow", LIDAR, str(out), "--azimuth", "163", "--elevation", "10", "-q"]
    r = runner.invoke(cli, args + ["--max-memory", "20MB"])
    _one_line(r, 1, "give at least --max-memory ")
    least = re.search(r"give at least --max-memory (\S+)$", r.stderr.strip()).group(1)
    assert not out.exists() and os.listdir(tmp_path) == []
    r = runner.invoke(cli, args + ["--max-memory", least])
    assert r.exit_code == 0, r.output


# ---------------------------------------------------------------------------------------------
# years outside the solar position algorithm's range; warnings as one line

FAR = "9999-06-21"


@pytest.mark.parametrize("args", [
    ["shadow", "{dem}", "{out}", "--time", FAR + "T12:00Z", "-q"],
    ["hillshade", "{dem}", "{out}", "--start", FAR + "T10:00Z", "--end", FAR + "T12:00Z",
     "--step", "1h", "-q"],
    ["shadow", "{dem}", "{out}", "--start", "2026-06-21T10:00Z", "--end", FAR + "T12:00Z",
     "--step", "1h", "-q"],
    ["sun-hours", "{dem}", "{out}", "--date", FAR, "-q"],
    ["sun-hours", "{dem}", "{out}", "--date", "2026-06-21", "--end-date", FAR, "-q"],
    ["irradiance", "{dem}", "{out}", "--date", FAR, "-q"],
    ["query", "{dem}", "--at-xy", "476300,4399700", "--time", FAR + "T12:00Z"],
    ["animate", "{dem}", "{gif}", "--date", FAR, "-q"],
])
def test_years_outside_the_spa_are_refused(tmp_path, runner, dem, args):
    out, gif = str(tmp_path / "o.tif"), str(tmp_path / "o.gif")
    before = sorted(os.listdir(tmp_path))
    r = runner.invoke(cli, [a.format(dem=dem, out=out, gif=gif) for a in args])
    _one_line(r, 2, "year 9999 is outside the solar position algorithm's range (NREL SPA: "
                    "years -2000 to 6000)")
    assert "site-packages" not in r.stderr and "Warning" not in r.stderr
    _nothing_new(tmp_path, before)


def test_years_outside_the_spa_from_python(tmp_path, dem):
    import datetime as dt
    from hillshade_rt.errors import UsageProblem
    from hillshade_rt.model.solar import solar_position
    with pytest.raises(UsageProblem, match="outside the solar position algorithm's range"):
        hr.shade(dem, tmp_path / "o.tif", times=[FAR + "T12:00Z"])
    far = dt.datetime(7000, 1, 1, tzinfo=dt.timezone.utc)
    with pytest.raises(UsageProblem, match="year 7000"):
        solar_position([far], 45.0, 7.0)
    assert not (tmp_path / "o.tif").exists()


def test_an_extrapolated_delta_t_is_one_line_even_with_q(tmp_path, dem):
    import subprocess
    import sys
    p = subprocess.run([sys.executable, "-m", "hillshade_rt", "shadow", dem,
                        str(tmp_path / "o.tif"), "--time", "4000-06-21T12:00Z", "-q"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hillshade-rt: warning: year 4000: delta T"), \
        p.stderr
    assert "site-packages" not in p.stderr and "warnings.warn" not in p.stderr


def test_warnings_raised_inside_a_run_are_one_line_each(tmp_path, runner, dem, monkeypatch):
    import warnings
    from hillshade_rt.engine import shader
    real = shader.render

    def noisy(*a, **k):
        np.log(np.zeros(1))                                         # numpy's RuntimeWarning
        warnings.warn_explicit("Something odd.\n  with a second line", UserWarning,
                               "/usr/lib/python3/site-packages/pvlib/spa.py", 1261)
        warnings.warn_explicit("Dataset has no geotransform", UserWarning,
                               "/opt/venv/lib/python3.11/site-packages/rasterio/__init__.py", 9)
        return real(*a, **k)
    monkeypatch.setattr(shader, "render", noisy)
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif"), "--azimuth", "200",
                            "--elevation", "10", "-q"])
    assert r.exit_code == 0, r.output
    lines = r.stderr.strip().splitlines()
    assert lines == ["hillshade-rt: warning: divide by zero encountered in log (RuntimeWarning)",
                     "hillshade-rt: warning: Something odd. (UserWarning from pvlib)",
                     "hillshade-rt: warning: Dataset has no geotransform (UserWarning from "
                     "rasterio)"], r.stderr
    assert "site-packages" not in r.stderr


# ---------------------------------------------------------------------------------------------
# exit statuses: a folder as the DEM, standard output as OUTPUT

def _run_of(command, dem, out):
    return {"shadow": ["shadow", dem, out, "--azimuth", "200", "--elevation", "10"],
            "sun-hours": ["sun-hours", dem, out, "--date", "2026-06-21", "--step", "6h"],
            "horizon": ["horizon", dem, out, "--azimuth", "200"]}[command]


@pytest.mark.parametrize("command", ["shadow", "sun-hours", "horizon"])
def test_a_folder_as_the_dem_fails_like_a_missing_file(tmp_path, runner, command):
    folder = tmp_path / "tiles"
    folder.mkdir()
    out = str(tmp_path / "o.tif")
    r = runner.invoke(cli, _run_of(command, str(folder), out))
    _one_line(r, 1, f"hillshade-rt: error: {folder}: is a folder, not a raster file")
    missing = runner.invoke(cli, _run_of(command, str(tmp_path / "absent.tif"), out))
    _one_line(missing, 1, "absent.tif: no such file")
    assert not os.path.exists(out)


@pytest.mark.parametrize("command", ["shadow", "sun-hours", "horizon"])
def test_standard_output_as_output_is_one_usage_error_in_every_spelling(tmp_path, runner, dem,
                                                                         command):
    before = sorted(os.listdir(tmp_path))
    for out in ("-", "/vsistdout/"):
        r = runner.invoke(cli, _run_of(command, dem, out))
        _one_line(r, 2, f"'{out}' (standard output) is not supported for outputs")
    _nothing_new(tmp_path, before)
