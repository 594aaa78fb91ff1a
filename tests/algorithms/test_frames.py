"""algorithms/frames.py: the octant mapping (views, index conversion), the reach of a ray."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import frames
from hillshade_rt.model.geometry import Grid, sun_rays

AZIMUTHS = [0.0, 45.0, 163.0, 203.7, 290.0, 333.0, 90.0, 120.0]


@pytest.mark.parametrize("azimuth", AZIMUTHS)
def test_view_is_a_view_and_dem_index_inverts_it(azimuth):
    a = np.arange(5 * 8, dtype=np.float32).reshape(5, 8)
    f = frames.frame_of(sun_rays(Grid.uniform(5, 8, 1.0), azimuth, 20.0))
    v = f.view(a)
    assert np.shares_memory(v, a)
    L, P = v.shape
    assert (L, P) == ((8, 5) if f.dom_col else (5, 8))
    for i in range(L):
        for j in range(P):
            r, c = frames.dem_index(i, j, L, P, f.dom_col, f.flip_line, f.flip_pos)
            assert v[i, j] == a[r, c]


@pytest.mark.parametrize("azimuth", AZIMUTHS)
def test_a_step_toward_the_sun_is_one_line_forward(azimuth):
    """In canonical order the sun lies toward increasing line index and positions grow: one
    step toward the sun (in the DEM: step_dom along the dominant axis, step_other across) is
    (+1 line, +s positions), s = |step_other| >= 0."""
    rays = sun_rays(Grid.uniform(7, 7, 1.0), azimuth, 20.0)
    f = frames.frame_of(rays)
    assert f.s >= 0 and f.s == abs(f.so) and f.sd in (1, -1)
    # the DEM's step toward the sun, (rows, cols)
    step = (f.so, f.sd) if f.dom_col else (f.sd, f.so)
    # what +1 line and +1 position are in the DEM: read off views of the index grids
    rr, cc = np.mgrid[0:7, 0:7].astype(float)
    vr, vc = f.view(rr), f.view(cc)
    per_line = (vr[1, 0] - vr[0, 0], vc[1, 0] - vc[0, 0])
    per_pos = (vr[0, 1] - vr[0, 0], vc[0, 1] - vc[0, 0])
    assert math.isclose(per_line[0] + f.s * per_pos[0], step[0])
    assert math.isclose(per_line[1] + f.s * per_pos[1], step[1])


def test_frame_of_carries_rise_and_step_length():
    rays = sun_rays(Grid.uniform(4, 4, 2.0, 3.0), 203.7, 30.0)
    f = frames.frame_of(rays)
    assert f.rise == pytest.approx(math.tan(math.radians(30.0)) * f.step_m)
    assert f.step_m == pytest.approx(float(rays.step_m[0]))


def test_uniform_rays_tells_per_row_spacing_apart():
    g = Grid.uniform(6, 6, 10.0)
    assert frames.uniform_rays(sun_rays(g, 163.0, 10.0))
    per_row = Grid(6, 6, np.linspace(8.0, 10.0, 6), np.full(6, 10.0))
    assert not frames.uniform_rays(sun_rays(per_row, 163.0, 10.0))


def test_steps_over_is_the_relief_over_the_rise_clamped():
    assert frames.steps_over(100.0, 4.0, 1000) == 25.0
    assert frames.steps_over(100.0, 4.0, 10) == 10.0        # at most the lines
    assert frames.steps_over(0.5, 4.0, 10) == 1.0           # at least one step
    assert frames.steps_over(-3.0, 4.0, 10) == 1.0
    assert frames.steps_over(100.0, 0.0, 10) == math.inf     # a sun on the horizon
    assert frames.steps_over(100.0, math.inf, 10) == math.inf  # at the zenith


def test_reach_uses_the_extent_along_the_rays():
    """Sun from the west (dominant axis: columns): at most the column count; 1 m cells at 10
    deg rise tan(10 deg) per step."""
    rays = sun_rays(Grid.uniform(50, 300, 1.0), 270.0, 10.0)
    assert frames.reach((50, 300), (0.0, 20.0), rays) == pytest.approx(
        20.0 / math.tan(math.radians(10.0)))
    assert frames.reach((50, 300), (0.0, 2000.0), rays) == 300.0
    rays = sun_rays(Grid.uniform(50, 300, 1.0), 180.0, 10.0)
    assert frames.reach((50, 300), (0.0, 2000.0), rays) == 50.0
