"""``hillshade-rt query`` (issue 20, item 5): lit or shadowed at points, per time, with the sun,
the horizon toward it and the margin. At cell centres it is the shadow mask (given suns, times
with every cell's own sun, an observer above the ground); between centres the observer stands on
the bilinear ground (a plane); irradiance is pvlib's clear sky; each format round-trips."""

import json
import math

import numpy as np
import pandas as pd
import pytest
from affine import Affine
from rasterio.crs import CRS

import hillshade_rt as hr
from hillshade_rt.engine import arrays
from hillshade_rt.engine.arrays import point_light_mask
from hillshade_rt.cli import cli
from hillshade_rt.io import read_dem
from hillshade_rt.testing import data_path, fractal_terrain, read_band, write_geotiff

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")                 # UTM 15N, 1 m
SRTM = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")            # geographic
EVEREST = data_path("everest_srtm3_voids_crop200.tif")               # geographic, voids


def _cells(path, n, seed=0):
    """``n`` distinct valid cells of the DEM at ``path``, at random."""
    d = read_dem(path)
    ok = np.flatnonzero(np.isfinite(d.heights).ravel())
    pick = np.random.default_rng(seed).choice(ok, n, replace=False)
    return d, [divmod(int(i), d.shape[1]) for i in pick]


def _points_csv(tmp_path, d, cells, name="p.csv"):
    """A CSV of the cells' centres in the DEM's CRS (x, y), ids "row_col"."""
    path = tmp_path / name
    lines = ["id,x,y"]
    for r, c in cells:
        x, y = (float(v) for v in d.transform @ (c + 0.5, r + 0.5))
        lines.append(f"{r}_{c},{x!r},{y!r}")
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def _query(runner, args, fmt="json"):
    r = runner.invoke(cli, ["query"] + args + ["--format", fmt])
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout) if fmt in ("json", "geojson") else r.stdout


def _mask(runner, tmp_path, dem, args, name="m.tif"):
    out = tmp_path / name
    r = runner.invoke(cli, ["shadow", dem, str(out), "--overwrite", "-q"] + args)
    assert r.exit_code == 0, r.output
    return out


@pytest.mark.parametrize("dem", [LIDAR, SRTM, EVEREST])
def test_cell_centres_are_the_shadow_mask(tmp_path, runner, dem):
    """600 cell centres, the observer on the ground, suns at 163, 203.7 and 290 deg: the query's
    lit is the shadow mask's, cell for cell (projected and geographic DEMs, voids, curvature
    as shadow decides it); both answers occur."""
    d, cells = _cells(dem, 600)
    pts = _points_csv(tmp_path, d, cells)
    for az, el in ((163.0, 6.0), (203.7, 9.0), (290.0, 4.0)):
        sun = ["--azimuth", str(az), "--elevation", str(el)]
        mask = read_band(_mask(runner, tmp_path, dem, sun))
        doc = _query(runner, [dem, "--points", pts] + sun)
        lit = np.array([row["lit"] for row in doc["rows"]])
        want = np.array([mask[c] == 0 for c in cells])
        np.testing.assert_array_equal(lit, want, err_msg=f"az {az}")
        assert 0.02 < want.mean() < 0.98
        rows = doc["rows"]
        assert all(r["sun_azimuth_deg"] == az and r["sun_elevation_deg"] == el for r in rows)
        assert all(r["margin_deg"] == pytest.approx(el - r["horizon_deg"], abs=1e-12)
                   and r["lit"] == (r["margin_deg"] >= 0) for r in rows)
        assert all(r["observer_m"] == r["ground_m"] == float(d.heights[c])
                   for r, c in zip(rows, cells))


def test_cell_centres_above_the_ground_are_the_lifted_mask(tmp_path, runner):
    """--height-above-ground 2.5 on both: the query's march from the lifted point and brute's
    lifted ray agree cell for cell (and differ from the ground's)."""
    d, cells = _cells(LIDAR, 800, seed=2)
    pts = _points_csv(tmp_path, d, cells)
    sun = ["--azimuth", "203.7", "--elevation", "5"]
    lifted = read_band(_mask(runner, tmp_path, LIDAR, sun + ["--height-above-ground", "2.5"]))
    ground = read_band(_mask(runner, tmp_path, LIDAR, sun, "g.tif"))
    doc = _query(runner, [LIDAR, "--points", pts, "--height-above-ground", "2.5"] + sun)
    lit = np.array([row["lit"] for row in doc["rows"]])
    np.testing.assert_array_equal(lit, [lifted[c] == 0 for c in cells])
    assert sum(ground[c] == 1 and lifted[c] == 0 for c in cells) > 20
    assert all(r["observer_m"] == pytest.approx(r["ground_m"] + 2.5) for r in doc["rows"])
    assert doc["height_above_ground_m"] == 2.5


