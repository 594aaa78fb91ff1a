"""STAC (issue 23, item 4): ``--sun-from-stac ITEM`` takes a satellite scene's sun from its
item (``view:sun_azimuth`` / ``view:sun_elevation``, else its datetime) and ``--stac-item
OUT.json`` writes a STAC item describing the output (pystac), validated here against the STAC
schemas without the network (tests/data/stac_schemas)."""

import datetime as dt
import hashlib
import json
import os
import pathlib
import zipfile

import numpy as np
import pytest
from affine import Affine
from pyproj import Transformer
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.io.stac import item_sun
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff

SCHEMAS = pathlib.Path(__file__).resolve().parents[1] / "data" / "stac_schemas"
# the STAC extension schemas the written items declare, vendored (SOURCES.md there)
SCHEMA_FILES = {
    "https://stac-extensions.github.io/projection/v2.0.0/schema.json": "projection-v2.0.0.json",
    "https://stac-extensions.github.io/view/v1.0.0/schema.json": "view-v1.0.0.json",
    "https://stac-extensions.github.io/file/v2.1.0/schema.json": "file-v2.1.0.json",
}
UTM32 = CRS.from_epsg(32632)
T = Affine(10.0, 0, 420000.0, 0, -10.0, 5160000.0)     # 10 m cells in the Alps (46.6 N, 8 E)
WHEN = "2023-07-14T10:27:39.024000Z"


def sentinel2_item(**props) -> dict:
    """A Sentinel-2 L2A item as Earth Search serves them (its properties' names and kinds), the
    sun's angles of the brief: azimuth 151.3, elevation 28.7."""
    p = {"created": "2023-07-14T16:05:12.104Z", "platform": "sentinel-2b",
         "constellation": "sentinel-2", "instruments": ["msi"], "eo:cloud_cover": 3.21,
         "proj:epsg": 32632, "mgrs:utm_zone": 32, "mgrs:latitude_band": "T",
         "mgrs:grid_square": "MS", "grid:code": "MGRS-32TMS", "view:sun_azimuth": 151.3,
         "view:sun_elevation": 28.7, "s2:mean_solar_azimuth": 151.3,
         "s2:mean_solar_zenith": 61.3, "s2:processing_baseline": "05.09",
         "s2:product_type": "S2MSI2A", "datetime": WHEN}
    p.update(props)
    p = {k: v for k, v in p.items() if v is not ...}
    return {"type": "Feature", "stac_version": "1.0.0",
            "stac_extensions": ["https://stac-extensions.github.io/eo/v1.1.0/schema.json",
                                "https://stac-extensions.github.io/projection/v1.1.0/schema.json",
                                "https://stac-extensions.github.io/view/v1.0.0/schema.json",
                                "https://stac-extensions.github.io/mgrs/v1.0.0/schema.json"],
            "id": "S2B_32TMS_20230714_0_L2A",
            "geometry": {"type": "Polygon", "coordinates": [[[7.66, 46.85], [9.10, 46.87],
                                                             [9.08, 45.88], [7.67, 45.86],
                                                             [7.66, 46.85]]]},
            "bbox": [7.66, 45.86, 9.10, 46.87], "properties": p,
            "links": [{"rel": "self", "href": "https://earth-search.aws.element84.com/v1/"
                       "collections/sentinel-2-l2a/items/S2B_32TMS_20230714_0_L2A"}],
            "assets": {"red": {"href": "https://sentinel-cogs.s3.us-west-2.amazonaws.com/"
                               "sentinel-s2-l2a-cogs/32/T/MS/2023/7/S2B_32TMS_20230714_0_L2A/"
                               "B04.tif", "type": "image/tiff; application=geotiff; "
                               "profile=cloud-optimized", "roles": ["data"]}},
            "collection": "sentinel-2-l2a"}


def _json(path, doc) -> str:
    path.write_text(json.dumps(doc))
    return str(path)


