"""io.vector: the cells of a mask's values as polygons in GeoPackage, GeoJSON and FlatGeobuf,
their area the cells', their CRS the raster's, written whole or not at all."""

import os

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.io.vector import (PolygonSource, check_connectivity, vector_driver,
                                    write_polygons)
from hillshade_rt.testing import write_geotiff

UTM = CRS.from_epsg(32611)
TR = Affine(2.5, 0, 400000.0, 0, -2.5, 3800000.0)
FIELDS = {"azimuth": "float", "elevation": "float"}


def ring_area(ring) -> float:
    xy = np.asarray(ring, dtype=float)
    xy = xy - xy[0]          # (map coordinates in the millions would cancel)
    return 0.5 * abs(float(np.dot(xy[:-1, 0], xy[1:, 1]) - np.dot(xy[1:, 0], xy[:-1, 1])))


def polygon_area(geom) -> float:
    rings = geom["coordinates"]
    return ring_area(rings[0]) - sum(ring_area(r) for r in rings[1:])


def read_back(path):
    """(features as (geometry dict, properties dict), the layer's CRS, its layer names)."""
    import fiona
    with fiona.open(path) as src:
        feats = [(dict(f.geometry), dict(f.properties)) for f in src]
        return feats, src.crs, fiona.listlayers(path)


def mask_raster(tmp_path, name="mask.tif", seed=3, bands=1, transform=TR, crs=UTM):
    """A uint8 mask (0 lit, 1 shadow, 255 nodata) with blobs, holes and a void."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(bands):
        m = (rng.random((60, 70)) < 0.45).astype(np.uint8)
        m[10:30, 10:40] = 1
        m[15:20, 20:25] = 0          # a hole in a polygon
        m[40:50, 5:25] = 255         # a void
        out.append(m)
    arr = np.stack(out)
    return write_geotiff(tmp_path / name, arr, transform, crs, nodata=255), arr


def test_the_extension_names_the_format_and_an_unknown_one_is_a_usage_error():
    assert [vector_driver(p) for p in ("a.gpkg", "b.GeoJSON", "c/d.fgb")] == [
        "GPKG", "GeoJSON", "FlatGeobuf"]
    for bad in ("shadow.shp", "shadow", "shadow.tif"):
        with pytest.raises(UsageProblem, match="unknown vector format") as e:
            vector_driver(bad)
        assert "\n" not in str(e.value) and ".gpkg, .geojson, .fgb" in str(e.value)
    assert check_connectivity("8") == 8 and check_connectivity(4) == 4
    with pytest.raises(UsageProblem, match="4 or 8"):
        check_connectivity(6)


@pytest.mark.parametrize("ext", [".gpkg", ".geojson", ".fgb"])
def test_polygons_cover_exactly_the_shadow_cells_in_every_format(tmp_path, ext):
    """The polygons' total area is the count of value-1 cells times the cell's area (lit and
    nodata cells make none); burnt back into the grid they are the mask's 1s exactly; the
    layer's CRS is the raster's; the attributes are the source's."""
    from rasterio.features import rasterize
    path, arr = mask_raster(tmp_path)
    out = tmp_path / f"shadow{ext}"
    stats = write_polygons(out, [PolygonSource(path=path, band=1,
                                               attributes={"azimuth": 203.7,
                                                           "elevation": 11.5})], FIELDS)
    feats, crs, layers = read_back(out)
    cells = int((arr[0] == 1).sum())
    area = sum(polygon_area(g) for g, _ in feats)
    assert area == pytest.approx(cells * 2.5 * 2.5, rel=1e-12)
    assert stats.polygons == [len(feats)] and stats.area[0] == pytest.approx(area, rel=1e-12)
    assert stats.area_m2[0] == pytest.approx(area, rel=1e-12)        # metres: the same
    burnt = rasterize(((g, 1) for g, _ in feats), out_shape=arr.shape[1:], transform=TR)
    np.testing.assert_array_equal(burnt, (arr[0] == 1).astype(np.uint8))
    assert CRS.from_user_input(crs) == UTM
    assert layers == ["shadow"]
    assert {tuple(sorted(p.items())) for _, p in feats} == {
        (("azimuth", 203.7), ("elevation", 11.5))}
    assert any(len(g["coordinates"]) > 1 for g, _ in feats)           # the hole kept
    assert sorted(os.listdir(tmp_path)) == sorted(["mask.tif", f"shadow{ext}"])


