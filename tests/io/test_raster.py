"""io/raster.py: the driver an output gets and what it can hold, creation options over the
tool's defaults (moved here from test_output_options), the GeoTIFF profile, BandWriter (bands,
windows, descriptions, tags; 16-bit soft shadows in PNG), read back; PNG pictures, VRT copies.
(--co and --format through the commands: test_output_options.)"""

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.io import raster
from hillshade_rt.io.raster import merged_options, parse_creation_options
from hillshade_rt.io.vrt import VrtSource, vrt_xml
from hillshade_rt.testing import fractal_terrain, write_geotiff

UTM = CRS.from_epsg(32611)
TR = Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0)


class _Dem:
    """What the writers take of a DEM: its shape, CRS and transform."""

    def __init__(self, shape, crs=UTM, transform=TR):
        self.shape, self.crs, self.transform = shape, crs, transform


def test_parse_creation_options():
    assert parse_creation_options(()) == {}
    assert parse_creation_options(["compress=zstd", "PREDICTOR=2", "COMPRESS=LZW"]) == \
        {"COMPRESS": "LZW", "PREDICTOR": "2"}        # names upper-cased, the last one wins
    assert parse_creation_options(["NAME=a=b"]) == {"NAME": "a=b"}
    assert parse_creation_options({"tiled": True, "blockxsize": 512}) == \
        {"TILED": "YES", "BLOCKXSIZE": "512"}
    for bad in (["FOO"], ["=ZSTD"], ["COMPRESS="], ["2X=1"], ["A B=1"]):
        with pytest.raises(UsageProblem, match="expected NAME=VALUE"):
            parse_creation_options(bad)


def test_merged_options_override_defaults():
    d = dict(compress="deflate", zlevel=1, tiled=True, blockxsize=256, blockysize=256,
             predictor=3)
    assert merged_options(d) == dict(COMPRESS="deflate", ZLEVEL="1", TILED="YES",
                                     BLOCKXSIZE="256", BLOCKYSIZE="256", PREDICTOR="3")
    # another codec: the deflate level goes, the predictor stays where the codec takes one
    assert merged_options(d, {"COMPRESS": "ZSTD"}) == dict(
        COMPRESS="ZSTD", TILED="YES", BLOCKXSIZE="256", BLOCKYSIZE="256", PREDICTOR="3")
    assert "PREDICTOR" not in merged_options(d, {"COMPRESS": "NONE"})
    assert merged_options(d, {"COMPRESS": "NONE", "PREDICTOR": "2"})["PREDICTOR"] == "2"
    assert "BLOCKXSIZE" not in merged_options(d, {"TILED": "NO"})
    assert merged_options(d, {"BLOCKXSIZE": "512"})["BLOCKXSIZE"] == "512"


def test_output_driver():
    assert raster.output_driver("a.tif") == "GTiff"
    assert raster.output_driver("a.png") == "PNG"
    assert raster.output_driver("a.unknownext") == "GTiff"
    assert raster.output_driver("a.dat", "aaigrid") == "AAIGrid"
    assert raster.output_driver("a.tif", cog=True) == "COG"
    for args, why in [(("a.vrt",), "cannot write VRT"),
                      (("a.tif", "NoSuchDriver"), "not a GDAL raster driver here"),
                      (("a.png", None, True), "--cog writes a GeoTIFF; this path names PNG")]:
        with pytest.raises(HillshadeError, match=why):
            raster.output_driver(*args)


@pytest.mark.parametrize("args, why", [
    (("a.png", "PNG", "float32", 1, False), "PNG holds integers, this product is float32"),
    (("a.png", "PNG", "uint8", 2, False), "PNG holds one band, this run makes 2"),
    (("a.jpg", "JPEG", "uint8", 1, False), "JPEG is lossy and would change the mask"),
    (("a.tif", "GTiff", "uint8", 1, False, {"COMPRESS": "JPEG"}), "--co COMPRESS=JPEG is lossy"),
    (("a.tif", "GTiff", "uint8", 1, False, {"COMPRESS": "WEBP"}), "--co COMPRESS=WEBP"),
])
def test_check_output_format_refusals(args, why):
    with pytest.raises(HillshadeError, match=why):
        raster.check_output_format(*args)


def test_check_output_format_accepts():
    raster.check_output_format("a.png", "PNG", "float32", 1, True)     # soft: 16-bit PNG
    raster.check_output_format("a.tif", "GTiff", "float32", 3, True, {"COMPRESS": "ZSTD"})


def test_output_options_defaults():
    g = raster.output_options("GTiff", "float32", 2)
    assert g["COMPRESS"] == "DEFLATE" and g["PREDICTOR"] == "3" and g["INTERLEAVE"] == "BAND"
    assert g["BLOCKXSIZE"] == str(raster.GTIFF_BLOCK) and "BIGTIFF" not in g
    assert raster.output_options("GTiff", "uint8", 1, big=True)["BIGTIFF"] == "IF_SAFER"
    assert "PREDICTOR" not in raster.output_options("GTiff", "uint8", 1)
    c = raster.output_options("COG", "float32", 1, resampling="average")
    assert c["RESAMPLING"] == "AVERAGE" and c["PREDICTOR"] == "YES"
    assert raster.output_options("PNG", "uint8", 1) == {"ZLEVEL": "6"}
    assert raster.output_options("AAIGrid", "uint8", 1, {"DECIMAL_PRECISION": "2"}) == {
        "DECIMAL_PRECISION": "2"}


