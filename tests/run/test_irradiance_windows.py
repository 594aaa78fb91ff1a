"""irradiance in windows (``run.irradiance_windows``): region by region, the samples in groups
whose windows fit memory, each region's sky view from the windowed horizon march (or read
from --sky-view window by window), written as the regions are made, or each region a Dask
task: the four bands equal the run in memory bit for bit, on a real DEM (a crop of the
Jacksboro fault's SRTM, geographic) and on a fractal (UTM), with Perez and --mean, with the
sky view read and written; the options' refusals."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import rasterio
from affine import Affine
from click.testing import CliRunner
from rasterio.crs import CRS

from hillshade_rt import api
from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, fractal_terrain, write_geotiff

DAY = dict(date="2026-03-02", step="1h", skyview_directions=8)
UTM32 = CRS.from_epsg(32632)
ORIGIN = Affine(10.0, 0, 600000.0, 0, -10.0, 5150000.0)      # about 46.5 N 8.3 E


@pytest.fixture
def any_window(monkeypatch):
    """--window-size down to one cell a side (the command line asks for 64 at least)."""
    from hillshade_rt.run import config
    monkeypatch.setattr(config, "MIN_WINDOW_SIDE", 1)


@pytest.fixture(scope="module")
def dems(tmp_path_factory):
    """A 70 x 90 crop of the Jacksboro fault's SRTM (geographic, the spacing per row; a few
    voids put in) and a 72 x 90 fractal on UTM cells of 10 m, 300 m of relief."""
    d = tmp_path_factory.mktemp("dems")
    with rasterio.open(data_path("jacksboro_fault_srtm3_mpl_403x344.tif")) as ds:
        z = ds.read(1, window=((120, 190), (200, 290))).astype(np.float32)
        z[30:33, 40:52] = -9999.0
        real = write_geotiff(d / "real.tif", z,
                             ds.window_transform(((120, 190), (200, 290))), ds.crs, -9999.0)
    frac = write_geotiff(d / "frac.tif", fractal_terrain(72, 90, 163, relief=300.0), ORIGIN,
                         UTM32)
    return {"real": real, "frac": frac}


def _run(path, dem, **kw):
    """The four bands, the report, and the file's tags, descriptions and band tags."""
    rep = api.irradiance(dem, path, overwrite=True, progress=False, **{**DAY, **kw})
    with rasterio.open(path) as ds:
        return (ds.read(), rep, ds.tags(), ds.descriptions,
                [ds.tags(i) for i in range(1, ds.count + 1)])


def _same(got, want):
    """Bits, tags, descriptions and band tags of two runs' outputs."""
    np.testing.assert_array_equal(got[0], want[0])
    assert got[2] == want[2] and got[3] == want[3] and got[4] == want[4]


