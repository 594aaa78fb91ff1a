"""``hillshade --light-position / --light-lonlat`` (issue 21, items 1 and 5): Lambert shading
from each cell to a point light, its cast shadows, the inverse-square falloff, 8/16-bit PNG
lightmaps (``run.lightmap``, ``algorithms.lightmap``)."""

import json

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.engine.arrays import point_light_mask
from hillshade_rt.cli import cli
from hillshade_rt.io import read_dem
from hillshade_rt.run.lightmap import point_light_relief
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff

X0, Y0, CELL = 500000.0, 4000000.0, 10.0
T = Affine(CELL, 0, X0, 0, -CELL, Y0)


def xy(row, col):
    """The DEM's coordinates of fractional (row, col), cell centres at whole numbers."""
    return X0 + CELL * (col + 0.5), Y0 - CELL * (row + 0.5)


def _dem(tmp_path, z, name="d.tif", crs=None):
    """A GeoTIFF of ``z`` on ``T``; without a CRS its cells are 10 m exactly (with UTM's, the
    ground spacing is 10.004 m: the projection's scale)."""
    return write_geotiff(tmp_path / name, np.asarray(z, np.float32), T, crs)


def plane(rows, cols, a=0.0, b=0.0, base=100.0):
    """Heights base + a * east + b * north (metres; north-up, row 0 at the top)."""
    r, c = np.mgrid[0:rows, 0:cols].astype(np.float64)
    return (base + a * CELL * c - b * CELL * r).astype(np.float32)


def lambert(rows, cols, a, b, base, row_l, col_l, height, lift=0.0):
    """cos(incidence) on the plane of ``plane`` lit from (row_l, col_l, height), clipped at 0,
    and the distance to the light: the plain formula per cell."""
    r, c = np.mgrid[0:rows, 0:cols].astype(np.float64)
    ve = (col_l - c) * CELL
    vn = -(row_l - r) * CELL
    vu = height - (base + a * CELL * c - b * CELL * r + lift)
    d = np.sqrt(ve ** 2 + vn ** 2 + vu ** 2)
    cosi = (vu - a * ve - b * vn) / (np.sqrt(1 + a * a + b * b) * d)
    return np.maximum(cosi, 0.0), d


def test_a_flat_plane_gets_height_over_distance_and_the_cube_with_inverse_square(tmp_path):
    rows, cols, L = 40, 50, 60.0
    d = read_dem(_dem(tmp_path, plane(rows, cols)))
    r0, c0 = 17, 29
    x, y = xy(r0, c0)
    res = point_light_relief(d, x, y, 100.0 + L, ambient=0.0)
    _, dist = lambert(rows, cols, 0, 0, 100.0, r0, c0, 100.0 + L)
    assert (res["mask"] == 0).all()
    np.testing.assert_allclose(res["direct"], L / dist, rtol=1e-6)
    assert res["direct"][r0, c0] == pytest.approx(1.0) and res["relief"][r0, c0] == 255
    assert res["relief"].max() == 255 and (res["relief"] == 255).sum() <= 9
    np.testing.assert_array_equal(res["relief"], 1 + np.rint(254 * res["direct"]))
    sq = point_light_relief(d, x, y, 100.0 + L, ambient=0.0, falloff="inverse-square")
    assert sq["d_ref"] == pytest.approx(L)
    np.testing.assert_allclose(sq["direct"], (L / dist) ** 3, rtol=1e-5)
    assert sq["direct"][r0, c0] == pytest.approx(1.0)
    # the ratio of the two: (d_ref / d)^2, clipped at 1
    np.testing.assert_allclose(sq["direct"] / res["direct"], np.minimum(1.0, (L / dist) ** 2),
                               rtol=1e-5)


