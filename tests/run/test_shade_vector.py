"""run.shade with --vector: the shadow polygons of every sun, traced from the raster written
(or a scratch raster beside them), cover exactly the mask's shadow cells (voids excluded), in
the DEM's CRS, each with its sun; the report and the summary line say how many and how much."""

import os

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.run.config import RunOptions, ShadeConfig
from hillshade_rt.run.shade import shade
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff

UTM = CRS.from_epsg(32611)
TR = Affine(10.0, 0, 400000.0, 0, -10.0, 3800000.0)
CELL = 100.0
TIMES = ("2026-03-02T07:40-08:00", "2026-03-02T11:05-08:00", "2026-03-02T16:50-08:00")


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    z = fractal_terrain(110, 127, seed=41, relief=320.0)
    z[50:56, 30:70] = np.nan             # a void: nodata in the mask, no polygon
    return write_geotiff(tmp_path_factory.mktemp("vec") / "dem.tif", z, TR, UTM)


def config(dem, out, vector, **kw):
    sun = kw.pop("sun", {"azimuth": 203.7, "elevation": 11.0})
    return ShadeConfig(files=[dem], output=None if out is None else str(out), sun=sun,
                       curvature=False, vector=str(vector),
                       run=RunOptions(quiet=True, say=kw.pop("say", None) or (lambda k, m: None),
                                      overwrite=kw.pop("overwrite", False)), **kw)


def polygon_area(geom) -> float:
    def ring(r):
        xy = np.asarray(r, dtype=float)
        xy = xy - xy[0]      # (map coordinates in the millions would cancel)
        return 0.5 * abs(float(np.dot(xy[:-1, 0], xy[1:, 1]) - np.dot(xy[1:, 0], xy[:-1, 1])))
    rings = geom["coordinates"]
    return ring(rings[0]) - sum(ring(r) for r in rings[1:])


def features(path):
    import fiona
    with fiona.open(path) as src:
        return [(dict(f.geometry), dict(f.properties)) for f in src], CRS.from_user_input(src.crs)


def burnt(feats, shape):
    from rasterio.features import rasterize
    if not feats:
        return np.zeros(shape, np.uint8)
    return rasterize(((g, 1) for g, _ in feats), out_shape=shape, transform=TR)


@pytest.mark.parametrize("azimuth,ext", [(163.0, ".gpkg"), (203.7, ".geojson"),
                                         (290.0, ".fgb")])
def test_polygons_are_the_masks_shadow_cells_in_the_dems_crs(tmp_path, dem, azimuth, ext):
    vec = tmp_path / f"shadow{ext}"
    rep = shade(config(dem, tmp_path / "mask.tif", vec, sun={"azimuth": azimuth,
                                                             "elevation": 9.5}))
    mask = read_band(tmp_path / "mask.tif")
    feats, crs = features(vec)
    cells = int((mask == 1).sum())
    assert cells > 0 and (mask == 0).any() and (mask == 255).sum() == 6 * 40
    # exactly the shadow cells: area, and burnt back into the grid (voids and lit cells out)
    assert sum(polygon_area(g) for g, _ in feats) == pytest.approx(cells * CELL, rel=1e-12)
    np.testing.assert_array_equal(burnt(feats, mask.shape), (mask == 1).astype(np.uint8))
    assert crs == UTM
    assert {tuple(p) for _, p in feats} == {("azimuth", "elevation")}
    assert all(p["azimuth"] == pytest.approx(azimuth) and p["elevation"] == 9.5
               for _, p in feats)
    v = rep["vector"]
    assert v["polygons"] == len(feats) and v["area_m2"] == pytest.approx(cells * CELL)
    assert v["area"] == pytest.approx(cells * CELL) and v["connectivity"] == 4
    assert v["path"] == os.path.abspath(vec) and v["times"] is None
    assert rep["cells"]["shadow"] == cells


def test_a_series_one_set_per_time_with_its_sun(tmp_path, dem):
    """Every time's polygons in one layer, each with its time, azimuth, elevation and index
    (band index + 1); each time's set is that band's shadow cells."""
    vec = tmp_path / "day.gpkg"
    rep = shade(config(dem, tmp_path / "day.tif", vec, sun={"time": TIMES}))
    feats, _ = features(vec)
    assert set(feats[0][1]) == {"azimuth", "elevation", "time", "true_azimuth", "index"}
    assert sorted({p["index"] for _, p in feats}) == [0, 1, 2]
    for i, rec in enumerate(rep["times"]):
        band = read_band(tmp_path / "day.tif", i + 1)
        mine = [(g, p) for g, p in feats if p["index"] == i]
        assert mine and {p["time"] for _, p in mine} == {rec["time"]}
        for k in ("azimuth", "elevation", "true_azimuth"):
            assert all(p[k] == pytest.approx(rec[k], abs=1e-9) for _, p in mine), k
        np.testing.assert_array_equal(burnt(mine, band.shape), (band == 1).astype(np.uint8))
        per = rep["vector"]["times"][i]
        assert per["index"] == i and per["polygons"] == len(mine)
        assert per["area_m2"] == pytest.approx((band == 1).sum() * CELL)
    assert rep["vector"]["polygons"] == len(feats)


