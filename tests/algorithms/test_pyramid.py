"""The exact fast methods of issue 18: the pyramid march, the bounds sweep, ``auto``.

Each must give the plain march's mask cell for cell (brute with ``pyramid=False``, itself checked
against the plain-Python model in test_brute): random terrains of every kind (noise, power-law
spectral fractals, plateaus with flat tops, voids), uniform and per-row spacing (geographic),
curvature on and off, any azimuth and elevation, drawn by hypothesis; plus fixed real DEMs at
non-special azimuths, and the plain-Python reference itself on small grids.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from hillshade_rt import read_dem
from hillshade_rt.algorithms import auto, bounds, brute, smap
from hillshade_rt.algorithms.frames import uniform_rays
from hillshade_rt.algorithms.pyramid import MaxPyramid, _levels
from hillshade_rt.model.geometry import Grid, curvature_per_m2, sun_rays
from hillshade_rt.testing import data_path, reference_mask, spectral, repo_root

SETTINGS = settings(max_examples=int(os.environ.get("HILLSHADE_PYRAMID_EXAMPLES", "400")),
                    deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _terrain(kind: str, rows: int, cols: int, seed: int, relief: float) -> np.ndarray:
    rng = np.random.default_rng(seed)
    if kind == "noise":
        z = rng.random((rows, cols)) * relief
    elif kind == "spectral":
        n = max(rows, cols)
        z = spectral(n, float(rng.choice([2.0, 2.4, 3.2])), seed=seed,
                     relief=relief)[:rows, :cols]
    elif kind == "plateaus":   # flat tops and cliffs: ties between the ray and the terrain
        z = np.round(rng.random((rows, cols)) * 4) * (relief / 4)
    else:                      # steps of integer heights on integer spacing: exact ties
        z = np.floor(np.add.outer(np.arange(rows), np.arange(cols)) * 0.5 % 7)
    return np.ascontiguousarray(z, dtype=np.float32)


@st.composite
def cases(draw):
    rows = draw(st.integers(2, 70))
    cols = draw(st.integers(2, 70))
    kind = draw(st.sampled_from(["noise", "spectral", "plateaus", "ties"]))
    seed = draw(st.integers(0, 10_000))
    relief = draw(st.sampled_from([1.0, 50.0, 800.0, 5000.0]))
    z = _terrain(kind, rows, cols, seed, relief)
    if draw(st.booleans()):      # voids
        rng = np.random.default_rng(seed + 1)
        z[rng.random(z.shape) < draw(st.sampled_from([0.02, 0.2, 0.6]))] = np.nan
    dx = draw(st.sampled_from([1.0, 30.0, 92.6]))
    dy = draw(st.sampled_from([1.0, 30.0, 92.6]))
    if draw(st.booleans()):      # per-row spacing (geographic)
        lat0 = draw(st.floats(-80, 80))
        lat = lat0 + np.linspace(0, draw(st.sampled_from([0.5, 5.0, 20.0])), rows)
        grid = Grid(rows, cols, dx * np.cos(np.radians(np.clip(lat, -89, 89))),
                    np.full(rows, dy), 1, -1, "per row")
    else:
        grid = Grid.uniform(rows, cols, dx, dy)
    az = draw(st.one_of(st.sampled_from([0.0, 45.0, 90.0, 163.0, 203.7, 290.0, 315.0]),
                        st.floats(0, 360, exclude_max=True)))
    el = draw(st.one_of(st.sampled_from([0.5, 3.0, 8.0, 20.0, 60.0, 89.9]),
                        st.floats(0.05, 89.0)))
    curv = curvature_per_m2(draw(st.sampled_from([6.371e6, 1.7374e6, 2e4])), 0.13) \
        if draw(st.booleans()) else 0.0
    return z, grid, az, el, curv


def _plain(z, rays):
    return brute.shadow_mask(z, rays, pyramid=False)


@pytest.mark.slow
@SETTINGS
@given(cases())
def test_pyramid_bounds_auto_equal_the_plain_march(case):
    z, grid, az, el, curv = case
    if not np.isfinite(z).any():
        return
    rays = sun_rays(grid, az, el, curv)
    ref = _plain(z, rays)
    np.testing.assert_array_equal(brute.shadow_mask(z, rays), ref, "pyramid march")
    st_b = {}
    np.testing.assert_array_equal(bounds.shadow_mask(z, rays, stats=st_b), ref, "bounds")
    assert 0.0 <= st_b["undecided_fraction"] <= 1.0
    np.testing.assert_array_equal(auto.shadow_mask(z, rays), ref, "auto")
    if uniform_rays(rays):   # smap's jump loop over the pyramid (it takes straight rays)
        flat = sun_rays(grid, az, el)
        ref_flat = ref if curv == 0.0 else _plain(z, flat)
        for pyr in (True, False):
            np.testing.assert_array_equal(smap.shadow_mask(z, flat, pyramid=pyr), ref_flat,
                                          f"smap, pyramid {pyr}")


@pytest.mark.slow
@SETTINGS
@given(cases(), st.integers(2, 4))
def test_bounds_in_narrow_strips_equal_the_plain_march(case, nstrips):
    """The wavefront cut into several strips of as few as 12 positions (the raster's own
    strips are at least 64 wide and these grids at most 70): each strip also bounds the segment
    before it, where a cell's lookup can land, so no strip reads lines the strip behind it has
    not reached (it did: 7 cells of a column at a strip's edge differed from the plain march)."""
    z, grid, az, el, curv = case
    if not np.isfinite(z).any():
        return
    rays = sun_rays(grid, az, el, curv)
    real = bounds.strip_count
    try:
        bounds.strip_count = lambda P, s, K: max(1, min(nstrips, P // max(12, int(np.ceil(K * s)) + 8)))
        np.testing.assert_array_equal(bounds.shadow_mask(z, rays), _plain(z, rays))
    finally:
        bounds.strip_count = real


@pytest.mark.parametrize("az", [163.0, 203.7, 290.0, 20.0])
@pytest.mark.parametrize("el", [3.0, 20.0])
def test_against_the_plain_python_model(az, el):
    """The independent plain-Python reference, not our own plain march."""
    z = _terrain("spectral", 40, 52, 11, 300.0)
    z[5:8, 30:33] = np.nan
    ref = reference_mask(z, 30.0, 30.0, az, el)
    rays = sun_rays(Grid.uniform(40, 52, 30.0), az, el)
    np.testing.assert_array_equal(brute.shadow_mask(z, rays), ref)
    np.testing.assert_array_equal(bounds.shadow_mask(z, rays), ref)


@pytest.mark.parametrize("name", ["bigtujunga_srtm30m_utm11n_1197x643.tif",
                                  "jacksboro_fault_srtm3_mpl_403x344.tif"])
@pytest.mark.parametrize("az,el", [(163.0, 3.0), (203.7, 8.0), (290.0, 20.0)])
@pytest.mark.parametrize("curved", [False, True])
def test_real_dems(name, az, el, curved):
    path = data_path(name) if os.path.exists(data_path(name)) else os.path.join(
        repo_root(), "examples", name)
    d = read_dem(path)
    z = np.ascontiguousarray(d.heights[:300, :400])
    grid = Grid(z.shape[0], z.shape[1], d.grid.dx[:300].copy(), d.grid.dy[:300].copy(),
                d.grid.col_sign, d.grid.row_sign, d.grid.method)
    rays = sun_rays(grid, az, el, curvature_per_m2(6.371e6, 0.13) if curved else 0.0)
    ref = _plain(z, rays)
    np.testing.assert_array_equal(brute.shadow_mask(z, rays), ref)
    st_b = {}
    np.testing.assert_array_equal(bounds.shadow_mask(z, rays, stats=st_b), ref)
    # the bounds decide most cells on real terrain: only a few are left to the march
    assert st_b["undecided_fraction"] < 0.35


@pytest.mark.parametrize("lat0,span", [(27.5, 1.0), (62.0, 8.0), (-75.0, 10.0)])
@pytest.mark.parametrize("az", [163.0, 203.7, 290.0])
def test_bounds_on_per_row_grids_carry_blocks_exactly(lat0, span, az):
    """Per-row spacing: the bounds are carried bin to bin in blocks of lines and widen only at
    a block's end (``bounds._blocks``). Rough terrain high enough for long rays, spacings from a
    1-degree SRTM tile to polar rows (blocks of a few lines): the mask is the plain march's,
    and the bounds leave about as few cells undecided as on one spacing (they left 5-10 times
    as many when they widened by a bin per line)."""
    rows, cols = 240, 200
    z = _terrain("spectral", rows, cols, 11, 3000.0)
    z[50:53, 60:70] = np.nan
    lat = lat0 + np.linspace(0.0, span, rows)
    dx = 92.6 * np.cos(np.radians(lat))
    grid = Grid(rows, cols, dx, np.full(rows, 92.6), 1, -1, "per row")
    uni = Grid.uniform(rows, cols, float(dx[rows // 2]), 92.6)
    for el in (3.0, 8.0):
        rays = sun_rays(grid, az, el)
        s = np.abs(rays.step_other)
        M, W_end = bounds._blocks(float(s.max() - s.min()))
        assert (M > 1 and W_end == 2) if span <= 1.0 else M >= 1
        st_g, st_u = {}, {}
        np.testing.assert_array_equal(bounds.shadow_mask(z, rays, stats=st_g), _plain(z, rays))
        bounds.shadow_mask(z, sun_rays(uni, az, el), stats=st_u)
        if span <= 1.0:
            assert st_g["undecided_fraction"] <= 2.0 * st_u["undecided_fraction"] + 0.002


def test_pyramid_is_a_bound_of_every_block():
    z = _terrain("noise", 37, 53, 3, 100.0)
    z[3, 4] = np.nan
    p = MaxPyramid(z)
    data, off, widths, nlev = p.args
    assert nlev == _levels(37, 53)
    for lev in range(1, nlev + 1):
        size = 1 << lev
        nr = (37 - 1) // size + 1
        for i in range(nr):
            for j in range(widths[lev]):
                block = z[i * size:(i + 1) * size + 1, j * size:(j + 1) * size + 1]
                top = np.nanmax(block) if np.isfinite(block).any() else -np.inf
                v = data[off[lev] + i * widths[lev] + j]
                assert v >= top and (not np.isfinite(top) or v == np.nextafter(
                    np.float32(top), np.float32(np.inf)))


def test_pyramid_is_reused_and_shape_checked():
    z = _terrain("noise", 20, 20, 1, 10.0)
    p = MaxPyramid(z)
    rays = sun_rays(Grid.uniform(20, 20, 1.0), 203.7, 10.0)
    np.testing.assert_array_equal(brute.shadow_mask(z, rays, pyramid=p), _plain(z, rays))
    other = _terrain("noise", 20, 21, 2, 10.0)   # a pyramid of another shape is not used
    rays2 = sun_rays(Grid.uniform(20, 21, 1.0), 203.7, 10.0)
    np.testing.assert_array_equal(brute.shadow_mask(other, rays2, pyramid=p),
                                  _plain(other, rays2))


@pytest.mark.slow
def test_read_only_heights():
    z = _terrain("spectral", 50, 60, 9, 400.0)
    z.setflags(write=False)
    rays = sun_rays(Grid.uniform(50, 60, 30.0), 290.0, 5.0)
    ref = _plain(z, rays)
    np.testing.assert_array_equal(bounds.shadow_mask(z, rays), ref)
    np.testing.assert_array_equal(brute.shadow_mask(z, rays), ref)


@pytest.mark.slow
def test_degenerate_shapes_and_suns():
    for shape in [(1, 1), (1, 9), (9, 1), (2, 2)]:
        z = _terrain("noise", *shape, 4, 10.0)
        for az in (0.0, 163.0, 290.0):
            for el in (0.5, 45.0, 90.0):
                rays = sun_rays(Grid.uniform(*shape, 1.0), az, el)
                ref = _plain(z, rays)
                np.testing.assert_array_equal(bounds.shadow_mask(z, rays), ref)
                np.testing.assert_array_equal(brute.shadow_mask(z, rays), ref)
    z = np.full((5, 5), np.nan, np.float32)
    rays = sun_rays(Grid.uniform(5, 5, 1.0), 163.0, 5.0)
    assert (bounds.shadow_mask(z, rays) == 255).all()
    assert (auto.shadow_mask(z, rays) == 255).all()
    assert math.isfinite(float(rays.rise[0]))


@pytest.mark.slow
def test_code_counts_equal_bincount():
    from hillshade_rt.algorithms.counts import code_counts
    rng = np.random.default_rng(8)
    for shape in [(1, 1), (3, 5000), (70, 130), (200, 3)]:
        a = rng.choice(np.array([0, 1, 2, 255], np.uint8), size=shape)
        np.testing.assert_array_equal(code_counts(a), np.bincount(a.ravel(), minlength=256))
    v = np.arange(256, dtype=np.uint8)[None, :].repeat(80, 0)[:, ::2]   # a strided view
    np.testing.assert_array_equal(code_counts(v), np.bincount(v.ravel(), minlength=256))


def test_time_based_sun_uses_the_per_cell_field():
    """A time-based sun over a large DEM: the engine marches every cell with its own sun in one
    pass (no tiles), and the mask agrees with the per-tile one but where the two approximations
    of the sun differ (cells at the edge of a shadow)."""
    from hillshade_rt.engine.shader import Shader, render
    from hillshade_rt.model.site import Site
    from hillshade_rt.model.sun import sun_over
    from hillshade_rt.model.times import parse_time
    from pyproj import CRS, Transformer
    z = _terrain("spectral", 300, 400, 12, 2500.0)
    grid = Grid.uniform(300, 400, 150.0)   # 60 km across
    crs = CRS.from_epsg(32633)
    tr = Transformer.from_crs(crs, crs.geodetic_crs, always_xy=True)

    def to_lonlat(r, c):
        return tr.transform(500000.0 + 150.0 * (np.asarray(c) + 0.5),
                            5200000.0 - 150.0 * (np.asarray(r) + 0.5))
    site = Site(lat=47.0, lon=15.0, height=500.0, source="test", to_lonlat=to_lonlat,
                convergence=lambda r, c: np.zeros(np.shape(r)))
    [sun] = sun_over(site, z.shape, [parse_time("2026-06-21T06:10+02:00")], tolerance=0.05)
    assert sun.tiles and sun.lattice is not None and sun.field_deviation_deg < 0.01
    st = {}
    sh = Shader(z, grid, "auto", {}, "cpu", False)          # the default: a sun per cell
    got = render(sh, sun, "shadow", stats=st)
    assert st["sun_field"] == 1 and sum(st["auto"]["chose"].values()) == 1  # one march, no tiles
    tiles = render(Shader(z, grid, "smap", {}, "cpu", False), sun, "shadow")
    assert np.count_nonzero(got != tiles) < 0.02 * z.size
    # brute with the field gives the same mask as auto (bounds) with it
    np.testing.assert_array_equal(render(Shader(z, grid, "brute", {}, "cpu", False,
                                                sun_field=True), sun, "shadow"), got)
    st = {}   # sun_field=False: tiles
    render(Shader(z, grid, "auto", {}, "cpu", False, sun_field=False), sun, "shadow", stats=st)
    assert "sun_field" not in st and sum(st["auto"]["chose"].values()) == len(sun.tiles)


def _lattice(az0, el0, daz, del_, n=9):
    """A 9 x 9 lattice of suns varying by ``daz`` in azimuth and ``del_`` in elevation."""
    from hillshade_rt.algorithms.per_cell_sun import lattice_vectors
    i, j = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n), indexing="ij")
    return lattice_vectors(az0 + daz * j + 0.3 * daz * i * j, el0 + del_ * i)


@pytest.mark.parametrize("az0,el0,daz", [(163.0, 3.0, 4.0), (203.7, 8.0, 0.4), (290.0, 1.0, 2.0),
                                         (44.0, 0.3, 1.0), (89.0, 5.0, 3.0)])
@pytest.mark.parametrize("curved", [False, True])
def test_bounds_with_a_per_cell_sun_equal_the_field_march(az0, el0, daz, curved):
    from hillshade_rt.algorithms import per_cell_sun
    for seed, shape in [(4, (23, 31)), (9, (60, 45))]:
        z = _terrain("spectral", *shape, seed, 600.0)
        z[4:6, 7:9] = np.nan
        lat = np.linspace(45, 47, shape[0])
        grid = Grid(*shape, 30.0 * np.cos(np.radians(lat)) / np.cos(np.radians(45)),
                    np.full(shape[0], 30.0), 1, -1, "per row")
        vec = _lattice(az0, el0, daz, 0.5 * daz)
        c = curvature_per_m2(2e4, 0.13) if curved else 0.0
        ref = per_cell_sun.shadow_mask(z, grid, vec, c, pyramid=False)
        st_ = {}
        np.testing.assert_array_equal(bounds.shadow_mask_field(z, grid, vec, c, stats=st_), ref)
        assert 0 <= st_["undecided_fraction"] <= 1


@pytest.mark.slow
@SETTINGS
@given(cases())
def test_horizon_scan_over_the_pyramid_is_the_plain_scan(case):
    """The horizon angles over the pyramid equal the plain scan's bit for bit (the same samples
    raise the maximum), and with a floor and a cap (soft shadows) they give the same visible
    fraction of the sun's disk."""
    from hillshade_rt.algorithms import horizon
    from hillshade_rt.model.solar import SUN_RADIUS_DEG, disk_fraction
    z, grid, az, el, curv = case
    if not np.isfinite(z).any():
        return
    rays = sun_rays(grid, az, el, curv)
    plain = horizon.horizon_angles(z, rays, pyramid=False)
    np.testing.assert_array_equal(horizon.horizon_angles(z, rays), plain)
    lo, hi = el - SUN_RADIUS_DEG, el + SUN_RADIUS_DEG
    clipped = horizon.horizon_angles(z, rays, floor_deg=lo, cap_deg=hi)
    ok = np.isfinite(plain)
    np.testing.assert_array_equal(disk_fraction(clipped[ok], el), disk_fraction(plain[ok], el))
    np.testing.assert_array_equal(horizon.shadow_mask(z, rays), _plain(z, rays))
