"""``hillshade-rt horizon``: one azimuth, or ``--directions N`` (issue 20) — one band per
direction, clockwise from north, 0 first."""

import math

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band, write_geotiff

SRTM = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")      # geographic (EPSG:4326)
FLAT = ["--no-earth-curvature"]


def test_directions_are_the_single_azimuth_runs_band_by_band(tmp_path, runner):
    """Band i is exactly the run toward i * 360 / N; descriptions and tags say which."""
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--directions", "10"])
    assert r.exit_code == 0, r.output
    assert "10 directions (36 deg apart)" in r.stderr
    with rasterio.open(out) as ds:
        assert ds.count == 10 and ds.dtypes[0] == "float32" and ds.nodata == -9999.0
        assert ds.descriptions[3] == "horizon angle toward azimuth 108"
        assert ds.tags()["AZIMUTHS"] == "0,36,72,108,144,180,216,252,288,324"
        assert ds.tags(4)["AZIMUTH"] == "108"
    for band, az in ((2, 36.0), (9, 288.0)):
        one = tmp_path / f"one{band}.tif"
        r = runner.invoke(cli, ["horizon", SRTM, str(one), "--azimuth", str(az)])
        assert r.exit_code == 0, r.output
        np.testing.assert_array_equal(read_band(out, band), read_band(one))


def test_each_direction_decides_the_shadows_of_a_sun_there(tmp_path, runner):
    """The horizon toward the sun's azimuth decides every shadow: a cell is shadowed iff its
    angle exceeds the sun's elevation, cell for cell against brute (non-special azimuths)."""
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--directions", "10"] + FLAT)
    assert r.exit_code == 0, r.output
    for band, az, el in ((3, 72.0, 4.0), (6, 180.0, 9.0), (9, 288.0, 2.5)):
        m = tmp_path / f"m{band}.tif"
        r = runner.invoke(cli, ["shadow", SRTM, str(m), "--azimuth", str(az), "--elevation",
                                str(el), "--algorithm", "brute"] + FLAT)
        assert r.exit_code == 0, r.output
        beta, mask = read_band(out, band), read_band(m)
        valid = mask != 255
        assert np.array_equal(valid, beta != -9999.0)
        assert np.array_equal((beta > el)[valid], (mask == 1)[valid]), (az, el)
        assert 0.02 < (mask[valid] == 1).mean() < 0.98       # the test can fail both ways


def test_tilted_plane_uphill_is_its_slope_and_downhill_minus_it(tmp_path, runner):
    """An analytic case: a plane rising northward at slope S (flat model): toward north every
    cell but the top row sees the plane's own angle S; toward south -S (it looks down the
    plane; the nearest sample is the highest); no terrain beyond the raster: -90 at the edge."""
    rows, cols, d, s = 60, 40, 10.0, 0.3
    z = ((rows - 1 - np.arange(rows))[:, None] * d * s + np.zeros((1, cols))).astype(np.float32)
    dem = write_geotiff(tmp_path / "plane.tif", z, Affine(d, 0, 500000, 0, -d, 4000000),
                        CRS.from_epsg(32633))
    out = tmp_path / "h.tif"
    # --pixel-size: 10 m on the ground (UTM's grid metres are 1/0.9996 of them near its
    # central meridian)
    r = runner.invoke(cli, ["horizon", dem, str(out), "--directions", "8", "--pixel-size",
                            str(d)] + FLAT)
    assert r.exit_code == 0, r.output
    slope = math.degrees(math.atan(s))
    north, south = read_band(out, 1), read_band(out, 5)
    np.testing.assert_allclose(north[1:], slope, atol=1e-4)
    np.testing.assert_allclose(south[:-1], -slope, atol=1e-4)
    assert (north[0] == -90).all() and (south[-1] == -90).all()
    east = read_band(out, 3)                      # along the contour: level
    np.testing.assert_allclose(east[:, :-1], 0.0, atol=1e-4)


@pytest.mark.parametrize("args, code, words", [
    (["--directions", "4"], 2, "8<=x<=360"),
    (["--directions", "100000"], 2, "8<=x<=360"),
    ([], 2, "give --azimuth A (one direction) or --directions N"),
    (["--directions", "8", "--azimuth", "10"], 2, "one of them"),
])
def test_bad_directions_are_one_line_and_write_nothing(tmp_path, runner, args, code, words):
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out)] + args)
    assert r.exit_code == code and words in r.stderr and len(r.stderr.splitlines()) == 1
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_distance_is_the_nearest_sample_of_the_maximum(tmp_path, runner):
    """--distance: toward north on an axis the samples are the cells above; an independent
    plain-Python scan finds each cell's maximum (the nearest of equal ones) and its distance,
    which the file must hold, with the angle the file gives; -9999 where nothing lies ahead."""
    rng = np.random.default_rng(5)
    rows, cols, d = 40, 12, 25.0
    z = (rng.random((rows, cols)) * 80.0).astype(np.float32)
    z[7, 3] = np.nan
    dem = write_geotiff(tmp_path / "r.tif", z, Affine(d, 0, 500000, 0, -d, 4000000),
                        CRS.from_epsg(32633))
    out, dist = tmp_path / "h.tif", tmp_path / "d.tif"
    r = runner.invoke(cli, ["horizon", dem, str(out), "--azimuth", "0", "--distance", str(dist),
                            "--pixel-size", str(d)] + FLAT)
    assert r.exit_code == 0, r.output
    beta, got = read_band(out), read_band(dist)
    for i in range(rows):
        for j in range(cols):
            if np.isnan(z[i, j]):
                assert got[i, j] == -9999.0 and beta[i, j] == -9999.0
                continue
            best, kbest = -np.inf, 0
            for k in range(1, i + 1):
                t = z[i - k, j]
                if not np.isnan(t) and (float(t) - float(z[i, j])) / k > best:
                    best, kbest = (float(t) - float(z[i, j])) / k, k
            if kbest == 0:
                assert got[i, j] == -9999.0 and beta[i, j] == -90.0
            else:
                assert got[i, j] == pytest.approx(kbest * d, rel=1e-6), (i, j)
                assert beta[i, j] == pytest.approx(math.degrees(math.atan(best / d)), abs=1e-4)
    # the hull keeps no horizon point
    r = runner.invoke(cli, ["horizon", dem, str(tmp_path / "h2.tif"), "--azimuth", "0",
                            "--method", "hull", "--distance", str(tmp_path / "d2.tif")])
    assert r.exit_code == 2 and "--method scan only" in r.stderr


def test_distance_bands_follow_the_directions(tmp_path, runner):
    out, dist = tmp_path / "h.tif", tmp_path / "d.tif"
    r = runner.invoke(cli, ["horizon", SRTM, str(out), "--directions", "8", "--distance",
                            str(dist)])
    assert r.exit_code == 0, r.output
    with rasterio.open(dist) as ds:
        assert ds.count == 8 and ds.descriptions[2].endswith("toward azimuth 90")
        d3 = ds.read(3)
    b3 = read_band(out, 3)
    assert np.array_equal(d3 == -9999.0, (b3 == -9999.0) | (b3 == -90.0))
    assert (d3[d3 != -9999.0] > 0).all()
