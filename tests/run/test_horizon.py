"""``hillshade-rt horizon``: one azimuth, or ``--directions N`` (issue 20) — one band per
direction, clockwise from north, 0 first."""

import math
import re

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band, write_geotiff

SRTM = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")      # geographic (EPSG:4326)
FLAT = ["--no-earth-curvature"]


@pytest.mark.slow
def test_directions_are_the_single_azimuth_runs_band_by_band(tmp_path, runner):
    """Band i is exactly the run toward i * 360 / N; descriptions and tags say which."""
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--directions", "10"])
    assert r.exit_code == 0, r.output
    assert "10 directions (36 deg apart)" in r.stderr
    with rasterio.open(out) as ds:
        assert ds.count == 10 and ds.dtypes[0] == "float32" and ds.nodata == -9999.0
        assert ds.descriptions[3] == "horizon angle toward azimuth 108"
        assert ds.tags()["AZIMUTHS"] == "0,36,72,108,144,180,216,252,288,324"
        assert ds.tags(4)["AZIMUTH"] == "108"
    for band, az in ((2, 36.0), (9, 288.0)):
        one = tmp_path / f"one{band}.tif"
        r = runner.invoke(cli, ["horizon", SRTM, str(one), "--azimuth", str(az)])
        assert r.exit_code == 0, r.output
        np.testing.assert_array_equal(read_band(out, band), read_band(one))


@pytest.mark.slow
def test_each_direction_decides_the_shadows_of_a_sun_there(tmp_path, runner):
    """The horizon toward the sun's azimuth decides every shadow: a cell is shadowed iff its
    angle exceeds the sun's elevation, cell for cell against brute (non-special azimuths)."""
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--directions", "10"] + FLAT)
    assert r.exit_code == 0, r.output
    for band, az, el in ((3, 72.0, 4.0), (6, 180.0, 9.0), (9, 288.0, 2.5)):
        m = tmp_path / f"m{band}.tif"
        r = runner.invoke(cli, ["shadow", SRTM, str(m), "--azimuth", str(az), "--elevation",
                                str(el), "--algorithm", "brute"] + FLAT)
        assert r.exit_code == 0, r.output
        beta, mask = read_band(out, band), read_band(m)
        valid = mask != 255
        assert np.array_equal(valid, beta != -9999.0)
        assert np.array_equal((beta > el)[valid], (mask == 1)[valid]), (az, el)
        assert 0.02 < (mask[valid] == 1).mean() < 0.98       # the test can fail both ways


def test_tilted_plane_uphill_is_its_slope_and_downhill_minus_it(tmp_path, runner):
    """An analytic case: a plane rising northward at slope S (flat model): toward north every
    cell but the top row sees the plane's own angle S; toward south -S (it looks down the
    plane; the nearest sample is the highest); no terrain beyond the raster: -90 at the edge."""
    rows, cols, d, s = 60, 40, 10.0, 0.3
    z = ((rows - 1 - np.arange(rows))[:, None] * d * s + np.zeros((1, cols))).astype(np.float32)
    dem = write_geotiff(tmp_path / "plane.tif", z, Affine(d, 0, 500000, 0, -d, 4000000),
                        CRS.from_epsg(32633))
    out = tmp_path / "h.tif"
    # --pixel-size: 10 m on the ground (UTM's grid metres are 1/0.9996 of them near its
    # central meridian)
    r = runner.invoke(cli, ["horizon", dem, str(out), "--directions", "8", "--pixel-size",
                            str(d)] + FLAT)
    assert r.exit_code == 0, r.output
    slope = math.degrees(math.atan(s))
    north, south = read_band(out, 1), read_band(out, 5)
    np.testing.assert_allclose(north[1:], slope, atol=1e-4)
    np.testing.assert_allclose(south[:-1], -slope, atol=1e-4)
    assert (north[0] == -90).all() and (south[-1] == -90).all()
    east = read_band(out, 3)                      # along the contour: level
    np.testing.assert_allclose(east[:, :-1], 0.0, atol=1e-4)


