"""Rasters in windows: the same answers as in memory, halos from the physics on the sun's side
only, bounded memory, mosaics of several files, COG output, Dask workers, Ctrl-C."""

import json
import math
import os

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.engine import windows as tiling
from hillshade_rt.cli import cli
from hillshade_rt.engine.lighting import Lighting
from hillshade_rt.engine.shader import Shader, render
from hillshade_rt.model.earth import dem_body
from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import open_dem, read_dem
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import (data_path, fractal_terrain, read_band, split_geotiff,
                                  write_geotiff)

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
EVEREST = data_path("everest_srtm3_voids_crop200.tif")
UTM = CRS.from_epsg(32611)


def _tiled(path, azimuth, elevation, algorithm, window_shape, kind="shadow", soft=False,
           curvature="auto", options=None, sun=None):
    """The product of a tiled run, put together from its windows (API level)."""
    src = open_dem(path)
    stats = tiling.block_stats(src)
    rows, cols = src.shape
    dx, dy = src.grid.centre_spacing()
    lighting = Lighting(algorithm=algorithm, options=options or {}, backend="cpu",
                        curvature=curvature, soft=soft, self_shadow=kind != "shadow")
    job = tiling.WindowLighting(src, lighting, dem_body(src), (stats.zmin, stats.zmax),
                                math.hypot(cols * dx, rows * dy), kind)
    pieces = job.pieces(sun or SunOver(None, azimuth, elevation), stats, 1 << 40, window_shape)
    out = None
    carry = job.carrier([pieces])
    with src.reader() as rd:
        cache = tiling.WindowCache(rd)
        for p in pieces:
            arr = job.light(cache.get(p.window), p, carry=carry)
            if out is None:
                out = np.full(src.shape, 99, arr.dtype)
            r0, r1, c0, c1 = p.region
            out[r0:r1, c0:c1] = arr
        carried = cache.carried_bytes
    return out, pieces, carried, carry


def _whole(path, azimuth, elevation, algorithm, kind="shadow", soft=False, curvature="auto",
           options=None):
    d = read_dem(path)
    sh = Shader(d.heights, d.grid, algorithm, options or {}, "cpu", curvature, None, dem_body(d))
    return render(sh, SunOver(None, azimuth, elevation), kind, soft=soft,
                  self_shadow=kind != "shadow")


@pytest.mark.parametrize("algorithm", ["smap", "brute", "horizon", "sweep"])
@pytest.mark.parametrize("azimuth,elevation", [(163.0, 8.0), (203.7, 4.0), (291.0, 15.0)])
def test_windows_equal_the_whole_raster(algorithm, azimuth, elevation):
    tiled, pieces, carried, carry = _tiled(LIDAR, azimuth, elevation, algorithm, (96, 112))
    whole = _whole(LIDAR, azimuth, elevation, algorithm)
    assert len(pieces) >= 16 and carried > 0
    if algorithm == "smap":   # SMap's tables were carried along the strips, not rebuilt
        assert carry.lines_carried > 0
    assert 0.02 < np.mean(whole == 1) < 0.9
    if algorithm != "sweep":
        np.testing.assert_array_equal(tiled, whole)
        return
    # sweep is approximate: its interpolated stored values depend on where the sweep starts (a
    # window's sun-side edge), so a few cells differ from the whole-raster sweep; both stay
    # within the stated error against brute
    exact = _whole(LIDAR, azimuth, elevation, "brute")
    assert np.mean(tiled != exact) <= 0.003 and np.mean(whole != exact) <= 0.003
    assert np.mean(tiled != whole) <= 0.002


