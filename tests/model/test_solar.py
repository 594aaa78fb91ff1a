"""The solar position (NREL's SPA through pvlib: the report's worked example, refraction) and
sun hours' samples (the part of each interval the sun is up: never more than the day length)."""

import json

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.model.solar import Atmosphere, solar_position, standard_pressure
from hillshade_rt.model.times import parse_time
from hillshade_rt.testing import read_band, write_geotiff

# a 3 km square of 30 m cells near the SPA report's site (Golden, Colorado), UTM 13N
GOLDEN = Affine(30.0, 0, 476000.0, 0, -30.0, 4400000.0)
UTM13 = CRS.from_epsg(32613)


def _dem(tmp_path, z, transform=GOLDEN, crs=UTM13, name="dem.tif"):
    return write_geotiff(tmp_path / name, np.asarray(z, np.float32), transform, crs)


def test_spa_worked_example():
    """The SPA report's example (Reda & Andreas 2004, table A4.1): 17 Oct 2003 12:30:30 at
    UTC-7, 39.742476 N 105.1786 W, 1830.14 m, 820 mbar, 11 C, delta T 67 s."""
    t = parse_time("2003-10-17T12:30:30-07:00")
    az, el, zen = solar_position([t], 39.742476, -105.1786, 1830.14,
                                 Atmosphere(True, 820.0, 11.0), delta_t=67.0)
    assert zen[0] == pytest.approx(50.11162, abs=1e-5)
    assert az[0] == pytest.approx(194.34024, abs=1e-5)
    assert el[0] == pytest.approx(90.0 - 50.11162, abs=1e-5)
    # without refraction the sun is lower (the SPA's e0)
    _, el0, _ = solar_position([t], 39.742476, -105.1786, 1830.14,
                               Atmosphere(False, 820.0, 11.0), delta_t=67.0)
    assert 0.005 < el[0] - el0[0] < 0.05


@pytest.mark.parametrize("atmosphere", [Atmosphere(), Atmosphere(refraction=False),
                                        Atmosphere(pressure_hpa=850.0, temperature_c=-3.0)])
def test_times_against_places_are_the_bits_of_the_spa_on_every_pair(atmosphere):
    """Times (T, 1) against places (1, P) run the SPA's time part once per time: each value
    is the bits of pvlib's SPA on the broadcast (time, place) pairs, as the per-pair call
    gives them."""
    rng = np.random.default_rng(7)
    t = 1.7e9 + np.sort(rng.uniform(0.0, 3.2e7, 211))     # a year of odd instants
    lat = rng.uniform(-70.0, 70.0, 81)
    lon = rng.uniform(-180.0, 180.0, 81)
    h = rng.uniform(0.0, 4000.0, 81)
    got = solar_position(t[:, None], lat[None, :], lon[None, :], h[None, :], atmosphere)
    pairs = [np.broadcast_to(a, (t.size, lat.size)).ravel()
             for a in (t[:, None], lat[None, :], lon[None, :], h[None, :])]
    want = solar_position(*pairs, atmosphere=atmosphere)       # one SPA call per pair
    for g, w in zip(got, want):
        assert g.shape == (t.size, lat.size)
        np.testing.assert_array_equal(g.ravel(), w)
    # one time, many places; and a scalar place against many times: the same bits too
    one = solar_position(t[5], lat, lon, h, atmosphere)
    for g, w in zip(one, got):
        np.testing.assert_array_equal(g, w[5])
    many = solar_position(t, lat[3], lon[3], h[3], atmosphere)
    for g, w in zip(many, got):
        np.testing.assert_array_equal(g, w[:, 3])


def test_atmosphere_pressure_given_or_standard_at_the_height():
    """--pressure wins at every height; without it the ICAO standard atmosphere: 1013.25 hPa at
    sea level, about 820 at 1830 m (the SPA report's site), arrays too."""
    assert standard_pressure(0.0) == pytest.approx(1013.25)
    assert standard_pressure(1830.14) == pytest.approx(812.6, abs=1.0)
    p = standard_pressure(np.array([0.0, 1000.0, 3000.0]))
    assert p.shape == (3,) and (np.diff(p) < 0).all()
    assert Atmosphere(True, 900.0).pressure_at(1830.14) == 900.0
    assert (Atmosphere(True, 900.0).pressure_at(np.zeros(4)) == 900.0).all()
    assert Atmosphere().pressure_at(500.0) == standard_pressure(500.0)


