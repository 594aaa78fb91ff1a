"""Suns over a DEM from times (grid north, night, per tile), series, sun hours; Earth curvature,
soft shadows, self-shadow and classes, shaded relief, previews."""

import json
import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.engine.shader import Shader, render
from hillshade_rt.model.earth import Body
from hillshade_rt.model.geometry import Grid, curvature_per_m2, grid_from_transform, sun_rays
from hillshade_rt.model.solar import disk_fraction
from hillshade_rt.model.sun import Region, SunOver
from hillshade_rt.model.times import parse_time
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff

# a 3 km square of 30 m cells near the SPA report's site (Golden, Colorado), UTM 13N
GOLDEN = Affine(30.0, 0, 476000.0, 0, -30.0, 4400000.0)
UTM13 = CRS.from_epsg(32613)


def _dem(tmp_path, z, transform=GOLDEN, crs=UTM13, name="dem.tif"):
    return write_geotiff(tmp_path / name, np.asarray(z, np.float32), transform, crs)


# ---------------------------------------------------------------------------------------------
# suns over a DEM from times

def test_same_instant_in_two_offsets_gives_one_mask(tmp_path, runner):
    dem = _dem(tmp_path, fractal_terrain(90, 110, 3, relief=400.0))
    outs = []
    for i, args in enumerate((["--time", "2026-06-21T06:40:00-06:00"],
                              ["--time", "2026-06-21T12:40:00Z"],
                              ["--time", "2026-06-21T06:40", "--tz", "America/Denver"])):
        out = tmp_path / f"m{i}.tif"
        r = runner.invoke(cli, ["shadow", dem, str(out), *args, "-q"])
        assert r.exit_code == 0, r.output
        outs.append(read_band(out))
    assert (outs[0] == outs[1]).all() and (outs[0] == outs[2]).all()
    assert 0 < (outs[0] == 1).mean() < 1
    # one hour later in winter time is the same clock time but another instant: another mask
    out = tmp_path / "w.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--time", "2026-06-21T07:40", "--tz",
                            "America/Denver", "-q"])
    assert r.exit_code == 0 and (read_band(out) != outs[0]).any()


def test_night_is_all_shadow_and_said_so(tmp_path, runner):
    z = fractal_terrain(40, 50, 5, relief=100.0)
    z[3, 4] = np.nan
    dem = _dem(tmp_path, z)
    out, rep = tmp_path / "n.tif", tmp_path / "n.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--time", "2026-06-21T00:30-06:00",
                            "--report", str(rep)])
    assert r.exit_code == 0, r.output
    m = read_band(out)
    assert m[3, 4] == 255 and (np.delete(m.ravel(), 3 * 50 + 4) == 1).all()
    doc = json.loads(rep.read_text())
    assert doc["sun"]["night"] is True and doc["sun"]["elevation"] < 0
    assert doc["night_count"] == 1 and doc["shadow_fraction"] == 1.0
    assert "below the horizon" in r.stderr


def test_time_sun_matches_given_sun_in_grid_terms(tmp_path, runner):
    """A sun from --time equals --azimuth/--elevation with the SPA's apparent elevation and the
    azimuth turned from true north to the UTM grid's north (meridian convergence)."""
    dem = _dem(tmp_path, fractal_terrain(60, 70, 8, relief=300.0))
    a, b, rep = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "a.json"
    r = runner.invoke(cli, ["shadow", dem, str(a), "--time", "2026-03-02T16:20Z",
                            "--report", str(rep), "-q", "--no-earth-curvature"])
    assert r.exit_code == 0, r.output
    doc = json.loads(rep.read_text())
    sun = doc["sun"]
    assert sun["mode"] == "one vector" and sun["deviation_deg"] < 0.05
    # west of zone 13's central meridian (105 W) true north leans east, toward the meridian, by
    # about -(lon + 105) sin(lat) degrees of grid azimuth
    lon, lat = doc["site"]["longitude"], doc["site"]["latitude"]
    assert -(lon + 105.0) * math.sin(math.radians(lat)) == pytest.approx(0.176, abs=0.01)
    assert sun["azimuth"] - sun["true_azimuth"] == pytest.approx(
        -(lon + 105.0) * math.sin(math.radians(lat)), abs=0.003)
    r = runner.invoke(cli, ["shadow", dem, str(b), "--azimuth", repr(sun["azimuth"]),
                            "--elevation", repr(sun["elevation"]), "-q", "--no-earth-curvature"])
    assert r.exit_code == 0
    assert (read_band(a) == read_band(b)).all()


