"""What the bounds sweep adds for every cell's own sun: the potential fitted to the cells' rays
takes their variation out (one straight ray left), and the heights lessened by it in the ring.
(The masks, equal to the per-cell sun's exact march: tests/algorithms/test_pyramid.py.)"""

import numpy as np
import pytest

from hillshade_rt.algorithms.bounds_per_cell_sun import field_fit, less_potential


def _sample(L, P, s, r0, a, b, c0, step=7):
    v, p = np.meshgrid(np.arange(0, L, step, dtype=float), np.arange(0, P, step, dtype=float),
                       indexing="ij")
    v, p = v.ravel(), p.ravel()
    s = np.broadcast_to(np.asarray(s, float), v.shape)
    return np.stack([v, p, s, r0 + a * v + b * p, np.full(v.shape, c0)], axis=1)


@pytest.mark.parametrize("a, b", [(2e-6, -3e-7), (-1.5e-6, 4e-7), (0.0, 0.0)])
def test_the_fit_leaves_one_straight_ray(a, b):
    """Rays whose rise grows linearly across the raster (as a time-based sun's does toward the
    sun): over the heights less Phi = A v^2 + B v p every ray rises the same per step; A and B
    as the fit's derivation says, the ranges padded around the one value left."""
    L, P, s0, r0, c0 = 400, 300, 0.37, 0.0863, -1e-7
    A, B, s_rng, r_rng, c_rng, phi_rng = field_fit(_sample(L, P, s0, r0, a, b, c0), L, P)
    assert B == pytest.approx(b, abs=1e-15)
    assert A == pytest.approx(0.5 * (a - s0 * b), abs=1e-15)
    q = A + s0 * B
    assert r_rng[0] <= r0 <= r_rng[1] and r_rng[1] - r_rng[0] < 1e-9
    assert c_rng[0] <= c0 - q <= c_rng[1] and c_rng[1] - c_rng[0] < 1e-9
    assert s_rng[0] <= s0 <= s_rng[1] and s_rng[0] >= 0.0
    # Phi's extremes over the raster: linear in p, so on the edges p = 0 and P - 1, there at a
    # corner or where dPhi/dv = 0 (sampled finely along v here)
    vv, pp = np.meshgrid(np.linspace(0.0, L - 1.0, 100_001), [0.0, P - 1.0], indexing="ij")
    phi = A * vv * vv + B * vv * pp
    assert phi_rng[0] == pytest.approx(phi.min(), abs=1e-10)
    assert phi_rng[1] == pytest.approx(phi.max(), abs=1e-10)


def test_steps_that_vary_widen_the_ranges_they_span():
    rng = np.random.default_rng(3)
    L, P = 200, 150
    sample = _sample(L, P, 0.0, 0.05, 1e-6, 2e-7, 0.0)
    sample[:, 2] = rng.uniform(0.2, 0.6, len(sample))
    A, B, s_rng, r_rng, c_rng, _ = field_fit(sample, L, P)
    s, rise, curv = sample[:, 2], sample[:, 3], sample[:, 4]
    q = A + s * B
    rp, cp = rise - ((A + q) * sample[:, 0] + B * sample[:, 1]), curv - q
    for x, (lo, hi) in ((s, s_rng), (rp, r_rng), (cp, c_rng)):
        assert lo < x.min() and x.max() < hi


def test_less_potential_lessens_the_ring_lines_it_is_given():
    """Lines v_top .. v_top - nb + 1 of the ring (row v mod R), positions [p0, p1) after the
    ``zo`` NaN positions, less A w^2 + B w p; every other value untouched."""
    rng = np.random.default_rng(5)
    R, zo, P = 7, 2, 40
    ZB = rng.normal(100.0, 30.0, (R, zo + P + 5))
    want = ZB.copy()
    A, B, v_top, nb, p0, p1 = 3e-4, -2e-3, 163, 4, 5, 33
    less_potential(ZB, zo, v_top, nb, p0, p1, A, B)
    for w in range(v_top - nb + 1, v_top + 1):
        p = np.arange(p0, p1)
        want[w % R, zo + p0:zo + p1] -= A * w * w + B * w * p
    np.testing.assert_allclose(ZB, want, rtol=0, atol=1e-12)
    untouched = np.ones(ZB.shape, bool)
    for w in range(v_top - nb + 1, v_top + 1):
        untouched[w % R, zo + p0:zo + p1] = False
    assert (ZB[untouched] == want[untouched]).all()
