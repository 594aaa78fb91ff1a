"""algorithms/raymath.py: the per-ray arithmetic (snapping onto a line, interpolation on a grid
line, one ray's march) against planes, a wall and the plain-Python reference."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import raymath
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import fractal_terrain, reference_mask


def test_line_position_snaps_within_eps_and_refuses_outside():
    lp = raymath.line_position
    assert lp(3.25, 10) == 3.25
    assert lp(-0.5 * raymath.EDGE_EPS, 10) == 0.0
    assert lp(9.0 + 0.5 * raymath.EDGE_EPS, 10) == 9.0
    assert lp(-2.0 * raymath.EDGE_EPS, 10) == -1.0
    assert lp(9.0 + 2.0 * raymath.EDGE_EPS, 10) == -1.0
    assert lp(-0.3, 10) == -1.0


def test_madd_is_a_plus_b_times_c():
    assert raymath.madd(1.5, 2.0, 3.25) == 1.5 + 2.0 * 3.25


@pytest.mark.parametrize("dom_col", [True, False])
def test_terrain_on_line_is_exact_on_a_plane(dom_col):
    """Linear interpolation between two cell centres reproduces a plane z = 3r - 2c + 7."""
    r, c = np.mgrid[0:6, 0:7]
    z = (3.0 * r - 2.0 * c + 7.0).astype(np.float32)
    for line in range(7 if dom_col else 6):
        for pos in (0.0, 0.37, 2.5, 4.999):
            got = raymath.terrain_on_line(z, dom_col, line, pos)
            rr, cc = (pos, line) if dom_col else (line, pos)
            assert got == pytest.approx(3.0 * rr - 2.0 * cc + 7.0, abs=1e-9)


def test_terrain_on_line_propagates_a_void():
    z = np.zeros((3, 3), np.float32)
    z[1, 1] = np.nan
    assert math.isnan(raymath.terrain_on_line(z, False, 1, 0.5))
    assert raymath.terrain_on_line(z, False, 0, 0.5) == 0.0


def test_ray_origin_orders_the_axes():
    z = np.zeros((4, 9), np.float32)
    assert tuple(raymath.ray_origin(z, 2, 5, True)) == (5, 2, 9, 4)
    assert tuple(raymath.ray_origin(z, 2, 5, False)) == (2, 5, 4, 9)


def _blocked(z, rays, r, c, zmax, lift=0.0):
    return raymath.ray_is_blocked(z, r, c, bool(rays.dom_col[r]), int(rays.step_dom[r]),
                                  float(rays.step_other[r]), float(rays.rise[r]),
                                  float(rays.curv[r]), zmax, lift)


@pytest.mark.parametrize("elevation", [17.0, 31.3])
def test_wall_shadow_length_is_h_over_tan_elevation(elevation):
    """Sun from the west over a north-south wall of height h at column 5 (1 m cells): a cell d
    metres east of the wall is blocked exactly when h > d tan(el)."""
    h = 12.0
    z = np.zeros((3, 60), np.float32)
    z[:, 5] = h
    rays = sun_rays(Grid.uniform(3, 60, 1.0), 270.0, elevation)
    for c in range(6, 60):
        d = c - 5
        assert _blocked(z, rays, 1, c, h) == (h > d * math.tan(math.radians(elevation))), c
    # west of the wall (the sun's side) nothing is blocked; lifted above the wall's top, neither
    assert not any(_blocked(z, rays, 1, c, h) for c in range(0, 5))
    assert not _blocked(z, rays, 1, 6, h, lift=h + 0.01)


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
def test_ray_is_blocked_matches_the_plain_reference(azimuth):
    z = fractal_terrain(23, 29, seed=5, relief=40.0)
    z[7, 11] = np.nan
    dx, dy = 2.0, 1.5
    el = 14.0
    rays = sun_rays(Grid.uniform(23, 29, dx, dy), azimuth, el)
    ref = reference_mask(z, dx, dy, azimuth, el)
    zmax = float(np.nanmax(z))
    got = np.zeros_like(ref)
    for r in range(23):
        for c in range(29):
            got[r, c] = 255 if math.isnan(z[r, c]) else _blocked(z, rays, r, c, zmax)
    assert 0 < (got == 1).sum() < got.size - 1   # some shadow, some light
    np.testing.assert_array_equal(got, ref)


def test_ray_is_blocked_with_curvature_drops_far_obstacles():
    """The curvature term k^2 curv lowers the terrain relative to the ray: a wall that blocks
    a flat-Earth ray 40 steps away no longer does with a large curvature term."""
    z = np.zeros((1, 50), np.float32)
    z[0, 0] = 5.0
    flat = raymath.ray_is_blocked(z, 0, 40, True, -1, 0.0, 0.1, 0.0, 5.0, 0.0)
    curved = raymath.ray_is_blocked(z, 0, 40, True, -1, 0.0, 0.1, 0.01, 5.0, 0.0)
    assert flat and not curved
