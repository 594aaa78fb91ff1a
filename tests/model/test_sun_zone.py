"""The zone of a DEM's place (sun.zone_at, timezonefinder + zoneinfo) and --tz auto: Zurich
with its daylight saving, the bundled example in California, the open ocean's nautical zones."""

from __future__ import annotations

import datetime as dt
import json

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.model.sun import SunRequest, dem_site, zone_at, zone_label
from hillshade_rt.testing import fractal_terrain, memory_dem, repo_root

UTC = dt.timezone.utc


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
    import hillshade_rt.model.sun as sun
    monkeypatch.setattr(sun, "zone_name_at", lambda lon, lat: None)
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
