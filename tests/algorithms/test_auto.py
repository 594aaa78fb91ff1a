"""algorithms/auto.py: the default's choice between bounds and brute (its cost model) and its
mask (brute's, exactly: against the plain-Python reference)."""

import numpy as np
import pytest

from hillshade_rt.algorithms import auto
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import fractal_terrain, reference_mask, spectral


@pytest.mark.parametrize("azimuth", [163.0, 203.7, 290.0])
def test_auto_mask_equals_the_plain_reference(azimuth):
    z = fractal_terrain(30, 26, seed=11, relief=60.0)
    z[4:6, 20] = np.nan
    rays = sun_rays(Grid.uniform(30, 26, 3.0, 2.0), azimuth, 12.0)
    stats = {}
    got = auto.shadow_mask(z, rays, stats=stats)
    np.testing.assert_array_equal(got, reference_mask(z, 3.0, 2.0, azimuth, 12.0))
    assert sum(stats["auto"]["chose"].values()) == 1 and "Mcells/s" in stats["auto"]["why"]


def test_survey_counts_valid_cells_and_their_range():
    z = np.array([[1.0, np.nan], [-4.0, 7.5]], np.float32)
    assert auto.survey(z) == (0.75, -4.0, 7.5)


def test_cost_model_pieces():
    """brute: the plain march below PYRAMID_REACH steps, else over the pyramid (capped at
    BRUTE_NS_LONG per valid cell, plus the build per cell); bounds: valid and void cells
    weighted."""
    steps = auto.PYRAMID_REACH - 1
    assert auto.brute_ns(steps, 0.5) == pytest.approx(
        0.5 * (auto.PLAIN_NS_FIXED + auto.PLAIN_NS_PER_STEP * steps))
    assert auto.brute_ns(50.0) == pytest.approx(
        auto.BRUTE_NS_FIXED + auto.BRUTE_NS_PER_STEP * 50.0 + auto.BUILD_NS)
    assert auto.brute_ns(1e9) == pytest.approx(auto.BRUTE_NS_LONG + auto.BUILD_NS)
    assert auto.bounds_ns(True, 0.25) == pytest.approx(
        0.25 * auto.BOUNDS_NS + 0.75 * auto.BOUNDS_NS_VOID)
    assert auto.bounds_ns(False, 1.0) == auto.BOUNDS_NS_PER_ROW


def test_pyramid_pays_only_for_long_rays():
    grid = Grid.uniform(400, 400, 1.0)
    low = sun_rays(grid, 203.7, 5.0)     # 100 m of relief: over a thousand steps
    high = sun_rays(grid, 203.7, 80.0)   # 100 m at tan(80 deg) per step: 18 steps
    steep = sun_rays(grid, 203.7, 85.0)  # 9 steps
    assert auto.pyramid_pays((400, 400), (0.0, 100.0), low)
    assert auto.pyramid_pays((400, 400), (0.0, 100.0), high)
    assert not auto.pyramid_pays((400, 400), (0.0, 100.0), steep)


def test_record_counts_each_choice():
    stats = {}
    auto.record(stats, "bounds", "a")
    auto.record(stats, "brute", "b")
    auto.record(stats, "bounds", "c")
    assert stats["auto"]["chose"] == {"bounds": 2, "brute": 1} and stats["auto"]["why"] == "c"
    auto.record(None, "brute", "nothing to fill")


def test_zenith_single_line_and_all_voids_go_to_brute():
    grid = Grid.uniform(50, 50, 1.0)
    assert auto.choose((50, 50), 1.0, (0.0, 10.0), sun_rays(grid, 163.0, 90.0))[0] == "brute"
    rays = sun_rays(grid, 163.0, 10.0)
    assert auto.choose((50, 50), 0.0, (0.0, 10.0), rays)[0] == "brute"
    assert auto.choose((1, 50), 1.0, (0.0, 10.0), rays)[0] == "brute"


def test_auto_picks_bounds_on_mountains_and_brute_on_short_rays():
    rays = sun_rays(Grid.uniform(2000, 2000, 30.0), 203.7, 3.0)
    name, why = auto.choose((2000, 2000), 1.0, (0.0, 2000.0), rays)
    assert name == "bounds" and "reach" in why
    # gentle terrain under a high sun: rays clear the relief in a few steps
    rays = sun_rays(Grid.uniform(500, 500, 1000.0), 203.7, 40.0)
    assert auto.choose((500, 500), 1.0, (0.0, 300.0), rays)[0] == "brute"
    # mostly sea (voids): brute skips voids for free
    assert auto.choose((2000, 2000), 0.02, (0.0, 100.0), rays)[0] == "brute"
    assert auto.choose((2000, 2000), 1.0, (0.0, 2000.0), rays, "gpu")[0] == "brute"
    # a geographic tile too narrow for the wavefront to use a second thread: bounds on one
    # thread is estimated at half its rate, a tile of 150 positions per thread at its full rate
    import numba
    if numba.get_num_threads() >= 2:
        lat = np.linspace(32.0, 32.1, 100)
        grid = Grid(100, 300, 92.6 * np.cos(np.radians(lat)), np.full(100, 92.6), 1, -1, "")
        rays = sun_rays(grid, 290.0, 3.0)
        assert "(per-row rays, 1 of" in auto.choose((100, 300), 1.0, (0.0, 2000.0), rays)[1]
        lat = np.linspace(32.0, 33.0, 300)
        grid = Grid(300, 300, 92.6 * np.cos(np.radians(lat)), np.full(300, 92.6), 1, -1, "")
        rays = sun_rays(grid, 290.0, 3.0)     # two strips of 150 positions
        assert auto.choose((300, 300), 1.0, (0.0, 2000.0), rays)[0] == "bounds"
    st_ = {}
    auto.shadow_mask(spectral(64, 2.4, seed=5, relief=500.0), rays, stats=st_)
    assert st_["auto"]["chose"] in ({"bounds": 1}, {"brute": 1}) and st_["auto"]["why"]
