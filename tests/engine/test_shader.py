"""The shader's geometry (engine.shader): how far a ray reaches before it clears the terrain
(against the closed form), and the halo of a window: shading the window with only its halo's
heights gives the same cells as shading the whole raster, at non-special azimuths."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import brute
from hillshade_rt.engine.shader import halo_bounds, reach_m
from hillshade_rt.model.geometry import Grid, curvature_per_m2, sun_rays
from hillshade_rt.testing import fractal_terrain

AZIMUTHS = (163.0, 203.7, 290.0)


@pytest.mark.parametrize("el", [0.7, 9.0, 41.0])
@pytest.mark.parametrize("c", [0.0, curvature_per_m2(6.371e6), 1e-4])
def test_reach_is_where_the_ray_has_risen_dz(el, c):
    for dz in (1.0, 350.0, 4000.0):
        d = reach_m(dz, el, c)
        # the ray's height above its start at ground distance d: d tan(el) + c d^2
        assert d * math.tan(math.radians(el)) + c * d * d == pytest.approx(dz, rel=1e-9)
        assert d <= dz / math.tan(math.radians(el)) * (1 + 1e-12)   # curvature shortens it
    assert reach_m(10.0, 0.0) == math.inf and reach_m(10.0, -3.0) == math.inf
    assert reach_m(10.0, 90.0) == 0.0 and reach_m(0.0, el) == 0.0


@pytest.mark.parametrize("az", AZIMUTHS)
@pytest.mark.parametrize("el", [4.0, 15.0])
def test_the_halo_holds_everything_that_shades_the_window(az, el):
    z = fractal_terrain(120, 130, seed=9, relief=500.0)
    dx, dy = 20.0, 15.0
    rays = sun_rays(Grid.uniform(*z.shape, dx, dy), az, el)
    whole = brute.shadow_mask(z, rays)
    bounds = (50, 70, 55, 80)
    r0, r1, c0, c1 = bounds
    dz = float(np.nanmax(z)) - float(np.nanmin(z[r0:r1, c0:c1]))
    h0, h1, g0, g1 = halo_bounds(bounds, z.shape, Grid.uniform(*z.shape, dx, dy), az,
                                 reach_m(dz, el))
    assert h0 <= r0 and h1 >= r1 and g0 <= c0 and g1 >= c1
    assert (h1 - h0) * (g1 - g0) < z.size        # a halo, not the whole raster
    part = z[h0:h1, g0:g1].copy()
    cut = brute.shadow_mask(part, sun_rays(Grid.uniform(*part.shape, dx, dy), az, el))
    np.testing.assert_array_equal(cut[r0 - h0:r1 - h0, c0 - g0:c1 - g0], whole[r0:r1, c0:c1])


def test_halo_margin_and_an_endless_reach():
    g = Grid.uniform(100, 100, 10.0, 10.0)
    # the sun due east (grid azimuth 90): grows toward higher columns only, 2 cells across rows
    assert halo_bounds((40, 50, 40, 50), (100, 100), g, 90.0, 100.0) == (38, 52, 40, 62)
    assert halo_bounds((40, 50, 40, 50), (100, 100), g, 90.0, 100.0, margin=3) == (35, 55, 37, 65)
    assert halo_bounds((40, 50, 40, 50), (100, 100), g, 203.7, math.inf)[1] == 100


def test_threads_for_caps_the_threads_by_cells_and_restores_them():
    import numba

    from hillshade_rt.engine.shader import CELLS_PER_THREAD, threads_for
    n = numba.get_num_threads()
    with threads_for(CELLS_PER_THREAD - 1) as k:
        assert k == numba.get_num_threads() == 1
    assert numba.get_num_threads() == n
    with threads_for(10**9) as k:           # never more than were set
        assert k == numba.get_num_threads() == n
    with pytest.raises(ZeroDivisionError), threads_for(5):
        1 / 0
    assert numba.get_num_threads() == n
    if n >= 2:
        with threads_for(2 * CELLS_PER_THREAD + 7) as k:
            assert k == numba.get_num_threads() == 2


def test_a_small_dems_sun_runs_on_one_thread_with_the_same_mask(monkeypatch):
    """render caps the threads of its kernels by the DEM's cells (a parallel region's wait
    cost a small DEM more than its cells): the mask is brute's all the same, and the caller's
    thread count is back afterwards."""
    import numba

    from hillshade_rt.engine.shader import Shader, render
    from hillshade_rt.model.sun import SunOver
    z = fractal_terrain(60, 70, seed=4, relief=500.0)
    g = Grid.uniform(*z.shape, 30.0, 30.0)
    seen = []
    real = Shader.cast

    def spy(self, region, stats=None):
        seen.append(numba.get_num_threads())
        return real(self, region, stats)

    monkeypatch.setattr(Shader, "cast", spy)
    n = numba.get_num_threads()
    for az, el in [(163.0, 7.0), (290.0, 23.0)]:
        mask = render(Shader(z, g, "bounds", curvature=False), SunOver(None, az, el), "shadow")
        assert np.array_equal(mask, brute.shadow_mask(z, sun_rays(g, az, el)))
    assert seen == [1, 1] and numba.get_num_threads() == n