@pytest.mark.parametrize("dem, sun", [
    (SRTM, ["--time", "2026-03-20T16:40-05:00", "--time", "2026-03-20T08:10-05:00"]),
    (LIDAR, ["--start", "2026-06-21T05:10", "--end", "2026-06-21T07:10", "--step", "40min",
             "--tz", "America/Chicago"]),
])
def test_suns_from_times_are_the_masks_suns(tmp_path, runner, dem, sun):
    """Suns from times: the same sun as ``shadow --time`` at each cell (the lattice's
    interpolated sun where it varies across the DEM: "per cell"), so the same mask, band by
    band; rows in point-then-time order with each band's time."""
    d, cells = _cells(dem, 400, seed=3)
    pts = _points_csv(tmp_path, d, cells)
    rep = tmp_path / "r.json"
    out = _mask(runner, tmp_path, dem, sun + ["--report", str(rep)])
    times = json.loads(rep.read_text())["times"]
    doc = _query(runner, [dem, "--points", pts] + sun)
    m = len(times)
    assert doc["suns"] == m and len(doc["rows"]) == m * len(cells) and doc["sun_source"] == "time"
    seen = 0
    for j, t in enumerate(times):
        band = read_band(out, j + 1)
        rows = doc["rows"][j::m]
        assert all(r["time"] == t["time"] for r in rows)
        lit = np.array([r["lit"] for r in rows])
        np.testing.assert_array_equal(lit, [band[c] == 0 for c in cells], err_msg=t["time"])
        seen += lit.sum() > 0 and (~lit).sum() > 0
        el = np.array([r["sun_elevation_deg"] for r in rows])
        assert np.all(np.abs(el - t["elevation"]) < 0.2)
        if t["elevation"] <= 0:
            assert not lit.any()
    assert seen >= 1
    if dem == SRTM:
        assert times[0]["mode"] == "per cell"
        az = [r["sun_azimuth_deg"] for r in doc["rows"][::m]]
        assert max(az) - min(az) > 0.01         # each point its own sun
        assert all(r["sun_true_azimuth_deg"] == r["sun_azimuth_deg"] for r in doc["rows"])


def _plane(tmp_path, a=-2.0, b=4.0, rows=50, cols=60):
    """z = a * col + b * row (exact in float32) on 10 m UTM cells."""
    r, c = np.mgrid[0:rows, 0:cols]
    z = (a * c + b * r).astype(np.float32)
    return write_geotiff(tmp_path / "plane.tif", z, Affine(10, 0, 500000, 0, -10, 4000000),
                         CRS.from_epsg(32633))


def test_between_centres_the_observer_stands_on_the_bilinear_ground(tmp_path, runner):
    """On a plane z = -2 col + 4 row, points between cell centres: the ground is the plane
    there; the horizon toward 203.7 deg is the plane's slope that way, atan(a E / dx - b N / dy)
    (every sample lies on the plane), lit just above it and shadowed just below; from 1 m up
    the horizon is lower."""
    dem = _plane(tmp_path)
    d = read_dem(dem)
    frac = [(10.25, 30.6), (20.5, 41.125), (33.8, 44.3)]
    xy = [tuple(float(v) for v in d.transform @ (c + 0.5, r + 0.5)) for r, c in frac]
    at = sum((["--at-xy", f"{x!r},{y!r}"] for x, y in xy), [])
    east, north = math.sin(math.radians(203.7)), math.cos(math.radians(203.7))
    slope = math.degrees(math.atan(-2.0 * east / d.grid.dx[20] - 4.0 * north / d.grid.dy[20]))
    assert 20 < slope < 30
    for el, lit in ((slope + 0.01, True), (slope - 0.01, False)):
        doc = _query(runner, [dem, "--azimuth", "203.7", "--elevation", repr(el)] + at
                     + ["--no-earth-curvature"])
        for r, (row, col) in zip(doc["rows"], frac):
            assert r["ground_m"] == pytest.approx(-2.0 * col + 4.0 * row, abs=1e-9)
            assert r["horizon_deg"] == pytest.approx(slope, abs=1e-9)
            assert r["lit"] is lit
    up = _query(runner, [dem, "--azimuth", "203.7", "--elevation", "24", "--height-above-ground",
                         "1"] + at + ["--no-earth-curvature"])
    assert all(r["horizon_deg"] < slope - 0.01 for r in up["rows"])


