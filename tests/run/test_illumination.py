"""The illumination run (issue 21, item 4): fraction lit against a numpy reference on a lunar
sphere, the longest shadow of a crafted series, a polar pit never lit, --soft, windows and
Dask equal to the run in memory, --height-above-ground, bad series files."""

from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.engine.cell_suns import body_from_option, sun_vector
from hillshade_rt.cli import cli
from hillshade_rt.model.ephemeris import read_subsolar
from hillshade_rt.run.config import IllumConfig
from hillshade_rt.run.illumination import illumination
from hillshade_rt.testing import (LUNAR_SOUTH_POLAR_STEREO, MOON_GEOGRAPHIC, read_band,
                                  spectral, toy_lunar_subsolar, write_geotiff,
                                  write_subsolar_csv)

MOON = body_from_option("moon")


def _run(tmp_path, dem, csv, name="out.tif", **kw):
    out = str(tmp_path / name)
    rep = illumination(IllumConfig(files=[dem, out], subsolar_file=csv, **kw))
    return out, rep


def _bands(path, n):
    return [read_band(path, i + 1) for i in range(n)]


def _flat_geographic(tmp_path, lon0=-20.0, lat0=10.0, res=0.5, shape=(40, 80)):
    z = np.zeros(shape, np.float32)
    tr = Affine(res, 0, lon0, 0, -res, lat0)
    path = write_geotiff(str(tmp_path / "flat.tif"), z, tr, MOON_GEOGRAPHIC)
    rows, cols = shape
    lon = lon0 + res * (np.arange(cols) + 0.5)
    lat = lat0 - res * (np.arange(rows) + 0.5)
    return path, np.meshgrid(np.radians(lon), np.radians(lat))


def test_flat_sphere_fraction_lit_matches_reference(tmp_path):
    """A flat DEM on the lunar sphere across the terminator: each cell lit exactly when the
    sun's centre is above its horizon (S . n > R), time-weighted by the series' intervals."""
    dem, (lam, phi) = _flat_geographic(tmp_path)
    hours = np.array([0, 5, 7.5, 20, 21, 40, 43, 60], float)     # uneven intervals
    rows = [(f"2027-01-01T00:00:00+00:00", 0.7, -95.0)]
    import datetime as dt
    t0 = dt.datetime(2027, 1, 1, tzinfo=dt.timezone.utc)
    lons = [-95.0, -101.3, -104.0, -111.0, 71.0, 76.5, 80.0, 84.2]
    lats = [0.7, 0.9, 1.1, 1.3, -1.2, -1.0, -0.4, 0.2]
    rows = [((t0 + dt.timedelta(hours=h)).isoformat(), la, lo)
            for h, la, lo in zip(hours, lats, lons)]
    csv = write_subsolar_csv(tmp_path / "s.csv", rows)
    out, rep = _run(tmp_path, dem, csv)
    frac, longest, psr = _bands(out, 3)
    dts = read_subsolar(csv).durations_h()
    n = np.stack([np.cos(phi) * np.cos(lam), np.cos(phi) * np.sin(lam), np.sin(phi)], -1)
    lit = np.zeros(frac.shape)
    never = np.ones(frac.shape, bool)
    for la, lo, d in zip(lats, lons, dts):
        s = sun_vector(MOON, la, lo)
        up = n @ s > MOON.a
        lit += d * up
        never &= ~up
    ref = lit / dts.sum()
    assert 0.05 < ref.mean() < 0.95 and np.unique(np.round(ref, 6)).size > 3
    np.testing.assert_allclose(frac, ref, atol=1e-6)
    np.testing.assert_array_equal(psr == 1.0, never)
    assert rep["times"] == 8 and rep["bands"][0] == "fraction_lit"