@pytest.mark.parametrize("args, code, words", [
    (["--directions", "4"], 2, "8<=x<=360"),
    (["--directions", "100000"], 2, "8<=x<=360"),
    ([], 2, "give --azimuth A (one direction), --directions N or --start/--end/--step"),
    (["--directions", "8", "--azimuth", "10"], 2, "one of them"),
    (["--directions", "8", "--step", "10"], 2, "one of them"),
    (["--start", "10", "--end", "50"], 2, "--start and --end go with --step"),
    (["--step", "10", "--start", "400"], 2, "--start must be in [0, 360)"),
    (["--step", "45", "--angle-unit", "grads"], 2, "'grads' is not one of"),
])
def test_bad_directions_are_one_line_and_write_nothing(tmp_path, runner, args, code, words):
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out)] + args)
    assert r.exit_code == code and words in r.stderr and len(r.stderr.splitlines()) == 1
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_distance_is_the_nearest_sample_of_the_maximum(tmp_path, runner):
    """--distance: toward north on an axis the samples are the cells above; an independent
    plain-Python scan finds each cell's maximum (the nearest of equal ones) and its distance,
    which the file must hold, with the angle the file gives; -9999 where nothing lies ahead."""
    rng = np.random.default_rng(5)
    rows, cols, d = 40, 12, 25.0
    z = (rng.random((rows, cols)) * 80.0).astype(np.float32)
    z[7, 3] = np.nan
    dem = write_geotiff(tmp_path / "r.tif", z, Affine(d, 0, 500000, 0, -d, 4000000),
                        CRS.from_epsg(32633))
    out, dist = tmp_path / "h.tif", tmp_path / "d.tif"
    r = runner.invoke(cli, ["horizon", dem, str(out), "--azimuth", "0", "--distance", str(dist),
                            "--pixel-size", str(d)] + FLAT)
    assert r.exit_code == 0, r.output
    beta, got = read_band(out), read_band(dist)
    for i in range(rows):
        for j in range(cols):
            if np.isnan(z[i, j]):
                assert got[i, j] == -9999.0 and beta[i, j] == -9999.0
                continue
            best, kbest = -np.inf, 0
            for k in range(1, i + 1):
                t = z[i - k, j]
                if not np.isnan(t) and (float(t) - float(z[i, j])) / k > best:
                    best, kbest = (float(t) - float(z[i, j])) / k, k
            if kbest == 0:
                assert got[i, j] == -9999.0 and beta[i, j] == -90.0
            else:
                assert got[i, j] == pytest.approx(kbest * d, rel=1e-6), (i, j)
                assert beta[i, j] == pytest.approx(math.degrees(math.atan(best / d)), abs=1e-4)
    # the hull keeps no horizon point
    r = runner.invoke(cli, ["horizon", dem, str(tmp_path / "h2.tif"), "--azimuth", "0",
                            "--method", "hull", "--distance", str(tmp_path / "d2.tif")])
    assert r.exit_code == 2 and "--method scan only" in r.stderr


def test_distance_bands_follow_the_directions(tmp_path, runner):
    out, dist = tmp_path / "h.tif", tmp_path / "d.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--directions", "8", "--distance",
                            str(dist)])
    assert r.exit_code == 0, r.output
    with rasterio.open(dist) as ds:
        assert ds.count == 8 and ds.descriptions[2].endswith("toward azimuth 90")
        d3 = ds.read(3)
    b3 = read_band(out, 3)
    assert np.array_equal(d3 == -9999.0, (b3 == -9999.0) | (b3 == -90.0))
    assert (d3[d3 != -9999.0] > 0).all()


# ---------------------------------------------------------------------------------------------
# --max-distance and windows (issue 20, items 1 and 3)

EVEREST = data_path("everest_srtm3_voids_crop200.tif")     # geographic, with voids


