"""``shadow --light-position / --light-lonlat`` (issue 21, item 1): the command writes the point
light's mask of ``arrays.point_light_mask``; what it does not take yet is a usage error."""

import json

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.engine.arrays import point_light_mask
from hillshade_rt.cli import cli
from hillshade_rt.io import read_dem
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff


@pytest.fixture
def dem(tmp_path):
    z = fractal_terrain(70, 80, 6, relief=300.0) + 200.0
    z[3, 4] = np.nan
    return write_geotiff(tmp_path / "d.tif", z, Affine(10, 0, 500000, 0, -10, 4000000),
                         CRS.from_epsg(32633))


def test_light_position_and_lonlat_write_the_api_mask(tmp_path, runner, dem):
    d = read_dem(dem)
    x, y, zl = 500000 + 10 * 31.3, 4000000 - 10 * 47.8, 650.0
    out, rep = tmp_path / "m.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--light-position", f"{x},{y},{zl}",
                            "--height-above-ground", "1.5", "--report", str(rep)])
    assert r.exit_code == 0, r.output
    want = point_light_mask(d, x, y, zl, height_above_ground=1.5)
    assert np.array_equal(read_band(out), want)
    assert (want == 1).any() and (want == 0).any() and (want == 255).sum() == 1
    doc = json.loads(rep.read_text())
    assert doc["light"]["z"] == zl and doc["height_above_ground_m"] == 1.5
    from pyproj import Transformer
    lon, lat = Transformer.from_crs("EPSG:32633", "EPSG:4326", always_xy=True).transform(x, y)
    out2 = tmp_path / "m2.tif"
    r = runner.invoke(cli, ["shadow", dem, "-o", str(out2), "--light-lonlat",
                            f"{lon!r},{lat!r},{zl}", "--height-above-ground", "1.5"])
    assert r.exit_code == 0, r.output
    assert np.array_equal(read_band(out2), want)


@pytest.mark.parametrize("extra, code, words", [
    (["--azimuth", "163", "--elevation", "10"], 2, "--azimuth"),
    (["--soft"], 2, "--soft"),
    (["--scheduler", "synchronous"], 2, "--scheduler"),
    (["--algorithm", "smap"], 2, "--algorithm"),
])
def test_what_a_point_light_does_not_take_is_a_usage_error(tmp_path, runner, dem, extra, code,
                                                           words):
    out = tmp_path / "m.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--light-position",
                            "500300,3999500,900"] + extra)
    assert r.exit_code == code and words in r.output and "Traceback" not in r.output
    assert not out.exists()


def test_a_light_inside_the_terrain_fails_and_writes_nothing(tmp_path, runner, dem):
    out = tmp_path / "m.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--light-position", "500300,3999500,10"])
    assert r.exit_code == 1 and "inside the terrain" in r.output
    assert not out.exists()
    r = runner.invoke(cli, ["shadow", dem, str(out), "--light-position", "1,2"])
    assert r.exit_code == 2 and "three numbers" in r.output


def test_backend_gpu_writes_the_cpu_mask(tmp_path, runner):
    """--backend gpu (the CUDA kernel; numba's simulator in the tests) writes the CPU's mask and
    says so in the report."""
    z = fractal_terrain(18, 22, 3, relief=60.0) + 100.0
    z[5, 6] = np.nan
    dem = write_geotiff(tmp_path / "s.tif", z, Affine(10, 0, 500000, 0, -10, 4000000),
                        CRS.from_epsg(32633))
    x, y, zl = 500000 + 10 * 15.3, 4000000 - 10 * 4.8, 190.0
    out, rep = tmp_path / "m.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--light-position", f"{x},{y},{zl}",
                            "--backend", "gpu", "--report", str(rep)])
    assert r.exit_code == 0, r.output
    want = point_light_mask(read_dem(dem), x, y, zl, backend="cpu")
    assert np.array_equal(read_band(out), want) and (want == 1).any() and (want == 0).any()
    assert json.loads(rep.read_text())["backend"] == "gpu"


@pytest.mark.parametrize("light", [(41.3, 57.8, 30.0), (-30.2, 190.6, 400.0),
                                   (140.7, -12.4, 250.0)])
def test_windows_write_the_in_memory_mask(tmp_path, runner, light):
    """--window-size: windows read with their halo toward the light (inside the raster, low; off
    it, high and low) write the in-memory mask cell for cell."""
    z = fractal_terrain(150, 170, 12, relief=300.0) + 100.0
    z[60:63, 20:24] = np.nan
    dem = write_geotiff(tmp_path / "w.tif", z, Affine(10, 0, 500000, 0, -10, 4000000),
                        CRS.from_epsg(32633))
    row, col, zl = light
    if 0 <= row < 150 and 0 <= col < 170:
        from hillshade_rt.algorithms.horizon import bilinear
        zl += bilinear(z, row, col)
    x, y = 500000 + 10 * (col + 0.5), 4000000 - 10 * (row + 0.5)
    out, rep = tmp_path / "m.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--light-position", f"{x},{y},{zl}",
                            "--window-size", "64x72", "--height-above-ground", "1",
                            "--report", str(rep)])
    assert r.exit_code == 0, r.output
    want = point_light_mask(read_dem(dem), x, y, zl, height_above_ground=1.0)
    assert np.array_equal(read_band(out), want)
    assert 0.02 < (want == 1).mean() < 0.98
    proc = json.loads(rep.read_text())["processing"]
    assert proc["mode"] == "tiled" and proc["windows"] == 9


def test_a_light_inside_the_terrain_is_refused_in_windows(tmp_path, runner, dem):
    out = tmp_path / "m.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--light-position", "500300,3999500,10",
                            "--window-size", "64"])
    assert r.exit_code == 1 and "inside the terrain" in r.output
    assert not out.exists()


@pytest.mark.parametrize("command", ["shadow", "hillshade"])
def test_no_earth_curvature_is_taken_and_earth_curvature_still_refused(tmp_path, runner, dem,
                                                                        command):
    light = ["--light-position", "500300,3999500,900", "-q"]
    plain, flat, curved = (tmp_path / f"{n}.tif" for n in ("plain", "flat", "curved"))
    r = runner.invoke(cli, [command, dem, str(plain)] + light)
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, [command, dem, str(flat), "--no-earth-curvature"] + light)
    assert r.exit_code == 0, r.output
    assert np.array_equal(read_band(flat), read_band(plain))      # a flat Earth: the same
    r = runner.invoke(cli, [command, dem, str(curved), "--earth-curvature"] + light)
    assert r.exit_code == 2 and "--earth-curvature" in r.output, r.output
    assert not curved.exists()