@pytest.mark.parametrize("which,size,extra", [
    ("real", "24x40", {}),
    pytest.param("frac", "30x37", dict(perez=True, mean=True), marks=pytest.mark.slow),
])
def test_windows_give_the_bits_of_the_run_in_memory(tmp_path, dems, any_window, which, size,
                                                    extra):
    """Regions of --window-size (their sky view by the windowed march, each sample's beam from
    its pieces): the four bands of the run in memory, voids included; the report says how."""
    whole = _run(tmp_path / "whole.tif", dems[which], **extra)
    got = _run(tmp_path / "win.tif", dems[which], window_size=size, **extra)
    _same(got, whole)
    rep, wrep = whole[1], got[1]
    assert rep["processing"]["mode"] == "in memory"
    p = wrep["processing"]
    rows, cols = (int(v) for v in size.split("x"))
    shape = rep["shape"]
    assert p["mode"] == "windows"
    assert p["regions"] == -(-shape[0] // rows) * -(-shape[1] // cols) > 4
    assert p["windows"] >= p["regions"] * wrep["samples_with_shadows"] > 0
    assert p["window_shape_requested"] == [rows, cols]
    assert p["sky_view"]["regions"] == p["regions"]
    for k in ("shape", "samples", "samples_with_sun", "samples_with_shadows", "curvature",
              "period", "open_sky", "sky_view_from"):
        assert wrep[k] == rep[k], k
    for k in ("beam", "global"):
        assert wrep["bands"][k]["max"] == rep["bands"][k]["max"]
        assert wrep["bands"][k]["mean"] == pytest.approx(rep["bands"][k]["mean"], rel=1e-5)
    if which == "real":
        assert (whole[0][0] == -9999.0).sum() == 3 * 12


def _limit(monkeypatch, cells: int, per_cell: int) -> int:
    """A --max-memory leaving room for ``cells`` cells of ``per_cell`` bytes, the process as
    large as 200 MB whatever it holds."""
    from hillshade_rt.engine import windows
    monkeypatch.setattr(windows, "process_rss", lambda: 200_000_000)
    return 200_000_000 + (windows.GDAL_CACHE_MB << 20) + (32 << 20) + cells * per_cell


def test_max_memory_decides(tmp_path, dems, monkeypatch):
    """A --max-memory the fractal does not fit in (72 x 90 cells in memory) but its windows
    do: made in windows, the bits of the run in memory."""
    from hillshade_rt.engine.lighting import Lighting
    from hillshade_rt.run.irradiance_windows import memory_per_cell, window_bytes_per_cell
    whole = _run(tmp_path / "whole.tif", dems["frac"])
    per_cell = window_bytes_per_cell(Lighting(algorithm="auto"))
    assert 6600 * per_cell < 72 * 90 * memory_per_cell(Lighting(algorithm="auto"))
    limit = _limit(monkeypatch, 6600, per_cell)
    got = _run(tmp_path / "win.tif", dems["frac"], max_memory=str(limit))
    _same(got, whole)
    p = got[1]["processing"]
    assert p["mode"] == "windows" and p["memory"]["max_memory"] == limit
    assert p["window_shape_requested"] is None


def test_groups_of_suns_under_a_small_memory_limit(tmp_path, dems, monkeypatch, any_window):
    """Regions of 36 x 45 under a --max-memory of about 4,200 cells of window: the samples'
    windows do not fit together (the lowest suns' reach the raster's edge), so each region's
    samples are lit in several groups, each read once; the bits of the run in memory."""
    from hillshade_rt.engine.lighting import Lighting
    from hillshade_rt.run.irradiance_windows import window_bytes_per_cell
    whole = _run(tmp_path / "whole.tif", dems["frac"], perez=True)
    limit = _limit(monkeypatch, 4200, window_bytes_per_cell(Lighting(algorithm="auto")))
    got = _run(tmp_path / "win.tif", dems["frac"], perez=True, max_memory=str(limit),
               window_size="36x45")
    _same(got, whole)
    p = got[1]["processing"]
    assert p["mode"] == "windows" and p["regions"] == 4
    assert p["windows_read"] > 2 * p["regions"]


@pytest.mark.slow       # four runs
def test_the_sky_view_read_and_written_in_windows(tmp_path, dems, any_window):
    """--sky-view-out in windows writes the Vd the run in memory writes (the same bits; no
    digest of the heights, never read whole); --sky-view read window by window gives the
    bands of the run that computed it."""
    dem = dems["real"]
    whole = _run(tmp_path / "whole.tif", dem, perez=True, sky_view_out=tmp_path / "vd_m.tif")
    got = _run(tmp_path / "win.tif", dem, perez=True, window_size="32x45",
               sky_view_out=tmp_path / "vd_w.tif")
    _same(got, whole)
    with rasterio.open(tmp_path / "vd_m.tif") as a, rasterio.open(tmp_path / "vd_w.tif") as b:
        np.testing.assert_array_equal(b.read(), a.read())
        assert b.descriptions == a.descriptions and b.nodata == a.nodata
        ta, tb = a.tags(), b.tags()
        assert "HEIGHTS_DIGEST" in ta and "HEIGHTS_DIGEST" not in tb
        ta.pop("HEIGHTS_DIGEST")
        assert tb == ta
    for vd in ("vd_m.tif", "vd_w.tif"):
        read = _run(tmp_path / "read.tif", dem, perez=True, window_size="40x30",
                    sky_view=tmp_path / vd)
        _same(read, whole)
        assert read[1]["sky_view_from"] == "read"
        assert read[1]["processing"]["sky_view"] is None


def test_a_tile_in_its_context_in_windows(tmp_path, dems, any_window):
    """--context with --window-size: the tile made region by region from the context's
    windows equals the same cells of the whole DEM's run in memory."""
    dem = dems["frac"]
    whole = _run(tmp_path / "whole.tif", dem)
    with rasterio.open(dem) as ds:
        w = ((20, 60), (35, 80))
        tile = write_geotiff(tmp_path / "tile.tif", ds.read(1, window=w),
                             ds.window_transform(w), ds.crs)
    got = _run(tmp_path / "t.tif", tile, context=dem, window_size="16x20")
    np.testing.assert_array_equal(got[0], whole[0][:, 20:60, 35:80])
    p = got[1]["processing"]
    assert p["mode"] == "windows" and p["regions"] == 3 * 3
    assert p["context"]["window"] == [20, 60, 35, 80]


def test_the_command_line_in_windows(tmp_path, dems):
    """--window-size, --report, --preview on the command line: the summary names the windows,
    the report says how it ran, the bands are the run in memory's."""
    dem = dems["frac"]
    whole = _run(tmp_path / "whole.tif", dem)
    out, rep, png = tmp_path / "w.tif", tmp_path / "w.json", tmp_path / "w.png"
    r = CliRunner().invoke(cli, ["irradiance", dem, str(out), "--date", DAY["date"], "--step",
                                 DAY["step"], "--skyview-directions", "8", "--window-size",
                                 "64x70", "--report", str(rep), "--preview", str(png)])
    assert r.exit_code == 0, r.output
    assert r.stderr.strip().splitlines()[-1].endswith(", 4 windows")
    with rasterio.open(out) as ds:
        np.testing.assert_array_equal(ds.read(), whole[0])
    doc = json.loads(rep.read_text())
    assert doc["processing"]["mode"] == "windows" and doc["processing"]["regions"] == 4
    with rasterio.open(png) as p:
        assert (p.height, p.width) == (72, 90)


@pytest.mark.parametrize("extra,code,words", [
    (["--window-size", "10"], 2, "--window-size"),
    (["--max-memory", "lots"], 2, "--max-memory"),
    (["--max-memory", "10MB"], 1, "give at least --max-memory"),
    (["--context", "{dem}", "--scheduler", "local:1"], 2, "--context does not go with "
                                                          "--scheduler"),
])
def test_refusals_are_one_line(tmp_path, dems, extra, code, words):
    """A malformed --window-size or --max-memory, a limit too small for one window, --scheduler
    on a tile: one line, the exit status, no output."""
    dem = dems["frac"]
    out = tmp_path / "o.tif"
    r = CliRunner().invoke(cli, ["irradiance", dem, str(out), "--date", DAY["date"], "-q",
                                 *[e.format(dem=dem) for e in extra]])
    assert r.exit_code == code, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], lines
    assert not out.exists()


