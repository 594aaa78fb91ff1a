"""Sums over many suns in windows (engine.sun_sums): the regions' sums, whatever the grouping of
the suns per read (one group, several, one per sun), are the bits of the same sums over the
raster in memory; a memory too small for one sun's window says how many cells it needs."""

import math

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.engine.lighting import Lighting
from hillshade_rt.engine.shader import render
from hillshade_rt.engine.sun_sums import (SunGroup, plan_regions, region_shape, region_sum,
                                          region_sums, weighted_light)
from hillshade_rt.engine.windows import (MemoryTooSmall, WindowCache, WindowLighting,
                                         block_stats)
from hillshade_rt.io import open_dem
from hillshade_rt.model.earth import dem_body
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import fractal_terrain, write_geotiff

SUNS = [(120.0, 4.0), (163.0, 11.0), (203.7, 17.0), (290.0, 6.0)]
WEIGHTS = [0.25, 1.0, 0.5, 0.75]


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    z = fractal_terrain(90, 110, seed=7, relief=120.0)
    z[40:44, 20:60] = np.nan
    path = write_geotiff(tmp_path_factory.mktemp("sums") / "dem.tif", z,
                         Affine(10.0, 0, 5000.0, 0, -10.0, 9000.0))
    return z, path


def _in_memory(z, src, lighting, sun_list=SUNS):
    sh = lighting.shader(z, src.grid, body=dem_body(src))
    acc = np.where(np.isnan(z), np.float32(np.nan), np.float32(0.0))
    for (az, el), w in zip(sun_list, WEIGHTS):
        acc += np.float32(w) * render(sh, SunOver(None, az, el), "sun", self_shadow=True)
    return acc


def _in_windows(src, lighting, budget, shape=None, sun_list=SUNS):
    st = block_stats(src)
    rows, cols = src.shape
    job = WindowLighting(src, lighting, dem_body(src), (st.zmin, st.zmax), math.hypot(cols * 10, rows * 10),
                         "sun")
    suns = [SunOver(None, az, el) for az, el in sun_list]
    regs = plan_regions(job, suns, st, budget, shape)
    out = np.full(src.shape, -1.0, np.float32)
    with src.reader() as rd:
        cache = WindowCache(rd)
        for rs in regs:
            r0, r1, c0, c1 = rs.region
            out[r0:r1, c0:c1] = region_sum(cache.get, rs, weighted_light(job, WEIGHTS))
    return out, regs


@pytest.mark.parametrize("budget", [10 ** 6, 1])
def test_each_groups_sum_is_the_bits_of_its_suns_in_memory(dem, budget):
    """``region_sums`` with the suns in groups (0, 1, 0, 1: not contiguous, as the months'
    are not among the lit suns of one region's reads): the total the bits of ``region_sum``'s,
    each group's the bits of its own suns' sum over the whole raster in memory (the same
    float32 terms added in the suns' order), voids NaN."""
    z, path = dem
    lighting = Lighting(algorithm="brute", curvature=False, self_shadow=True)
    group_of = np.array([0, 1, 0, 1])
    with open_dem(path, windows=True) as src:
        sh = lighting.shader(z, src.grid, body=dem_body(src))
        want = [np.where(np.isnan(z), np.float32(np.nan), np.float32(0.0)) for _ in range(2)]
        for k, ((az, el), w) in enumerate(zip(SUNS, WEIGHTS)):
            want[group_of[k]] += np.float32(w) * render(sh, SunOver(None, az, el), "sun",
                                                        self_shadow=True)
        total, regs = _in_windows(src, lighting, budget, (30, 40))
        st = block_stats(src)
        job = WindowLighting(src, lighting, dem_body(src), (st.zmin, st.zmax),
                             math.hypot(110 * 10, 90 * 10), "sun")
        got = np.full((3,) + src.shape, -1.0, np.float32)
        with src.reader() as rd:
            cache = WindowCache(rd)
            for rs in regs:
                r0, r1, c0, c1 = rs.region
                acc, per = region_sums(cache.get, rs, weighted_light(job, WEIGHTS), None,
                                       group_of, 2)
                got[:, r0:r1, c0:c1] = [acc] + per
    np.testing.assert_array_equal(got[0], total)
    np.testing.assert_array_equal(got[1], want[0])
    np.testing.assert_array_equal(got[2], want[1])
    assert np.isnan(got[1][40:44, 20:60]).all() and (got[1] != got[2]).any()
    assert np.nanmax(got[1]) > 0 and np.nanmax(got[2]) > 0


