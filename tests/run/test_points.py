"""run/points.py: points read from the command line, CSV and GeoJSON, placed on a DEM's grid
(fractional row and column, snapped to centres), their ground interpolated bilinearly."""

import json
import types

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.run import points


def test_parse_pair():
    assert points.parse_pair(" 1.5, -2 ", "--at") == (1.5, -2.0)
    with pytest.raises(UsageProblem, match="--at must be two numbers"):
        points.parse_pair("1,2,3", "--at")
    with pytest.raises(UsageProblem, match="finite"):
        points.parse_pair("nan,2", "--at")


def test_read_points_csv_and_geojson(tmp_path):
    p = tmp_path / "p.csv"
    p.write_text("\ufeffName, LON ,Lat\nsummit,7.5,46.25\n,8,47\n", encoding="utf-8")
    got = points.read_points(str(p))
    assert got == [{"id": "summit", "lon": 7.5, "lat": 46.25}, {"id": "", "lon": 8.0, "lat": 47.0}]
    p = tmp_path / "xy.csv"
    p.write_text("x,y\n500010,5199990\n")
    assert points.read_points(str(p)) == [{"id": "0", "x": 500010.0, "y": 5199990.0}]
    g = tmp_path / "p.geojson"
    g.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "geometry": {"type": "Point", "coordinates": [7.0, 46.0, 1200]},
         "properties": {"name": "a"}},
        {"type": "Feature", "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, 1]]}},
        {"type": "Feature", "geometry": {"type": "Point", "coordinates": [8.0, 47.0]},
         "properties": None}]}))
    assert points.read_points(str(g)) == [{"id": "a", "lon": 7.0, "lat": 46.0},
                                          {"id": "2", "lon": 8.0, "lat": 47.0}]


@pytest.mark.parametrize("name, text, why", [
    ("a.csv", "", "no points"),
    ("a.csv", "e,n\n1,2\n", "no coordinates"),
    ("a.csv", "lon,lat\n1,x\n", "row 2: '1', 'x' are not numbers"),
    ("a.csv", "lon,lat\n1,2\n1,inf\n", "row 3: .* are not finite"),
    ("a.json", "{", "not a GeoJSON file of points"),
    ("a.geojson", '{"type": "Feature", "geometry": null}', "no Point feature"),
])
def test_read_points_refusals(tmp_path, name, text, why):
    p = tmp_path / name
    p.write_text(text)
    with pytest.raises(HillshadeError, match=why):
        points.read_points(str(p))
    with pytest.raises(HillshadeError, match="absent.csv: "):
        points.read_points(str(tmp_path / "absent.csv"))


def test_gather_orders_and_numbers():
    got = points.gather([(7.0, 46.0)], [(1.0, 2.0), (3.0, 4.0)], None)
    assert got == [{"id": "0", "lon": 7.0, "lat": 46.0}, {"id": "1", "x": 1.0, "y": 2.0},
                   {"id": "2", "x": 3.0, "y": 4.0}]
    with pytest.raises(UsageProblem, match="give a point"):
        points.gather([], [], None)


def test_snap():
    assert points.snap(3.0000004) == 3.0 and points.snap(-0.0000009) == 0.0
    assert points.snap(2.5) == 2.5 and points.snap(3.00001) == 3.00001


UTM = CRS.from_epsg(32632)
TR = Affine(10, 0, 500000, 0, -10, 5200000)


def _src(crs=UTM, transform=TR):
    return types.SimpleNamespace(path="dem.tif", crs=crs, transform=transform)


def test_locate_xy_and_lonlat():
    """(x, y) of a cell centre -> its whole row and column; a lon/lat through the CRS and
    back lands on the same place."""
    pts = [{"id": "0", "x": 500000 + 10 * 3.5, "y": 5200000 - 10 * 7.5},   # centre of (7, 3)
           {"id": "1", "x": 500000 + 10 * 2.25, "y": 5200000 - 10 * 1.0}]
    got, to_ll = points.locate(pts, _src())
    assert (got[0]["row"], got[0]["col"]) == (7.0, 3.0)
    assert got[1]["row"] == pytest.approx(0.5) and got[1]["col"] == pytest.approx(1.75)
    lon, lat = got[0]["lon"], got[0]["lat"]
    assert 8.9 < lon < 9.1 and 46.9 < lat < 47.0          # UTM 32N near 500 km E, 5200 km N
    again, _ = points.locate([{"id": "a", "lon": lon, "lat": lat}], _src())
    assert (again[0]["row"], again[0]["col"]) == (7.0, 3.0)


def test_locate_refusals():
    with pytest.raises(HillshadeError, match="no georeferencing"):
        points.locate([{"id": "0", "x": 1.0, "y": 1.0}], _src(transform=None))
    with pytest.raises(HillshadeError, match="no CRS"):
        points.locate([{"id": "0", "lon": 1.0, "lat": 1.0}], _src(crs=None))
    got, to_ll = points.locate([{"id": "0", "x": 500005.0, "y": 5199995.0}], _src(crs=None))
    assert to_ll is None and got[0]["lon"] is None and (got[0]["row"], got[0]["col"]) == (0, 0)


def test_on_ground_is_bilinear_and_refuses_outside_and_nodata():
    r, c = np.mgrid[0:4, 0:5]
    z = (2.0 * r + 3.0 * c + 1.0).astype(np.float32)       # a plane: bilinear is exact
    z[3, 4] = np.nan
    d = types.SimpleNamespace(shape=z.shape, heights=z)
    got = points.on_ground([{"id": "0", "row": 1.25, "col": 2.5, "x": 0.0, "y": 0.0}], d, 1.5)
    assert got[0]["ground"] == pytest.approx(2.0 * 1.25 + 3.0 * 2.5 + 1.0)
    assert got[0]["observer"] == pytest.approx(got[0]["ground"] + 1.5)
    with pytest.raises(HillshadeError, match="point 7 .* is outside the DEM's cell centres"):
        points.on_ground([{"id": "7", "row": 3.2, "col": 0.0, "x": 1.0, "y": 2.0}], d)
    with pytest.raises(HillshadeError, match="point 8 lies on nodata"):
        points.on_ground([{"id": "8", "row": 2.5, "col": 3.5, "x": 1.0, "y": 2.0}], d)


def test_write_text_to_a_file_or_stdout(tmp_path, capsys):
    out = tmp_path / "o.txt"
    points.write_text(str(out), "a,b\n")
    assert out.read_text() == "a,b\n"
    with pytest.raises(HillshadeError):
        points.write_text(str(out), "again\n")          # no clobbering without overwrite
    points.write_text(str(out), "c\n", overwrite=True)
    assert out.read_text() == "c\n"
    points.write_text(None, "to stdout\n")
    assert capsys.readouterr().out == "to stdout\n"
