"""algorithms/relief.py: Horn's normals and the sun's incidence, against planes (exact up to
the raster's corners and around voids) and Horn's 3 x 3 formula written out in Python."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import relief
from hillshade_rt.model.geometry import Grid
from hillshade_rt.testing import fractal_terrain

GE, GN = 0.31, -0.17    # the plane's slopes: dz/d(east), dz/d(north)


def _plane(rows, cols, dx, dy, col_sign=1, row_sign=-1):
    r, c = np.mgrid[0:rows, 0:cols]
    east, north = col_sign * c * dx, row_sign * r * dy
    return (100.0 + GE * east + GN * north).astype(np.float64)


def _cos_i(azimuth, elevation):
    lx, ly, lz = relief.sun_vector(azimuth, elevation)
    return (lz - GE * lx - GN * ly) / math.sqrt(1.0 + GE * GE + GN * GN)


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
def test_sun_vector_is_a_unit_vector_toward_the_azimuth(azimuth):
    x, y, z = relief.sun_vector(azimuth, 25.0)
    assert math.isclose(x * x + y * y + z * z, 1.0)
    assert math.isclose(math.degrees(math.atan2(x, y)) % 360.0, azimuth)
    assert math.isclose(math.degrees(math.asin(z)), 25.0)


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
@pytest.mark.parametrize("col_sign, row_sign", [(1, -1), (-1, 1)])
def test_incidence_on_a_plane_is_exact_everywhere(azimuth, col_sign, row_sign):
    """Every cell of a plane, edges and corners included, gets cos(i) = L . N."""
    dx, dy = 2.0, 3.5
    z = _plane(9, 12, dx, dy, col_sign, row_sign).astype(np.float32)
    grid = Grid.uniform(9, 12, dx, dy, col_sign=col_sign, row_sign=row_sign)
    got = relief.incidence(z, grid, azimuth, 35.0)
    assert got.dtype == np.float32 and got.shape == z.shape
    np.testing.assert_allclose(got, _cos_i(azimuth, 35.0), atol=2e-5)


def test_incidence_around_voids_stays_exact_and_voids_are_nan():
    dx, dy = 1.0, 1.0
    z = _plane(10, 10, dx, dy).astype(np.float32)
    z[4, 4] = z[0, 9] = np.nan
    z[6, 0] = np.nan
    got = relief.incidence(z, Grid.uniform(10, 10, dx, dy), 203.7, 20.0)
    voids = np.isnan(z)
    assert np.array_equal(np.isnan(got), voids)
    np.testing.assert_allclose(got[~voids], _cos_i(203.7, 20.0), atol=2e-5)


def test_a_slope_facing_away_is_self_shadowed():
    """A 45 deg plane falling eastward faces east: lit from the east (cos(i) > 0); from the west
    below 45 deg it faces away (cos(i) < 0), at 45 deg the light grazes it (cos(i) = 0)."""
    c = np.mgrid[0:5, 0:5][1]
    z = (-1.0 * c).astype(np.float32)
    grid = Grid.uniform(5, 5, 1.0)
    assert (relief.incidence(z, grid, 90.0, 30.0) > 0).all()
    assert (relief.incidence(z, grid, 270.0, 30.0) < 0).all()
    np.testing.assert_allclose(relief.incidence(z, grid, 270.0, 45.0), 0.0, atol=1e-6)


def _horn_python(z, r, c, dx, dy):
    a, b, cc = z[r - 1, c - 1], z[r - 1, c], z[r - 1, c + 1]
    d, f = z[r, c - 1], z[r, c + 1]
    g, h, i = z[r + 1, c - 1], z[r + 1, c], z[r + 1, c + 1]
    dzdx = ((cc + 2 * f + i) - (a + 2 * d + g)) / (8 * dx)
    dzdy = ((g + 2 * h + i) - (a + 2 * b + cc)) / (8 * dy)
    return dzdx, -dzdy     # north-up: dz/d(north) = -dz/d(row)


@pytest.mark.parametrize("azimuth", [163.0, 290.0])
def test_incidence_matches_horn_written_out(azimuth):
    dx, dy = 30.0, 25.0
    z = fractal_terrain(16, 14, seed=3, relief=300.0)
    got = relief.incidence(z, Grid.uniform(16, 14, dx, dy), azimuth, 28.0)
    lx, ly, lz = relief.sun_vector(azimuth, 28.0)
    z64 = z.astype(np.float64)
    for r in range(1, 15):
        for c in range(1, 13):
            ge, gn = _horn_python(z64, r, c, dx, dy)
            want = (lz - ge * lx - gn * ly) / math.sqrt(1 + ge * ge + gn * gn)
            assert got[r, c] == pytest.approx(want, abs=1e-5)


def test_a_window_reads_its_neighbours_from_the_whole_raster():
    z = fractal_terrain(20, 20, seed=8, relief=50.0)
    grid = Grid.uniform(20, 20, 5.0)
    whole = relief.incidence(z, grid, 203.7, 40.0)
    part = relief.incidence(z, grid, 203.7, 40.0, rows=slice(3, 11), cols=slice(6, 19))
    np.testing.assert_array_equal(part, whole[3:11, 6:19])