def test_sun_per_tile_equals_each_tiles_own_sun():
    """A 3 x 3 degree geographic DEM: the sun differs across it by more than the tolerance, so
    it is computed per tile; every tile's cells equal a whole-raster run with that tile's sun."""
    from hillshade_rt.model.site import Site
    from hillshade_rt.model.sun import sun_over
    rows, cols = 90, 90
    z = fractal_terrain(rows, cols, 11, relief=6000.0)
    tr = Affine(3.0 / cols, 0, 7.0, 0, -3.0 / rows, 47.5)
    grid = grid_from_transform(tr, CRS.from_epsg(4326), (rows, cols))

    def to_lonlat(r, c):
        return tr.c + tr.a * (np.asarray(c) + 0.5), tr.f + tr.e * (np.asarray(r) + 0.5)
    site = Site(46.0, 8.5, 1000.0, "test", to_lonlat,
                lambda r, c: np.zeros(np.broadcast(np.asarray(r), np.asarray(c)).shape))
    [s] = sun_over(site, (rows, cols), [parse_time("2026-06-21T19:05Z")], tolerance=0.4)
    assert s.deviation_deg > 1.5 and 9 <= len(s.tiles) <= 100 and s.tile_deviation_deg < 0.4
    assert max(t.elevation for t in s.tiles) - min(t.elevation for t in s.tiles) > 2.0
    for algorithm in ("smap", "sweep"):
        sh = Shader(z, grid, algorithm, curvature=False)
        m = render(sh, s, "shadow")
        for t in s.tiles[::5]:
            whole = SunOver(None, t.azimuth, t.elevation)
            ref = render(Shader(z, grid, "brute", curvature=False), whole, "shadow")
            assert (m[t.rows, t.cols] == ref[t.rows, t.cols]).all()
        assert 0.05 < (m == 1).mean() < 0.95


# ---------------------------------------------------------------------------------------------
# time series

def test_series_bands_and_pattern(tmp_path, runner):
    import rasterio
    dem = _dem(tmp_path, fractal_terrain(50, 60, 2, relief=300.0))
    out, rep = tmp_path / "s.tif", tmp_path / "s.json"
    r = runner.invoke(cli, ["shadow", dem, str(out), "--start", "2026-03-29T00:30",
                            "--end", "2026-03-29T04:00", "--step", "1h", "--tz", "Europe/Zurich",
                            "--lat", "46.9", "--lon", "7.4", "--report", str(rep), "-q"])
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as ds:
        # equal steps in elapsed time across the daylight-saving change: 00:30 +01:00 to
        # 04:00 +02:00 is 2.5 hours, so three times, none after --end (tests/model/test_times.py)
        assert ds.count == 3
        assert ds.descriptions == ("2026-03-29T00:30+01:00", "2026-03-29T01:30+01:00",
                                   "2026-03-29T03:30+02:00")
        assert ds.tags(1)["TIME"] == "2026-03-29T00:30+01:00"
    doc = json.loads(rep.read_text())
    assert len(doc["times"]) == 3 and doc["night_count"] == 3 and doc["sun"] is None

    pat = str(tmp_path / "p_{time:%H%M}.tif")
    r = runner.invoke(cli, ["shadow", dem, "--output-pattern", pat, "--time",
                            "2026-06-21T06:30-06:00", "--time", "2026-06-21T18:30-06:00", "-q"])
    assert r.exit_code == 0, r.output
    a, b = read_band(tmp_path / "p_0630.tif"), read_band(tmp_path / "p_1830.tif")
    assert (a != b).any()
    # the multi-band output holds the same masks
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "ab.tif"), "--time",
                            "2026-06-21T06:30-06:00", "--time", "2026-06-21T18:30-06:00", "-q"])
    assert (read_band(tmp_path / "ab.tif", 1) == a).all()
    assert (read_band(tmp_path / "ab.tif", 2) == b).all()
    r = runner.invoke(cli, ["shadow", dem, "--output-pattern", str(tmp_path / "q_{time:%d}.tif"),
                            "--time", "2026-06-21T09:00Z", "--time", "2026-06-21T15:00Z"])
    assert r.exit_code == 1 and "same file name" in r.stderr
    assert not list(tmp_path.glob("q_*"))