@pytest.mark.parametrize("azimuth", [21.3, 68.0, 113.5, 163.0, 203.7, 251.0, 291.0, 338.6])
def test_smap_tables_carried_in_every_octant(tmp_path, azimuth):
    """SMap's Black colours and NextV pointers carried from window to window along a strip, in
    each of the eight octants (transposed and flipped frames), on rough terrain with voids and a
    low sun: the same mask as brute on the whole raster, cell for cell."""
    z = fractal_terrain(150, 170, seed=int(azimuth), relief=60.0)
    z[40:47, 100:109] = np.nan
    z[120, 30:90] = np.nan
    path = str(tmp_path / "dem.tif")
    write_geotiff(path, z, Affine(2.0, 0, 500000, 0, -2.0, 4100000), UTM)
    tiled, pieces, _, carry = _tiled(path, azimuth, 7.0, "smap", (24, 40))
    whole = _whole(path, azimuth, 7.0, "brute")
    # each strip coloured each line of the raster about once (one lookahead line per window)
    lines_are_cols = carry.key[0]
    strips = {p.region[:2] if lines_are_cols else p.region[2:] for p in pieces}
    n_lines = z.shape[1] if lines_are_cols else z.shape[0]
    assert len(pieces) >= 20 and carry.lines_carried > 0
    assert carry.lines_coloured <= len(strips) * n_lines + len(pieces)
    # each line coloured is a window's positions (its extent across the lines) of cells
    across = [p.window[1] - p.window[0] if lines_are_cols else p.window[3] - p.window[2]
              for p in pieces]
    assert min(across) * carry.lines_coloured <= carry.cells_coloured
    assert carry.cells_coloured <= max(across) * carry.lines_coloured
    fig = carry.figures(z.size)
    assert fig["smap_lines_carried"] == carry.lines_carried > 0
    assert fig["smap_coloured_beyond_output_fraction"] == pytest.approx(
        carry.cells_coloured / z.size - 1.0)
    assert 0.05 < np.mean(whole == 1) < 0.9
    np.testing.assert_array_equal(tiled, whole)


@pytest.mark.parametrize("azimuth", [37.0, 203.7])
def test_windows_on_a_geographic_dem_with_voids(azimuth):
    """Per-row spacing (EPSG:4326) and voids; the shared part carried between windows."""
    tiled, pieces, _, _ = _tiled(EVEREST, azimuth, 6.0, "smap", (64, 80))
    whole = _whole(EVEREST, azimuth, 6.0, "smap")
    assert (whole == 255).any() and len(pieces) >= 9
    np.testing.assert_array_equal(tiled, whole)


@pytest.mark.parametrize("kind,soft", [("classes", False), ("hillshade", False),
                                       ("shadow", True), ("hillshade", True)])
def test_products_and_curvature_in_windows(kind, soft):
    """Self-shadow normals need the neighbours across window edges; soft shadows the halo of the
    sun's lower edge; curvature the whole raster's extent."""
    tiled, _, _, _ = _tiled(LIDAR, 203.7, 3.0, "smap", (90, 130), kind, soft, curvature=True)
    whole = _whole(LIDAR, 203.7, 3.0, "smap", kind, soft, curvature=True)
    np.testing.assert_array_equal(tiled, whole)


def test_halo_is_on_the_sun_side_only_and_as_long_as_the_physics_says(tmp_path):
    """Flat ground with one 60 m tower; sun at 163 deg (south-south-east: toward higher rows and
    columns of a north-up raster), 30 deg up, 1 m cells."""
    z = np.zeros((600, 600), np.float32)
    z[400:404, 300:304] = 60.0
    p = write_geotiff(tmp_path / "t.tif", z, Affine(1, 0, 500000, 0, -1, 4000000), UTM)
    src = open_dem(p)
    stats = tiling.block_stats(src, block=32)
    az, el = 163.0, 30.0
    east, south = math.sin(math.radians(az)), -math.cos(math.radians(az))
    # a region just north-west of the tower: its halo reaches the tower
    reg = (256, 384, 192, 288)
    r0, r1, c0, c1 = tiling.window_for(reg, src.shape, src.grid, az, el, 0.0, stats)
    reach = 60.0 / math.tan(math.radians(el))
    assert (r0, c0) == (reg[0] - 1, reg[2] - 1)          # away from the sun: the 1-cell margin
    assert r1 == reg[1] + math.ceil(reach * south) + 2 + 1
    assert c1 == reg[3] + math.ceil(reach * east) + 2 + 1
    # a region whose sun side is flat ground: the halo shrinks to the two cells of the model
    reg = (0, 128, 0, 128)
    assert tiling.window_for(reg, src.shape, src.grid, az, el, 0.0, stats) == (0, 131, 0, 131)
    # curvature shortens the reach: d tan E + c d^2 = dh
    c = 1e-4
    r0, r1, c0, c1 = tiling.window_for((256, 384, 192, 288), src.shape, src.grid, az, el, c, stats)
    t = math.tan(math.radians(el))
    d = (-t + math.sqrt(t * t + 4 * c * 60.0)) / (2 * c)
    assert r1 == 384 + math.ceil(d * south) + 3 and d < reach


