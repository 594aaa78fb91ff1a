"""The viewer's PNG encoder: pictures read back by GDAL, byte for byte."""

import numpy as np

from hillshade_rt.pictures.png import png_bytes
from hillshade_rt.testing import png_pixels


def test_png_encoder_round_trip():
    rng = np.random.default_rng(1)
    pic = rng.integers(0, 256, (7, 13, 4), dtype=np.uint8)
    assert np.array_equal(png_pixels(png_bytes(pic)), pic)


def test_png_of_one_pixel_and_a_wide_strip():
    """Shapes at the edges: one pixel, one row; zlib levels change the bytes, not the picture."""
    rng = np.random.default_rng(7)
    for shape in ((1, 1, 4), (1, 300, 4), (300, 1, 4)):
        pic = rng.integers(0, 256, shape, dtype=np.uint8)
        stored, packed = png_bytes(pic), png_bytes(pic, 6)
        assert stored.startswith(b"\x89PNG\r\n\x1a\n") and stored != packed
        assert np.array_equal(png_pixels(stored), pic) and np.array_equal(png_pixels(packed), pic)
