"""An observer above the ground on rasters (issue 20, item 5): ``--height-above-ground H`` on
shadow, hillshade and sun-hours starts each cell's ray H metres above its centre. Checked on a
wall where the answer is known in closed form, against the plain-Python reference on fractal
terrain, between the march's variants (plain, pyramid, per-cell sun, GPU twin in the simulator),
in windows against memory, and for sun hours' monotony."""

import json
import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.engine import gpu
from hillshade_rt.algorithms import brute, per_cell_sun
from hillshade_rt.cli import cli
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.io import read_dem
from hillshade_rt.testing import (data_path, fractal_terrain, read_band, reference_mask,
                                  wall_contacts, wall_terrain, write_geotiff)

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
UTM = CRS.from_epsg(32615)
FLAT = ["--no-earth-curvature"]


def _run(runner, args):
    r = runner.invoke(cli, args)
    assert r.exit_code == 0, r.output
    return r


@pytest.mark.slow
def test_a_wall_lights_an_observer_exactly_above_its_shadow_line(tmp_path, runner):
    """A wall h = 30 m perpendicular to the sun at 203.7 deg, 20 deg up: an observer on the
    ground d metres from the wall (along the ray, to the wall's first full sample) is lit
    exactly when H >= h - d tan(20 deg): checked on both sides of one cell's threshold
    (H +- 1 mm), and every other such cell on its side at those heights."""
    az, el, h = 203.7, 20.0, 30.0
    z, wall = wall_terrain(az, h)
    dem = write_geotiff(tmp_path / "wall.tif", z, Affine(1, 0, 500000, 0, -1, 4000000), UTM)
    need = {cell: h - d * math.tan(math.radians(el)) for cell, d in
            wall_contacts(wall, sun_rays(read_dem(dem).grid, az, el), range(4, 60, 3),
                          range(20, z.shape[1] - 4, 3)).items()}
    assert len(need) > 50 and min(need.values()) < 5 < max(need.values())
    target = sorted(need, key=lambda k: abs(need[k] - 12.0))[0]     # a cell 12 m short
    base = ["--azimuth", str(az), "--elevation", str(el)] + FLAT
    seen = {}
    for H in (need[target] - 1e-3, need[target] + 1e-3):
        out = tmp_path / f"m{H:.4f}.tif"
        _run(runner, ["shadow", dem, str(out), "--height-above-ground", repr(H)] + base)
        mask = read_band(out)
        for cell, hstar in need.items():
            if abs(hstar - H) > 1e-6:
                assert mask[cell] == (0 if H >= hstar else 1), (cell, H, hstar)
        seen[H >= need[target]] = mask[target]
        assert (mask[wall] == 0).all()       # the wall's top sees the sun
    assert seen == {False: 1, True: 0}
    _run(runner, ["shadow", dem, str(tmp_path / "g.tif")] + base)     # on the ground
    g = read_band(tmp_path / "g.tif")
    assert all(g[cell] == (1 if hstar > 0 else 0) for cell, hstar in need.items())


@pytest.mark.parametrize("az", [pytest.param(163.0, marks=pytest.mark.slow), 203.7, 290.0])
def test_lift_equals_the_plain_python_reference(az):
    """Fractal terrain with voids, rectangular cells and spacing that varies per row (as in a
    geographic CRS): brute over the pyramid and the plain march equal the reference with the
    same lift, cell for cell; H = 0 is today's mask."""
    z = fractal_terrain(33, 41, 7, relief=120.0)
    z[10:13, 17:19] = np.nan
    z[0, 5] = np.nan
    dx = np.linspace(28.0, 31.0, 33)
    grid = Grid(33, 41, dx, np.full(33, 22.0))
    rays = sun_rays(grid, az, 9.0)
    for H in (0.0, 1.5, 7.0, 40.0):
        ref = reference_mask(z, dx, 22.0, az, 9.0, lift=H)
        got = brute.shadow_mask(z, rays, lift=H)
        np.testing.assert_array_equal(got, ref, err_msg=f"az {az} H {H}")
        np.testing.assert_array_equal(brute.shadow_mask(z, rays, pyramid=False, lift=H), ref)
        if H == 0.0:
            np.testing.assert_array_equal(got, brute.shadow_mask(z, rays))
            np.testing.assert_array_equal(ref, reference_mask(z, dx, 22.0, az, 9.0))
            low = (got == 1).mean()
        elif H == 1.5:
            assert 0 < (got == 1).mean() < low          # fewer shadows from higher up
    assert low > 0.1


def test_lift_is_monotone_and_an_observer_above_every_summit_is_lit():
    """A higher start at the same angle lies above the lower ray everywhere: every cell lit
    at H is lit at any larger H; above the highest cell nothing can block."""
    z = fractal_terrain(40, 44, 3, relief=200.0)
    grid = Grid.uniform(40, 44, 25.0)
    rays = sun_rays(grid, 203.7, 6.0)
    prev = brute.shadow_mask(z, rays)
    for H in (0.5, 3.0, 20.0, 80.0):
        m = brute.shadow_mask(z, rays, lift=H)
        assert not ((prev == 0) & (m == 1)).any()
        prev = m
    assert (brute.shadow_mask(z, rays, lift=float(z.max() - z.min())) == 0).all()


