"""algorithms/irradiance.py: the normals once, the incidence on them and one sample added in
place give, bit for bit, what ``relief.incidence`` and the numpy expressions of the irradiance
sums give (voids, geographic rows, per-tile suns, Perez with and without the circumsolar
part)."""

import numpy as np
import pytest

from hillshade_rt.algorithms import irradiance as ka
from hillshade_rt.algorithms import relief
from hillshade_rt.model.geometry import Grid
from hillshade_rt.testing import fractal_terrain


def _terrain(rows=37, cols=53):
    z = fractal_terrain(rows, cols, 7, relief=600.0).astype(np.float32)
    z[4, 5] = z[0, 9] = z[20, 52] = np.nan
    z[30:33, 10:12] = np.nan
    # a geographic-like grid: every row its own spacing, rows growing southward
    dx = np.linspace(24.0, 27.0, rows)
    grid = Grid(rows, cols, dx, np.full(rows, 30.8), 1, -1, "test")
    return z, grid


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint32 if a.dtype == np.float32 else np.uint64)


@pytest.mark.parametrize("azimuth, elevation", [(163.0, 35.0), (203.7, 8.5), (290.0, 61.0),
                                                (0.0, 90.0), (203.7, 0.0)])
def test_incidence_on_the_normals_is_relief_incidence(azimuth, elevation):
    z, grid = _terrain()
    nrm = ka.normals(z, grid)
    got = ka.incidence_of(nrm, *relief.sun_vector(azimuth, elevation))
    want = relief.incidence(z, grid, azimuth, elevation)
    assert np.array_equal(_bits(got), _bits(want))
    assert np.isnan(got[4, 5]) and np.isfinite(got[5, 5])


def _tiles(shape):
    """Three row bands and two column bands, each with its own sun."""
    rows, cols = shape
    row_tile = np.repeat(np.arange(3), [10, 15, rows - 25]).astype(np.int64)
    col_tile = np.repeat(np.arange(2), [20, cols - 20]).astype(np.int64)
    suns = [[(163.0, 35.0), (163.4, 35.2)], [(203.7, 8.5), (204.0, 8.1)],
            [(290.0, 61.0), (289.5, 60.7)]]
    vec = np.array([[relief.sun_vector(*s) for s in row] for row in suns], np.float64)
    want = np.empty(shape, np.float32)
    return row_tile, col_tile, vec, suns, want


def _reference(cos_i, lit, vd, sin_s, share, samples, perez):
    """The sums as the numpy expressions make them."""
    beam, diff = np.zeros(cos_i.shape), np.zeros(cos_i.shape)
    for dni, dhi, w, f1, f2, bz in samples:
        d_k = np.maximum(cos_i, np.float32(0.0)) * lit
        beam += w * (np.float32(dni) * d_k)
        if perez:
            d_t = (1.0 - f1) * vd + f2 * sin_s * share
            if f1 > 0:
                d_t += (f1 / bz) * d_k
            diff += w * np.maximum(dhi * d_t, 0.0)
    return beam, diff


def _kernel(lit, cast, nrm, tiles, vd, sin_s, share, samples, perez):
    """The same sums by ``add_sample``: ``cast`` (uint8) instead of ``lit`` when given;
    ``nrm`` None: ``lit`` is max(cos i, 0) * lit already."""
    shape = vd.shape
    beam, diff = np.zeros(shape), np.zeros(shape)
    none = np.empty((1, 1))
    if nrm is None:
        nrm, tiles = (none, none, none), (np.zeros(shape[0], np.int64), np.zeros(1, np.int64),
                                          np.zeros((1, 1, 3)))
    for dni, dhi, w, f1, f2, bz in samples:
        ka.add_sample(lit if cast is None else np.empty((1, 1), np.float32),
                      np.empty((1, 1), np.uint8) if cast is None else cast, cast is not None,
                      *nrm, *tiles, nrm[0] is not none, True, np.float32(dni), float(w), beam,
                      perez, bool(perez and f1 > 0), float(f1), float(f1 / bz), float(f2), dhi,
                      vd, sin_s, share, diff)
    return beam, diff


@pytest.mark.parametrize("perez", [False, True])
def test_add_sample_is_the_numpy_expression(perez):
    """Two samples added in place equal the numpy loop of the sums (float32 beam product,
    float64 sums, Perez's terms in their order, max(..., 0) keeping NaN), bit for bit: from
    the normals and a float light, from the normals and a hard uint8 mask, and from the
    direct light given whole."""
    z, grid = _terrain()
    shape = z.shape
    nrm = ka.normals(z, grid)
    row_tile, col_tile, vec, suns, cos_i = _tiles(shape)
    for a in range(3):
        for b in range(2):
            rs = slice(*np.flatnonzero(row_tile == a)[[0, -1]] + [0, 1])
            cs = slice(*np.flatnonzero(col_tile == b)[[0, -1]] + [0, 1])
            cos_i[rs, cs] = relief.incidence(z, grid, *suns[a][b], rs, cs)
    rng = np.random.default_rng(3)
    void = np.isnan(z)
    lit = (rng.random(shape) > 0.3).astype(np.float32) * rng.random(shape).astype(np.float32)
    lit[void] = np.nan
    cast = np.where(void, np.uint8(255), (rng.random(shape) > 0.4).astype(np.uint8))
    hard = np.where(void, np.float32(np.nan), (cast == 0).astype(np.float32))
    vd = rng.uniform(0.55, 1.0, shape)
    vd[void] = np.nan
    cos_s = relief.incidence(z, grid, 0.0, 90.0).astype(np.float64)
    sin_s = np.sqrt(np.maximum(1.0 - cos_s * cos_s, 0.0))
    share = np.minimum(vd / ((1.0 + cos_s) / 2.0), 1.0)
    # the weights numpy float64 scalars, as the sums' (a Python float would keep the beam's
    # product float32 in numpy: NEP 50)
    samples = [(812.3, 97.25, np.float64(0.75), np.float64(0.4137), np.float64(-0.0731),
                np.float64(0.61)),
               (0.0, 143.5, np.float64(1.25), np.float64(0.0), np.float64(0.1523),
                np.float64(0.2))]
    common = (vd, sin_s, share, samples, perez)
    tiles = (row_tile, col_tile, vec)
    for got, want in (
            (_kernel(lit, None, nrm, tiles, *common), _reference(cos_i, lit, *common)),
            (_kernel(None, cast, nrm, tiles, *common), _reference(cos_i, hard, *common)),
            (_kernel(np.ascontiguousarray(np.maximum(cos_i, np.float32(0.0)) * lit), None,
                     None, None, *common), _reference(cos_i, lit, *common))):
        for g, w in zip(got, want):
            assert np.array_equal(_bits(g), _bits(w))
        beam, diff = got
        assert np.isnan(beam[4, 5]) and beam[5, 5] >= 0.0
        if perez:
            assert np.isnan(diff[4, 5]) and (diff[np.isfinite(diff)] > 0).any()