def _fractal_dem(tmp_path, rows=150, cols=170, seed=11):
    """A rough terrain with voids (inside and on the edge), 30 m cells in UTM."""
    from hillshade_rt.testing import fractal_terrain
    z = fractal_terrain(rows, cols, seed, relief=600.0, octaves=5) + 1000.0
    z[40:46, 70:79] = np.nan
    z[0, 12] = np.nan
    return write_geotiff(tmp_path / "fractal.tif", z.astype(np.float32),
                         Affine(30.0, 0, 500000, 0, -30.0, 4000000), CRS.from_epsg(32633))


def _bands(path):
    with rasterio.open(path) as ds:
        return ds.read(), ds.descriptions, ds.tags()


@pytest.mark.slow
@pytest.mark.parametrize("dem", ["fractal", "everest"])
@pytest.mark.parametrize("args", [["--azimuth", "203.7"], ["--directions", "8"],
                                  ["--directions", "8", "--max-distance", "2500"]])
def test_windows_give_the_bits_of_the_run_in_memory(tmp_path, runner, dem, args):
    """--window-size 64: every band of the angles and of --distance equals the run in memory
    bit for bit, on a fractal (UTM) and a real DEM (geographic: per-row spacing; voids), toward
    a non-special azimuth and 8 directions, with and without a maximum distance (curvature on:
    both rasters are more than 1 km across); the preview too."""
    path = _fractal_dem(tmp_path) if dem == "fractal" else EVEREST
    runs = {}
    for name, extra in (("mem", []), ("win", ["--window-size", "64"])):
        out, dist = tmp_path / f"{name}.tif", tmp_path / f"{name}_d.tif"
        r = runner.invoke(cli, ["horizon", path, str(out), "--distance", str(dist),
                                "--preview", str(tmp_path / f"{name}.png")] + args + extra)
        assert r.exit_code == 0, r.output
        assert bool(re.search(r", \d+ windows\)", r.stderr)) == (name == "win"), r.stderr
        runs[name] = (_bands(out), _bands(dist))
    (a, ad, at), (b, bd, bt) = runs["mem"][0], runs["win"][0]
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(runs["mem"][1][0], runs["win"][1][0])
    assert ad == bd and at == bt
    assert (a == -90).any() and (a > 5).any() and (a < -5).any()    # horizons of all kinds
    np.testing.assert_array_equal(read_band(tmp_path / "mem.png"), read_band(tmp_path / "win.png"))


def test_max_distance_on_the_command_line(tmp_path, runner):
    """Beyond the raster, M changes no bit; a short M keeps every horizon point within M and
    changes the horizons of cells whose horizon lay farther; the tag says which M."""
    path = _fractal_dem(tmp_path)
    outs = {}
    for m in (None, "1e6", "400"):
        out, dist = tmp_path / f"h{m}.tif", tmp_path / f"d{m}.tif"
        r = runner.invoke(cli, ["horizon", path, str(out), "--azimuth", "163", "--distance",
                                str(dist)] + ([] if m is None else ["--max-distance", m]))
        assert r.exit_code == 0, r.output
        outs[m] = (read_band(out), read_band(dist), _bands(out)[2])
    np.testing.assert_array_equal(outs[None][0], outs["1e6"][0])
    np.testing.assert_array_equal(outs[None][1], outs["1e6"][1])
    beta, dist, tags = outs["400"]
    far = outs[None][1] > 400
    assert far.sum() > 100 and (beta[far] != outs[None][0][far]).all()
    near = (outs[None][1] <= 400) & (outs[None][1] > 0)
    np.testing.assert_array_equal(beta[near], outs[None][0][near])
    assert (dist[dist != -9999] <= 400).all()
    assert tags["MAX_DISTANCE"].startswith("400 m") and outs[None][2]["MAX_DISTANCE"].startswith(
        "none")


