"""The brute-force reference against analytic cases and an independent implementation."""

import functools
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from hillshade_rt.testing import box_terrain, fractal_terrain, reference_mask
import hillshade_rt
from hillshade_rt import Grid

# these tests check the algorithms against the flat model (analytic cases, references without
# curvature): shadow_mask with Earth curvature off (its default is the command line's, "auto")
shadow_mask = functools.partial(hillshade_rt.shadow_mask, curvature=False)

H = 10.0
EL = 30.0  # h / tan(30 deg) = 17.32 cells at 1 m: never near an integer


@pytest.mark.parametrize("azimuth, drow, dcol", [
    (0, 1, 0), (90, 0, -1), (180, -1, 0), (270, 0, 1),          # sun from N, E, S, W
    (45, 1, -1), (135, -1, -1), (225, -1, 1), (315, 1, 1),       # diagonals
])
def test_box_shadow_length_and_direction(azimuth, drow, dcol):
    """A box of height h casts a shadow of h / tan(E) away from the sun."""
    z = box_terrain(rows=101, cols=101, h=H, r0=45, r1=56, c0=45, c1=56)
    m = shadow_mask(z, azimuth, EL, spacing=1.0)
    step_len = math.hypot(drow, dcol)                     # ground metres per diagonal step
    n_expected = math.floor(H / math.tan(math.radians(EL)) / step_len)
    # walk from the box's centre cell away from the sun, past its edge
    r, c = 50, 50
    while 45 <= r < 56 and 45 <= c < 56:
        r, c = r + drow, c + dcol
    run = 0
    while m[r + run * drow, c + run * dcol] == 1:
        run += 1
    assert run == n_expected
    # nothing shadowed on the sun's side of the box
    rs, cs = np.nonzero(m == 1)
    assert np.all((rs - 50) * drow + (cs - 50) * dcol > 0)
    # the box's own top is lit, and so is flat ground beyond the shadow
    assert m[50, 50] == 0
    assert m[r + n_expected * drow, c + n_expected * dcol] == 0


def test_box_shadow_rectangular_pixels():
    """Spacing per axis: 2 m columns, 0.5 m rows. Sun from W: shadow runs east 17.32 m = 8 cols;
    sun from S: shadow runs north 17.32 m = 34 rows."""
    z = box_terrain(rows=120, cols=60, h=H, r0=58, r1=62, c0=20, c1=24)
    m = shadow_mask(z, 270, EL, spacing=(2.0, 0.5))
    assert np.array_equal(np.nonzero(m[60] == 1)[0], np.arange(24, 24 + 8))
    m = shadow_mask(z, 180, EL, spacing=(2.0, 0.5))
    assert np.array_equal(np.nonzero(m[:, 22] == 1)[0], np.arange(58 - 34, 58))


@pytest.mark.parametrize("azimuth", [253.7, 286.3, 241.0, 298.9])
def test_wall_shadow_at_non_special_azimuths(azimuth):
    """A north-south wall of height h: ground distance to it along the ray is
    (c - c_wall) * dx / |sin A|, so cell c is shadowed iff (c - c_wall) < h |sin A| / (dx tan E).
    Off-axis azimuths: the ray crosses the wall between two cell centres, both of height h."""
    rows, cols, cw, dx = 200, 80, 10, 1.5
    z = np.zeros((rows, cols), np.float32)
    z[:, cw] = H
    m = shadow_mask(z, azimuth, EL, spacing=dx)
    limit = H * abs(math.sin(math.radians(azimuth))) / (dx * math.tan(math.radians(EL)))
    expected = ((np.arange(cols) - cw) > 0) & ((np.arange(cols) - cw) < limit)
    for r in (80, 100, 120):  # rows whose rays stay inside the raster
        assert np.array_equal(m[r] == 1, expected), (azimuth, r)


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 17.5])
def test_ridge_shadow_at_non_special_azimuths(azimuth):
    """An east-west ridge, sun from the south or north (row-dominant rays)."""
    rows, cols, rw, dy = 80, 200, 40, 2.0
    z = np.zeros((rows, cols), np.float32)
    z[rw, :] = 25.0
    m = shadow_mask(z, azimuth, 20.0, spacing=(1.0, dy))
    cos_a = math.cos(math.radians(azimuth))
    limit = 25.0 * abs(cos_a) / (dy * math.tan(math.radians(20.0)))
    # distance in rows from the ridge, away from the sun (sun from the north: shadow falls
    # south, to higher rows; from the south: to lower rows)
    d = (np.arange(rows) - rw) * (1 if cos_a > 0 else -1)
    expected = (d > 0) & (d < limit)
    for c in (80, 100, 120):
        assert np.array_equal(m[:, c] == 1, expected), (azimuth, c)


def test_flat_terrain_has_no_shadow():
    z = np.full((50, 60), 123.5, np.float32)
    for az in (0, 45, 163, 203.7, 300):
        assert not shadow_mask(z, az, 0.5, spacing=1.0).any()


def test_sun_at_zenith_casts_no_shadow():
    z = fractal_terrain(64, 64, seed=1, relief=500.0)
    assert not shadow_mask(z, 123.0, 90.0, spacing=1.0).any()


