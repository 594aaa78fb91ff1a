"""io/raw.py: raw grids and SRTM .hgt tiles: the layout checked against the file's size, the
tile's georeferencing from its name, whole and memory-mapped reads."""

import numpy as np
import pytest

from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import raw


def test_parse_raw_shape():
    assert raw.parse_raw_shape(None) is None
    assert raw.parse_raw_shape(" 12x7 ") == (12, 7) and raw.parse_raw_shape("3,4") == (3, 4)
    for bad in ("12", "12x", "axb", "-3x4"):
        with pytest.raises(HillshadeError, match="ROWSxCOLS"):
            raw.parse_raw_shape(bad)
    with pytest.raises(HillshadeError, match="empty raster"):
        raw.parse_raw_shape("0x5")


def test_layout_of_raw_and_hgt():
    lay = raw.layout("a.raw", 3 * 5 * 4, (3, 5), "float32", None, None)
    assert lay == raw.Layout("<f4", (3, 5), None, "raw")
    lay = raw.layout("N27E086.hgt", 2 * 11 * 11, None, None, None, None)
    assert lay == raw.Layout(">i2", (11, 11), -32768.0, "SRTM .hgt (raw)")
    assert raw.layout("x.HGT", 8 * 4, (4, 1), "float64", "little", 0.0).dtype == "<f8"


@pytest.mark.parametrize("args, why", [
    (("a.raw", 0, (1, 1), "int16", None, None), "a.raw: the file is empty"),
    (("a.raw", 8, (2, 2), None, None, None), "needs --raw-dtype"),
    (("a.raw", 8, (2, 2), "int8", None, None), "--raw-dtype must be one of"),
    (("a.raw", 8, (2, 2), "int16", "middle", None), "--raw-byteorder must be"),
    (("a.raw", 7, (1, 3), "int16", None, None), "7 bytes is not a whole number of int16"),
    (("a.raw", 8, None, "int16", None, None), "needs --raw-shape"),
    (("N00E000.hgt", 2 * 12, None, None, None, None), "needs --raw-shape"),   # not square
    (("a.raw", 8, (3, 3), "int16", None, None), "--raw-shape 3x3 needs 9 int16 values"),
])
def test_layout_refusals_name_the_problem(args, why):
    with pytest.raises(HillshadeError, match=why):
        raw.layout(*args)


def test_hgt_geometry_centres_on_whole_degrees():
    t, crs = raw.hgt_geometry("/d/S27W086.hgt", 1201)
    assert crs.to_epsg() == 4326
    step = 1.0 / 1200
    # the first cell's centre at the tile's north-west corner (lat -26, lon -86), the last at
    # its south-east (lat -27, lon -85)
    assert t @ (0.5, 0.5) == pytest.approx((-86.0, -26.0))
    assert t @ (1200.5, 1200.5) == pytest.approx((-85.0, -27.0))
    assert t.a == pytest.approx(step) and t.e == pytest.approx(-step)
    assert raw.hgt_geometry("/d/n27e086.hgt", 3601)[0] @ (0.5, 0.5) == pytest.approx((86.0, 28.0))
    assert raw.hgt_geometry("/d/tile.hgt", 1201) == (None, None)
    assert raw.hgt_geometry("/d/N27E086.raw", 1201) == (None, None)


def test_whole_and_memmapped_reads_agree(tmp_path):
    z = (np.arange(12, dtype=np.int16) * 300 - 1000).reshape(3, 4)
    path = tmp_path / "g.raw"
    z.astype(">i2").tofile(path)
    lay = raw.layout(str(path), path.stat().st_size, (3, 4), "int16", "big", None)
    whole = raw.read_whole(str(path), lay.dtype, lay.shape)
    np.testing.assert_array_equal(whole, z)
    np.testing.assert_array_equal(raw.read_whole(str(path), lay.dtype, lay.shape,
                                                 data=path.read_bytes()), z)
    mm = raw.memmap(str(path), lay.dtype, lay.shape)
    np.testing.assert_array_equal(mm[1:3, 2:], z[1:3, 2:])
    assert not mm.flags.writeable
    from_bytes = raw.read_whole(str(path), lay.dtype, lay.shape, data=path.read_bytes())
    from_bytes[0, 0] = 7     # the caller owns it
