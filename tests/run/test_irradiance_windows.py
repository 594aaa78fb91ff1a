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
