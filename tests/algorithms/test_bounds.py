"""The certified bounds (algorithms.bounds): every cell the bounds decide is brute's answer (the
bounds really bound the exact horizon), they decide most cells, and the whole mask is brute's
cell for cell, on flat and curved rays, at non-special azimuths."""

import numpy as np
import pytest

from hillshade_rt.algorithms import bounds, brute
from hillshade_rt.model.geometry import Grid, curvature_per_m2, sun_rays
from hillshade_rt.testing import fractal_terrain, reference_mask

AZIMUTHS = (163.0, 203.7, 290.0)


def _decided_by_bounds(monkeypatch, z, rays):
    """The mask as the bounds left it, before brute refines the undecided cells."""
    seen = {}
    real = brute.refine

    def spy(z_, rays_, out, code, *a, **k):
        seen["out"], seen["code"] = out.copy(), code
        return real(z_, rays_, out, code, *a, **k)

    monkeypatch.setattr(brute, "refine", spy)
    full = bounds.shadow_mask(z, rays)
    return seen["out"], seen["code"], full


@pytest.mark.parametrize("az", AZIMUTHS)
@pytest.mark.parametrize("el", [2.0, 11.0, 37.0])
def test_decided_cells_are_brutes_and_most_are_decided(monkeypatch, az, el):
    z = fractal_terrain(96, 80, seed=7, relief=400.0)
    z[30:34, 20:50] = np.nan
    g = Grid.uniform(*z.shape, 30.0, 22.0)
    rays = sun_rays(g, az, el)
    pre, code, full = _decided_by_bounds(monkeypatch, z, rays)
    exact = brute.shadow_mask(z, rays)
    decided = pre != code
    assert np.array_equal(pre[decided], exact[decided]), int((pre[decided] != exact[decided]).sum())
    assert decided.mean() > 0.5          # the bounds do the work, not the fallback
    assert np.array_equal(full, exact)
    assert np.all(full[np.isnan(z)] == 255)


@pytest.mark.parametrize("az", AZIMUTHS)
def test_curved_rays_decided_cells_are_brutes(monkeypatch, az):
    z = fractal_terrain(64, 120, seed=3, relief=900.0)
    g = Grid.uniform(*z.shape, 250.0, 250.0)        # 30 km across: curvature matters
    rays = sun_rays(g, az, 1.5, curvature=curvature_per_m2(6.371e6))
    pre, code, full = _decided_by_bounds(monkeypatch, z, rays)
    exact = brute.shadow_mask(z, rays)
    decided = pre != code
    assert np.array_equal(pre[decided], exact[decided])
    assert np.array_equal(full, exact)
    flat = brute.shadow_mask(z, sun_rays(g, az, 1.5))
    assert (flat != exact).any()                    # the curved case is not the flat one


@pytest.mark.parametrize("az", AZIMUTHS)
def test_small_grid_against_the_independent_reference(az):
    z = fractal_terrain(18, 21, seed=11, relief=120.0)
    g = Grid.uniform(*z.shape, 10.0, 10.0)
    m = bounds.shadow_mask(z, sun_rays(g, az, 9.0))
    assert np.array_equal(m, reference_mask(z, 10.0, 10.0, az, 9.0))


def test_edges_all_void_zenith_and_bad_input():
    g = Grid.uniform(8, 8, 10.0, 10.0)
    voids = np.full((8, 8), np.nan, np.float32)
    assert np.all(bounds.shadow_mask(voids, sun_rays(g, 203.7, 20.0)) == 255)
    z = fractal_terrain(8, 8, seed=1, relief=50.0)
    z[2, 3] = np.nan
    top = bounds.shadow_mask(z, sun_rays(g, 163.0, 90.0))
    assert top[2, 3] == 255 and np.all(np.delete(top.ravel(), 2 * 8 + 3) == 0)
    with pytest.raises(TypeError):
        bounds.shadow_mask(z.astype(np.float64), sun_rays(g, 290.0, 20.0))


def test_field_step_samples_about_a_thousand_rays_of_a_small_raster():
    assert [bounds.field_step(n) for n in (1, 4095, 4096, 30_000, 1 << 16)] == [1, 1, 2, 5, 8]
    assert bounds.field_step((1 << 16) + 1) == bounds.field_step(10_000 * 10_000) == 16
    for rows, cols in [(64, 64), (150, 200), (97, 331), (256, 256)]:
        step = bounds.field_step(rows * cols)
        taken = (-(-rows // step) + 1) * (-(-cols // step) + 1)   # field_sample's lines x positions
        assert 0.5 * bounds.FIELD_SAMPLE < taken < 2.5 * bounds.FIELD_SAMPLE


@pytest.mark.parametrize("az0,el0,daz", [(163.0, 4.0, 0.6), (203.7, 11.0, 0.3), (71.0, 2.5, 1.5)])
def test_a_sampled_field_keeps_the_mask_and_the_decisions(monkeypatch, az0, el0, daz):
    """A sun per cell on a 150 x 200 raster, its field fitted to every 5th ray: the mask is the
    field's exact march cell for cell, and the bounds leave about as few cells undecided as
    with every ray in the fit (the sample's reason: 10 ms of 15 a sun went to the fit)."""
    from hillshade_rt.algorithms import per_cell_sun
    from hillshade_rt.algorithms.per_cell_sun import lattice_vectors
    z = fractal_terrain(150, 200, seed=5, relief=700.0)
    z[40:44, 90:97] = np.nan
    lat = np.linspace(34.2, 34.35, z.shape[0])
    g = Grid(*z.shape, 60.0 * np.cos(np.radians(lat)) / np.cos(np.radians(34.2)),
             np.full(z.shape[0], 60.0), 1, -1, "per row")
    i, j = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(-1, 1, 9), indexing="ij")
    vec = lattice_vectors(az0 + daz * j + 0.2 * daz * i * j, el0 + 0.4 * daz * i)
    c = curvature_per_m2(6.371e6, 0.13)
    assert bounds.field_step(z.size) == 5
    sampled = {}
    mask = bounds.shadow_mask_field(z, g, vec, c, stats=sampled)
    assert np.array_equal(mask, per_cell_sun.shadow_mask(z, g, vec, c, pyramid=False))
    monkeypatch.setattr(bounds, "field_step", lambda cells: 1)
    every = {}
    assert np.array_equal(bounds.shadow_mask_field(z, g, vec, c, stats=every), mask)
    assert sampled["undecided_fraction"] <= every["undecided_fraction"] + 0.01
    assert sampled["undecided_fraction"] < 0.2
