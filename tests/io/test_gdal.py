"""io/gdal.py: GDAL's chained errors said in one line (the deepest useful message, the file's
name dropped), what a refusal means (no such file, truncated or corrupt, not a raster), bands,
opening from a path, a GDAL name or bytes."""

import contextlib
import warnings

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import gdal
from hillshade_rt.testing import write_geotiff


def _chain(*texts):
    """An exception whose causes say ``texts``, the first raised deepest."""
    exc = None
    for t in texts:
        new = RuntimeError(t)
        new.__cause__ = exc
        exc = new
    return exc


def test_gdal_message_takes_the_deepest_useful_line():
    exc = _chain("/d/c.tif: c.tif:TIFFFillTile:Read error at row 3",
                 "Read failed. See previous exception for details.")
    assert gdal.gdal_message(exc, "/d/c.tif") == "Read error at row 3"
    exc = _chain("x.tif, band 1: IReadBlock failed at X offset 0,\n Y offset 0")
    assert gdal.gdal_message(exc, "x.tif") == "IReadBlock failed at X offset 0, Y offset 0"
    assert gdal.gdal_message(RuntimeError("")) == "RuntimeError"
    assert len(gdal.gdal_message(RuntimeError("y" * 500))) == 200


def test_has_tiff_magic(tmp_path):
    assert gdal.has_tiff_magic("", b"II*\x00rest") and gdal.has_tiff_magic("", b"MM\x00+")
    assert not gdal.has_tiff_magic("", b"PK\x03\x04")
    p = tmp_path / "a.tif"
    p.write_bytes(b"MM\x00*")
    assert gdal.has_tiff_magic(str(p)) and not gdal.has_tiff_magic(str(tmp_path / "none"))


def test_open_error_says_what_it_means(tmp_path):
    e = gdal.open_error("a.tif", RuntimeError("a.tif: No such file or directory"))
    assert str(e) == "a.tif: no such file"
    bad = tmp_path / "t.tif"
    bad.write_bytes(b"II*\x00" + b"\x00" * 10)
    e = gdal.open_error(str(bad), RuntimeError(f"{bad}: not recognized as a supported format"))
    assert str(e).startswith(f"{bad}: truncated or corrupt (")    # a TIFF by its header
    e = gdal.open_error("x.dat", RuntimeError("x.dat: not recognized as being in a supported "
                                              "file format"))
    assert str(e) == "x.dat: cannot read as a raster (not a raster format GDAL can read)"
    e = gdal.open_error("y.nc", RuntimeError("decompression failed"))
    assert str(e) == "y.nc: truncated or corrupt (decompression failed)"
    e = gdal.read_error("z.tif", _chain("z.tif: TIFFReadEncodedTile() failed."))
    assert str(e) == "z.tif: truncated or corrupt (TIFFReadEncodedTile() failed.)"


def test_open_raster_path_name_bytes_and_bands(tmp_path):
    z = np.arange(12, dtype=np.float32).reshape(3, 4)
    path = write_geotiff(tmp_path / "d.tif", z, Affine(10, 0, 0, 0, -10, 0), "EPSG:32632")
    plain = write_geotiff(tmp_path / "p.tif", z)
    with contextlib.ExitStack() as stack:
        ds = gdal.open_raster(path, stack)
        np.testing.assert_array_equal(ds.read(1), z)
        assert gdal.check_band(ds, path, 1)
        with pytest.raises(HillshadeError, match="has 1 band\\(s\\), --band 2 asked"):
            gdal.check_band(ds, path, 2)
        with open(plain, "rb") as fh:
            data = fh.read()
        with warnings.catch_warnings():
            warnings.simplefilter("error")          # no NotGeoreferencedWarning escapes
            mem = gdal.open_raster("<stdin>", stack, data=data)
        np.testing.assert_array_equal(mem.read(1), z)
        assert not gdal.check_band(mem, "<stdin>", 1)
        named = gdal.open_raster("alias", stack, name=str(path))
        assert named.shape == (3, 4)
        with pytest.raises(HillshadeError, match="absent.tif: no such file"):
            gdal.open_raster(str(tmp_path / "absent.tif"), stack)
        junk = tmp_path / "junk.tif"
        junk.write_bytes(b"II*\x00" + b"\x01" * 7)
        with pytest.raises(HillshadeError, match="junk.tif: truncated or corrupt"):
            gdal.open_raster(str(junk), stack)
