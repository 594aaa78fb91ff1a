"""--context RASTER: a tile lit with the heights of the mosaic around it equals the same cells of
the whole mosaic's output, for every lighting and horizon product; what a context must be; the
windows read; tiles of the sea."""

from __future__ import annotations

import os

import numpy as np
import pytest
import rasterio
from affine import Affine
from click.testing import CliRunner
from rasterio.windows import Window

from hillshade_rt import api
from hillshade_rt.cli import cli
from hillshade_rt.io.vrt import VrtSource, vrt_xml
from hillshade_rt.testing import read_band, repo_root, write_geotiff

DEM = "examples/bigtujunga_srtm30m_utm11n_1197x643.tif"
ROWS, COLS, SIDE = 512, 768, 256      # the mosaic: the DEM's top-left 512 x 768, 256² tiles


def _vrt(path, shape, transform, crs, tiles, nodata):
    """A VRT of ``tiles`` ((path, row, col, shape)) written with io.vrt's document."""
    doc = vrt_xml(shape, transform, crs,
                  [[VrtSource(p, 1, (r, c), s, nodata) for p, r, c, s in tiles]], "Int16",
                  nodata)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(doc)
    return str(path)


@pytest.fixture(scope="module")
def mosaic(tmp_path_factory):
    """The real DEM cut into 256² GeoTIFF tiles and their VRT: (vrt, [(tile, r0, c0)], meta)."""
    d = tmp_path_factory.mktemp("context")
    tiles = []
    with rasterio.open(os.path.join(repo_root(), DEM)) as ds:
        meta = dict(transform=ds.transform, crs=ds.crs, nodata=ds.nodata)
        for r in range(0, ROWS, SIDE):
            for c in range(0, COLS, SIDE):
                w = Window(c, r, SIDE, SIDE)
                p = write_geotiff(d / f"t_{r}_{c}.tif", ds.read(1, window=w),
                                  ds.window_transform(w), ds.crs, ds.nodata)
                tiles.append((p, r, c))
    vrt = _vrt(d / "all.vrt", (ROWS, COLS), meta["transform"], meta["crs"],
               [(p, r, c, (SIDE, SIDE)) for p, r, c in tiles], meta["nodata"])
    return vrt, tiles, meta, d


def _cells(whole, r, c):
    return whole[..., r:r + SIDE, c:c + SIDE]


def _read_all(path):
    with rasterio.open(path) as ds:
        return ds.read(), ds.profile


@pytest.mark.parametrize("azimuth,elevation", [(163.0, 4.0), (203.7, 45.0), (290.0, 12.0)])
def test_shadow_tiles_equal_the_mosaic(mosaic, azimuth, elevation):
    vrt, tiles, meta, d = mosaic
    api.shade(vrt, d / "whole.tif", azimuth=azimuth, elevation=elevation, overwrite=True)
    whole = read_band(d / "whole.tif")
    differ_alone = 0
    for p, r, c in tiles:
        rep = api.shade(p, d / "tile.tif", azimuth=azimuth, elevation=elevation, overwrite=True,
                        context=vrt)
        got, prof = _read_all(d / "tile.tif")
        with rasterio.open(p) as t:       # the tile's grid: shape, transform, CRS
            assert (prof["height"], prof["width"]) == (t.height, t.width)
            assert prof["transform"] == t.transform and prof["crs"] == t.crs
        np.testing.assert_array_equal(got[0], _cells(whole, r, c))
        assert rep["shape"] == [SIDE, SIDE]
        api.shade(p, d / "alone.tif", azimuth=azimuth, elevation=elevation, overwrite=True)
        differ_alone += int((read_band(d / "alone.tif") != _cells(whole, r, c)).sum())
    # without --context the shadows cast across the tiles' edges are lost
    assert differ_alone > 0