@pytest.fixture
def dem(tmp_path):
    """A DEM in UTM 32N, west of the zone's central meridian (9 E): grid north is 0.76 degrees
    east of true north at its centre."""
    z = fractal_terrain(60, 70, seed=23, relief=400.0)
    return write_geotiff(tmp_path / "dem.tif", z, T, UTM32)


@pytest.fixture
def dem_ll(tmp_path):
    """A DEM in longitude/latitude (grid north is true north), 0.0001 degree cells (~10 m)."""
    z = fractal_terrain(60, 70, seed=23, relief=400.0)
    return write_geotiff(tmp_path / "dem_ll.tif", z, Affine(1e-4, 0, 7.96, 0, -1e-4, 46.59),
                         CRS.from_epsg(4326))


@pytest.fixture
def offline(monkeypatch):
    """No URL is read: pystac's StacIO (the validator's schema fetches) and urllib refuse."""
    import urllib.request

    import pystac.stac_io

    def refuse(*a, **k):
        raise AssertionError(f"the test tried to read a URL: {a or k}")
    local = pystac.stac_io.DefaultStacIO.read_text_from_href

    def local_only(self, href, *a, **k):
        if "://" in str(href):
            refuse(href)
        return local(self, href, *a, **k)
    monkeypatch.setattr(pystac.stac_io.DefaultStacIO, "read_text_from_href", local_only)
    monkeypatch.setattr(urllib.request, "urlopen", refuse)


def validator():
    """pystac's JSON-schema validator with the vendored extension schemas in its cache (the core
    STAC and GeoJSON schemas come with pystac): validation never fetches a schema."""
    from pystac.validation import JsonSchemaSTACValidator
    v = JsonSchemaSTACValidator()
    for uri, name in SCHEMA_FILES.items():
        v.schema_cache[uri] = json.loads((SCHEMAS / name).read_text())
    return v


def run(runner, *args):
    return runner.invoke(cli, [str(a) for a in args])


def test_the_mask_from_an_item_is_the_mask_of_its_angles(runner, tmp_path, dem_ll):
    dem = dem_ll
    item = _json(tmp_path / "item.json", sentinel2_item())
    a, b, rep = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "r.json"
    r = run(runner, "shadow", dem, a, "--sun-from-stac", item, "--report", rep)
    assert r.exit_code == 0, r.output
    r = run(runner, "shadow", dem, b, "--azimuth", 151.3, "--elevation", 28.7)
    assert r.exit_code == 0, r.output
    ma, mb = read_band(a), read_band(b)
    assert np.array_equal(ma, mb) and 0 < (ma == 1).mean() < 0.9
    import rasterio
    with rasterio.open(a) as ds:
        tags, band = ds.tags(), ds.tags(1)
    assert tags["STAC_ITEM"] == "S2B_32TMS_20230714_0_L2A"
    assert tags["SUN_SOURCE"].startswith("STAC item (angles: view:sun_azimuth")
    assert float(band["SUN_AZIMUTH"]) == pytest.approx(151.3)
    doc = json.loads(rep.read_text())
    assert doc["sun_from_stac"]["item"] == "S2B_32TMS_20230714_0_L2A"
    assert doc["sun_from_stac"]["sun_from"] == "angles" and doc["sun_source"] == "given"
    assert doc["sun"]["azimuth"] == pytest.approx(151.3)


def test_hillshade_takes_the_items_sun_too(runner, tmp_path, dem_ll):
    dem = dem_ll
    item = _json(tmp_path / "item.json", sentinel2_item())
    a, b = tmp_path / "a.tif", tmp_path / "b.tif"
    assert run(runner, "hillshade", dem, a, "--sun-from-stac", item).exit_code == 0
    assert run(runner, "hillshade", dem, b, "--azimuth", 151.3, "--elevation", 28.7
               ).exit_code == 0
    ha, hb = read_band(a), read_band(b)
    assert np.array_equal(ha, hb)
    # not the default sun (315, 45): the item's sun was used
    c = tmp_path / "c.tif"
    assert run(runner, "hillshade", dem, c).exit_code == 0
    assert not np.array_equal(ha, read_band(c))


