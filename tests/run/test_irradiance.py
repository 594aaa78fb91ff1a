"""``hillshade-rt irradiance`` and ``arrays.irradiance`` (issue 20, item 4): beam, diffuse,
reflected and global irradiance on terrain, checked against pvlib's plane-of-array irradiance
on open planes (where the sky view factor is (1 + cos S) / 2), against an independent assembly
from ``arrays.shadow_mask`` masks under cast shadows, and through the command line (periods,
units, measured series, errors)."""

import datetime as dt
import json
import math
import os

import numpy as np
import pandas as pd
import pvlib
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.engine.arrays import horizon_angles, irradiance, shadow_mask
from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.solar import Atmosphere, disk_fraction, solar_position
from hillshade_rt.model.times import day_samples, zone
from hillshade_rt.testing import box_terrain, fractal_terrain, read_band, repo_root, write_geotiff

# pvlib 0.16 asks pandas 3 for DatetimeIndex.dayofyear (deprecated there), inside pvlib
pytestmark = pytest.mark.filterwarnings("ignore:DatetimeIndex.dayofyear:DeprecationWarning")

LAT, LON, ALT = 34.3, -118.2, 500.0
LA = zone("America/Los_Angeles")
BANDS = ("beam", "diffuse", "reflected", "global")
EXAMPLE = os.path.join(repo_root(), "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif")


def _plane(slope_deg, aspect_deg, n=40, d=10.0):
    """A plane of ``slope_deg`` facing (descending toward) ``aspect_deg``, north-up."""
    s, a = math.tan(math.radians(slope_deg)), math.radians(aspect_deg)
    x = np.arange(n)[None, :] * d            # east
    y = -np.arange(n)[:, None] * d           # north (row 0 the northern edge)
    z = -s * (x * math.sin(a) + y * math.cos(a))
    return (z - z.min() + 100.0).astype(np.float32)


def _pvlib_sky(times, lat=LAT, lon=LON, alt=ALT):
    """pvlib's own solar position (SPA) and Ineichen clear sky at ``times``: independent of
    the project's code path."""
    idx = pd.DatetimeIndex([pd.Timestamp(t) for t in times]).tz_convert("UTC")
    sp = pvlib.solarposition.get_solarposition(idx, lat, lon, altitude=alt, temperature=12.0)
    cs = pvlib.location.Location(lat, lon, altitude=alt).get_clearsky(idx, solar_position=sp)
    return idx, sp, cs


def _day(date=dt.date(2026, 6, 21), step="15min"):
    return day_samples(date, date, step, LA, LON)


# ---------------------------------------------------------------------------------------------
# open planes: pvlib's plane-of-array irradiance

@pytest.mark.slow
@pytest.mark.parametrize("slope, aspect", [(0.0, 0.0), (25.0, 163.0), (40.0, 290.0)])
def test_open_plane_equals_pvlib_isotropic(slope, aspect):
    """Flat, 25 deg facing 163 and 40 deg facing 290: every band at every time of a day equals
    pvlib.irradiance.get_total_irradiance (isotropic) with pvlib's own SPA position and
    Ineichen sky, and so does each day's energy. (On a plane Dozier's Vd over 32 directions
    equals (1 + cos S)/2 to float precision: the sum over directions of its smooth integrand
    is exact, so the tolerance stays tight: the suns differ by ~1e-4 deg.)"""
    times, w = _day()
    idx, sp, cs = _pvlib_sky(times)
    z = _plane(slope, aspect)
    per = irradiance(z, times, 10.0, lat=LAT, lon=LON, altitude=ALT, curvature=False)
    tot = pvlib.irradiance.get_total_irradiance(slope, aspect, sp["apparent_zenith"],
                                                sp["azimuth"], cs["dni"], cs["ghi"], cs["dhi"],
                                                albedo=0.2, model="isotropic")
    inner = (slice(None), slice(2, -2), slice(2, -2))
    energy = irradiance(z, times, 10.0, lat=LAT, lon=LON, altitude=ALT, curvature=False,
                        weights=w)
    for ours, theirs in zip(BANDS, ("poa_direct", "poa_sky_diffuse", "poa_ground_diffuse",
                                    "poa_global")):
        want = tot[theirs].to_numpy()
        got = per[ours][inner]
        assert got.shape[0] == len(times)
        np.testing.assert_allclose(got, np.broadcast_to(want[:, None, None], got.shape),
                                   rtol=1e-4, atol=0.02, err_msg=ours)
        e = float(np.dot(w, want))
        np.testing.assert_allclose(energy[ours][2:-2, 2:-2], e, rtol=2e-4, err_msg=ours)
    assert float(np.dot(w, tot["poa_global"])) > 5000.0       # a clear summer day, Wh/m2
    if slope == 0.0:
        np.testing.assert_allclose(energy["reflected"], 0.0, atol=1e-3)
    else:
        assert energy["reflected"][2:-2, 2:-2].min() > 10.0


