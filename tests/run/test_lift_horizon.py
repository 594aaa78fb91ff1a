"""An observer above the ground for the horizon scan (issue 20, item 5, the rest):
``--height-above-ground H`` on horizon, skyview, irradiance and ``shadow --soft``. Checked on a
wall where the horizon is known in closed form, against the plain-Python reference on fractal
terrain, between memory, windows and the GPU twins (numba's simulator), and for the monotony a
higher observer must show (lower horizons, more sky, more sun)."""

import json
import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.engine import gpu
from hillshade_rt.algorithms import horizon as hz
from hillshade_rt.cli import cli
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.io import read_dem
from hillshade_rt.testing import (data_path, fractal_terrain, read_band, reference_horizon,
                                  wall_contacts, wall_terrain, write_geotiff)

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
UTM = CRS.from_epsg(32615)


def _run(runner, args):
    r = runner.invoke(cli, args)
    assert r.exit_code == 0, r.output
    return r


def _tags(path):
    import rasterio
    with rasterio.open(path) as ds:
        return ds.tags()


def _fractal_dem(tmp_path, rows=150, cols=170, seed=5, relief=90.0):
    z = fractal_terrain(rows, cols, seed, relief=relief)
    z[40:44, 60:63] = np.nan
    return write_geotiff(tmp_path / "f.tif", z, Affine(2.0, 0, 500000.0, 0, -2.0, 4000000.0),
                         UTM), z


@pytest.mark.slow
@pytest.mark.parametrize("az", [163.0, 203.7])
def test_the_horizon_toward_a_wall_from_above_the_ground(tmp_path, runner, az):
    """Flat ground, a wall h = 30 m perpendicular to the azimuth: toward it, from H above a
    ground cell d metres before the wall (along the ray, to its first full sample), the horizon
    is atan((h - H) / d); the command says the same as the kernel, and tags the height."""
    h, rows, cols = 30.0, 150, 170
    z, wall = wall_terrain(az, h, 70.0, 10.0, rows, cols)    # metres along az (1 m cells)
    dem = write_geotiff(tmp_path / "w.tif", z, Affine(1.0, 0, 500000.0, 0, -1.0, 4000000.0), UTM)
    rays = sun_rays(read_dem(dem).grid, az, 45.0)    # (UTM's 1 m cell over its scale)
    cells = wall_contacts(wall, rays, range(3, 50, 2), range(15, cols - 15, 3))
    assert len(cells) > 40
    for H in (0.0, 2.0, 12.5):
        beta = hz.horizon_angles(z, rays, lift=H)
        want = np.array([math.degrees(math.atan((h - H) / d)) for d in cells.values()])
        got = np.array([beta[cell] for cell in cells])
        np.testing.assert_allclose(got, want, atol=1e-4)
        out = tmp_path / f"h{H}.tif"
        _run(runner, ["horizon", dem, str(out), "--azimuth", str(az), "--no-earth-curvature",
                      "--height-above-ground", str(H), "--quiet"])
        np.testing.assert_array_equal(read_band(out), beta)
        assert float(_tags(out)["HEIGHT_ABOVE_GROUND_M"]) == H


@pytest.mark.slow
def test_the_lifted_horizon_equals_the_plain_python_reference():
    """Fractal terrain with voids, rectangular cells whose spacing varies per row, at 203.7 and
    290 deg: the scan (over the pyramid and plain) and the hull's exact lines give the
    reference with the observer lifted; H = 0 gives today's angles bit for bit."""
    z = fractal_terrain(30, 34, 3, relief=300.0, octaves=4)
    z[9:11, 14:16] = np.nan
    dx = np.linspace(27.0, 31.0, 30)
    grid = Grid(30, 34, dx, np.full(30, 22.0))
    for az in (203.7, 290.0):
        rays = sun_rays(grid, az, 45.0)
        np.testing.assert_array_equal(hz.horizon_angles(z, rays, lift=0.0),
                                      hz.horizon_angles(z, rays))
        ok = ~np.isnan(z)
        prev = None
        for H in (1.5, 12.0, 80.0):
            beta = hz.horizon_angles(z, rays, lift=H)
            ref, _ = reference_horizon(z, dx, 22.0, az, lift=H)
            np.testing.assert_allclose(beta[ok], ref[ok], atol=1e-5, err_msg=f"{az} {H}")
            np.testing.assert_array_equal(hz.horizon_angles(z, rays, pyramid=False, lift=H),
                                          beta)
            if prev is not None:       # a higher observer sees a lower horizon
                assert (beta[ok] <= prev[ok]).all() and (beta[ok] < prev[ok]).mean() > 0.5
            prev = beta