def test_gtiff_profile():
    p = raster.gtiff_profile(_Dem((40, 50)), "uint8", 255)
    assert (p["width"], p["height"], p["count"], p["nodata"]) == (50, 40, 1, 255)
    assert p["crs"] == UTM and p["transform"] == TR and p["tiled"] and p["blockxsize"] == 256
    assert "crs" not in raster.gtiff_profile(_Dem((4, 5), None, None), "uint8", 255)


def test_band_writer_bands_windows_tags(tmp_path):
    z = fractal_terrain(40, 50, seed=1, relief=100.0)
    path = tmp_path / "o.tif"
    with raster.BandWriter(str(path), _Dem(z.shape), 2, "float32", -9999.0,
                           tags={"what": "test"}) as w:
        w.write(1, z, description="heights", tags={"band": "one"})
        w.write(2, z[:20] * 2, window=(0, 20, 0, 50))
        w.write(2, z[20:] * 2, window=(20, 40, 0, 50), description="double")
        assert not path.exists()                         # published only when complete
    with rasterio.open(path) as ds:
        np.testing.assert_array_equal(ds.read(1), z)
        np.testing.assert_array_equal(ds.read(2), z * 2)
        assert ds.descriptions == ("heights", "double") and ds.tags()["what"] == "test"
        assert ds.tags(1)["band"] == "one" and ds.nodata == -9999.0 and ds.crs == UTM
        assert ds.profile["compress"] == "deflate" and ds.block_shapes[0] == (256, 256)
    before = path.read_bytes()
    with pytest.raises(HillshadeError):                  # no clobbering without overwrite
        with raster.BandWriter(str(path), _Dem(z.shape), 1, "uint8", 255) as w:
            w.write(1, np.zeros(z.shape, np.uint8))
    assert path.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["o.tif"]


def test_an_error_inside_publishes_nothing(tmp_path):
    path = tmp_path / "o.tif"
    with pytest.raises(RuntimeError):
        with raster.BandWriter(str(path), _Dem((4, 4)), 1, "uint8", 255) as w:
            w.write(1, np.zeros((4, 4), np.uint8))
            raise RuntimeError("stop")
    assert list(tmp_path.iterdir()) == []


def test_soft_shadows_in_png_are_16_bit(tmp_path):
    soft = np.array([[0.0, 0.5, 1.0], [np.nan, 0.25, 2.0]], np.float32)
    path = tmp_path / "s.png"
    raster.write_raster(str(path), soft, _Dem(soft.shape), np.nan, overview_resampling="average")
    with rasterio.open(path) as ds:
        assert ds.dtypes[0] == "uint16" and ds.driver == "PNG"
        np.testing.assert_array_equal(ds.read(1), [[1, 32768, 65535], [0, 16385, 65535]])


def test_read_decimated_and_write_png(tmp_path):
    z = np.arange(16, dtype=np.float32).reshape(4, 4)
    z[:2, :2] = -1.0
    p = write_geotiff(tmp_path / "z.tif", z, TR, UTM, nodata=-1.0)
    small = raster.read_decimated(p, (2, 2))
    assert small.shape == (2, 2) and small.dtype == np.float32 and np.isnan(small[0, 0])
    assert small[1, 1] in z[2:, 2:] and small[0, 1] in z[:2, 2:]
    rgb = np.random.default_rng(0).integers(0, 256, (5, 7, 3)).astype(np.uint8)
    raster.write_png(str(tmp_path / "p.png"), rgb)
    from PIL import Image
    with Image.open(tmp_path / "p.png") as im:
        np.testing.assert_array_equal(np.asarray(im), rgb)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["p.png", "z.tif"]


def test_copy_vrt_as_geotiff_and_png(tmp_path):
    z = (fractal_terrain(20, 30, seed=5, relief=200.0)).astype(np.uint8)
    a = write_geotiff(tmp_path / "a.tif", z[:, :15], TR, UTM)
    b = write_geotiff(tmp_path / "b.tif", z[:, 15:], TR @ Affine.translation(15, 0), UTM)
    doc = vrt_xml((20, 30), TR, UTM, [[VrtSource(str(a), 1, (0, 0), (20, 15)),
                                      VrtSource(str(b), 1, (0, 15), (20, 15))]], dtype="Byte")
    raster.copy_vrt(doc, str(tmp_path / "m.tif"), "uint8")
    raster.copy_vrt(doc, str(tmp_path / "m.png"), "uint8")
    for name in ("m.tif", "m.png"):
        with rasterio.open(tmp_path / name) as ds:
            np.testing.assert_array_equal(ds.read(1), z)
