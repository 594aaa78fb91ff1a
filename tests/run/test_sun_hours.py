"""The sun-hours run (``run.sun_hours``): on open flat ground the hours are the day length the
model's daylight samples give; a pillar's shadow toward the north-north-east (the sun at
azimuth ~203.7 in December) takes hours from the cells behind it and none from the cells in
front; a tile lit in its ``--context`` equals the same cells of the whole DEM in memory, cell
for cell, where the tile alone loses the shadow cast across its edge."""

from __future__ import annotations

import datetime as dt
import json
import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import UsageProblem
from hillshade_rt.model.solar import daylight_samples
from hillshade_rt.model.sun import SunRequest
from hillshade_rt.run import ReadOptions, RunOptions, SunHoursConfig, sun_hours
from hillshade_rt.testing import read_band, write_geotiff

TZ = "Europe/Zurich"
CELL = 10.0                              # metres
ORIGIN = Affine(CELL, 0, 600000.0, 0, -CELL, 5150000.0)     # UTM 32N, about 46.5 N 8.3 E
UTM32 = CRS.from_epsg(32632)
SIDE = 80
PILLAR = (slice(38, 43), slice(38, 43))  # 50 m square, rows/cols 38..42
PILLAR_M = 200.0


def _dem(tmp_path, z, name="dem.tif", transform=ORIGIN):
    return write_geotiff(str(tmp_path / name), z.astype(np.float32), transform, UTM32, -9999.0)


def _pillar():
    z = np.full((SIDE, SIDE), 500.0, np.float32)
    z[PILLAR] += PILLAR_M
    return z


def _run(tmp_path, dem, out="out.tif", date="2026-12-21", step="20min", context=None,
         report=None):
    cfg = SunHoursConfig(dem=dem, output=str(tmp_path / out), date=date, step=step,
                         place={"tz": TZ}, read=ReadOptions(context=context),
                         run=RunOptions(report_path=report, overwrite=True, quiet=True))
    rep = sun_hours(cfg)
    return read_band(tmp_path / out), rep


def _day_length(dem, date, step):
    """The hours of the daylight samples at the DEM's place: the sun-hours of open ground."""
    req = SunRequest.at_place([], tz=TZ)
    d = ReadOptions().read(dem)
    site = req.site(d)
    day = dt.date.fromisoformat(date)
    _, weights = daylight_samples(day, day, step, req.tz, site, req.atmosphere)
    return float(np.sum(weights))


@pytest.mark.parametrize("date", ["2026-06-21", "2026-12-21"])
def test_flat_ground_gets_the_day_length(tmp_path, date):
    dem = _dem(tmp_path, np.full((40, 40), 420.0))
    hours, rep = _run(tmp_path, dem, date=date)
    want = _day_length(dem, date, "20min")
    # the day at 46.5 N: about 15.7 h at the June solstice, 8.6 h at the December one
    assert (15.3 < want < 16.1) if date.endswith("06-21") else (8.2 < want < 9.0)
    np.testing.assert_allclose(hours, want, rtol=1e-5)
    assert rep["hours"]["min"] == pytest.approx(want, rel=1e-5)
    assert rep["samples_with_sun"] < rep["samples"] == 72


def test_the_cell_behind_a_pillar_gets_fewer_hours(tmp_path):
    """In December the sun at azimuth 203.7 stands about 17 deg high: the 200 m pillar's
    shadow reaches some 650 m toward azimuth 23.7, over the cell 150 m that way; the cell 150
    m toward 203.7 (in front of it) is open all day."""
    dem = _dem(tmp_path, _pillar())
    hours, _ = _run(tmp_path, dem)
    open_day = _day_length(dem, "2026-12-21", "20min")
    r, c = 40, 40                                             # the pillar's centre
    a = math.radians(23.7)
    behind = (r - round(15 * math.cos(a)), c + round(15 * math.sin(a)))
    front = (r + round(15 * math.cos(a)), c - round(15 * math.sin(a)))
    assert hours[behind] < open_day - 0.3
    assert hours[front] == pytest.approx(open_day, rel=1e-5)
    # a corner far to the south-west: nothing between it and the sun
    assert hours[SIDE - 1, 0] == pytest.approx(open_day, rel=1e-5)