@pytest.mark.slow
def test_per_cell_sun_and_gpu_twins_take_the_lift():
    """The per-cell sun's march (a sun that varies across the raster) and the CUDA kernels
    (run here in numba's simulator) with a lift: the same mask as brute on the CPU."""
    from hillshade_rt.algorithms.per_cell_sun import lattice_vectors
    z = fractal_terrain(17, 21, 5, relief=150.0)
    z[6:8, 9:11] = np.nan
    grid = Grid.uniform(17, 21, 30.0, 20.0)
    g = gpu.GpuDem(z)
    for az in (163.0, 290.0):
        rays = sun_rays(grid, az, 12.0)
        cpu = brute.shadow_mask(z, rays, lift=4.0)
        assert (cpu == 1).any() and (cpu == 0).any()
        assert (cpu != brute.shadow_mask(z, rays)).any()
        np.testing.assert_array_equal(brute.shadow_mask_gpu(g, rays, g.zmax, lift=4.0), cpu)
        np.testing.assert_array_equal(
            brute.shadow_mask_gpu(g, rays, g.zmax, pyramid=False, lift=4.0), cpu)
        vec = lattice_vectors(np.full((3, 3), az), np.full((3, 3), 12.0))   # one direction
        np.testing.assert_array_equal(per_cell_sun.shadow_mask(z, grid, vec, lift=4.0), cpu)
        np.testing.assert_array_equal(per_cell_sun.shadow_mask_gpu(g, grid, vec, 0.0, g.zmax,
                                                            lift=4.0), cpu)


def test_height_zero_is_todays_run_and_the_report_says_the_height(tmp_path, runner):
    a, b, c = (tmp_path / n for n in ("a.tif", "b.tif", "c.tif"))
    sun = ["--azimuth", "163", "--elevation", "7"]
    _run(runner, ["shadow", LIDAR, str(a)] + sun)
    _run(runner, ["shadow", LIDAR, str(b), "--height-above-ground", "0"] + sun)
    np.testing.assert_array_equal(read_band(a), read_band(b))
    rep = tmp_path / "c.json"
    _run(runner, ["shadow", LIDAR, str(c), "--height-above-ground", "2", "--report", str(rep)]
         + sun)
    doc = json.loads(rep.read_text())
    assert doc["height_above_ground_m"] == 2.0 and doc["algorithm"] == "brute"
    ma, mc = read_band(a), read_band(c)
    assert not ((ma == 0) & (mc == 1)).any() and ((ma == 1) & (mc == 0)).sum() > 100
    import rasterio
    with rasterio.open(c) as ds:
        assert ds.tags()["HEIGHT_ABOVE_GROUND_M"] == "2"


def test_hillshade_lights_what_the_lifted_shadow_lights(tmp_path, runner):
    """hillshade: the relief's shading stays the ground's; cells whose lifted ray is lit get
    their direct light back."""
    a, b, s = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "s.tif"
    sun = ["--azimuth", "290", "--elevation", "8"]
    _run(runner, ["hillshade", LIDAR, str(a)] + sun)
    _run(runner, ["hillshade", LIDAR, str(b), "--height-above-ground", "3"] + sun)
    _run(runner, ["shadow", LIDAR, str(s), "--height-above-ground", "3", "--self-shadow"] + sun)
    ha, hb, sh = read_band(a), read_band(b), read_band(s)
    ambient = 1 + round(254 * 0.2)
    assert (hb[sh == 1] == ambient).all() and (hb[sh == 0] >= ambient).all()
    changed = ha != hb
    assert changed.sum() > 100 and (hb[changed] > ha[changed]).all()


@pytest.mark.slow
def test_windows_equal_memory_with_a_lift_and_the_halo_is_shorter(tmp_path, runner):
    """--window-size 64 with H = 6 m gives the in-memory mask cell for cell; the halos it
    reads are shorter than at H = 0 (the rays start higher: reach (zmax - (low + H)) / tan E)."""
    sun = ["--azimuth", "203.7", "--elevation", "5"]
    outs = {}
    for H in ("0", "6"):
        a, b = tmp_path / f"a{H}.tif", tmp_path / f"b{H}.tif"
        rep = tmp_path / f"b{H}.json"
        _run(runner, ["shadow", LIDAR, str(a), "--height-above-ground", H] + sun)
        _run(runner, ["shadow", LIDAR, str(b), "--height-above-ground", H, "--window-size",
                      "64", "--report", str(rep)] + sun)
        np.testing.assert_array_equal(read_band(b), read_band(a))
        outs[H] = (read_band(a), json.loads(rep.read_text())["processing"])
    assert outs["6"][1]["cells_lit"] < outs["0"][1]["cells_lit"]
    assert (outs["6"][0] != outs["0"][0]).sum() > 100