def test_window_order_follows_the_sun_and_the_plan_fits_the_budget(tmp_path):
    z = fractal_terrain(700, 900, 5, relief=80.0)
    p = write_geotiff(tmp_path / "f.tif", z, Affine(2, 0, 500000, 0, -2, 4000000), UTM)
    src = open_dem(p)
    stats = tiling.block_stats(src)
    budget = 250_000
    pieces = tiling.plan(src.shape, src.grid, 250.0, 10.0, 0.0, stats, budget, align=64)
    assert len(pieces) > 2 and all(q.cells <= budget for q in pieces)
    # sun from the west-south-west: columns from the west edge first
    starts = [q.region[2] for q in pieces]
    assert starts == sorted(starts)
    covered = np.zeros(src.shape, int)
    for q in pieces:
        r0, r1, c0, c1 = q.region
        covered[r0:r1, c0:c1] += 1
    assert (covered == 1).all()
    with pytest.raises(HillshadeError, match="raise --max-memory"):
        tiling.plan(src.shape, src.grid, 250.0, 1.0, 0.0, stats, 2_000)


def test_parse_size():
    assert tiling.parse_size("2GB") == 2_000_000_000
    assert tiling.parse_size("1.5GiB") == int(1.5 * 2 ** 30)
    assert tiling.parse_size("512 MB") == 512_000_000
    assert tiling.parse_size("800M") == 800_000_000
    assert tiling.parse_size("4096") == 4096
    for bad in ("lots", "-1GB", "0", "2XB"):
        with pytest.raises(HillshadeError):
            tiling.parse_size(bad)


# ------------------------------------------------------------------------------------------
# command line

def _run(runner, args):
    r = runner.invoke(cli, args)
    return r


def test_cli_window_size_equals_in_memory_and_reports_reads(tmp_path, runner):
    a, b, rep = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "b.json"
    base = ["--azimuth", "203.7", "--elevation", "6"]
    assert _run(runner, ["shadow", LIDAR, str(a)] + base).exit_code == 0
    r = _run(runner, ["shadow", LIDAR, str(b), "--window-size", "100x150", "--report",
                      str(rep)] + base)
    assert r.exit_code == 0, r.output
    np.testing.assert_array_equal(read_band(a), read_band(b))
    doc = json.loads(rep.read_text())["processing"]
    assert doc["mode"] == "tiled" and doc["windows"] == 12
    assert doc["cells_output"] == 400 * 400 and doc["cells_lit"] > doc["cells_output"]
    assert 0 < doc["bytes_read_beyond_output"] < doc["bytes_read"]
    assert doc["bytes_carried"] > 0
    assert doc["bytes_read"] + doc["bytes_carried"] == doc["cells_lit"] * 4


def test_preview_from_windows_equals_in_memory(tmp_path, runner):
    """The preview of a windowed run is put together from the windows' every-n-th cells."""
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    base = ["shadow", LIDAR, "--azimuth", "203.7", "--elevation", "6"]
    assert _run(runner, base + [str(tmp_path / "a.tif"), "--preview", str(a)]).exit_code == 0
    r = _run(runner, base + [str(tmp_path / "b.tif"), "--preview", str(b), "--window-size",
                             "100x150"])
    assert r.exit_code == 0, r.output
    pa, pb = read_band(a), read_band(b)
    assert (pa != pa[0, 0]).any()
    np.testing.assert_array_equal(pa, pb)


def test_cli_max_memory_switches_to_windows(tmp_path, runner):
    out, rep = tmp_path / "m.tif", tmp_path / "m.json"
    # room for the process, GDAL's cache and about 1 MB of windows: fewer cells than the DEM's
    limit = tiling.process_rss() + ((tiling.GDAL_CACHE_MB + 32 + 1) << 20)
    r = _run(runner, ["shadow", LIDAR, str(out), "--azimuth", "163", "--elevation", "10",
                      "--max-memory", str(limit), "--report", str(rep)])
    assert r.exit_code == 0, r.output
    doc = json.loads(rep.read_text())["processing"]
    assert doc["mode"] == "tiled" and doc["windows"] > 1
    assert doc["largest_window"][0] * doc["largest_window"][1] * doc["memory"]["bytes_per_cell"] \
        <= doc["memory"]["window_bytes"]
    np.testing.assert_array_equal(read_band(out), _whole(LIDAR, 163.0, 10.0, "smap"))