@pytest.mark.slow
def test_max_memory_switches_to_windows(tmp_path):
    """A --max-memory the DEM does not fit runs in windows, within that memory, with the bits
    of the run in memory."""
    from hillshade_rt.run import HorizonConfig, horizon
    from hillshade_rt.engine import windows as tiling
    from hillshade_rt.run.config import RunOptions
    path = _fractal_dem(tmp_path, 400, 400)
    reps = {}
    for name in ("mem", "win"):
        # room for the process, GDAL's cache and about 3 MB of windows: the DEM needs 3.8
        limit = tiling.process_rss() + ((tiling.GDAL_CACHE_MB + 32 + 3) << 20)
        reps[name] = horizon(HorizonConfig(dem=path, output=str(tmp_path / f"{name}.tif"),
                                           directions=8,
                                           max_memory=None if name == "mem" else str(limit),
                                           run=RunOptions(quiet=True)))
    doc = reps["win"]["processing"]
    assert doc["mode"] == "windows" and doc["regions"] > 1
    assert reps["mem"]["processing"]["mode"] == "in memory"
    assert doc["largest_window"] * 6 <= doc["memory"]["window_bytes"]
    np.testing.assert_array_equal(_bands(tmp_path / "mem.tif")[0], _bands(tmp_path / "win.tif")[0])


@pytest.mark.parametrize("args, code, words", [
    (["--max-distance", "0"], 2, "--max-distance"),
    (["--max-distance", "-3"], 2, "--max-distance"),
    (["--max-distance", "nan"], 2, "--max-distance"),
    (["--max-distance", "inf"], 2, "--max-distance"),
    (["--max-distance", "300", "--method", "hull"], 2, "--method scan only"),
    (["--window-size", "64", "--method", "hull"], 2, "in memory only"),
    (["--window-size", "8"], 2, "at least 64"),
    (["--max-memory", "lots"], 2, "--max-memory"),
    (["--max-memory", "20MB"], 1, "give at least --max-memory"),
])
def test_bad_reach_options_are_one_line_and_write_nothing(tmp_path, runner, args, code, words):
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--azimuth", "203.7"] + args)
    assert r.exit_code == code, r.output
    assert words in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_windows_on_dask_give_the_same_files(tmp_path, runner):
    """--scheduler local:2: the regions as Dask tasks, their parts put together through a VRT:
    the bands, descriptions and tags of the run in memory (angles and distances), no parts
    left behind."""
    runs = {}
    for name, extra in (("mem", []), ("dask", ["--window-size", "64", "--scheduler", "local:2"])):
        out, dist = tmp_path / f"{name}.tif", tmp_path / f"{name}_d.tif"
        r = runner.invoke(cli, ["horizon", EVEREST, str(out), "--directions", "8", "--distance",
                                str(dist), "--max-distance", "4000"] + extra)
        assert r.exit_code == 0, r.output
        runs[name] = (_bands(out), _bands(dist))
    assert "16 windows on Dask" in r.stderr
    for i in range(2):
        (a, ad, at), (b, bd, bt) = runs["mem"][i], runs["dask"][i]
        np.testing.assert_array_equal(a, b)
        assert ad == bd and at == bt
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dask.tif", "dask_d.tif", "mem.tif",
                                                          "mem_d.tif"]


def _check_report(path, keys):
    """The report at ``path`` parses, has ``keys`` and its phases' seconds add up."""
    import json
    rep = json.loads(path.read_text())
    assert set(keys) <= set(rep), set(keys) - set(rep)
    sec = rep["seconds"]
    phases = [sec[k] for k in ("read", "prepare", "compute", "write")]
    assert all(s >= 0.0 for s in phases) and sec["total"] >= sum(phases) - 1e-3
    return rep


