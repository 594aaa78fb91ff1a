"""``hillshade-rt skyview`` (issue 20, item 3): the sky view factor from the exact horizon, two
definitions, checked on planes where both are known in closed form."""

import math

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band, write_geotiff

FLAT = ["--no-earth-curvature"]


def _plane(tmp_path, slope_deg, rows=40, cols=44, d=10.0):
    """A plane rising northward at ``slope_deg`` (its downslope aspect: south)."""
    s = math.tan(math.radians(slope_deg))
    z = ((rows - 1 - np.arange(rows))[:, None] * d * s + np.zeros((1, cols))).astype(np.float32)
    return write_geotiff(tmp_path / f"plane{slope_deg}.tif", z,
                         Affine(d, 0, 500000, 0, -d, 4000000), CRS.from_epsg(32633))


def _expected(slope_deg, n, definition):
    """The definitions' sums over the same n directions for a plane rising north: the horizon
    toward φ is atan(tan S cos φ), clipped at the horizontal."""
    S = math.radians(slope_deg)
    phi = np.radians(360.0 * np.arange(n) / n)
    g = np.maximum(np.arctan(math.tan(S) * np.cos(phi)), 0.0)
    if definition == "zaksek":
        return 1.0 - np.mean(np.sin(g))
    h = np.pi / 2 - g
    sc = -math.sin(S) * np.cos(phi)        # sin S cos(φ - A), aspect A = 180 (south)
    return np.mean(math.cos(S) * np.sin(h) ** 2 + sc * (h - np.sin(h) * np.cos(h)))


@pytest.mark.parametrize("definition", ["zaksek", "dozier"])
def test_planes_give_the_closed_forms(tmp_path, runner, definition):
    """A flat plane: 1; a plane of slope S: the definition's sum over the same directions (and
    near its continuous form: 1 - S/π for Zakšek, (1 + cos S)/2 for Dozier) in every cell with
    terrain in every direction (the border sees open sky outward)."""
    for slope in (0.0, 20.0):
        out = tmp_path / f"svf{slope}.tif"
        r = runner.invoke(cli, ["skyview", _plane(tmp_path, slope), str(out), "--directions",
                                "36", "--definition", definition, "--pixel-size", "10"] + FLAT)
        assert r.exit_code == 0, r.output
        svf = read_band(out)[1:-1, 1:-1]
        want = _expected(slope, 36, definition)
        np.testing.assert_allclose(svf, want, atol=2e-5)
        cont = (1 - math.radians(slope) / math.pi if definition == "zaksek"
                else (1 + math.cos(math.radians(slope))) / 2)
        assert want == pytest.approx(cont, abs=2e-3)


def test_terrain_configuration_is_the_rest_of_the_tilted_hemisphere(tmp_path, runner):
    """1 - Vd: on a plane of slope S, (1 - cos S)/2 in the continuous limit, the Dozier sum's
    complement over the same directions cell for cell; it needs --definition dozier."""
    out = tmp_path / "ct.tif"
    dem = _plane(tmp_path, 30.0)
    r = runner.invoke(cli, ["skyview", dem, str(out), "--directions", "36", "--definition",
                            "dozier", "--terrain-configuration", "--pixel-size", "10"] + FLAT)
    assert r.exit_code == 0, r.output
    ct = read_band(out)[1:-1, 1:-1]
    np.testing.assert_allclose(ct, 1.0 - _expected(30.0, 36, "dozier"), atol=2e-5)
    assert ct.mean() == pytest.approx((1 - math.cos(math.radians(30.0))) / 2, abs=2e-3)
    r = runner.invoke(cli, ["skyview", dem, str(tmp_path / "x.tif"), "--terrain-configuration"])
    assert r.exit_code == 2 and "--definition dozier" in r.stderr


def test_pits_see_less_sky_than_peaks_on_real_terrain(tmp_path, runner):
    """On a real DEM: values in (0, 1], and the cells lowest in their 5x5 neighbourhood (valley
    floors) see less sky than the highest (summits), by both definitions."""
    from numpy.lib.stride_tricks import sliding_window_view
    from hillshade_rt.io import read_dem
    dem = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")
    z = read_dem(dem).heights
    win = sliding_window_view(np.pad(z, 2, constant_values=np.nan), (5, 5))
    with np.errstate(invalid="ignore"):
        peak = z >= np.nanmax(win, axis=(2, 3))
        pit = z <= np.nanmin(win, axis=(2, 3))
    for definition in ("zaksek", "dozier"):
        out = tmp_path / f"{definition}.tif"
        r = runner.invoke(cli, ["skyview", dem, str(out), "--directions", "16",
                                "--definition", definition])
        assert r.exit_code == 0, r.output
        svf = read_band(out)
        ok = (svf != -9999.0) & ~np.isnan(z)
        assert (svf[ok] > 0.3).all() and (svf[ok] <= 1.0 + 1e-6).all()
        assert peak[ok].sum() > 20 and pit[ok].sum() > 20
        assert svf[ok & pit].mean() < svf[ok & peak].mean() - 0.01, definition


@pytest.mark.parametrize("args, words", [(["--directions", "2"], "4<=x<=360"),
                                         (["--definition", "rvt"], "--definition")])
def test_bad_options_are_usage_errors(tmp_path, runner, args, words):
    out = tmp_path / "s.tif"
    r = runner.invoke(cli, ["skyview", data_path("jacksboro_fault_srtm3_mpl_403x344.tif"),
                            str(out)] + args)
    assert r.exit_code == 2 and words in r.stderr and not out.exists()
