"""io/paths.py: GDAL names told from local paths, rasterio URLs turned into /vsi paths, how
reports name an input, the local checks, standard input's refusals."""

import io

import pytest

from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import paths


def test_gdal_path_of_rasterio_urls(tmp_path, monkeypatch):
    from hillshade_rt.io import gdal_path   # the package exports it
    monkeypatch.chdir(tmp_path)
    assert gdal_path("zip://a.zip!d.tif") == f"/vsizip/{tmp_path}/a.zip/d.tif"
    assert gdal_path("zip:///x/a.zip!/s/d.tif") == "/vsizip//x/a.zip/s/d.tif"
    assert gdal_path("tar://t.tar!d.tif") == f"/vsitar/{tmp_path}/t.tar/d.tif"
    assert gdal_path("gzip://d.tif.gz") == f"/vsigzip/{tmp_path}/d.tif.gz"
    assert gdal_path("zip+https://h/a.zip!d.tif") == "/vsizip//vsicurl/https://h/a.zip/d.tif"
    assert gdal_path("https://h/d.tif") == "/vsicurl/https://h/d.tif"
    assert gdal_path("s3://b/k/d.tif") == "/vsis3/b/k/d.tif"
    for same in ("/vsizip/a.zip/d.tif", "d.tif", "NETCDF:f.nc:z", "/abs/d.tif"):
        assert gdal_path(same) == same
    from hillshade_rt.io import input_label
    assert input_label("zip://a.zip!d.tif") == "zip://a.zip!d.tif"
    assert input_label("d.tif") == f"{tmp_path}/d.tif" and input_label("-") == "<stdin>"


def test_is_gdal_name():
    for name in ("/vsizip/a.zip/d.tif", "/vsimem/x", "zip://a.zip!d.tif", "https://h/d.tif",
                 "NETCDF:f.nc:z", "GTiff:x"):
        assert paths.is_gdal_name(name), name
    for name in ("d.tif", "/abs/d.tif", "./zip/d.tif", "C:/data/d.tif", "-"):
        assert not paths.is_gdal_name(name), name


def test_gdal_path_leaves_unknown_or_mixed_schemes():
    assert paths.gdal_path("foo://a/b") == "foo://a/b"              # not a scheme we know
    assert paths.gdal_path("s3+https://a/b") == "s3+https://a/b"    # two transports
    assert paths.gdal_path("file:///abs/d.tif") == "/abs/d.tif"


def test_dataset_name_makes_local_files_absolute(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "d.tif").write_bytes(b"")
    assert paths.dataset_name("d.tif") == str(tmp_path / "d.tif")
    assert paths.dataset_name("zip://a.zip!d.tif") == f"/vsizip/{tmp_path}/a.zip/d.tif"
    assert paths.dataset_name("/vsimem/x.tif") == "/vsimem/x.tif"


def test_check_input_path(tmp_path):
    with pytest.raises(HillshadeError, match=r"absent\.tif: no such file"):
        paths.check_input_path(str(tmp_path / "absent.tif"))
    (tmp_path / "folder").mkdir()
    with pytest.raises(HillshadeError, match="is a folder, not a raster file"):
        paths.check_input_path(str(tmp_path / "folder"))
    (tmp_path / "db.gdb").mkdir()          # folders GDAL opens as datasets
    paths.check_input_path(str(tmp_path / "db.gdb"))
    paths.check_input_path("/vsizip/absent.zip/d.tif")      # GDAL's to refuse
    paths.check_input_path(paths.STDIN)


class _Stdin:
    def __init__(self, data, tty=False):
        if isinstance(data, bytes):
            self.buffer = io.BytesIO(data)
        self._text, self._tty = data, tty

    def isatty(self):
        return self._tty

    def read(self):
        return self._text


def test_read_stdin(monkeypatch):
    import sys
    monkeypatch.setattr(sys, "stdin", _Stdin(b"II*\x00rest"))
    assert paths.read_stdin() == b"II*\x00rest"
    for stdin, why in [(_Stdin(b""), "standard input is empty"),
                       (_Stdin(b"x", tty=True), "is a terminal"),
                       (_Stdin("text"), "standard input is text"),
                       (None, "there is no standard input")]:
        monkeypatch.setattr(sys, "stdin", stdin)
        with pytest.raises(HillshadeError, match=f"^<stdin>: {why}"):
            paths.read_stdin()
