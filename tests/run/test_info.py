"""``run.info``: what hillshade-rt understood of a DEM, and its preview."""

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import UsageProblem
from hillshade_rt.run import describe
from hillshade_rt.run.config import ReadOptions
from hillshade_rt.testing import fractal_terrain, png_pixels, write_geotiff


@pytest.fixture
def dem(tmp_path):
    z = (fractal_terrain(40, 50, 6, relief=300.0) + 200.0).astype(np.float32)
    z[3:5, 7:10] = -9999.0
    return z, write_geotiff(tmp_path / "d.tif", z, Affine(10, 0, 500000.0, 0, -20, 4000000.0),
                            CRS.from_epsg(32633), nodata=-9999.0)


def test_the_description_is_the_dems(dem):
    z, path = dem
    doc, d = describe(path, ReadOptions())
    valid = z[z != -9999.0]
    assert doc["shape"] == [40, 50] and d.shape == (40, 50)
    assert doc["crs"] == "EPSG:32633" and doc["orientation"] == "north-up"
    dx, dy = doc["spacing_m"]["centre"]     # ground metres: UTM's scale factor off 1
    assert dx == pytest.approx(10.0, rel=1e-3) and dy / dx == pytest.approx(2.0, rel=1e-6)
    assert doc["transform"] == [10.0, 0.0, 500000.0, 0.0, -20.0, 4000000.0]
    assert doc["valid_cells"] == 2000 - 6 and doc["nodata"] == -9999.0
    assert doc["nodata_fraction"] == pytest.approx(6 / 2000)
    assert doc["height_range_m"] == pytest.approx([float(valid.min()), float(valid.max())])


def test_the_preview_is_the_relief_and_no_input(tmp_path, dem):
    _, path = dem
    png = tmp_path / "p.png"
    describe(path, ReadOptions(), str(png))
    assert png_pixels(png.read_bytes()).shape[:2] == (40, 50)
    with pytest.raises(UsageProblem, match="--preview is also an input"):
        describe(path, ReadOptions(), path, overwrite=True)
    with pytest.raises(Exception, match="exists"):
        describe(path, ReadOptions(), str(png))        # not replaced without overwrite
