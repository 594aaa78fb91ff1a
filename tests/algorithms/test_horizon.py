"""algorithms/horizon.py: horizon angles (scan: exact against the plain-Python reference and a
wall's atan(h / d); hull: equal to the scan on the axes and diagonals), their distances, the
mask of eq. 6, floors and caps, the horizon at points, and the checks of the options.
(``max_distance`` and the marches through windows: test_horizon_reach.py.)"""

import functools
import math

import numpy as np
import pytest

import hillshade_rt
from hillshade_rt.algorithms import horizon
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.geometry import Grid, curvature_per_m2, sun_rays
from hillshade_rt.testing import fractal_terrain, reference_horizon, reference_mask

DX, DY = 3.0, 2.0

# the array API on the flat model (its default curvature is the command line's "auto")
api_horizon = functools.partial(hillshade_rt.horizon_angles, curvature=False)
api_mask = functools.partial(hillshade_rt.shadow_mask, curvature=False)


def _terrain():
    z = fractal_terrain(24, 27, seed=21, relief=50.0)
    z[9, 13] = z[17, 3] = np.nan
    return z


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
@pytest.mark.parametrize("pyramid", [True, False])
def test_scan_equals_the_plain_reference(azimuth, pyramid):
    z = _terrain()
    rays = sun_rays(Grid.uniform(*z.shape, DX, DY), azimuth, 10.0)
    dist = np.empty(z.shape, np.float32)
    beta = horizon.horizon_angles(z, rays, distance=dist, pyramid=pyramid)
    ref, rdist = reference_horizon(z, DX, DY, azimuth)
    assert beta.dtype == np.float32
    np.testing.assert_array_equal(np.isnan(beta), np.isnan(z))
    np.testing.assert_allclose(beta, ref, atol=1e-4)
    np.testing.assert_allclose(dist, rdist, rtol=1e-5)
    assert (ref == -90).any() and (ref > 0).any() and (ref < 0).any()


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
def test_scan_mask_is_the_reference_mask(azimuth):
    z = _terrain()
    rays = sun_rays(Grid.uniform(*z.shape, DX, DY), azimuth, 8.0)
    np.testing.assert_array_equal(horizon.shadow_mask(z, rays),
                                  reference_mask(z, DX, DY, azimuth, 8.0))


@pytest.mark.parametrize("azimuth", [0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0])
def test_hull_equals_scan_on_axes_and_diagonals(azimuth):
    z = fractal_terrain(20, 20, seed=4, relief=30.0)
    rays = sun_rays(Grid.uniform(20, 20, 2.0), azimuth, 12.0)
    np.testing.assert_allclose(horizon.horizon_angles(z, rays, "hull"),
                               horizon.horizon_angles(z, rays), atol=1e-4)
    np.testing.assert_array_equal(horizon.shadow_mask(z, rays, method="hull"),
                                  horizon.shadow_mask(z, rays))


def test_hull_between_lines_stays_close_to_scan():
    z = fractal_terrain(30, 30, seed=6, relief=20.0)
    rays = sun_rays(Grid.uniform(30, 30, 5.0), 203.7, 12.0)
    hull = horizon.horizon_angles(z, rays, "hull")
    scan = horizon.horizon_angles(z, rays)
    ahead = scan > -90
    assert np.median(np.abs(hull - scan)[ahead]) < 0.5


@pytest.mark.parametrize("elevation_of_wall", [5.0, 20.0])
def test_a_wall_is_seen_at_atan_h_over_d(elevation_of_wall):
    """A north-south wall of height h at column 30, looking west from d metres east of it:
    beta = atan(h / d), its distance d."""
    h = 10.0
    z = np.zeros((3, 60), np.float32)
    z[:, 30] = h
    rays = sun_rays(Grid.uniform(3, 60, 1.0), 270.0, elevation_of_wall)
    dist = np.empty(z.shape, np.float32)
    beta = horizon.horizon_angles(z, rays, distance=dist)
    for c in range(31, 60):
        d = c - 30
        assert beta[1, c] == pytest.approx(math.degrees(math.atan(h / d)), abs=1e-4)
        assert dist[1, c] == d
    assert beta[1, 0] == -90.0 and np.isnan(dist[1, 0])      # nothing ahead
    assert beta[1, 10] == pytest.approx(0.0, abs=1e-6)       # flat ground ahead


def test_floor_and_cap():
    """Soft shadows' bounds: at or below the floor comes back as -90 (all of the disk seen, as
    with nothing ahead), above the cap as 90 (none of it); between them the exact angle."""
    z = _terrain()
    rays = sun_rays(Grid.uniform(*z.shape, DX, DY), 203.7, 10.0)
    full = horizon.horizon_angles(z, rays)
    valid = ~np.isnan(z)
    floored = horizon.horizon_angles(z, rays, floor_deg=-2.0, cap_deg=5.0)
    low, high = valid & (full <= -2.0), valid & (full > 5.0)
    mid = valid & ~low & ~high
    assert low.any() and high.any() and mid.any()
    assert (floored[low] == -90.0).all() and (floored[high] == 90.0).all()
    np.testing.assert_array_equal(floored[mid], full[mid])