def _alternating_series(tmp_path, pattern, hours):
    """Subsolar points over (0, 0) for 'L' and over (0, 180) for 'D' at ``hours``."""
    import datetime as dt
    t0 = dt.datetime(2027, 3, 1, tzinfo=dt.timezone.utc)
    rows = [((t0 + dt.timedelta(hours=h)).isoformat(), 0.0, 0.0 if p == "L" else 180.0)
            for p, h in zip(pattern, hours)]
    return write_subsolar_csv(tmp_path / "alt.csv", rows)


def test_longest_shadow_hours_exact(tmp_path):
    """L D D L D D at hours 0 1 3 4 10 12: intervals 1 2 1 6 2 (2 for the last): the shadow
    runs last 3 and 4 hours; lit 7 of 14 hours; never permanently dark."""
    dem, _ = _flat_geographic(tmp_path, lon0=-2.0, lat0=2.0, res=0.25, shape=(16, 16))
    csv = _alternating_series(tmp_path, "LDDLDD", [0, 1, 3, 4, 10, 12])
    out, rep = _run(tmp_path, dem, csv, soft=True)
    # the sun over the far side: dark everywhere without a march
    assert rep["positions"] == {"marched": 2, "dark_everywhere": 4}
    frac, soft, longest, psr = _bands(out, 4)
    np.testing.assert_allclose(frac, 0.5, atol=1e-7)
    np.testing.assert_allclose(longest, 4.0, atol=1e-6)
    assert (psr == 0).all()
    # the disk always wholly up or wholly down: the soft mean equals the hard fraction
    np.testing.assert_allclose(soft, frac, atol=1e-6)
    # a series that ends dark and starts dark: the runs at both ends count
    csv2 = _alternating_series(tmp_path, "DDLLDDD", [0, 2, 5, 6, 9, 10, 15])
    out2, _ = _run(tmp_path, dem, csv2, name="o2.tif")
    f2, l2, p2 = _bands(out2, 3)
    np.testing.assert_allclose(l2, 1 + 5 + 5, atol=1e-6)          # 9->10->15, last repeats 5
    np.testing.assert_allclose(f2, 4 / 20, atol=1e-7)


def _polar_pit(tmp_path, n=160, res=20.0, depth=600.0, radius=700.0, rough=0.0, name="pit.tif"):
    """A paraboloid pit at the lunar south pole (polar stereographic), ``rough`` metres of
    fractal relief on top; returns (path, pit mask, rim mask)."""
    c = (np.arange(n) - n / 2 + 0.5) * res
    x, y = np.meshgrid(c, -c)
    r = np.hypot(x, y)
    z = (-depth * np.clip(1 - (r / radius) ** 2, 0, None)).astype(np.float32)
    if rough:
        z = z + spectral(n, 2.2, seed=5, relief=rough).astype(np.float32)
    tr = Affine(res, 0, -n / 2 * res, 0, -res, n / 2 * res)
    path = write_geotiff(str(tmp_path / name), z, tr, LUNAR_SOUTH_POLAR_STEREO)
    return path, r < 0.4 * radius, (r > 1.05 * radius) & (r < 1.3 * radius)


def _toy(tmp_path, n=40, step_h=18.0, name="toy.csv"):
    # phase 270: the subsolar latitude starts at -1.54 deg, the sun up at the south pole
    return write_subsolar_csv(tmp_path / name, toy_lunar_subsolar(n, step_h, phase_deg=270.0))


@pytest.mark.slow
def test_polar_pit_floor_permanently_shadowed(tmp_path):
    dem, floor, rim = _polar_pit(tmp_path)
    csv = _toy(tmp_path)
    out, rep = _run(tmp_path, dem, csv, soft=True)
    frac, soft, longest, psr = _bands(out, 4)
    assert (psr[floor] == 1).all() and (frac[floor] == 0).all()
    assert (psr[rim] == 0).all() and (frac[rim] > 0.5).all()
    hours = read_subsolar(csv).durations_h().sum()
    np.testing.assert_allclose(longest[floor], hours, rtol=1e-9)
    assert (longest[rim] < hours).all()
    assert (soft >= 0).all() and (soft <= 1).all()
    assert (soft[floor] < 1e-6).all()
    assert rep["permanently_shadowed_cells"] == int((psr == 1).sum())


