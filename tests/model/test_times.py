"""Times and zones. Series and days across daylight-saving changes: steps are elapsed time,
--end is included when a step lands on it, every time lies between --start and --end as
instants, labels carry each instant's own offset; local times a zone skips are refused (naming
the gap), ones it repeats are refused (naming both offsets); a sun-hours day on which the clocks
change has the hours that elapse (23, 25; 23.5, 24.5 in Lord Howe). The zone of a DEM's place
(zone_at, timezonefinder + zoneinfo) and --tz auto: Zurich with its daylight saving, the bundled
example in California, the open ocean's nautical zones."""

import datetime as dt
import json

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.site import dem_site
from hillshade_rt.model.sun import SunRequest
from hillshade_rt.model.times import (
    day_samples, iso, parse_step, parse_time, time_range, zone, zone_at, zone_label
)
from hillshade_rt.testing import (
    data_path, fractal_terrain, memory_dem, read_band, repo_root, write_geotiff
)

UTC = dt.timezone.utc
LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
NY = "America/New_York"


def series(start, end, step, tz):
    z = zone(tz)
    return [iso(t) for t in time_range(parse_time(start, z, "--start"),
                                       parse_time(end, z, "--end"), parse_step(step))]


def check_series(times, start, end, step):
    """The invariants of a series, as instants."""
    u = [t.astimezone(UTC) for t in times]
    u0, u1 = start.astimezone(UTC), end.astimezone(UTC)
    assert u[0] == u0
    assert all(b - a == step for a, b in zip(u, u[1:]))
    assert u[-1] <= u1 < u[-1] + step
    assert len(times) == (u1 - u0) // step + 1
    for t in times:      # each label is its own instant, with the zone's offset at that instant
        # (compared in UTC: Python never calls a time in a fold equal to one of another zone)
        assert dt.datetime.fromisoformat(iso(t)).astimezone(UTC) == t.astimezone(UTC)
        assert t.utcoffset() == t.astimezone(UTC).astimezone(start.tzinfo).utcoffset()


# ---------------------------------------------------------------------------------------------
# the reproductions, through the functions

def test_new_york_spring_forward_series():
    # 00:30 EST to 04:30 EDT is 3 hours: 4 times, the last one --end itself
    assert series("2026-03-08T00:30", "2026-03-08T04:30", "1h", NY) == [
        "2026-03-08T00:30-05:00", "2026-03-08T01:30-05:00",
        "2026-03-08T03:30-04:00", "2026-03-08T04:30-04:00"]
    assert series("2026-03-08T00:30", "2026-03-08T04:30", "30min", NY) == [
        "2026-03-08T00:30-05:00", "2026-03-08T01:00-05:00", "2026-03-08T01:30-05:00",
        "2026-03-08T03:00-04:00", "2026-03-08T03:30-04:00", "2026-03-08T04:00-04:00",
        "2026-03-08T04:30-04:00"]


def test_new_york_fall_back_series():
    # 00:30 EDT to 04:30 EST is 5 hours: 6 times; 01:30 twice, first EDT then EST
    assert series("2026-11-01T00:30", "2026-11-01T04:30", "1h", NY) == [
        "2026-11-01T00:30-04:00", "2026-11-01T01:30-04:00", "2026-11-01T01:30-05:00",
        "2026-11-01T02:30-05:00", "2026-11-01T03:30-05:00", "2026-11-01T04:30-05:00"]
    # to 03:30 EST by 30 min: 4 elapsed hours, 9 times, 03:00 and 03:30 EST (--end) included
    s = series("2026-11-01T00:30", "2026-11-01T03:30", "30min", NY)
    assert len(s) == 9 and s[-2:] == ["2026-11-01T03:00-05:00", "2026-11-01T03:30-05:00"]
    assert s[2:5] == ["2026-11-01T01:30-04:00", "2026-11-01T01:00-05:00",
                      "2026-11-01T01:30-05:00"]


