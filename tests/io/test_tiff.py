"""io/tiff.py: TIFFs without georeferencing through tifffile: a band of 2-D and 3-D images (planar
or contiguous), the GDAL_NODATA tag, refusals naming the file."""

import numpy as np
import pytest
import tifffile

from hillshade_rt.errors import HillshadeError
from hillshade_rt.io.tiff import TiffUnreadable, read_tiff


def test_a_plain_tiff_and_its_nodata_tag(tmp_path):
    z = np.arange(20, dtype=np.int16).reshape(4, 5)
    p = tmp_path / "a.tif"
    tifffile.imwrite(p, z, extratags=[(42113, "s", 0, "-32768\x00", False)])
    values, nodata = read_tiff(str(p), 1)
    np.testing.assert_array_equal(values, z)
    assert nodata == -32768.0
    tifffile.imwrite(tmp_path / "b.tif", z.astype(np.float32))
    assert read_tiff(str(tmp_path / "b.tif"), 1)[1] is None
    # from its bytes (standard input)
    values, _ = read_tiff("<stdin>", 1, data=p.read_bytes())
    np.testing.assert_array_equal(values, z)


@pytest.mark.parametrize("planar", ["separate", "contig"])
def test_bands_of_a_three_band_image(tmp_path, planar):
    bands = np.stack([np.full((6, 7), k, np.float32) + np.arange(7) for k in (10, 20, 30)])
    data = bands if planar == "separate" else np.moveaxis(bands, 0, -1)
    p = tmp_path / "m.tif"
    tifffile.imwrite(p, data, planarconfig=planar, photometric="rgb")
    for band in (1, 2, 3):
        np.testing.assert_array_equal(read_tiff(str(p), band)[0], bands[band - 1])
    with pytest.raises(HillshadeError, match="m.tif: has 3 band\\(s\\), --band 4 asked"):
        read_tiff(str(p), 4)


def test_refusals(tmp_path):
    p = tmp_path / "junk.tif"
    p.write_bytes(b"II*\x00garbage")
    with pytest.raises(TiffUnreadable, match="junk.tif: cannot read as a TIFF"):
        read_tiff(str(p), 1)
    one = tmp_path / "one.tif"
    tifffile.imwrite(one, np.zeros((3, 3), np.uint8))
    with pytest.raises(HillshadeError, match="expected a single-band 2-D image"):
        read_tiff(str(one), 2)
    c = tmp_path / "c.tif"
    tifffile.imwrite(c, np.zeros((3, 3), np.complex64))
    with pytest.raises(HillshadeError, match="pixel type complex64 is not a height"):
        read_tiff(str(c), 1)
