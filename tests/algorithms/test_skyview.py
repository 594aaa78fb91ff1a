"""algorithms/skyview.py: the sums of the sky view factors (Zaksek, Dozier) and openness from
given horizon angles, against their formulas evaluated plainly (flat ground under a uniform
horizon; a tilted plane with a horizon that changes with direction)."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import skyview
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.geometry import Grid

AZ = [i * 360.0 / 8 for i in range(8)]


def test_definitions_and_their_settings():
    assert skyview.definition_of() == "zaksek"
    assert skyview.definition_of("dozier") == "dozier"
    assert skyview.definition_of("dozier", "negative") == "openness-negative"
    with pytest.raises(HillshadeError, match="definition must be one of zaksek, dozier"):
        skyview.definition_of("rvt")
    with pytest.raises(HillshadeError, match="openness must be one of positive, negative"):
        skyview.definition_of(openness="up")
    assert skyview.inverted("openness-negative") and not skyview.inverted("openness-positive")
    assert skyview.floor_deg("zaksek") == 0.0 and skyview.floor_deg("openness-positive") is None
    assert skyview.units("openness-negative").startswith("degrees")
    assert skyview.units("dozier") == "fraction 0..1"


@pytest.mark.parametrize("gamma", [0.0, 12.5, 37.0])
def test_flat_ground_under_a_uniform_horizon(gamma):
    """Zaksek: 1 - sin(gamma); Dozier on flat ground: mean sin^2 H = cos^2(gamma); openness:
    90 - gamma."""
    z = np.zeros((4, 5), np.float32)
    grid = Grid.uniform(4, 5, 10.0)
    beta = lambda a: np.full((4, 5), gamma, np.float32)   # noqa: E731
    zak = skyview.sky_view(z, grid, AZ, beta, "zaksek")
    doz = skyview.sky_view(z, grid, AZ, beta, "dozier")
    opn = skyview.sky_view(z, grid, AZ, beta, "openness-positive")
    assert zak.dtype == np.float32
    np.testing.assert_allclose(zak, 1.0 - math.sin(math.radians(gamma)), rtol=1e-6)
    np.testing.assert_allclose(doz, math.cos(math.radians(gamma)) ** 2, rtol=1e-6)
    np.testing.assert_allclose(opn, 90.0 - gamma, rtol=1e-6)


def test_terrain_below_the_horizontal_hides_no_sky_but_counts_for_openness():
    z = np.zeros((2, 2), np.float32)
    grid = Grid.uniform(2, 2, 1.0)
    beta = lambda a: np.full((2, 2), -20.0, np.float32)   # noqa: E731
    np.testing.assert_allclose(skyview.sky_view(z, grid, AZ, beta, "zaksek"), 1.0)
    np.testing.assert_allclose(skyview.sky_view(z, grid, AZ, beta, "dozier"), 1.0, rtol=1e-6)
    np.testing.assert_allclose(skyview.sky_view(z, grid, AZ, beta, "openness-positive"), 110.0)


def test_openness_skips_directions_with_nothing_ahead_and_voids_are_nan():
    s = skyview.Sum("openness-positive", np.zeros((1, 3), np.float32), Grid.uniform(1, 3, 1.0))
    s.add(0.0, np.array([[10.0, -90.0, np.nan]], np.float32))
    s.add(90.0, np.array([[30.0, -90.0, np.nan]], np.float32))
    out = s.result()
    assert out[0, 0] == pytest.approx(70.0)     # mean of 80 and 60
    assert np.isnan(out[0, 1]) and np.isnan(out[0, 2])
    z = skyview.Sum("zaksek", np.zeros((1, 2), np.float32), Grid.uniform(1, 2, 1.0))
    z.add(0.0, np.array([[10.0, np.nan]], np.float32))
    z.add(90.0, np.array([[10.0, 5.0]], np.float32))
    assert np.isnan(z.result()[0, 1]) and not np.isnan(z.result()[0, 0])


@pytest.mark.parametrize("azimuths", [[163.0, 203.7, 290.0], AZ])
def test_dozier_on_a_tilted_plane_against_the_formula(azimuths):
    """A plane of slope S facing aspect A; a horizon gamma(phi) that depends on the direction:
    Vd = mean over phi of cos S sin^2 H + sin S cos(phi - A) (H - sin H cos H), H = 90 - gamma
    (gamma clipped at 0)."""
    ge, gn = 0.2, -0.35                          # dz/d(east), dz/d(north)
    dx = 5.0
    r, c = np.mgrid[0:6, 0:6]
    z = (ge * c * dx - gn * r * dx).astype(np.float32)     # north-up: north = -row
    grid = Grid.uniform(6, 6, dx)
    gamma = {a: 25.0 * math.sin(math.radians(a)) ** 2 - 3.0 for a in azimuths}
    got = skyview.sky_view(z, grid, azimuths, lambda a: np.full((6, 6), gamma[a], np.float32),
                           "dozier")
    norm = math.sqrt(1 + ge * ge + gn * gn)
    cos_s = 1.0 / norm
    total = 0.0
    for a in azimuths:
        # sin S cos(phi - A): the unit normal's horizontal part along the direction phi
        sc = (-ge * math.sin(math.radians(a)) - gn * math.cos(math.radians(a))) / norm
        g = math.radians(max(0.0, np.float32(gamma[a])))
        h = math.pi / 2 - g
        total += cos_s * math.sin(h) ** 2 + sc * (h - math.sin(h) * math.cos(h))
    np.testing.assert_allclose(got, total / len(azimuths), rtol=2e-5)


def test_a_window_sum_equals_the_whole_rasters_cells():
    rng = np.random.default_rng(3)
    z = rng.random((8, 9)).astype(np.float32) * 20
    grid = Grid.uniform(8, 9, 2.0)
    betas = {a: rng.random((8, 9)).astype(np.float32) * 40 - 10 for a in AZ[:5]}
    whole = skyview.sky_view(z, grid, AZ[:5], betas.get, "dozier")
    part = skyview.Sum("dozier", z, grid, slice(2, 6), slice(3, 9))
    for a in AZ[:5]:
        part.add(a, betas[a][2:6, 3:9])
    np.testing.assert_array_equal(part.result(), whole[2:6, 3:9])


def test_dozier_sum_from_given_normals_is_the_same():
    """Horn's normals given (computed once by irradiance) give Dozier's Vd bit for bit."""
    from hillshade_rt.algorithms.irradiance import normals
    from hillshade_rt.algorithms.skyview import sky_view
    from hillshade_rt.testing import fractal_terrain
    z = fractal_terrain(40, 50, 4, relief=500.0).astype(np.float32)
    z[6, 7] = np.nan
    grid = Grid(40, 50, np.linspace(29.0, 31.0, 40), np.full(40, 30.9), 1, -1, "test")
    rng = np.random.default_rng(2)
    betas = {a: rng.uniform(-5.0, 40.0, z.shape).astype(np.float32)
             for a in (0.0, 90.0, 163.0, 203.7, 290.0)}
    plain = sky_view(z, grid, list(betas), betas.get, "dozier")
    given = sky_view(z, grid, list(betas), betas.get, "dozier", normals=normals(z, grid))
    assert np.array_equal(plain.view(np.uint32), given.view(np.uint32))
    assert np.isnan(given[6, 7]) and np.isfinite(given[7, 7])