def test_classes_soft_and_hillshade_tiles(mosaic):
    vrt, tiles, meta, d = mosaic
    cases = [dict(product="classes", azimuth=203.7, elevation=8.0),
             dict(product="shadow", soft=True, azimuth=163.0, elevation=6.0),
             dict(product="hillshade", azimuth=290.0, elevation=10.0)]
    for kw in cases:
        api.shade(vrt, d / "whole.tif", overwrite=True, **kw)
        whole = read_band(d / "whole.tif")
        alone_differs = False
        for p, r, c in tiles[1:5]:
            api.shade(p, d / "tile.tif", overwrite=True, context=vrt, **kw)
            np.testing.assert_array_equal(read_band(d / "tile.tif"), _cells(whole, r, c))
            api.shade(p, d / "alone.tif", overwrite=True, **kw)
            alone_differs |= bool((read_band(d / "alone.tif") != _cells(whole, r, c)).any())
        assert alone_differs, kw


def test_suns_per_cell_are_the_mosaics(mosaic):
    """--time: the sun varies across the mosaic (per cell, tiles of the whole raster); the tile
    takes the mosaic's suns, not its own (its centre's sun differs)."""
    vrt, tiles, meta, d = mosaic
    times = ["2026-06-21T07:00:00-07:00", "2026-12-21T15:40:00-08:00"]
    rep_w = api.shade(vrt, d / "whole.tif", times=times, overwrite=True)
    assert rep_w["times"][0]["mode"] == "per cell" and rep_w["times"][0]["tiles"] > 1
    whole, _ = _read_all(d / "whole.tif")
    for p, r, c in (tiles[0], tiles[4]):
        rep = api.shade(p, d / "tile.tif", times=times, overwrite=True, context=vrt)
        got, _ = _read_all(d / "tile.tif")
        np.testing.assert_array_equal(got, _cells(whole, r, c))
        assert [s["azimuth"] for s in rep["times"]] == [s["azimuth"] for s in rep_w["times"]]
        alone = api.shade(p, d / "alone.tif", times=times, overwrite=True)
        assert alone["times"][0]["azimuth"] != rep_w["times"][0]["azimuth"]
    # soft shadows keep the tiles of the whole raster (one sun per tile of the mosaic)
    api.shade(vrt, d / "whole.tif", times=times[1:], soft=True, overwrite=True)
    whole = read_band(d / "whole.tif")
    p, r, c = tiles[2]
    api.shade(p, d / "tile.tif", times=times[1:], soft=True, overwrite=True, context=vrt)
    np.testing.assert_array_equal(read_band(d / "tile.tif"), _cells(whole, r, c))


def test_curvature_auto_decided_for_the_context(mosaic):
    """At 45° the mosaic's relief (1645 m) turns Earth curvature on ("auto": a ray longer than
    1 km), the top-left tile's own (933 m) would not: with --context the tile decides as the
    mosaic does."""
    vrt, tiles, meta, d = mosaic
    p, r, c = tiles[0]
    rep_w = api.shade(vrt, d / "whole.tif", azimuth=203.7, elevation=45.0, overwrite=True)
    rep = api.shade(p, d / "tile.tif", azimuth=203.7, elevation=45.0, overwrite=True,
                    context=vrt)
    alone = api.shade(p, d / "alone.tif", azimuth=203.7, elevation=45.0, overwrite=True)
    assert rep_w["curvature"]["applied"] and rep["curvature"]["applied"]
    assert not alone["curvature"]["applied"]
    np.testing.assert_array_equal(read_band(d / "tile.tif"),
                                  _cells(read_band(d / "whole.tif"), r, c))


def test_sun_hours_tiles(mosaic):
    vrt, tiles, meta, d = mosaic
    r_ = CliRunner()
    args = ["--date", "2026-12-21", "--step", "2h", "--overwrite", "-q"]
    res = r_.invoke(cli, ["sun-hours", vrt, str(d / "whole.tif"), *args])
    assert res.exit_code == 0, res.output
    whole = read_band(d / "whole.tif")
    differ = 0
    for p, r, c in tiles[:3]:
        res = r_.invoke(cli, ["sun-hours", p, str(d / "tile.tif"), "--context", vrt, *args])
        assert res.exit_code == 0, res.output
        np.testing.assert_array_equal(read_band(d / "tile.tif"), _cells(whole, r, c))
        r_.invoke(cli, ["sun-hours", p, str(d / "alone.tif"), *args])
        differ += int((read_band(d / "alone.tif") != _cells(whole, r, c)).sum())
    assert differ > 0