def test_azimuth_wraps():
    z = fractal_terrain(64, 64, seed=2, relief=80.0)
    m0 = shadow_mask(z, 0.0, 10.0, spacing=2.0)
    assert m0.any()
    assert np.array_equal(m0, shadow_mask(z, 360.0, 10.0, spacing=2.0))
    assert np.array_equal(m0, shadow_mask(z, -720.0, 10.0, spacing=2.0))
    m = shadow_mask(z, 203.7, 10.0, spacing=2.0)
    assert np.array_equal(m, shadow_mask(z, 203.7 - 360.0, 10.0, spacing=2.0))
    assert np.array_equal(m, shadow_mask(z, 203.7 + 720.0, 10.0, spacing=2.0))


def test_sun_from_west_shadows_fall_east():
    z = box_terrain(rows=40, cols=40, h=5.0, r0=18, r1=22, c0=10, c1=14)
    m = shadow_mask(z, 270.0, 20.0, spacing=1.0)
    rs, cs = np.nonzero(m == 1)
    assert len(cs) > 0 and cs.min() >= 14


def test_long_low_sun_shadow_does_not_drift():
    """A 1000 m cliff at 0.5 deg on 100 m cells: h / tan(E) / dx = 1145.9 cells, exactly 1145."""
    cols = 1400
    z = np.zeros((1, cols), np.float32)
    z[0, :5] = 1000.0
    m = shadow_mask(z, 270.0, 0.5, spacing=100.0)
    expected = math.floor(1000.0 / math.tan(math.radians(0.5)) / 100.0)
    assert expected == 1145
    assert m[0, 5:5 + expected].all() and not m[0, 5 + expected:].any()


@pytest.mark.slow
def test_raising_the_sun_never_adds_shadow():
    z = fractal_terrain(90, 70, seed=3, relief=300.0)
    for az in (0.0, 163.0, 203.7, 45.0):
        prev = None
        for el in (1.0, 3.0, 8.0, 15.0, 30.0, 60.0, 89.0):
            m = shadow_mask(z, az, el, spacing=(10.0, 12.0)) == 1
            if prev is not None:
                assert not (m & ~prev).any(), (az, el)
            prev = m


def test_voids_are_nodata_and_cast_no_shadow():
    """A void (NaN) is written 255 and does not block rays; rays skip it."""
    z = box_terrain(rows=60, cols=60, h=10.0, r0=28, r1=32, c0=10, c1=14)
    solid = shadow_mask(z, 270.0, EL, spacing=1.0)
    z2 = z.copy()
    z2[28:32, 10:14] = np.nan  # the box becomes a void
    m = shadow_mask(z2, 270.0, EL, spacing=1.0)
    assert np.all(m[28:32, 10:14] == 255)
    assert not (m == 1).any()
    assert (solid == 1).any()
    # a void in the path of a ray, behind a real obstacle, changes nothing for cells beyond
    z3 = z.copy()
    z3[29, 16] = np.nan
    m3 = shadow_mask(z3, 270.0, EL, spacing=1.0)
    assert m3[29, 16] == 255
    other = np.ones_like(m3, bool)
    other[29, 16] = False
    assert np.array_equal(m3[other], solid[other])


settings.register_profile("ci", deadline=None, max_examples=60)
settings.load_profile("ci")

special_az = st.sampled_from([0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0])
any_az = st.floats(0.0, 360.0, exclude_max=True, allow_nan=False)


@pytest.mark.slow
@given(rows=st.integers(2, 22), cols=st.integers(2, 22), seed=st.integers(0, 2**31),
       relief=st.floats(1.0, 400.0), dx=st.floats(0.5, 50.0), dy=st.floats(0.5, 50.0),
       azimuth=st.one_of(special_az, any_az), elevation=st.floats(0.5, 89.0))
def test_brute_equals_independent_reference(rows, cols, seed, relief, dx, dy, azimuth, elevation):
    z = fractal_terrain(rows, cols, seed, relief)
    got = shadow_mask(z, azimuth, elevation, spacing=(dx, dy))
    want = reference_mask(z, dx, dy, azimuth, elevation)
    assert np.array_equal(got, want)


def test_brute_equals_reference_with_spacing_per_row_and_voids():
    """Geographic-style spacing (dx shrinking with latitude, dominant axis changing across rows
    at azimuth ~40 deg) and voids, at several non-special azimuths."""
    rows, cols = 30, 28
    z = fractal_terrain(rows, cols, seed=7, relief=200.0)
    z[5:8, 9:12] = np.nan
    z[20, 3] = np.nan
    lat = np.linspace(70.0, 40.0, rows)
    dx = 30.0 * np.cos(np.radians(lat)) / np.cos(np.radians(55.0))
    dy = np.full(rows, 30.0)
    grid = Grid(rows, cols, dx, dy)
    for az in (40.0, 163.0, 203.7, 317.2):
        for el in (2.0, 11.0):
            got = shadow_mask(z, az, el, spacing=grid)
            assert np.array_equal(got, reference_mask(z, dx, dy, az, el)), (az, el)


def test_strictly_below_means_shadow():
    """A ray that touches the terrain exactly is lit; one a hair below is shadowed.
    Heights and rise are exact binary fractions, so equality is exact."""
    from hillshade_rt.algorithms.raymath import ray_is_blocked

    z = np.array([[0.0, 0.5, 1.0, 1.5, 0.0]], np.float32)  # the ray from (0,0) rises 0.5 a column
    assert not ray_is_blocked(z, 0, 0, True, 1, 0.0, 0.5, 0.0, 10.0, 0.0)
    z[0, 3] = np.nextafter(np.float32(1.5), np.float32(2.0))
    assert ray_is_blocked(z, 0, 0, True, 1, 0.0, 0.5, 0.0, 10.0, 0.0)
