"""``hillshade-rt profile`` (issue 20, item 2): horizon profiles at points, in the formats the
tools around PV siting and GIS read, each round-tripped."""

import json

import numpy as np
import pandas as pd
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.io import read_dem
from hillshade_rt.testing import data_path, fractal_terrain, read_band, write_geotiff

SRTM = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")      # geographic (EPSG:4326)


@pytest.fixture
def utm_dem(tmp_path):
    z = fractal_terrain(120, 140, 9, relief=600.0)
    z[5, 5] = np.nan
    return write_geotiff(tmp_path / "dem.tif", z, Affine(30, 0, 500000, 0, -30, 4000000),
                         CRS.from_epsg(32633)), z


def _json(runner, args):
    r = runner.invoke(cli, ["profile"] + args + ["--format", "json"])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


@pytest.mark.parametrize("dem_kind", ["utm", pytest.param("geographic", marks=pytest.mark.slow)])
def test_profile_at_cell_centres_is_the_horizon_raster(tmp_path, runner, utm_dem, dem_kind):
    """At a cell centre with the observer on the ground, the profile is the horizon raster's
    value there, every 10 degrees (projected and geographic DEMs, curvature by default)."""
    dem = utm_dem[0] if dem_kind == "utm" else SRTM
    d = read_dem(dem)
    cells = [(17, 23), (60, 70), (100, 9)]
    xy = [d.transform @ (c + 0.5, r + 0.5) for r, c in cells]
    doc = _json(runner, [dem, "--step", "10"] + sum((["--at-xy", f"{x!r},{y!r}"]
                                                     for x, y in xy), []))
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["horizon", dem, str(out), "--directions", "36"])
    assert r.exit_code == 0, r.output
    bands = np.stack([read_band(out, b) for b in range(1, 37)])
    for p, (row, col) in zip(doc["points"], cells):
        assert p["azimuth"] == [10.0 * i for i in range(36)]
        np.testing.assert_allclose(p["horizon_deg"], bands[:, row, col], atol=2e-5)


def test_observer_above_the_ground_sees_a_lower_horizon(runner, utm_dem):
    dem = utm_dem[0]
    base = _json(runner, [dem, "--at-xy", "502015.5,3998123.25", "--step", "15"])
    up = _json(runner, [dem, "--at-xy", "502015.5,3998123.25", "--step", "15",
                        "--height-above-ground", "25"])
    a, b = np.array(base["points"][0]["horizon_deg"]), np.array(up["points"][0]["horizon_deg"])
    assert (b <= a + 1e-9).all() and (b < a).any()
    assert up["points"][0]["observer_m"] == pytest.approx(base["points"][0]["ground_m"] + 25)


def test_formats_round_trip(tmp_path, runner):
    """pvlib's CSV becomes a Series (azimuth clockwise from north, degrees); PVGIS's list is
    the same values from north; GRASS's azimuths are counter-clockwise from east; GeoJSON has
    the point and its 3-D horizon line; every one carries the values of the JSON."""
    args = [SRTM, "--at=-84.25,36.45", "--step", "7.5"]
    ref = _json(runner, args)["points"][0]
    h = np.array(ref["horizon_deg"])
    files = {}
    for fmt in ("pvlib", "pvgis", "grass", "geojson", "csv"):
        files[fmt] = tmp_path / f"p.{fmt}"
        r = runner.invoke(cli, ["profile"] + args + ["--format", fmt, "-o", str(files[fmt])])
        assert r.exit_code == 0, r.output
    s = pd.read_csv(files["pvlib"], index_col=0, comment="#").squeeze()
    assert isinstance(s, pd.Series) and list(s.index) == [7.5 * i for i in range(48)]
    np.testing.assert_allclose(s.to_numpy(), h, atol=1e-6)
    lines = [ln for ln in files["pvgis"].read_text().splitlines() if not ln.startswith("#")]
    np.testing.assert_allclose([float(v) for v in lines[0].split(",")], h, atol=1e-6)
    g = pd.read_csv(files["grass"], comment="#")
    assert list(g.columns) == ["azimuth", "horizon_height"]
    east_ccw = dict(zip(g["azimuth"], g["horizon_height"]))
    assert east_ccw[90.0] == pytest.approx(h[0])            # north
    assert east_ccw[0.0] == pytest.approx(h[12])            # east = 90 clockwise from north
    assert east_ccw[180.0] == pytest.approx(h[36])          # west = 270
    gj = json.loads(files["geojson"].read_text())
    pt, line = gj["features"]
    assert pt["geometry"]["coordinates"] == pytest.approx([-84.25, 36.45], abs=1e-9)
    np.testing.assert_allclose(pt["properties"]["horizon_deg"], h)
    assert line["geometry"]["type"] == "LineString"
    assert len(line["geometry"]["coordinates"]) == sum(v is not None for v in ref["distance_m"])
    assert all(len(c) == 3 for c in line["geometry"]["coordinates"])
    c = pd.read_csv(files["csv"], comment="#")
    np.testing.assert_allclose(c["horizon_deg"].to_numpy(), h, atol=1e-6)


