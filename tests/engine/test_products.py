"""The products (engine.products): statistics against plain counts, and the statistics of
windows merged equal the whole raster's, for every product; the preview's shade; the table."""

import functools

import numpy as np
import pytest

from hillshade_rt.engine import products
from hillshade_rt.errors import UsageProblem


def _array(kind, soft, rng, shape=(37, 53)):
    if kind == "hillshade":
        return rng.integers(0, 256, shape).astype(np.uint8)
    if soft:
        a = rng.random(shape).astype(np.float32)
        a[rng.random(shape) < 0.1] = np.nan
        return a
    codes = np.array([0, 1, 255] if kind == "shadow" else [0, 1, 2, 255], np.uint8)
    return codes[rng.integers(0, len(codes), shape)]


def _windows(arr, rng):
    """Arbitrary windows that tile the array (uneven row and column cuts)."""
    r = np.unique(np.r_[0, np.sort(rng.integers(1, arr.shape[0], 3)), arr.shape[0]])
    c = np.unique(np.r_[0, np.sort(rng.integers(1, arr.shape[1], 2)), arr.shape[1]])
    return [arr[r0:r1, c0:c1] for r0, r1 in zip(r[:-1], r[1:]) for c0, c1 in zip(c[:-1], c[1:])]


@pytest.mark.parametrize("kind,soft", sorted(products.PRODUCTS))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_merged_window_stats_equal_the_whole_rasters(kind, soft, seed):
    rng = np.random.default_rng(seed)
    arr = _array(kind, soft, rng)
    p = products.product(kind, soft)
    whole = p.stats(arr)
    merged = functools.reduce(products.merge_stats, (p.stats(w) for w in _windows(arr, rng)),
                              None)
    assert set(merged) <= set(whole)
    for k, v in merged.items():
        if isinstance(v, float):
            assert v == pytest.approx(whole[k], rel=1e-6), k
        else:
            assert v == whole[k], k


@pytest.mark.parametrize("kind,soft", sorted(products.PRODUCTS))
def test_stats_against_plain_counts(kind, soft):
    arr = _array(kind, soft, np.random.default_rng(5))
    s = products.product_stats(kind, soft, arr)
    flat = arr.ravel().tolist()
    if kind == "hillshade":
        assert s["nodata_cells"] == flat.count(0) and s["lit_cells"] == len(flat) - flat.count(0)
    elif soft:
        vals = [v for v in flat if v == v]
        assert s["valid_cells"] == len(vals) and s["nodata_cells"] == len(flat) - len(vals)
        assert s["shadow_fraction"] == pytest.approx(1 - sum(vals) / len(vals), rel=1e-9)
    else:
        shadow = sum(1 for v in flat if v in (1, 2))
        lit = flat.count(0)
        assert (s["shadow_cells"], s["lit_cells"], s["nodata_cells"]) == (
            shadow, lit, flat.count(255))
        assert s["shadow_fraction"] == pytest.approx(shadow / (shadow + lit))
        if kind == "classes":
            assert (s["self_shadow_cells"], s["cast_shadow_cells"]) == (flat.count(1),
                                                                        flat.count(2))


def test_nothing_valid_has_no_fraction_and_merges_to_none():
    m = products.mask_stats(np.full((3, 4), 255, np.uint8))
    assert m == {"shadow_cells": 0, "lit_cells": 0, "nodata_cells": 12, "shadow_fraction": None}
    soft = products.product_stats("shadow", True, np.full((2, 2), np.nan, np.float32))
    assert soft["shadow_fraction"] is None and soft["valid_cells"] == 0
    assert products.merge_stats(soft, soft)["shadow_fraction"] is None
    one = products.product_stats("shadow", True, np.array([[0.25, np.nan]], np.float32))
    assert products.merge_stats(soft, one)["shadow_fraction"] == pytest.approx(0.75)


def test_shade_and_the_table():
    mask = np.array([[0, 1, 255]], np.uint8)
    assert products.product("shadow").shade(mask, 0.2).tolist() == [[0, 1, 0]]
    cls = np.array([[0, 1, 2, 255]], np.uint8)
    assert products.product("classes").shade(cls, 0.2).tolist() == [[0, 1, 1, 0]]
    soft = np.array([[1.0, 0.25, np.nan]], np.float32)
    assert products.product("shadow", True).shade(soft, 0.2).tolist() == [[0, 0.75, 0]]
    # hillshade: cells no brighter than the ambient's value are shadow; 0 is nodata
    base = 1 + round(254 * 0.2)
    hs = np.array([[0, 1, base, base + 1, 255]], np.uint8)
    assert products.product("hillshade").shade(hs, 0.2).tolist() == [[0, 1, 1, 0, 0]]
    with pytest.raises(UsageProblem):
        products.product("classes", soft=True)
    for (kind, soft_), p in products.PRODUCTS.items():
        assert (p.kind, p.soft) == (kind, soft_)
        assert p.continuous == (p.dtype == "float32" or kind == "hillshade")
        assert np.dtype(p.dtype).type(p.nodata) == p.nodata     # nodata fits its type
