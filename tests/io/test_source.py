"""``io.open_dem``: one source for every DEM, checked once, read whole or in windows alike; the
file opened once; the I/O layer importing only the layers below it."""

import ast
import os
import pickle
import re
import subprocess
import sys

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.io import DemOptions, open_dem, read_dem
from hillshade_rt.testing import fractal_terrain, write_geotiff

UTM = CRS.from_epsg(32611)
TR = Affine(10, 0, 500000, 0, -10, 4100000)
SUN = ["--azimuth", "203.7", "--elevation", "9"]


@pytest.fixture
def opens(monkeypatch):
    """The datasets rasterio opens for reading, by name, while the test runs."""
    seen = []
    real = rasterio.open

    def counting(fp, mode="r", *a, **k):
        if mode == "r":
            seen.append(os.path.basename(str(fp)))
        return real(fp, mode, *a, **k)
    monkeypatch.setattr(rasterio, "open", counting)
    return seen


def _windows(src, shape=(64, 80)):
    """The source read window by window into one array."""
    out = np.full(src.shape, -1.0, np.float32)
    with src.reader() as rd:
        for r0 in range(0, src.shape[0], shape[0]):
            for c0 in range(0, src.shape[1], shape[1]):
                r1, c1 = min(src.shape[0], r0 + shape[0]), min(src.shape[1], c0 + shape[1])
                rd.read((r0, r1, c0, c1), out[r0:r1, c0:c1])
    return out


def test_a_dem_is_opened_once_read_whole_or_in_windows(tmp_path, opens):
    """The dataset opened to check the DEM serves the whole read, the centre height and every
    windowed reader of its thread: one rasterio.open."""
    z = fractal_terrain(150, 170, seed=3, relief=300.0)
    p = write_geotiff(tmp_path / "d.tif", z, TR, UTM, -9999.0)
    read_dem(p)
    assert opens == ["d.tif"]
    opens.clear()
    with open_dem(p) as src:
        whole = src.read()
        src.centre_height()
        np.testing.assert_array_equal(_windows(src), whole.heights)
        with src.reader() as a, src.reader() as b:   # two at once: the second opens its own
            assert a._ds is not b._ds
    assert opens == ["d.tif", "d.tif"]


def test_a_windowed_run_opens_the_dem_once(tmp_path, runner, opens):
    """A run in windows (statistics pass, the sun's observer height, the windows) opens its DEM
    once; in memory the command line still opens it twice (once to size it, once to read it:
    the run layer is to call open_dem once and read that source)."""
    z = fractal_terrain(200, 220, seed=4, relief=300.0)
    p = write_geotiff(tmp_path / "d.tif", z, TR, UTM, -9999.0)
    r = runner.invoke(cli, ["shadow", p, str(tmp_path / "o.tif"), "--time",
                            "2026-06-21T15:00-07:00", "--window-size", "64", "-q"])
    assert r.exit_code == 0, r.output
    assert opens.count("d.tif") == 1


def test_whole_and_windows_read_the_same_heights_of_every_kind(tmp_path):
    """GDAL, a plain TIFF (tifffile whole, GDAL in windows), a raw grid (memory-mapped in
    windows), a .hgt tile GDAL cannot georeference (raw: now in windows too), a mosaic."""
    import tifffile

    z = fractal_terrain(130, 150, seed=5, relief=200.0)
    z[10:14, 20:30] = -9999.0
    gdal = write_geotiff(tmp_path / "g.tif", z, TR, UTM, -9999.0)
    plain = str(tmp_path / "plain.tif")
    tifffile.imwrite(plain, z.astype(np.float32))
    raw = tmp_path / "r.f32"
    z.astype("<f4").tofile(raw)
    hgt = tmp_path / "tile.hgt"                  # not an SRTM name: GDAL refuses it
    square = np.round(fractal_terrain(121, 121, seed=6, relief=900.0)).astype(">i2")
    square[3, 3] = -32768
    square.tofile(hgt)
    top = write_geotiff(tmp_path / "top.tif", z[:60], TR, UTM, -9999.0)
    bottom = write_geotiff(tmp_path / "bottom.tif", z[60:], TR @ Affine.translation(0, 60), UTM,
                           -9999.0)
    cases = [(gdal, DemOptions(z_factor=0.5), "gdal"),
             (plain, DemOptions(nodata=-9999.0, pixel_size=(2.0, 2.0)), "tiff"),
             (str(raw), DemOptions(nodata=-9999.0, pixel_size=(1.0, 1.0), raw_shape=z.shape,
                                   raw_dtype="float32"), "raw"),
             (str(hgt), DemOptions(pixel_size=(30.0, 30.0)), "raw"),
             ([top, bottom], DemOptions(), "mosaic")]
    for path, opts, kind in cases:
        with open_dem(path, opts) as src:
            whole = src.read()
            assert whole.kind == kind, path
            assert src.grid is whole.grid        # gridded once
            np.testing.assert_array_equal(_windows(src), whole.heights)
        if kind != "mosaic":
            assert np.isnan(whole.heights).sum() == (40 if path != str(hgt) else 1), path
    with open_dem([top, bottom]) as src:
        np.testing.assert_array_equal(src.read().heights, read_dem(gdal).heights)