def test_points_from_csv_and_geojson(tmp_path, runner):
    pts = tmp_path / "p.csv"
    pts.write_text("name,lon,lat\nA,-84.25,36.45\nB,-84.2,36.5\n")
    doc = _json(runner, [SRTM, "--points", str(pts), "--step", "30"])
    assert [p["id"] for p in doc["points"]] == ["A", "B"]
    gj = tmp_path / "p.geojson"
    gj.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"id": "A"},
         "geometry": {"type": "Point", "coordinates": [-84.25, 36.45]}}]}))
    doc2 = _json(runner, [SRTM, "--points", str(gj), "--step", "30"])
    assert doc2["points"][0]["horizon_deg"] == doc["points"][0]["horizon_deg"]


@pytest.mark.parametrize("args, code, words", [
    (["--at=-90,10"], 1, "outside the DEM"),
    (["--at", "nonsense"], 2, "two numbers"),
    (["--at=-84.25,36.45", "--at=-84.2,36.5", "--format", "pvlib"], 2, "one point"),
    (["--at=-84.25,36.45", "--format", "shp"], 2, "Invalid value for '--format'"),
    (["--at=-84.25,36.45", "--step", "0"], 2, "--step"),
    ([], 2, "give a point"),
])
def test_bad_points_are_one_line_errors(tmp_path, runner, args, code, words):
    out = tmp_path / "o.csv"
    r = runner.invoke(cli, ["profile", SRTM, "-o", str(out)] + args)
    assert r.exit_code == code and words in r.stderr, r.stderr
    assert len(r.stderr.splitlines()) == 1 and not out.exists()


def test_point_on_nodata_and_csv_without_coordinates(tmp_path, runner, utm_dem):
    dem, z = utm_dem
    d = read_dem(dem)
    x, y = d.transform @ (5.5, 5.5)             # the void's centre
    r = runner.invoke(cli, ["profile", dem, "--at-xy", f"{x},{y}"])
    assert r.exit_code == 1 and "nodata" in r.stderr
    bad = tmp_path / "p.csv"
    bad.write_text("a,b\n1,2\n")
    r = runner.invoke(cli, ["profile", dem, "--points", str(bad)])
    assert r.exit_code == 1 and "lon,lat" in r.stderr and len(r.stderr.splitlines()) == 1


def test_preview_is_the_first_points_panorama(tmp_path, runner):
    """--preview: a 720 x 200 panorama, north at the left edge; a wall to the east of the
    observer stands above the horizontal a quarter of the way across and nowhere to the west."""
    import rasterio
    z = np.zeros((81, 81), np.float32)
    z[:, 50:53] = 100.0                 # a wall 100 m high, 10 cells east of the centre
    dem = write_geotiff(tmp_path / "wall.tif", z, Affine(10, 0, 500000, 0, -10, 4000000),
                        CRS.from_epsg(32633))
    x, y = 500000 + 40.5 * 10, 4000000 - 40.5 * 10
    png = tmp_path / "p.png"
    r = runner.invoke(cli, ["profile", dem, "--at-xy", f"{x},{y}", "--preview", str(png),
                            "--no-earth-curvature", "-o", str(tmp_path / "p.csv")])
    assert r.exit_code == 0, r.output
    with rasterio.open(png) as ds:
        pic = ds.read().astype(int)
    assert pic.shape == (3, 200, 720)
    ground = pic[2] < pic[0] + 20           # brown below the line, blue sky above
    east, west = ground[:, 180], ground[:, 540]
    assert east.sum() > west.sum() + 50     # atan(100 / 100 m) = 45 degrees up in the east