def test_report_of_horizon_and_its_clash(tmp_path, runner):
    """--report: the run's JSON (absolute output, the azimuths, threads, the phases' seconds);
    a report path that is the DEM or OUTPUT is a usage error (exit 2, one line)."""
    out, rep = tmp_path / "h.tif", tmp_path / "h.json"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--azimuth", "203.7", "--report",
                            str(rep), "--threads", "1"])
    assert r.exit_code == 0, r.output
    doc = _check_report(rep, ["input", "output", "shape", "azimuths", "method", "backend",
                              "threads", "angle_deg", "version"])
    assert doc["output"] == str(out.resolve()) and doc["azimuths"] == [203.7]
    assert doc["shape"] == [344, 403] and doc["threads"] == 1
    st = doc["angle_deg"]
    assert -90.0 <= st["min"] <= st["mean"] <= st["max"] <= 90.0
    rep2 = tmp_path / "w.json"         # in windows: the same figures
    r = runner.invoke(cli, ["horizon", SRTM, str(tmp_path / "w.tif"), "--azimuth", "203.7",
                            "--window-size", "100", "--report", str(rep2)])
    assert r.exit_code == 0, r.output
    w = _check_report(rep2, ["angle_deg"])["angle_deg"]
    assert w["min"] == st["min"] and w["max"] == st["max"]
    assert abs(w["mean"] - st["mean"]) < 1e-9
    for clash in (SRTM, str(out)):
        r = runner.invoke(cli, ["horizon", SRTM, str(out), "--azimuth", "163", "--report",
                                clash, "--overwrite"])
        assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.output
        assert "--report" in r.stderr


def _small_dem(tmp_path):
    """A rough 100 x 120 terrain with a void, 30 m cells in UTM (curvature on: 3.6 km
    across)."""
    from hillshade_rt.testing import fractal_terrain
    z = fractal_terrain(100, 120, 11, relief=400.0, octaves=5) + 500.0
    z[20:23, 30:34] = np.nan
    return write_geotiff(tmp_path / "small.tif", z.astype(np.float32),
                         Affine(30.0, 0, 500000, 0, -30.0, 4000000), CRS.from_epsg(32633))


def test_start_end_step_are_directions_where_they_coincide(tmp_path, runner):
    """--step 45 (start 0, end 360) is --directions 8, bit for bit, its tags aside; --start 0
    --end 360 --step 30 is --directions 12."""
    dem = _small_dem(tmp_path)
    for series, n in ((["--step", "45"], 8), (["--start", "0", "--end", "360", "--step", "30"],
                                               12)):
        a, b = tmp_path / f"a{n}.tif", tmp_path / f"b{n}.tif"
        r = runner.invoke(cli, ["horizon", dem, str(a), "-q"] + series)
        assert r.exit_code == 0, r.output
        r = runner.invoke(cli, ["horizon", dem, str(b), "-q", "--directions", str(n)])
        assert r.exit_code == 0, r.output
        (va, da, ta), (vb, db, tb) = _bands(a), _bands(b)
        assert va.shape[0] == n and da == db
        np.testing.assert_array_equal(va, vb)
        assert ta["AZIMUTHS"] == tb["AZIMUTHS"] and ta["STEP"] == f"{360 / n:g}"


def test_start_step_bands_are_the_single_azimuth_runs(tmp_path, runner):
    """--start 163 --step 40.7: floor(360 / 40.7) = 8 bands at 163 + 40.7 k (mod 360), each
    the --azimuth run toward it, bit for bit; the descriptions give the azimuths; the report
    and the summary say the series."""
    dem = _small_dem(tmp_path)
    out, rep = tmp_path / "s.tif", tmp_path / "s.json"
    r = runner.invoke(cli, ["horizon", dem, str(out), "--start", "163", "--step", "40.7",
                            "--report", str(rep)])
    assert r.exit_code == 0, r.output
    assert "8 directions (az 163 to 523 every 40.7 deg)" in r.stderr
    azimuths = [(163.0 + 40.7 * k) % 360.0 for k in range(8)]
    vals, desc, tags = _bands(out)
    assert vals.shape[0] == 8
    assert tags["START"] == "163" and tags["END"] == "523" and tags["STEP"] == "40.7"
    assert "r.horizon" in tags["AZIMUTH_CONVENTION"]
    import json
    report = json.loads(rep.read_text())
    assert report["azimuths"] == pytest.approx(azimuths)
    assert report["series"] == {"start": 163.0, "end": 523.0, "step": 40.7}
    assert report["angle_unit"] == "degrees"
    for k in (0, 3, 5):          # 163, 285.1, 1.5 (past north)
        assert desc[k] == f"horizon angle toward azimuth {azimuths[k]:g}"
        one = tmp_path / f"one{k}.tif"
        r = runner.invoke(cli, ["horizon", dem, str(one), "-q", "--azimuth", repr(azimuths[k])])
        assert r.exit_code == 0, r.output
        np.testing.assert_array_equal(vals[k], read_band(one))
    assert len(np.unique(vals[3])) > 10


