"""algorithms/per_cell_sun.py: every cell's own sun, interpolated on a lattice: the
interpolation (exact at the nodes and on linear fields), one vector's ray as ``sun_rays`` makes
it, night, the march of each cell with its own ray (moved here from test_pyramid), refine."""

import numpy as np
import pytest

from hillshade_rt.algorithms import brute, per_cell_sun
from hillshade_rt.algorithms.raymath import ray_is_blocked
from hillshade_rt.model.geometry import Grid, curvature_per_m2, sun_rays
from hillshade_rt.testing import spectral


def test_lattice_scale():
    assert per_cell_sun.lattice_scale(5, 101) == 0.04
    assert per_cell_sun.lattice_scale(5, 1) == 0.0


def test_lattice_at_is_bilinear():
    """Exact at the nodes; a field linear in row and column is reproduced between them."""
    n = 4
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    vec = np.stack([1.0 + 0.5 * i - 0.25 * j, 2.0 * j, np.full(i.shape, 3.0)], -1)
    si = per_cell_sun.lattice_scale(n, 31)     # 31 rows: node i at row 10 i
    sj = per_cell_sun.lattice_scale(n, 16)     # 16 cols: node j at col 5 j
    f = per_cell_sun.lattice_at.py_func
    assert f(20, 10, si, sj, vec) == pytest.approx(tuple(vec[2, 2]))
    for r, c in [(0, 0), (7, 3), (29, 14), (30, 15)]:
        fi, fj = r / 10.0, c / 5.0
        assert f(r, c, si, sj, vec) == pytest.approx((1.0 + 0.5 * fi - 0.25 * fj, 2.0 * fj, 3.0))


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
@pytest.mark.parametrize("spacing", [(30.0, 30.0), (20.0, 35.0)])
def test_ray_of_one_vector_is_sun_rays(azimuth, spacing):
    el = 7.5
    dx, dy = spacing
    rays = sun_rays(Grid.uniform(2, 2, dx, dy), azimuth, el, curvature=1e-7)
    e, no, up = per_cell_sun.lattice_vectors([[azimuth]], [[el]])[0, 0] * 3.0  # any length
    night, dc, sd, so, rise, curv = per_cell_sun.ray_of.py_func(e, no, up, dx, dy, 1.0, -1.0, 1e-7)
    assert not night and dc == bool(rays.dom_col[0]) and sd == rays.step_dom[0]
    assert so == pytest.approx(rays.step_other[0], abs=1e-12)
    assert rise == pytest.approx(rays.rise[0], rel=1e-12)
    assert curv == pytest.approx(rays.curv[0], rel=1e-12)


def test_a_sun_at_or_below_the_horizon_is_night():
    for up in (0.0, -0.2):
        night, dc, sd, so, rise, curv = per_cell_sun.ray_of.py_func(0.6, 0.8, up, 1.0, 1.0,
                                                                     1.0, -1.0, 0.0)
        assert night and not dc and rise == 0.0
    z = np.zeros((5, 6), np.float32)
    z[1, 1] = np.nan
    vec = per_cell_sun.lattice_vectors(np.full((2, 2), 163.0), [[5.0, 5.0], [-1.0, -1.0]])
    m = per_cell_sun.shadow_mask(z, Grid.uniform(5, 6, 1.0), vec)
    # the sun sinks below the horizon toward the last row: flat ground lit above, night below
    assert m[1, 1] == 255 and (m[0] == 0).all() and (m[4] == 1).all()
    with pytest.raises(TypeError):
        per_cell_sun.shadow_mask(z.astype(np.float64), Grid.uniform(5, 6, 1.0), vec)


def test_refine_answers_only_the_cells_of_its_code():
    z = spectral(32, 2.4, seed=9, relief=300.0)[:20, :24].copy()
    grid = Grid.uniform(20, 24, 30.0)
    vec = _lattice(203.7, 6.0, 3.0, 1.0)
    exact = per_cell_sun.shadow_mask(z, grid, vec)
    out = exact.copy()
    out[::3, ::2] = 7
    n = per_cell_sun.refine(z, grid, vec, 0.0, float(np.nanmax(z)), out, 7)
    assert n == np.count_nonzero(exact[::3, ::2] >= 0)
    np.testing.assert_array_equal(out, exact)
    assert per_cell_sun.refine(z, grid, vec, 0.0, float(np.nanmax(z)), out, 7) == 0


def _lattice(az0, el0, daz, del_, n=9):
    i, j = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n), indexing="ij")
    return per_cell_sun.lattice_vectors(az0 + daz * j + 0.3 * daz * i * j, el0 + del_ * i)


@pytest.mark.parametrize("az0,el0", [(163.0, 3.0), (203.7, 8.0), (290.0, 1.0), (44.0, 0.3)])
@pytest.mark.parametrize("curved", [False, True])
def test_per_cell_sun_is_each_cells_own_ray(az0, el0, curved):
    """Every cell marched with its own interpolated sun equals, cell by cell, the plain
    march of that cell with the ray ``cell_ray`` gives it (a night cell is shadowed); the
    direction varies by several degrees here, far more than a time-based sun does."""
    z = spectral(32, 2.4, seed=4, relief=400.0)[:23, :31].copy()
    z[4:6, 7:9] = np.nan
    lat = np.linspace(45, 46, 23)
    grid = Grid(23, 31, 30.0 * np.cos(np.radians(lat)) / np.cos(np.radians(45)),
                np.full(23, 30.0), 1, -1, "per row")
    vec = _lattice(az0, el0, 4.0, 2.5)
    c = curvature_per_m2(2e4, 0.13) if curved else 0.0
    zmax = float(np.nanmax(z))
    got = per_cell_sun.shadow_mask(z, grid, vec, c)
    plain = per_cell_sun.shadow_mask(z, grid, vec, c, pyramid=False)
    for r in range(23):
        for col in range(31):
            if np.isnan(z[r, col]):
                assert got[r, col] == 255
                continue
            night, dc, sd, so, ri, cv = per_cell_sun.cell_ray.py_func(
                r, col, vec, grid.dx, grid.dy, 1.0, -1.0, c, 0, 0, 23, 31)
            want = 1 if night else int(ray_is_blocked(z, r, col, dc, sd, so, ri, cv, zmax, 0.0))
            assert got[r, col] == want == plain[r, col], (r, col)


def test_per_cell_sun_with_one_direction_is_the_fixed_sun():
    z = spectral(64, 2.4, seed=6, relief=500.0)[:40, :50].copy()
    grid = Grid.uniform(40, 50, 30.0)
    for az, el in [(163.0, 4.0), (203.7, 12.0), (290.0, 2.0)]:
        vec = _lattice(az, el, 0.0, 0.0)
        got = per_cell_sun.shadow_mask(z, grid, vec)
        ref = brute.shadow_mask(z, sun_rays(grid, az, el), pyramid=False)
        # the same direction, computed through unit vectors: at most a rounding tie apart
        assert np.count_nonzero(got != ref) <= 2