def test_series_through_the_sun_options():
    req = SunRequest.from_options(start="2026-11-01T00:30", end="2026-11-01T04:30", step="1h",
                                  tz=NY)
    assert [iso(t) for t in req.times] == series("2026-11-01T00:30", "2026-11-01T04:30", "1h", NY)
    # --start and --end compared as instants: 01:50 EDT comes 20 minutes before 01:10 EST
    req = SunRequest.from_options(start="2026-11-01T01:50-04:00", end="2026-11-01T01:10-05:00",
                                  step="10min", tz=NY)
    assert [iso(t) for t in req.times] == ["2026-11-01T01:50-04:00", "2026-11-01T01:00-05:00",
                                           "2026-11-01T01:10-05:00"]
    with pytest.raises(HillshadeError, match="before --start"):
        SunRequest.from_options(start="2026-11-01T01:10-05:00", end="2026-11-01T01:50-04:00",
                                step="10min", tz=NY)


def test_southern_hemisphere_sydney():
    # first Sunday of April 2026: 03:00 AEDT -> 02:00 AEST; 01:30 to 04:30 is 4 hours
    assert series("2026-04-05T01:30", "2026-04-05T04:30", "1h", "Australia/Sydney") == [
        "2026-04-05T01:30+11:00", "2026-04-05T02:30+11:00", "2026-04-05T02:30+10:00",
        "2026-04-05T03:30+10:00", "2026-04-05T04:30+10:00"]
    # first Sunday of October 2026: 02:00 AEST -> 03:00 AEDT; 01:30 to 04:30 is 2 hours
    assert series("2026-10-04T01:30", "2026-10-04T04:30", "1h", "Australia/Sydney") == [
        "2026-10-04T01:30+10:00", "2026-10-04T03:30+11:00", "2026-10-04T04:30+11:00"]


def test_lord_howe_half_hour_shift_and_a_step_that_does_not_divide_it():
    lh = "Australia/Lord_Howe"
    # 4 Oct 2026: 02:00 +10:30 -> 02:30 +11:00; 01:30 to 03:10 is 70 minutes, by 20 min
    assert series("2026-10-04T01:30", "2026-10-04T03:10", "20min", lh) == [
        "2026-10-04T01:30+10:30", "2026-10-04T01:50+10:30", "2026-10-04T02:40+11:00",
        "2026-10-04T03:00+11:00"]
    # 5 Apr 2026: 02:00 +11:00 -> 01:30 +10:30; 01:00 to 02:20 is 110 minutes, by 20 min
    assert series("2026-04-05T01:00", "2026-04-05T02:20", "20min", lh) == [
        "2026-04-05T01:00+11:00", "2026-04-05T01:20+11:00", "2026-04-05T01:40+11:00",
        "2026-04-05T01:30+10:30", "2026-04-05T01:50+10:30", "2026-04-05T02:10+10:30"]


def _changes(tz, year=2026):
    """The instants (UTC, to the hour) at which ``tz``'s offset changes in ``year``."""
    z = zone(tz)
    t = dt.datetime(year, 1, 1, tzinfo=UTC)
    out, off = [], t.astimezone(z).utcoffset()
    while t.year == year:
        t += dt.timedelta(hours=1)
        o = t.astimezone(z).utcoffset()
        if o != off:
            out.append(t)
            off = o
    return out


@pytest.mark.parametrize("tz", [NY, "Europe/Zurich", "Australia/Sydney", "Australia/Lord_Howe",
                                "America/Santiago", "Antarctica/Troll"])
def test_series_invariants_around_every_change(tz):
    z = zone(tz)
    changes = _changes(tz)
    assert len(changes) == 2
    for change in changes:
        for before, after in ((dt.timedelta(hours=3), dt.timedelta(hours=4)),
                              (dt.timedelta(minutes=50), dt.timedelta(minutes=95))):
            # start and end on either side of the change, in the zone (with their folds)
            s, e = (change - before).astimezone(z), (change + after).astimezone(z)
            for step in ("7min", "20min", "1h", "90min", "2h"):
                check_series(time_range(s, e, parse_step(step)), s, e, parse_step(step))


# ---------------------------------------------------------------------------------------------
# local times the zone skips or repeats