def test_sun_hours_shadowed_valley_gets_fewer_hours(tmp_path, runner):
    z = np.zeros((40, 120), np.float32)
    z[:, 55:65] = 800.0        # a north-south wall: the west side loses the afternoon
    out = tmp_path / "h.tif"
    r = runner.invoke(cli, ["sun-hours", _dem(tmp_path, z), str(out), "--date", "2026-12-21",
                            "--step", "15min", "-q", "--algorithm", "sweep"])
    assert r.exit_code == 0, r.output
    h = read_band(out)
    assert h[20, 50] < h[20, 5] - 1.0 and h[20, 70] < h[20, 115] - 1.0


# ---------------------------------------------------------------------------------------------
# physics

def test_geographic_dem_at_60n_gets_the_right_metres_per_degree():
    """One degree at 60 N on WGS84: 55 799.98 m of longitude, 111 412.24 m of latitude."""
    tr = Affine(1 / 1200, 0, 10.0, 0, -1 / 1200, 60.0 + 0.5 / 1200 + 1 / 1200)
    g = grid_from_transform(tr, CRS.from_epsg(4326), (3, 4))
    assert g.dx[1] * 1200 == pytest.approx(55799.98, abs=0.05)
    assert g.dy[1] * 1200 == pytest.approx(111412.24, abs=0.5)
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    w = math.sqrt(1 - e2 * math.sin(math.radians(60)) ** 2)
    assert g.dx[1] == pytest.approx(a / w * math.cos(math.radians(60)) * math.radians(1 / 1200),
                                    rel=1e-9)
    assert g.dy[1] == pytest.approx(a * (1 - e2) / w ** 3 * math.radians(1 / 1200), rel=1e-9)


@pytest.mark.parametrize("algorithm", ["brute", "smap", "horizon", "sweep"])
def test_curvature_matches_the_analytic_drop(algorithm):
    """A 500 m wall on a 200 km flat profile, sun 0.5 deg from the west: on a flat Earth the
    shadow is h / tan(e) = 57.3 km long; with the terrain falling away by d^2 (1 - k) / 2R it
    ends where h - d^2 (1-k)/2R = d tan(e)."""
    dx, n, h, el = 100.0, 2000, 500.0, 0.5
    z = np.zeros((3, n), np.float32)
    z[:, 0] = h
    R = 6371000.0
    k = 0.13
    c = (1 - k) / (2 * R)
    t = math.tan(math.radians(el))
    flat_len = h / t
    curved_len = (-t + math.sqrt(t * t + 4 * c * h)) / (2 * c)
    grid = Grid.uniform(3, n, dx)
    body = Body(R, R, 0.0, True, "sphere")
    for on, length in ((False, flat_len), (True, curved_len)):
        sh = Shader(z, grid, algorithm, curvature=on, body=body)
        m = render(sh, SunOver(None, 270.0, el), "shadow")
        last = int(np.nonzero(m[1] == 1)[0].max())
        assert abs(last * dx - length) <= dx, (on, last * dx, length)
    assert flat_len - curved_len > 10_000