def test_the_written_item_validates_and_describes_the_raster(runner, tmp_path, dem, offline):
    import pystac
    item = _json(tmp_path / "scene.json", sentinel2_item())
    out = tmp_path / "out" / "shadow_alps.tif"
    out.parent.mkdir()
    meta = tmp_path / "meta" / "shadow_alps.json"
    meta.parent.mkdir()
    r = run(runner, "shadow", dem, out, "--sun-from-stac", item, "--stac-item", meta)
    assert r.exit_code == 0, r.output
    written = pystac.Item.from_file(str(meta))
    checked = written.validate(validator=validator())
    assert set(SCHEMA_FILES) <= set(checked)       # every extension's schema was checked
    d = json.loads(meta.read_text())
    assert d["id"] == "shadow_alps"
    p = d["properties"]
    assert p["datetime"] == "2023-07-14T10:27:39.024000Z"          # the scene's time
    assert p["view:sun_azimuth"] == 151.3 and p["view:sun_elevation"] == 28.7
    assert p["proj:code"] == "EPSG:32632" and p["proj:shape"] == [60, 70]
    assert p["proj:transform"] == [10.0, 0.0, 420000.0, 0.0, -10.0, 5160000.0]
    assert p["proj:bbox"] == [420000.0, 5159400.0, 420700.0, 5160000.0]
    assert p["hillshade_rt:sun_from_stac"] == "S2B_32TMS_20230714_0_L2A"
    assert "--sun-from-stac" in p["hillshade_rt:command"]
    assert p["hillshade_rt:product"] == "shadow"
    # the footprint: the raster's corners in WGS84, inside the bbox
    to_ll = Transformer.from_crs(32632, 4326, always_xy=True)
    corners = [to_ll.transform(x, y) for x, y in ((420000, 5160000), (420700, 5159400))]
    w, s, e, n = d["bbox"]
    for lon, lat in corners:
        assert w - 1e-9 <= lon <= e + 1e-9 and s - 1e-9 <= lat <= n + 1e-9
    assert e - w < 0.02 and n - s < 0.01 and 7.9 < w < 8.0 and 46.5 < s < 46.6
    ring = d["geometry"]["coordinates"][0]
    assert ring[0] == ring[-1] and len(ring) > 5
    # the asset: the raster, its href relative to the item, its checksum and size
    a = d["assets"]["data"]
    assert a["href"] == "../out/shadow_alps.tif"
    assert a["type"] == "image/tiff; application=geotiff" and a["roles"] == ["data"]
    data = out.read_bytes()
    assert a["file:checksum"] == "1220" + hashlib.sha256(data).hexdigest()
    assert a["file:size"] == len(data)
    assert written.assets["data"].get_absolute_href() == str(out)
    assert not list(meta.parent.glob(".*"))          # no temporary file left


def test_a_damaged_item_does_not_validate(tmp_path, dem, runner, offline):
    """The validation above can fail: the same item with a bad checksum and sun is refused."""
    import pystac
    from pystac.errors import STACValidationError
    out, meta = tmp_path / "o.tif", tmp_path / "o.json"
    r = run(runner, "shadow", dem, out, "--azimuth", 200, "--elevation", 30,
            "--stac-item", meta)
    assert r.exit_code == 0, r.output
    d = json.loads(meta.read_text())
    assert "datetime" in d["properties"]       # now, without a time
    pystac.Item.from_dict(d).validate(validator=validator())
    d["assets"]["data"]["file:checksum"] = "not hex"
    with pytest.raises(STACValidationError):
        pystac.Item.from_dict(d).validate(validator=validator())
    d = json.loads(meta.read_text())
    d["properties"]["view:sun_elevation"] = 123.0
    with pytest.raises(STACValidationError):
        pystac.Item.from_dict(d).validate(validator=validator())