def test_formats_round_trip(tmp_path, runner):
    """CSV (read back by pandas; lit 1/0), JSON (the rows), GeoJSON (a Point per point, its
    series as properties): the same values, exactly; -o's extension picks the format."""
    d, cells = _cells(LIDAR, 3, seed=5)
    pts = _points_csv(tmp_path, d, cells)
    args = [LIDAR, "--points", pts, "--start", "2026-09-01T06:00", "--end", "2026-09-01T18:00",
            "--step", "3h", "--tz", "America/Chicago", "--irradiance", "--height-above-ground",
            "1.5"]
    files = {f: tmp_path / f"q.{f}" for f in ("csv", "json", "geojson")}
    for f, path in files.items():
        r = runner.invoke(cli, ["query"] + args + ["-o", str(path)])
        assert r.exit_code == 0, r.output
        assert str(path) in r.stderr
    doc = json.loads(files["json"].read_text())
    rows = doc["rows"]
    assert len(rows) == 3 * 5 and doc["irradiance"] and "ineichen" in doc["irradiance"]
    text = files["csv"].read_text()
    assert text.startswith("# hillshade-rt") and "ineichen" in text.splitlines()[2]
    c = pd.read_csv(files["csv"], comment="#", dtype={"point": str})
    assert list(c["lit"]) == [int(r["lit"]) for r in rows]
    for col in ("sun_azimuth_deg", "sun_elevation_deg", "horizon_deg", "margin_deg",
                "observer_m", "dni_w_m2", "beam_horizontal_w_m2", "x", "y", "lon", "lat"):
        assert list(c[col]) == [r[col] for r in rows], col
    assert list(c["time"]) == [r["time"] for r in rows]
    assert list(c["point"]) == [r["point"] for r in rows]
    gj = json.loads(files["geojson"].read_text())
    assert gj["type"] == "FeatureCollection" and len(gj["features"]) == 3
    for i, f in enumerate(gj["features"]):
        part = rows[i * 5:(i + 1) * 5]
        assert f["geometry"] == {"type": "Point", "coordinates": [part[0]["lon"], part[0]["lat"]]}
        p = f["properties"]
        assert p["id"] == part[0]["point"] and p["height_above_ground_m"] == 1.5
        for k in ("time", "lit", "horizon_deg", "margin_deg", "beam_horizontal_w_m2"):
            assert p[k] == [r[k] for r in part], k


@pytest.mark.filterwarnings("ignore:.*dayofyear is deprecated")   # pvlib's own
def test_irradiance_is_pvlibs_clear_sky_and_the_beam_needs_the_sun(tmp_path, runner):
    """DNI: pvlib's Ineichen clear sky at the point (its own solar position, its altitude), to
    0.2 %; the beam on a horizontal surface is DNI x sin(elevation) where lit, 0 where
    shadowed or at night."""
    from pvlib.location import Location
    d, cells = _cells(LIDAR, 40, seed=7)
    pts = _points_csv(tmp_path, d, cells)
    doc = _query(runner, [LIDAR, "--points", pts, "--start", "2026-12-01T04:00-06:00", "--end",
                          "2026-12-01T17:00-06:00", "--step", "1h", "--irradiance"])
    rows = doc["rows"]
    lit = [r for r in rows if r["lit"]]
    dark = [r for r in rows if not r["lit"] and r["sun_elevation_deg"] > 2]
    assert lit and dark and any(r["sun_elevation_deg"] < 0 for r in rows)
    for r in rows:
        el = r["sun_elevation_deg"]
        want = r["dni_w_m2"] * math.sin(math.radians(el)) if r["lit"] else 0.0
        assert r["beam_horizontal_w_m2"] == pytest.approx(want, abs=1e-9)
        if el <= 0:
            assert r["dni_w_m2"] == 0.0 and not r["lit"]
    assert all(r["dni_w_m2"] > 100 for r in dark)          # shadowed, the sun still shines
    for pid in (rows[0]["point"], rows[-1]["point"]):
        first = [r for r in rows if r["point"] == pid and r["sun_elevation_deg"] > 2]
        times = pd.DatetimeIndex([r["time"] for r in first])
        loc = Location(first[0]["lat"], first[0]["lon"], altitude=first[0]["observer_m"])
        got = [r["dni_w_m2"] for r in first]
        cs = loc.get_clearsky(times, model="ineichen")      # pvlib's own sun there: 0.2 %
        np.testing.assert_allclose(got, cs["dni"].to_numpy(), rtol=2e-3)
        zen = np.array([90.0 - r["sun_elevation_deg"] for r in first])    # the query's sun
        pos = pd.DataFrame({"apparent_zenith": zen, "zenith": zen,
                            "apparent_elevation": 90.0 - zen}, index=times)
        cs = loc.get_clearsky(times, model="ineichen", solar_position=pos)
        np.testing.assert_allclose(got, cs["dni"].to_numpy(), rtol=1e-12)