def test_tile_in_its_context_equals_the_whole(tmp_path):
    """The north-east quarter (the pillar's shadow crosses into it), lit in the context of the
    whole DEM, equals the whole run's cells bit for bit; alone it loses that shadow."""
    z = _pillar()
    whole_dem = _dem(tmp_path, z)
    whole, _ = _run(tmp_path, whole_dem, "whole.tif", step="30min")
    r0, c0 = 0, 43
    tile = z[r0:40, c0:]
    tile_dem = _dem(tmp_path, tile, "tile.tif", ORIGIN @ Affine.translation(c0, r0))
    report = str(tmp_path / "tile.json")
    got, rep = _run(tmp_path, tile_dem, "tile_out.tif", step="30min", context=whole_dem,
                    report=report)
    np.testing.assert_array_equal(got, whole[r0:40, c0:])
    with open(report, encoding="utf-8") as fh:
        assert json.load(fh)["context"]["window"] == [r0, 40, c0, SIDE]
    assert rep["shape"] == [40, SIDE - c0]
    alone, _ = _run(tmp_path, tile_dem, "alone.tif", step="30min")
    assert (alone > got).sum() > 10


def test_end_date_before_date_is_a_usage_error(tmp_path):
    dem = _dem(tmp_path, np.full((20, 20), 420.0))
    with pytest.raises(UsageProblem, match="--end-date is before --date"):
        sun_hours(SunHoursConfig(dem=dem, output=str(tmp_path / "o.tif"), date="2026-12-21",
                                 end_date="2026-12-20"))
    assert not (tmp_path / "o.tif").exists()


@pytest.mark.parametrize("window_size", [None, "64"])
def test_one_day_is_named_as_r_sun_names_it(tmp_path, window_size):
    """One day's hours are r.sun's insol_time: that is the band's description (in memory and
    in windows); several days' sum is not r.sun's product: our description; the tags NAME and
    RSUN_NAME say both either way."""
    import rasterio
    dem = _dem(tmp_path, _pillar())
    for out, end_date, want in (("one.tif", None, "insol_time"),
                                ("two.tif", "2026-12-22", "hours of direct sun")):
        cfg = SunHoursConfig(dem=dem, output=str(tmp_path / out), date="2026-12-21",
                             end_date=end_date, step="1h", place={"tz": TZ},
                             window_size=window_size,
                             run=RunOptions(overwrite=True, quiet=True))
        sun_hours(cfg)
        with rasterio.open(tmp_path / out) as ds:
            assert ds.descriptions == (want,), out
            assert ds.tags()["NAME"] == "hours of direct sun"
            assert ds.tags()["RSUN_NAME"] == "insol_time"


def test_monthly_bands_sum_to_the_total_and_equal_each_months_days(tmp_path):
    """--monthly: band 1 the bits of the run without it, then one band per month (YYYY-MM),
    each the hours of its own days' runs, together the total (in windows:
    test_sun_hours_windows)."""
    import rasterio
    dem = _dem(tmp_path, _pillar())

    def run(out, first, last, monthly=False, **kw):
        cfg = SunHoursConfig(dem=dem, output=str(tmp_path / out), date=first, end_date=last,
                             step="1h", place={"tz": TZ}, monthly=monthly,
                             run=RunOptions(overwrite=True, quiet=True,
                                            report_path=str(tmp_path / "r.json")), **kw)
        return sun_hours(cfg)
    run("plain.tif", "2027-01-30", "2027-02-02")
    rep = run("m.tif", "2027-01-30", "2027-02-02", monthly=True)
    with rasterio.open(tmp_path / "m.tif") as ds:
        bands, desc = ds.read(), ds.descriptions
    assert desc[1:] == ("2027-01", "2027-02")
    np.testing.assert_array_equal(bands[0], read_band(tmp_path / "plain.tif"))
    np.testing.assert_allclose(bands[1] + bands[2], bands[0], rtol=1e-6)
    run("jan.tif", "2027-01-30", "2027-01-31")
    run("feb.tif", "2027-02-01", "2027-02-02")
    np.testing.assert_array_equal(bands[1], read_band(tmp_path / "jan.tif"))
    np.testing.assert_array_equal(bands[2], read_band(tmp_path / "feb.tif"))
    assert [m["month"] for m in rep["months"]] == ["2027-01", "2027-02"]
    assert bands[0][PILLAR].max() > 0 and bands[1].min() < bands[1].max()
