"""Dynamic terrain: ``Shader.update`` and ``render(..., previous=...)`` (issue 22, item 3).

The check: after random edits (windows anywhere, of any size, raised, lowered, voided), the
product brought up to date from the previous one equals the product of a new Shader of the
edited DEM, for every algorithm of the registry, at non-special suns; the re-render makes fewer
cells than the raster for a small edit (a counter, not a timing); the pyramid patched equals a
new build; the GPU's copy (``GpuDem.update``, under the CUDA simulator) equals a new upload.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from hillshade_rt.algorithms import REGISTRY
from hillshade_rt.algorithms.brute import march_box, shadow_mask
from hillshade_rt.algorithms.pyramid import MaxPyramid
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.engine.shader import Shader, render
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import fractal_terrain


def _build(z):
    """A new pyramid of ``z``'s heights: (data, offsets, widths, levels)."""
    return MaxPyramid(z.copy()).args

AZIMUTHS = (163.0, 203.7, 290.0)
ELEVATIONS = (4.0, 12.0, 35.0)
ROWS, COLS = 40, 46
# every algorithm of the registry, and the approximate options (a full render of their own)
METHODS = [(name, {}) for name in REGISTRY] + [
    ("brute", {"pyramid": False}), ("horizon", {"method": "hull"}),
    ("horizon", {"sample_spacing": 2}), ("smap", {"nextv": "quad"})]
KINDS = [("shadow", {}), ("shadow", {"self_shadow": True}), ("classes", {}),
         ("hillshade", {}), ("sun", {}), ("shadow", {"soft": True})]


def _terrain(seed=3):
    z = fractal_terrain(ROWS, COLS, seed, relief=120.0, octaves=4)
    z[10:12, 30:33] = np.nan
    return z


def _grid(geographic: bool) -> Grid:
    if not geographic:
        return Grid.uniform(ROWS, COLS, 10.0)
    lat = np.linspace(61.0, 60.6, ROWS)
    return Grid(ROWS, COLS, 30.0 * np.cos(np.radians(lat)) / np.cos(np.radians(60.8)),
                np.full(ROWS, 30.0), 1, -1, "test")


def _scratch(z, grid, name, options, kind, extra, sun, curvature):
    sh = Shader(z.copy(), grid, name, options, "cpu", curvature)
    return render(sh, sun, kind, **extra)


edit = st.tuples(st.integers(0, ROWS - 1), st.integers(0, COLS - 1), st.integers(1, 12),
                 st.integers(1, 12), st.sampled_from(("raise", "lower", "void", "flat", "mix")),
                 st.floats(5.0, 150.0))


def _heights(z, r0, c0, h, w, how, dh, rng):
    old = z[r0:r0 + h, c0:c0 + w]
    if how == "raise":
        return old + np.float32(dh)
    if how == "lower":
        return old - np.float32(dh)
    if how == "void":
        new = old.copy()
        new[rng.random(new.shape) < 0.5] = np.nan
        return new
    if how == "flat":
        return np.full(old.shape, np.float32(np.nanmax(z) + dh))   # a new highest block
    return (old + rng.normal(0, dh, old.shape)).astype(np.float32)