def test_curvature_on_rough_terrain_all_algorithms_equal_brute():
    z = fractal_terrain(70, 90, 21, relief=1500.0)
    grid = Grid.uniform(70, 90, 400.0)
    for az in (163.0, 203.7, 291.0):
        sun = SunOver(None, az, 3.0)
        ref = render(Shader(z, grid, "brute", curvature=True), sun, "shadow")
        flat = render(Shader(z, grid, "brute", curvature=False), sun, "shadow")
        assert (ref <= flat).all() and (ref < flat).any()   # curvature only ever lights cells
        for alg in ("smap", "horizon"):
            assert (render(Shader(z, grid, alg, curvature=True), sun, "shadow") == ref).all()


def test_curvature_auto_turns_on_for_long_rays():
    z = np.zeros((10, 10), np.float32)
    z[0, 0] = 10.0
    small = Shader(z, Grid.uniform(10, 10, 1.0))        # 14 m across: off
    assert small.curvature_for(90.0, 1.0) == 0.0
    big = Shader(z, Grid.uniform(10, 10, 500.0))        # 7 km across, rays up to 573 m: off
    assert big.curvature_for(90.0, 1.0) == 0.0
    z[0, 0] = 100.0
    big = Shader(z, Grid.uniform(10, 10, 500.0))        # rays up to 5.7 km: on
    assert big.curvature_for(90.0, 1.0) == pytest.approx(curvature_per_m2(big.body.radius(90.0)))


def test_soft_fraction_is_half_when_the_horizon_is_at_the_suns_centre():
    assert disk_fraction(5.0, 5.0) == pytest.approx(0.5)
    assert disk_fraction(5.0, 5.0 + 0.2665) == pytest.approx(1.0)
    assert disk_fraction(5.0, 5.0 - 0.2665) == pytest.approx(0.0)
    # a 10 m wall, flat ground; the cell 40 columns (of 1 m) east of it sees the wall's top at
    # atan(10/40); a sun exactly there is half hidden; nearer cells less, farther cells more
    dx, az = 1.0, 270.0
    z = np.zeros((5, 120), np.float32)
    z[:, 10] = 10.0
    el = math.degrees(math.atan(10.0 / 40.0))
    f = render(Shader(z, Grid.uniform(5, 120, dx), curvature=False), SunOver(None, az, el),
               "shadow", soft=True)
    assert f[2, 50] == pytest.approx(0.5, abs=1e-6)
    assert f[2, 49] < 0.5 < f[2, 51]
    assert f[2, 20] == 0.0 and f[2, 110] == 1.0 and f[2, 5] == 1.0


def test_soft_at_a_non_special_azimuth_agrees_with_hard_at_the_centre():
    z = fractal_terrain(60, 80, 4, relief=200.0)
    grid = Grid.uniform(60, 80, 10.0)
    for az in (163.0, 203.7):
        sun = SunOver(None, az, 12.0)
        sh = Shader(z, grid, curvature=False)
        f = render(sh, sun, "shadow", soft=True)
        m = render(sh, sun, "shadow")
        assert (f[m == 1] <= 0.5).all() and (f[m == 0] >= 0.5).all()
        assert ((f > 0) & (f < 1)).any()


def test_self_shadow_and_classes():
    """A ridge running north-south, sun low from the east: the west face turns away from the
    sun (self-shadow, 1) and the flat ground west of the ridge lies in its cast shadow (2)."""
    cols = 80
    x = np.arange(cols, dtype=np.float32)
    ridge = np.clip(30.0 - np.abs(x - 40.0) * 3.0, 0.0, None)    # 72 deg flanks
    z = np.tile(ridge, (30, 1))
    z[5, 5] = np.nan
    grid = Grid.uniform(30, cols, 1.0)
    sun = SunOver(None, 93.0, 20.0)
    sh = Shader(z, grid, "smap", curvature=False)
    cls = render(sh, sun, "classes")
    assert cls[15, 45] == 0                    # east face: lit
    assert cls[15, 35] == 1                    # west face: faces away
    assert cls[15, 20] == 2                    # ground west of the ridge: cast shadow
    assert cls[15, 75] == 0 and cls[5, 5] == 255
    cast = render(sh, sun, "shadow")
    both = render(sh, sun, "shadow", self_shadow=True)
    assert (both == np.where(cls == 255, 255, (cls > 0).astype(np.uint8))).all()
    assert ((both == 1) & (cast == 0)).any()   # self-shadow adds cells