@pytest.mark.parametrize("tz, text, gap", [
    (NY, "2026-03-08T02:30", "02:00-03:00 on 2026-03-08"),
    ("Australia/Sydney", "2026-10-04T02:00", "02:00-03:00 on 2026-10-04"),
    ("Australia/Lord_Howe", "2026-10-04T02:15", "02:00-02:30 on 2026-10-04"),
])
def test_a_local_time_that_does_not_exist_is_refused_naming_the_gap(tz, text, gap):
    with pytest.raises(HillshadeError, match="does not exist") as e:
        parse_time(text, zone(tz), "--start")
    assert gap in str(e.value) and "--start" in str(e.value)


@pytest.mark.parametrize("tz, text, first, second", [
    (NY, "2026-11-01T01:30", "-04:00", "-05:00"),
    ("Australia/Sydney", "2026-04-05T02:30", "+11:00", "+10:00"),
    ("Australia/Lord_Howe", "2026-04-05T01:45", "+11:00", "+10:30"),
])
def test_a_local_time_that_happens_twice_is_refused_naming_both(tz, text, first, second):
    z = zone(tz)
    with pytest.raises(HillshadeError, match="happens twice") as e:
        parse_time(text, z)
    msg = str(e.value)
    assert f"{text}{first} (the first)" in msg and f"{text}{second} (the second)" in msg
    # either as suggested: that instant, labelled with its own offset
    assert iso(parse_time(text + first, z)) == text + first
    assert iso(parse_time(text + second, z)) == text + second
    assert parse_time(text + second, z).timestamp() - parse_time(text + first, z).timestamp() == \
        (1800 if tz.endswith("Lord_Howe") else 3600)


def test_cli_refuses_skipped_and_repeated_times_as_usage_errors(tmp_path, runner):
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "a.tif"), "--start",
                            "2026-03-08T02:30", "--end", "2026-03-08T05:00", "--step", "1h",
                            "--tz", NY])
    assert r.exit_code == 2 and "does not exist" in r.stderr
    assert "02:00-03:00 on 2026-03-08" in r.stderr
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "a.tif"), "--time",
                            "2026-11-01T01:30", "--tz", NY])
    assert r.exit_code == 2 and "happens twice" in r.stderr
    assert "2026-11-01T01:30-05:00" in r.stderr
    assert not list(tmp_path.iterdir())


# ---------------------------------------------------------------------------------------------
# the command line: band descriptions, tags, report, output patterns

def test_cli_spring_forward_bands(tmp_path, runner):
    import rasterio
    out, rep = tmp_path / "s.tif", tmp_path / "s.json"
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), "--start", "2026-03-08T00:30",
                            "--end", "2026-03-08T04:30", "--step", "1h", "--tz", NY,
                            "--report", str(rep), "-q"])
    assert r.exit_code == 0, r.output
    want = ("2026-03-08T00:30-05:00", "2026-03-08T01:30-05:00",
            "2026-03-08T03:30-04:00", "2026-03-08T04:30-04:00")
    with rasterio.open(out) as ds:
        assert ds.descriptions == want
        assert tuple(ds.tags(i)["TIME"] for i in range(1, 5)) == want
    doc = json.loads(rep.read_text())
    assert tuple(t["time"] for t in doc["times"]) == want


def test_cli_fall_back_output_pattern(tmp_path, runner):
    pat = str(tmp_path / "m_{time:%H%M%z}.tif")
    r = runner.invoke(cli, ["shadow", LIDAR, "--output-pattern", pat, "--start",
                            "2026-11-01T00:30", "--end", "2026-11-01T04:30", "--step", "1h",
                            "--tz", NY, "-q"])
    assert r.exit_code == 0, r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        f"m_{n}.tif" for n in ("0030-0400", "0130-0400", "0130-0500", "0230-0500", "0330-0500",
                               "0430-0500"))
    # without the offset the repeated hour has two times with one name: refused, saying why
    r = runner.invoke(cli, ["shadow", LIDAR, "--output-pattern",
                            str(tmp_path / "q_{time:%H%M}.tif"), "--start", "2026-11-01T00:30",
                            "--end", "2026-11-01T04:30", "--step", "1h", "--tz", NY, "-q"])
    assert r.exit_code == 1 and "clocks go back" in r.stderr and "%z" in r.stderr
    assert not list(tmp_path.glob("q_*"))


