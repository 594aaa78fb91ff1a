"""``hillshade-rt skyview`` (issue 20, item 3): the sky view factor from the exact horizon, two
definitions, checked on planes where both are known in closed form."""

import json
import math
import re

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band, write_geotiff

FLAT = ["--no-earth-curvature"]


def _plane(tmp_path, slope_deg, rows=40, cols=44, d=10.0):
    """A plane rising northward at ``slope_deg`` (its downslope aspect: south)."""
    s = math.tan(math.radians(slope_deg))
    z = ((rows - 1 - np.arange(rows))[:, None] * d * s + np.zeros((1, cols))).astype(np.float32)
    return write_geotiff(tmp_path / f"plane{slope_deg}.tif", z,
                         Affine(d, 0, 500000, 0, -d, 4000000), CRS.from_epsg(32633))


def _expected(slope_deg, n, definition):
    """The definitions' sums over the same n directions for a plane rising north: the horizon
    toward φ is atan(tan S cos φ), clipped at the horizontal."""
    S = math.radians(slope_deg)
    phi = np.radians(360.0 * np.arange(n) / n)
    g = np.maximum(np.arctan(math.tan(S) * np.cos(phi)), 0.0)
    if definition == "zaksek":
        return 1.0 - np.mean(np.sin(g))
    h = np.pi / 2 - g
    sc = -math.sin(S) * np.cos(phi)        # sin S cos(φ - A), aspect A = 180 (south)
    return np.mean(math.cos(S) * np.sin(h) ** 2 + sc * (h - np.sin(h) * np.cos(h)))


@pytest.mark.parametrize("definition", ["zaksek", "dozier"])
def test_planes_give_the_closed_forms(tmp_path, runner, definition):
    """A flat plane: 1; a plane of slope S: the definition's sum over the same directions (and
    near its continuous form: 1 - S/π for Zakšek, (1 + cos S)/2 for Dozier) in every cell with
    terrain in every direction (the border sees open sky outward)."""
    for slope in (0.0, 20.0):
        out = tmp_path / f"svf{slope}.tif"
        r = runner.invoke(cli, ["skyview", _plane(tmp_path, slope), str(out), "--directions",
                                "36", "--definition", definition, "--pixel-size", "10"] + FLAT)
        assert r.exit_code == 0, r.output
        svf = read_band(out)[1:-1, 1:-1]
        want = _expected(slope, 36, definition)
        np.testing.assert_allclose(svf, want, atol=2e-5)
        cont = (1 - math.radians(slope) / math.pi if definition == "zaksek"
                else (1 + math.cos(math.radians(slope))) / 2)
        assert want == pytest.approx(cont, abs=2e-3)


def test_terrain_configuration_is_the_rest_of_the_tilted_hemisphere(tmp_path, runner):
    """1 - Vd: on a plane of slope S, (1 - cos S)/2 in the continuous limit, the Dozier sum's
    complement over the same directions cell for cell; it needs --definition dozier."""
    out = tmp_path / "ct.tif"
    dem = _plane(tmp_path, 30.0)
    r = runner.invoke(cli, ["skyview", dem, str(out), "--directions", "36", "--definition",
                            "dozier", "--terrain-configuration", "--pixel-size", "10"] + FLAT)
    assert r.exit_code == 0, r.output
    ct = read_band(out)[1:-1, 1:-1]
    np.testing.assert_allclose(ct, 1.0 - _expected(30.0, 36, "dozier"), atol=2e-5)
    assert ct.mean() == pytest.approx((1 - math.cos(math.radians(30.0))) / 2, abs=2e-3)
    r = runner.invoke(cli, ["skyview", dem, str(tmp_path / "x.tif"), "--terrain-configuration"])
    assert r.exit_code == 2 and "--definition dozier" in r.stderr


def test_pits_see_less_sky_than_peaks_on_real_terrain(tmp_path, runner):
    """On a real DEM: values in (0, 1], and the cells lowest in their 5x5 neighbourhood (valley
    floors) see less sky than the highest (summits), by both definitions."""
    from numpy.lib.stride_tricks import sliding_window_view
    from hillshade_rt.io import read_dem
    dem = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")
    z = read_dem(dem).heights
    win = sliding_window_view(np.pad(z, 2, constant_values=np.nan), (5, 5))
    with np.errstate(invalid="ignore"):
        peak = z >= np.nanmax(win, axis=(2, 3))
        pit = z <= np.nanmin(win, axis=(2, 3))
    for definition in ("zaksek", "dozier"):
        out = tmp_path / f"{definition}.tif"
        r = runner.invoke(cli, ["skyview", dem, str(out), "--directions", "16",
                                "--definition", definition])
        assert r.exit_code == 0, r.output
        svf = read_band(out)
        ok = (svf != -9999.0) & ~np.isnan(z)
        assert (svf[ok] > 0.3).all() and (svf[ok] <= 1.0 + 1e-6).all()
        assert peak[ok].sum() > 20 and pit[ok].sum() > 20
        assert svf[ok & pit].mean() < svf[ok & peak].mean() - 0.01, definition