@pytest.mark.slow       # a local cluster of two worker processes
def test_dask_gives_the_bits_of_the_run_in_memory(tmp_path, dems, any_window):
    """Each region a task on two worker processes, --perez, --sky-view-out: the bands, the
    tags and descriptions of the run in memory, the Vd file too; the parts' folder gone."""
    pytest.importorskip("distributed")
    dem = dems["real"]
    whole = _run(tmp_path / "whole.tif", dem, perez=True, sky_view_out=tmp_path / "vd_m.tif")
    got = _run(tmp_path / "dask.tif", dem, perez=True, window_size="35x45", client="local:2",
               sky_view_out=tmp_path / "vd_d.tif")
    _same(got, whole)
    p = got[1]["processing"]
    assert p["mode"] == "dask" and p["workers"] == 2 and p["tasks"] == p["regions"] == 2 * 2
    assert p["sky_view"]["regions"] == 4
    with rasterio.open(tmp_path / "vd_m.tif") as a, rasterio.open(tmp_path / "vd_d.tif") as b:
        np.testing.assert_array_equal(b.read(), a.read())
        assert b.descriptions == a.descriptions
    assert sorted(os.listdir(tmp_path)) == ["dask.tif", "vd_d.tif", "vd_m.tif", "whole.tif"]


# ---------------------------------------------------------------------------------------------
# --monthly and the albedo by month or as rasters, in windows and on Dask

# two months, few samples: 2026-01-31 and 2026-02-01 every 3 hours
MONTHS = dict(date="2026-01-31", end_date="2026-02-01", step="3h", skyview_directions=8)
ALBEDO_12 = "0.13,0.31,0.22,0.2,0.2,0.2,0.2,0.2,0.2,0.2,0.2,0.17"


def _gradient(rows, cols, month=1):
    """An albedo that varies across a raster (rows and columns unevenly), by month: 0.1..0.6."""
    y, x = np.mgrid[0:rows, 0:cols]
    v = 0.1 + 0.35 * (x / cols) ** 1.3 + 0.1 * (y / rows) + 0.04 * np.sin(0.7 * x + 0.3 * y)
    return (v + 0.011 * month).astype(np.float32)