# ---------------------------------------------------------------------------------------------
# sun-hours: a day is midnight to midnight, as many hours as elapse

@pytest.mark.parametrize("tz, day, hours", [
    (NY, "2026-03-08", 23.0), (NY, "2026-11-01", 25.0), (NY, "2026-06-21", 24.0),
    ("Australia/Sydney", "2026-04-05", 25.0), ("Australia/Sydney", "2026-10-04", 23.0),
    ("Australia/Lord_Howe", "2026-04-05", 24.5), ("Australia/Lord_Howe", "2026-10-04", 23.5),
    ("America/Santiago", "2026-09-06", 23.0),      # clocks skip midnight itself
])
def test_day_samples_cover_exactly_the_local_day(tz, day, hours):
    z = zone(tz)
    d = dt.date.fromisoformat(day)
    for step in ("7min", "1h", "10min"):
        times, weights = day_samples(d, d, step, z, lon=0.0)
        assert sum(weights) == pytest.approx(hours, abs=1e-9)
        s = parse_step(step).total_seconds() / 3600.0
        assert all(w == pytest.approx(s) for w in weights[:-1]) and 0 < weights[-1] <= s + 1e-12
        # the samples are the middles of back-to-back intervals from the day's first instant
        # to the next day's, every one on that local date
        u = [t.astimezone(UTC) for t in times]
        edges = [u[0] - dt.timedelta(hours=weights[0] / 2)]
        for t, w in zip(u, weights):
            assert t - edges[-1] == pytest.approx(dt.timedelta(hours=w / 2),
                                                  abs=dt.timedelta(microseconds=1))
            edges.append(t + (t - edges[-1]))
        assert edges[0].astimezone(z).date() == d and edges[0].second == 0
        assert edges[-1] - edges[0] == pytest.approx(dt.timedelta(hours=hours),
                                                     abs=dt.timedelta(microseconds=10))
        assert all(t.date() == d for t in times)
        assert (edges[0] - dt.timedelta(seconds=1)).astimezone(z).date() == d - dt.timedelta(1)
        assert edges[-1].astimezone(z).date() == d + dt.timedelta(1)
    # days in a row tile the time without overlap
    t3, w3 = day_samples(d - dt.timedelta(1), d + dt.timedelta(1), "1h", z, lon=0.0)
    assert sum(w3) == pytest.approx(48.0 + hours)
    assert all(b.astimezone(UTC) > a.astimezone(UTC) for a, b in zip(t3, t3[1:]))


def test_sun_hours_on_a_day_the_clocks_change_count_its_hours(tmp_path, runner):
    """Flat ground near a pole in polar day, every sample lit: the hours are the day's length
    on the clock of --tz (the zone need not be the place's)."""
    dem = write_geotiff(tmp_path / "flat.tif", np.full((12, 16), 100.0, np.float32),
                        Affine(30.0, 0, 500000.0, 0, -30.0, 5000000.0), CRS.from_epsg(32633))
    for tz, day, lat, hours in (("Europe/Zurich", "2026-03-29", 89.0, 23.0),
                                (NY, "2026-11-01", -89.0, 25.0),
                                ("Australia/Lord_Howe", "2026-04-05", 89.0, 24.5)):
        out = tmp_path / f"h_{day}.tif"
        r = runner.invoke(cli, ["sun-hours", dem, str(out), "--date", day, "--step", "20min",
                                "--tz", tz, "--lat", str(lat), "--lon", "0", "-q"])
        assert r.exit_code == 0, r.output
        h = read_band(out)
        assert np.ptp(h) == 0 and float(h[0, 0]) == pytest.approx(hours, abs=1e-4), (tz, day)