@pytest.mark.slow
def test_height_above_ground_lights_more(tmp_path):
    dem, floor, rim = _polar_pit(tmp_path)
    csv = _toy(tmp_path)
    base, _ = _run(tmp_path, dem, csv)
    up, _ = _run(tmp_path, dem, csv, name="up.tif", height_above_ground=450.0)
    f0, f1 = read_band(base, 1), read_band(up, 1)
    assert (f1 >= f0 - 1e-7).all()
    pit = ~rim & (f0 < 1)
    assert (f1[floor | pit] > f0[floor | pit]).any()
    assert read_band(up, 3).sum() < read_band(base, 3).sum()


@pytest.mark.slow
@pytest.mark.parametrize("curvature", [True, False])
def test_windows_equal_memory(tmp_path, curvature):
    dem, _, _ = _polar_pit(tmp_path, n=200, rough=300.0)
    csv = _toy(tmp_path, n=12, step_h=40.0)
    mem, _ = _run(tmp_path, dem, csv, soft=True, curvature=curvature)
    win, rep = _run(tmp_path, dem, csv, name="win.tif", soft=True, curvature=curvature,
                    window_size="64x80")
    assert rep["windows"] == 12
    for i in range(4):
        np.testing.assert_array_equal(read_band(win, i + 1), read_band(mem, i + 1))


@pytest.mark.slow
def test_dask_equals_local(tmp_path):
    """The times cut into chunks across Dask tasks (3 chunks, windows too), combined in time
    order: bit for bit the local run."""
    pytest.importorskip("distributed")
    dem, _, _ = _polar_pit(tmp_path, n=120, rough=300.0)
    csv = _toy(tmp_path, n=14, step_h=30.0)
    mem, _ = _run(tmp_path, dem, csv, soft=True)
    d1, rep = _run(tmp_path, dem, csv, name="d1.tif", soft=True, scheduler="local:2", chunks=3)
    assert rep["scheduler"] == "local:2"
    d2, _ = _run(tmp_path, dem, csv, name="d2.tif", soft=True, scheduler="local:2", chunks=4,
                 window_size=64)
    for d in (d1, d2):
        for i in range(4):
            np.testing.assert_allclose(read_band(d, i + 1), read_band(mem, i + 1), rtol=1e-6,
                                       atol=1e-9)


def test_combine_is_associative():
    from hillshade_rt.algorithms.illumination import accumulate, combine
    rng = np.random.default_rng(3)
    masks = rng.integers(0, 2, (9, 5, 7)).astype(np.uint8)
    masks[:, 0, 0] = 255
    dts = rng.uniform(0.5, 3, 9)

    def sums(ms, ds):
        s = {"lit": np.zeros((5, 7)), "soft": None, "start": np.zeros((5, 7)),
             "end": np.zeros((5, 7)), "longest": np.zeros((5, 7)),
             "dark": np.ones((5, 7), np.uint8)}
        for m, d in zip(ms, ds):
            accumulate(m, float(d), s["lit"], s["start"], s["end"], s["longest"], s["dark"])
        return s
    whole = sums(masks, dts)
    parts = [sums(masks[a:b], dts[a:b]) for a, b in ((0, 2), (2, 3), (3, 7), (7, 9))]
    left = combine(combine(combine(parts[0], parts[1]), parts[2]), parts[3])
    right = combine(parts[0], combine(parts[1], combine(parts[2], parts[3])))
    for k in ("lit", "start", "end", "longest", "dark"):
        np.testing.assert_allclose(left[k], whole[k])
        np.testing.assert_allclose(right[k], whole[k])
    # the plain-Python longest run
    for r in range(5):
        for c in range(7):
            best = run = 0.0
            for m, d in zip(masks[:, r, c], dts):
                run = run + d if m == 1 else 0.0
                best = max(best, run)
            assert abs(whole["longest"][r, c] - best) < 1e-12


