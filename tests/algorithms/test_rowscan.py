"""algorithms/rowscan.py: the scan taken row by row gives the per-cell march's angles and
distances bit for bit (both are checked against the plain-Python reference in
test_horizon.py): every option of the scan, flat and curved, one spacing and a spacing per row,
rows long enough that their last rays finish in the pyramid march, and rasters too small for
the vectorised loops."""

import numpy as np
import pytest

from hillshade_rt.algorithms import horizon
from hillshade_rt.algorithms.pyramid import MaxPyramid
from hillshade_rt.model.geometry import Grid, curvature_per_m2, sun_rays
from hillshade_rt.testing import fractal_terrain

AZIMUTHS = [163.0, 203.7, 290.0, 0.0, 45.0, 90.0, 11.25]
OPTIONS = [{}, {"max_distance": 70.0}, {"floor_deg": 0.0}, {"lift": 5.0}, {"lift": -3.0},
           {"floor_deg": 2.0, "cap_deg": 6.0}]


def _terrain(rows=70, cols=96):
    z = fractal_terrain(rows, cols, seed=5, relief=80.0)
    z[:, 60:] *= 0.05                      # a low plain: its rays run long, past the dense part
    z[11, 17] = z[40, 3] = z[52, 88] = np.nan
    return z


def _geographic(rows, cols):
    lat = np.radians(np.linspace(61.0, 59.0, rows))
    return Grid(rows, cols, 3.0 * np.cos(lat) / np.cos(np.radians(60.0)), np.full(rows, 3.2),
                1, -1, "geographic")


def _same(z, rays, pyr, **kw):
    d_cell = np.empty(z.shape, np.float32)
    d_row = np.empty(z.shape, np.float32)
    by_cell = horizon.horizon_angles(z, rays, pyramid=pyr, distance=d_cell, row_wise=False,
                                     **kw)
    by_row = horizon.horizon_angles(z, rays, pyramid=pyr, distance=d_row, **kw)
    np.testing.assert_array_equal(by_row.view(np.uint32), by_cell.view(np.uint32))
    np.testing.assert_array_equal(d_row.view(np.uint32), d_cell.view(np.uint32))
    return by_row


@pytest.mark.parametrize("azimuth", AZIMUTHS)
@pytest.mark.parametrize("geographic", [False, True])
def test_rows_equal_the_cell_march_bit_for_bit(azimuth, geographic):
    z = _terrain()
    grid = _geographic(*z.shape) if geographic else Grid.uniform(*z.shape, 3.0, 3.2)
    pyr = MaxPyramid(z)
    for curvature in (0.0, curvature_per_m2(6371000.0)):
        rays = sun_rays(grid, azimuth, 30.0, curvature)
        for kw in OPTIONS:
            beta = _same(z, rays, pyr, **kw)
            if not kw:    # the terrain gives every kind of answer
                assert (beta == -90).any() and (beta > 0).any() and (beta < 0).any()


@pytest.mark.parametrize("shape", [(1, 9), (9, 1), (2, 2), (3, 5), (5, 3), (4, 40), (40, 4)])
@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0, 0.0, 90.0])
def test_small_rasters_and_the_ends_of_rows(shape, azimuth):
    z = fractal_terrain(*shape, seed=9, relief=20.0) if min(shape) > 1 else \
        np.linspace(0.0, 7.0, shape[0] * shape[1]).reshape(shape).astype(np.float32)
    rays = sun_rays(Grid.uniform(*shape, 2.0, 2.5), azimuth, 30.0)
    for kw in OPTIONS:
        _same(z, rays, True, **kw)


def test_without_a_pyramid_and_with_a_flat_top():
    """The plain march finishes the long rays alike; a flat raster (every sample equal to
    its cell's height) gives 0 everywhere but where nothing lies ahead."""
    z = _terrain()
    rays = sun_rays(Grid.uniform(*z.shape, 3.0), 203.7, 30.0)
    _same(z, rays, False)
    flat = np.full((20, 50), 7.5, np.float32)
    beta = _same(flat, sun_rays(Grid.uniform(20, 50, 3.0), 290.0, 30.0), True)
    assert set(np.unique(beta)) == {-90.0, 0.0}