@pytest.mark.parametrize("cmd,extra", [
    ("horizon", ["--azimuth", "203.7", "--max-distance", "3000"]),
    ("horizon", ["--directions", "8", "--max-distance", "1500", "--distance", "{dist}"]),
    pytest.param("skyview", ["--directions", "16", "--max-distance", "2000"],
                 marks=pytest.mark.slow),
    pytest.param("skyview", ["--directions", "8", "--definition", "dozier"],  # the whole context
                 marks=pytest.mark.slow),
])
def test_horizon_and_skyview_tiles(mosaic, cmd, extra):
    vrt, tiles, meta, d = mosaic
    r_ = CliRunner()

    def run(dem, out, *more):
        args = [a.replace("{dist}", str(out) + ".dist.tif") for a in extra]
        res = r_.invoke(cli, [cmd, dem, str(out), "--overwrite", "-q", *args, *more])
        assert res.exit_code == 0, res.output
        got, _ = _read_all(out)
        if "--distance" in extra:
            got = np.concatenate([got, _read_all(str(out) + ".dist.tif")[0]])
        return got
    whole = run(vrt, d / "whole.tif")
    differ = 0
    for p, r, c in (tiles[1], tiles[5]):
        np.testing.assert_array_equal(run(p, d / "tile.tif", "--context", vrt),
                                      _cells(whole, r, c))
        differ += int((run(p, d / "alone.tif") != _cells(whole, r, c)).sum())
    assert differ > 0


@pytest.mark.slow
@pytest.mark.parametrize("extra", [
    ["--date", "2026-12-21", "--step", "2h", "--skyview-directions", "8"],
    ["--start", "2026-06-21T05:00-07:00", "--end", "2026-06-21T19:00-07:00", "--step", "3h",
     "--skyview-directions", "8", "--perez", "--soft", "--mean"],
])
def test_irradiance_tiles(mosaic, extra):
    """irradiance --context: the beam's cast shadows and incidence per sun from the context's
    windows, Dozier's sky view with rays to the context's edge, the place, the suns per tile
    and curvature "auto" the mosaic's: the four bands equal the mosaic's cells bit for bit."""
    import json
    vrt, tiles, meta, d = mosaic
    r_ = CliRunner()

    def run(dem, out, *more):
        rep = str(out) + ".json"
        res = r_.invoke(cli, ["irradiance", dem, str(out), "--overwrite", "-q", "--report",
                              rep, *extra, *more])
        assert res.exit_code == 0, res.output
        with open(rep, encoding="utf-8") as fh:
            return _read_all(out)[0], json.load(fh)
    whole, rep_w = run(vrt, d / "whole.tif")
    differ = 0
    for p, r, c in (tiles[0], tiles[4]):
        got, rep = run(p, d / "tile.tif", "--context", vrt)
        np.testing.assert_array_equal(got, _cells(whole, r, c))
        assert rep["shape"] == [SIDE, SIDE] and rep["context"]["window"] == [r, r + SIDE, c,
                                                                            c + SIDE]
        assert rep["site"] == rep_w["site"]
        assert rep["curvature"]["applied"] == rep_w["curvature"]["applied"]
        alone, rep_a = run(p, d / "alone.tif")
        assert rep_a["site"] != rep_w["site"]
        differ += int((alone != _cells(whole, r, c)).sum())
    # without --context the shadows and the sky beyond the tile's edges are lost
    assert differ > 0