def test_horn_incidence_on_a_plane():
    from hillshade_rt.algorithms.relief import incidence
    # a plane rising 1 m per 2 m toward the north-east, on 2 x 1 m cells, north-up
    rows, cols = 12, 14
    r, c = np.mgrid[0:rows, 0:cols]
    east, north = c * 2.0, -r * 1.0
    z = (0.3 * east + 0.4 * north).astype(np.float32)
    grid = Grid.uniform(rows, cols, 2.0, 1.0)
    for az, el in ((203.7, 25.0), (163.0, 60.0)):
        n = np.array([-0.3, -0.4, 1.0]) / math.sqrt(1.25)
        a, e = math.radians(az), math.radians(el)
        ll = np.array([math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e)])
        assert np.allclose(incidence(z, grid, az, el), n @ ll, atol=1e-5)   # edges too


def test_hillshade_values(tmp_path, runner):
    z = np.zeros((30, 40), np.float32)
    z[10:14, 10:14] = 20.0
    z[0, 0] = np.nan
    out = tmp_path / "hs.tif"
    r = runner.invoke(cli, ["hillshade", _dem(tmp_path, z), str(out), "--azimuth", "270",
                            "--elevation", "30", "--ambient", "0.25", "-q"])
    assert r.exit_code == 0, r.output
    hs = read_band(out)
    lit_flat = 1 + round(254 * (0.25 + 0.75 * 0.5))
    shade = 1 + round(254 * 0.25)
    assert hs[25, 30] == lit_flat and hs[0, 0] == 0
    assert hs[12, 14] == shade                  # in the box's shadow (34.6 m east of it)
    assert hs[12, 15] == lit_flat
    # gdaldem-like defaults (315/45) and -s: a DEM in degrees with --scale 111120
    geo = write_geotiff(tmp_path / "geo.tif", fractal_terrain(30, 30, 1, relief=300.0),
                        Affine(1 / 120, 0, 8.0, 0, -1 / 120, 47.0), CRS.from_epsg(4326))
    a, b = tmp_path / "a.tif", tmp_path / "b.tif"
    assert runner.invoke(cli, ["hillshade", geo, str(a), "-q"]).exit_code == 0
    assert runner.invoke(cli, ["hillshade", geo, str(b), "-q", "-s", "111120"]).exit_code == 0
    assert (read_band(a) != read_band(b)).any()     # 1/120 deg x 111120 = 926 m, not 926 x 633
    assert runner.invoke(cli, ["hillshade", geo, str(b), "-q", "-s", "111120", "-z", "2",
                               "--overwrite"]).exit_code == 0


def test_preview_png(tmp_path, runner):
    import warnings

    import rasterio
    from rasterio.errors import NotGeoreferencedWarning
    dem = _dem(tmp_path, fractal_terrain(40, 60, 9, relief=300.0))
    png = tmp_path / "p.png"
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "m.tif"), "--azimuth", "203.7",
                            "--elevation", "15", "--preview", str(png), "-q"])
    assert r.exit_code == 0, r.output
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(png) as ds:
            assert ds.driver == "PNG" and ds.count == 3 and ds.shape == (40, 60)
            rgb = ds.read()
    m = read_band(tmp_path / "m.tif")
    # shadowed cells are tinted blue: blue above red there
    assert (rgb[2][m == 1] > rgb[0][m == 1]).all()
    assert not list(tmp_path.glob("*.aux.xml")) and not list(tmp_path.glob(".*part*"))


