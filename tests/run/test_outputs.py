"""Where a run's products go (run.outputs): the names ``--output-pattern`` gives (fields, tiles,
the refusals), the tags, and through the command: a write that fails in a series leaves the files
before it whole and nothing under the failed file's final name."""

import datetime as dt
import errno
import os
from zoneinfo import ZoneInfo

import pytest
import rasterio

from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import write as writes
from hillshade_rt.model.sun import SunOver
from hillshade_rt.run import outputs
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
UTC = dt.timezone.utc


def _suns(*times, az=(163.0, 203.7, 290.0)):
    return [SunOver(t, a, 12.5) for t, a in zip(times, az)]


def test_tile_name():
    assert outputs.tile_name("/data/n46/e007.tif") == "e007"
    assert outputs.tile_name("zip:///x/t.zip!n46/e007.hgt") == "e007"
    assert outputs.tile_name("folder/") == "folder"


def test_pattern_fields_and_tiles():
    t0 = dt.datetime(2026, 6, 21, 9, 30, tzinfo=UTC)
    suns = _suns(t0, t0 + dt.timedelta(minutes=15))
    p = outputs.OutputPattern("o/{tile}_{index:02d}_{time:%H%M}_{azimuth:.1f}_{elevation:.0f}.tif")
    paths = p.paths(suns, ["/a/n46e007.tif", "/b/n46e008.tif"])
    assert paths == [["o/n46e007_00_0930_163.0_12.tif", "o/n46e008_00_0930_163.0_12.tif"],
                     ["o/n46e007_01_0945_203.7_12.tif", "o/n46e008_01_0945_203.7_12.tif"]]
    assert p.per_tile and p.planned == [q for ps in paths for q in ps]
    one = outputs.OutputPattern("{index}.tif")
    assert one.paths(suns, ["/a/x.tif", "/b/y.tif"]) == [["0.tif"], ["1.tif"]]


def test_pattern_refusals():
    with pytest.raises(HillshadeError, match="unknown field"):
        outputs.OutputPattern("{when}.tif")
    with pytest.raises(HillshadeError, match="output-pattern"):
        outputs.OutputPattern("{time.tif")
    t0 = dt.datetime(2026, 6, 21, 9, 30, tzinfo=UTC)
    with pytest.raises(HillshadeError, match="same file name"):
        outputs.OutputPattern("{time:%Y%m%d}.tif").paths(
            _suns(t0, t0 + dt.timedelta(hours=1)))
    with pytest.raises(HillshadeError, match="rename one"):
        outputs.OutputPattern("{tile}_{index}.tif").paths(_suns(t0), ["/a/e7.tif", "/b/e7.tif"])
    # the hour repeated when the clocks go back: 01:30 EDT and 01:30 EST
    ny = ZoneInfo("America/New_York")
    first = dt.datetime(2026, 11, 1, 5, 30, tzinfo=UTC).astimezone(ny)
    second = dt.datetime(2026, 11, 1, 6, 30, tzinfo=UTC).astimezone(ny)
    assert first.strftime("%H%M") == second.strftime("%H%M") == "0130"
    with pytest.raises(HillshadeError, match="clocks go back"):
        outputs.OutputPattern("{time:%Y%m%dT%H%M}.tif").paths(_suns(first, second))
    ok = outputs.OutputPattern("{time:%Y%m%dT%H%M%z}.tif").paths(_suns(first, second))
    assert ok == [["20261101T0130-0400.tif"], ["20261101T0130-0500.tif"]]


def test_tags_and_label():
    t = dt.datetime(2026, 6, 21, 9, 30, tzinfo=UTC)
    s = SunOver(t, 203.7, 12.25)
    tags = outputs.sun_tags(s)
    assert tags == {"SUN_AZIMUTH": "203.700000", "SUN_ELEVATION": "12.250000", "NIGHT": "no",
                    "TIME": "2026-06-21T09:30+00:00"}
    assert outputs.label(s) == "2026-06-21T09:30+00:00"
    assert outputs.label(SunOver(None, 290.0, 7.5)) == "sun az 290 el 7.5"


def test_a_failed_write_in_a_series_leaves_no_partial_file(tmp_path, monkeypatch, runner):
    real = writes._fsync
    calls = []

    def second_fails(path):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)
        return real(path)

    monkeypatch.setattr(writes, "_fsync", second_fails)
    out = tmp_path / "s"
    out.mkdir()
    r = runner.invoke(cli, ["shadow", LIDAR, "--output-pattern", str(out / "t_{index}.tif"),
                            "--start", "2026-06-21T09:00-05:00", "--end",
                            "2026-06-21T11:00-05:00", "--step", "1h", "-q"])
    assert r.exit_code == 1 and "no space left on device" in r.stderr.lower()
    names = sorted(os.listdir(out))
    assert names == ["t_0.tif"], names            # nothing hidden, nothing under t_1's name
    with rasterio.open(out / "t_0.tif") as ds:   # the one before is whole
        m = ds.read(1)
        assert m.shape == (400, 400) and set(map(int, set(m.ravel()))) <= {0, 1, 255}
