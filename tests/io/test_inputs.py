"""Inputs (issue 16): any dataset name GDAL opens (/vsizip/, zip://…!…, /vsigzip/, /vsimem/),
a DEM from standard input, corrupt files named in a one-line error, geotransforms that cannot
be shaded, and +-inf heights as nodata."""

import gzip
import json
import os
import subprocess
import sys
import uuid
import zipfile

import numpy as np
import pytest
import rasterio
import rasterio.shutil
from affine import Affine
from rasterio.crs import CRS

import hillshade_rt as hr
from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import read_dem
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff

UTM = CRS.from_epsg(32632)
TR = Affine(10, 0, 500000, 0, -10, 5200000)
SUN = ["--azimuth", "135", "--elevation", "15"]


def _tiled_geotiff(path, z, transform=TR, crs=UTM, block=64):
    """A tiled, deflate-compressed GeoTIFF (as DEMs are shipped)."""
    prof = dict(driver="GTiff", width=z.shape[1], height=z.shape[0], count=1, dtype="float32",
                crs=crs, transform=transform, tiled=True, blockxsize=block, blockysize=block,
                compress="deflate", nodata=-9999.0)
    with rasterio.open(path, "w", **prof) as dst:
        dst.write(z.astype(np.float32), 1)
    return str(path)


@pytest.fixture
def dem(tmp_path):
    """A 300 x 300 DEM on disk and zipped (member sub/dem.tif) and gzipped."""
    z = fractal_terrain(300, 300, 16, relief=400.0)
    path = _tiled_geotiff(tmp_path / "dem.tif", z)
    with zipfile.ZipFile(tmp_path / "dems.zip", "w") as zf:
        zf.write(path, "sub/dem.tif")
    with open(path, "rb") as src, gzip.open(tmp_path / "dem.tif.gz", "wb") as dst:
        dst.write(src.read())
    return path


@pytest.fixture
def expected(dem, tmp_path, runner):
    """The mask of the plain file."""
    out = tmp_path / "expected.tif"
    r = runner.invoke(cli, ["shadow", dem, str(out), *SUN, "-q"])
    assert r.exit_code == 0, r.output
    return read_band(out)


def _one_line_error(r, code=1):
    assert r.exit_code == code, r.output
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hillshade-rt: error: "), r.stderr
    assert "Traceback" not in r.output
    return lines[0]


def _cut(path, fraction=0.6):
    data = open(path, "rb").read()
    with open(path, "wb") as fh:
        fh.write(data[:int(len(data) * fraction)])


# ---------------------------------------------------------------------------------------------
# GDAL dataset names

@pytest.mark.parametrize("form", ["vsizip", "vsizip-relative", "zip-url", "zip-url-relative",
                                  "vsigzip"])
def test_archives_are_opened_by_gdal_not_refused_locally(form, dem, expected, tmp_path,
                                                         runner, monkeypatch):
    monkeypatch.chdir(tmp_path)
    name = {"vsizip": f"/vsizip/{tmp_path}/dems.zip/sub/dem.tif",
            "vsizip-relative": "/vsizip/dems.zip/sub/dem.tif",
            "zip-url": f"zip://{tmp_path}/dems.zip!sub/dem.tif",
            "zip-url-relative": "zip://dems.zip!sub/dem.tif",   # rasterio itself loses this one
            "vsigzip": f"/vsigzip/{tmp_path}/dem.tif.gz"}[form]
    out = tmp_path / "o.tif"
    r = runner.invoke(cli, ["shadow", name, str(out), *SUN])
    assert r.exit_code == 0, r.output
    np.testing.assert_array_equal(read_band(out), expected)


