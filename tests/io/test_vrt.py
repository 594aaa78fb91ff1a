"""io/vrt.py: VRT documents that GDAL reads back as the mosaic they describe (placement, the part
of a source taken, nodata, descriptions and tags)."""

import math

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.io.vrt import VrtSource, vrt_xml
from hillshade_rt.testing import fractal_terrain, write_geotiff

TR = Affine(10.0, 0, 500000.0, 0, -10.0, 5200000.0)
UTM = CRS.from_epsg(32632)


def test_tiles_put_together_read_back_as_the_whole(tmp_path):
    z = fractal_terrain(30, 41, seed=4, relief=200.0)
    cuts = [(0, 0, 12, 25), (0, 25, 12, 16), (12, 0, 18, 41)]   # (row, col, rows, cols)
    sources = []
    for k, (r, c, h, w) in enumerate(cuts):
        p = write_geotiff(tmp_path / f"t{k}.tif", z[r:r + h, c:c + w],
                          TR @ Affine.translation(c, r), UTM)
        sources.append(VrtSource(str(p), 1, (r, c), (h, w)))
    doc = vrt_xml(z.shape, TR, UTM, [sources, sources[:1]], nodata=-9999.0,
                  descriptions=["heights", ""], metadata={"a": "x<y"},
                  band_metadata=[{"k": "1"}, {}])
    with rasterio.open(doc) as ds:
        assert ds.shape == z.shape and ds.count == 2 and ds.crs == UTM
        assert ds.transform.almost_equals(TR)
        np.testing.assert_array_equal(ds.read(1), z)
        two = ds.read(2)
        np.testing.assert_array_equal(two[:12, :25], z[:12, :25])
        assert (two[12:] == -9999.0).all() and (two[:12, 25:] == -9999.0).all()
        assert ds.descriptions == ("heights", None)
        assert ds.tags()["a"] == "x<y" and ds.tags(1)["k"] == "1"


@pytest.mark.filterwarnings("ignore::rasterio.errors.NotGeoreferencedWarning")
def test_a_part_of_a_source_and_its_nodata(tmp_path):
    z = fractal_terrain(20, 20, seed=9, relief=50.0)
    z[5, 6] = -1.0
    p = write_geotiff(tmp_path / "s.tif", z, TR, UTM)
    part = VrtSource(str(p), 1, (1, 2), (8, 7), nodata=-1.0, src_offset=(3, 4))
    doc = vrt_xml((10, 10), None, None, [[part]], nodata=math.nan)
    assert "<NoDataValue>nan</NoDataValue>" in doc and "<NODATA>-1.0</NODATA>" in doc
    with rasterio.open(doc) as ds:
        got = ds.read(1)
    want = np.full((10, 10), np.nan, np.float32)
    want[1:9, 2:9] = z[3:11, 4:11]
    want[1 + 5 - 3, 2 + 6 - 4] = np.nan        # the source's nodata left to the band's
    np.testing.assert_array_equal(got, want)