def test_an_item_without_angles_gives_its_datetime_and_says_so(runner, tmp_path, dem):
    item = _json(tmp_path / "item.json", sentinel2_item(**{
        "view:sun_azimuth": ..., "view:sun_elevation": ..., "s2:mean_solar_azimuth": ...,
        "s2:mean_solar_zenith": ...}))
    a, b, rep = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "r.json"
    r = run(runner, "shadow", dem, a, "--sun-from-stac", item, "--report", rep)
    assert r.exit_code == 0, r.output
    assert "no view:sun_azimuth/view:sun_elevation" in r.stderr and WHEN[:19] in r.stderr
    r = run(runner, "shadow", dem, b, "--time", WHEN)
    assert r.exit_code == 0, r.output
    assert np.array_equal(read_band(a), read_band(b))
    doc = json.loads(rep.read_text())
    assert doc["sun_source"] == "time" and doc["sun_from_stac"]["sun_from"] == "datetime"


def test_planetary_computer_landsat_and_old_eo_items():
    """The property names of Sentinel-2 L2A on Planetary Computer (s2:mean_solar_*: a zenith),
    Landsat Collection 2 (view:sun_*, no eo sun) and sat-api's Landsat (eo:sun_*)."""
    pc = sentinel2_item(**{"view:sun_azimuth": ..., "view:sun_elevation": ...,
                           "s2:mean_solar_azimuth": 151.3, "s2:mean_solar_zenith": 61.3})
    s = item_sun(pc, "pc.json")
    assert (s.azimuth, s.elevation) == pytest.approx((151.3, 28.7))
    assert s.keys == ("s2:mean_solar_azimuth", "s2:mean_solar_zenith")
    landsat = {"type": "Feature", "stac_version": "1.0.0", "id": "LC09_L2SP_195028_20230715_"
               "20230717_02_T1", "properties": {"datetime": "2023-07-15T10:13:52.812129Z",
                                                 "platform": "landsat-9",
                                                 "view:sun_azimuth": 136.95,
                                                 "view:sun_elevation": 60.78,
                                                 "view:off_nadir": 0,
                                                 "landsat:wrs_path": "195"}}
    s = item_sun(landsat, "ls.json")
    assert (s.azimuth, s.elevation, s.id) == (136.95, 60.78, landsat["id"])
    assert s.time == dt.datetime(2023, 7, 15, 10, 13, 52, 812129, tzinfo=dt.timezone.utc)
    old = {"type": "Feature", "id": "LC80300322019001", "properties": {
        "datetime": "2019-01-01T17:31:47Z", "eo:sun_azimuth": 154.88, "eo:sun_elevation": 28.26}}
    assert item_sun(old, "o.json").elevation == 28.26
    coll = {"type": "FeatureCollection", "features": [landsat]}
    assert item_sun(coll, "c.json").id == landsat["id"]


def test_an_item_collection_of_one_and_a_zip_member(runner, tmp_path, dem_ll, monkeypatch):
    dem = dem_ll
    a, b, c = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "c.tif"
    coll = _json(tmp_path / "search.json",
                 {"type": "FeatureCollection", "features": [sentinel2_item()]})
    assert run(runner, "shadow", dem, a, "--sun-from-stac", coll).exit_code == 0
    with zipfile.ZipFile(tmp_path / "scene.zip", "w") as z:
        z.writestr("S2B/item.json", json.dumps(sentinel2_item()))
    r = run(runner, "shadow", dem, b, "--sun-from-stac",
            f"/vsizip/{tmp_path / 'scene.zip'}/S2B/item.json")
    assert r.exit_code == 0, r.output
    monkeypatch.chdir(tmp_path)
    r = run(runner, "shadow", dem, c, "--sun-from-stac", "zip://scene.zip!S2B/item.json")
    assert r.exit_code == 0, r.output
    assert np.array_equal(read_band(a), read_band(b)) and np.array_equal(read_band(a),
                                                                          read_band(c))


