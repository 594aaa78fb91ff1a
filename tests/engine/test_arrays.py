"""The array API (``hillshade_rt.engine.arrays``): the commands' results on arrays in memory."""

import json

import numpy as np
import pytest

import hillshade_rt as hr
from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band

SRTM = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")


@pytest.mark.slow
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


def test_flat_plane_horizon_is_zero_or_the_curvature_dip():
    """A flat plane 6 km across: flat model, every horizon with terrain ahead is 0; with the
    Earth's curvature (and refraction k = 0.13) the nearest sample is the horizon, the ground
    there lying d²(1 - k)/2R below the observer: β = atan(-(1 - k) d / 2R), d = one step."""
    import math
    from hillshade_rt.engine.arrays import horizon_angles
    from hillshade_rt.model.earth import EARTH_MEAN_RADIUS
    z = np.zeros((200, 200), np.float32)
    az = 163.0
    flat = horizon_angles(z, az, 30.0, curvature=False)
    ahead = flat[2:-2, 2:-2]
    np.testing.assert_array_equal(ahead, 0.0)
    curved = horizon_angles(z, az, 30.0, curvature=True)
    d = 30.0 / abs(math.cos(math.radians(az)))    # rows dominate at 163 degrees
    want = math.degrees(math.atan(-(1 - 0.13) * d / (2 * EARTH_MEAN_RADIUS)))
    np.testing.assert_allclose(curved[2:-2, 2:-2], want, rtol=1e-4)
    assert want < 0


def test_height_above_ground_in_the_array_api_is_the_commands(tmp_path, runner):
    """shadow_mask, horizon_angles and sky_view take height_above_ground as the commands'
    --height-above-ground (a DEM from read_dem, its grid and body), and a higher observer
    sees no more shadow, no higher horizon, no less sky."""
    from hillshade_rt.engine.arrays import horizon_angles, shadow_mask, sky_view
    from hillshade_rt.io import read_dem
    dem = data_path("everest_srtm3_voids_crop200.tif")
    d = read_dem(dem)
    runs = {"shadow": (["--azimuth", "203.7", "--elevation", "12"],
                       lambda h: shadow_mask(d, 203.7, 12.0, height_above_ground=h)),
            "horizon": (["--azimuth", "163"],
                        lambda h: horizon_angles(d, 163.0, height_above_ground=h)),
            "skyview": (["--directions", "8"],
                        lambda h: sky_view(d, directions=8, height_above_ground=h))}
    got = {}
    for cmd, (args, fn) in runs.items():
        out = tmp_path / f"{cmd}.tif"
        r = runner.invoke(cli, [cmd, dem, str(out), "--height-above-ground", "5"] + args)
        assert r.exit_code == 0, r.output
        a = fn(5.0)
        b = read_band(out)
        if a.dtype != np.uint8:
            a = np.where(np.isnan(a), np.float32(-9999.0), a)
        np.testing.assert_array_equal(a, b)
        got[cmd] = (fn(0.0), a)
    (m0, m5), (h0, h5), (s0, s5) = got["shadow"], got["horizon"], got["skyview"]
    ok = m0 != 255
    assert (m5[ok] <= m0[ok]).all() and (m5[ok] < m0[ok]).any()
    ok = np.isfinite(h0) & (h0 > -90)
    assert (h5[ok] <= h0[ok]).all()
    ok = np.isfinite(s0)
    assert (s5[ok] >= s0[ok]).all()
    with pytest.raises(Exception, match="height_above_ground"):
        horizon_angles(d, 10.0, height_above_ground=-1.0)