def test_the_hull_takes_the_lift_where_it_is_exact():
    """Along an axis and a diagonal the hull's lines are the scan's rays: with a lift too."""
    z = fractal_terrain(40, 44, 9, relief=200.0)
    grid = Grid.uniform(40, 44, 10.0, 10.0)
    for az in (90.0, 225.0):
        rays = sun_rays(grid, az, 45.0)
        np.testing.assert_allclose(hz.horizon_angles(z, rays, method="hull", lift=6.0),
                                   hz.horizon_angles(z, rays, lift=6.0), atol=1e-4)


@pytest.mark.slow
def test_gpu_twins_and_windows_take_the_lift():
    """The CUDA kernels (numba's simulator here) and the windowed march (``Marches``: a region
    marched through two windows) give the in-memory scan's bits with a lift."""
    z = fractal_terrain(24, 28, 4, relief=150.0)
    z[5:7, 8:10] = np.nan
    grid = Grid.uniform(24, 28, 20.0, 15.0)
    g = gpu.GpuDem(z)
    # (to a float32 ulp: at a cell or two the simulator's Python math.degrees(math.atan(t))
    # rounds the angle otherwise than the compiled kernel, at H = 0 as well, e.g. at 290 deg)
    for az in (163.0, 290.0):
        rays = sun_rays(grid, az, 45.0)
        want = hz.horizon_angles(z, rays, lift=5.0)
        assert (want != hz.horizon_angles(z, rays)).any()
        np.testing.assert_allclose(hz.horizon_angles_gpu(g, rays, lift=5.0), want, rtol=0,
                                   atol=1e-5)
        zmax = float(np.nanmax(z))
        region = (4, 12, 5, 15)
        for on_gpu in (None, gpu.GpuDem):
            m = hz.Marches(z[4:12, 5:15], region, rays, z.shape, zmax, lift=5.0)
            for win in ((0, 14, 0, 28), (0, 24, 0, 28)):
                if m.open().any():
                    w = z[win[0]:win[1], win[2]:win[3]].copy()
                    m.march(hz.ScanWindow(w, win, z.shape, True, on_gpu))
            np.testing.assert_array_equal(m.angles(), want[4:12, 5:15])


@pytest.mark.slow
def test_horizon_and_skyview_in_windows_equal_memory_with_a_lift(tmp_path, runner):
    """--window-size 64 with H = 3 m: horizon (8 directions) and skyview (zaksek and
    negative openness) give the in-memory rasters cell for cell; the sky view factor at H is
    >= at 0 everywhere (a higher observer sees a lower horizon), negative openness <= (the
    terrain below falls away more steeply)."""
    dem, z = _fractal_dem(tmp_path)
    ok = ~np.isnan(z)
    runs = {
        "horizon": ["horizon", "--directions", "8"],
        "svf": ["skyview", "--directions", "8"],
        "neg": ["skyview", "--directions", "8", "--openness", "negative"],
    }
    got = {}
    for name, args in runs.items():
        for H in ("0", "3"):
            a, b = tmp_path / f"{name}{H}a.tif", tmp_path / f"{name}{H}b.tif"
            cmd, rest = args[0], args[1:]
            _run(runner, [cmd, dem, str(a), "--height-above-ground", H, "--quiet"] + rest)
            got[name, H] = read_band(a) if cmd == "skyview" else _bands(a)
            if H == "3":
                _run(runner, [cmd, dem, str(b), "--height-above-ground", H, "--quiet",
                              "--window-size", "64"] + rest)
                np.testing.assert_array_equal(read_band(b) if cmd == "skyview" else _bands(b),
                                              got[name, H], err_msg=name)
                assert float(_tags(b)["HEIGHT_ABOVE_GROUND_M"]) == 3.0
    for lo, hi in ((got["svf", "0"], got["svf", "3"]), (got["neg", "3"], got["neg", "0"]),
                   (got["horizon", "3"], got["horizon", "0"])):
        assert (hi[..., ok] >= lo[..., ok]).all()
        assert (hi[..., ok] > lo[..., ok]).mean() > 0.3


def _bands(path):
    import rasterio
    with rasterio.open(path) as ds:
        return ds.read()


