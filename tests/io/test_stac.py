"""io/stac.py: an item's sun read from plain JSON (the three families of properties, a zenith
turned into an elevation, times, bboxes, one item of a collection, every refusal in one line),
the item's bytes from files and archives, and what an output's item is made of (checksum,
footprint)."""

import datetime as dt
import gzip
import hashlib
import json
import zipfile

import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import stac

UTC = dt.timezone.utc


def _item(**props):
    p = {"datetime": "2023-07-14T10:27:39.024Z"}
    p.update(props)
    return {"type": "Feature", "id": "S2B_X", "properties": p, "bbox": [7.0, 46.0, 8.0, 47.0]}


def test_view_angles_first_then_s2_zenith_then_eo():
    s = stac.item_sun(_item(**{"view:sun_azimuth": 163.0, "view:sun_elevation": 40.5,
                               "s2:mean_solar_azimuth": 1.0, "s2:mean_solar_zenith": 2.0}), "i")
    assert (s.azimuth, s.elevation, s.keys) == (163.0, 40.5,
                                                ("view:sun_azimuth", "view:sun_elevation"))
    s = stac.item_sun(_item(**{"s2:mean_solar_azimuth": 203.7, "s2:mean_solar_zenith": 61.25}),
                      "i")
    assert (s.azimuth, s.elevation) == (203.7, 28.75)
    s = stac.item_sun(_item(**{"eo:sun_azimuth": 290, "eo:sun_elevation": 12}), "i")
    assert (s.azimuth, s.elevation) == (290.0, 12.0) and s.has_angles
    assert s.time == dt.datetime(2023, 7, 14, 10, 27, 39, 24000, tzinfo=UTC)
    assert s.bbox == (7.0, 46.0, 8.0, 47.0)
    d = s.as_dict()
    assert d["sun_from"] == "angles" and d["properties"] == ["eo:sun_azimuth", "eo:sun_elevation"]
    assert d["datetime"] == "2023-07-14T10:27:39.024000+00:00"


def test_an_item_with_only_a_time():
    s = stac.item_sun(_item(datetime="2023-07-14T10:27:39"), "i")   # no offset: UTC
    assert not s.has_angles and s.time.tzinfo == UTC and s.as_dict()["sun_from"] == "datetime"


@pytest.mark.parametrize("doc, why", [
    ([1, 2], "not a STAC item \\(a JSON list, not an object\\)"),
    ({"type": "FeatureCollection", "features": []}, "the collection holds no item"),
    ({"type": "FeatureCollection", "features": [_item(), _item(), _item(), _item()]},
     "the collection holds 4 items \\(S2B_X, S2B_X, S2B_X, ...\\); give one scene's item"),
    ({"type": "Collection", "id": "c"}, "not a STAC item \\(type 'Collection'"),
    ({"type": "Feature", "id": "x"}, "no properties"),
    ({"type": "Feature", "properties": {}}, "no id"),
    (_item(**{"view:sun_azimuth": 100.0}), "has view:sun_azimuth but no view:sun_elevation"),
    (_item(**{"eo:sun_azimuth": "east", "eo:sun_elevation": 10}),
     "eo:sun_azimuth is 'east', not a number of degrees"),
    (_item(**{"view:sun_azimuth": 100.0, "view:sun_elevation": True}), "not a number"),
    (_item(**{"s2:mean_solar_azimuth": 100.0, "s2:mean_solar_zenith": 91.0}),
     "the sun's elevation is -1 degrees \\(s2:mean_solar_zenith\\)"),
    (_item(datetime=None), "gives no sun: no view:sun_azimuth/view:sun_elevation and no "
                           "datetime$"),
    (_item(datetime=None, start_datetime="2023-01-01T00:00:00Z"), "a span, not an instant"),
    (_item(datetime="yesterday"), "datetime 'yesterday' is not an RFC 3339 time"),
    (_item(datetime=5), "datetime is 5, not a time"),
])
def test_refusals(doc, why):
    with pytest.raises(HillshadeError, match=why):
        stac.item_sun(doc, "item.json")


def test_bbox_of_4_or_6_numbers_else_none():
    assert stac._bbox([1, 2, 3, 4]) == (1.0, 2.0, 3.0, 4.0)
    assert stac._bbox([1, 2, 0, 3, 4, 100]) == (1.0, 2.0, 3.0, 4.0)
    for bad in (None, [1, 2, 3], [1, 2, 3, float("nan")], [1, 2, 3, True], "1,2,3,4"):
        assert stac._bbox(bad) is None


def test_read_item_sun_from_files_and_archives(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    item = _item(**{"view:sun_azimuth": 163.0, "view:sun_elevation": 40.5})
    text = json.dumps(item).encode()
    (tmp_path / "i.json").write_bytes(text)
    with gzip.open(tmp_path / "i.json.gz", "wb") as fh:
        fh.write(text)
    with zipfile.ZipFile(tmp_path / "a.zip", "w") as z:
        z.writestr("sub/i.json", text)
    for path in ("i.json", f"file://{tmp_path}/i.json", "gzip://i.json.gz",
                 f"/vsigzip/{tmp_path}/i.json.gz", "zip://a.zip!sub/i.json",
                 f"/vsizip/{tmp_path}/a.zip/sub/i.json"):
        assert stac.read_item_sun(path).azimuth == 163.0, path
    (tmp_path / "bad.json").write_text("{\n  'x': 1}")
    for path, why in [("absent.json", "absent.json: no such file"),
                      (str(tmp_path), "is a folder, not a STAC item"),
                      ("zip://a.zip!other.json", "no other.json in"),
                      ("/vsis3/bucket/i.json", "reads local files, http\\(s\\) URLs"),
                      ("bad.json", "not JSON: Expecting property name enclosed in double "
                                   "quotes at line 2 column 3")]:
        with pytest.raises(HillshadeError, match=why):
            stac.read_item_sun(path)
    (tmp_path / "bin.json").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(HillshadeError, match="not JSON text|not JSON"):
        stac.read_item_sun("bin.json")


def test_sha256_multihash(tmp_path):
    p = tmp_path / "f"
    p.write_bytes(b"hillshade" * 1000)
    assert stac.sha256_multihash(str(p)) == "1220" + hashlib.sha256(b"hillshade" * 1000).hexdigest()


def test_footprint_of_a_utm_raster():
    """A 10 km square in UTM 32N: its WGS84 ring is closed, passes through the corners'
    lon/lat (pyproj) and its bbox holds them."""
    from pyproj import Transformer
    crs = CRS.from_epsg(32632)
    t = Affine(100.0, 0, 500000.0, 0, -100.0, 5200000.0)
    geom, bbox = stac.footprint(crs, t, (100, 100), points_per_side=4)
    ring = geom["coordinates"][0]
    assert geom["type"] == "Polygon" and ring[0] == ring[-1] and len(ring) == 17
    to_ll = Transformer.from_crs("EPSG:32632", "EPSG:4326", always_xy=True)
    for x, y in [(500000, 5200000), (510000, 5200000), (510000, 5190000), (500000, 5190000)]:
        lon, lat = to_ll.transform(x, y)
        assert any(abs(p[0] - lon) < 1e-9 and abs(p[1] - lat) < 1e-9 for p in ring)
        assert bbox[0] <= lon <= bbox[2] and bbox[1] <= lat <= bbox[3]
    assert stac.footprint(None, t, (100, 100)) == (None, None)
    moon = CRS.from_proj4("+proj=eqc +R=1737400 +units=m")
    with pytest.raises(HillshadeError, match="not on the Earth"):
        stac.footprint(moon, t, (100, 100))