def test_irradiance_context_refusals(mosaic, tmp_path):
    vrt, tiles, meta, d = mosaic
    res = CliRunner().invoke(cli, ["irradiance", tiles[0][0], str(tmp_path / "o.tif"),
                                   "--context", vrt, "--date", "2026-06-21", "--preview",
                                   str(tmp_path / "p.png")])
    assert res.exit_code == 2 and "--preview" in res.output, res.output
    assert len(res.output.strip().splitlines()) == 1
    res = CliRunner().invoke(cli, ["irradiance", tiles[0][0], vrt, "--context", vrt,
                                   "--date", "2026-06-21", "--overwrite"])
    assert res.exit_code != 0 and len(res.output.strip().splitlines()) == 1, res.output
    assert not (tmp_path / "o.tif").exists()


def test_reads_only_the_tiles_windows(tmp_path, monkeypatch):
    """A tile in the middle of a context 8 x 8 tiles large: the windows lit are the tile and its
    halo toward the sun (recorded), a small share of the context; far away cells do not
    matter (made voids, the same mask)."""
    from hillshade_rt.engine import windows
    from hillshade_rt.testing import fractal_terrain
    n, side = 1024, 128
    z = fractal_terrain(n, n, 7, relief=60.0).astype(np.float32) + 500.0
    t = Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0)
    ctx = write_geotiff(tmp_path / "ctx.tif", z, t, "EPSG:32611", -9999.0)
    r0 = c0 = 448
    tile = write_geotiff(tmp_path / "tile.tif", z[r0:r0 + side, c0:c0 + side],
                         t @ Affine.translation(c0, r0), "EPSG:32611", -9999.0)
    seen = []
    get = windows.WindowCache.get

    def spy(self, window):
        seen.append(window)
        return get(self, window)
    monkeypatch.setattr(windows.WindowCache, "get", spy)
    rep = api.shade(tile, tmp_path / "m.tif", azimuth=203.7, elevation=20.0, context=ctx)
    assert seen
    for a, b, c, e in seen:        # the sun is south-south-west: the halo runs down and left
        assert r0 - 2 <= a and b <= r0 + side + 64 and c0 - 32 <= c and e <= c0 + side + 2
    read = rep["processing"]["bytes_read"]
    assert read < 2 * side * side * 4 < n * n * 4 // 16
    # the cells beyond the windows read: voids now, the tile's mask the same
    far = np.full_like(z, np.nan)
    a = min(w[0] for w in seen), max(w[1] for w in seen)
    b = min(w[2] for w in seen), max(w[3] for w in seen)
    far[a[0]:a[1], b[0]:b[1]] = z[a[0]:a[1], b[0]:b[1]]
    far[0, 0], far[-1, -1] = np.nanmin(z), np.nanmax(z)     # the same height range
    ctx2 = write_geotiff(tmp_path / "ctx2.tif", far, t, "EPSG:32611", -9999.0)
    api.shade(tile, tmp_path / "m2.tif", azimuth=203.7, elevation=20.0, context=ctx2)
    np.testing.assert_array_equal(read_band(tmp_path / "m2.tif"), read_band(tmp_path / "m.tif"))


# ---------------------------------------------------------------------------------------------
# what a context must be

def _bad(tmp_path, tile, **change):
    """A copy of ``tile`` (as a context) with its grid changed."""
    with rasterio.open(tile) as ds:
        z, t, crs = ds.read(1), ds.transform, ds.crs
    t = change.get("transform", lambda t: t)(t)
    return write_geotiff(tmp_path / f"ctx_{len(os.listdir(tmp_path))}.tif", z, t,
                         change.get("crs", crs), -32768)