def test_sun_option_errors(tmp_path, runner):
    dem = _dem(tmp_path, fractal_terrain(20, 20, 1))
    raw = tmp_path / "r.f32"
    np.zeros((8, 8), np.float32).tofile(raw)
    moon = write_geotiff(tmp_path / "moon.tif", np.zeros((8, 8), np.float32),
                         Affine(0.01, 0, 0, 0, -0.01, 0),
                         CRS.from_wkt('GEOGCS["Moon 2000",DATUM["D_Moon_2000",SPHEROID['
                                      '"Moon_2000_IAU_IAG",1737400.0,0.0]],PRIMEM["Greenwich",0],'
                                      'UNIT["Decimal_Degree",0.0174532925199433]]'))
    out = str(tmp_path / "o.tif")
    cases = [
        (["shadow", dem, out, "--time", "2026-06-21T12:00"], "no UTC offset"),
        (["shadow", dem, out, "--time", "2026-06-21T12:00Z", "--azimuth", "3"], "one way"),
        (["shadow", dem, out, "--azimuth", "3", "--tz", "UTC", "--elevation", "4"], "--tz"),
        (["shadow", dem, out, "--start", "2026-06-21T12:00Z"], "go together"),
        (["shadow", dem, out, "--time", "noon"], "ISO 8601"),
        (["shadow", dem, out, "--time", "2026-06-21T12:00Z", "--tz", "Nowhere/Land"], "IANA"),
        (["shadow", str(raw), out, "--raw-dtype", "float32", "--raw-shape", "8x8",
          "--pixel-size", "1", "--time", "2026-06-21T12:00Z"], "--lat and --lon"),
        (["shadow", moon, out, "--time", "2026-06-21T12:00Z"], "not the Earth"),
        (["shadow", dem, out, "--azimuth", "3", "--elevation", "4", "--soft", "--classes"],
         "do not go together"),
        (["shadow", dem, "--azimuth", "3", "--elevation", "4"], "OUTPUT or --output-pattern"),
        (["sun-hours", dem, out, "--date", "2026-02-30"], "not a date"),
        (["sun-hours", dem, out, "--date", "2026-06-21", "--step", "0s"], "at least"),
    ]
    for args, msg in cases:
        r = runner.invoke(cli, args)
        assert r.exit_code in (1, 2), (args, r.output)
        assert msg in r.stderr, (args, r.stderr)
        assert len(r.stderr.strip().splitlines()) == 1, r.stderr
        assert "Traceback" not in r.stderr
    assert not (tmp_path / "o.tif").exists()
    # the raw grid works with --lat/--lon; the Moon with a given sun (no refraction there)
    r = runner.invoke(cli, ["shadow", str(raw), out, "--raw-dtype", "float32", "--raw-shape",
                            "8x8", "--pixel-size", "1", "--time", "2026-06-21T12:00Z", "--lat",
                            "47", "--lon", "8", "-q"])
    assert r.exit_code == 0, r.output