def test_cli_memory_too_small_is_one_line_and_no_output(tmp_path, runner):
    out = tmp_path / "m.tif"
    r = _run(runner, ["shadow", LIDAR, str(out), "--azimuth", "163", "--elevation", "10",
                      "--max-memory", "20MB"])
    assert r.exit_code == 1 and "--max-memory" in r.stderr and len(r.stderr.splitlines()) == 1
    assert not out.exists() and os.listdir(tmp_path) == []
    r = _run(runner, ["shadow", LIDAR, str(out), "--azimuth", "163", "--elevation", "10",
                      "--max-memory", "plenty"])
    assert r.exit_code == 2 and "--max-memory" in r.stderr


def test_mosaic_of_tiles_is_one_surface(tmp_path, runner):
    """A ridge in one tile shadows the next: the mosaic equals the whole DEM, a tile alone does
    not (the classic tile-edge error)."""
    z = fractal_terrain(300, 360, 11, relief=150.0)
    z[140:150, 170:178] = 400.0     # a tower near the tiles' corner
    tr = Affine(5, 0, 400000, 0, -5, 3800000)
    whole = write_geotiff(tmp_path / "whole.tif", z, tr, UTM)
    tiles = split_geotiff(tmp_path, z, tr, UTM, [(0, 150), (150, 300)],
                          [(0, 175), (175, 360)])
    a, b, one = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "one.tif"
    sun = ["--azimuth", "291", "--elevation", "7"]
    assert _run(runner, ["shadow", whole, str(a)] + sun).exit_code == 0
    r = _run(runner, ["shadow", *tiles[::-1], "-o", str(b)] + sun)   # any order
    assert r.exit_code == 0, r.output
    np.testing.assert_array_equal(read_band(a), read_band(b))
    import rasterio
    with rasterio.open(b) as ds, rasterio.open(whole) as w:
        assert ds.transform == w.transform and ds.crs == w.crs
    # the south-east tile alone misses the tower's shadow across its edge
    assert _run(runner, ["shadow", tiles[3], str(one)] + sun).exit_code == 0
    alone = read_band(one)
    assert (alone != read_band(a)[150:, 175:]).sum() > 20


@pytest.mark.parametrize("extra", [[], ["--cog", "--window-size", "96x128"],
                                   pytest.param(["--scheduler", "local:2", "--window-size", "128"],
                                                marks=pytest.mark.slow)])
def test_mosaic_one_output_per_tile(tmp_path, runner, extra):
    """--output-pattern with {tile}: the mosaic shaded as one surface, written as one file per
    input tile and time on the tile's own grid (the same cells as the whole DEM's run there);
    no scratch left beside them."""
    import rasterio
    z = fractal_terrain(260, 300, 5, relief=300.0)
    z[120:128, 140:146] = 500.0
    tr = Affine(5, 0, 400000, 0, -5, 3800000)
    whole = write_geotiff(tmp_path / "whole.tif", z, tr, UTM)
    tiles = split_geotiff(tmp_path, z, tr, UTM, [(0, 125), (125, 260)],
                          [(0, 143), (143, 300)])
    sun = ["--time", "2026-03-02T07:20-08:00", "--time", "2026-03-02T17:05-08:00"]
    ref = tmp_path / "ref.tif"
    assert _run(runner, ["shadow", whole, str(ref)] + sun).exit_code == 0
    outdir = tmp_path / "out"
    outdir.mkdir()
    r = _run(runner, ["shadow", *tiles, "--output-pattern", str(outdir / "{tile}_{index}.tif"),
                      "--report", str(tmp_path / "r.json")] + sun + extra)
    assert r.exit_code == 0, r.output
    names = sorted(f"tile_{i}{j}_{k}.tif" for i in range(2) for j in range(2) for k in range(2))
    assert sorted(os.listdir(outdir)) == names
    doc = json.loads((tmp_path / "r.json").read_text())
    assert len(doc["times"][1]["outputs"]) == 4
    with rasterio.open(ref) as rf:
        want = [rf.read(1), rf.read(2)]
        for t in tiles:
            stem = os.path.basename(t)[:-4]
            with rasterio.open(t) as src:
                c0, r0 = (round(v) for v in ~tr @ (src.transform.c, src.transform.f))
                for k in range(2):
                    with rasterio.open(outdir / f"{stem}_{k}.tif") as ds:
                        assert ds.transform == src.transform and ds.crs == src.crs
                        assert ds.shape == src.shape and ds.nodata == 255
                        assert ds.tags()["TILE_SOURCE"] == os.path.abspath(t)
                        assert ds.tags()["TIME"] == rf.tags(k + 1)["TIME"]
                        if "--cog" in extra:
                            assert ds.tags(ns="IMAGE_STRUCTURE").get("LAYOUT") == "COG"
                            _cog_valid(outdir / f"{stem}_{k}.tif")
                        np.testing.assert_array_equal(
                            ds.read(1), want[k][r0:r0 + src.height, c0:c0 + src.width])
    assert all(0.05 < np.mean(w == 1) < 0.9 for w in want)