def test_a_series_item_has_a_span_and_no_single_sun(runner, tmp_path, dem, offline):
    import pystac
    out, meta = tmp_path / "s.tif", tmp_path / "s.json"
    r = run(runner, "shadow", dem, out, "--start", "2023-07-14T08:00Z", "--end",
            "2023-07-14T10:00Z", "--step", "1h", "--stac-item", meta)
    assert r.exit_code == 0, r.output
    d = json.loads(meta.read_text())
    p = d["properties"]
    assert p["datetime"] is None
    assert p["start_datetime"] == "2023-07-14T08:00:00Z"
    assert p["end_datetime"] == "2023-07-14T10:00:00Z"
    assert "view:sun_azimuth" not in p and p["hillshade_rt:bands"] == 3
    pystac.Item.from_file(str(meta)).validate(validator=validator())


def test_query_takes_the_items_sun(runner, tmp_path, dem):
    item = _json(tmp_path / "item.json", sentinel2_item())
    out = tmp_path / "q.json"
    r = run(runner, "query", dem, "--at-xy", "420305,5159705", "--sun-from-stac", item,
            "-o", out, "--format", "json")
    assert r.exit_code == 0, r.output
    doc = json.loads(out.read_text())
    assert doc["sun_from_stac"]["item"] == "S2B_32TMS_20230714_0_L2A"
    assert doc["rows"][0]["sun_elevation_deg"] == pytest.approx(28.7)


@pytest.mark.parametrize("content, code, words", [
    (None, 1, "no such file"),
    ("{not json", 1, "not JSON"),
    (json.dumps([1, 2]), 1, "not a STAC item"),
    (json.dumps(sentinel2_item(**{"view:sun_azimuth": ..., "view:sun_elevation": ...,
                                  "s2:mean_solar_azimuth": ..., "s2:mean_solar_zenith": ...,
                                  "datetime": None, "start_datetime": "2023-01-01T00:00:00Z",
                                  "end_datetime": "2023-12-31T00:00:00Z"})), 1, "gives no sun"),
    (json.dumps(sentinel2_item(**{"view:sun_elevation": ...})), 1,
     "has view:sun_azimuth but no view:sun_elevation"),
    (json.dumps(sentinel2_item(**{"view:sun_elevation": -3.0})), 1, "below the horizon"),
    (json.dumps({"type": "FeatureCollection", "features": [sentinel2_item()] * 2}), 1,
     "holds 2 items"),
])
def test_bad_items_fail_in_one_line(runner, tmp_path, dem, content, code, words):
    item = tmp_path / "item.json"
    if content is not None:
        item.write_text(content)
    out = tmp_path / "o.tif"
    r = run(runner, "shadow", dem, out, "--sun-from-stac", item, "--stac-item",
            tmp_path / "o.json")
    assert r.exit_code == code, r.output
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "Traceback" not in r.output
    assert not out.exists() and not (tmp_path / "o.json").exists()


@pytest.mark.parametrize("extra, words", [
    (["--azimuth", "10", "--elevation", "20"], "not with --azimuth, --elevation"),
    (["--time", WHEN], "not with --time"),
    (["--tz", "Europe/Zurich"], "the STAC item S2B_32TMS_20230714_0_L2A gives the sun's angles"),
    (["--stac-item", "{dir}/item.json", "--overwrite"], "--stac-item is also an input"),
    (["--stac-item", "{dir}/o.tif"], "name the same file"),
    (["--output-pattern", "{dir}/o_{{index}}.tif", "--stac-item", "{dir}/m.json"],
     "not the files of --output-pattern"),
])
def test_conflicts_are_usage_errors(runner, tmp_path, dem, extra, words):
    item = _json(tmp_path / "item.json", sentinel2_item())
    args = ["shadow", dem] + ([] if "--output-pattern" in extra else [tmp_path / "o.tif"])
    args += ["--sun-from-stac", item] + [e.format(dir=tmp_path) for e in extra]
    r = run(runner, *args)
    assert r.exit_code == 2, r.output
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not (tmp_path / "o.tif").exists()
    assert json.loads((tmp_path / "item.json").read_text())["id"]    # the item untouched