def test_zip_url_in_windows_and_as_mosaic_tiles(dem, expected, tmp_path, runner):
    """--window-size on a /vsizip DEM, and a mosaic of two zipped tiles: the same mask."""
    out = tmp_path / "w.tif"
    r = runner.invoke(cli, ["shadow", f"/vsizip/{tmp_path}/dems.zip/sub/dem.tif", str(out), *SUN,
                            "--window-size", "128"])
    assert r.exit_code == 0, r.output
    np.testing.assert_array_equal(read_band(out), expected)

    z = read_band(dem)
    with zipfile.ZipFile(tmp_path / "tiles.zip", "w") as zf:
        for i, (c0, c1) in enumerate([(0, 170), (170, 300)]):
            p = _tiled_geotiff(tmp_path / f"t{i}.tif", z[:, c0:c1], TR @ Affine.translation(c0, 0))
            zf.write(p, f"t{i}.tif")
            os.remove(p)
    tiles = [f"/vsizip/{tmp_path}/tiles.zip/t0.tif", f"zip://{tmp_path}/tiles.zip!t1.tif"]
    for extra in ([], ["--window-size", "128"]):
        out = tmp_path / f"m{len(extra)}.tif"
        r = runner.invoke(cli, ["shadow", *tiles, str(out), *SUN, *extra])
        assert r.exit_code == 0, r.output
        np.testing.assert_array_equal(read_band(out), expected)


def test_shade_api_reads_zip_and_vsimem(dem, expected, tmp_path):
    out = tmp_path / "api.tif"
    hr.shade(f"zip://{tmp_path}/dems.zip!sub/dem.tif", str(out), azimuth=135, elevation=15)
    np.testing.assert_array_equal(read_band(out), expected)

    # a DEM GDAL holds in memory: written to /vsimem/ by rasterio, and a rasterio.MemoryFile
    mem = f"/vsimem/{uuid.uuid4().hex}/dem.tif"
    try:
        with rasterio.open(dem) as src, rasterio.open(mem, "w", **src.profile) as dst:
            dst.write(src.read())
        out = tmp_path / "mem.tif"
        hr.shade(mem, str(out), azimuth=135, elevation=15, window_size=128)
        np.testing.assert_array_equal(read_band(out), expected)
    finally:
        rasterio.shutil.delete(mem)
    with open(dem, "rb") as fh, rasterio.MemoryFile(fh.read(), ext=".tif") as mf:
        d = read_dem(mf.name)
        np.testing.assert_array_equal(d.heights, read_dem(dem).heights)
        assert d.path == mf.name


def test_vsimem_through_the_cli(dem, expected, tmp_path, runner):
    with open(dem, "rb") as fh, rasterio.MemoryFile(fh.read(), ext=".tif") as mf:
        out = tmp_path / "o.tif"
        r = runner.invoke(cli, ["shadow", mf.name, str(out), *SUN])
        assert r.exit_code == 0, r.output
    np.testing.assert_array_equal(read_band(out), expected)


@pytest.mark.parametrize("name", ["/vsizip/{d}/dems.zip/sub/nope.tif", "zip://{d}/dems.zip!nope.tif",
                                  "/vsizip/{d}/missing.zip/dem.tif", "/vsimem/nothing/here.tif"])
def test_missing_member_or_archive_is_no_such_file(name, dem, tmp_path, runner):
    name = name.format(d=tmp_path)
    before = set(os.listdir(tmp_path))
    out = tmp_path / "o.tif"
    for extra in ([], ["--window-size", "128"]):
        r = runner.invoke(cli, ["shadow", name, str(out), *SUN, *extra])
        assert _one_line_error(r) == f"hillshade-rt: error: {name}: no such file"
    with pytest.raises(HillshadeError, match="no such file"):
        hr.shade(name, str(out), azimuth=135, elevation=15)
    assert set(os.listdir(tmp_path)) == before


def test_local_paths_keep_their_own_checks(tmp_path, runner):
    r = runner.invoke(cli, ["shadow", str(tmp_path / "absent.tif"), str(tmp_path / "o.tif"), *SUN])
    assert "absent.tif: no such file" in _one_line_error(r)
    (tmp_path / "folder.tif").mkdir()
    with pytest.raises(HillshadeError, match="is a folder"):
        read_dem(str(tmp_path / "folder.tif"))


# ---------------------------------------------------------------------------------------------
# standard input

