"""smap, horizon and sweep against brute (and the independent reference) on the same model."""

import functools
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from hillshade_rt.testing import box_terrain, data_path, fractal_terrain, reference_mask
from hillshade_rt.algorithms import brute, horizon, smap, sweep
from hillshade_rt.algorithms.frames import frame_of
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.io import read_dem
import hillshade_rt
from hillshade_rt import is_shadowed

# these tests check the algorithms against the flat model (analytic cases, references without
# curvature): shadow_mask with Earth curvature off (its default is the command line's, "auto")
shadow_mask = functools.partial(hillshade_rt.shadow_mask, curvature=False)
horizon_angles = functools.partial(hillshade_rt.horizon_angles, curvature=False)

settings.register_profile("ci", deadline=None, max_examples=60)
settings.load_profile("ci")

AZIMUTHS = [0.0, 45.0, 90.0, 135.0, 163.0, 203.7, 241.0, 298.9, 315.0, 17.5]
ELEVATIONS = [0.5, 3.0, 15.0, 45.0, 89.0]
EXACT = [("smap", {}), ("smap", {"nextv": "binary"}), ("smap", {"nextv": "quad"}),
         ("smap", {"better_nextv": True}), ("horizon", {})]


def masks(z, dx, dy, az, el, name, opts):
    g = Grid.uniform(*z.shape, dx, dy)
    return (shadow_mask(z, az, el, g, algorithm="brute"),
            shadow_mask(z, az, el, g, algorithm=name, **opts))


@pytest.mark.parametrize("name,opts", [pytest.param(*e, marks=pytest.mark.slow) if i in (0, 3)
                                       else e for i, e in enumerate(EXACT)])
def test_exact_equals_brute_on_fractal_with_voids(name, opts):
    z = fractal_terrain(61, 47, seed=5, relief=250.0)
    z[20:24, 10:30] = np.nan
    z[40, 5] = np.nan
    for az in AZIMUTHS:
        for el in ELEVATIONS:
            a, b = masks(z, 30.0, 22.0, az, el, name, opts)
            assert np.array_equal(a, b), (name, opts, az, el, int((a != b).sum()))


@pytest.mark.slow
@settings(max_examples=40)
@given(seed=st.integers(0, 10_000), rows=st.integers(2, 32), cols=st.integers(2, 32),
       dx=st.floats(0.5, 100.0), dy=st.floats(0.5, 100.0),
       az=st.one_of(st.sampled_from([0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]),
                    st.floats(0.0, 360.0)),
       el=st.floats(0.5, 89.0), relief=st.floats(1.0, 2000.0))
def test_property_smap_and_horizon_equal_brute(seed, rows, cols, dx, dy, az, el, relief):
    z = fractal_terrain(rows, cols, seed=seed, relief=relief)
    ref = reference_mask(z, dx, dy, az, el) if rows * cols <= 400 else None
    g = Grid.uniform(rows, cols, dx, dy)
    b = shadow_mask(z, az, el, g, algorithm="brute")
    if ref is not None:
        assert np.array_equal(b, ref)
    for name, opts in EXACT:
        assert np.array_equal(b, shadow_mask(z, az, el, g, algorithm=name, **opts)), (name, opts)
    # sweep: approximate. On real DEMs its error is small (test_real_dems, docs/algorithms.md);
    # on these tiny random terrains (often steeper than 45 degrees) it is larger: a sharp peak
    # between the two stored rays it interpolates can be missed. Bound the share of wrong cells.
    sw = shadow_mask(z, az, el, g, algorithm="sweep")
    assert np.mean(sw != b) < 0.15


@pytest.mark.slow
@pytest.mark.parametrize("az", [17.0, 77.7, 163.0, 203.7, 291.3])
def test_sweep_line_passes_equal_per_cell_kernel(az):
    """The vectorised line passes (one ray direction) and the per-cell kernel (per-row rays)
    compute the same thing; the refinement makes the unsure cells exact."""
    z = fractal_terrain(90, 110, seed=5, relief=600.0)
    z[40:44, 50:57] = np.nan
    g = Grid.uniform(90, 110, 20.0)
    for el in (3.0, 12.0):
        rays = sun_rays(g, az, el)
        f, s, rise, per_line = sweep._per_cell_rays(rays)
        out = np.empty(z.shape, np.uint8)
        # hmin -inf: every cell trusts the stored values, as the line passes of one ray do
        sweep._sweep_lines(f.view(z), s, rise, np.full(len(s), -np.inf), per_line,
                           np.int64(sweep.EXACT_STEPS), True, float(np.nanmin(z)) - 1.0,
                           float(np.nanmax(z)), f.view(out))
        stats = {}
        fast = sweep.shadow_mask(z, rays, stats=stats)
        ref = brute.shadow_mask(z, rays)
        unsure = out == sweep.UNSURE
        assert np.array_equal(fast[~unsure], out[~unsure])
        assert np.array_equal(fast[unsure], ref[unsure])
        assert stats["unsure_fraction"] == pytest.approx(unsure.mean())
    assert unsure.any()


