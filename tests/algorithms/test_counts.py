"""The counting passes against numpy: codes, valid ranges, block ranges, the nodata pass."""

import numpy as np
import pytest

from hillshade_rt.algorithms import counts


def _heights(rows, cols, seed=3):
    rng = np.random.default_rng(seed)
    z = rng.normal(500.0, 120.0, (rows, cols)).astype(np.float32)
    z[rng.random((rows, cols)) < 0.1] = np.nan
    return z


@pytest.mark.parametrize("shape", [(1, 7), (5, 6), (70, 33), (3, 9000)])
def test_code_counts_equal_bincount(shape):
    a = np.random.default_rng(1).integers(0, 256, shape, dtype=np.uint8)
    np.testing.assert_array_equal(counts.code_counts(a), np.bincount(a.ravel(), minlength=256))


@pytest.mark.parametrize("shape", [(1, 1), (4, 9), (101, 37)])
def test_valid_range_equals_numpy(shape):
    z = _heights(*shape)
    n, lo, hi = counts.valid_range(z)
    valid = z[~np.isnan(z)]
    assert n == valid.size
    if valid.size:
        assert (lo, hi) == (valid.min(), valid.max())
    lo2, hi2, voids = counts.z_range(z)
    assert voids == (valid.size < z.size)


def test_valid_range_of_nothing_valid():
    z = np.full((3, 4), np.nan, np.float32)
    n, lo, hi = counts.valid_range(z)
    assert n == 0 and lo == np.inf and hi == -np.inf
    n, lo, hi = counts.valid_range(np.zeros((0, 4), np.float32))
    assert n == 0 and lo == np.inf and hi == -np.inf


def test_clean_heights_turns_nodata_and_infinities_to_nan_in_place():
    z = _heights(40, 23)
    z[2, 3], z[5, 5], z[7, 1] = -9999.0, np.inf, -np.inf
    want = z.copy()
    want[(want == -9999.0) | ~np.isfinite(want)] = np.nan
    n, lo, hi = counts.clean_heights(z, -9999.0, True)
    np.testing.assert_array_equal(z, want)
    valid = want[~np.isnan(want)]
    assert (n, lo, hi) == (valid.size, valid.min(), valid.max())
    z2 = np.array([[-9999.0, 1.0]], np.float32)
    assert counts.clean_heights(z2, -9999.0, False)[0] == 2      # nodata not in use: kept


def test_code_tests_equal_numpy():
    a = np.random.default_rng(2).integers(0, 3, (50, 41), dtype=np.uint8)
    a[17, 40] = 255
    for code in (0, 1, 2, 255, 7):
        assert counts.count_code(a, np.uint8(code)) == int((a == code).sum())
        assert counts.any_code(a, code) == bool((a == code).any())
        assert counts.any_code(a[:, ::2], code) == bool((a[:, ::2] == code).any())   # numpy path


@pytest.mark.parametrize("shape, B", [((37, 53), 8), ((64, 64), 16), ((5, 300), 7), ((1, 1), 4)])
def test_block_range_equals_numpy_per_block(shape, B):
    """Each B x B block's lowest and highest valid height (ragged blocks at the edges), +inf /
    -inf for a block of voids, and the count of valid cells."""
    z = _heights(*shape, seed=B)
    z[:B, :B] = np.nan                              # the first block: voids only
    nbr, nbc = -(-shape[0] // B), -(-shape[1] // B)
    lo, hi = np.empty((nbr, nbc), np.float32), np.empty((nbr, nbc), np.float32)
    n = counts.block_range(z, B, lo, hi)
    assert n == np.count_nonzero(~np.isnan(z))
    for i in range(nbr):
        for j in range(nbc):
            blk = z[i * B:(i + 1) * B, j * B:(j + 1) * B]
            if np.isnan(blk).all():
                assert lo[i, j] == np.inf and hi[i, j] == -np.inf
            else:
                assert lo[i, j] == np.nanmin(blk) and hi[i, j] == np.nanmax(blk)
