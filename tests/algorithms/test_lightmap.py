"""algorithms/lightmap.py: a point light's Lambert shading (flat ground and a tilted plane:
N . V / d written out; the inverse-square falloff; cast shadows, voids), its integers, and the
light seen from points (azimuth, elevation, distance; a wall between point and light at 163,
203.7 and 290 degrees)."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import lightmap
from hillshade_rt.model.geometry import Grid

DX = 2.0


def _flat(rows=9, cols=11):
    return np.zeros((rows, cols), np.float32), Grid.uniform(rows, cols, DX)


def test_flat_ground_is_lit_by_height_over_distance():
    z, grid = _flat()
    mask = np.zeros(z.shape, np.uint8)
    H, rl, cl = 6.0, 3.5, 4.25
    got = lightmap.direct_light(z, grid, mask, rl, cl, H)
    r, c = np.mgrid[0:9, 0:11]
    d = np.sqrt(((c - cl) * DX) ** 2 + ((r - rl) * DX) ** 2 + H * H)
    np.testing.assert_allclose(got, H / d, rtol=1e-6)
    sq = lightmap.direct_light(z, grid, mask, rl, cl, H, falloff="inverse-square", d_ref=H)
    np.testing.assert_allclose(sq, H / d * np.minimum(1.0, (H / d) ** 2), rtol=1e-6)
    lifted = lightmap.direct_light(z, grid, mask, rl, cl, H, lift=1.5)
    d2 = np.sqrt(((c - cl) * DX) ** 2 + ((r - rl) * DX) ** 2 + (H - 1.5) ** 2)
    np.testing.assert_allclose(lifted, (H - 1.5) / d2, rtol=1e-6)


def test_shadows_voids_and_a_light_on_the_ground():
    z, grid = _flat(4, 4)
    z[0, 3] = np.nan
    mask = np.zeros(z.shape, np.uint8)
    mask[2, 1] = 1
    got = lightmap.direct_light(z, grid, mask, 1.0, 1.0, 0.0)
    assert got[1, 1] == 1.0                   # under the light, on the ground: it faces it
    assert got[2, 1] == 0.0 and np.isnan(got[0, 3])
    assert got[3, 3] == 0.0                   # a light on flat ground grazes the others
    with pytest.raises(ValueError, match="falloff"):
        lightmap.direct_light(z, grid, mask, 1.0, 1.0, 1.0, falloff="linear")
    with pytest.raises(TypeError):
        lightmap.direct_light(z.astype(np.float64), grid, mask, 1.0, 1.0, 1.0)


@pytest.mark.parametrize("above", [1.5, -0.5])
def test_tilted_plane_against_n_dot_v(above):
    """N . V / d written out on a plane; a light above the plane lights all of it, one below
    it (``above`` < 0: metres over the plane at the light's place) none."""
    ge, gn = 0.3, -0.2
    r, c = np.mgrid[0:7, 0:8]
    east, north = c * DX, -r * DX
    z = (ge * east + gn * north + 50.0).astype(np.float32)
    grid = Grid.uniform(7, 8, DX)
    rl, cl = 2.3, 6.6
    H = 50.0 + ge * cl * DX + gn * -rl * DX + above
    got = lightmap.direct_light(z, grid, np.zeros(z.shape, np.uint8), rl, cl, H)
    ve, vn, vu = (cl - c) * DX, -(rl - r) * DX, H - z.astype(np.float64)
    d = np.sqrt(ve ** 2 + vn ** 2 + vu ** 2)
    want = np.maximum(0.0, (vu - ge * ve - gn * vn) / (math.sqrt(1 + ge * ge + gn * gn) * d))
    np.testing.assert_allclose(got, want, atol=2e-6)
    assert (got > 0).all() if above > 0 else (got == 0).all()


def test_encode():
    direct = np.array([[0.0, 1.0, 0.5, np.nan]], np.float32)
    np.testing.assert_array_equal(lightmap.encode(direct, 0.0), [[1, 255, 128, 0]])
    np.testing.assert_array_equal(lightmap.encode(direct, 0.2, bits=16),
                                  [[1 + round(65534 * 0.2), 65535, 1 + round(65534 * 0.6), 0]])
    assert lightmap.encode(direct, 0.0).dtype == np.uint8
    with pytest.raises(ValueError, match="bits"):
        lightmap.encode(direct, 0.0, bits=12)


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
def test_light_at_points_direction_and_a_wall(azimuth):
    """A point at the centre of a flat 41 x 41 grid and a light 12 cells away toward
    ``azimuth``, 9 m up; a wall across the dominant axis halfway: the line to the light
    passes it at 9 / 2 m plus what the point stands on; below that the light is seen."""
    n, h0 = 41, 1.0
    a = math.radians(azimuth)
    r0 = c0 = 20.0
    rl, cl = r0 - 12 * math.cos(a), c0 + 12 * math.sin(a)      # north-up: north = -row
    H = 9.0
    z = np.zeros((n, n), np.float32)
    grid = Grid.uniform(n, n, DX)
    got = lightmap.light_at_points(z, grid, [r0], [c0], [h0], rl, cl, H)
    assert got["azimuth"][0] == pytest.approx(azimuth)
    assert got["distance"][0] == pytest.approx(math.hypot(24.0, H - h0))
    assert got["elevation"][0] == pytest.approx(math.degrees(math.atan2(H - h0, 24.0)))
    assert got["incidence"][0] == pytest.approx((H - h0) / math.hypot(24.0, H - h0))
    assert got["lit"][0]
    dom_col = abs(cl - c0) >= abs(rl - r0)
    half = round((c0 + cl) / 2) if dom_col else round((r0 + rl) / 2)
    k = abs(half - (c0 if dom_col else r0))
    frac = k / abs((cl - c0) if dom_col else (rl - r0))
    at_wall = h0 + frac * (H - h0)                # the line's height over the wall
    for wall, lit in ((at_wall - 0.01, True), (at_wall + 0.01, False)):
        zw = z.copy()
        if dom_col:
            zw[:, half] = wall
        else:
            zw[half, :] = wall
        assert lightmap.light_at_points(zw, grid, [r0], [c0], [h0], rl, cl, H)["lit"][0] == lit


def test_light_at_points_on_a_void_and_length_checks():
    z, grid = _flat(5, 5)
    z[2, 2] = np.nan
    got = lightmap.light_at_points(z, grid, [2.0, 0.0], [2.0, 0.0], [1.0, 0.0], 4.0, 4.0, 3.0)
    assert np.isnan(got["incidence"][0]) and not np.isnan(got["incidence"][1])
    with pytest.raises(ValueError, match="same length"):
        lightmap.light_at_points(z, grid, [1.0], [1.0, 2.0], [0.0], 4.0, 4.0, 3.0)