def _coarse_over(dem, ratio, margin=2.37, crs=None):
    """(transform, rows, cols) of a raster ``ratio`` times coarser than ``dem``'s cells (in
    ``crs``, default the DEM's), its origin off the DEM's grid, covering it with a margin."""
    from rasterio.warp import transform_bounds
    with rasterio.open(dem) as ds:
        b = ds.bounds if crs is None else transform_bounds(ds.crs, crs, *ds.bounds)
        dx = abs(ds.transform.a) * ratio
        dy = abs(ds.transform.e) * ratio
        if crs is not None:      # degrees over metres: about the DEM's cell times ratio
            dx, dy = (b[2] - b[0]) / ds.width * ratio, (b[3] - b[1]) / ds.height * ratio
    x0, y1 = b[0] - margin * dx, b[3] + 0.61 * margin * dy
    cols = int(np.ceil((b[2] - x0) / dx + margin))
    rows = int(np.ceil((y1 - b[1]) / dy + margin))
    return Affine(dx, 0, x0, 0, -dy, y1), rows, cols


@pytest.fixture(scope="module")
def albedos(tmp_path_factory, dems):
    """A gradient albedo raster 3.7 times coarser than the real DEM's cells (geographic, its
    origin off the DEM's grid); twelve monthly gradients over the fractal in geographic
    coordinates (the fractal is UTM: a reprojection), named albedo_MM.tif; a raster covering
    only the real DEM's western half."""
    d = tmp_path_factory.mktemp("albedo")
    tr, rows, cols = _coarse_over(dems["real"], 3.7)
    with rasterio.open(dems["real"]) as ds:
        crs = ds.crs
    one = write_geotiff(d / "albedo.tif", _gradient(rows, cols), tr, crs, -1.0)
    half = _gradient(rows, cols)
    half[:, cols // 2:] = -1.0
    west = write_geotiff(d / "west.tif", half, tr, crs, -1.0)
    tr, rows, cols = _coarse_over(dems["frac"], 2.9, crs=CRS.from_epsg(4326))
    for m in range(1, 13):
        write_geotiff(d / f"albedo_{m:02d}.tif", _gradient(rows, cols, m)[::-1], tr,
                      CRS.from_epsg(4326), -1.0)
    return {"raster": one, "pattern": str(d / "albedo_{month:02d}.tif"), "west": west}


def _albedo(kw, albedos):
    return {**kw, "albedo": albedos[kw["albedo"]]} if kw.get("albedo") in albedos else kw


@pytest.mark.parametrize("which,size,extra", [
    ("real", "24x40", dict(monthly=True)),
    ("frac", "30x37", dict(monthly=True, albedo=ALBEDO_12, perez=True, mean=True)),
    ("real", "24x40", dict(albedo="raster")),
    pytest.param("real", "35x45", dict(albedo="raster", monthly=True, daily_mean=True,
                                       perez=True), marks=pytest.mark.slow),
    ("frac", "30x37", dict(albedo="pattern", monthly=True)),
    pytest.param("frac", "40x45", dict(albedo="pattern"), marks=pytest.mark.slow),
])
def test_monthly_and_albedo_in_windows_give_the_bits_of_the_run_in_memory(
        tmp_path, dems, albedos, any_window, which, size, extra):
    """Two months every 3 hours: --monthly (a global band per month after the four), the
    albedo as twelve numbers, a gradient raster coarser than the DEM, a {month} pattern of
    rasters in another CRS: every band, its description and tags the run in memory's; the
    report's months; no albedo files left beside OUTPUT."""
    kw = {**MONTHS, **_albedo(extra, albedos)}
    whole = _run(tmp_path / "whole.tif", dems[which], **kw)
    got = _run(tmp_path / "win.tif", dems[which], window_size=size, **kw)
    _same(got, whole)
    assert got[1]["processing"]["mode"] == "windows" and got[1]["processing"]["regions"] >= 4
    assert sorted(os.listdir(tmp_path)) == ["whole.tif", "win.tif"]
    bands = np.where(whole[0] == -9999.0, np.nan, whole[0])
    if extra.get("monthly"):
        assert whole[3][4:] == ("2026-01", "2026-02") and bands.shape[0] == 6
        assert [m["month"] for m in got[1]["months"]] == ["2026-01", "2026-02"]
        for g, w in zip(got[1]["months"], whole[1]["months"]):
            assert g["hours"] == w["hours"] and g["global"]["max"] == w["global"]["max"]
            assert g["global"]["mean"] == pytest.approx(w["global"]["mean"], rel=1e-6)
        assert np.nanmax(np.abs(bands[4] - bands[5])) > 0
        if not (extra.get("mean") or extra.get("daily_mean")):
            np.testing.assert_allclose(bands[4] + bands[5], bands[3], rtol=1e-5)
    else:
        assert bands.shape[0] == 4 and "months" not in got[1]
    if extra.get("albedo") in ("raster", "pattern"):     # the reflected light varies with it
        refl = bands[2]
        assert np.nanstd(refl) > 0.05 * np.nanmean(refl) > 0


def test_an_albedo_raster_on_the_grid_is_the_run_in_memorys(tmp_path, dems, albedos):
    """The albedo grids of a run in windows (``SkyGrids``: the raster resampled once to
    the whole grid into a file) cut to any window are, to the bit, the same cells of
    ``SkyValue.on_grid`` on the whole grid (the run in memory's): a geographic DEM off the
    raster's grid, and a UTM grid from rasters in geographic coordinates."""
    from hillshade_rt.run import ReadOptions
    from hillshade_rt.run.irradiance_windows import SkyGrids
    from hillshade_rt.run.sky_inputs import SkyValue
    for which, name in (("real", "raster"), ("frac", "pattern")):
        value = SkyValue.parse("--albedo", albedos[name], 0.0, 1.0)
        src = ReadOptions().open(dems[which], windows=True)
        with src:
            grids = SkyGrids(str(tmp_path / "out.tif"))
            try:
                for month in (1, 2, 7):
                    g = grids.grid(value, month, src, src, (0, 0))
                    want = value.on_grid(month, src.transform, src.crs, src.shape, None)
                    for w in ((0, 7, 0, 90), (13, 51, 29, 83), (69, src.shape[0], 0, 1)):
                        np.testing.assert_array_equal(g.cut(w), want[w[0]:w[1], w[2]:w[3]])
                    assert np.isfinite(want).all() and want.std() > 0.02
            finally:
                grids.close()
            assert not os.path.exists(grids.folder)


def test_an_albedo_raster_short_of_the_dem_is_the_same_line_in_windows(tmp_path, dems,
                                                                        albedos):
    """An albedo raster that misses part of the DEM: the one line of the run in memory
    (exit status 2, the same count of cells), in windows too; no output, no albedo files."""
    lines = []
    for extra in ([], ["--window-size", "64"]):
        out = tmp_path / "o.tif"
        r = CliRunner().invoke(cli, ["irradiance", dems["real"], str(out), "--date",
                                     MONTHS["date"], "--step", "3h", "--albedo",
                                     albedos["west"], "-q", *extra])
        assert r.exit_code == 2, r.output
        lines.append(r.stderr.strip().splitlines())
        assert not out.exists() and os.listdir(tmp_path) == []
    assert len(lines[0]) == 1 and lines[1] == lines[0]
    assert "does not cover the DEM" in lines[0][0] and "west.tif" in lines[0][0]


@pytest.mark.slow       # three runs
def test_monthly_and_a_pattern_in_a_context_tile_in_windows(tmp_path, dems, albedos,
                                                            any_window):
    """--context with --window-size, --monthly and an albedo pattern: the tile's six bands the
    bits of the tile's run in memory (its albedo resampled to the tile's grid, as there);
    the beam and diffuse bands the same cells of the whole DEM's run."""
    dem = dems["frac"]
    kw = dict(MONTHS, monthly=True, albedo=albedos["pattern"])
    whole = _run(tmp_path / "whole.tif", dem, **kw)
    with rasterio.open(dem) as ds:
        w = ((20, 60), (35, 80))
        tile = write_geotiff(tmp_path / "tile.tif", ds.read(1, window=w),
                             ds.window_transform(w), ds.crs)
    got = _run(tmp_path / "t.tif", tile, context=dem, window_size="16x20", **kw)
    mem = _run(tmp_path / "tm.tif", tile, context=dem, **kw)
    _same(got, mem)
    assert got[1]["processing"]["regions"] == 3 * 3 and mem[1]["processing"]["mode"] == \
        "windows" and "regions" not in mem[1]["processing"]
    np.testing.assert_array_equal(got[0][:2], whole[0][:2, 20:60, 35:80])
    assert got[3] == whole[3] and got[4] == whole[4]


@pytest.mark.slow       # a local cluster of two worker processes
def test_monthly_and_albedo_rasters_on_dask_give_the_bits_of_the_run_in_memory(
        tmp_path, dems, albedos, any_window):
    """--monthly with a {month} pattern of albedo rasters, each region a task on two worker
    processes: the six bands, their descriptions and tags the run in memory's; nothing left
    beside OUTPUT."""
    pytest.importorskip("distributed")
    kw = dict(MONTHS, monthly=True, albedo=albedos["pattern"], perez=True)
    whole = _run(tmp_path / "whole.tif", dems["frac"], **kw)
    got = _run(tmp_path / "dask.tif", dems["frac"], window_size="36x45", client="local:2",
               **kw)
    _same(got, whole)
    p = got[1]["processing"]
    assert p["mode"] == "dask" and p["tasks"] == p["regions"] == 2 * 2
    assert [m["month"] for m in got[1]["months"]] == ["2026-01", "2026-02"]
    assert sorted(os.listdir(tmp_path)) == ["dask.tif", "whole.tif"]


def test_no_room_for_the_albedo_grid_is_one_line(tmp_path, dems, albedos, monkeypatch):
    """A disk too full for the albedo raster on the DEM's grid (``posix_fallocate`` says
    ENOSPC): one line, exit status 1, no output and no albedo files left."""
    import errno

    from hillshade_rt.run import irradiance_windows as iw

    def full(fd, offset, length):
        raise OSError(errno.ENOSPC, "No space left on device")
    monkeypatch.setattr(iw.os, "posix_fallocate", full, raising=False)
    out = tmp_path / "o.tif"
    r = CliRunner().invoke(cli, ["irradiance", dems["real"], str(out), "--date",
                                 MONTHS["date"], "--step", "3h", "--albedo",
                                 albedos["raster"], "--window-size", "64", "-q"])
    assert r.exit_code == 1, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "no room for the --albedo raster" in lines[0], lines
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------------------------------------
# Linke turbidity and clear-sky index rasters (the open sky per cell) in windows and on Dask

def _wave(rows, cols, low, high, month=1):
    """Values from about ``low`` to ``high`` varying unevenly across a raster, by month."""
    y, x = np.mgrid[0:rows, 0:cols]
    v = (x / cols) ** 1.2 * 0.6 + 0.25 * (y / rows) + 0.1 * np.sin(0.9 * x + 0.4 * y + month)
    return (low + (high - low) * (v + 0.1) / 1.05).astype(np.float32)


@pytest.fixture(scope="module")
def skies(tmp_path_factory, dems):
    """Over the real DEM (its CRS, 3.1 times coarser, off its grid): a Linke turbidity raster
    (about 2..6) and a diffuse index raster (0.5..0.95); over the fractal, in geographic
    coordinates: twelve monthly Linke rasters ``linke_MM.tif`` (January's one value, 3.4,
    on the fractal's grid: the number's path; February's varying) and a beam index raster
    (0.4..0.9)."""
    d = tmp_path_factory.mktemp("skies")
    tr, rows, cols = _coarse_over(dems["real"], 3.1)
    with rasterio.open(dems["real"]) as ds:
        crs = ds.crs
    linke = write_geotiff(d / "linke.tif", _wave(rows, cols, 2.0, 6.0), tr, crs, -1.0)
    kd = write_geotiff(d / "kd.tif", _wave(rows, cols, 0.5, 0.95, 5)[::-1], tr, crs, -1.0)
    geo = CRS.from_epsg(4326)
    tr, rows, cols = _coarse_over(dems["frac"], 2.6, crs=geo)
    with rasterio.open(dems["frac"]) as ds:      # January's on the fractal's own grid
        write_geotiff(d / "linke_01.tif", np.full(ds.shape, 3.4, np.float32), ds.transform,
                      ds.crs, -1.0)
    for m in range(2, 13):
        write_geotiff(d / f"linke_{m:02d}.tif", _wave(rows, cols, 2.5, 5.5, m)[:, ::-1], tr,
                      geo, -1.0)
    kb = write_geotiff(d / "kb.tif", _wave(rows, cols, 0.4, 0.9, 3), tr, geo, -1.0)
    return {"linke": linke, "kd": kd, "pattern": str(d / "linke_{month:02d}.tif"), "kb": kb}


def _sky(kw, skies, albedos):
    out = dict(kw)
    for k in ("linke_turbidity", "beam_index", "diffuse_index"):
        if out.get(k) in skies:
            out[k] = skies[out[k]]
    return _albedo(out, albedos)


@pytest.mark.parametrize("which,size,extra", [
    pytest.param("real", "24x40", dict(linke_turbidity="linke"), marks=pytest.mark.slow),
    ("frac", "30x37", dict(linke_turbidity="pattern", beam_index="kb", monthly=True,
                           perez=True)),
    pytest.param("real", "35x45", dict(diffuse_index="kd", beam_index="0.8", albedo="raster",
                                       mean=True), marks=pytest.mark.slow),
    pytest.param("frac", "40x45", dict(beam_index="kb", soft=True, albedo="pattern"),
                 marks=pytest.mark.slow),
    pytest.param("real", "24x40", dict(linke_turbidity="linke", diffuse_index="kd",
                                       monthly=True, perez=True), marks=pytest.mark.slow),
])
def test_linke_and_index_rasters_in_windows_give_the_bits_of_the_run_in_memory(
        tmp_path, dems, skies, albedos, any_window, which, size, extra):
    """The open sky per cell in windows: a Linke turbidity raster coarser than the DEM, a
    {month} pattern of Linke rasters in another CRS (one month's of one value, the number's
    path) with a beam index raster, a diffuse index raster with an albedo raster: every band,
    its description and tags the run in memory's, the report's turbidity too; the sky per
    cell shows (the bands vary as the rasters do); no grids left beside OUTPUT."""
    kw = {**MONTHS, **_sky(extra, skies, albedos)}
    whole = _run(tmp_path / "whole.tif", dems[which], **kw)
    got = _run(tmp_path / "win.tif", dems[which], window_size=size, **kw)
    _same(got, whole)
    assert got[1]["processing"]["mode"] == "windows" and got[1]["processing"]["regions"] >= 4
    assert sorted(os.listdir(tmp_path)) == ["whole.tif", "win.tif"]
    assert got[1]["turbidity"] == whole[1]["turbidity"]
    for k in ("beam_index", "diffuse_index"):
        assert got[1][k] == whole[1][k]
    # against the numbers' run: a per-cell sky moves the bands away from the open sky's
    plain = {k: v for k, v in kw.items()
             if k not in ("linke_turbidity", "beam_index", "diffuse_index")}
    ref = _run(tmp_path / "plain.tif", dems[which], window_size=size, **plain)
    b, r = (np.where(a == -9999.0, np.nan, a) for a in (got[0], ref[0]))
    ratio = b[3] / r[3]
    assert np.nanstd(ratio) > 0.01 and np.isfinite(b[3]).sum() == np.isfinite(r[3]).sum()
    if extra.get("linke_turbidity"):
        assert "each cell its own" in got[1]["turbidity"]


def test_sky_grids_resolve_as_the_run_in_memory(tmp_path, dems, skies):
    """``SkyGrids.resolved`` (the figures of a raster from its grid, row band by row band) is
    ``SkyValue.resolved`` on the whole grid: the mean over the DEM's valid cells to the bit,
    min and max, a raster of one value that value (January's Linke); a region's cells of the
    ``GridSky`` the same cells of the whole grid's raster, its voids the mean."""
    from hillshade_rt.run import ReadOptions
    from hillshade_rt.run.irradiance_windows import GridSky, SkyGrids
    from hillshade_rt.engine.irradiance import SampleSky
    from hillshade_rt.run.sky_inputs import CellInputs, SkyValue
    cases = (("real", "--linke-turbidity", skies["linke"], 1.0, 10.0, (1,)),
             ("real", "--diffuse-index", skies["kd"], 0.0, 1.0, (1,)),
             ("frac", "--linke-turbidity", skies["pattern"], 1.0, 10.0, (1, 2, 9)))
    for which, option, value, low, high, months in cases:
        v = SkyValue.parse(option, value, low, high)
        src = ReadOptions().open(dems[which], windows=True)
        with src, rasterio.open(dems[which]) as ds:
            z = ds.read(1, masked=True)
            valid = ~np.ma.getmaskarray(z)
            grids = SkyGrids(str(tmp_path / "out.tif"))
            try:
                for m in months:
                    g, fig, fill = grids.resolved(v, m, src, src, (0, 0))
                    want = v.resolved(m, src.transform, src.crs, src.shape, valid)
                    if m == 1 and which == "frac":          # January: 3.4 everywhere
                        t = float(np.float32(3.4))            # (a float32 raster)
                        assert fig == (t, False, t, t) and want == t
                        continue
                    inside = want[valid]
                    assert fig == (float(np.mean(inside)), True, float(inside.min()),
                                   float(inside.max()))
                    assert fill == float(np.mean(inside))
                    ci = CellInputs(np.array([m]), (v.by_month, False, False),
                                    frozenset({(0, m if v.by_month else 1)}), (None, None, None),
                                    SampleSky(*(np.ones(1),) * 6, (1.0,) * 5, np.ones(1),
                                              np.ones(1)))
                    key = m if v.by_month else 1
                    sky = GridSky(ci, {(0, key): (g, fill)})
                    for w in ((0, 7, 0, 90), (25, 40, 29, 83), (69, src.shape[0], 0, 1)):
                        void = ~valid[w[0]:w[1], w[2]:w[3]]
                        tl = sky.cells(w, void).at(0)[0]
                        np.testing.assert_array_equal(tl, want[w[0]:w[1], w[2]:w[3]])
                    assert (~valid).any() or which == "frac"
            finally:
                grids.close()
            assert not os.path.exists(grids.folder)


@pytest.mark.slow       # a run
def test_the_grids_folder_of_a_killed_run_is_removed_by_the_next(tmp_path, dems, skies,
                                                                  monkeypatch):
    """The grids' folder beside OUTPUT is named after the run (``io.write.scratch_folder``):
    one left by a dead process (SIGKILL: no clean-up of its own) is removed by the next run
    writing into that folder; one of a live process, and one of another host, are kept."""
    import subprocess
    import sys

    from hillshade_rt.io import write as writes
    out = tmp_path / "out"
    out.mkdir()
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait(30)
    tag = writes.owner_tag()
    rest = tag.split("-", 1)[1]
    dead = out / f".o.tif.grids.abcd1234~{child.pid}-{rest}.scratch.dir"
    live = out / f".o.tif.grids.efgh5678~{tag}.scratch.dir"
    other = out / f".o.tif.grids.ijkl9012~{child.pid}-{rest.split('@')[0]}@elsewhere.scratch.dir"
    for d in (dead, live, other):
        d.mkdir()
        (d / "grid_0.npy").write_bytes(b"x" * 64)
    assert writes.writer_dead(dead.name) and not writes.writer_dead(live.name)
    folders = []
    real = writes.scratch_folder
    writes.reset()

    def seen(path, kind):
        folders.append(real(path, kind))
        return folders[-1]
    monkeypatch.setattr(writes, "scratch_folder", seen)
    r = CliRunner().invoke(cli, ["irradiance", dems["real"], str(out / "o.tif"), "--date",
                                 MONTHS["date"], "--step", "3h", "--linke-turbidity",
                                 skies["linke"], "--window-size", "64", "-q"])
    assert r.exit_code == 0, r.output
    left = sorted(os.listdir(out))
    assert left == sorted(["o.tif", live.name, other.name]), left
    name = os.path.basename(folders[0])         # the run's own, removed at its end
    assert name.startswith(".o.tif.grids.") and name.endswith(f"~{tag}.scratch.dir")
    assert writes.writer_dead(name) is False


@pytest.mark.slow       # a local cluster of two worker processes
def test_linke_and_index_rasters_on_dask_give_the_bits_of_the_run_in_memory(
        tmp_path, dems, skies, any_window):
    """A {month} pattern of Linke rasters (January's of one value, February's varying) and a
    beam index raster, --monthly and Perez, each region a task on two worker processes: the
    six bands, their descriptions and tags the run in memory's; nothing left beside OUTPUT."""
    pytest.importorskip("distributed")
    kw = dict(MONTHS, monthly=True, perez=True, linke_turbidity=skies["pattern"],
              beam_index=skies["kb"])
    whole = _run(tmp_path / "whole.tif", dems["frac"], **kw)
    got = _run(tmp_path / "dask.tif", dems["frac"], window_size="36x45", client="local:2",
               **kw)
    _same(got, whole)
    p = got[1]["processing"]
    assert p["mode"] == "dask" and p["tasks"] == p["regions"] == 2 * 2
    assert "each cell its own" in got[1]["turbidity"]
    assert sorted(os.listdir(tmp_path)) == ["dask.tif", "whole.tif"]


@pytest.mark.slow       # two runs
def test_linke_and_index_rasters_in_a_context_tile_in_windows(tmp_path, dems, skies,
                                                              any_window):
    """--context with --window-size and a {month} pattern of Linke rasters and a beam index
    raster: the tile's bands the bits of the tile's run in memory (the rasters resampled to
    the tile's grid, their figures over the tile's cells, as there)."""
    dem = dems["frac"]
    kw = dict(MONTHS, linke_turbidity=skies["pattern"], beam_index=skies["kb"])
    with rasterio.open(dem) as ds:
        w = ((20, 60), (35, 80))
        tile = write_geotiff(tmp_path / "tile.tif", ds.read(1, window=w),
                             ds.window_transform(w), ds.crs)
    got = _run(tmp_path / "t.tif", tile, context=dem, window_size="16x20", **kw)
    mem = _run(tmp_path / "tm.tif", tile, context=dem, **kw)
    _same(got, mem)
    assert got[1]["processing"]["regions"] == 3 * 3 and got[1]["turbidity"] == \
        mem[1]["turbidity"] and "each cell its own" in mem[1]["turbidity"]
    assert sorted(os.listdir(tmp_path)) == ["t.tif", "tile.tif", "tm.tif"]