@pytest.mark.parametrize("a, b, row_l, col_l, lift", [
    (0.3, -0.2, 11.3, 37.8, 0.0),      # toward 163 deg-ish and across the slope
    (-0.4, 0.25, 31.6, 6.2, 1.5),      # off to the south-west, an observer 1.5 m up
    (0.1, 0.5, -8.0, 60.0, 0.0),       # off the raster, north-east
])
def test_a_tilted_plane_matches_the_plain_formula(tmp_path, a, b, row_l, col_l, lift):
    rows, cols = 36, 44
    z = plane(rows, cols, a, b)
    d = read_dem(_dem(tmp_path, z))
    x, y = xy(row_l, col_l)
    height = float(np.max(z)) + 80.0
    res = point_light_relief(d, x, y, height, ambient=0.25, height_above_ground=lift)
    want, _ = lambert(rows, cols, a, b, 100.0, row_l, col_l, height, lift)
    assert (res["mask"] == 0).all()      # a plane casts no shadow on itself
    np.testing.assert_allclose(res["direct"], want, atol=2e-6)
    np.testing.assert_array_equal(res["relief"], 1 + np.rint(254 * (0.25 + 0.75 * want)))


def test_faces_turned_away_get_the_ambient_only(tmp_path):
    rows, cols = 30, 30
    z = plane(rows, cols, a=1.0)                 # rising eastward at 45 deg: facing west
    d = read_dem(_dem(tmp_path, z))
    x, y = xy(15.4, 70.0)                        # east, above every cell, below the slope
    res = point_light_relief(d, x, y, 400.0, ambient=0.3)
    assert (res["direct"] == 0).all() and (res["relief"] == 1 + round(254 * 0.3)).all()


def test_a_wall_casts_its_shadow_and_zeroes_the_cells_behind(tmp_path):
    rows, cols = 40, 40
    z = plane(rows, cols)
    z[:, 20] = 200.0                              # a wall along column 20
    d = read_dem(_dem(tmp_path, z))
    x, y = xy(20.4, 8.3)                          # west of the wall, 30 m up
    res = point_light_relief(d, x, y, 130.0, ambient=0.2)
    mask = point_light_mask(d, x, y, 130.0)
    np.testing.assert_array_equal(res["mask"], mask)
    behind = mask == 1
    assert behind[:, 21:].sum() > 100 and not behind[:, :20].any()
    assert (res["direct"][behind] == 0).all()
    assert (res["relief"][behind] == 1 + round(254 * 0.2)).all()
    lit = (mask == 0) & (np.arange(cols) < 20)[None, :]
    assert (res["direct"][lit] > 0).all()


def test_voids_are_nodata_and_shadows_follow_the_mask_on_fractal_terrain(tmp_path):
    z = fractal_terrain(60, 70, 6, relief=300.0) + 200.0
    z[5, 9] = np.nan
    d = read_dem(_dem(tmp_path, z))
    x, y = xy(23.7, 41.2)
    res = point_light_relief(d, x, y, 700.0, height_above_ground=2.0, ambient=0.1)
    mask = point_light_mask(d, x, y, 700.0, height_above_ground=2.0)
    np.testing.assert_array_equal(res["mask"], mask)
    assert res["relief"][5, 9] == 0 and np.isnan(res["direct"][5, 9])
    assert (res["relief"] > 0).sum() == z.size - 1
    assert (res["direct"][mask == 1] == 0).all() and (mask == 1).any()
    # lit cells: Lambert from the Horn normal of the directional hillshade
    from hillshade_rt.algorithms.relief import incidence
    lit = np.argwhere(mask == 0)[::97]
    assert len(lit) > 20
    for r, c in lit:
        ve = (41.2 - c) * d.grid.dx[r]
        vn = -(23.7 - r) * d.grid.dy[r]
        vu = 700.0 - (float(z[r, c]) + 2.0)
        dist = np.sqrt(ve ** 2 + vn ** 2 + vu ** 2)
        az = np.degrees(np.arctan2(ve, vn)) % 360
        el = np.degrees(np.arcsin(vu / dist))
        want = incidence(d.heights, d.grid, az, el, slice(r, r + 1), slice(c, c + 1))[0, 0]
        assert res["direct"][r, c] == pytest.approx(max(float(want), 0.0), abs=1e-5)


@pytest.fixture
def fractal_dem(tmp_path):
    z = fractal_terrain(50, 60, 4, relief=200.0) + 300.0
    z[2, 3] = np.nan
    return _dem(tmp_path, z, "f.tif", CRS.from_epsg(32633))