def test_times_offsets_zones_and_dst():
    zurich = zone("Europe/Zurich")
    summer = parse_time("2026-06-21T14:30", zurich)
    assert summer == parse_time("2026-06-21T12:30:00Z") == parse_time("2026-06-21T14:30+02:00")
    winter = parse_time("2026-01-15T14:30", zurich)   # CET: +01:00
    assert winter.utcoffset() == dt.timedelta(hours=1)
    assert winter == parse_time("2026-01-15T13:30Z")
    with pytest.raises(HillshadeError, match="no UTC offset"):
        parse_time("2026-06-21T14:30")
    with pytest.raises(HillshadeError, match="does not exist"):
        parse_time("2026-03-29T02:30", zurich)          # clocks jump 02:00 -> 03:00
    with pytest.raises(HillshadeError, match="happens twice"):
        parse_time("2026-10-25T02:30", zurich)          # 02:00-03:00 twice
    with pytest.raises(HillshadeError, match="IANA"):
        zone("Mars/Olympus")
    assert parse_step("1h30min") == dt.timedelta(minutes=90)
    assert parse_step("PT10M") == parse_step("10min") == dt.timedelta(minutes=10)
    with pytest.raises(HillshadeError):
        parse_step("soon")


# ---------------------------------------------------------------------------------------------
# zones: a place's zone, --tz auto


def zurich_dem():
    """A small geographic DEM whose centre is in Zurich (8.54 E, 47.37 N)."""
    z = fractal_terrain(40, 50, 3, relief=300.0).astype(np.float32) + 400.0
    return memory_dem(z, Affine(0.001, 0, 8.515, 0, -0.001, 47.39), "EPSG:4326")


def offset(tz, when):
    return when.astimezone(tz).utcoffset()


def test_zurich_is_europe_zurich_with_daylight_saving():
    site = dem_site(zurich_dem())
    tz, name = zone_at(site.lon, site.lat)
    assert name == "Europe/Zurich"
    july = dt.datetime(2026, 7, 15, 10, tzinfo=UTC)
    january = dt.datetime(2026, 1, 15, 10, tzinfo=UTC)
    assert offset(tz, july) == dt.timedelta(hours=2)
    assert offset(tz, january) == dt.timedelta(hours=1)
    assert zone_label(tz, name, july) == "Europe/Zurich (UTC+02:00, CEST)"
    assert zone_label(tz, name, january) == "Europe/Zurich (UTC+01:00, CET)"


def test_the_bundled_example_is_los_angeles():
    from hillshade_rt.io import read_dem
    dem = read_dem(f"{repo_root()}/examples/bigtujunga_srtm30m_utm11n_1197x643.tif")
    site = dem_site(dem)       # UTM 11N -> WGS84 through the DEM's own CRS
    tz, name = zone_at(site.lon, site.lat)
    assert name == "America/Los_Angeles"
    assert offset(tz, dt.datetime(2026, 12, 21, 20, tzinfo=UTC)) == dt.timedelta(hours=-8)
    assert offset(tz, dt.datetime(2026, 6, 21, 20, tzinfo=UTC)) == dt.timedelta(hours=-7)


@pytest.mark.parametrize("lon, lat, name, hours", [
    (-30.0, 0.0, "Etc/GMT+2", -2),        # mid-Atlantic: 2 h behind UTC (POSIX's sign)
    (-150.0, 10.0, "Etc/GMT+10", -10),    # mid-Pacific
    (170.0, -60.0, "Etc/GMT-11", 11),     # Southern Ocean, east
])
def test_the_open_ocean_has_nautical_zones(lon, lat, name, hours):
    z = np.full((20, 20), -4000.0, np.float32)
    dem = memory_dem(z, Affine(0.01, 0, lon - 0.1, 0, -0.01, lat + 0.1), "EPSG:4326")
    site = dem_site(dem)
    tz, got = zone_at(site.lon, site.lat)
    assert got == name
    assert offset(tz, dt.datetime(2026, 7, 1, tzinfo=UTC)) == dt.timedelta(hours=hours)