def test_open_plane_equals_pvlib_perez():
    """With --perez, the sky diffuse (and the global) on an open 25-degree plane facing 163
    is pvlib's Perez (1990, allsitescomposite1990) at every time: the terrain's changes
    (isotropic part times Vd, horizon band times Vd / ((1 + cos S)/2), circumsolar part
    shadowed) all vanish on an open plane."""
    times, w = _day(dt.date(2026, 3, 20), "20min")
    idx, sp, cs = _pvlib_sky(times)
    per = irradiance(_plane(25.0, 163.0), times, 10.0, lat=LAT, lon=LON, altitude=ALT,
                     curvature=False, perez=True)
    tot = pvlib.irradiance.get_total_irradiance(
        25.0, 163.0, sp["apparent_zenith"], sp["azimuth"], cs["dni"], cs["ghi"], cs["dhi"],
        dni_extra=pvlib.irradiance.get_extra_radiation(idx), albedo=0.2, model="perez")
    inner = (slice(None), slice(2, -2), slice(2, -2))
    for ours, theirs in (("diffuse", "poa_sky_diffuse"), ("global", "poa_global")):
        want = tot[theirs].to_numpy()
        got = per[ours][inner]
        np.testing.assert_allclose(got, np.broadcast_to(want[:, None, None], got.shape),
                                   rtol=1e-4, atol=0.02, err_msg=ours)
    iso = pvlib.irradiance.get_total_irradiance(
        25.0, 163.0, sp["apparent_zenith"], sp["azimuth"], cs["dni"], cs["ghi"], cs["dhi"],
        albedo=0.2)["poa_sky_diffuse"].to_numpy()
    assert abs(float(np.dot(w, tot["poa_sky_diffuse"])) - float(np.dot(w, iso))) > 50.0


# ---------------------------------------------------------------------------------------------
# cast shadows

def _box():
    """A 60 m block on a plain of 5 m cells (300 m across: Earth curvature off either way)."""
    return box_terrain(60, 60, 60.0, 24, 34, 26, 36)


def _flat_cells(z):
    """Cells whose 3x3 neighbourhood is all at the plain's height: cos i = sin(elevation)."""
    from numpy.lib.stride_tricks import sliding_window_view
    win = sliding_window_view(np.pad(z, 1, mode="edge"), (3, 3))
    return (win == 0.0).all(axis=(2, 3))


@pytest.mark.slow
def test_beam_under_cast_shadows_is_the_masks_sum():
    """On a block at 46 N at the winter solstice (suns at non-special azimuths all day), the
    beam energy of every flat cell equals the sum over the day of DNI sin(E) (1 - mask) with
    the masks of arrays.shadow_mask for the same suns (the SPA's, assembled here); a cell in
    the block's shadow at 14:50 gets no beam then but its diffuse light, reduced by the block
    it sees (Vd < 1), and some light the block reflects."""
    lat, lon, alt = 46.0, 7.5, 0.0
    zurich = zone("Europe/Zurich")
    times, w = day_samples(dt.date(2026, 12, 21), dt.date(2026, 12, 21), "20min", zurich, lon)
    z = _box()
    energy = irradiance(z, times, 5.0, lat=lat, lon=lon, altitude=alt, curvature=False,
                        weights=w)
    az, el, zen = solar_position(times, lat, lon, alt, Atmosphere())
    pos = pd.DataFrame({"apparent_zenith": zen, "zenith": zen, "apparent_elevation": el},
                       index=pd.DatetimeIndex([pd.Timestamp(t) for t in times]).tz_convert("UTC"))
    dni = pvlib.location.Location(lat, lon, altitude=alt).get_clearsky(
        pos.index, solar_position=pos)["dni"].to_numpy()
    want = np.zeros(z.shape)
    shadowed_somewhere = np.zeros(z.shape, bool)
    for k in range(len(times)):
        if el[k] <= 0 or dni[k] <= 0:
            continue
        mask = shadow_mask(z, az[k], el[k], 5.0, curvature=False)
        want += w[k] * dni[k] * math.sin(math.radians(el[k])) * (mask == 0)
        shadowed_somewhere |= mask == 1
    flat = _flat_cells(z)
    assert (flat & shadowed_somewhere).sum() > 100     # shadows on the flat cells checked
    np.testing.assert_allclose(energy["beam"][flat], want[flat], rtol=1e-5, atol=1e-3)
    assert energy["beam"][flat & shadowed_somewhere].min() < 0.8 * want[flat].max()

    # one time: 14:50 local, the sun low in the south-west
    k = next(i for i, t in enumerate(times) if (t.hour, t.minute) == (14, 50))
    assert 200.0 < az[k] < 240.0 and 0.0 < el[k] < 20.0
    mask = shadow_mask(z, az[k], el[k], 5.0, curvature=False)
    per = irradiance(z, [times[k]], 5.0, lat=lat, lon=lon, altitude=alt, curvature=False)
    dark = flat & (mask == 1)
    assert dark.sum() > 20
    assert (per["beam"][0][dark] == 0.0).all()
    assert (per["beam"][0][flat & (mask == 0)] > 50.0).all()
    dhi = per["diffuse"][0][flat & (mask == 0)].max()          # far from the block: ~DHI
    assert (per["diffuse"][0][dark] > 0.5 * dhi).all()
    assert (per["diffuse"][0][dark] < dhi).all()              # the block hides some sky
    assert (per["reflected"][0][dark] > 0.0).all()
    np.testing.assert_allclose(per["global"][0], per["beam"][0] + per["diffuse"][0]
                               + per["reflected"][0], rtol=1e-6)


