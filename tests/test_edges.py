"""Correct at the edges (issue 17): spacing up to and at the poles on any body, the curvature
radius the rays use, read-only heights."""

import json
import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.geometry import WGS84_A, WGS84_B, grid_from_transform, radius_in_azimuth
from conftest import data_path, fractal_terrain, write_geotiff

UTM32N = CRS.from_epsg(32632)


def test_report_gives_the_curvature_radius_the_rays_use(tmp_path, runner):
    """UTM 32N at 45 N, sun from the west: the rays use the east-west radius (the prime
    vertical, 6 388 838 m), not the north-south one (6 367 382 m) reported before."""
    z = fractal_terrain(200, 200, 3, relief=1500)
    # 45 N on the central meridian of zone 32 (9 E): northing 4 984 944
    dem = write_geotiff(tmp_path / "alps.tif", z, Affine(30, 0, 497000, 0, -30, 4987944), UTM32N)
    for az, want in ((270.0, radius_in_azimuth(45.0, 270.0)), (0.0, radius_in_azimuth(45.0, 0.0))):
        rep = tmp_path / f"r{az:g}.json"
        r = runner.invoke(cli, ["shadow", dem, str(tmp_path / f"m{az:g}.tif"), "--azimuth",
                                str(az), "--elevation", "5", "--earth-curvature", "-q",
                                "--report", str(rep)])
        assert r.exit_code == 0, r.output
        got = json.loads(rep.read_text())["curvature"]
        assert got["applied"] is True
        assert got["radius_m"] == pytest.approx(want, abs=30.0)
    assert radius_in_azimuth(45.0, 270.0) - radius_in_azimuth(45.0, 0.0) > 20000


def test_series_reports_the_mean_radius_and_its_range(tmp_path, runner):
    z = fractal_terrain(120, 120, 4, relief=1500)
    dem = write_geotiff(tmp_path / "alps.tif", z, Affine(30, 0, 497000, 0, -30, 4987944), UTM32N)
    rep = tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "m.tif"), "--start",
                            "2026-06-21T06:00+02:00", "--end", "2026-06-21T20:00+02:00", "--step",
                            "2h", "--earth-curvature", "-q", "--report", str(rep)])
    assert r.exit_code == 0, r.output
    got = json.loads(rep.read_text())["curvature"]
    lo, hi = got["radius_m_range"]
    assert radius_in_azimuth(45.0, 0.0) - 30 < lo < hi < radius_in_azimuth(45.0, 90.0) + 30
    assert lo <= got["radius_m"] <= hi
