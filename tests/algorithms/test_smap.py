"""algorithms/smap.py: SMap's mask against the plain-Python reference (every NextV method, with
and without the pyramid), its tables (the NextV methods agree; better NextV skips hidden
silhouettes), points, and what it refuses. (Against brute on many terrains: test_agreement.)"""

import functools

import numpy as np
import pytest

import hillshade_rt
from hillshade_rt.algorithms import brute, smap
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import fractal_terrain, reference_mask

# the array API on the flat model (its default curvature is the command line's "auto")
shadow_mask = functools.partial(hillshade_rt.shadow_mask, curvature=False)


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
@pytest.mark.parametrize("opts", [{}, {"nextv": "binary"}, {"nextv": "quad"},
                                  {"better_nextv": True}, {"pyramid": False}])
def test_mask_equals_the_plain_reference(azimuth, opts):
    z = fractal_terrain(26, 31, seed=17, relief=60.0)
    z[3:5, 20] = np.nan
    rays = sun_rays(Grid.uniform(26, 31, 3.0, 2.5), azimuth, 9.0)
    stats = {}
    got = smap.shadow_mask(z, rays, stats=stats, **opts)
    np.testing.assert_array_equal(got, reference_mask(z, 3.0, 2.5, azimuth, 9.0))
    assert 0.0 < stats["black_fraction"] < 1.0 and stats["smap_bytes"] > 0


def test_a_box_casts_h_over_tan_el():
    """A 12 m block on a plain, sun from the west at 25 deg, 1 m cells: the shadow runs
    floor(12 / tan 25 deg) = 25 cells east of it."""
    z = np.zeros((21, 80), np.float32)
    z[8:13, 10:14] = 12.0
    m = smap.SMap(z, 270.0, 25.0, 1.0).mask()
    run = np.nonzero(m[10] == 1)[0]
    assert run[0] == 14 and len(run) == int(12.0 / np.tan(np.radians(25.0)))


def test_points_on_the_cell_centres_are_the_mask():
    z = fractal_terrain(30, 30, seed=2, relief=80.0)
    sm = smap.SMap(z, 203.7, 8.0, 5.0)
    rr, cc = np.mgrid[0:30, 0:30]
    got = sm.is_shadowed(np.c_[rr.ravel(), cc.ravel(), z.ravel()]).reshape(z.shape)
    np.testing.assert_array_equal(got, sm.mask() == 1)
    assert not sm.is_shadowed([[5.0, 5.0, 1e4]])[0]          # far above everything
    assert sm.is_shadowed(np.empty((0, 3))).shape == (0,)
    with pytest.raises(HillshadeError, match="an \\(N, 3\\) array"):
        sm.is_shadowed([[1.0, 2.0]])
    with pytest.raises(HillshadeError, match="finite"):
        sm.is_shadowed([[1.0, 2.0, np.nan]])


def test_refusals_and_the_per_row_fallback():
    z = fractal_terrain(20, 20, seed=3, relief=50.0)
    per_row = Grid(20, 20, np.linspace(20.0, 25.0, 20), np.full(20, 30.0))
    rays = sun_rays(per_row, 163.0, 6.0)
    with pytest.raises(HillshadeError, match="smap needs one sun direction"):
        smap.SMap(z, 0.0, 0.0, rays=rays)
    stats = {}
    np.testing.assert_array_equal(smap.shadow_mask(z, rays, stats=stats),
                                  brute.shadow_mask(z, rays))
    assert "smap marched every cell's ray like brute" in stats["note"]
    with pytest.raises(HillshadeError, match="nextv must be one of scan, binary, quad"):
        smap.SMap(z, 163.0, 6.0, 30.0, nextv="fast")


@pytest.mark.filterwarnings("ignore:All-NaN slice:RuntimeWarning")
def test_all_voids_and_a_sun_at_the_zenith():
    voids = np.full((6, 7), np.nan, np.float32)
    assert (smap.SMap(voids, 163.0, 10.0).mask() == 255).all()
    z = fractal_terrain(6, 7, seed=1)
    z[2, 2] = np.nan
    m = smap.SMap(z, 163.0, 90.0).mask()
    assert m[2, 2] == 255 and (m[~np.isnan(z)] == 0).all()


def test_tolerance_grows_with_the_heights():
    assert smap.tolerance(0.0, 0.0) == pytest.approx(1e-7)
    assert smap.tolerance(8848.0, 2.0) == pytest.approx(1e-7 * 8851.0)


def test_nextv_variants_build_the_same_table():
    z = fractal_terrain(90, 70, seed=4, relief=800.0)
    for az in (163.0, 203.7, 45.0, 300.0):
        tabs = [smap.SMap(z, az, 4.0, 30.0, nextv=m).J for m in smap.NEXTV_METHODS]
        assert np.array_equal(tabs[0], tabs[1]) and np.array_equal(tabs[0], tabs[2])


def test_better_nextv_skips_hidden_silhouettes_but_not_shadow():
    z = fractal_terrain(120, 120, seed=8, relief=1500.0)
    plain = smap.SMap(z, 203.7, 3.0, 30.0)
    better = smap.SMap(z, 203.7, 3.0, 30.0, better_nextv=True)
    assert np.array_equal(plain.mask(), better.mask())
    # Black elements of better NextV point at least as far ahead as plain ones (v + 1)
    L = plain.J.shape[0]
    v = np.arange(L)[:, None]
    black = plain.J <= -2
    assert np.array_equal(black, better.J <= -2)
    assert ((-2 - better.J)[black] >= (v + 1).repeat(plain.J.shape[1], 1)[black]).all()
    assert ((-2 - better.J)[black] > (v + 1).repeat(plain.J.shape[1], 1)[black]).any()


def test_black_fraction_is_reported_and_small():
    z = fractal_terrain(100, 100, seed=3, relief=600.0)
    stats = {}
    shadow_mask(z, 203.7, 5.0, 30.0, algorithm="smap", stats=stats)
    assert 0.0 < stats["black_fraction"] < 0.2