def test_horizon_command_curvature_and_previews(tmp_path, runner):
    """The horizon angles of a DEM more than 1 km across include curvature by default: every
    angle that looks across terrain is lower than on a flat Earth, never higher; previews of
    horizon and info are written."""
    dem = _dem(tmp_path, fractal_terrain(60, 80, 6, relief=600.0))   # 2.4 km across
    a, b, png, png2 = (tmp_path / n for n in ("a.tif", "b.tif", "a.png", "i.png"))
    r = runner.invoke(cli, ["horizon", dem, str(a), "--azimuth", "203.7", "--preview", str(png),
                            "-q"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, ["horizon", dem, str(b), "--azimuth", "203.7", "--no-earth-curvature",
                            "-q"])
    assert r.exit_code == 0
    ca, fb = read_band(a), read_band(b)
    looks = fb > -90
    assert (ca[looks] <= fb[looks]).all() and (ca[looks] < fb[looks]).mean() > 0.5
    assert png.stat().st_size > 0
    assert runner.invoke(cli, ["info", dem, "--preview", str(png2)]).exit_code == 0
    assert png2.stat().st_size > 0


def test_tiles_with_small_halos_run_the_algorithm_on_their_window():
    """High suns: a tile's window (tile + halo) is less than 3x the tile, so the algorithm runs
    on the window; each tile still equals a whole-raster run with its sun."""
    z = fractal_terrain(64, 72, 13, relief=40.0)
    for r, c in ((14, 14), (14, 50), (46, 14), (46, 50)):
        z[r:r + 4, c:c + 4] += 30.0           # a tower in each tile
    z[10, 60] = np.nan
    grid = Grid.uniform(64, 72, 5.0)
    tiles = [Region(slice(a, a + 32), slice(b, b + 36), az, el)
             for (a, b), az, el in zip(((0, 0), (0, 36), (32, 0), (32, 36)),
                                       (163.0, 203.7, 291.0, 20.0), (45.0, 50.0, 40.0, 55.0))]
    for algorithm in ("smap", "horizon", "sweep"):
        stats = {}
        sh = Shader(z, grid, algorithm, curvature=False)
        m = render(sh, SunOver(None, 0.0, 30.0, tiles=tiles), "shadow", stats=stats)
        assert "tiles_marched_by_brute" not in stats
        for t in tiles:
            ref = render(Shader(z, grid, algorithm, curvature=False),
                         SunOver(None, t.azimuth, t.elevation), "shadow")
            assert (m[t.rows, t.cols] == ref[t.rows, t.cols]).all(), (algorithm, t)
        assert (m == 1).any() and (m == 0).any()


@pytest.mark.parametrize("by_brute", [True, False])
def test_tiles_of_auto_by_brute_or_by_bounds_on_the_window_equal_whole_runs(monkeypatch,
                                                                            by_brute):
    """Low suns (halos larger than the tiles): auto's tiles go to brute over their own cells or
    to bounds over their window as ``auto.tile_by_brute`` estimates; both are exact (forced
    here each way), and the estimate prefers bounds unless the window dwarfs the tile."""
    from hillshade_rt.algorithms import auto
    z = fractal_terrain(64, 72, 21, relief=120.0)
    z[10, 60] = np.nan
    grid = Grid.uniform(64, 72, 5.0)
    tiles = [Region(slice(a, a + 32), slice(b, b + 36), az, el)
             for (a, b), az, el in zip(((0, 0), (0, 36), (32, 0), (32, 36)),
                                       (163.0, 203.7, 291.0, 20.0), (3.0, 5.0, 4.0, 6.0))]
    monkeypatch.setattr(auto, "tile_by_brute", lambda *a: by_brute)
    stats = {}
    m = render(Shader(z, grid, "auto", curvature=False), SunOver(None, 0.0, 5.0, tiles=tiles),
               "shadow", stats=stats)
    assert ("tiles_marched_by_brute" in stats) == by_brute
    for t in tiles:
        ref = render(Shader(z, grid, "brute", curvature=False),
                     SunOver(None, t.azimuth, t.elevation), "shadow")
        assert (m[t.rows, t.cols] == ref[t.rows, t.cols]).all(), t
    monkeypatch.undo()
    rays = sun_rays(grid, 203.7, 5.0)
    assert not auto.tile_by_brute(4 * 1000, 1000, (0.0, 120.0), rays)
    assert auto.tile_by_brute(100 * 1000, 1000, (0.0, 120.0), rays)


def test_lat_lon_on_a_projected_dem_still_turns_to_grid_north(tmp_path, runner):
    dem = _dem(tmp_path, fractal_terrain(30, 30, 8, relief=300.0))
    rep = tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "m.tif"), "--time", "2026-03-02T16:20Z",
                            "--lat", "39.74", "--lon", "-105.28", "--report", str(rep), "-q"])
    assert r.exit_code == 0, r.output
    sun = json.loads(rep.read_text())["sun"]
    assert sun["mode"] == "one vector"
    assert sun["azimuth"] - sun["true_azimuth"] == pytest.approx(0.176, abs=0.01)