def test_sun_at_points_from_python(tmp_path):
    """The array API: rows x suns arrays; one sun per point and column; at cell centres the
    mask of ``shadow_mask``; a ray that grazes the terrain (horizon = elevation) is lit."""
    z = fractal_terrain(60, 70, 4, relief=300.0)
    rr, cc = np.meshgrid(np.arange(0, 60, 3), np.arange(0, 70, 4), indexing="ij")
    rr, cc = rr.ravel(), cc.ravel()
    suns = [(163.0, 10.0), (203.7, 14.0), (290.0, 7.0)]
    res = hr.sun_at_points(z, rr, cc, [a for a, _ in suns], [e for _, e in suns], 30.0)
    assert res["lit"].shape == (rr.size, 3) and res["ground_m"].shape == (rr.size,)
    for j, (a, e) in enumerate(suns):
        m = hr.shadow_mask(z, a, e, 30.0)
        np.testing.assert_array_equal(res["lit"][:, j], m[rr, cc] == 0)
        assert 0 < res["lit"][:, j].mean() < 1
    per = hr.sun_at_points(z, rr[:5], cc[:5], np.tile([[163.0, 290.0]], (5, 1)) + np.arange(5)[:, None],
                           np.full((5, 2), 8.0), 30.0, height_above_ground=[0, 1, 2, 3, 4])
    for i in range(5):
        one = hr.sun_at_points(z, rr[i:i + 1], cc[i:i + 1], [163.0 + i, 290.0 + i], 8.0, 30.0,
                               height_above_ground=float(i))
        for k in ("horizon_deg", "lit", "margin_deg"):
            np.testing.assert_array_equal(per[k][i], one[k][0])
    frame = pd.DataFrame({k: v.ravel() for k, v in res.items() if v.ndim == 2})
    assert len(frame) == rr.size * 3 and frame["lit"].dtype == bool
    flat = np.zeros((1, 4), np.float32)
    flat[0, 1] = 1.0                                  # 1 m up one 1 m step east: 45.0 deg
    tie = hr.sun_at_points(flat, [0.0], [0.0], 90.0, 45.0, 1.0, curvature=False)
    assert tie["horizon_deg"][0, 0] == 45.0 and tie["margin_deg"][0, 0] == 0.0
    assert tie["lit"][0, 0]
    low = hr.sun_at_points(flat, [0.0], [0.0], 90.0, 44.999, 1.0, curvature=False)
    assert not low["lit"][0, 0]
    with pytest.raises(hr.HillshadeError, match="nodata"):
        hr.sun_at_points(np.full((3, 3), np.nan, np.float32), [1.0], [1.0], 90.0, 10.0, 1.0)


