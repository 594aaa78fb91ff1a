"""``shadow --subsolar LAT,LON [--sun-distance M] [--body B]`` (issue 21, item 2): the command
writes ``arrays.subsolar_mask``'s mask and reports the sun over the DEM; what it does not take
is a usage error (exit 2, one line)."""

import json

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.engine.arrays import subsolar_mask
from hillshade_rt.cli import cli
from hillshade_rt.io import read_dem
from hillshade_rt.testing import MOON_GEOGRAPHIC, fractal_terrain, read_band, write_geotiff


@pytest.fixture
def dem(tmp_path):
    z = fractal_terrain(40, 50, 6, relief=2500.0)
    z[3, 4] = np.nan
    return write_geotiff(tmp_path / "d.tif", z, Affine(0.01, 0, 20.0, 0, -0.01, -30.0),
                         MOON_GEOGRAPHIC)


def test_subsolar_writes_the_api_mask_and_reports(tmp_path, runner, dem):
    out, rep = tmp_path / "m.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--subsolar", "-20.5,97.3",
                            "--sun-distance", "2e11", "--report", str(rep)])
    assert r.exit_code == 0, r.output
    want = subsolar_mask(read_dem(dem), -20.5, 97.3, sun_distance=2e11)
    got = read_band(out)
    assert np.array_equal(got, want)
    assert (want == 1).any() and (want == 0).any() and (want == 255).sum() == 1
    doc = json.loads(rep.read_text())
    assert doc["subsolar"] == {"lat": -20.5, "lon": 97.3} and doc["sun_distance_m"] == 2e11
    assert doc["body"]["a_m"] == 1737400.0
    lo, hi = doc["sun"]["elevation_deg"]
    assert 0 < lo < hi < 30


def test_body_overrides_the_crs(tmp_path, runner, dem):
    out = tmp_path / "m.tif"
    """A small body curves the rays more: the same suns, more cells lit."""
    r = runner.invoke(cli, ["shadow", dem, str(out), "--subsolar", "-20.5,97.3", "--body",
                            "20000", "--report", str(tmp_path / "r.json")])
    assert r.exit_code == 0, r.output
    want = subsolar_mask(read_dem(dem), -20.5, 97.3, body="20000")
    assert np.array_equal(read_band(out), want)
    moon = subsolar_mask(read_dem(dem), -20.5, 97.3)
    assert ((want == 1) <= (moon == 1)).all() and (want != moon).any()
    assert json.loads((tmp_path / "r.json").read_text())["body"]["a_m"] == 20000.0


@pytest.mark.parametrize("extra, words", [
    (["--subsolar", "95,0"], "latitude"),
    (["--subsolar", "10"], "LAT,LON"),
    (["--subsolar", "10,0", "--azimuth", "163", "--elevation", "10"], "--azimuth"),
    (["--subsolar", "10,0", "--classes"], "--classes"),
    (["--subsolar", "10,0", "--window-size", "64"], "--window-size"),
    (["--subsolar", "10,0", "--algorithm", "smap"], "--algorithm"),
    (["--subsolar", "10,0", "--light-position", "1,2,3"], "--light-position"),
    (["--subsolar", "10,0", "--body", "venus"], "--body"),
    (["--sun-distance", "2e11", "--azimuth", "163", "--elevation", "10"], "--subsolar"),
])
def test_what_subsolar_does_not_take_is_a_usage_error(tmp_path, runner, dem, extra, words):
    out = tmp_path / "m.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out)] + extra)
    assert r.exit_code == 2 and words in r.output and "Traceback" not in r.output, r.output
    assert len(r.output.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("distance, words", [("1000", "radius"), ("-5", "positive")])
def test_a_sun_inside_the_body_is_a_usage_error(tmp_path, runner, dem, distance, words):
    out = tmp_path / "m.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--subsolar", "10,0", "--sun-distance",
                            distance])
    assert r.exit_code == 2 and words in r.output and "Traceback" not in r.output
    assert len(r.output.strip().splitlines()) == 1 and not out.exists()


def test_soft_writes_the_visible_fraction(tmp_path, runner, dem):
    out, rep = tmp_path / "f.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--subsolar", "-20.5,97.3", "--soft",
                            "--sun-distance", "5e9", "--report", str(rep)])
    assert r.exit_code == 0, r.output
    want = subsolar_mask(read_dem(dem), -20.5, 97.3, sun_distance=5e9, soft=True)
    got = read_band(out)
    assert got.dtype == np.float32 and got[3, 4] == -9999.0
    valid = np.isfinite(want)
    np.testing.assert_array_equal(got[valid], want[valid])
    assert ((want > 0) & (want < 1)).any()
    doc = json.loads(rep.read_text())
    assert doc["soft"] and abs(doc["sun_radius_deg"] - 7.99) < 0.01


