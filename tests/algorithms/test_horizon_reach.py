"""The horizon scan's reach (issue 20): a maximum distance along each ray, and the march carried
through windows (``Marches``), which must give the bits of the march in memory."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import horizon as hz
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import fractal_terrain, reference_horizon

AZIMUTHS = (163.0, 203.7, 290.0, 0.0, 45.0)
LAT = np.linspace(60.5, 60.0, 30)
DX_GEO = 111320.0 * np.cos(np.radians(LAT)) / 1200.0     # 3" cells: per-row spacing


def _terrain(rows=30, cols=34, seed=3, relief=400.0):
    z = fractal_terrain(rows, cols, seed, relief=relief, octaves=4)
    z[10:12, 14:17] = np.nan         # voids inside
    z[0, 5] = np.nan                 # and on the edge
    return z


GRIDS = [("uniform", Grid.uniform(30, 34, 30.0, 20.0), 30.0, 20.0),
         ("per-row", Grid(30, 34, DX_GEO, np.full(30, 92.6), 1, -1, "test"), DX_GEO, 92.6)]


@pytest.mark.parametrize("name, grid, dx, dy", GRIDS)
@pytest.mark.parametrize("azimuth", AZIMUTHS)
def test_max_distance_is_the_reference_within_that_distance(name, grid, dx, dy, azimuth):
    """Within M metres of ground distance along each ray, angles and distances are the plain
    reference's; beyond the raster's reach M changes nothing; a short M changes cells (the test
    can fail both ways)."""
    z = _terrain()
    rays = sun_rays(grid, azimuth, 10.0)
    ok = ~np.isnan(z)
    whole, wdist = hz.horizon_angles(z, rays), np.empty(z.shape, np.float32)
    hz.horizon_angles(z, rays, distance=wdist)
    changed = 0
    for m in (60.0, 130.0, 400.0):
        dist = np.empty(z.shape, np.float32)
        beta = hz.horizon_angles(z, rays, distance=dist, max_distance=m)
        ref, rdist = reference_horizon(z, dx, dy, azimuth, max_distance=m)
        np.testing.assert_allclose(beta[ok], ref[ok], atol=1e-5)
        assert np.array_equal(np.isnan(dist), np.isnan(rdist))
        assert (dist[~np.isnan(dist)] <= m * (1 + 1e-9)).all()
        # the nearest sample of the maximum (ties within rounding may pick another)
        assert np.isclose(dist, rdist, rtol=1e-6, equal_nan=True).mean() > 0.99
        changed += int((beta != whole)[ok].sum())
    assert changed > 30
    far = 10 * math.hypot(34 * float(np.max(dx)), 30 * float(np.max(dy)))
    dist = np.empty(z.shape, np.float32)
    np.testing.assert_array_equal(hz.horizon_angles(z, rays, distance=dist, max_distance=far),
                                  whole)
    np.testing.assert_array_equal(dist, wdist)


@pytest.mark.slow
def test_max_distance_beyond_the_raster_changes_no_bit():
    """Curved rays, every-third samples, the plain march and soft shadows' floor and cap: with M
    larger than the raster, the same bits as without M."""
    z = _terrain(60, 64, 7, 900.0)
    grid = Grid.uniform(60, 64, 30.0)
    for az in AZIMUTHS:
        rays = sun_rays(grid, az, 10.0, 5e-8)
        for kw in ({}, {"sample_spacing": 3}, {"pyramid": False},
                   {"floor_deg": 2.0, "cap_deg": 3.0}):
            np.testing.assert_array_equal(hz.horizon_angles(z, rays, max_distance=1e6, **kw),
                                          hz.horizon_angles(z, rays, **kw))


def test_a_distance_shorter_than_a_step_sees_nothing():
    z = _terrain()
    rays = sun_rays(Grid.uniform(30, 34, 30.0, 20.0), 203.7, 10.0)
    beta = hz.horizon_angles(z, rays, max_distance=1.0)
    assert (beta[~np.isnan(z)] == -90.0).all() and np.isnan(beta[np.isnan(z)]).all()


@pytest.mark.parametrize("bad", [0.0, -5.0, float("nan")])
def test_bad_max_distance_is_refused(bad):
    z = _terrain()
    rays = sun_rays(Grid.uniform(30, 34, 30.0), 203.7, 10.0)
    with pytest.raises(HillshadeError, match="maximum distance"):
        hz.horizon_angles(z, rays, max_distance=bad)


def test_hull_takes_no_max_distance():
    z = _terrain()
    rays = sun_rays(Grid.uniform(30, 34, 30.0), 90.0, 10.0)
    with pytest.raises(HillshadeError, match="scan method only"):
        hz.horizon_angles(z, rays, method="hull", max_distance=100.0)


def _windows(rows, cols, size, overlap):
    return [(a, min(rows, a + size + overlap), b, min(cols, b + size + overlap))
            for a in range(0, rows, size) for b in range(0, cols, size)]


@pytest.mark.slow
@pytest.mark.parametrize("name, grid, dx, dy", GRIDS)
@pytest.mark.parametrize("max_distance", [None, 250.0])
def test_marches_through_any_windows_give_the_same_bits(name, grid, dx, dy, max_distance):
    """A region's rays marched through windows of 9 x 9 cells (overlapping by one: a sample
    interpolates between two cells), taken in any order, round after round until every ray is
    closed: the angles and distances of the march in memory, bit for bit, curved or flat, over
    the windows' pyramids (whose blocks cut by a window's far edge must not be skipped) or not."""
    z = _terrain()
    rows, cols = z.shape
    zmax = float(np.nanmax(z))
    rng = np.random.default_rng(0)
    for az in AZIMUTHS:
        for curv in (0.0, 1e-7):
            rays = sun_rays(grid, az, 10.0, curv)
            want_d = np.empty(z.shape, np.float32)
            want = hz.horizon_angles(z, rays, distance=want_d, max_distance=max_distance)
            for pyramid in (True, False):
                got = np.full(z.shape, 7.0, np.float32)
                got_d = np.full(z.shape, 7.0, np.float32)
                for reg in _windows(rows, cols, 13, 0):
                    r0, r1, c0, c1 = reg
                    region_rays = sun_rays(Grid(r1 - r0, cols, grid.dx[r0:r1], grid.dy[r0:r1],
                                                1, -1, "t"), az, 10.0, curv)
                    m = hz.Marches(z[r0:r1, c0:c1], reg, region_rays, z.shape, zmax,
                                   max_distance=max_distance)
                    wins = _windows(rows, cols, 9, 1)
                    for _ in range(200):
                        if not m.open().any():
                            break
                        for i in rng.permutation(len(wins)):
                            w = wins[i]
                            m.march(hz.ScanWindow(np.ascontiguousarray(
                                z[w[0]:w[1], w[2]:w[3]]), w, z.shape, pyramid))
                    assert not m.open().any()
                    d = np.empty((r1 - r0, c1 - c0), np.float32)
                    got[r0:r1, c0:c1] = m.angles(d)
                    got_d[r0:r1, c0:c1] = d
                np.testing.assert_array_equal(got, want, err_msg=f"{name} {az} {curv}")
                np.testing.assert_array_equal(got_d, want_d)


def test_window_pyramid_poisons_only_the_cut_blocks():
    """Blocks that a window's far edge cuts short are +inf where the raster goes on beyond that
    edge, and keep their maxima where the window ends at the raster's edge."""
    from hillshade_rt.algorithms.pyramid import MaxPyramid
    z = _terrain(40, 40, 2)
    plain = MaxPyramid(z).args
    inside = hz.window_pyramid(z, (0, 40, 0, 40), (40, 40))
    np.testing.assert_array_equal(inside[0], plain[0])
    cut = hz.window_pyramid(z, (10, 50, 0, 40), (80, 40))      # rows go on below
    data, off, widths, nlev = cut
    lev1 = data[off[1]:off[2]].reshape(-1, widths[1])
    assert np.isinf(lev1[-1]).all() and np.isfinite(lev1[:-1]).all()   # 40 rows: 20 blocks
    assert np.array_equal(lev1[:-1], plain[0][off[1]:off[2]].reshape(-1, widths[1])[:-1])