def test_a_point_beside_a_void_stands_on_its_own_cell(tmp_path, runner):
    """A cell centre next to nodata has its own height (only the centres with a weight count);
    a point whose interpolation needs the void is on nodata."""
    d = read_dem(EVEREST)
    void = np.isnan(d.heights)
    r, c = np.argwhere(~void[1:-1, 1:-1] & void[2:, 1:-1])[0] + 1   # valid, a void below
    x, y = (float(v) for v in d.transform @ (c + 0.5, r + 0.5))
    doc = _query(runner, [EVEREST, "--at-xy", f"{x!r},{y!r}", "--azimuth", "163", "--elevation",
                          "10"])
    assert doc["rows"][0]["ground_m"] == float(d.heights[r, c])
    x2, y2 = (float(v) for v in d.transform @ (c + 0.5, r + 1.0))  # half-way to the void
    rr = runner.invoke(cli, ["query", EVEREST, "--at-xy", f"{x2!r},{y2!r}", "--azimuth", "163",
                             "--elevation", "10"])
    assert rr.exit_code == 1 and "nodata" in rr.stderr


@pytest.mark.parametrize("args, code, words", [
    (["--at=-90,10", "--azimuth", "1", "--elevation", "9"], 1, "outside the DEM"),
    (["--at=-84.25,36.45"], 2, "no sun given"),
    (["--at=-84.25,36.45", "--azimuth", "1", "--elevation", "9", "--irradiance"], 2,
     "--irradiance needs suns from times"),
    (["--at=-84.25,36.45", "--azimuth", "1", "--elevation", "9", "--format", "shp"], 2,
     "Invalid value for '--format'"),
    (["--at=-84.25,36.45", "--azimuth", "1", "--elevation", "9",
      "--height-above-ground", "-2"], 2, "--height-above-ground"),
    (["--azimuth", "1", "--elevation", "9"], 2, "give a point"),
    (["--at", "x", "--azimuth", "1", "--elevation", "9"], 2, "two numbers"),
])
def test_bad_queries_are_one_line_errors_and_write_nothing(tmp_path, runner, args, code, words):
    out = tmp_path / "o.csv"
    r = runner.invoke(cli, ["query", SRTM, "-o", str(out)] + args)
    assert r.exit_code == code and words in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and not out.exists()


def test_points_files_without_coordinates_or_on_nodata(tmp_path, runner):
    out = tmp_path / "o.csv"
    bad = tmp_path / "bad.csv"
    bad.write_text("name,east,north\nA,1,2\n")
    r = runner.invoke(cli, ["query", SRTM, "--points", str(bad), "--azimuth", "1", "--elevation",
                            "9", "-o", str(out)])
    assert r.exit_code == 1 and "no coordinates" in r.stderr and not out.exists()
    d = read_dem(EVEREST)
    r0, c0 = np.argwhere(np.isnan(d.heights))[0]
    gj = tmp_path / "p.geojson"
    lon, lat = (float(v) for v in d.transform @ (c0 + 0.5, r0 + 0.5))
    gj.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"id": "hole"},
         "geometry": {"type": "Point", "coordinates": [lon, lat]}}]}))
    r = runner.invoke(cli, ["query", EVEREST, "--points", str(gj), "--azimuth", "1",
                            "--elevation", "9", "-o", str(out)])
    assert r.exit_code == 1 and "point hole lies on nodata" in r.stderr and not out.exists()


def test_the_sun_at_a_point_is_the_masks_sun_for_that_cell():
    """``run.query.sun_at``: per cell, the lattice interpolated as the per-cell march does it
    (the same ray: dominant axis, step, direction); per tile, the tile's; else the one sun."""
    from hillshade_rt.algorithms.per_cell_sun import cell_ray, lattice_vectors
    from hillshade_rt.model.geometry import Grid, sun_rays
    from hillshade_rt.run.query import sun_at
    from hillshade_rt.model.sun import Region, SunOver
    i, j = np.meshgrid(np.linspace(-0.5, 0.5, 9), np.linspace(-0.5, 0.5, 9), indexing="ij")
    lat = lattice_vectors(203.7 + 3.0 * j + 0.5 * i, 12.0 + 1.5 * i)
    tiles = [Region(slice(0, 50), slice(0, 80), 200.0, 11.0),
             Region(slice(50, 100), slice(0, 80), 207.0, 13.0)]
    field_sun = SunOver(None, 203.7, 12.0, deviation_deg=3.0, tiles=tiles, lattice=lat)
    grid = Grid.uniform(100, 80, 30.0, 20.0)
    for r, c in ((0, 0), (17, 61), (99, 79), (50, 3)):
        a, e = sun_at(field_sun, (100, 80), r, c)
        rays = sun_rays(grid, a, e)
        night, dc, sd, so, ri, cv = cell_ray.py_func(r, c, lat, grid.dx, grid.dy, 1.0, -1.0,
                                                     0.0, 0, 0, 100, 80)
        assert not night and dc == rays.dom_col[r] and sd == rays.step_dom[r]
        assert so == pytest.approx(rays.step_other[r], abs=1e-12)
        assert ri == pytest.approx(rays.rise[r], rel=1e-12)
    tiled = SunOver(None, 203.7, 12.0, deviation_deg=3.0, tiles=tiles)   # no lattice
    assert sun_at(tiled, (100, 80), 61.2, 10.0) == (207.0, 13.0)
    assert sun_at(tiled, (100, 80), 3.0, 79.0) == (200.0, 11.0)
    assert sun_at(SunOver(None, 163.0, 9.0), (100, 80), 5.5, 6.25) == (163.0, 9.0)


