"""Subsolar series files (issue 21): the plain CSV and a JPL Horizons table; bad files are
one-line errors naming the line."""

import numpy as np
import pytest

from hillshade_rt.model.ephemeris import AU_M, read_subsolar, subsolar_point
from hillshade_rt.errors import HillshadeError


def write(tmp_path, text, name="sun.csv"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def test_plain_csv_with_distances_in_au(tmp_path):
    p = write(tmp_path, "# a lunation\ntime,lat,lon,distance_au\n"
                        "2026-01-01T00:00Z,1.5,-30,0.99\n"
                        "2026-01-01T06:00Z,1.49,-33.05,0.99\n"
                        "2026-01-01T12:00+02:00,1.48,190,1.01\n")
    s = read_subsolar(p)
    assert len(s) == 3
    assert s.lat.tolist() == [1.5, 1.49, 1.48]
    assert s.lon[2] == pytest.approx(-170.0)            # wrapped into [-180, 180)
    assert s.distance == pytest.approx([0.99 * AU_M, 0.99 * AU_M, 1.01 * AU_M])
    # the third row is 10:00 UTC: 4 hours after the second
    assert np.diff(s.unix).tolist() == [6 * 3600, 4 * 3600]
    assert s.durations_h().tolist() == [6, 4, 4]
    assert s.times()[2].hour == 10


def test_plain_csv_without_distance_and_other_names(tmp_path):
    s = read_subsolar(write(tmp_path, "Time , Latitude, Longitude\n2026-03-01T00:00Z, -1, 5\n"))
    assert s.distance is None and s.lat.tolist() == [-1.0] and s.lon.tolist() == [5.0]
    assert s.durations_h().tolist() == [0.0]


@pytest.mark.parametrize("text, words", [
    ("time,lat\n2026-01-01T00:00Z,1\n", "no lon column"),
    ("when,lat,lon\n2026-01-01T00:00Z,1,2\n", "no time column"),
    ("time,lat,lon\n2026-01-01T00:00Z,95,2\n", "line 2: latitude 95 is outside"),
    ("time,lat,lon\n2026-01-01T06:00Z,1,2\n2026-01-01T00:00Z,1,2\n",
     "times must increase, but row 2 is not after row 1"),
    ("time,lat,lon\n2026-01-01T00:00Z,1,2\n2026-01-01T00:00Z,1,2\n", "times must increase"),
    ("time,lat,lon\n2026-01-01T00:00,1,2\n", "no UTC offset"),
    ("time,lat,lon\n2026-01-01T00:00Z,x,2\n", "line 2: lat 'x' is not a number"),
    ("time,lat,lon\n2026-01-01T00:00Z,1\n", "line 2: 2 fields"),
    ("time,lat,lon,distance_m\n2026-01-01T00:00Z,1,2,-5\n", "distance must be positive"),
    ("time,lat,lon\n", "no rows after the header"),
    ("", "empty"),
])
def test_bad_files_are_one_line_errors(tmp_path, text, words):
    with pytest.raises(HillshadeError) as e:
        read_subsolar(write(tmp_path, text))
    assert words in str(e.value) and "\n" not in str(e.value)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(HillshadeError, match="no such file"):
        read_subsolar(str(tmp_path / "nope.csv"))
    with pytest.raises(HillshadeError, match="is a directory"):
        read_subsolar(str(tmp_path))


HORIZONS = """*******************************************************************************
Target body name: Mars (499)                      {source: mar097}
Target pole/equ : IAU_MARS                        {West-longitude positive}
*******************************************************************************
 Date__(UT)__HR:MN, , , Ob-lon, Ob-lat, Sl-lon, Sl-lat,             r,       rdot,
*******************************************************************************
$$SOE
 2026-Jan-01 00:00, , , 10.0, 2.0, 300.5000, -20.2500, 1.38000000, 1.2,
 2026-Jan-01 01:00, , , 25.0, 2.0, 315.1000, -20.2400, 1.38010000, 1.2,
$$EOE
*******************************************************************************
"""


def test_horizons_table_west_longitudes_and_range(tmp_path):
    s = read_subsolar(write(tmp_path, HORIZONS, "horizons.csv"))
    assert s.lat.tolist() == [-20.25, -20.24]
    # west-positive 300.5 is east -300.5 = 59.5
    assert s.lon == pytest.approx([59.5, 44.9])
    assert s.distance == pytest.approx([1.38 * AU_M, 1.3801 * AU_M])
    assert np.diff(s.unix).tolist() == [3600.0]


def test_horizons_east_positive_and_bad_tables(tmp_path):
    east = HORIZONS.replace("West-longitude", "East-longitude")
    assert read_subsolar(write(tmp_path, east, "e.csv")).lon[0] == pytest.approx(-59.5)
    no_sub = HORIZONS.replace("Sl-lon", "X").replace("Sl-lat", "Y")
    with pytest.raises(HillshadeError, match="quantity 15"):
        read_subsolar(write(tmp_path, no_sub, "n.csv"))
    cut = HORIZONS.split("$$EOE")[0]
    with pytest.raises(HillshadeError, match=r"without its \$\$EOE"):
        read_subsolar(write(tmp_path, cut, "c.csv"))


def test_subsolar_point_checks():
    assert subsolar_point(90, 180) == (90.0, -180.0)
    with pytest.raises(HillshadeError, match="outside -90..90"):
        subsolar_point(-90.5, 0)
    with pytest.raises(HillshadeError, match="finite"):
        subsolar_point(float("nan"), 0)
