"""Correct at the edges (issue 17): spacing up to and at the poles on any body, the curvature
radius the rays use, read-only heights."""

import json
import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.model.geometry import WGS84_A, WGS84_B, grid_from_transform, radius_in_azimuth
from hillshade_rt.testing import fractal_terrain, write_geotiff

UTM32N = CRS.from_epsg(32632)


def test_report_gives_the_curvature_radius_the_rays_use(tmp_path, runner):
    """UTM 32N at 45 N, sun from the west: the rays use the east-west radius (the prime
    vertical, 6 388 838 m), not the north-south one (6 367 382 m) reported before."""
    z = fractal_terrain(200, 200, 3, relief=1500)
    # 45 N on the central meridian of zone 32 (9 E): northing 4 984 944
    dem = write_geotiff(tmp_path / "alps.tif", z, Affine(30, 0, 497000, 0, -30, 4987944), UTM32N)
    for az, want in ((270.0, radius_in_azimuth(45.0, 270.0)), (0.0, radius_in_azimuth(45.0, 0.0))):
        rep = tmp_path / f"r{az:g}.json"
        r = runner.invoke(cli, ["shadow", dem, str(tmp_path / f"m{az:g}.tif"), "--azimuth",
                                str(az), "--elevation", "5", "--earth-curvature", "-q",
                                "--report", str(rep)])
        assert r.exit_code == 0, r.output
        got = json.loads(rep.read_text())["curvature"]
        assert got["applied"] is True
        assert got["radius_m"] == pytest.approx(want, abs=30.0)
    assert radius_in_azimuth(45.0, 270.0) - radius_in_azimuth(45.0, 0.0) > 20000


def test_series_reports_the_mean_radius_and_its_range(tmp_path, runner):
    z = fractal_terrain(120, 120, 4, relief=1500)
    dem = write_geotiff(tmp_path / "alps.tif", z, Affine(30, 0, 497000, 0, -30, 4987944), UTM32N)
    rep = tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "m.tif"), "--start",
                            "2026-06-21T06:00+02:00", "--end", "2026-06-21T20:00+02:00", "--step",
                            "2h", "--earth-curvature", "-q", "--report", str(rep)])
    assert r.exit_code == 0, r.output
    got = json.loads(rep.read_text())["curvature"]
    lo, hi = got["radius_m_range"]
    assert radius_in_azimuth(45.0, 0.0) - 30 < lo < hi < radius_in_azimuth(45.0, 90.0) + 30
    assert lo <= got["radius_m"] <= hi


# ---------------------------------------------------------------------------------------------
# spacing up to and at the poles

MOON_R = 1737400.0
MOON_EQC = CRS.from_proj4(f"+proj=eqc +R={MOON_R:.0f} +units=m +no_defs")
MOON_LL = CRS.from_proj4(f"+proj=longlat +R={MOON_R:.0f} +no_defs")
MOON_SPS = CRS.from_proj4(f"+proj=stere +lat_0=-90 +R={MOON_R:.0f} +units=m +no_defs")


def _global_eqc(rows, overshoot=2.4):
    """A global lunar grid like LOLA's: equirectangular metres on the 1737.4 km sphere, the
    top edge ``overshoot`` metres past the north pole (a rounding in the real product)."""
    cell = math.pi * MOON_R / rows
    tr = Affine(cell, 0, -math.pi * MOON_R, 0, -cell, math.pi * MOON_R / 2 + overshoot)
    lat = np.degrees((tr.f + tr.e * (np.arange(rows) + 0.5)) / MOON_R)
    return tr, cell, lat