def test_box_profile_is_atan_of_height_over_distance_across_its_width(runner, tmp_path):
    """A box 50 m high on flat ground, its near face D = 36 rows north of the observer: toward
    azimuth φ within the box's angular width the first sample on the face's row is the
    horizon, atan(h cos φ / (D dy)) (the ray crosses that row D dy / cos φ metres away);
    beyond the width the ground is flat: 0."""
    z = np.zeros((80, 100), np.float32)
    z[20:25, 30:71] = 50.0
    dem = write_geotiff(tmp_path / "box.tif", z, Affine(10, 0, 500000, 0, -10, 4000000),
                        CRS.from_epsg(32633))
    x, y = 500000 + 50.5 * 10, 4000000 - 60.5 * 10        # row 60, column 50
    doc = _json(runner, [dem, "--at-xy", f"{x},{y}", "--step", "1", "--no-earth-curvature"])
    got = np.array(doc["points"][0]["horizon_deg"])
    az = np.array(doc["points"][0]["azimuth"])
    phi = np.radians(((az + 180.0) % 360.0) - 180.0)
    inside = (np.cos(phi) > 0) & (np.abs(np.tan(phi)) * 36 < 19.5)   # the face's row, in it
    dy = float(read_dem(dem).grid.dy[60])   # ground metres per row (UTM's scale: 10 / 0.9996)
    want = np.degrees(np.arctan(50.0 * np.cos(phi) / (36 * dy)))
    np.testing.assert_allclose(got[inside], want[inside], atol=1e-5)
    assert inside.sum() >= 55                               # about ±28 degrees
    outside = np.abs(phi) > np.radians(35)                 # the box out of the rays' way
    np.testing.assert_allclose(got[outside], 0.0, atol=1e-9)


def _check_report(path, keys):
    """The report at ``path`` parses, has ``keys`` and its phases' seconds add up."""
    rep = json.loads(path.read_text())
    assert set(keys) <= set(rep), set(keys) - set(rep)
    sec = rep["seconds"]
    phases = [sec[k] for k in ("read", "prepare", "compute", "write")]
    assert all(s >= 0.0 for s in phases) and sec["total"] >= sum(phases) - 1e-3
    return rep


def test_report_of_profile_and_its_clash(tmp_path, runner, utm_dem):
    """--report: the document's keys and the run's (absolute output, counts, the horizon's
    min/mean/max, the phases' seconds); the report as -o is a usage error (exit 2)."""
    dem, _ = utm_dem
    out, rep = tmp_path / "p.csv", tmp_path / "p.json"
    r = runner.invoke(cli, ["profile", dem, "--at-xy", "501515,3998185", "--at-xy",
                            "502015,3998485", "--step", "7.5", "-o", str(out), "--report",
                            str(rep)])
    assert r.exit_code == 0, r.output
    doc = _check_report(rep, ["input", "output", "shape", "threads", "point_count",
                              "azimuth_count", "horizon_deg_stats", "version", "points"])
    assert doc["output"] == str(out.resolve()) and doc["shape"] == [120, 140]
    assert doc["point_count"] == 2 and doc["azimuth_count"] == 48
    st = doc["horizon_deg_stats"]
    assert -90.0 <= st["min"] <= st["mean"] <= st["max"] <= 90.0
    r = runner.invoke(cli, ["profile", dem, "--at-xy", "501515,3998185", "-o", str(out),
                            "--report", str(out), "--overwrite"])
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.output