@pytest.mark.parametrize("az", [163.0, 203.7, 291.3])
def test_sweep_islands_in_a_nodata_sea(az):
    """Half the cells void (islands in a nodata sea): rays over the sea meet no terrain, the
    coasts are void edges. sweep stays within 1 degree of the sun on the wrong cells, and the
    exact march that replaces interpolation next to no-terrain rays gives brute's mask there."""
    z = fractal_terrain(130, 150, seed=4, relief=800.0, octaves=5).astype(np.float32)
    z[z < np.percentile(z, 50)] = np.nan
    g = Grid.uniform(130, 150, 30.0)
    for el in (3.0, 9.0):
        rays = sun_rays(g, az, el)
        ref = brute.shadow_mask(z, rays)
        wrong = sweep.shadow_mask(z, rays) != ref
        assert (ref == 1).any() and wrong.sum() <= 0.005 * (ref != 255).sum()
        if wrong.any():
            beta = horizon.horizon_angles(z, rays)
            assert np.abs(beta[wrong] - el).max() < 1.0


@pytest.mark.parametrize("az", [163.0, 203.7, 12.5, 77.0, 300.2])
def test_sweep_wavefront_strips_equal_one_strip(az):
    """The parallel wavefront (positions cut into strips, strip j one block of lines behind
    strip j-1) gives the same codes as a single strip, whatever the number of strips."""
    z = fractal_terrain(120, 150, seed=9, relief=600.0)
    z[60:64, 70:77] = np.nan
    z = z.astype(np.float32)
    f = frame_of(sun_rays(Grid.uniform(120, 150, 20.0), az, 4.0))
    outs = []
    for strips in (1, 2, 5):
        out = np.empty(z.shape, np.uint8)
        sweep._sweep_uniform(z, f.view(z), f.dom_col, f.flip_line, f.flip_pos, f.s, f.rise,
                             np.int64(4), np.int64(strips), True,
                             float(np.nanmin(z)) - 1.0, float(np.nanmax(z)), out)
        outs.append(out)
    assert (outs[0] == 1).any() and (outs[0] == sweep.UNSURE).any()
    for out in outs[1:]:
        assert np.array_equal(out, outs[0])


@pytest.mark.parametrize("az", [0.0, 45.0, pytest.param(90.0, marks=pytest.mark.slow), 135.0,
                                pytest.param(180.0, marks=pytest.mark.slow), 225.0, 270.0,
                                315.0])
def test_sweep_and_hull_exact_on_axes_and_diagonals(az):
    z = fractal_terrain(70, 60, seed=2, relief=400.0)
    z[30:33, 30:40] = np.nan
    g = Grid.uniform(70, 60, 25.0)
    for el in (2.0, 10.0, 30.0):
        b = shadow_mask(z, az, el, g, algorithm="brute")
        assert np.array_equal(b, shadow_mask(z, az, el, g, algorithm="sweep")), el
        assert np.array_equal(b, shadow_mask(z, az, el, g, algorithm="horizon", method="hull")), el
    scan = horizon_angles(z, az, g)
    hull = horizon_angles(z, az, g, method="hull")
    np.testing.assert_allclose(hull, scan, atol=1e-4, equal_nan=True)


@pytest.mark.parametrize("name,opts", EXACT + [("sweep", {}), ("horizon", {"method": "hull"})])
def test_box_shadow_length_at_non_special_azimuth(name, opts):
    # 100 m tower on flat ground, sun from 253.7 deg (WSW) at 20 deg: the shadow runs
    # h / tan(E) = 274.7 m toward 73.7 deg, i.e. 274.7 * sin(73.7) = 263.7 m = 26.4 cells east of
    # the tower's east face (column 23).
    z = box_terrain(60, 120, h=100.0, r0=28, r1=32, c0=20, c1=24)
    a, b = masks(z, 10.0, 10.0, 253.7, 20.0, name, opts)
    if name in ("smap", "horizon") and opts.get("method") != "hull":
        assert np.array_equal(a, b)
    else:
        assert (a != b).sum() <= 0.15 * (a == 1).sum()   # approximate: shadow edges blur
    exact = name in ("smap", "horizon") and opts.get("method") != "hull"
    cols = np.nonzero((b == 1).any(axis=0))[0]
    expected = 100.0 / math.tan(math.radians(20.0)) * math.sin(math.radians(73.7)) / 10.0
    assert cols.min() >= 20 and cols.max() - 23 == pytest.approx(expected, abs=1.0 if exact else 2.0)
    rows = np.nonzero((b == 1).any(axis=1))[0]
    assert rows.min() < 28 and rows.max() <= (31 if exact else 32)   # drifts north (ENE)