@pytest.mark.parametrize("rows", [720, 180])
def test_equirectangular_global_grid_spacing_in_every_row(rows):
    """LOLA's 0.25 deg grid (1440 x 720): rows 0 and 719 got dx = 7580.84 m (the raw pixel size)
    instead of 16.5 m because a cell edge lay 2.4 m past the pole."""
    tr, cell, lat = _global_eqc(rows)
    g = grid_from_transform(tr, MOON_EQC, (rows, 2 * rows))
    # eqc on a sphere: the parallel's arc; the geodesic between the cell's edges is shorter by
    # about (dlon sin(lat))^2 / 24 (1.3e-5 for 1 deg cells)
    want_dx = cell * np.cos(np.radians(lat))
    assert np.allclose(g.dx, want_dx, rtol=2e-5), (g.dx[[0, -1]], want_dx[[0, -1]])
    assert np.allclose(g.dy, cell, rtol=1e-9)          # the meridian: exactly the pixel height
    assert g.dx[0] < 0.01 * cell and g.dx[-1] < 0.01 * cell


def test_geographic_global_grid_spacing_at_the_poles():
    rows, step = 720, 0.25
    tr = Affine(step, 0, -180, 0, -step, 90)
    g = grid_from_transform(tr, MOON_LL, (rows, 1440))
    lat = 90 - step * (np.arange(rows) + 0.5)
    rad = math.radians(step)
    assert np.allclose(g.dx, MOON_R * np.cos(np.radians(lat)) * rad, rtol=1e-9)
    assert np.allclose(g.dy, MOON_R * rad, rtol=1e-9)
    # an Earth grid on WGS84 up to the pole: the ellipsoid's radii at each row
    e2 = 1 - (WGS84_B / WGS84_A) ** 2
    g = grid_from_transform(Affine(step, 0, 0, 0, -step, 90), CRS.from_epsg(4326), (40, 40))
    phi = np.radians(90 - step * (np.arange(40) + 0.5))
    w = np.sqrt(1 - e2 * np.sin(phi) ** 2)
    assert np.allclose(g.dx, WGS84_A / w * np.cos(phi) * rad, rtol=1e-9)
    assert np.allclose(g.dy, WGS84_A * (1 - e2) / w ** 3 * rad, rtol=1e-9)


@pytest.mark.parametrize("pole_at", ["corner", "centre"])
def test_polar_stereographic_spacing_through_the_pole(pole_at):
    """South polar stereographic on the Moon (k0 = 1): ground spacing = map spacing / k with
    k = 2 / (1 + sin|lat|), at the centre column of each row, the pole's row included."""
    n, cell = 81 if pole_at == "centre" else 80, 1000.0
    half = n * cell / 2
    tr = Affine(cell, 0, -half, 0, -cell, half)
    g = grid_from_transform(tr, MOON_SPS, (n, n))
    x = tr.c + cell * n / 2
    y = tr.f + tr.e * (np.arange(n) + 0.5)
    rho = np.hypot(x, y)
    colat = 2 * np.arctan(rho / (2 * MOON_R))            # the sphere's polar stereographic
    k = 2 / (1 + np.cos(colat))
    assert np.allclose(g.dx, cell / k, rtol=1e-6) and np.allclose(g.dy, cell / k, rtol=1e-6)


def test_global_lunar_grid_shadows_exact_in_border_rows():
    """Every exact algorithm against the plain-Python reference (given the closed-form spacing)
    on a global lunar-like grid, border rows included (a check skipping them cannot see the
    pole rows' spacing)."""
    from hillshade_rt.engine.arrays import shadow_mask
    from hillshade_rt.testing import reference_mask
    rows = 36
    tr, cell, lat = _global_eqc(rows)
    z = (fractal_terrain(rows, 2 * rows, 11, relief=12000.0)
         + np.random.default_rng(17).random((rows, 2 * rows)).astype(np.float32) * 4000)
    g = grid_from_transform(tr, MOON_EQC, (rows, 2 * rows))
    want_dx = cell * np.cos(np.radians(lat))
    for az, el in ((163.0, 2.0), (290.0, 1.0), (203.7, 0.5)):
        ref = reference_mask(z, want_dx, cell, az, el)
        for algo in ("brute", "smap", "horizon"):
            m = shadow_mask(z, az, el, g, algorithm=algo, backend="cpu", curvature=False)
            diff = np.argwhere(m != ref)
            assert diff.size == 0, (algo, az, el, diff[:5])
        assert ref[[0, -1]].any() and not ref[[0, -1]].all()  # border rows are not trivial