@pytest.mark.slow
def test_windows_with_each_cells_own_sun_and_a_lift(tmp_path, runner):
    """A 60 km DEM at a low sun from a time (every cell its own sun): windows of 64 x 64 with
    H = 15 m give the in-memory mask cell for cell, and a mask that differs from the ground's."""
    z = fractal_terrain(200, 260, 11, relief=2500.0)
    z += np.random.default_rng(11).normal(0.0, 30.0, z.shape).astype(np.float32)
    dem = write_geotiff(tmp_path / "d.tif", z, Affine(200.0, 0, 400000.0, 0, -200.0, 3800000.0),
                        CRS.from_epsg(32611))
    sun = ["--time", "2026-06-21T06:10-07:00", "--sun-tolerance", "0.15"]
    a, b, g = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "g.tif"
    rep = tmp_path / "a.json"
    _run(runner, ["shadow", dem, str(a), "--height-above-ground", "15", "--report", str(rep)]
         + sun)
    assert json.loads(rep.read_text())["times"][0]["mode"] == "per cell"
    _run(runner, ["shadow", dem, str(b), "--height-above-ground", "15", "--window-size", "64"]
         + sun)
    _run(runner, ["shadow", dem, str(g)] + sun)
    np.testing.assert_array_equal(read_band(b), read_band(a))
    ma, mg = read_band(a), read_band(g)
    assert not ((mg == 0) & (ma == 1)).any() and ((mg == 1) & (ma == 0)).sum() > 50


@pytest.mark.slow
def test_sun_hours_from_higher_up_are_never_fewer(tmp_path, runner):
    """A higher ray start at the same angle lies above the lower ray everywhere, so sun hours
    at H > 0 are >= those at H = 0 cell for cell (strictly more somewhere); with H > 0 the
    surface's orientation counts only when --self-shadow is given (the observer does not stand
    on the facet)."""
    day = ["--date", "2026-10-15", "--step", "30min", "--tz", "America/Chicago"]
    hours, reps = {}, {}
    for name, extra in (("0", []), ("2", ["--height-above-ground", "2"]),
                        ("2s", ["--height-above-ground", "2", "--self-shadow"]),
                        ("0n", ["--no-self-shadow"])):
        out, rep = tmp_path / f"h{name}.tif", tmp_path / f"h{name}.json"
        _run(runner, ["sun-hours", LIDAR, str(out), "--report", str(rep)] + day + extra)
        hours[name], reps[name] = read_band(out), json.loads(rep.read_text())
    assert reps["0"]["self_shadow"] and not reps["2"]["self_shadow"] and reps["2s"]["self_shadow"]
    assert reps["2"]["height_above_ground_m"] == 2.0 and reps["2"]["algorithm"] == "brute"
    for lo, hi in (("0", "2s"), ("0n", "2"), ("2s", "2")):
        assert (hours[hi] >= hours[lo]).all(), (lo, hi)
        assert (hours[hi] > hours[lo]).sum() > 100, (lo, hi)


@pytest.mark.parametrize("args, words", [
    (["--algorithm", "smap"], "--algorithm brute or auto"),
    (["--algorithm", "bounds"], "cannot start the rays above the ground"),
])
def test_what_cannot_lift_is_a_usage_error(tmp_path, runner, args, words):
    out = tmp_path / "o.tif"
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "--azimuth", "163", "--elevation", "9",
                            "--height-above-ground", "2"] + args)
    assert r.exit_code == 2 and words in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not out.exists()


@pytest.mark.parametrize("value", ["-1", "nan", "inf"])
def test_a_bad_height_is_a_usage_error(tmp_path, runner, value):
    for cmd in (["shadow", LIDAR, str(tmp_path / "o.tif"), "--azimuth", "1", "--elevation",
                 "9"], ["sun-hours", LIDAR, str(tmp_path / "o.tif"), "--date", "2026-06-01"]):
        r = runner.invoke(cli, cmd + [f"--height-above-ground={value}"])
        assert r.exit_code == 2 and "--height-above-ground" in r.stderr, r.stderr
        assert not (tmp_path / "o.tif").exists()


def test_api_shade_takes_the_height(tmp_path, runner):
    import hillshade_rt as hr
    a, b = tmp_path / "a.tif", tmp_path / "b.tif"
    hr.shade(LIDAR, str(a), azimuth=203.7, elevation=6, height_above_ground=2.5)
    _run(runner, ["shadow", LIDAR, str(b), "--azimuth", "203.7", "--elevation", "6",
                  "--height-above-ground", "2.5"])
    np.testing.assert_array_equal(read_band(a), read_band(b))
    d = read_dem(LIDAR)
    rays = sun_rays(d.grid, 203.7, 6.0)
    np.testing.assert_array_equal(read_band(a), brute.shadow_mask(d.heights, rays, lift=2.5))