# ---------------------------------------------------------------------------------------------
# sun hours' samples

def test_sun_hours_on_flat_terrain_equal_day_length(tmp_path, runner):
    import pandas as pd
    from pvlib.solarposition import sun_rise_set_transit_spa

    dem = _dem(tmp_path, np.full((20, 30), 1700.0, np.float32))
    out, rep = tmp_path / "h.tif", tmp_path / "h.json"
    step_min = 10
    r = runner.invoke(cli, ["sun-hours", dem, str(out), "--date", "2026-06-21",
                            "--step", f"{step_min}min", "--tz", "America/Denver",
                            "--report", str(rep), "-q"])
    assert r.exit_code == 0, r.output
    h = read_band(out)
    doc = json.loads(rep.read_text())
    lat, lon = doc["site"]["latitude"], doc["site"]["longitude"]
    day = pd.DatetimeIndex([pd.Timestamp("2026-06-21 12:00", tz="America/Denver")])
    rs = sun_rise_set_transit_spa(day, lat, lon)
    length = (rs["sunset"].iloc[0] - rs["sunrise"].iloc[0]).total_seconds() / 3600.0
    assert np.ptp(h) == 0
    assert abs(float(h[0, 0]) - length) <= step_min / 60.0
    assert 14.5 < length < 15.5
    # a range of days adds up
    r = runner.invoke(cli, ["sun-hours", dem, str(tmp_path / "h3.tif"), "--date", "2026-06-20",
                            "--end-date", "2026-06-22", "--step", "20min", "-q"])
    assert r.exit_code == 0
    assert float(read_band(tmp_path / "h3.tif")[0, 0]) == pytest.approx(3 * length, abs=1.0)


@pytest.mark.parametrize("lat, date", [(0.0, "2026-03-20"), (45.0, "2026-06-21"),
                                       (45.0, "2026-12-21"), (60.0, "2026-06-21"),
                                       (-33.9, "2026-06-21"), (52.5, "2026-10-07"),
                                       (67.0, "2026-12-21"), (69.0, "2026-06-21"),
                                       (69.0, "2026-12-21")])
def test_sun_hours_never_exceed_the_day_length(tmp_path, runner, lat, date):
    """A flat open plain: its sun hours are the time the sun's apparent centre is above the
    horizon (the tool's sunrise to sunset), found here by sampling pvlib's SPA every 5 s, and
    never more (samples counting whole steps at both ends gave up to one step more)."""
    import pandas as pd
    from pvlib import spa
    from pvlib.solarposition import spa_python

    lon = 10.3
    dem = write_geotiff(tmp_path / "flat.tif", np.zeros((10, 12), np.float32),
                        Affine(10, 0, 0, 0, -10, 0), None)
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["sun-hours", dem, str(out), "--date", date, "--step", "1h",
                            "--lat", str(lat), "--lon", str(lon), "-q"])
    assert r.exit_code == 0, r.output
    h = read_band(out)
    assert np.ptp(h) == 0
    # the day in local mean solar time at lon (no --tz), sampled every 5 s
    t0 = pd.Timestamp(date, tz="UTC") - pd.Timedelta(hours=lon / 15.0)
    times = pd.date_range(t0, t0 + pd.Timedelta(days=1), freq="5s", inclusive="left")
    dt = float(spa.calculate_deltat(np.array([times[0].year]), np.array([times[0].month]))[0])
    el = spa_python(times, lat, lon, altitude=0.0, pressure=101325.0, temperature=12.0,
                    delta_t=dt)["apparent_elevation"].to_numpy()
    length = float((el > 0).sum()) * 5.0 / 3600.0
    assert float(h[0, 0]) <= length + 10 / 3600.0, (float(h[0, 0]), length)
    assert float(h[0, 0]) == pytest.approx(length, abs=20 / 3600.0), (float(h[0, 0]), length)