def test_tile_outputs_need_tiles_of_distinct_names(tmp_path, runner):
    z = fractal_terrain(40, 60, 3)
    (tmp_path / "d1").mkdir()
    (tmp_path / "d2").mkdir()
    a = write_geotiff(tmp_path / "d1" / "t.tif", z[:, :30].copy(),
                      Affine(5, 0, 400000, 0, -5, 3800000), UTM)
    b = write_geotiff(tmp_path / "d2" / "t.tif", z[:, 30:].copy(),
                      Affine(5, 0, 400150, 0, -5, 3800000), UTM)
    r = _run(runner, ["shadow", a, b, "--output-pattern", str(tmp_path / "o_{tile}.tif"),
                      "--azimuth", "200", "--elevation", "10"])
    assert r.exit_code == 1 and "have the same file name" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert sorted(os.listdir(tmp_path)) == ["d1", "d2"]


def test_mosaic_refuses_misaligned_or_foreign_tiles(tmp_path, runner):
    z = fractal_terrain(64, 64, 2)
    a = write_geotiff(tmp_path / "a.tif", z, Affine(5, 0, 400000, 0, -5, 3800000), UTM)
    b = write_geotiff(tmp_path / "b.tif", z, Affine(5, 0, 400322.5, 0, -5, 3800000), UTM)
    c = write_geotiff(tmp_path / "c.tif", z, Affine(5, 0, 400320, 0, -5, 3800000),
                      CRS.from_epsg(32612))
    out = tmp_path / "o.tif"
    for other, msg in ((b, "not aligned"), (c, "CRS differs")):
        r = _run(runner, ["shadow", a, other, "-o", str(out), "--azimuth", "90",
                          "--elevation", "10"])
        assert r.exit_code == 1 and msg in r.stderr and not out.exists()
    # an input as the output
    r = _run(runner, ["shadow", a, b, "-o", b, "--azimuth", "90", "--elevation", "10",
                      "--overwrite"])
    assert r.exit_code == 2 and "also an input" in r.stderr


@pytest.mark.parametrize("window", [None, "200x256"])
def test_cog_output(tmp_path, runner, window):
    import rasterio
    dem = "examples/bigtujunga_srtm30m_utm11n_1197x643.tif"
    ref, out = tmp_path / "ref.tif", tmp_path / "cog.tif"
    sun = ["--azimuth", "203.7", "--elevation", "12"]
    assert _run(runner, ["shadow", dem, str(ref)] + sun).exit_code == 0
    args = ["shadow", dem, str(out), "--cog"] + sun + (["--window-size", window] if window else [])
    r = _run(runner, args)
    assert r.exit_code == 0, r.output
    with rasterio.open(out) as ds:
        assert ds.driver == "GTiff" and ds.block_shapes[0] == (512, 512)
        assert ds.overviews(1)[:1] == [2]
        assert ds.tags(ns="IMAGE_STRUCTURE").get("LAYOUT") == "COG"
        np.testing.assert_array_equal(ds.read(1), read_band(ref))
    _cog_valid(out)
    assert sorted(os.listdir(tmp_path)) == ["cog.tif", "ref.tif"]


def _cog_valid(path):
    """rio-cogeo's validator (the test extra): a valid COG, no errors."""
    from rio_cogeo.cogeo import cog_validate
    ok, errors, warnings = cog_validate(str(path), quiet=True)
    assert ok and errors == [], (path, errors, warnings)


