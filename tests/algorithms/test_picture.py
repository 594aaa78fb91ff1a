"""algorithms.picture (the viewer's pictures): the fused kernel against the same picture made
with numpy from relief.incidence, nearest resampling, voids and pixels outside transparent."""

from __future__ import annotations

import numpy as np

from hillshade_rt.algorithms.picture import gradients, rgba
from hillshade_rt.algorithms.relief import incidence, sun_vector
from hillshade_rt.model.geometry import Grid
from hillshade_rt.testing import fractal_terrain


def test_rgba_equals_numpy_from_incidence():
    z = fractal_terrain(60, 70, seed=5).astype(np.float32)
    z[10:14, 20:30] = np.nan
    grid = Grid(60, 70, np.linspace(25.0, 31.0, 60), np.full(60, 30.0), 1, -1, "test")
    az, el = 203.7, 23.0
    ge = np.empty(z.shape, np.float32)
    gn = np.empty_like(ge)
    gradients(z, grid.dx, grid.dy, 1.0, -1.0, 0, 0, ge, gn)
    rng = np.random.default_rng(3)
    mask = rng.choice(np.array([0, 1, 255], np.uint8), z.shape)
    low, high = np.array([1.0, 0.97, 0.88]), np.array([0.30, 0.42, 0.85])
    # pixels: rows 5..44 every 0.5 cell (each row twice), a column outside on each side
    ri = np.repeat(np.arange(5, 45), 2)
    ci = np.concatenate([[-1], np.arange(0, 70), [-1]])
    out = np.empty((len(ri), len(ci), 4), np.uint8)
    rgba(ge, gn, 0, 0, mask, 0, 0, True, ri, ci, *sun_vector(az, el), low, high, out)

    cosi = incidence(z, grid, az, el).astype(np.float64)
    g = 0.25 + 0.75 * np.clip(np.nan_to_num(cosi), 0.0, 1.0)
    v = (mask == 1).astype(np.float64)[..., None]
    want_rgb = np.floor(255.0 * np.clip(g[..., None] * (low * (1 - v) + high * v), 0, 1) + 0.5)
    cells = np.ix_(ri, ci[1:-1])
    got = out[:, 1:-1]
    valid = ~np.isnan(z)[cells]
    # float32 gradients against relief's float64 arithmetic: at most one step of 255
    assert np.abs(got[..., :3].astype(int) - want_rgb[cells].astype(int))[valid].max() <= 1
    assert (got[..., 3][valid] == 255).all() and (got[~valid] == 0).all()
    assert (out[:, [0, -1]] == 0).all()
    # shadow pixels are bluer than red, lit ones redder
    s = got[..., 2].astype(int) > got[..., 0].astype(int)
    assert np.array_equal(s[valid], (mask[cells] == 1)[valid])


def test_rgba_with_offsets_and_a_float_value():
    z = fractal_terrain(30, 30, seed=2).astype(np.float32)
    grid = Grid.uniform(30, 30, 10.0)
    ge = np.empty((10, 12), np.float32)
    gn = np.empty_like(ge)
    gradients(z, grid.dx, grid.dy, 1.0, -1.0, 8, 5, ge, gn)     # the window's own gradients
    full_e = np.empty(z.shape, np.float32)
    full_n = np.empty_like(full_e)
    gradients(z, grid.dx, grid.dy, 1.0, -1.0, 0, 0, full_e, full_n)
    assert np.array_equal(ge, full_e[8:18, 5:17]) and np.array_equal(gn, full_n[8:18, 5:17])
    value = np.linspace(0.0, 1.0, 100, dtype=np.float32).reshape(10, 10)
    value[0, 0] = np.nan
    ri, ci = np.arange(9, 17), np.arange(6, 16)
    a = np.empty((8, 10, 4), np.uint8)
    b = np.empty_like(a)
    low, high = np.array([0.2, 0.2, 0.1]), np.array([1.0, 0.86, 0.45])
    sun = sun_vector(163.0, 30.0)
    rgba(ge, gn, 8, 5, value, 8, 6, False, ri, ci, *sun, low, high, a)
    rgba(full_e, full_n, 0, 0, value, 8, 6, False, ri, ci, *sun, low, high, b)
    assert np.array_equal(a, b) and (a[..., 3] == 255).all()