@pytest.mark.slow
def test_soft_beam_is_the_visible_fraction_of_the_disk():
    """With soft, the beam on a flat cell is DNI sin(E) times the visible fraction of the solar
    disk above the cell's horizon toward the sun (arrays.horizon_angles, solar.disk_fraction):
    0..1 in the penumbra, where the hard beam is all or nothing."""
    lat, lon, alt = 46.0, 7.5, 0.0
    z = box_terrain(60, 60, 20.0, 45, 55, 5, 15)     # a block near the south-west corner
    t = dt.datetime(2026, 12, 21, 15, 50, tzinfo=zone("Europe/Zurich"))  # the sun ~7 deg up
    az, el, zen = solar_position([t], lat, lon, alt, Atmosphere())
    assert 220.0 < az[0] < 240.0 and 5.0 < el[0] < 9.0
    soft = irradiance(z, [t], 5.0, lat=lat, lon=lon, altitude=alt, curvature=False, soft=True)
    hard = irradiance(z, [t], 5.0, lat=lat, lon=lon, altitude=alt, curvature=False)
    flat = _flat_cells(z)
    full = hard["beam"][0][flat & (shadow_mask(z, az[0], el[0], 5.0, curvature=False) == 0)]
    dni_sin = float(full.max())
    assert np.ptp(full) < 1e-3 * dni_sin
    f = disk_fraction(horizon_angles(z, az[0], 5.0, curvature=False), el[0])
    np.testing.assert_allclose(soft["beam"][0][flat], (dni_sin * f)[flat], atol=1e-3 * dni_sin)
    penumbra = flat & (f > 0.01) & (f < 0.99)
    assert penumbra.sum() >= 3


@pytest.mark.slow
def test_gpu_backend_gives_the_cpu_bands():
    """backend="gpu" (the cast shadows and Vd's horizon scans as CUDA kernels; numba's CUDA
    simulator here, the device with NUMBA_ENABLE_CUDASIM=0): the CPU's bands, a void
    included."""
    z = fractal_terrain(14, 16, 3, relief=120.0)
    z[5, 6] = np.nan
    ts = [dt.datetime(2026, 6, 21, h, 20, tzinfo=dt.timezone.utc) for h in (15, 19, 23)]
    kw = dict(lat=LAT, lon=LON, sky_view_directions=8, weights=[0.5, 1.0, 1.5], perez=True)
    g = irradiance(z, ts, 10.0, backend="gpu", **kw)
    c = irradiance(z, ts, 10.0, backend="cpu", **kw)
    for k in BANDS:
        np.testing.assert_allclose(g[k], c[k], rtol=1e-6, atol=1e-4, err_msg=k)
        assert np.isnan(c[k][5, 6]) and np.isfinite(np.delete(c[k].ravel(), 5 * 16 + 6)).all()
    assert np.nanmax(c["beam"]) > 500.0 and np.nanmin(c["beam"]) < 0.5 * np.nanmax(c["beam"])


def test_array_api_checks_its_arguments():
    z = _plane(10.0, 200.0, n=8)
    t = dt.datetime(2026, 6, 21, 12, tzinfo=dt.timezone.utc)
    for kw, words in (({}, "lat and lon"),
                      ({"lat": LAT, "lon": LON, "mean": True}, "mean needs weights"),
                      ({"lat": LAT, "lon": LON, "albedo": -0.1}, "--albedo"),
                      ({"lat": LAT, "lon": LON, "weights": [1.0, 2.0]}, "one number"),
                      ({"lat": LAT, "lon": LON, "clear_sky": "solis"}, "--clear-sky")):
        with pytest.raises(HillshadeError, match=words):
            irradiance(z, [t], 10.0, **kw)
    with pytest.raises(HillshadeError, match="aware"):
        irradiance(z, [dt.datetime(2026, 6, 21, 12)], 10.0, lat=LAT, lon=LON)


# ---------------------------------------------------------------------------------------------
# the command line

UTM11 = CRS.from_epsg(32611)