# --- a point light (issue 21, item 1): query --light-position / --light-lonlat ---------------

@pytest.mark.parametrize("lift", [0.0, 1.5])
def test_a_point_light_at_cell_centres_is_its_mask(tmp_path, runner, lift):
    """400 cell centres of the lidar DEM: lit is the point light's mask of the same light (the
    same observer above the ground), cell for cell; azimuth, elevation and distance are the
    geometry of the light seen from the centre."""
    d, cells = _cells(LIDAR, 400, seed=21)
    x, y = (float(v) for v in d.transform @ (211.3 + 0.5, 143.8 + 0.5))   # col, row
    zl = arrays.ground_height(d.heights, 143.8, 211.3) + 8.0     # a lamp 8 m up
    pts = _points_csv(tmp_path, d, cells)
    doc = _query(runner, [LIDAR, "--points", pts, "--light-position", f"{x!r},{y!r},{zl!r}",
                          "--height-above-ground", str(lift)])
    mask = point_light_mask(d, x, y, zl, height_above_ground=lift)
    assert doc["light"]["z"] == zl and doc["suns"] == 1 and len(doc["rows"]) == 400
    lit = np.array([row["lit"] for row in doc["rows"]])
    want = np.array([mask[r, c] == 0 for r, c in cells])
    assert np.array_equal(lit, want) and lit.any() and not lit.all()
    for row, (r, c) in zip(doc["rows"], cells):
        ve = (211.3 - c) * d.grid.dx[r]
        vn = -(143.8 - r) * d.grid.dy[r]
        vu = zl - (float(d.heights[r, c]) + lift)
        assert row["light_azimuth_deg"] == pytest.approx(math.degrees(math.atan2(ve, vn)) % 360)
        assert row["light_elevation_deg"] == pytest.approx(
            math.degrees(math.atan2(vu, math.hypot(ve, vn))))
        assert row["light_distance_m"] == pytest.approx(math.sqrt(ve * ve + vn * vn + vu * vu))
        assert row["observer_m"] == pytest.approx(float(d.heights[r, c]) + lift)


def test_a_point_light_between_centres_and_its_incidence_on_a_plane(tmp_path, runner):
    """A tilted plane with a wall: between centres the observer stands on the plane; the
    incidence is the plane's Lambert cos; behind the wall the light is blocked."""
    rows, cols, cell = 40, 50, 10.0
    r, c = np.mgrid[0:rows, 0:cols].astype(np.float64)
    a, b = 0.2, -0.1                                    # dz/d(east), dz/d(north)
    z = (100.0 + a * cell * c - b * cell * r).astype(np.float32)
    z[:, 30] += 200.0                                   # a wall along column 30
    t = Affine(cell, 0, 0.0, 0, -cell, 0.0)
    dem = write_geotiff(tmp_path / "p.tif", z, t, None)
    row_l, col_l, zl = 17.3, 12.6, 190.0
    lx, ly = t @ (col_l + 0.5, row_l + 0.5)
    pts = [(5.25, 8.5), (21.7, 20.2), (10.4, 36.3)]     # (row, col); the last behind the wall
    args = [dem, "--light-position", f"{lx},{ly},{zl}"]
    for pr, pc in pts:
        args += ["--at-xy", "{},{}".format(*(t @ (pc + 0.5, pr + 0.5)))]
    doc = _query(runner, args)
    got = doc["rows"]
    assert [g["lit"] for g in got] == [True, True, False]
    for g, (pr, pc) in zip(got[:2], pts[:2]):
        ground = 100.0 + a * cell * pc - b * cell * pr
        assert g["ground_m"] == pytest.approx(ground)
        ve, vn, vu = (col_l - pc) * cell, -(row_l - pr) * cell, zl - ground
        dist = math.sqrt(ve * ve + vn * vn + vu * vu)
        assert g["light_distance_m"] == pytest.approx(dist)
        want = (vu - a * ve - b * vn) / (math.sqrt(1 + a * a + b * b) * dist)
        assert g["incidence_cos"] == pytest.approx(want, abs=1e-9)
    # the CSV says it is a point light and has the light's columns
    text = _query(runner, args, "csv")
    assert "point light at x" in text.splitlines()[0]
    assert "light_azimuth_deg,light_elevation_deg,light_distance_m,incidence_cos,lit" in text