@pytest.mark.parametrize("text,words", [
    ("time,lat\n2027-01-01T00:00:00Z,1\n2027-01-01T06:00:00Z,1\n", "lon"),
    ("time,lat,lon\n2027-01-01T06:00:00Z,1,2\n2027-01-01T00:00:00Z,1,3\n", "increas"),
])
def test_bad_series_one_line_nothing_written(tmp_path, runner, text, words):
    dem, _ = _flat_geographic(tmp_path, shape=(8, 8))
    csv = tmp_path / "bad.csv"
    csv.write_text(text)
    out = tmp_path / "o.tif"
    rep = tmp_path / "r.json"
    r = runner.invoke(cli, ["illumination", dem, str(out), "--subsolar-file", str(csv),
                            "--report", str(rep)])
    assert r.exit_code == 1, r.output
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert len(lines) == 1 and words in lines[0].lower() and "bad.csv" in lines[0]
    assert "Traceback" not in r.output
    assert sorted(os.listdir(tmp_path)) == sorted(["bad.csv", "flat.tif"])


def test_cli_report_and_bands(tmp_path, runner):
    dem, _, _ = _polar_pit(tmp_path, n=64)
    csv = _toy(tmp_path, n=6)
    out, rep = tmp_path / "o.tif", tmp_path / "r.json"
    png = tmp_path / "p.png"
    r = runner.invoke(cli, ["illumination", dem, str(out), "--subsolar-file", csv, "--soft",
                            "--report", str(rep), "--preview", str(png)])
    assert r.exit_code == 0, r.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "6 subsolar positions" in r.output
    import rasterio
    with rasterio.open(out) as ds:
        assert ds.count == 4 and ds.dtypes[0] == "float32"
        assert ds.descriptions[0].startswith("fraction of the time lit")
        assert ds.descriptions[3].startswith("permanently shadowed")
        assert "SUBSOLAR_FILE" in ds.tags()
    j = json.loads(rep.read_text())
    assert j["times"] == 6 and j["bands"] == ["fraction_lit", "soft_mean", "longest_shadow_h",
                                             "permanent_shadow"]
    # the series is an input: it cannot be the output
    r = runner.invoke(cli, ["illumination", dem, csv, "--subsolar-file", csv, "--overwrite"])
    assert r.exit_code != 0 and "Traceback" not in r.output
    h = runner.invoke(cli, ["illumination", "--help"])
    assert h.exit_code == 0 and "--subsolar-file" in h.output


@pytest.mark.slow
def test_gpu_backend_equals_cpu(tmp_path):
    """--backend gpu (here numba's CUDA simulator; a real device with NUMBA_ENABLE_CUDASIM=0):
    the CUDA twins' masks folded into the same sums, equal to the CPU run band for band."""
    from hillshade_rt.run.config import RunOptions
    dem, _, _ = _polar_pit(tmp_path, n=24, rough=300.0)
    csv = _toy(tmp_path, n=5, step_h=60.0)
    cpu, rep_c = _run(tmp_path, dem, csv, soft=True, run=RunOptions(quiet=True, backend="cpu"))
    gpu, rep_g = _run(tmp_path, dem, csv, name="g.tif", soft=True,
                      run=RunOptions(quiet=True, backend="gpu"))
    assert rep_c["backend"] == "cpu" and rep_g["backend"] == "gpu"
    assert rep_g["positions"]["marched"] > 0
    for i in range(4):
        np.testing.assert_allclose(read_band(gpu, i + 1), read_band(cpu, i + 1), rtol=1e-6,
                                   atol=1e-9)
    assert 0 < np.nanmean(read_band(cpu, 1)) < 1