@pytest.mark.parametrize("what,change,words", [
    ("crs", dict(crs="EPSG:32612"), "CRS differs"),
    ("resolution", dict(transform=lambda t: Affine(60.0, 0, t.c, 0, -60.0, t.f)), "cell size"),
    ("half a cell", dict(transform=lambda t: t @ Affine.translation(0.5, 0)), "not aligned"),
    ("outside", dict(transform=lambda t: t @ Affine.translation(100, 0)), "does not contain"),
])
def test_context_on_another_grid_is_a_usage_error(mosaic, tmp_path, what, change, words):
    vrt, tiles, meta, d = mosaic
    p = tiles[4][0]
    ctx = _bad(tmp_path, p, **change)
    for cmd, extra in (("shadow", ["--azimuth", "200", "--elevation", "10"]),
                       ("horizon", ["--azimuth", "200"]),
                       ("sun-hours", ["--date", "2026-06-21"])):
        res = CliRunner().invoke(cli, [cmd, p, str(tmp_path / "o.tif"), "--context", ctx,
                                       *extra])
        assert res.exit_code == 2, (what, cmd, res.output)
        lines = res.output.strip().splitlines()
        assert len(lines) == 1 and words in lines[0], res.output
        assert not (tmp_path / "o.tif").exists()


def test_context_is_no_output_and_takes_one_dem(mosaic, tmp_path):
    vrt, tiles, meta, d = mosaic
    res = CliRunner().invoke(cli, ["shadow", tiles[0][0], vrt, "--context", vrt, "--azimuth",
                                   "200", "--elevation", "10", "--overwrite"])
    assert res.exit_code != 0 and len(res.output.strip().splitlines()) == 1
    res = CliRunner().invoke(cli, ["shadow", tiles[0][0], tiles[1][0], "-o",
                                   str(tmp_path / "o.tif"), "--context", vrt, "--azimuth",
                                   "200", "--elevation", "10"])
    assert res.exit_code == 2 and "one DEM" in res.output


# ---------------------------------------------------------------------------------------------
# tiles of the sea

@pytest.fixture
def coast(tmp_path):
    """Two tiles side by side, the right one all nodata (the sea), and their VRT."""
    z = np.full((64, 128), -9999, np.int16)
    z[:, :64] = (np.arange(64)[None, :] * 20 + 100).astype(np.int16)
    t = Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0)
    land = write_geotiff(tmp_path / "land.tif", z[:, :64], t, "EPSG:32611", -9999)
    sea = write_geotiff(tmp_path / "sea.tif", z[:, 64:], t @ Affine.translation(64, 0),
                        "EPSG:32611", -9999)
    vrt = _vrt(tmp_path / "all.vrt", (64, 128), t, rasterio.crs.CRS.from_epsg(32611),
               [(land, 0, 0, (64, 64)), (sea, 0, 64, (64, 64))], -9999)
    return tmp_path, sea, vrt


@pytest.mark.parametrize("cmd,extra,nodata", [
    ("shadow", ["--azimuth", "200", "--elevation", "10"], 255),
    ("hillshade", [], 0),
    ("shadow", ["--azimuth", "200", "--elevation", "10", "--soft"], -9999.0),
    ("sun-hours", ["--date", "2026-06-21", "--step", "3h"], -9999.0),
    ("horizon", ["--azimuth", "200", "--max-distance", "500"], -9999.0),
    ("skyview", ["--directions", "8"], -9999.0),
])
@pytest.mark.parametrize("with_context", [True, False])
def test_all_nodata_tile_writes_nodata(coast, cmd, extra, nodata, with_context):
    d, sea, vrt = coast
    out = d / "o.tif"
    more = ["--context", vrt] if with_context else []
    res = CliRunner().invoke(cli, [cmd, sea, str(out), *extra, *more])
    assert res.exit_code == 0, res.output
    notes = [ln for ln in res.output.splitlines() if "every cell is nodata" in ln]
    assert len(notes) == 1 and "note" in notes[0], res.output
    quiet = CliRunner().invoke(cli, [cmd, sea, str(out), *extra, *more, "-q", "--overwrite"])
    assert quiet.exit_code == 0 and quiet.output == "", quiet.output    # -q: nothing said
    got, prof = _read_all(out)
    assert prof["nodata"] == nodata and (got == nodata).all()
    assert (prof["height"], prof["width"]) == (64, 64)