def test_a_point_light_refuses_the_stac_options(runner, tmp_path, dem):
    item = _json(tmp_path / "item.json", sentinel2_item())
    r = run(runner, "shadow", dem, tmp_path / "o.tif", "--light-position",
            "420300,5159700,3000", "--stac-item", tmp_path / "o.json")
    assert r.exit_code == 2 and "--stac-item" in r.stderr, r.output
    r = run(runner, "shadow", dem, tmp_path / "o.tif", "--light-position",
            "420300,5159700,3000", "--sun-from-stac", item)
    assert r.exit_code == 2, r.output


def test_a_dem_without_crs_gets_an_item_without_geometry(runner, tmp_path, offline):
    import pystac
    z = fractal_terrain(40, 40, seed=5, relief=50.0)
    dem = write_geotiff(tmp_path / "plain.tif", z)
    out, meta = tmp_path / "o.tif", tmp_path / "o.json"
    r = run(runner, "shadow", dem, out, "--pixel-size", 2, "--azimuth", 120, "--elevation", 25,
            "--stac-item", meta)
    assert r.exit_code == 0, r.output
    d = json.loads(meta.read_text())
    assert d["geometry"] is None and "bbox" not in d and d["properties"]["proj:code"] is None
    assert d["properties"]["proj:shape"] == [40, 40]
    assert "proj:transform" not in d["properties"] and "proj:bbox" not in d["properties"]
    pystac.Item.from_file(str(meta)).validate(validator=validator())


def test_the_python_api_takes_both(tmp_path, dem):
    import hillshade_rt as hr
    item = _json(tmp_path / "item.json", sentinel2_item())
    rep = hr.shade(dem, str(tmp_path / "a.tif"), sun_from_stac=item,
                   stac_item=tmp_path / "a.json")
    assert rep["sun_from_stac"]["item"] == "S2B_32TMS_20230714_0_L2A"
    d = json.loads((tmp_path / "a.json").read_text())
    assert d["properties"]["view:sun_elevation"] == 28.7
    assert d["properties"]["hillshade_rt:command"].startswith("hillshade_rt.shade")


def test_reading_an_item_imports_no_pystac(tmp_path):
    """pystac is imported only to write an item: the command line and a run that reads one do
    not import it."""
    import subprocess
    import sys
    item = _json(tmp_path / "item.json", sentinel2_item())
    code = ("import sys\n"
            "import hillshade_rt.cli, hillshade_rt.run.shade\n"
            "from hillshade_rt.run.stac import sun_from_item\n"
            f"sun, scene = sun_from_item({{'sun_from_stac': {item!r}}})\n"
            "assert sun['azimuth'] == 151.3 and scene.id.startswith('S2B')\n"
            "print('pystac' in sys.modules, 'jsonschema' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "False"]


def test_an_item_from_a_url(runner, tmp_path, dem):
    """An http URL (a server on the loopback interface: the test stays offline); a missing one
    fails in one line."""
    import functools
    import http.server
    import threading
    _json(tmp_path / "item.json", sentinel2_item())
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *a):      # the server's log is not the command's stderr
            pass
    handler = functools.partial(Quiet, directory=str(tmp_path))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        url = f"http://127.0.0.1:{server.server_address[1]}"
        a, rep = tmp_path / "a.tif", tmp_path / "r.json"
        r = run(runner, "shadow", dem, a, "--sun-from-stac", f"{url}/item.json", "--report", rep)
        assert r.exit_code == 0, r.output
        assert json.loads(rep.read_text())["sun_from_stac"]["elevation"] == 28.7
        r = run(runner, "shadow", dem, tmp_path / "b.tif", "--sun-from-stac", f"{url}/no.json")
        assert r.exit_code == 1 and "HTTP 404" in r.stderr, r.output
        assert len(r.stderr.strip().splitlines()) == 1
    finally:
        server.shutdown()
        server.server_close()


