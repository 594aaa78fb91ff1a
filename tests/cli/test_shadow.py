"""``hillshade-rt shadow``'s own options: --vector (shadow polygons beside OUTPUT or instead of
it) and --vector-connectivity; the forms without them unchanged."""

import json
import os

import numpy as np
import pytest

from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
SUN = ["--azimuth", "203.7", "--elevation", "9"]


def read_layer(path):
    import fiona
    with fiona.open(path) as src:
        return [dict(f.properties) for f in src], src.crs


def test_vector_beside_output_and_instead_of_it(tmp_path, runner):
    out, vec, rep = tmp_path / "m.tif", tmp_path / "m.geojson", tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", LIDAR, str(out), *SUN, "--vector", str(vec),
                            "--report", str(rep)])
    assert r.exit_code == 0, r.output
    doc = json.loads(rep.read_text())
    props, crs = read_layer(vec)
    assert doc["vector"]["polygons"] == len(props) > 0 and str(crs) == "EPSG:26915"
    import rasterio
    with rasterio.open(out) as ds:
        mask, cell = ds.read(1), abs(ds.transform.a * ds.transform.e)
    assert doc["vector"]["area_m2"] == pytest.approx((mask == 1).sum() * cell, rel=1e-9)
    assert f"{len(props)} shadow polygons (" in r.stderr and f"in {vec}" in r.stderr
    # polygons only: one path is the DEM, nothing else written
    only = tmp_path / "only"
    only.mkdir()
    r = runner.invoke(cli, ["shadow", LIDAR, *SUN, "--vector", str(only / "s.gpkg"), "-q"])
    assert r.exit_code == 0, r.output
    assert os.listdir(only) == ["s.gpkg"] and len(read_layer(only / "s.gpkg")[0]) == len(props)
    r = runner.invoke(cli, ["shadow", LIDAR, *SUN, "--vector", str(only / "e.fgb"),
                            "--vector-connectivity", "8", "-q"])
    assert r.exit_code == 0, r.output
    assert 0 < len(read_layer(only / "e.fgb")[0]) <= len(props)


def test_vector_usage_errors_are_one_line(tmp_path, runner):
    """An unknown extension, a missing OUTPUT without --vector (as before), --vector with
    --each or --soft: exit status 2, one line, nothing written."""
    out = str(tmp_path / "m.tif")
    cases = [(["shadow", LIDAR, out, *SUN, "--vector", str(tmp_path / "s.shp")],
              "unknown vector format '.shp'"),
             (["shadow", LIDAR, *SUN], "give OUTPUT or --output-pattern"),
             (["shadow", LIDAR, *SUN, "--each", "--output-pattern",
               str(tmp_path / "{stem}.tif"), "--vector", str(tmp_path / "s.gpkg")],
              "--each and --vector do not go together"),
             (["shadow", LIDAR, out, *SUN, "--soft", "--vector", str(tmp_path / "s.gpkg")],
              "not with --soft"),
             (["shadow", LIDAR, *SUN, "--vector", str(tmp_path / "s.gpkg"), "-f", "PNG"],
              "-f/--format goes with a raster OUTPUT"),
             (["shadow", LIDAR, out, *SUN, "--vector", str(tmp_path / "s.gpkg"),
               "--report", str(tmp_path / "s.gpkg")], "name the same file"),
             (["shadow", LIDAR, *SUN, "--vector", str(tmp_path / "s.gpkg"),
               "--vector-connectivity", "6"], "'6' is not one of '4', '8'"),
             (["shadow", LIDAR, "--light-position", "500,500,900", "--vector",
               str(tmp_path / "s.gpkg")], "a point light does not take --vector")]
    for args, words in cases:
        r = runner.invoke(cli, args)
        assert r.exit_code == 2, (args, r.output)
        assert words in r.stderr, (args, r.stderr)
        assert len(r.stderr.strip().splitlines()) <= 3, r.stderr     # click's usage lines
    assert os.listdir(tmp_path) == []


def test_an_existing_vector_is_kept_without_overwrite(tmp_path, runner):
    vec = tmp_path / "s.gpkg"
    vec.write_bytes(b"keep")
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.tif"), *SUN, "--vector",
                            str(vec)])
    assert r.exit_code == 1 and "s.gpkg: already exists (use --overwrite" in r.stderr
    assert vec.read_bytes() == b"keep" and sorted(os.listdir(tmp_path)) == ["s.gpkg"]
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.tif"), *SUN, "--vector",
                            str(vec), "--overwrite", "-q"])
    assert r.exit_code == 0 and vec.read_bytes()[:6] == b"SQLite"
    assert np.isin(read_band(tmp_path / "m.tif"), [0, 1, 255]).all()