@pytest.mark.parametrize("name,opts", EXACT + [("sweep", {}), ("horizon", {"method": "hull"})])
def test_raising_the_sun_never_adds_shadow(name, opts):
    z = fractal_terrain(50, 50, seed=11, relief=500.0)
    g = Grid.uniform(50, 50, 30.0)
    for az in (163.0, 203.7, 290.0):
        prev = None
        for el in (1.0, 3.0, 7.0, 15.0, 30.0, 60.0):
            m = shadow_mask(z, az, el, g, algorithm=name, **opts) == 1
            if prev is not None:
                assert not (m & ~prev).any(), (az, el)
            prev = m


def _point_reference(z, dx, dy, az, el, pts):
    """Plain march of a free point's ray (array coordinates), sampling every dominant grid line
    strictly ahead of it."""
    rows, cols = z.shape
    a = math.radians(az)
    vc, vr = math.sin(a) / dx, -math.cos(a) / dy     # pixels per metre (north-up)
    dom_col = abs(vc) >= abs(vr)
    dom = max(abs(vc), abs(vr))
    tan_e = math.tan(math.radians(el))
    out = []
    for r0, c0, h in pts:
        start = c0 if dom_col else r0
        sgn = 1 if (vc if dom_col else vr) > 0 else -1
        line = math.floor(start) + 1 if sgn > 0 else math.ceil(start) - 1
        res = False
        n_lines = cols if dom_col else rows
        while (sgn > 0 and line < n_lines) or (sgn < 0 and line >= 0):
            if not 0 <= line < n_lines:      # not yet over the raster: next line
                line += sgn
                continue
            t = abs(line - start) / dom
            r, c = r0 + vr * t, c0 + vc * t
            other, n = (r, rows) if dom_col else (c, cols)
            if 0 <= other <= n - 1:
                i = min(int(math.floor(other)), n - 2) if n > 1 else 0
                f = other - i
                if dom_col:
                    terr = (1 - f) * z[i, line] + (f * z[i + 1, line] if f else 0.0)
                else:
                    terr = (1 - f) * z[line, i] + (f * z[line, i + 1] if f else 0.0)
                if terr > h + t * tan_e:
                    res = True
                    break
            line += sgn
        out.append(res)
    return np.array(out)


@pytest.mark.parametrize("az", [163.0, 203.7, 45.0, 290.0,
                                pytest.param(90.0, marks=pytest.mark.slow)])
def test_is_shadowed_points(az):
    z = fractal_terrain(50, 40, seed=9, relief=300.0)
    # cell centres on the terrain: same as the mask
    rr, cc = np.mgrid[0:50, 0:40]
    centres = np.c_[rr.ravel(), cc.ravel(), z.ravel()]
    got = is_shadowed(z, centres, az, 8.0, (30.0, 25.0)).reshape(z.shape)
    assert np.array_equal(got, shadow_mask(z, az, 8.0, (30.0, 25.0)) == 1)
    # free points above, below and off the raster
    rng = np.random.default_rng(int(az * 10))
    pts = np.c_[rng.uniform(-3, 53, 500), rng.uniform(-3, 43, 500), rng.uniform(-20, 320, 500)]
    got = is_shadowed(z, pts, az, 8.0, (30.0, 25.0))
    exp = _point_reference(z.astype(np.float64), 30.0, 25.0, az, 8.0, pts)
    assert got.any() and not got.all()
    assert np.array_equal(got, exp)


@pytest.mark.slow
def test_geographic_grid_falls_back_with_a_note():
    d = read_dem(data_path("jacksboro_fault_srtm3_mpl_403x344.tif"))
    rays = sun_rays(d.grid, 203.7, 10.0)
    ref = brute.shadow_mask(d.heights, rays)
    stats = {}
    assert np.array_equal(ref, smap.shadow_mask(d.heights, rays, None, stats))
    assert "per row" in stats["note"]
    sw = sweep.shadow_mask(d.heights, rays)
    assert (sw != ref).mean() < 0.002   # measured 0.011 %
    assert np.array_equal(ref, horizon.shadow_mask(d.heights, rays))


@pytest.mark.parametrize("name", ["lidar_dem_1m_utm15n_400x400.tif",
                                  "everest_srtm3_voids_crop200.tif"])
def test_real_dems(name):
    d = read_dem(data_path(name))
    for az, el in ((203.7, 10.0), (77.7, 4.0)):
        rays = sun_rays(d.grid, az, el)
        ref = brute.shadow_mask(d.heights, rays)
        assert np.array_equal(ref, smap.shadow_mask(d.heights, rays))
        assert np.array_equal(ref, horizon.shadow_mask(d.heights, rays))
        valid = (ref != 255).sum()
        wrong = sweep.shadow_mask(d.heights, rays) != ref
        # measured: <= 0.02 % on both (the voids' 0.45 % before void edges were tracked)
        assert wrong.sum() / valid < 0.001
        if wrong.any():
            # the wrong cells are those whose horizon is within 1 degree of the sun, next to the
            # voids too (void-edge terrain within reach leaves a cell to the exact march)
            beta = horizon.horizon_angles(d.heights, rays)
            assert np.abs(beta[wrong] - el).max() < 1.0