def test_the_command_writes_the_relief_and_a_report(tmp_path, runner, fractal_dem):
    d = read_dem(fractal_dem)
    x, y = xy(20.3, 33.9)
    out, rep = tmp_path / "h.tif", tmp_path / "r.json"
    r = runner.invoke(cli, ["hillshade", fractal_dem, str(out), "--light-position",
                            f"{x},{y},800", "--ambient", "0.15", "--height-above-ground", "1",
                            "--falloff", "inverse-square", "--report", str(rep)])
    assert r.exit_code == 0, r.output
    want = point_light_relief(d, x, y, 800.0, ambient=0.15, height_above_ground=1.0,
                              falloff="inverse-square")
    got = read_band(out)
    assert got.dtype == np.uint8 and np.array_equal(got, want["relief"])
    doc = json.loads(rep.read_text())
    assert doc["product"]["falloff"] == "inverse-square" and doc["product"]["bits"] == 8
    assert doc["product"]["falloff_reference_m"] == pytest.approx(want["d_ref"])
    assert doc["light"]["z"] == 800.0
    # the same light by longitude and latitude
    from pyproj import Transformer
    lon, lat = Transformer.from_crs("EPSG:32633", "EPSG:4326", always_xy=True).transform(x, y)
    out2 = tmp_path / "h2.tif"
    r = runner.invoke(cli, ["hillshade", fractal_dem, "-o", str(out2), "--light-lonlat",
                            f"{lon!r},{lat!r},800", "--ambient", "0.15",
                            "--height-above-ground", "1", "--falloff", "inverse-square"])
    assert r.exit_code == 0, r.output
    assert np.array_equal(read_band(out2), want["relief"])


@pytest.mark.parametrize("bits", [8, 16])
def test_png_lightmaps_read_back_with_their_scaling(tmp_path, runner, fractal_dem, bits):
    import rasterio
    d = read_dem(fractal_dem)
    x, y = xy(12.6, 40.1)
    out = tmp_path / "light.png"
    args = ["hillshade", fractal_dem, str(out), "--light-position", f"{x},{y},650",
            "--ambient", "0.05", "-f", "PNG"] + (["--bits", "16"] if bits == 16 else [])
    r = runner.invoke(cli, args)
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as ds:
        assert ds.driver == "PNG" and ds.count == 1
        got = ds.read(1)
    want = point_light_relief(d, x, y, 650.0, ambient=0.05)
    levels = 254 if bits == 8 else 65534
    assert got.dtype == (np.uint8 if bits == 8 else np.uint16)
    valid = ~np.isnan(want["direct"])
    np.testing.assert_array_equal(
        got[valid], 1 + np.rint(levels * (0.05 + 0.95 * want["direct"][valid].astype(np.float64))))
    assert got[2, 3] == 0 and (got == 0).sum() == 1
    assert got.max() > 0.9 * (levels + 1)
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".") or "scratch" in p.name]


def test_bad_input_fails_in_one_line_and_writes_nothing(tmp_path, runner, fractal_dem):
    out = tmp_path / "h.png"
    x, y = xy(20, 20)
    cases = [
        (["--light-position", f"{x},{y},100"], 1, "inside the terrain"),
        (["--light-position", f"{x},{y},900", "--falloff", "cubic"], 2, "--falloff"),
        (["--light-position", f"{x},{y},900", "--bits", "12"], 2, "--bits"),
        (["--falloff", "inverse-square"], 2, "point light"),
        (["--bits", "16"], 2, "point light"),
        (["--light-position", f"{x},{y},900", "--azimuth", "163"], 2, "--azimuth"),
        (["--light-position", f"{x},{y},900", "--soft"], 2, "--soft"),
        (["--light-position", f"{x},{y},900", "--window-size", "64"], 2, "--window-size"),
        (["--light-position", f"{x},{y}"], 2, "three numbers"),
        (["--light-position", f"{x},{y},900", "--light-lonlat", "1,2,3"], 2, "one of them"),
        # the raster's edge nearest the light is higher than it: no distance of reference
        (["--light-position", f"{X0 - 5000},{Y0},150", "--falloff", "inverse-square"], 1,
         "not above the ground"),
    ]
    for extra, code, words in cases:
        r = runner.invoke(cli, ["hillshade", fractal_dem, str(out)] + extra)
        assert r.exit_code == code, (extra, r.output)
        assert words in r.output and "Traceback" not in r.output, (extra, r.output)
        lines = [ln for ln in r.output.splitlines() if ln.strip()]
        assert len(lines) == 1 or code == 2, (extra, r.output)
        assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.tif"]
