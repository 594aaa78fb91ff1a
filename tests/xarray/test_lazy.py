"""hillshade_rt.xarray.lazy: Dask-backed inputs give lazy results, window by window as the
command line's windowed runs (chunks smaller than the sun's halo), equal to the in-memory ones;
a task reads only its window's chunks."""

from __future__ import annotations

import math

import numpy as np
import pytest
import rioxarray           # the `xarray` extra, in `test`

import hillshade_rt.xarray  # noqa: F401 -- registers da.hrt
from hillshade_rt.testing import data_path
from hillshade_rt.xarray import lazy as lazy_graph

EVEREST = data_path("everest_srtm3_voids_crop200.tif")    # EPSG:4326, voids (-32768)
TIMES = ["2026-06-21T03:00:00+00:00", "2026-06-21T09:30:00+00:00",
         "2026-06-21T18:00:00+00:00"]      # Everest: morning, afternoon, night


def same_place(out, ref):
    """The same cells, coordinates, CRS and transform."""
    assert out.dims[-2:] == ("y", "x")
    np.testing.assert_array_equal(out.x.values, ref.x.values)
    np.testing.assert_array_equal(out.y.values, ref.y.values)
    assert out.rio.crs == ref.rio.crs
    assert out.rio.transform() == ref.rio.transform()


@pytest.mark.slow
def test_dask_input_is_lazy_and_equals_in_memory_with_chunks_smaller_than_the_halo(monkeypatch):
    import dask

    da = rioxarray.open_rasterio(EVEREST)
    dk = rioxarray.open_rasterio(EVEREST, chunks={"band": 1, "y": 32, "x": 40})
    lo, hi = float(da.where(da != -32768).min()), float(da.max())
    # the halo toward a sun at 12 degrees: more cells than a chunk (~ 90 m cells)
    assert (hi - lo) / math.tan(math.radians(12.0)) / 90.0 > 4 * 40
    calls = []
    real = lazy_graph.light_piece

    def counting(job, piece, z):
        calls.append((piece.region, piece.window))
        return real(job, piece, z)
    monkeypatch.setattr(lazy_graph, "light_piece", counting)
    lazy = dk.hrt.shadow(azimuth=203.7, elevation=12.0)
    assert isinstance(lazy.data, dask.array.Array) and not calls    # nothing lit yet
    assert lazy.chunks == ((32,) * 6 + (8,), (40,) * 5)             # the input's chunks
    got = lazy.compute()
    monkeypatch.undo()
    mem = da.hrt.shadow(azimuth=203.7, elevation=12.0)
    np.testing.assert_array_equal(got.values, mem.values)
    same_place(got, mem)
    # windows: the region and the halo on the sun's side (south-south-west: higher rows,
    # lower columns), larger than a chunk
    assert len(calls) > 10
    assert any((w[1] - w[0]) > 2 * (r[1] - r[0]) for r, w in calls)
    assert all(w[0] >= r[0] - 3 and w[3] <= r[3] + 3 for r, w in calls)

    series = dk.hrt.shadow(time=TIMES)
    assert isinstance(series.data, dask.array.Array)
    np.testing.assert_array_equal(series.values, da.hrt.shadow(time=TIMES).values)
    hours = dk.hrt.sun_hours(date="2026-06-21", step="2h")
    assert isinstance(hours.data, dask.array.Array)
    np.testing.assert_array_equal(hours.values, da.hrt.sun_hours(date="2026-06-21",
                                                                  step="2h").values)
    # horizons: windows toward each azimuth, to the edge or within max_distance
    for kw in ({}, {"max_distance": 3000.0}):
        h = dk.hrt.horizon([100.0, 203.7], **kw)
        assert isinstance(h.data, dask.array.Array) and h.dims == ("azimuth", "y", "x")
        np.testing.assert_array_equal(h.values, da.hrt.horizon([100.0, 203.7], **kw).values)
    for kw in ({"max_distance": 2500.0}, {"max_distance": 2000.0, "openness": "negative"}):
        v = dk.hrt.skyview(directions=8, **kw)
        assert isinstance(v.data, dask.array.Array)
        np.testing.assert_array_equal(v.values, da.hrt.skyview(directions=8, **kw).values)


def test_dask_task_reads_only_its_window():
    """Computing one output chunk reads the input chunks of its window (the region and its
    halo toward the sun), not the whole input."""
    import dask.array as dka

    da = rioxarray.open_rasterio(EVEREST).isel(band=0, drop=True)
    reads = []

    def record(block, block_info=None):
        reads.append(tuple(block_info[0]["chunk-location"]))
        return block
    counted = dka.from_array(da.values, chunks=(32, 40)).map_blocks(record, dtype=da.dtype)
    dk = da.copy(data=counted)
    # a high sun: the halo toward the south-south-west is ~30 rows, ~15 columns here
    lazy = dk.hrt.shadow(azimuth=203.7, elevation=60.0)
    assert len(set(reads)) == 35          # the block height ranges: one pass over the input
    reads.clear()
    top_right = lazy[:32, 160:].compute()
    np.testing.assert_array_equal(
        top_right.values, da.hrt.shadow(azimuth=203.7, elevation=60.0).values[:32, 160:])
    assert set(reads) <= {(r, c) for r in (0, 1, 2) for c in (3, 4)}
    assert (1, 4) in set(reads) and (0, 4) in set(reads)