@pytest.mark.parametrize("budget", [10 ** 6, 3500, 1])
def test_any_grouping_of_the_suns_gives_the_bits_in_memory(dem, budget):
    """One group per region (all four suns' windows fit), several, one per sun (a budget of
    one cell): each cell's sum equal to the sum over the whole raster."""
    z, path = dem
    lighting = Lighting(algorithm="brute", curvature=False, self_shadow=True)
    with open_dem(path, windows=True) as src:
        want = _in_memory(z, src, lighting)
        got, regs = _in_windows(src, lighting, budget, (30, 40))
    np.testing.assert_array_equal(got, want)
    groups = [len(rs.groups) for rs in regs]
    assert len(regs) == 3 * 3
    if budget == 1:
        assert groups == [4] * 9
    elif budget == 10 ** 6:
        assert groups == [1] * 9
    else:
        assert max(groups) > 1 and min(groups) < 4
    for rs in regs:           # every sun's pieces in the suns' order, cut to the region
        idx = [i for g in rs.groups for i, _ in g.pieces]
        assert idx == sorted(idx) and set(idx) == {0, 1, 2, 3}
        for g in rs.groups:
            for _, p in g.pieces:
                assert _inside(p.window, g.window) and _inside(p.region, rs.region)


def _inside(a, b):
    return b[0] <= a[0] and a[1] <= b[1] and b[2] <= a[2] and a[3] <= b[3]


def test_the_shape_reads_the_fewest_cells_within_the_budget(dem):
    """Without --window-size the regions read the DEM about once when the suns' windows fit,
    and a budget smaller than one sun's window is MemoryTooSmall with the cells needed."""
    z, path = dem
    lighting = Lighting(algorithm="brute", curvature=False, self_shadow=True)
    high = [(az, el + 25.0) for az, el in SUNS]      # halos of some 20 cells
    with open_dem(path, windows=True) as src:
        st = block_stats(src)
        job = WindowLighting(src, lighting, dem_body(src), (st.zmin, st.zmax), 1500.0, "sun")
        suns = [SunOver(None, az, el) for az, el in high]
        assert region_shape(job, suns, st, 10 ** 6, (0, 90, 0, 110)) == (90, 110)
        tr, tc = region_shape(job, suns, st, 9000, (0, 90, 0, 110))
        assert (tr, tc) != (90, 110)
        with pytest.raises(MemoryTooSmall) as err:
            region_shape(job, suns, st, 100, (0, 90, 0, 110))
        assert err.value.cells > 100
        got, regs = _in_windows(src, lighting, 9000, sun_list=high)
        want = _in_memory(z, src, lighting, high)
    np.testing.assert_array_equal(got, want)
    assert len(regs) > 1
    assert all(g.cells <= 9000 for rs in regs for g in rs.groups if len(g.pieces) > 1)


def test_without_suns_the_sum_is_zero_and_the_voids(dem):
    """No sun with light (a polar night): every region read once, its sum 0 where there are
    heights and NaN on the voids."""
    z, path = dem
    lighting = Lighting(algorithm="brute", curvature=False)
    with open_dem(path, windows=True) as src:
        st = block_stats(src)
        job = WindowLighting(src, lighting, dem_body(src), (st.zmin, st.zmax), 1500.0, "sun")
        regs = plan_regions(job, [], st, 10 ** 6, (50, 64))
        assert [rs.groups for rs in regs] == [(SunGroup(rs.region, ()),) for rs in regs]
        assert region_shape(job, [], st, 5000, (0, 90, 0, 110)) == (64, 64)
        assert region_shape(job, [], st, 10 ** 6, (0, 90, 0, 110)) == (90, 110)
        got = np.full(z.shape, -1.0, np.float32)
        with src.reader() as rd:
            for rs in regs:
                r0, r1, c0, c1 = rs.region
                got[r0:r1, c0:c1] = region_sum(WindowCache(rd).get, rs, None)
    np.testing.assert_array_equal(got, np.where(np.isnan(z), np.float32(np.nan),
                                                np.float32(0.0)))