def _dem(tmp_path, z, name="dem.tif", d=30.0):
    return write_geotiff(tmp_path / name, np.asarray(z, np.float32),
                         Affine(d, 0, 400000.0, 0, -d, 3800000.0), UTM11)


def _run(runner, args):
    r = runner.invoke(cli, ["irradiance"] + [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return r


def _tags(path):
    with rasterio.open(path) as ds:
        return ds.tags(), ds.descriptions, ds.count, ds.nodata


@pytest.mark.slow
def test_mean_is_energy_over_the_period_hours(tmp_path, runner):
    """--mean divides the energy by the period's hours (23 on the day the clocks spring
    forward in America/Los_Angeles); bands, descriptions, units and tags say what they are."""
    dem = _dem(tmp_path, fractal_terrain(40, 40, 5, relief=300.0))
    e, m = tmp_path / "e.tif", tmp_path / "m.tif"
    common = ["--date", "2026-03-08", "--tz", "America/Los_Angeles", "--step", "30min", "-q",
              "--skyview-directions", "16"]
    _run(runner, [dem, e, "--report", tmp_path / "e.json"] + common)
    _run(runner, [dem, m, "--mean"] + common)
    te, desc, count, nodata = _tags(e)
    tm, mdesc = _tags(m)[:2]
    # one day's Wh/m2 is r.sun's mode 2 product: its names; the mean W/m2 is not: ours; the
    # band tags NAME keep ours, RSUN_NAME r.sun's, either way
    assert count == 4 and desc == ("beam_rad", "diff_rad", "refl_rad", "glob_rad")
    assert mdesc == BANDS and nodata == -9999.0
    with rasterio.open(e) as ds:
        assert [ds.tags(b)["NAME"] for b in range(1, 5)] == list(BANDS)
        assert ds.tags(4)["RSUN_NAME"] == "glob_rad" and ds.tags(4)["UNITS"] == "Wh/m2"
    with rasterio.open(m) as ds:
        assert ds.tags(2)["NAME"] == "diffuse" and ds.tags(2)["RSUN_NAME"] == "diff_rad"
    assert te["PERIOD_HOURS"] == tm["PERIOD_HOURS"] == "23"
    assert te["UNITS"].startswith("Wh/m2") and tm["UNITS"].startswith("W/m2")
    for key in ("PERIOD", "STEP", "CLEAR_SKY", "TURBIDITY", "ALBEDO", "DEFINITIONS"):
        assert te[key], key
    assert te["CLEAR_SKY"] == "ineichen" and "climatological" in te["TURBIDITY"]
    for b in range(1, 5):
        ev, mv = read_band(e, b), read_band(m, b)
        np.testing.assert_allclose(mv * 23.0, ev, rtol=1e-5, atol=1e-3)
    g = read_band(e, 4)
    np.testing.assert_allclose(g, read_band(e, 1) + read_band(e, 2) + read_band(e, 3),
                               rtol=1e-5)
    rep = json.loads((tmp_path / "e.json").read_text())
    assert rep["period_hours"] == 23.0 and rep["samples"] == 46
    assert rep["bands"]["global"]["max"] == pytest.approx(float(g.max()), rel=1e-6)


def test_night_gives_no_beam(tmp_path, runner):
    """A period in the night (--start/--end): no beam, no shadows computed, and the clear sky
    gives no diffuse either."""
    dem = _dem(tmp_path, fractal_terrain(30, 30, 2, relief=200.0))
    out, rep = tmp_path / "n.tif", tmp_path / "n.json"
    _run(runner, [dem, out, "--start", "2026-06-21T00:30-07:00", "--end",
                  "2026-06-21T03:30-07:00", "-q", "--report", rep])
    for b in range(1, 5):
        assert (read_band(out, b) == 0.0).all()
    doc = json.loads(rep.read_text())
    assert doc["samples"] == 12 and doc["samples_with_shadows"] == 0
    assert doc["period_hours"] == 3.0


@pytest.mark.slow
def test_tz_auto_is_the_dem_zone(tmp_path, runner):
    """--tz auto (the DEM is in UTM 11N at 34.3 N: America/Los_Angeles): local --start/--end
    read there after the DEM, and --date's days run there; the same as naming the zone."""
    dem = _dem(tmp_path, fractal_terrain(24, 24, 3, relief=200.0))
    reps = {}
    for tz in ("auto", "America/Los_Angeles"):
        for kind, extra in (("period", ["--start", "2026-06-21T09:00", "--end",
                                        "2026-06-21T11:00", "--step", "1h"]),
                            ("day", ["--date", "2026-11-01", "--step", "2h"])):
            rep = tmp_path / f"{kind}{len(reps)}.json"
            _run(runner, [dem, tmp_path / f"{kind}{len(reps)}.tif", "--tz", tz, "-q",
                          "--skyview-directions", "8", "--report", rep] + extra)
            reps[tz, kind] = json.loads(rep.read_text())
    for kind in ("period", "day"):
        a, b = reps["auto", kind], reps["America/Los_Angeles", kind]
        assert (a["period"], a["period_hours"], a["samples"]) == \
            (b["period"], b["period_hours"], b["samples"]), kind
    assert reps["auto", "period"]["period"].startswith("2026-06-21T09:00-07:00")
    assert reps["auto", "day"]["period_hours"] == 25.0      # clocks go back on 1 November


def _write_csv(path, rows, header="time,ghi,dni,dhi"):
    path.write_text(header + "\n" + "\n".join(",".join(str(v) for v in r) for r in rows) + "\n")
    return path


def test_measured_series_gives_its_values(tmp_path, runner):
    """--ghi FILE.csv: on a flat DEM the diffuse band is the sum of the series' DHI at the
    samples (linear in time between its rows), the beam that of DNI sin(E) with the sun up,
    nothing reflected; with GHI alone, DNI and DHI come from Erbs (said in the tags)."""
    z = np.full((12, 12), 800.0, np.float32)
    dem = _dem(tmp_path, z)
    hours = np.arange(0, 25)
    ghi = np.clip(900 * np.sin(np.pi * (hours - 5) / 15.0), 0, None).round(1)
    dni = (0.8 * ghi).round(1)
    dhi = (0.2 * ghi + 5).round(1)
    rows = [(f"2026-06-21T{h:02d}:00Z" if h < 24 else "2026-06-22T00:00Z", g, n, f)
            for h, g, n, f in zip(hours, ghi, dni, dhi)]
    csv = _write_csv(tmp_path / "sky.csv", rows)
    out, rep = tmp_path / "m.tif", tmp_path / "m.json"
    _run(runner, [dem, out, "--date", "2026-06-21", "--tz", "UTC", "--ghi", csv, "-q",
                  "--report", rep])
    doc = json.loads(rep.read_text())
    t0 = dt.datetime(2026, 6, 21, tzinfo=dt.timezone.utc)
    times = [t0 + dt.timedelta(minutes=7.5 + 15 * k) for k in range(96)]
    th = np.array([(t - t0).total_seconds() / 3600.0 for t in times])
    site = doc["site"]
    az, el, zen = solar_position(times, site["latitude"], site["longitude"], site["height_m"],
                                 Atmosphere())
    w = 0.25
    want_diffuse = w * np.interp(th, hours, dhi).sum()
    want_beam = w * (np.interp(th, hours, dni) * np.sin(np.radians(el)) * (el > 0)).sum()
    np.testing.assert_allclose(read_band(out, 2), want_diffuse, rtol=1e-5)
    np.testing.assert_allclose(read_band(out, 1), want_beam, rtol=1e-5)
    assert (read_band(out, 3) == 0.0).all()
    tags = _tags(out)[0]
    assert "sky.csv" in tags["SKY"] and "CLEAR_SKY" not in tags and "SPLIT" not in tags
    # GHI alone: Erbs
    csv1 = _write_csv(tmp_path / "ghi.csv", [(r[0], r[1]) for r in rows], "Time, GHI")
    out1 = tmp_path / "g.tif"
    _run(runner, [dem, out1, "--date", "2026-06-21", "--tz", "UTC", "--ghi", csv1, "-q"])
    split = pvlib.irradiance.erbs(np.interp(th, hours, ghi), zen,
                                  np.full(len(times), pd.Timestamp("2026-06-21").day_of_year))
    np.testing.assert_allclose(read_band(out1, 2), w * np.nansum(split["dhi"]), rtol=1e-5)
    assert "Erbs" in _tags(out1)[0]["SPLIT"]


def _one_line(r, code, words):
    assert r.exit_code == code, (r.exit_code, r.output)
    assert words in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "Traceback" not in r.output


@pytest.mark.parametrize("extra, code, words", [
    (["--date", "2026-06-21", "--end-date", "2026-06-20"], 2, "--end-date is before --date"),
    (["--date", "2026-06-21", "--clear-sky", "solis"], 2, "--clear-sky"),
    (["--date", "2026-06-21", "--albedo", "-0.2"], 2, "--albedo must be between 0 and 1"),
    (["--date", "2026-06-21", "--linke-turbidity", "0"], 2, "--linke-turbidity"),
    (["--date", "2026-06-21", "--clear-sky", "haurwitz", "--linke-turbidity", "3"], 2,
     "Haurwitz"),
    (["--date", "2026-06-21", "--start", "2026-06-21T06:00Z", "--end", "2026-06-21T08:00Z"],
     2, "give the period one way"),
    ([], 2, "give the period one way"),
    (["--end-date", "2026-06-21"], 2, "--end-date goes with --date"),
    (["--start", "2026-06-21T06:00Z"], 2, "--start and --end go together"),
    (["--start", "2026-06-21T08:00Z", "--end", "2026-06-21T06:00Z"], 2, "is not after"),
    (["--start", "2026-06-21T08:00", "--end", "2026-06-21T09:00Z"], 2, "no UTC offset"),
    (["--date", "2026-06-21", "--step", "0s"], 2, "at least one second"),
])
def test_bad_options_are_one_line_usage_errors(tmp_path, runner, extra, code, words):
    dem = _dem(tmp_path, fractal_terrain(20, 20, 1))
    before = sorted(os.listdir(tmp_path))
    r = runner.invoke(cli, ["irradiance", dem, str(tmp_path / "o.tif")] + extra)
    _one_line(r, code, words)
    assert sorted(os.listdir(tmp_path)) == before


def test_bad_series_fail_the_run_with_one_line(tmp_path, runner):
    """A CSV without a time or ghi column, with a value that is no number, or not covering the
    period: exit status 1, one line, nothing written; --ghi with --clear-sky: 2."""
    dem = _dem(tmp_path, fractal_terrain(20, 20, 1))
    cases = [
        (_write_csv(tmp_path / "a.csv", [("2026-06-21T00:00Z", 1), ("2026-06-22T00:00Z", 2)],
                    "when,ghi"), 1, "no time column"),
        (_write_csv(tmp_path / "b.csv", [("2026-06-21T00:00Z", 1), ("2026-06-22T00:00Z", 2)],
                    "time,global"), 1, "no ghi column"),
        (_write_csv(tmp_path / "c.csv", [("2026-06-21T00:00Z", 1), ("2026-06-22T00:00Z", "x")],
                    "time,ghi"), 1, "line 3: ghi 'x'"),
        (_write_csv(tmp_path / "d.csv", [("2026-06-21T06:00Z", 1), ("2026-06-21T20:00Z", 2)],
                    "time,ghi"), 1, "give a series that covers the period"),
        (_write_csv(tmp_path / "e.csv", [("2026-06-21T00:00Z", 1, 1), ("2026-06-22T00:00Z", 2, 2)],
                    "time,ghi,dni"), 1, "both dni and dhi"),
        (_write_csv(tmp_path / "f.csv", [("2026-06-21T00:00", 1), ("2026-06-22T00:00", 2)],
                    "time,ghi"), 1, "f.csv line 2: time '2026-06-21T00:00' has no UTC offset"),
        (_write_csv(tmp_path / "g.csv", [("2026-06-22T00:00Z", 1), ("2026-06-21T00:00Z", 2)],
                    "time,ghi"), 1, "times must increase"),
    ]
    before = sorted(os.listdir(tmp_path))
    for csv, code, words in cases:      # (local times without --tz: no offset to read them)
        tz = [] if csv.name == "f.csv" else ["--tz", "UTC"]
        r = runner.invoke(cli, ["irradiance", dem, str(tmp_path / "o.tif"), "--date",
                                "2026-06-21", "--ghi", str(csv)] + tz)
        _one_line(r, code, words)
    r = runner.invoke(cli, ["irradiance", dem, str(tmp_path / "o.tif"), "--date", "2026-06-21",
                            "--ghi", str(cases[0][0]), "--clear-sky", "haurwitz"])
    _one_line(r, 2, "do not go with it")
    r = runner.invoke(cli, ["irradiance", dem, str(tmp_path / "o.tif"), "--date", "2026-06-21",
                            "--ghi", str(tmp_path / "missing.csv")])
    _one_line(r, 1, "no such file")
    assert sorted(os.listdir(tmp_path)) == before


def test_one_band_formats_are_refused_before_any_work(tmp_path, runner):
    dem = _dem(tmp_path, fractal_terrain(20, 20, 1))
    before = sorted(os.listdir(tmp_path))
    for name in ("o.png", "o.jpg", "o.asc"):
        r = runner.invoke(cli, ["irradiance", dem, str(tmp_path / name), "--date",
                                "2026-06-21"])
        _one_line(r, 1, "irradiance writes 4 float32 bands")
    assert sorted(os.listdir(tmp_path)) == before


def test_a_dem_off_the_earth_or_without_a_place_fails_with_one_line(tmp_path, runner):
    moon = ('GEOGCS["Moon 2000",DATUM["D_Moon_2000",SPHEROID["Moon_2000_IAU_IAG",1737400.0,'
            '0.0]],PRIMEM["Greenwich",0],UNIT["Decimal_Degree",0.0174532925199433]]')
    dem = write_geotiff(tmp_path / "moon.tif", fractal_terrain(20, 20, 1),
                        Affine(0.01, 0, 10.0, 0, -0.01, -80.0), CRS.from_wkt(moon))
    plain = write_geotiff(tmp_path / "plain.tif", fractal_terrain(20, 20, 1))
    before = sorted(os.listdir(tmp_path))
    r = runner.invoke(cli, ["irradiance", dem, str(tmp_path / "o.tif"), "--date", "2026-06-21"])
    _one_line(r, 1, "irradiance computes the Earth's sun only")
    r = runner.invoke(cli, ["irradiance", plain, str(tmp_path / "o.tif"), "--date",
                            "2026-06-21", "--pixel-size", "30"])
    _one_line(r, 1, "give --lat and --lon")
    assert sorted(os.listdir(tmp_path)) == before
    _run(runner, [plain, tmp_path / "o.tif", "--date", "2026-06-21", "--pixel-size", "30",
                  "--lat", "46.5", "--lon", "7.5", "--step", "2h", "-q"])


@pytest.mark.slow
def test_geographic_dem_flat_gets_the_open_sky(tmp_path, runner):
    """An EPSG:4326 DEM (3 arc-second cells at 46.5 N; per-row spacing): on its flat part the
    global band is the clear sky's GHI over the day (Ineichen's DHI is GHI - DNI cos Z), the
    diffuse its DHI, and --perez and --soft run."""
    z = np.full((40, 40), 1500.0, np.float32)
    z[5:12, 25:32] = 1700.0
    tr = Affine(1 / 1200, 0, 7.5, 0, -1 / 1200, 46.5)
    dem = write_geotiff(tmp_path / "geo.tif", z, tr, CRS.from_epsg(4326))
    out, rep = tmp_path / "g.tif", tmp_path / "g.json"
    _run(runner, [dem, out, "--date", "2026-06-21", "--tz", "Europe/Zurich", "-q",
                  "--report", rep, "--linke-turbidity", "3"])
    doc = json.loads(rep.read_text())
    assert doc["site"]["latitude"] == pytest.approx(46.5 - 20 / 1200, abs=1e-3)
    assert "3 (given)" in doc["turbidity"]
    g, d = read_band(out, 4), read_band(out, 2)
    open_cells = np.zeros(z.shape, bool)
    open_cells[25:38, 2:15] = True        # far from the block (and from its shadows at noon)
    sky = doc["open_sky"]
    np.testing.assert_allclose(g[open_cells], sky["ghi_wh_m2"], rtol=2e-3)
    np.testing.assert_allclose(d[open_cells], sky["dhi_wh_m2"], rtol=2e-3)
    assert g.min() < 0.95 * sky["ghi_wh_m2"]         # cells the block shadows or faces away
    for flag in ("--perez", "--soft"):
        _run(runner, [dem, tmp_path / f"x{flag}.tif", "--date", "2026-06-21", "--step", "1h",
                      "-q", flag])


def test_the_sun_varies_across_a_wide_dem(tmp_path):
    """A flat geographic DEM 3 degrees wide in the morning: each part gets the incidence of its
    own sun (per tile, within --sun-tolerance), not the centre's: the beam across the raster
    goes as sin(E) of the SPA's sun at each cell (one DNI for the DEM), a 10 % spread."""
    from hillshade_rt.io import read_dem
    tr = Affine(0.075, 0, 6.0, 0, -0.075, 47.5)
    dem = write_geotiff(tmp_path / "wide.tif", np.full((40, 40), 400.0, np.float32), tr,
                        CRS.from_epsg(4326))
    t = dt.datetime(2026, 6, 21, 5, 0, tzinfo=dt.timezone.utc)
    beam = irradiance(read_dem(dem), [t])["beam"][0].astype(np.float64)
    rows, cols = np.meshgrid(np.arange(40), np.arange(40), indexing="ij")
    lon, lat = 6.0 + 0.075 * (cols + 0.5), 47.5 - 0.075 * (rows + 0.5)
    _, el, _ = solar_position(np.full(lon.shape, t.timestamp()), lat, lon, 400.0, Atmosphere())
    want = np.sin(np.radians(el))
    ratio = beam / want
    assert np.ptp(want) / want.mean() > 0.1
    np.testing.assert_allclose(ratio / ratio[20, 20], 1.0, rtol=5e-3)


@pytest.mark.slow
def test_the_bundled_example_runs(tmp_path, runner):
    """examples/bigtujunga (1197 x 643 SRTM, UTM 11N): four bands, voids none, the diffuse
    band between a valley's share of the sky and the open sky's DHI, the global band below
    what the best-facing slopes can get; preview and report written."""
    out, rep, png = tmp_path / "bt.tif", tmp_path / "bt.json", tmp_path / "bt.png"
    _run(runner, [EXAMPLE, out, "--date", "2026-06-21", "--tz", "America/Los_Angeles",
                  "--step", "2h", "--skyview-directions", "8", "-q", "--report", rep,
                  "--preview", png])
    doc = json.loads(rep.read_text())
    sky = doc["open_sky"]
    b, d, r, g = (read_band(out, k) for k in range(1, 5))
    assert (g > 0).all() and (g != -9999.0).all()
    assert d.max() <= sky["dhi_wh_m2"] * (1 + 1e-5) and d.min() < 0.8 * sky["dhi_wh_m2"]
    assert b.min() < 0.5 * b.max() and r.max() > 0
    assert doc["samples_with_shadows"] == doc["samples_with_sun"] > 0
    assert png.stat().st_size > 0
    assert set(doc["seconds"]) >= {"sky view", "shadows", "irradiance", "write"}


@pytest.mark.slow
def test_api_run_is_the_command_line(tmp_path, runner):
    """api.irradiance takes the command line's options as keywords (dates as date objects too)
    and writes the same bands; bad values raise HillshadeError with the same words."""
    from hillshade_rt import api
    dem = _dem(tmp_path, fractal_terrain(30, 30, 4, relief=250.0))
    _run(runner, [dem, tmp_path / "c.tif", "--date", "2026-06-21", "--tz", "America/Denver",
                  "--step", "1h", "--perez", "--albedo", "0.3", "-q"])
    rep = api.irradiance(dem, tmp_path / "a.tif", date=dt.date(2026, 6, 21),
                         tz="America/Denver", step="1h", perez=True, albedo=0.3)
    assert rep["sky_model"] == "perez" and rep["albedo"] == 0.3
    for b in range(1, 5):
        np.testing.assert_array_equal(read_band(tmp_path / "a.tif", b),
                                      read_band(tmp_path / "c.tif", b))
    with pytest.raises(HillshadeError, match="albedo") as e:
        api.irradiance(dem, tmp_path / "x.tif", date="2026-06-21", albedo=1.5)
    assert "--albedo" not in str(e.value)
    assert not (tmp_path / "x.tif").exists()


def test_no_output_may_be_the_ghi_series(tmp_path, runner):
    """The --ghi series is an input: naming it as OUTPUT or --report (also through another
    spelling of its path) is a usage error, the series untouched."""
    dem = _dem(tmp_path, fractal_terrain(20, 20, 1))
    csv = _write_csv(tmp_path / "sky.csv", [("2026-06-21T12:00Z", 800.0, 700.0, 100.0)])
    before = csv.read_bytes()
    for args in (["-q", str(csv)], [str(tmp_path / "o.tif"), "--report",
                                    str(tmp_path / "." / "sky.csv")]):
        r = runner.invoke(cli, ["irradiance", dem] + args + ["--date", "2026-06-21",
                                                             "--ghi", str(csv), "--overwrite"])
        _one_line(r, 2, "is also an input")
        assert csv.read_bytes() == before


@pytest.mark.slow
def test_clear_sky_indices_scale_the_beam_and_the_diffuse(tmp_path, runner):
    """r.sun's real sky (--beam-index kb, --diffuse-index kd: its coeff_bh, coeff_dh) on an
    open plane of 25° facing 163°: the beam is kb times the clear sky's, the diffuse kd times,
    the reflected light the real sky's global horizontal kb (GHI - DHI) + kd DHI times the
    same albedo and view factor; index 0 leaves no beam and computes no shadow."""
    dem = _dem(tmp_path, _plane(25.0, 163.0, n=30), d=10.0)
    common = ["--date", "2026-06-21", "--tz", "America/Los_Angeles", "--step", "30min", "-q",
              "--skyview-directions", "16"]
    p, k, z = tmp_path / "p.tif", tmp_path / "k.tif", tmp_path / "z.tif"
    _run(runner, [dem, p, "--report", tmp_path / "p.json"] + common)
    _run(runner, [dem, k, "--beam-index", "0.37", "--diffuse-index", "0.71", "--report",
                  tmp_path / "k.json"] + common)
    _run(runner, [dem, z, "--beam-index", "0", "--report", tmp_path / "z.json"] + common)
    pb = [read_band(p, b).astype(np.float64) for b in range(1, 5)]
    kb = [read_band(k, b).astype(np.float64) for b in range(1, 5)]
    sky = json.loads((tmp_path / "p.json").read_text())["open_sky"]
    g, d = sky["ghi_wh_m2"], sky["dhi_wh_m2"]
    assert pb[0].min() > 1000.0 and pb[2].min() > 10.0          # sunlit, reflecting
    np.testing.assert_allclose(kb[0], 0.37 * pb[0], rtol=1e-6)
    np.testing.assert_allclose(kb[1], 0.71 * pb[1], rtol=1e-6)
    np.testing.assert_allclose(kb[2], pb[2] * (0.37 * (g - d) + 0.71 * d) / g, rtol=1e-6)
    rep = json.loads((tmp_path / "k.json").read_text())
    assert rep["beam_index"] == 0.37 and rep["diffuse_index"] == 0.71
    assert rep["open_sky"]["dhi_wh_m2"] == pytest.approx(0.71 * d, rel=1e-12)
    assert np.all(read_band(z, 1) == 0.0)
    np.testing.assert_array_equal(read_band(z, 2), read_band(p, 2))
    assert json.loads((tmp_path / "z.json").read_text())["samples_with_shadows"] == 0