@pytest.mark.parametrize("args, words", [(["--directions", "2"], "4<=x<=360"),
                                         (["--definition", "rvt"], "--definition")])
def test_bad_options_are_usage_errors(tmp_path, runner, args, words):
    out = tmp_path / "s.tif"
    r = runner.invoke(cli, ["skyview", data_path("jacksboro_fault_srtm3_mpl_403x344.tif"),
                            str(out)] + args)
    assert r.exit_code == 2 and words in r.stderr and not out.exists()


# ---------------------------------------------------------------------------------------------
# --openness, --max-distance, windows (issue 20, items 1-3)

def _openness(tmp_path, runner, dem, sign, extra=()):
    out = tmp_path / f"o{sign}.tif"
    r = runner.invoke(cli, ["skyview", dem, str(out), "--openness", sign, "--overwrite",
                            "--pixel-size", "10"] + FLAT + list(extra))
    assert r.exit_code == 0, r.output
    return read_band(out)


def test_openness_of_planes(tmp_path, runner):
    """A flat plane: 90 degrees both ways, in every cell (a border cell's directions with
    nothing ahead are left out, the rest see the horizontal). A plane of slope S: 90 in every
    cell with terrain in every direction (the directions pair up: atan(tan S cos(φ - A)) is odd);
    on the top (uphill) row only the directions that do not leave the raster count: positive
    90 + mean atan(tan S |cos φ|) over cos φ <= 0, negative its mirror image about 90."""
    n = 36
    flat = _plane(tmp_path, 0.0)
    for sign in ("positive", "negative"):
        np.testing.assert_allclose(_openness(tmp_path, runner, flat, sign,
                                             ["--directions", str(n)]), 90.0, atol=1e-5)
    s = 25.0
    dem = _plane(tmp_path, s)
    pos = _openness(tmp_path, runner, dem, "positive", ["--directions", str(n)])
    neg = _openness(tmp_path, runner, dem, "negative", ["--directions", str(n)])
    np.testing.assert_allclose(pos[1:-1, 1:-1], 90.0, atol=1e-4)
    np.testing.assert_allclose(neg[1:-1, 1:-1], 90.0, atol=1e-4)
    phi = np.radians(360.0 * np.arange(n) / n)
    kept = np.cos(phi) <= 1e-12                    # not north: terrain ahead of the top row
    down = np.degrees(np.arctan(math.tan(math.radians(s)) * np.abs(np.cos(phi[kept]))))
    np.testing.assert_allclose(pos[0, 1:-1], 90.0 + down.mean(), atol=1e-4)
    np.testing.assert_allclose(neg[0, 1:-1], 90.0 - down.mean(), atol=1e-4)
    assert 90.0 + down.mean() > 95.0