def test_dem_from_stdin(dem, expected, tmp_path, runner):
    out = tmp_path / "o.tif"
    with open(dem, "rb") as fh:
        data = fh.read()
    r = runner.invoke(cli, ["shadow", "-", str(out), *SUN], input=data)
    assert r.exit_code == 0, r.output
    np.testing.assert_array_equal(read_band(out), expected)
    # a raw grid piped in: as the same bytes in a file
    raw = tmp_path / "dem.f32"
    raw.write_bytes(read_band(dem).astype("<f4").tobytes())
    opts = ["--raw-shape", "300x300", "--raw-dtype", "float32", "--pixel-size", "10"]
    masks = []
    for name, data in (("-", raw.read_bytes()), (str(raw), None)):
        o = tmp_path / f"raw{len(masks)}.tif"
        r = runner.invoke(cli, ["shadow", name, str(o), *SUN, *opts], input=data)
        assert r.exit_code == 0, r.output
        masks.append(read_band(o))
    np.testing.assert_array_equal(masks[0], masks[1])
    assert 0 < masks[0].mean() < 1


def test_dem_piped_into_a_real_process(dem, expected, tmp_path):
    out = tmp_path / "o.tif"
    with open(dem, "rb") as fh:
        p = subprocess.run([sys.executable, "-m", "hillshade_rt", "shadow", "-", str(out), *SUN,
                            "--threads", "1"], stdin=fh, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    np.testing.assert_array_equal(read_band(out), expected)
    with open(dem, "rb") as fh:
        p = subprocess.run([sys.executable, "-m", "hillshade_rt", "info", "-", "--json"],
                           stdin=fh, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert json.loads(p.stdout)["shape"] == [300, 300]


def test_stdin_errors(dem, tmp_path, runner):
    out = tmp_path / "o.tif"
    with open(dem, "rb") as fh:
        data = fh.read()
    before = set(os.listdir(tmp_path))
    for extra in (["--window-size", "128"], [dem]):     # windows, a mosaic: a usage error
        r = runner.invoke(cli, ["shadow", "-", *extra, str(out), *SUN], input=data)
        assert "standard input" in _one_line_error(r, 2)
    r = runner.invoke(cli, ["shadow", "-", str(out), *SUN], input=b"")
    assert _one_line_error(r) == "hillshade-rt: error: <stdin>: standard input is empty"
    r = runner.invoke(cli, ["shadow", "-", str(out), *SUN], input=b"not a raster at all")
    assert "<stdin>: cannot read as a raster" in _one_line_error(r)
    r = runner.invoke(cli, ["shadow", "-", str(out), *SUN], input=data[:len(data) * 6 // 10])
    assert "<stdin>: truncated or corrupt" in _one_line_error(r)
    assert set(os.listdir(tmp_path)) == before


# ---------------------------------------------------------------------------------------------
# corrupt inputs

def _flip(path, start_fraction=0.3):
    """Invert bytes of the compressed tile data (every 997th byte past ``start_fraction``)."""
    data = bytearray(open(path, "rb").read())
    for i in range(int(len(data) * start_fraction), len(data), 997):
        data[i] ^= 0xFF
    with open(path, "wb") as fh:
        fh.write(bytes(data))


@pytest.mark.parametrize("damage", ["truncated", "bit-flipped"])
@pytest.mark.parametrize("windows", [False, True])
def test_corrupt_geotiff_is_named(damage, windows, dem, tmp_path, runner):
    (_cut if damage == "truncated" else _flip)(dem)
    folder = tmp_path / "out"
    folder.mkdir()
    extra = ["--window-size", "128"] if windows else []
    r = runner.invoke(cli, ["shadow", dem, str(folder / "o.tif"), *SUN, *extra,
                            "--report", str(folder / "r.json")])
    line = _one_line_error(r)
    assert line.startswith(f"hillshade-rt: error: {dem}: truncated or corrupt (")
    assert "See previous exception" not in line
    assert os.listdir(folder) == []       # no output, no hidden temporary files
    with pytest.raises(HillshadeError, match="truncated or corrupt"):
        read_dem(dem)


def test_corrupt_tiff_header_is_named(dem, tmp_path, runner):
    _cut(dem, 100 / os.path.getsize(dem))      # the header's directory is gone
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif"), *SUN])
    assert f"{dem}: truncated or corrupt (" in _one_line_error(r)


@pytest.mark.parametrize("extra", [[], ["--window-size", "128"]])
def test_mosaic_names_its_corrupt_tile(extra, tmp_path, runner):
    z = fractal_terrain(300, 300, 5, relief=300.0)
    paths = []
    for i, (r0, c0) in enumerate([(0, 0), (0, 150), (150, 0), (150, 150)]):
        paths.append(_tiled_geotiff(tmp_path / f"tile{i + 1}.tif", z[r0:r0 + 150, c0:c0 + 150],
                                    TR @ Affine.translation(c0, r0)))
    _cut(paths[2])                               # tile 3
    folder = tmp_path / "out"
    folder.mkdir()
    r = runner.invoke(cli, ["shadow", *paths, str(folder / "o.tif"), *SUN, *extra])
    line = _one_line_error(r)
    assert line.startswith(f"hillshade-rt: error: {paths[2]}: truncated or corrupt (")
    assert not any(p in line for p in paths[:2] + paths[3:])
    assert os.listdir(folder) == []


# ---------------------------------------------------------------------------------------------
# geotransforms

@pytest.mark.parametrize("transform, says", [
    (Affine(10, 2, 500000, 1, -10, 5200000), "rotated or sheared geotransform"),
    (Affine(10, 0, 500000, 0, 0, 5200000), "degenerate geotransform"),
])
@pytest.mark.parametrize("extra", [[], ["--window-size", "128"], ["--pixel-size", "10"]])
def test_unusable_geotransform_names_the_file(transform, says, extra, tmp_path, runner):
    path = write_geotiff(tmp_path / "odd.tif", fractal_terrain(60, 60, 3), transform, UTM)
    r = runner.invoke(cli, ["shadow", path, str(tmp_path / "o.tif"), *SUN, *extra])
    line = _one_line_error(r)
    assert line.startswith(f"hillshade-rt: error: {path}: ") and says in line


def test_mosaic_names_its_degenerate_tile(tmp_path, runner):
    z = fractal_terrain(60, 60, 3)
    bad = write_geotiff(tmp_path / "bad.tif", z, Affine(10, 0, 500000, 0, 0, 5200000), UTM)
    good = write_geotiff(tmp_path / "good.tif", z, TR @ Affine.translation(60, 0), UTM)
    r = runner.invoke(cli, ["shadow", bad, good, str(tmp_path / "o.tif"), *SUN])
    line = _one_line_error(r)
    assert line.startswith(f"hillshade-rt: error: {bad}: degenerate geotransform")


# ---------------------------------------------------------------------------------------------
# heights

def test_infinite_heights_are_nodata(tmp_path, runner):
    z = fractal_terrain(60, 60, 4, relief=100.0)
    z[10, 12], z[30, 40] = np.inf, -np.inf
    path = write_geotiff(tmp_path / "inf.tif", z, TR, UTM)
    d = read_dem(path)
    assert np.isnan(d.heights[10, 12]) and np.isnan(d.heights[30, 40])
    assert d.valid_count() == 60 * 60 - 2 and np.isfinite(d.height_range()).all()
    out = tmp_path / "o.tif"
    r = runner.invoke(cli, ["shadow", path, str(out), *SUN])
    assert r.exit_code == 0, r.output
    m = read_band(out)
    assert m[10, 12] == 255 and m[30, 40] == 255 and (m != 255).sum() == 60 * 60 - 2


def test_tile_field_of_archive_members():
    """{tile} names a zip:// member by the member's own file name (was 't.zip!a')."""
    from hillshade_rt.run.outputs import tile_name
    assert tile_name("zip://t.zip!n46/e007.tif") == "e007"
    assert tile_name("/vsizip/t.zip/a.tif") == "a" and tile_name("dir/b.tif") == "b"