@pytest.mark.parametrize("extra, code, words", [
    (["--light-position", "150,-150,10"], 1, "inside the terrain"),
    (["--light-position", "150,-150,900", "--azimuth", "163", "--elevation", "20"], 2,
     "--azimuth"),
    (["--light-position", "150,-150,900", "--earth-curvature"], 2, "--earth-curvature"),
    (["--light-position", "150,-150"], 2, "three numbers"),
    (["--light-position", "150,-150,900", "--light-lonlat", "1,2,900"], 2, "one of them"),
    (["--light-lonlat", "1,2,900"], 1, "CRS"),
])
def test_bad_point_light_queries_are_one_line_errors(tmp_path, runner, extra, code, words):
    dem = write_geotiff(tmp_path / "f.tif", np.full((30, 30), 100.0, np.float32),
                        Affine(10, 0, 0, 0, -10, 0), None)
    out = tmp_path / "q.csv"
    r = runner.invoke(cli, ["query", dem, "--at-xy", "50,-50", "-o", str(out)] + extra)
    assert r.exit_code == code and words in r.output and "Traceback" not in r.output, r.output
    assert not out.exists()


def test_a_point_light_query_takes_no_earth_curvature(tmp_path, runner):
    dem = write_geotiff(tmp_path / "f.tif", np.full((30, 30), 100.0, np.float32),
                        Affine(10, 0, 0, 0, -10, 0), None)
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    base = ["query", dem, "--at-xy", "50,-50", "--light-position", "150,-150,900"]
    r = runner.invoke(cli, base + ["-o", str(a)])
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, base + ["-o", str(b), "--no-earth-curvature"])
    assert r.exit_code == 0, r.output
    assert a.read_text() == b.read_text()


def _check_report(path, keys):
    """The report at ``path`` parses, has ``keys`` and its phases' seconds add up."""
    rep = json.loads(path.read_text())
    assert set(keys) <= set(rep), set(keys) - set(rep)
    sec = rep["seconds"]
    phases = [sec[k] for k in ("read", "prepare", "compute", "write")]
    assert all(s >= 0.0 for s in phases) and sec["total"] >= sum(phases) - 1e-3
    return rep


def test_report_of_query_and_its_clash(tmp_path, runner):
    """--report: the document's keys (points, suns) and the run's (absolute output, the suns'
    times, lit rows, the phases' seconds); the DEM as the report is a usage error (exit 2)."""
    d, cells = _cells(LIDAR, 5, seed=4)
    pts = _points_csv(tmp_path, d, cells)
    out, rep = tmp_path / "q.csv", tmp_path / "q.json"
    sun = ["--time", "2026-03-20T16:40-05:00", "--time", "2026-03-20T08:10-05:00"]
    r = runner.invoke(cli, ["query", LIDAR, "--points", pts, "-o", str(out), "--report",
                            str(rep)] + sun)
    assert r.exit_code == 0, r.output
    doc = _check_report(rep, ["input", "output", "shape", "threads", "points", "suns",
                              "sun_times", "lit_rows", "version"])
    assert doc["output"] == str(out.resolve()) and doc["points"] == len(cells)
    assert doc["suns"] == 2 and len(doc["sun_times"]) == 2
    assert 0 <= doc["lit_rows"] <= 2 * len(cells)
    r = runner.invoke(cli, ["query", LIDAR, "--points", pts, "-o", str(out), "--report",
                            LIDAR, "--overwrite"] + sun)
    assert r.exit_code == 2 and len(r.stderr.strip().splitlines()) == 1, r.output
