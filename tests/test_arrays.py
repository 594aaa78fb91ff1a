"""The array API (``hillshade_rt.arrays``): the commands' results on arrays in memory."""

import json

import numpy as np
import pytest

import hillshade_rt as hr
from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band

SRTM = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")


def test_sky_view_is_the_commands(tmp_path, runner):
    out = tmp_path / "s.tif"
    for definition in ("zaksek", "dozier"):
        r = runner.invoke(cli, ["skyview", SRTM, str(out), "--directions", "12", "--definition",
                                definition, "--overwrite"])
        assert r.exit_code == 0, r.output
        d = hr.read_dem(SRTM)
        svf = hr.sky_view(d, directions=12, definition=definition)
        want = read_band(out)
        np.testing.assert_array_equal(np.where(np.isnan(svf), -9999.0, svf), want)
    with pytest.raises(hr.HillshadeError, match="definition"):
        hr.sky_view(d, definition="rvt")


def test_horizon_profile_is_the_commands(runner):
    d = hr.read_dem(SRTM)
    x, y = d.transform @ (40.25 + 0.5, 77.6 + 0.5)
    r = runner.invoke(cli, ["profile", SRTM, "--at-xy", f"{x!r},{y!r}", "--step", "15",
                            "--height-above-ground", "3", "--format", "json"])
    assert r.exit_code == 0, r.output
    p = json.loads(r.stdout)["points"][0]
    az, ang, dist = hr.horizon_profile(d, [77.6], [40.25], height_above_ground=3.0, step=15)
    assert list(az) == p["azimuth"]
    np.testing.assert_allclose(ang[0], p["horizon_deg"], atol=1e-6)
    np.testing.assert_allclose(np.nan_to_num(dist[0], nan=-1), [-1 if v is None else v
                                                                for v in p["distance_m"]],
                               atol=1e-3)
    with pytest.raises(hr.HillshadeError, match="outside"):
        hr.horizon_profile(d, [-3.0], [4.0])