@pytest.mark.parametrize("with_context", [True, False])
def test_all_nodata_irradiance(coast, with_context):
    d, sea, vrt = coast
    more = ["--context", vrt] if with_context else []
    res = CliRunner().invoke(cli, ["irradiance", sea, str(d / "i.tif"), "--date", "2026-06-21",
                                   "--step", "3h", *more])
    assert res.exit_code == 0, res.output
    assert "every cell is nodata" in res.output
    got, prof = _read_all(d / "i.tif")
    assert got.shape[0] == 4 and (got == -9999.0).all()


# ---------------------------------------------------------------------------------------------
# the context's block statistics, kept between runs (run.statscache)

@pytest.fixture
def small_mosaic(tmp_path, monkeypatch):
    """A fractal 512² cut into four 256² tiles and their VRT; the statistics cache in a folder
    of its own: (folder, [(tile, r0, c0)], vrt, heights, transform, cache folder)."""
    from hillshade_rt.testing import fractal_terrain
    z = (fractal_terrain(512, 512, 11, relief=400.0) + 500.0).astype(np.float32)
    t = Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0)
    tiles = []
    for r in (0, 256):
        for c in (0, 256):
            tiles.append((write_geotiff(tmp_path / f"s_{r}_{c}.tif", z[r:r + 256, c:c + 256],
                                        t @ Affine.translation(c, r), "EPSG:32611", -9999.0),
                          r, c))
    vrt = _vrt(tmp_path / "s.vrt", (512, 512), t, rasterio.crs.CRS.from_epsg(32611),
               [(p, r, c, (256, 256)) for p, r, c in tiles], -9999.0)
    # (Float32 tiles under an Int16 VRT would round: the VRT says Float32)
    with open(vrt, encoding="utf-8") as fh:
        doc = fh.read().replace('dataType="Int16"', 'dataType="Float32"')
    with open(vrt, "w", encoding="utf-8") as fh:
        fh.write(doc)
    cache = tmp_path / "stats"
    monkeypatch.setenv("HILLSHADE_RT_STATS_DIR", str(cache))
    return tmp_path, tiles, vrt, z, t, cache


def _shade_tile(tile, out, vrt):
    rep = api.shade(tile, out, azimuth=203.7, elevation=15.0, overwrite=True, context=vrt)
    return read_band(out), rep["processing"]


def test_statistics_cached_between_runs(small_mosaic, monkeypatch):
    """The first run of a tile reads the whole context once for its statistics and stores
    them; the next runs (other tiles, other commands) read only their windows; the outputs
    are the same with and without the cache."""
    from hillshade_rt.io import source
    d, tiles, vrt, z, t, cache = small_mosaic
    read = []
    orig = source.Reader.read

    def spy(self, bounds, out):
        read.append((bounds[1] - bounds[0]) * (bounds[3] - bounds[2]))
        return orig(self, bounds, out)
    monkeypatch.setattr(source.Reader, "read", spy)
    tile = tiles[3][0]
    first, proc = _shade_tile(tile, d / "a.tif", vrt)
    st = proc["context"]["statistics_pass"]
    assert st["cache"] == "stored" and st["bytes_read"] == 512 * 512 * 4
    assert proc["statistics_pass_bytes"] == 512 * 512 * 4 and sum(read) >= 512 * 512
    assert len(os.listdir(cache)) == 1 and st["file"].startswith(str(cache))
    before = sum(read)
    read.clear()
    again, proc = _shade_tile(tile, d / "b.tif", vrt)
    assert proc["context"]["statistics_pass"] == {"cache": "hit", "bytes_read": 0,
                                                  "file": st["file"]}
    assert proc["statistics_pass_bytes"] == 0
    # only the tile's windows (and its validity check): the statistics pass less
    assert sum(read) == before - 512 * 512 and sum(read) < 512 * 512
    np.testing.assert_array_equal(again, first)
    # the other commands take the same entry
    res = CliRunner().invoke(cli, ["sun-hours", tiles[0][0], str(d / "h.tif"), "--context",
                                   vrt, "--date", "2026-12-21", "--step", "3h", "-q",
                                   "--report", str(d / "h.json")])
    assert res.exit_code == 0, res.output
    import json
    with open(d / "h.json", encoding="utf-8") as fh:
        assert json.load(fh)["context"]["statistics_pass"]["cache"] == "hit"
    # without the cache: the same output
    monkeypatch.setenv("HILLSHADE_RT_STATS_DIR", "off")
    off, proc = _shade_tile(tile, d / "c.tif", vrt)
    assert proc["context"]["statistics_pass"]["cache"] == "off"
    np.testing.assert_array_equal(off, first)


