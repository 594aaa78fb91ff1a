"""algorithms/illumination.py: the per-position accumulators (hours lit, the longest shadow, the
shadow before the first and after the last light, never lit) against a plain-Python pass over
each cell's sequence, and ``combine`` (two stretches as one) against the whole sequence."""

import numpy as np
import pytest

from hillshade_rt.algorithms import illumination as ill


def _sums(shape, soft=False):
    return {"lit": np.zeros(shape), "soft": np.zeros(shape) if soft else None,
            "start": np.zeros(shape), "end": np.zeros(shape), "longest": np.zeros(shape),
            "dark": np.ones(shape, np.uint8)}


def _fold(masks, dts, fracs=None):
    s = _sums(masks[0].shape, fracs is not None)
    for k, (m, dt) in enumerate(zip(masks, dts)):
        ill.accumulate(m, dt, s["lit"], s["start"], s["end"], s["longest"], s["dark"])
        if fracs is not None:
            ill.accumulate_soft(fracs[k], dt, s["soft"])
    return s


def _plain(seq, dts):
    """One cell's (lit, start, end, longest, dark) from its sequence of 0/1/255."""
    lit = start = end = longest = 0.0
    seen_light = False
    run = 0.0
    for m, dt in zip(seq, dts):
        if m == 0:
            lit += dt
            seen_light = True
            run = 0.0
        elif m == 1:
            run += dt
            longest = max(longest, run)
            if not seen_light:
                start += dt
    end = run
    return lit, start, end, longest, 0 if seen_light else 1


def _series(seed, n=13, shape=(3, 4)):
    rng = np.random.default_rng(seed)
    masks = [rng.choice(np.array([0, 1, 1], np.uint8), size=shape) for _ in range(n)]
    for m in masks:
        m[2, 3] = 255                         # a void: left as it is
    masks[0][0, 0] = masks[5][0, 0] = 0       # lit twice
    for m in masks:
        m[1, 1] = 1                           # never lit
    dts = list(rng.choice([0.5, 1.0, 2.25], size=n))
    return masks, dts


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_accumulate_equals_the_plain_pass(seed):
    masks, dts = _series(seed)
    s = _fold(masks, dts)
    for r in range(3):
        for c in range(4):
            want = _plain([m[r, c] for m in masks], dts)
            got = (s["lit"][r, c], s["start"][r, c], s["end"][r, c], s["longest"][r, c],
                   s["dark"][r, c])
            assert got == pytest.approx(want), (r, c)
    assert s["dark"][1, 1] == 1 and s["longest"][1, 1] == pytest.approx(sum(dts))
    assert s["lit"][2, 3] == 0 and s["dark"][2, 3] == 1 and s["longest"][2, 3] == 0


@pytest.mark.parametrize("cut", [1, 6, 12])
def test_combine_of_two_stretches_is_the_whole(cut):
    masks, dts = _series(7)
    fracs = [np.where(m == 0, 0.75, np.where(m == 1, 0.25, np.nan)).astype(np.float32)
             for m in masks]
    whole = _fold(masks, dts, fracs)
    both = ill.combine(_fold(masks[:cut], dts[:cut], fracs[:cut]),
                       _fold(masks[cut:], dts[cut:], fracs[cut:]))
    for k in whole:
        np.testing.assert_allclose(both[k], whole[k], err_msg=k)


def test_accumulate_dark_shades_every_valid_cell():
    z = np.array([[1.0, np.nan], [3.0, 4.0]], np.float32)
    s = _sums(z.shape)
    m = np.array([[0, 255], [1, 0]], np.uint8)
    ill.accumulate(m, 1.0, s["lit"], s["start"], s["end"], s["longest"], s["dark"])
    ill.accumulate_dark(z, 2.5, s["start"], s["end"], s["longest"], s["dark"])
    np.testing.assert_array_equal(s["end"], [[2.5, 0.0], [3.5, 2.5]])
    np.testing.assert_array_equal(s["longest"], [[2.5, 0.0], [3.5, 2.5]])
    np.testing.assert_array_equal(s["start"], [[0.0, 0.0], [3.5, 0.0]])
    np.testing.assert_array_equal(s["dark"], [[0, 1], [1, 0]])


def test_accumulate_soft_skips_nan():
    soft = np.zeros((1, 3))
    ill.accumulate_soft(np.array([[0.5, np.nan, 1.0]], np.float32), 2.0, soft)
    np.testing.assert_array_equal(soft, [[1.0, 0.0, 2.0]])