def test_openness_of_a_valley(tmp_path, runner):
    """A V-shaped valley running north-south, walls rising at S on both sides (z = tan S |x|):
    from its floor the horizon toward φ is atan(tan S |sin φ|) exactly (linear interpolation is
    exact on each wall), S straight across: positive openness the mean of 90 - that (below 90:
    a valley), negative the mean of 90 + that."""
    rows, cols, d, s, n = 50, 41, 10.0, 30.0, 16
    t = math.tan(math.radians(s))
    z = (t * d * np.abs(np.arange(cols) - 20.0))[None, :] + np.zeros((rows, 1))
    dem = write_geotiff(tmp_path / "valley.tif", z.astype(np.float32),
                        Affine(d, 0, 500000, 0, -d, 4000000), CRS.from_epsg(32633))
    pos = _openness(tmp_path, runner, dem, "positive", ["--directions", str(n)])
    neg = _openness(tmp_path, runner, dem, "negative", ["--directions", str(n)])
    phi = np.radians(360.0 * np.arange(n) / n)
    g = np.degrees(np.arctan(t * np.abs(np.sin(phi))))
    floor = slice(18, 32)                  # rows far from the ends: terrain in every direction
    np.testing.assert_allclose(pos[floor, 20], 90.0 - g.mean(), atol=1e-4)
    np.testing.assert_allclose(neg[floor, 20], 90.0 + g.mean(), atol=1e-4)
    h = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", dem, str(h), "--directions", str(n), "--pixel-size",
                            "10"] + FLAT)
    assert r.exit_code == 0, r.output
    np.testing.assert_allclose(read_band(h, n // 4 + 1)[floor, 20], s, atol=1e-4)   # east: S


def test_openness_is_the_reference_horizons_mean(tmp_path):
    """On rough terrain with voids, at 10 directions (36 degrees apart: most off the axes) and
    within a maximum distance: the mean of 90 - β over the directions with terrain ahead, β
    from the plain reference scan (of -z for negative openness), cell for cell."""
    import hillshade_rt as hr
    from hillshade_rt.testing import fractal_terrain, reference_horizon
    z = fractal_terrain(28, 31, 5, relief=80.0, octaves=4)
    z[9:11, 12:15] = np.nan
    for sign, zz in (("positive", z), ("negative", -z)):
        for m in (None, 70.0):
            got = hr.sky_view(z, 10.0, directions=10, openness=sign, max_distance=m,
                              curvature=False)
            acc, cnt = np.zeros(z.shape), np.zeros(z.shape)
            for a in 36.0 * np.arange(10):
                b, _ = reference_horizon(zz, 10.0, 10.0, a, max_distance=m)
                ok = b != -90.0
                acc[ok] += 90.0 - b[ok]
                cnt += ok
            with np.errstate(invalid="ignore"):
                want = np.where(cnt > 0, acc / cnt, np.nan)
            np.testing.assert_allclose(got, want, atol=1e-4)
            assert np.array_equal(np.isnan(got), np.isnan(z))
    assert (got > 95).any() and (got < 85).any()


def test_max_distance_in_skyview(tmp_path, runner):
    """Beyond the raster M changes no bit; a shorter M sees less terrain: the sky view factor
    only grows, somewhere strictly."""
    dem = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")
    svf = {}
    for m in (None, "1e7", "600"):
        out = tmp_path / f"s{m}.tif"
        r = runner.invoke(cli, ["skyview", dem, str(out), "--directions", "8"]
                          + ([] if m is None else ["--max-distance", m]))
        assert r.exit_code == 0, r.output
        svf[m] = read_band(out)
    np.testing.assert_array_equal(svf[None], svf["1e7"])
    ok = svf[None] != -9999.0
    assert (svf["600"][ok] >= svf[None][ok]).all() and (svf["600"][ok] > svf[None][ok]).any()


@pytest.mark.parametrize("dem", ["fractal", "everest"])
@pytest.mark.parametrize("args", [["--definition", "zaksek"],
                                  ["--definition", "dozier", "--terrain-configuration"],
                                  ["--openness", "positive"],
                                  ["--openness", "negative", "--max-distance", "1500"]])
def test_windows_give_the_bits_of_the_run_in_memory(tmp_path, runner, dem, args):
    """--window-size 64: the sky view factor (both definitions) and the openness (both signs)
    equal the run in memory bit for bit, on a fractal (UTM) and a real DEM (geographic: per-row
    spacing; voids), 8 directions, curvature on (more than 1 km across)."""
    if dem == "fractal":
        from hillshade_rt.testing import fractal_terrain
        z = fractal_terrain(140, 150, 4, relief=500.0, octaves=5) + 800.0
        z[30:36, 60:66] = np.nan
        path = write_geotiff(tmp_path / "f.tif", z.astype(np.float32),
                             Affine(30.0, 0, 500000, 0, -30.0, 4000000), CRS.from_epsg(32633))
    else:
        path = data_path("everest_srtm3_voids_crop200.tif")
    got = {}
    for name, extra in (("mem", []), ("win", ["--window-size", "64"])):
        out = tmp_path / f"{name}.tif"
        r = runner.invoke(cli, ["skyview", path, str(out), "--directions", "8"] + args + extra)
        assert r.exit_code == 0, r.output
        assert bool(re.search(r", (9|16) windows, ", r.stderr)) == (name == "win"), r.stderr
        got[name] = read_band(out)
    np.testing.assert_array_equal(got["mem"], got["win"])
    assert (got["mem"] == -9999.0).any() and np.unique(got["mem"]).size > 1000


@pytest.mark.parametrize("args, words", [
    (["--openness", "positive", "--definition", "dozier"], "--openness"),
    (["--openness", "negative", "--terrain-configuration"], "--openness"),
    (["--openness", "sideways"], "--openness"),
    (["--max-distance", "0"], "--max-distance"),
    (["--max-distance", "-1"], "--max-distance"),
    (["--window-size", "10x10"], "at least 64"),
])
def test_bad_openness_and_reach_options(tmp_path, runner, args, words):
    out = tmp_path / "s.tif"
    r = runner.invoke(cli, ["skyview", data_path("jacksboro_fault_srtm3_mpl_403x344.tif"),
                            str(out)] + args)
    assert r.exit_code == 2 and words in r.stderr and len(r.stderr.splitlines()) == 1, r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_windows_on_dask(tmp_path, runner):
    """--scheduler local:2: Dozier's view factor from the regions as Dask tasks equals the run
    in memory, bit for bit; the summary's mean too."""
    path = data_path("everest_srtm3_voids_crop200.tif")
    got, said = {}, {}
    for name, extra in (("mem", []), ("dask", ["--window-size", "96", "--scheduler", "local:2"])):
        out = tmp_path / f"{name}.tif"
        r = runner.invoke(cli, ["skyview", path, str(out), "--directions", "8", "--definition",
                                "dozier"] + extra)
        assert r.exit_code == 0, r.output
        got[name] = read_band(out)
        said[name] = re.search(r"mean (\S+);", r.stderr).group(1)
    assert "9 windows on Dask" in r.stderr
    np.testing.assert_array_equal(got["mem"], got["dask"])
    assert said["mem"] == said["dask"]


def test_preview_colours_the_relief_by_the_result_in_memory_and_in_windows(tmp_path, runner):
    """--preview: a PNG of the DEM's size (under 2048 cells a side), the same picture in
    memory and in windows; brighter where the sky view factor is higher (a pit's floor is
    darker than the open plain around it)."""
    import rasterio
    z = np.full((90, 100), 500.0, np.float32)
    z[30:60, 40:70] = 380.0          # a pit 120 m deep, 30 x 30 cells
    path = write_geotiff(tmp_path / "pit.tif", z, Affine(10.0, 0, 500000, 0, -10.0, 4000000),
                         CRS.from_epsg(32633))
    pics = {}
    for name, extra in (("mem", []), ("win", ["--window-size", "64"])):
        png = tmp_path / f"{name}.png"
        r = runner.invoke(cli, ["skyview", path, str(tmp_path / f"{name}.tif"), "--directions",
                                "8", "--preview", str(png)] + extra + FLAT)
        assert r.exit_code == 0, r.output
        with rasterio.open(png) as ds:
            pics[name] = ds.read()
    assert pics["mem"].shape == (3, 90, 100)
    np.testing.assert_array_equal(pics["mem"], pics["win"])
    lum = pics["mem"].astype(int).sum(axis=0)
    assert lum[45, 55] < lum[10, 10]        # the pit's centre sees less sky than the plain


def _check_report(path, keys):
    """The report at ``path`` parses, has ``keys`` and its phases' seconds add up."""
    rep = json.loads(path.read_text())
    assert set(keys) <= set(rep), set(keys) - set(rep)
    sec = rep["seconds"]
    phases = [sec[k] for k in ("read", "prepare", "compute", "write")]
    assert all(s >= 0.0 for s in phases) and sec["total"] >= sum(phases) - 1e-3
    return rep


def test_report_of_skyview_and_its_clash(tmp_path, runner):
    """--report: absolute output, directions, threads, the factor's min/mean, the phases'
    seconds; the DEM as the report is a usage error (exit 2, one line)."""
    dem = _plane(tmp_path, 20.0)
    out, rep = tmp_path / "svf.tif", tmp_path / "svf.json"
    r = runner.invoke(cli, ["skyview", dem, str(out), "--directions", "8", "--report",
                            str(rep)] + FLAT)
    assert r.exit_code == 0, r.output
    doc = _check_report(rep, ["input", "output", "shape", "definition", "directions",
                              "backend", "threads", "svf", "version"])
    assert doc["output"] == str(out.resolve()) and doc["directions"] == 8
    assert 0.0 < doc["svf"]["min"] <= doc["svf"]["mean"] <= doc["svf"]["max"] <= 1.0
    r = runner.invoke(cli, ["skyview", dem, str(out), "--report", dem, "--overwrite"])
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.output