def test_statistics_cache_follows_the_sources(small_mosaic, monkeypatch):
    """Touching a tile of the context, or rewriting it, makes the next run read the context
    again (a new entry); the result is then that of the changed context."""
    d, tiles, vrt, z, t, cache = small_mosaic
    tile = tiles[3][0]
    _shade_tile(tile, d / "a.tif", vrt)
    _, proc = _shade_tile(tile, d / "a.tif", vrt)
    assert proc["context"]["statistics_pass"]["cache"] == "hit"
    far = tiles[0][0]                       # touched: its time changes, not its heights
    st = os.stat(far)
    os.utime(far, ns=(st.st_atime_ns, st.st_mtime_ns + 5_000_000_000))
    _, proc = _shade_tile(tile, d / "a.tif", vrt)
    assert proc["context"]["statistics_pass"]["cache"] == "stored"
    # rewritten: a mountain in the tile up-sun, higher than the whole context was
    z2 = z.copy()
    z2[:256, :256] += 3000.0
    write_geotiff(tiles[0][0], z2[:256, :256], t, "EPSG:32611", -9999.0)
    changed, proc = _shade_tile(tile, d / "b.tif", vrt)
    assert proc["context"]["statistics_pass"]["cache"] == "stored"
    monkeypatch.setenv("HILLSHADE_RT_STATS_DIR", "off")
    fresh, _ = _shade_tile(tile, d / "c.tif", vrt)
    np.testing.assert_array_equal(changed, fresh)


@pytest.mark.parametrize("garbage", [b"", b"PK\x03\x04 not a zip", None])
def test_statistics_cache_bad_entry_is_computed_again(small_mosaic, garbage):
    """A partial, corrupt or foreign entry (arrays that do not fit the context) is ignored: the statistics are read again and the entry replaced; the output the same."""
    d, tiles, vrt, z, t, cache = small_mosaic
    tile = tiles[1][0]
    first, proc = _shade_tile(tile, d / "a.tif", vrt)
    path = proc["context"]["statistics_pass"]["file"]
    if garbage is None:              # its key, but arrays of another shape
        with np.load(path) as f:
            key = f["key"]
        np.savez(path, key=key, lo=np.zeros((1, 1), np.float32),
                 hi=np.zeros((1, 1), np.float32), valid=np.array(1))
    else:
        with open(path, "wb") as fh:
            fh.write(garbage)
    again, proc = _shade_tile(tile, d / "b.tif", vrt)
    assert proc["context"]["statistics_pass"]["cache"] == "stored"
    np.testing.assert_array_equal(again, first)
    _, proc = _shade_tile(tile, d / "b.tif", vrt)
    assert proc["context"]["statistics_pass"]["cache"] == "hit"


def test_cache_command_shows_and_prunes_the_statistics(small_mosaic, monkeypatch, tmp_path):
    from hillshade_rt.run import statscache
    d, tiles, vrt, z, t, cache = small_mosaic
    _shade_tile(tiles[0][0], d / "a.tif", vrt)
    found = statscache.survey()
    assert found["root"] == str(cache) and found["entries"] == 1 and found["stale"] == []
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "numba"))    # (not the real one)
    res = CliRunner().invoke(cli, ["cache"])
    assert res.exit_code == 0 and f"context statistics cache: {cache}" in res.output
    assert "entries: 1" in res.output
    os.unlink(tiles[2][0])                       # a file of the entry gone: stale
    assert len(statscache.survey()["stale"]) == 1
    res = CliRunner().invoke(cli, ["cache", "--prune"])
    assert res.exit_code == 0, res.output
    assert os.listdir(cache) == []