def test_polygons_only_leave_no_raster_and_windows_agree(tmp_path, dem):
    """Without OUTPUT the polygons come from a scratch raster beside them, removed after;
    in windows they are the same as in memory."""
    folder = tmp_path / "only"
    folder.mkdir()
    rep = shade(config(dem, None, folder / "a.fgb"))
    assert sorted(os.listdir(folder)) == ["a.fgb"] and rep["output"] is None
    shade(config(dem, tmp_path / "ref.tif", tmp_path / "ref.fgb"))
    shade(config(dem, None, folder / "w.fgb", window_size=(64, 64)))
    assert sorted(os.listdir(folder)) == ["a.fgb", "w.fgb"]
    ref = read_band(tmp_path / "ref.tif")
    for name in ("a.fgb", "w.fgb"):
        feats, _ = features(folder / name)
        np.testing.assert_array_equal(burnt(feats, ref.shape), (ref == 1).astype(np.uint8))


def test_classes_and_8_connectivity(tmp_path, dem):
    rep = shade(config(dem, tmp_path / "c.tif", tmp_path / "c.gpkg", kind="classes",
                       self_shadow=True, sun={"azimuth": 290.0, "elevation": 14.0}))
    cls = read_band(tmp_path / "c.tif")
    feats, _ = features(tmp_path / "c.gpkg")
    for v in (1, 2):
        mine = [(g, p) for g, p in feats if p["shadow_class"] == v]
        assert mine and sum(polygon_area(g) for g, _ in mine) == pytest.approx(
            (cls == v).sum() * CELL, rel=1e-12)
    assert "shadow_class" in rep["vector"]["fields"]
    four = shade(config(dem, None, tmp_path / "four.gpkg"))["vector"]
    eight = shade(config(dem, None, tmp_path / "eight.gpkg", vector_connectivity=8))["vector"]
    # (fewer polygons where shadows touch at corners only: tests/io/test_vector.py)
    assert eight["connectivity"] == 8 and 0 < eight["polygons"] <= four["polygons"]
    assert eight["area_m2"] == pytest.approx(four["area_m2"])


def test_the_summary_line_counts_the_polygons(tmp_path, dem):
    lines = []
    cfg = config(dem, tmp_path / "s.tif", tmp_path / "s.gpkg",
                 say=lambda kind, msg: lines.append((kind, msg)))
    cfg.run.quiet = False
    rep = shade(cfg)
    summary = [m for k, m in lines if k == "summary"][0]
    n = rep["vector"]["polygons"]
    assert f"; {n} shadow polygons (" in summary and f" m2) in {tmp_path / 's.gpkg'};" in summary
    lines.clear()
    cfg = config(dem, None, tmp_path / "t.gpkg", sun={"time": TIMES},
                 say=lambda kind, msg: lines.append((kind, msg)))
    cfg.run.quiet = False
    shade(cfg)
    summary = [m for k, m in lines if k == "summary"][0]
    assert summary.startswith(f"hillshade-rt: {tmp_path / 't.gpkg'}: 127x110, 3 suns")
    assert " a time); " in summary and " in " not in summary.split(";")[1]


def test_refusals_and_nothing_half_written(tmp_path, dem, monkeypatch):
    """The vector's path checked with the others before any work (an input, OUTPUT, an
    existing file without overwrite); --soft, hillshade, an unknown extension refused; a
    failure while polygons are written leaves neither them nor the scratch raster."""
    import rasterio.features
    cases = [(dict(vector_kw=tmp_path / "v.shp"), UsageProblem, "unknown vector format"),
             (dict(soft=True), UsageProblem, "not with --soft"),
             (dict(kind="hillshade"), UsageProblem, "not hillshade"),
             (dict(out=tmp_path / "x.gpkg", vector_kw=tmp_path / "x.gpkg"), UsageProblem,
              "--vector and OUTPUT name the same file"),
             (dict(vector_connectivity=6), UsageProblem, "4 or 8")]
    for kw, cls, msg in cases:
        vec = kw.pop("vector_kw", tmp_path / "v.gpkg")
        out = kw.pop("out", None)
        with pytest.raises(cls, match=msg):
            shade(config(dem, out, vec, **kw))
    (tmp_path / "old.gpkg").write_bytes(b"old")
    with pytest.raises(HillshadeError, match="old.gpkg: already exists"):
        shade(config(dem, tmp_path / "new.tif", tmp_path / "old.gpkg"))
    assert not (tmp_path / "new.tif").exists()          # refused before any work
    with pytest.raises(UsageProblem, match="--cog goes with a raster OUTPUT"):
        shade(config(dem, None, tmp_path / "v.gpkg", cog=True))

    def broken(*a, **k):
        raise RuntimeError("no room for polygons")
    monkeypatch.setattr(rasterio.features, "shapes", broken)
    with pytest.raises(HillshadeError, match="v.gpkg: cannot write \\(no room for polygons\\)"):
        shade(config(dem, None, tmp_path / "v.gpkg"))
    assert sorted(os.listdir(tmp_path)) == ["old.gpkg"]
    # replaced with overwrite
    monkeypatch.undo()
    rep = shade(config(dem, None, tmp_path / "old.gpkg", overwrite=True))
    assert rep["vector"]["polygons"] > 0 and (tmp_path / "old.gpkg").read_bytes()[:6] == b"SQLite"