def test_whole_and_windowed_openings_refuse_alike(tmp_path):
    """The checks are one: a raw grid of the wrong size, a missing band, values that are no
    heights give the same message whether the DEM is to be read whole or in windows."""
    raw = tmp_path / "r.f32"
    np.zeros((10, 10), "<f4").tofile(raw)
    z = fractal_terrain(20, 20, seed=7)
    p = write_geotiff(tmp_path / "d.tif", z, TR, UTM)
    c = str(tmp_path / "c.tif")
    with rasterio.open(c, "w", driver="GTiff", width=4, height=4, count=1, dtype="complex64",
                       crs=UTM, transform=TR) as ds:
        ds.write(np.zeros((1, 4, 4), np.complex64))
    for path, opts, said in [
            (str(raw), DemOptions(raw_shape=(10, 11), raw_dtype="float32"), "--raw-shape 10x11"),
            (str(raw), DemOptions(raw_shape=(10, 10)), "needs --raw-dtype"),
            (p, DemOptions(band=2), "has 1 band(s), --band 2 asked"),
            (c, DemOptions(), "pixel type complex64 is not a height")]:
        got = []
        for windows in (False, True):
            with pytest.raises(HillshadeError, match=re.escape(said)) as e:
                open_dem(path, opts, windows=windows)
            got.append(str(e.value))
        assert got[0] == got[1]


def test_standard_input_is_read_whole_only(tmp_path, monkeypatch):
    z = fractal_terrain(40, 40, seed=8, relief=100.0)
    p = write_geotiff(tmp_path / "d.tif", z, TR, UTM)
    with pytest.raises(UsageProblem, match="read whole"):
        open_dem("-", windows=True)          # refused before standard input is read

    class Stdin:
        buffer = open(p, "rb")

        def isatty(self):
            return False
    monkeypatch.setattr(sys, "stdin", Stdin())
    with open_dem("-") as src:
        np.testing.assert_array_equal(src.read().heights, read_dem(p).heights)
        with pytest.raises(UsageProblem, match="read whole"), src.reader():
            pass


def test_a_source_pickles_without_its_dataset(tmp_path):
    """Dask sends the source to its workers: the copy opens the dataset again there."""
    z = fractal_terrain(70, 90, seed=9, relief=100.0)
    p = write_geotiff(tmp_path / "d.tif", z, TR, UTM)
    with open_dem(p) as src:
        copy = pickle.loads(pickle.dumps(src))
        assert src._held is not None and copy._held is None
        np.testing.assert_array_equal(_windows(copy), src.read().heights)
        copy.close()


_ALLOWED = {"errors", "model", "_preload", "_lazy", "algorithms", "io"}


def test_the_io_layer_imports_only_the_layers_below_it():
    """hillshade_rt.io may import errors, model, _preload and algorithms (deferred imports
    included), never engine, pictures, run, cli, api or xarray."""
    import hillshade_rt.io as pkg
    folder = os.path.dirname(pkg.__file__)
    bad = []
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".py"):
            continue
        tree = ast.parse(open(os.path.join(folder, name), encoding="utf-8").read())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level:
                mod = node.module or ""
                # level 1: inside io/; level 2: hillshade_rt's own modules
                top = "io" if node.level == 1 else (mod.split(".")[0] or "<package>")
                if top not in _ALLOWED:
                    bad.append(f"{name}: from {'.' * node.level}{mod} import ...")
            elif isinstance(node, ast.Import):
                bad += [f"{name}: import {a.name}" for a in node.names
                        if a.name.startswith("hillshade_rt")]
    assert not bad, bad


def test_the_write_module_loads_without_numpy_or_gdal():
    """The command line takes over the signals (io.write) before numpy, numba or GDAL load."""
    code = ("import sys; from hillshade_rt.io import write; "
            "print(sorted(m for m in ('numpy', 'rasterio', 'numba') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