@pytest.mark.parametrize("method,mode", [([], "per cell"), (["--algorithm", "smap"], "per tile")])
def test_series_and_varying_suns_in_windows(tmp_path, runner, method, mode):
    """Two times, a sun that varies across the DEM (a tiny tolerance), in windows: equal to in
    memory, with each cell's own sun (the default methods) or one per tile (smap)."""
    a, b = tmp_path / "a.tif", tmp_path / "b.tif"
    sun = ["--time", "2026-03-02T08:10-06:00", "--time", "2026-03-02T16:40-06:00",
           "--sun-tolerance", "0.0004"] + method
    ra = _run(runner, ["shadow", LIDAR, str(a), "--report", str(tmp_path / "a.json")] + sun)
    assert ra.exit_code == 0, ra.output
    assert json.loads((tmp_path / "a.json").read_text())["times"][0]["mode"] == mode
    rb = _run(runner, ["shadow", LIDAR, str(b), "--window-size", "128x128", "--report",
                       str(tmp_path / "b.json")] + sun)
    assert rb.exit_code == 0, rb.output
    assert json.loads((tmp_path / "b.json").read_text())["times"][0]["mode"] == mode
    for band in (1, 2):
        np.testing.assert_array_equal(read_band(a, band), read_band(b, band))


def test_interrupt_leaves_no_output(tmp_path, runner, monkeypatch):
    out = tmp_path / "m.tif"
    calls = []
    real = tiling.WindowLighting.light

    def light(self, *a, **k):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(self, *a, **k)
    monkeypatch.setattr(tiling.WindowLighting, "light", light)
    r = _run(runner, ["shadow", LIDAR, str(out), "--azimuth", "163", "--elevation", "10",
                      "--window-size", "100", "--cog"])
    assert r.exit_code == 130 and "no output written" in r.stderr
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
def test_dask_local_cluster_equals_one_process(tmp_path, runner):
    """Windows x times as tasks on three worker processes: the same bands as one process; the
    parts folder is gone afterwards."""
    a, b, rep = tmp_path / "a.tif", tmp_path / "b.tif", tmp_path / "b.json"
    sun = ["--time", "2026-06-21T07:00-05:00", "--time", "2026-06-21T18:30-05:00"]
    assert _run(runner, ["shadow", LIDAR, str(a)] + sun).exit_code == 0
    assert _run(runner, ["shadow", LIDAR, str(tmp_path / "a2.tif"), "--preview",
                         str(tmp_path / "a.png")] + sun).exit_code == 0
    r = _run(runner, ["shadow", LIDAR, str(b), "--scheduler", "local:3", "--window-size",
                      "128x160", "--report", str(rep), "--preview", str(tmp_path / "b.png")] + sun)
    assert r.exit_code == 0, r.output
    doc = json.loads(rep.read_text())
    assert doc["processing"]["mode"] == "dask" and doc["processing"]["workers"] == 3
    assert doc["processing"]["tasks"] == 2 * math.ceil(400 / 128) * math.ceil(400 / 160)
    import rasterio
    with rasterio.open(a) as x, rasterio.open(b) as y:
        assert y.count == 2 and y.descriptions == x.descriptions
        assert y.tags(1)["TIME"] == x.tags(1)["TIME"]
        for band in (1, 2):
            np.testing.assert_array_equal(x.read(band), y.read(band))
    np.testing.assert_array_equal(read_band(tmp_path / "a.png"), read_band(tmp_path / "b.png"))
    assert sorted(os.listdir(tmp_path)) == ["a.png", "a.tif", "a2.tif", "b.json", "b.png",
                                            "b.tif"]