def test_without_zone_data_the_nearest_whole_hour(monkeypatch):
    import hillshade_rt.model.times as times
    monkeypatch.setattr(times, "zone_name_at", lambda lon, lat: None)
    tz, name = zone_at(86.9, 27.9)        # Everest: UTC+5:45 in Nepal, 6 h by its longitude
    assert name == "Etc/GMT-6" and offset(tz, dt.datetime(2026, 1, 1, tzinfo=UTC)) == \
        dt.timedelta(hours=6)


def test_tz_auto_reads_local_times_in_the_dem_zone():
    dem = zurich_dem()
    req = SunRequest.from_options(time=["2026-07-15T12:00", "2026-01-15T12:00",
                                        "2026-07-15T12:00Z"], tz="auto")
    assert req.auto_tz and req.tz is None
    req.site(dem)
    assert req.tz.key == "Europe/Zurich"
    assert [t.isoformat() for t in req.times] == ["2026-07-15T12:00:00+02:00",
                                                  "2026-01-15T12:00:00+01:00",
                                                  "2026-07-15T14:00:00+02:00"]
    # a series: the same, read again once the zone is known
    req = SunRequest.from_options(start="2026-03-29T01:00", end="2026-03-29T04:00", step="1h",
                                  tz="AUTO")
    req.site(dem)
    assert [t.isoformat() for t in req.times] == ["2026-03-29T01:00:00+01:00",
                                                  "2026-03-29T03:00:00+02:00",
                                                  "2026-03-29T04:00:00+02:00"]


def test_cli_tz_auto(tmp_path):
    """shadow --time local --tz auto is --tz Europe/Zurich for a DEM in Zurich; a bad time is
    still a usage error before the DEM is read."""
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    from hillshade_rt.testing import write_geotiff
    d = zurich_dem()
    path = write_geotiff(tmp_path / "zurich.tif", d.heights, d.transform, "EPSG:4326")
    runner = CliRunner()
    reps = []
    for tz in ("auto", "Europe/Zurich"):
        rep = tmp_path / f"{tz.replace('/', '_')}.json"
        r = runner.invoke(cli, ["shadow", path, str(tmp_path / f"{tz.replace('/', '_')}.tif"),
                                "--time", "2026-07-15T08:30", "--tz", tz, "-q",
                                "--report", str(rep)])
        assert r.exit_code == 0, r.output
        reps.append(json.loads(rep.read_text()))
    got = [(t["time"], t["azimuth"], t["elevation"]) for rep in reps for t in rep["times"]]
    assert got[0] == got[1] and got[0][0] == "2026-07-15T08:30+02:00"
    assert any("--tz auto: Europe/Zurich" in n for n in reps[0]["site_notes"])
    r = runner.invoke(cli, ["shadow", str(tmp_path / "none.tif"), str(tmp_path / "x.tif"),
                            "--time", "noon", "--tz", "auto"])
    assert r.exit_code == 2 and "not an ISO 8601 time" in r.output


def test_sun_hours_tz_auto_days_in_the_dem_zone(tmp_path):
    """sun-hours --tz auto: days from midnight to midnight in the DEM's zone (its tag says
    which), the same hours as --tz Europe/Zurich; without --tz local mean solar time stays."""
    import rasterio
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    from hillshade_rt.testing import write_geotiff
    d = zurich_dem()
    path = write_geotiff(tmp_path / "zurich.tif", d.heights, d.transform, "EPSG:4326")
    out = {}
    for tz in ("auto", "Europe/Zurich", None):
        name = tmp_path / f"h{len(out)}.tif"
        r = CliRunner().invoke(cli, ["sun-hours", path, str(name), "--date", "2026-03-29",
                                     "--step", "1h", "-q"] + (["--tz", tz] if tz else []))
        assert r.exit_code == 0, r.output
        with rasterio.open(name) as ds:
            out[tz] = ds.tags()["DAY"], ds.read(1)
    assert out["auto"][0] == out["Europe/Zurich"][0] == "midnight to midnight, Europe/Zurich"
    assert np.array_equal(out["auto"][1], out["Europe/Zurich"][1])
    assert "mean solar" in out[None][0]
