"""``run.horizon_windows``: the horizon scan in windows gives every cell the bits of the run in
memory; a region as a Dask task (``region_task``) hands back its part (``RegionPart``)."""

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.run import HorizonConfig, horizon
from hillshade_rt.run.config import ReadOptions, RunOptions
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff


@pytest.fixture
def dem(tmp_path):
    z = fractal_terrain(230, 170, 11, relief=600.0) + 300.0
    z[100:104, 40:47] = -9999.0     # a void: nodata in and out
    return write_geotiff(tmp_path / "d.tif", z, Affine(30, 0, 500000.0, 0, -30, 4000000.0),
                         CRS.from_epsg(32633), nodata=-9999.0)


@pytest.mark.parametrize("azimuth, max_distance", [(203.7, None), (203.7, 1500.0),
                                                   (290.0, None)])
def test_windows_are_the_run_in_memory_bit_for_bit(tmp_path, dem, azimuth, max_distance):
    out = {}
    for name, ws in (("mem", None), ("win", "64x80")):
        path = str(tmp_path / f"{name}.tif")
        rep = horizon(HorizonConfig(dem=dem, output=path, azimuth=azimuth,
                                    distance=str(tmp_path / f"{name}_d.tif"), window_size=ws,
                                    max_distance=max_distance, run=RunOptions(quiet=True)))
        out[name] = (read_band(path), read_band(tmp_path / f"{name}_d.tif"), rep)
    (a, da, mem), (b, db, win) = out["mem"], out["win"]
    assert mem["processing"]["mode"] == "in memory"
    assert win["processing"]["mode"] == "windows" and win["processing"]["regions"] == 12
    assert win["processing"]["continuation_windows"] > 0 or max_distance is not None
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(da, db)
    assert (a == -9999.0).sum() == 28 and (a > 0).sum() > 1000     # the void; real horizons
    assert win["curvature"] == mem["curvature"] and win["azimuth"] == azimuth


def test_a_region_task_hands_back_its_part(tmp_path, dem):
    """``region_task`` (what a Dask worker runs) writes the region's part, the bits of the run
    in memory there, and hands back a ``RegionPart`` naming it."""
    from hillshade_rt.engine.windows import block_stats
    from hillshade_rt.run.horizon import horizon_job
    from hillshade_rt.run.horizon_windows import Product, RegionPart, region_task

    whole = str(tmp_path / "whole.tif")
    horizon(HorizonConfig(dem=dem, output=whole, azimuth=163.0, run=RunOptions(quiet=True)))
    with ReadOptions().open(dem, windows=True) as src:
        job, _ = horizon_job(src, [163.0], "cpu", None, None, "scan", block_stats(src))
        region = (64, 128, 80, 160)
        part = region_task(job, region, Product("horizon"), str(tmp_path), stride=16)
    assert isinstance(part, RegionPart)
    assert part.region == region and set(part.paths) == {"angles"}
    assert part.figures.as_dict()["regions"] == 1
    got = read_band(part.paths["angles"])
    np.testing.assert_array_equal(got, read_band(whole)[64:128, 80:160])
    sub, (r, c) = part.shade
    assert (r, c) == (4, 5) and sub.shape == (4, 5)