@pytest.mark.parametrize("when", ["2026-06-21T06:10-07:00", "2026-12-21T15:40-08:00"])
def test_each_cells_own_sun_in_windows_equals_in_memory(tmp_path, runner, when):
    """A 60 km DEM at a low sun (the direction varies ~0.35 deg across it): marched with each
    cell's own sun in memory and in small windows, whose halos hold every cell's ray (its
    lowest sun, both extreme azimuths): the same mask, cell for cell."""
    rng = np.random.default_rng(11)
    z = fractal_terrain(240, 320, 11, relief=2500.0).astype(np.float32)
    z += rng.normal(0.0, 30.0, z.shape).astype(np.float32)        # rough, not facets
    dem = tmp_path / "d.tif"
    write_geotiff(dem, z, Affine(200.0, 0, 400000.0, 0, -200.0, 3800000.0), CRS.from_epsg(32611))
    a, b = tmp_path / "a.tif", tmp_path / "b.tif"
    sun = ["--time", when, "--sun-tolerance", "0.15"]      # large tiles: suns far from theirs
    ra = _run(runner, ["shadow", str(dem), str(a), "--report", str(tmp_path / "a.json")] + sun)
    assert ra.exit_code == 0, ra.output
    rep = json.loads((tmp_path / "a.json").read_text())["times"][0]
    assert rep["mode"] == "per cell" and rep["deviation_deg"] > 0.2
    rb = _run(runner, ["shadow", str(dem), str(b), "--window-size", "64x64"] + sun)
    assert rb.exit_code == 0, rb.output
    mask = read_band(a)
    assert 0.05 < np.mean(mask == 1) < 0.95
    np.testing.assert_array_equal(read_band(b), mask)


def _varying_sun(shape, az0, el0, daz, del_, n_tiles=2):
    """A SunOver whose direction varies by ``daz`` / ``del_`` degrees across a raster of
    ``shape`` (a 9 x 9 lattice; tiles of n_tiles x n_tiles, each its centre's sun)."""
    from hillshade_rt.algorithms.per_cell_sun import lattice_vectors
    from hillshade_rt.model.sun import Region
    i, j = np.meshgrid(np.linspace(-0.5, 0.5, 9), np.linspace(-0.5, 0.5, 9), indexing="ij")
    az, el = az0 + daz * j + 0.2 * daz * i, el0 + del_ * i
    rows, cols = shape
    tiles = []
    for a in range(n_tiles):
        for b in range(n_tiles):
            r0, r1 = a * rows // n_tiles, (a + 1) * rows // n_tiles
            c0, c1 = b * cols // n_tiles, (b + 1) * cols // n_tiles
            fi, fj = ((r0 + r1) / 2 / rows - 0.5), ((c0 + c1) / 2 / cols - 0.5)
            tiles.append(Region(slice(r0, r1), slice(c0, c1), az0 + daz * fj + 0.2 * daz * fi,
                                el0 + del_ * fi))
    return SunOver(None, az0, el0, deviation_deg=max(daz, del_), tiles=tiles,
                   lattice=lattice_vectors(az, el))


@pytest.mark.parametrize("az0,el0,n_tiles", [(180.0, 8.0, 1), (270.0, 5.0, 1), (90.0, 20.0, 2),
                                             (33.0, 6.0, 1)])
def test_windows_hold_the_halo_of_every_cells_own_sun(tmp_path, az0, el0, n_tiles):
    """A sun per cell that varies by 8 deg of azimuth and 2 of elevation (far more than a
    time-based sun's 0.35) over needles on a plain, whose shadows depend on the ray's exact
    direction: windows of 40 x 40 whose halos cover each cell's ray (the tile's lowest sun and
    extreme azimuths) give what one run in memory gives (with the halos of the tile's own sun
    only, 9 and 44 cells differ at 8 and 5 deg)."""
    rng = np.random.default_rng(5)
    z = rng.normal(0.0, 0.3, (160, 200)).astype(np.float32)
    idx = rng.choice(z.size, 300, replace=False)
    z.flat[idx] = rng.uniform(80.0, 200.0, 300)
    z[70:74, 20:24] = np.nan
    path = tmp_path / "needles.tif"
    write_geotiff(path, z, Affine(10.0, 0, 500000.0, 0, -10.0, 4000000.0), UTM)
    d = read_dem(path)
    sun = _varying_sun(d.shape, az0, el0, 8.0, 2.0, n_tiles)
    assert sun.fieldwise
    st = {}
    whole = render(Shader(d.heights, d.grid, "auto", {}, "cpu", "auto", None, dem_body(d)), sun,
                   "shadow", stats=st)
    assert st["sun_field"] == 1
    out, pieces, _, _ = _tiled(path, az0, el0, "auto", (40, 40), sun=sun)
    assert all(p.sun is sun for p in pieces)
    np.testing.assert_array_equal(out, whole)