@pytest.mark.slow
def test_skyview_tags_and_dozier_take_the_height(tmp_path, runner):
    """The tags give the height; Dozier's Vd from above is not Vd from the ground;
    H = 0 is today's run bit for bit."""
    dem, z = _fractal_dem(tmp_path, 80, 90)
    base, zero, up = (tmp_path / f"{n}.tif" for n in ("base", "zero", "up"))
    _run(runner, ["skyview", dem, str(base), "--directions", "8", "--definition", "dozier",
                  "--quiet"])
    _run(runner, ["skyview", dem, str(zero), "--directions", "8", "--definition", "dozier",
                  "--height-above-ground", "0", "--quiet"])
    _run(runner, ["skyview", dem, str(up), "--directions", "8", "--definition", "dozier",
                  "--height-above-ground", "4", "--quiet"])
    np.testing.assert_array_equal(read_band(zero), read_band(base))
    assert (read_band(up) != read_band(base)).mean() > 0.5
    assert float(_tags(up)["HEIGHT_ABOVE_GROUND_M"]) == 4.0
    assert float(_tags(zero)["HEIGHT_ABOVE_GROUND_M"]) == 0.0


@pytest.mark.slow
def test_soft_shadows_from_above_the_ground(tmp_path, runner):
    """``shadow --soft --height-above-ground H``: the visible fraction at H >= at 0 cell for
    cell (strictly more somewhere), and where it is 0 or 1 the hard mask at H agrees (shadow /
    lit); in windows the same as in memory."""
    sun = ["--azimuth", "203.7", "--elevation", "4", "--quiet"]
    frac = {}
    for H in ("0", "2"):
        out = tmp_path / f"s{H}.tif"
        _run(runner, ["shadow", LIDAR, str(out), "--soft", "--height-above-ground", H] + sun)
        frac[H] = read_band(out)
    hard = tmp_path / "hard.tif"
    _run(runner, ["shadow", LIDAR, str(hard), "--height-above-ground", "2"] + sun)
    m = read_band(hard)
    ok = m != 255
    assert (frac["2"][ok] >= frac["0"][ok]).all()
    assert (frac["2"][ok] > frac["0"][ok]).sum() > 100
    f = frac["2"]
    assert ((f == 0) & ok).sum() > 100 and ((f == 1) & ok).sum() > 100
    assert (m[(f == 0) & ok] == 1).all() and (m[(f == 1) & ok] == 0).all()
    win = tmp_path / "win.tif"
    _run(runner, ["shadow", LIDAR, str(win), "--soft", "--height-above-ground", "2",
                  "--window-size", "64"] + sun)
    np.testing.assert_array_equal(read_band(win), f)


@pytest.mark.slow
def test_irradiance_beam_from_above_the_ground_is_never_less(tmp_path, runner):
    """irradiance --height-above-ground H: the beam band at H >= at 0 cell for cell (its cast
    shadows from H, the incidence the cell's surface), strictly more somewhere; the report and
    tags give the height and the algorithm that marched it."""
    day = ["--date", "2026-10-15", "--step", "1h", "--tz", "America/Chicago",
           "--skyview-directions", "8", "--quiet"]
    beam, reps = {}, {}
    for H in ("0", "2"):
        out, rep = tmp_path / f"i{H}.tif", tmp_path / f"i{H}.json"
        _run(runner, ["irradiance", LIDAR, str(out), "--height-above-ground", H,
                      "--report", str(rep)] + day)
        beam[H], reps[H] = _bands(out)[0], json.loads(rep.read_text())
        assert float(_tags(out)["HEIGHT_ABOVE_GROUND_M"]) == float(H)
    ok = beam["0"] != -9999.0
    assert (beam["2"][ok] >= beam["0"][ok]).all()
    assert (beam["2"][ok] > beam["0"][ok]).sum() > 100
    assert reps["2"]["height_above_ground_m"] == 2.0 and reps["2"]["algorithm"] == "brute"
    assert reps["2"]["sky_view"]["mean"] != reps["0"]["sky_view"]["mean"]


@pytest.mark.parametrize("cmd", [
    ["horizon", "--azimuth", "163"], ["skyview"],
    ["irradiance", "--date", "2026-06-01"]])
@pytest.mark.parametrize("value", ["-1", "nan"])
def test_a_bad_height_is_a_usage_error(tmp_path, runner, cmd, value):
    out = tmp_path / "o.tif"
    r = runner.invoke(cli, [cmd[0], LIDAR, str(out)] + cmd[1:]
                      + [f"--height-above-ground={value}"])
    assert r.exit_code == 2 and "--height-above-ground" in r.stderr, r.stderr
    assert not out.exists()