@pytest.mark.parametrize("extra", [[], ["--window-size", "64"],
                                   pytest.param(["--window-size", "64", "--scheduler", "local:1"],
                                                marks=pytest.mark.slow)])
def test_radians_are_the_degrees_times_pi_over_180(tmp_path, runner, extra):
    """--angle-unit radians: every angle the degrees' times float32(pi / 180), bit for bit
    (in memory, in windows, on Dask); -9999 stays nodata, -90 (no terrain ahead) becomes -pi/2; the
    tags say the unit."""
    dem = _small_dem(tmp_path)
    deg, rad = tmp_path / "deg.tif", tmp_path / "rad.tif"
    args = ["--start", "10", "--end", "300", "--step", "72.5"] + extra
    r = runner.invoke(cli, ["horizon", dem, str(deg), "-q"] + args)
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, ["horizon", dem, str(rad), "-q", "--angle-unit", "radians"] + args)
    assert r.exit_code == 0, r.output
    (d, dd, dt), (q, qd, qt) = _bands(deg), _bands(rad)
    assert d.shape[0] == 4 and dd == qd
    void = d == -9999.0
    assert void.any() and (q[void] == -9999.0).all()
    np.testing.assert_array_equal(q[~void], d[~void] * np.float32(math.pi / 180.0))
    np.testing.assert_allclose(q[~void], np.radians(d[~void].astype(np.float64)), rtol=2e-7)
    assert (d == -90.0).any() and np.allclose(q[d == -90.0], -math.pi / 2)
    assert dt["UNITS"] == "degrees above the horizontal"
    assert qt["UNITS"] == "radians above the horizontal"
    assert qt["NO_TERRAIN_AHEAD"].startswith("-1.57079")


def test_horizon_from_python_takes_the_same_keywords(tmp_path, runner):
    """hillshade_rt.horizon: the command as a function, start/end/step and angle_unit as
    keywords; its errors name the keywords."""
    import hillshade_rt as hr
    dem = _small_dem(tmp_path)
    r = runner.invoke(cli, ["horizon", dem, str(tmp_path / "cli.tif"), "-q", "--start", "163",
                            "--end", "400", "--step", "40.7", "--angle-unit", "radians"])
    assert r.exit_code == 0, r.output
    rep = hr.horizon(dem, tmp_path / "api.tif", start=163, end=400, step=40.7,
                     angle_unit="radians")
    assert rep["azimuths"] == pytest.approx([163.0 + 40.7 * k for k in range(5)])
    np.testing.assert_array_equal(_bands(tmp_path / "api.tif")[0],
                                  _bands(tmp_path / "cli.tif")[0])
    with pytest.raises(hr.HillshadeError) as e:
        hr.horizon(dem, tmp_path / "x.tif", directions=8, step=10)
    assert "directions N or start/end/step" in str(e.value) and "--" not in str(e.value)
    with pytest.raises(TypeError, match="elevation"):
        hr.horizon(dem, tmp_path / "x.tif", step=10, elevation=3)
    assert not (tmp_path / "x.tif").exists()