def _series_csv(tmp_path, rows, header="time,lat,lon,distance_m"):
    p = tmp_path / "sun.csv"
    p.write_text(header + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    return str(p)


def test_subsolar_file_writes_a_band_per_time(tmp_path, runner, dem):
    """``shadow --subsolar-file``: band k is ``--subsolar`` of row k (its distance, or
    --sun-distance where the file gives none), described by its UTC time."""
    rows = [("2026-01-01T00:00:00Z", -20.5, 97.3, 2e11), ("2026-01-01T06:00:00Z", -15.0, 120.0,
                                                          1.5e11),
            ("2026-01-01T12:00:00Z", 3.25, 163.0, 1.0e11)]
    csv = _series_csv(tmp_path, rows)
    out, rep = tmp_path / "s.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--subsolar-file", csv, "--report",
                            str(rep)])
    assert r.exit_code == 0, r.output
    import rasterio
    with rasterio.open(out) as ds:
        assert ds.count == 3
        assert ds.descriptions == ("2026-01-01T00:00+00:00", "2026-01-01T06:00+00:00",
                                   "2026-01-01T12:00+00:00")
        assert ds.tags(2)["SUBSOLAR"] == "lat -15 lon 120"
        bands = ds.read()
    for k, (_, lat, lon, dist) in enumerate(rows):
        want = subsolar_mask(read_dem(dem), lat, lon, sun_distance=dist)
        assert np.array_equal(bands[k], want), k
    assert not np.array_equal(bands[0], bands[2])
    doc = json.loads(rep.read_text())
    assert doc["sun_distance_m"] == [2e11, 1.5e11, 1e11] and len(doc["shadow_fraction"]) == 3
    # without distances: --sun-distance for every time; --soft: the visible fraction per band
    csv2 = _series_csv(tmp_path, [r[:3] for r in rows], "time,lat,lon")
    out2 = tmp_path / "s2.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out2), "--subsolar-file", csv2, "--soft",
                            "--sun-distance", "3e11"])
    assert r.exit_code == 0, r.output
    with rasterio.open(out2) as ds:
        got = ds.read(3, masked=True)
    want = subsolar_mask(read_dem(dem), 3.25, 163.0, sun_distance=3e11, soft=True)
    assert np.allclose(got.filled(np.nan), want, equal_nan=True)


@pytest.mark.parametrize("content, extra, code, words", [
    ("time,lat,lon\n2026-01-01T06:00Z,0,0\n2026-01-01T00:00Z,0,0\n", [], 1, "increas"),
    ("time,lon\n2026-01-01T00:00Z,0\n", [], 1, "no lat column"),
    ("time,lat,lon\n2026-01-01T00:00Z,0,0\n", ["--subsolar", "1,2"], 2, "not both"),
    ("time,lat,lon\n2026-01-01T00:00Z,0,0\n", ["--preview", "p.png"], 2, "--preview"),
])
def test_bad_subsolar_files_write_nothing(tmp_path, runner, dem, content, extra, code, words):
    p = tmp_path / "bad.csv"
    p.write_text(content)
    out = tmp_path / "o.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--subsolar-file", str(p)] + extra)
    assert r.exit_code == code, r.output
    assert words in r.output and "Traceback" not in r.output
    assert len(r.output.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.slow
def test_subsolar_series_into_a_cube(tmp_path, runner, dem):
    """``--subsolar-file`` into OUTPUT.nc: one CF time cube, its bands the GeoTIFF's, the
    subsolar points and distances per time."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("rioxarray")
    import rasterio
    rows = [("2026-01-01T00:00:00Z", -20.5, 97.3, 2e11), ("2026-01-01T06:00:00Z", -15.0, 120.0,
                                                          1.5e11),
            ("2026-01-01T12:00:00Z", 3.25, 163.0, 1.0e11)]
    csv = _series_csv(tmp_path, rows)
    for name in ("s.tif", "s.nc"):
        r = runner.invoke(cli, ["shadow", dem, str(tmp_path / name), "--subsolar-file", csv,
                                "-q"])
        assert r.exit_code == 0, r.output
    with rasterio.open(tmp_path / "s.tif") as ds:
        bands, crs = ds.read(), ds.crs
    with xr.open_dataset(tmp_path / "s.nc", mask_and_scale=False) as ds:
        np.testing.assert_array_equal(ds["shadow"].values, bands)
        np.testing.assert_array_equal(
            ds["time"].values, np.array([t[:19] for t, *_ in rows], "datetime64[ns]"))
        np.testing.assert_array_equal(ds["subsolar_lat"].values, [r[1] for r in rows])
        np.testing.assert_array_equal(ds["sun_distance"].values, [r[3] for r in rows])
        assert ds.rio.crs == crs
        assert ds["x"].attrs["units"] == "degrees_east"
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "t.nc"), "--subsolar-file", csv,
                            "--co", "COMPRESS=ZSTD"])
    assert r.exit_code == 2 and "--co" in r.stderr
    assert not (tmp_path / "t.nc").exists()