def test_connectivity_4_or_8(tmp_path):
    """Cells touching at a corner only: two polygons 4-connected (GDAL's default), one
    8-connected; the same area."""
    m = np.zeros((6, 6), np.uint8)
    m[1, 1] = m[2, 2] = m[3, 3] = 1
    m[4, 1] = 1
    path = write_geotiff(tmp_path / "m.tif", m, TR, UTM, nodata=255)
    src = [PolygonSource(path=path, band=1, attributes={"azimuth": 163.0, "elevation": 8.0})]
    four = write_polygons(tmp_path / "four.gpkg", src, FIELDS)
    eight = write_polygons(tmp_path / "eight.gpkg", src, FIELDS, connectivity=8)
    assert four.polygons == [4] and eight.polygons == [2]
    assert four.area == pytest.approx(eight.area) == [4 * 6.25]
    assert len(read_back(tmp_path / "eight.gpkg")[0]) == 2


def test_several_sources_in_one_layer_with_their_attributes_and_values(tmp_path):
    """One layer, every band's polygons with its own attributes; a value's own attributes
    (classes 1 and 2)."""
    path, arr = mask_raster(tmp_path, bands=3, seed=11)
    arr[1][arr[1] == 0] = 2
    path = write_geotiff(tmp_path / "cls.tif", arr, TR, UTM, nodata=255)
    fields = dict(FIELDS, index="int", shadow_class="int")
    src = [PolygonSource(path=path, band=b + 1,
                         attributes={"azimuth": 290.0, "elevation": 5.0 + b, "index": b},
                         values={1: {"shadow_class": 1}, 2: {"shadow_class": 2}})
           for b in range(3)]
    stats = write_polygons(tmp_path / "s.fgb", src, fields)
    feats, _, _ = read_back(tmp_path / "s.fgb")
    for b in range(3):
        mine = [(g, p) for g, p in feats if p["index"] == b]
        assert len(mine) == stats.polygons[b]
        assert all(p["elevation"] == 5.0 + b for _, p in mine)
        for v in (1, 2):
            a = sum(polygon_area(g) for g, p in mine if p["shadow_class"] == v)
            assert a == pytest.approx((arr[b] == v).sum() * 6.25, rel=1e-12)


def test_geographic_area_in_square_metres_on_the_ellipsoid(tmp_path):
    """A DEM in degrees: the area in square metres is the ellipsoid's (each row's cells
    narrower toward the pole), the planar area in square degrees."""
    from pyproj import Geod
    tr = Affine(1 / 3600, 0, 7.5, 0, -1 / 3600, 46.5)
    m = np.zeros((40, 30), np.uint8)
    m[5:35, 3:27] = 1
    path = write_geotiff(tmp_path / "g.tif", m, tr, CRS.from_epsg(4326), nodata=255)
    stats = write_polygons(tmp_path / "g.geojson", [PolygonSource(
        path=path, band=1, attributes={"azimuth": 163.0, "elevation": 20.0})], FIELDS)
    geod = Geod(ellps="WGS84")
    x0, x1 = 7.5 + 3 / 3600, 7.5 + 27 / 3600
    y0, y1 = 46.5 - 35 / 3600, 46.5 - 5 / 3600
    want = abs(geod.polygon_area_perimeter([x0, x1, x1, x0], [y0, y0, y1, y1])[0])
    assert stats.area_m2[0] == pytest.approx(want, rel=1e-9)
    assert stats.area[0] == pytest.approx(30 * 24 / 3600 ** 2, rel=1e-9)


def test_nothing_left_on_failure_and_no_clobbering(tmp_path, monkeypatch):
    """A failure while the polygons are written (the second source's) leaves no file and no
    temporary; an existing file is kept without overwrite, replaced with it."""
    import rasterio.features
    path, _ = mask_raster(tmp_path)
    src = PolygonSource(path=path, band=1, attributes={"azimuth": 203.7, "elevation": 9.0})
    out = tmp_path / "v.gpkg"
    real, calls = rasterio.features.shapes, []

    def failing(*a, **k):
        calls.append(1)
        if len(calls) > 1:
            raise RuntimeError("disk on fire")
        return real(*a, **k)
    monkeypatch.setattr(rasterio.features, "shapes", failing)
    with pytest.raises(HillshadeError, match="v.gpkg: cannot write \\(disk on fire\\)"):
        write_polygons(out, [src, src], FIELDS)
    assert sorted(os.listdir(tmp_path)) == ["mask.tif"]
    monkeypatch.setattr(rasterio.features, "shapes", real)
    out.write_bytes(b"old")
    with pytest.raises(HillshadeError, match="--overwrite"):
        write_polygons(out, [src], FIELDS)
    assert out.read_bytes() == b"old" and sorted(os.listdir(tmp_path)) == ["mask.tif", "v.gpkg"]
    write_polygons(out, [src], FIELDS, overwrite=True)
    assert len(read_back(out)[0]) > 3


def test_rasterio_and_fiona_in_one_process():
    """Both bundle a GDAL: imported together, each still opens its own formats."""
    import fiona
    import rasterio
    assert "GPKG" in fiona.supported_drivers and "FlatGeobuf" in fiona.supported_drivers
    assert rasterio.__gdal_version__ and fiona.__gdal_version__