def test_lift_lowers_the_horizon_as_the_reference():
    z = _terrain()
    rays = sun_rays(Grid.uniform(*z.shape, DX, DY), 290.0, 10.0)
    got = horizon.horizon_angles(z, rays, lift=4.0)
    ref, _ = reference_horizon(z, DX, DY, 290.0, lift=4.0)
    np.testing.assert_allclose(got, ref, atol=1e-4)


def test_profile_at_cell_centres_is_the_scans_horizon():
    z = _terrain()
    grid = Grid.uniform(*z.shape, DX, DY)
    azimuths = [163.0, 203.7, 290.0]
    rays_of = [sun_rays(grid, a, 10.0) for a in azimuths]
    rows = np.array([3.0, 12.0, 20.0])
    cols = np.array([5.0, 22.0, 8.0])
    heights = z[rows.astype(int), cols.astype(int)].astype(np.float64)
    angles, dist = horizon.profile(z, rows, cols, heights, rays_of)
    for j, rays in enumerate(rays_of):
        d = np.empty(z.shape, np.float32)
        beta = horizon.horizon_angles(z, rays, distance=d)
        for i in range(3):
            r, c = int(rows[i]), int(cols[i])
            assert angles[i, j] == pytest.approx(beta[r, c], abs=1e-4)
            if beta[r, c] > -90:
                assert dist[i, j] == pytest.approx(d[r, c], rel=1e-5)


def test_bilinear():
    r, c = np.mgrid[0:4, 0:5]
    z = (2.0 * r + 3.0 * c).astype(np.float32)
    assert horizon.bilinear(z, 1.25, 3.5) == pytest.approx(2.0 * 1.25 + 3.0 * 3.5)
    assert horizon.bilinear(z, 3.0, 4.0) == pytest.approx(18.0)
    assert math.isnan(horizon.bilinear(z, -0.1, 1.0)) and math.isnan(horizon.bilinear(z, 1, 4.2))
    z[1, 1] = np.nan
    assert math.isnan(horizon.bilinear(z, 0.5, 0.5))
    assert not math.isnan(horizon.bilinear(z, 2.5, 2.5))


def test_last_step():
    assert horizon.last_step(10.0, 3.0) == 3 and horizon.last_step(9.0, 3.0) == 3
    assert horizon.last_step(math.inf, 3.0) == horizon.NO_LIMIT


def test_checks_and_notes():
    z = _terrain()
    grid = Grid.uniform(*z.shape, DX, DY)
    rays = sun_rays(grid, 163.0, 10.0)
    with pytest.raises(HillshadeError, match="horizon method must be one of scan, hull"):
        horizon.horizon_angles(z, rays, "fast")
    with pytest.raises(HillshadeError, match="sample spacing must be a whole number >= 1"):
        horizon.horizon_angles(z, rays, sample_spacing=0)
    with pytest.raises(HillshadeError, match="--sample-spacing applies to the scan"):
        horizon.horizon_angles(z, rays, "hull", sample_spacing=2)
    with pytest.raises(HillshadeError, match="distance to the horizon comes from the scan"):
        horizon.horizon_angles(z, rays, "hull", distance=np.empty(z.shape, np.float32))
    with pytest.raises(HillshadeError, match="height above the ground must be a finite"):
        horizon.horizon_angles(z, rays, lift=math.inf)
    # the hull needs one flat-Earth ray for the raster: with curvature the scan runs, said
    curved = sun_rays(grid, 163.0, 10.0, curvature_per_m2(6.371e6))
    stats = {}
    got = horizon.horizon_angles(z, curved, "hull", stats=stats)
    assert "Earth curvature on: hull replaced by scan" in stats["note"]
    np.testing.assert_array_equal(got, horizon.horizon_angles(z, curved))


def test_horizon_angle_of_a_wall_and_of_a_summit():
    # wall of 50 m, 10 cells (100 m) west of a cell on flat ground: horizon toward 270 = atan(0.5)
    z = np.zeros((20, 40), np.float32)
    z[:, 5] = 50.0
    beta = api_horizon(z, 270.0, 10.0)
    assert beta[10, 15] == pytest.approx(math.degrees(math.atan(50.0 / 100.0)), abs=1e-5)
    assert beta[10, 0] == -90.0                  # nothing ahead inside the raster
    # a cone: its summit looks down in every direction (negative horizon)
    r, c = np.mgrid[0:41, 0:41]
    cone = (400.0 - 10.0 * np.hypot(r - 20, c - 20)).astype(np.float32)
    for az in (0.0, 163.0, 203.7):
        b = api_horizon(cone, az, 30.0)
        assert b[20, 20] < 0.0
        assert b[20, 20] == pytest.approx(-math.degrees(math.atan(10.0 / 30.0)), abs=0.5)


def test_horizon_angles_match_mask_and_sample_spacing():
    z = fractal_terrain(80, 80, seed=12, relief=700.0)
    g = Grid.uniform(80, 80, 30.0)
    beta = api_horizon(z, 163.0, g)
    for el in (2.0, 8.0, 20.0):
        assert np.array_equal(beta > el, api_mask(z, 163.0, el, g, algorithm="brute") == 1)
    sp2 = api_horizon(z, 163.0, g, sample_spacing=2)
    assert (sp2 <= beta + 1e-4).all()          # fewer samples: never a higher horizon
    assert (sp2 < beta - 1e-3).any()
    for el in (2.0, 8.0):                      # and mostly the same mask
        assert np.mean((sp2 > el) != (beta > el)) < 0.05