@settings(max_examples=30, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(edits=st.lists(edit, min_size=1, max_size=3), method=st.sampled_from(METHODS),
       product=st.sampled_from(KINDS), az=st.sampled_from(AZIMUTHS),
       el=st.sampled_from(ELEVATIONS), geographic=st.booleans(),
       curvature=st.sampled_from((False, True, "auto")), between=st.booleans())
def test_update_and_rerender_equal_a_new_shader(edits, method, product, az, el, geographic,
                                                curvature, between):
    name, options = method
    kind, extra = product
    rng = np.random.default_rng(len(edits))
    z = _terrain()
    grid = _grid(geographic)
    sun = SunOver(None, az, el)
    sh = Shader(z, grid, name, options, "cpu", curvature)
    prev, since = render(sh, sun, kind, **extra), sh.version
    for k, (r0, c0, h, w, how, dh) in enumerate(edits):
        h, w = min(h, ROWS - r0), min(w, COLS - c0)
        sh.update((r0, c0), _heights(sh.z, r0, c0, h, w, how, dh, rng))
        if between and k == 0 and len(edits) > 1:   # a render in between: the next from it
            prev = render(sh, sun, kind, previous=(prev, since), **extra)
            since = sh.version
    stats = {}
    got = render(sh, sun, kind, previous=(prev, since), stats=stats, **extra)
    want = _scratch(sh.z, grid, name, options, kind, extra, sun, curvature)
    np.testing.assert_array_equal(got, want)
    assert sh.zmin == float(np.nanmin(sh.z)) and sh.zmax == float(np.nanmax(sh.z))
    exact = REGISTRY[name].exact and not set(options) & {"method", "sample_spacing"}
    if exact or extra.get("soft"):
        assert stats["rerendered_cells"] > 0 and "rerender_full" not in stats
    else:   # an approximate method: its own full render
        assert stats["rerender_full"] == 1 and "rerendered_cells" not in stats


@pytest.mark.parametrize("az", AZIMUTHS)
def test_a_lifted_observer_after_an_edit_equals_a_new_shader(az):
    z = _terrain(7)
    grid = _grid(True)
    sun = SunOver(None, az, 9.0)
    sh = Shader(z, grid, "auto", {}, "cpu", True, lift=2.5)
    prev = render(sh, sun, "classes")
    sh.update((14, 9), np.full((5, 4), float(np.nanmax(z)) + 10.0, np.float32))
    want = render(Shader(sh.z.copy(), grid, "auto", {}, "cpu", True, lift=2.5), sun, "classes")
    np.testing.assert_array_equal(render(sh, sun, "classes", previous=(prev, 0)), want)


@pytest.mark.parametrize("az", AZIMUTHS)
def test_a_small_edit_remakes_few_cells_and_a_tall_one_its_shadow(az):
    z = fractal_terrain(120, 130, 9, relief=40.0)
    sh = Shader(z, Grid.uniform(120, 130, 10.0), "auto", {}, "cpu", False)
    sun = SunOver(None, az, 20.0)
    before = render(sh, sun)
    hill = float(np.nanmax(z)) + 60.0
    sh.update((55, 60), np.full((6, 6), hill, np.float32))
    stats = {}
    after = render(sh, sun, previous=(before, 0), stats=stats)
    assert 36 <= stats["rerendered_cells"] < z.size / 4
    # the tower casts a shadow away from the sun that was not there
    assert (after != before).sum() > 20
    np.testing.assert_array_equal(after, render(Shader(sh.z.copy(), sh.grid, "brute", {}, "cpu",
                                                       False), sun))
    # nothing edited since: a copy of the previous one, no cell made
    stats = {}
    again = render(sh, sun, previous=(after, sh.version), stats=stats)
    assert again is not after and np.array_equal(again, after)
    assert stats["rerendered_cells"] == 0


def test_lowering_the_highest_cell_and_voiding_everywhere_keep_the_range_exact():
    z = _terrain()
    sh = Shader(z, Grid.uniform(ROWS, COLS, 10.0), "auto", {}, "cpu", False)
    r, c = np.unravel_index(np.nanargmax(z), z.shape)
    sh.update((r, c), np.array([[float(np.nanmin(z)) + 1.0]], np.float32))
    assert sh.zmax == float(np.nanmax(z)) and sh.local_range == (sh.zmin, sh.zmax)
    r, c = np.unravel_index(np.nanargmin(z), z.shape)
    sh.update((r, c), np.array([[np.nan]], np.float32))
    assert sh.zmin == float(np.nanmin(z))
    sun = SunOver(None, 203.7, 12.0)
    sh.choose(sh.z, True, sun_rays(sh.grid, 203.7, 12.0))        # survey taken
    sh.update((0, 0), np.full((3, 3), np.nan, np.float32))
    valid = np.isfinite(z).sum() / z.size
    assert sh._survey == (valid, float(np.nanmin(z)), float(np.nanmax(z)))


@pytest.mark.parametrize("shape", [(37, 45), (64, 64), (5, 130)])
def test_the_patched_pyramid_equals_a_new_build(shape):
    rng = np.random.default_rng(shape[0])
    z = (rng.random(shape) * 100).astype(np.float32)
    z[rng.random(shape) < 0.05] = np.nan
    p = MaxPyramid(z)
    p.args
    for _ in range(12):
        r0, c0 = rng.integers(0, shape[0]), rng.integers(0, shape[1])
        r1, c1 = min(shape[0], r0 + rng.integers(1, 9)), min(shape[1], c0 + rng.integers(1, 9))
        z[r0:r1, c0:c1] = np.where(rng.random((r1 - r0, c1 - c0)) < 0.2, np.nan,
                                   rng.random((r1 - r0, c1 - c0)) * 150 - 20).astype(np.float32)
        ranges = p.update(z, (r0, r1, c0, c1))
        new = _build(z)
        np.testing.assert_array_equal(p.args[0], new[0])
        assert ranges[1:, 1].max() <= new[0].size and (ranges[1:, 1] > ranges[1:, 0]).all()
    # not built yet: built later from the edited heights
    q = MaxPyramid(z.copy())
    assert q.update(z, (0, 1, 0, 1)) is None
    np.testing.assert_array_equal(q.args[0], _build(z)[0])


def test_march_box_is_brute_of_those_cells():
    z = _terrain()
    rays = sun_rays(_grid(True), 290.0, 6.0)
    whole = shadow_mask(z, rays)
    for pyr in (True, False, MaxPyramid(z)):
        np.testing.assert_array_equal(march_box(z, rays, (5, 23, 17, 40), float(np.nanmax(z)),
                                                pyr), whole[5:23, 17:40])
    assert march_box(z, rays, (5, 5, 0, 3), 0.0).shape == (0, 3)
    from hillshade_rt.algorithms import brute     # the parallel loop of larger boxes
    big = np.tile(z, (4, 4))
    rays = sun_rays(Grid.uniform(*big.shape, 10.0), 163.0, 9.0)
    assert brute.BOX_SERIAL_CELLS < 150 * 170
    np.testing.assert_array_equal(march_box(big, rays, (3, 153, 2, 172), float(np.nanmax(big))),
                                  shadow_mask(big, rays)[3:153, 2:172])


def test_what_cannot_be_updated_says_so():
    z = _terrain()
    sh = Shader(z, Grid.uniform(ROWS, COLS, 10.0), "auto", {}, "cpu", False)
    with pytest.raises(HillshadeError, match="do not fit"):
        sh.update((ROWS - 2, 0), np.zeros((3, 3), np.float32))
    with pytest.raises(HillshadeError, match="2-D"):
        sh.update((0, 0), np.zeros(3, np.float32))
    with pytest.raises(HillshadeError, match="top-left"):
        sh.update(5, np.zeros((3, 3), np.float32))
    from types import SimpleNamespace
    with pytest.raises(HillshadeError, match="window is 2 x 3"):
        sh.update(SimpleNamespace(row_off=0, col_off=0, height=2, width=3),
                  np.zeros((3, 3), np.float32))
    assert sh.update(SimpleNamespace(row_off=1, col_off=2, height=3, width=3),
                     np.ones((3, 3), np.float32)) == 1 and (z[1:4, 2:5] == 1).all()
    sun = SunOver(None, 163.0, 20.0)
    with pytest.raises(HillshadeError, match="version 2"):
        render(sh, sun, previous=(np.zeros(z.shape, np.uint8), 2))
    with pytest.raises(HillshadeError, match="shape"):
        render(sh, sun, previous=(np.zeros((3, 3), np.uint8), 0))
    window = Shader(z, Grid.uniform(ROWS, COLS, 10.0), "auto", {}, "cpu", False,
                    halo_ready=True)
    with pytest.raises(HillshadeError, match="window of a larger raster"):
        window.update((0, 0), np.zeros((1, 1), np.float32))


def test_a_sun_at_night_or_per_tile_renders_in_full():
    z = _terrain()
    sh = Shader(z, Grid.uniform(ROWS, COLS, 10.0), "auto", {}, "cpu", False)
    night = SunOver(None, 203.7, -3.0)
    prev = render(sh, night)
    sh.update((3, 4), np.full((2, 2), np.nan, np.float32))
    stats = {}
    got = render(sh, night, previous=(prev, 0), stats=stats)
    assert stats == {"rerender_full": 1} and (got[3:5, 4:6] == 255).all()


# -- the GPU (numba's CUDA simulator unless NUMBA_ENABLE_CUDASIM=0) ---------------------------

@pytest.mark.slow
def test_gpudem_update_uploads_only_the_window_and_matches_a_new_upload():
    from hillshade_rt.engine import gpu
    from hillshade_rt.algorithms import frames
    z = fractal_terrain(13, 17, 4, relief=80.0)
    g = gpu.GpuDem(z)
    rays = sun_rays(Grid.uniform(13, 17, 10.0), 203.7, 10.0)
    g.shadow_mask(rays, "brute")                   # the pyramid on the device
    frame = frames.frame_of(rays)
    g.canonical(frame)                             # and a canonical copy
    before = g.stats["h2d_bytes"]
    new = np.full((3, 4), float(np.nanmax(z)) + 30.0, np.float32)
    new[1, 1] = np.nan
    g.update(5, 6, new)
    assert (z[5:8, 6:10] == new)[np.isfinite(new)].all()
    np.testing.assert_array_equal(g.z.copy_to_host(), z)
    levels = g.stats["h2d_bytes"] - before - new.nbytes
    assert 0 < levels < _build(z)[0].nbytes          # some pyramid rows, not all of it
    np.testing.assert_array_equal(g._pyramid[0].copy_to_host(), _build(z)[0])
    assert (g.zmax, g.void) == (float(np.nanmax(z)), True)
    np.testing.assert_array_equal(g.canonical(frame).copy_to_host(), frame.view(z))
    for name in ("brute", "smap", "horizon", "sweep"):
        np.testing.assert_array_equal(g.shadow_mask(rays, name),
                                      gpu.GpuDem(z.copy()).shadow_mask(rays, name))
    with pytest.raises(HillshadeError, match="not inside"):
        g.update(12, 0, new)


@pytest.mark.parametrize("name", ["auto", pytest.param("smap", marks=pytest.mark.slow)])
def test_a_gpu_shader_updates_and_rerenders_like_a_new_cpu_shader(name):
    z = fractal_terrain(14, 18, 6, relief=90.0)
    grid = Grid.uniform(14, 18, 10.0)
    sh = Shader(z, grid, name, {}, "gpu", False)
    sun = SunOver(None, 290.0, 12.0)
    prev = render(sh, sun)
    sh.update((4, 8), np.full((2, 3), float(np.nanmax(z)) + 20.0, np.float32))
    stats = {}
    got = render(sh, sun, previous=(prev, 0), stats=stats)
    want = render(Shader(sh.z.copy(), grid, name, {}, "cpu", False), sun)
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(render(sh, sun), want)      # a full render on the device
    assert 0 < stats["rerendered_cells"] < z.size