def test_a_dem_outside_the_scene_is_said(runner, tmp_path, dem):
    """The DEM lies in the Alps (46.6 N, 7.96 E): an item over Minnesota gets a note; the
    Sentinel-2 tile around it does not."""
    far = sentinel2_item()
    far["bbox"] = [-94.5, 46.0, -93.0, 47.0]
    item = _json(tmp_path / "far.json", far)
    r = run(runner, "shadow", dem, tmp_path / "a.tif", "--sun-from-stac", item)
    assert r.exit_code == 0 and "lies outside the bbox of STAC item" in r.stderr, r.output
    near = _json(tmp_path / "near.json", sentinel2_item(**{}))
    r = run(runner, "shadow", dem, tmp_path / "b.tif", "--sun-from-stac", near)
    assert r.exit_code == 0 and "lies outside" not in r.stderr, r.output


def test_a_sun_from_a_time_dates_the_item_and_gives_the_true_azimuth(runner, tmp_path, dem):
    out, meta, rep = tmp_path / "t.tif", tmp_path / "t.json", tmp_path / "r.json"
    r = run(runner, "shadow", dem, out, "--time", "2023-07-14T10:27:39Z", "--stac-item", meta,
            "--report", rep)
    assert r.exit_code == 0, r.output
    p = json.loads(meta.read_text())["properties"]
    sun = json.loads(rep.read_text())["sun"]
    assert p["datetime"] == "2023-07-14T10:27:39Z" and p["hillshade_rt:sun_source"] == "time"
    assert p["view:sun_azimuth"] == pytest.approx(sun["true_azimuth"])
    assert p["view:sun_elevation"] == pytest.approx(sun["elevation"])
    # west of its zone's central meridian (9 E), grid north is west of true north
    assert sun["true_azimuth"] != pytest.approx(sun["azimuth"], abs=0.1)


def test_on_a_projected_dem_the_items_azimuth_is_turned_to_grid_north(runner, tmp_path, dem):
    """view:sun_azimuth is from true north; a UTM DEM's rows run along grid north: the item's
    azimuth is turned by the meridian convergence at the DEM's centre (pyproj's, independently),
    as a sun from a time is; the report keeps the item's as the true azimuth."""
    from pyproj import Proj
    item = _json(tmp_path / "item.json", sentinel2_item())
    a, rep = tmp_path / "a.tif", tmp_path / "r.json"
    r = run(runner, "shadow", dem, a, "--sun-from-stac", item, "--report", rep)
    assert r.exit_code == 0, r.output
    sun = json.loads(rep.read_text())["sun"]
    lon, lat = Transformer.from_crs(32632, 4326, always_xy=True).transform(420350.0, 5159700.0)
    gamma = Proj(32632).get_factors(lon, lat).meridian_convergence      # -0.755 here
    assert gamma == pytest.approx(-0.755, abs=0.01)
    assert sun["azimuth"] == pytest.approx(151.3 - gamma, abs=1e-6)
    assert sun["true_azimuth"] == 151.3 and sun["elevation"] == 28.7
    b = tmp_path / "b.tif"
    r = run(runner, "shadow", dem, b, "--azimuth", repr(sun["azimuth"]), "--elevation", 28.7)
    assert r.exit_code == 0, r.output
    assert np.array_equal(read_band(a), read_band(b))
    c = tmp_path / "c.tif"       # the untouched angle gives another mask: the turn matters here
    assert run(runner, "shadow", dem, c, "--azimuth", 151.3, "--elevation", 28.7).exit_code == 0
    assert not np.array_equal(read_band(a), read_band(c))
