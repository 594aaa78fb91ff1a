"""hillshade_rt.xarray's accessor: ``da.hrt``'s products against the command line's GeoTIFFs
read back with rioxarray (coordinates, CRS, attributes), a series of times as a dimension, the
sun's errors, the imports the command line is spared, the docs' example."""

from __future__ import annotations

import numpy as np
import pytest
import rioxarray           # the `xarray` extra, in `test`

import hillshade_rt.xarray  # noqa: F401 -- registers da.hrt
from hillshade_rt import HillshadeError
from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")      # UTM 15N, 1 m, 31 m of relief
EVEREST = data_path("everest_srtm3_voids_crop200.tif")    # EPSG:4326, voids (-32768)


def cli(*args):
    from click.testing import CliRunner

    from hillshade_rt.cli import cli as main
    r = CliRunner().invoke(main, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return rioxarray.open_rasterio(args[2])


def same_place(out, ref):
    """The same cells, coordinates, CRS and transform as the GeoTIFF ``ref``."""
    assert out.dims[-2:] == ("y", "x")
    np.testing.assert_array_equal(out.x.values, ref.x.values)
    np.testing.assert_array_equal(out.y.values, ref.y.values)
    assert out.rio.crs == ref.rio.crs
    assert out.rio.transform() == ref.rio.transform()


@pytest.mark.parametrize("dem, azimuth, elevation", [
    (LIDAR, 163.0, 8.0), (LIDAR, 203.7, 12.0), (EVEREST, 290.0, 25.0), (EVEREST, 203.7, 12.0)])
def test_shadow_equals_the_command_line(tmp_path, dem, azimuth, elevation):
    ref = cli("shadow", dem, tmp_path / "cli.tif", "--azimuth", azimuth, "--elevation", elevation)
    da = rioxarray.open_rasterio(dem)
    out = da.hrt.shadow(azimuth=azimuth, elevation=elevation)
    same_place(out, ref)
    assert out.dtype == np.uint8 and out.rio.nodata == 255
    np.testing.assert_array_equal(out.values, ref.values[0])
    assert 0.02 < float((out.values == 1).mean()) < 0.98     # shadows and light both
    assert out.attrs["sun_azimuth"] == pytest.approx(azimuth)
    assert out.attrs["sun_elevation"] == pytest.approx(elevation)
    assert out.attrs["product"] == "shadow" and out.attrs["algorithm"] == "auto"
    assert out.attrs["values"] == ref.attrs["VALUES"]
    if dem == EVEREST:        # the voids (the file's nodata) are nodata
        assert ((out.values == 255) == (da.values[0] == -32768)).all()
        assert (out.values == 255).sum() > 1000


TIMES = ["2026-06-21T03:00:00+00:00", "2026-06-21T09:30:00+00:00",
         "2026-06-21T18:00:00+00:00"]      # Everest: morning, afternoon, night


@pytest.mark.slow
def test_time_series_is_a_time_dimension_equal_to_the_command_line(tmp_path):
    args = [a for t in TIMES for a in ("--time", t)]
    ref = cli("shadow", EVEREST, tmp_path / "cli.tif", *args)
    out = rioxarray.open_rasterio(EVEREST).hrt.shadow(time=TIMES)
    assert out.dims == ("time", "y", "x") and out.sizes["time"] == 3
    same_place(out, ref)
    np.testing.assert_array_equal(out.values, ref.values)
    assert list(out.time.values) == [np.datetime64(t[:19], "ns") for t in TIMES]
    night = out.sun_elevation.values <= 0
    assert night.tolist() == [False, False, True]
    assert (out.values[2] != 0).all()            # night: no cell lit
    assert out.attrs["sun_site"].endswith("(the DEM's centre)")
    # xarray's times (naive datetime64: UTC) and aware datetimes: the same suns
    import datetime as dt
    utc = out.time.values
    again = rioxarray.open_rasterio(EVEREST).hrt.shadow(time=utc)
    np.testing.assert_array_equal(again.values, out.values)
    aware = [dt.datetime.fromisoformat(t) for t in TIMES[:2]]
    np.testing.assert_array_equal(
        rioxarray.open_rasterio(EVEREST).hrt.shadow(time=aware).values, out.values[:2])
    # one time: no time dimension, the time as a scalar coordinate and in the attributes
    one = rioxarray.open_rasterio(EVEREST).hrt.shadow(time=TIMES[1])
    assert one.dims == ("y", "x")
    np.testing.assert_array_equal(one.values, out.values[1])
    assert one.attrs["time"].startswith("2026-06-21T09:30")
    assert one.attrs["sun_azimuth"] == pytest.approx(float(out.sun_azimuth[1]))


@pytest.mark.slow
def test_horizon_skyview_and_sun_hours_equal_the_command_line(tmp_path):
    da = rioxarray.open_rasterio(EVEREST)
    void = da.values[0] == -32768
    ref = cli("horizon", EVEREST, tmp_path / "h.tif", "--azimuth", 203.7)
    out = da.hrt.horizon(203.7)
    same_place(out, ref)
    np.testing.assert_array_equal(np.where(void, -9999.0, out.values), ref.values[0])
    assert np.isnan(out.values[void]).all() and out.attrs["azimuth"] == pytest.approx(203.7)
    two = da.hrt.horizon([203.7, 20.0])
    assert two.dims == ("azimuth", "y", "x")
    np.testing.assert_array_equal(two.values[0], out.values)

    ref = cli("skyview", EVEREST, tmp_path / "s.tif", "--directions", 8)
    out = da.hrt.skyview(directions=8)
    same_place(out, ref)
    np.testing.assert_allclose(np.where(void, -9999.0, out.values), ref.values[0], rtol=0,
                               atol=0)
    assert 0.3 < float(np.nanmean(out.values)) < 1.0

    ref = cli("sun-hours", EVEREST, tmp_path / "h.tif", "--date", "2026-06-21", "--step", "2h",
              "--overwrite")
    out = da.hrt.sun_hours(date="2026-06-21", step="2h")
    same_place(out, ref)
    np.testing.assert_array_equal(np.where(void, -9999.0, out.values), ref.values[0])
    assert float(np.nanmax(out.values)) > 8.0 and out.attrs["units"] == "hours of direct sun"


def test_sun_and_algorithm_errors_are_one_clear_message():
    da = rioxarray.open_rasterio(LIDAR)
    with pytest.raises(HillshadeError, match="one way"):
        da.hrt.shadow(azimuth=163, elevation=8, time="2026-06-21T12:00Z")
    with pytest.raises(HillshadeError, match="^no sun given"):
        da.hrt.shadow()
    with pytest.raises(HillshadeError, match="^azimuth and elevation go together"):
        da.hrt.shadow(azimuth=163)
    with pytest.raises(HillshadeError, match="no UTC offset"):
        da.hrt.shadow(time="2026-06-21T12:00")
    with pytest.raises(HillshadeError, match="algorithm"):
        da.hrt.shadow(azimuth=163, elevation=8, algorithm="nope")


def test_the_command_line_and_the_api_do_not_import_xarray():
    """xarray and rioxarray are imported by ``hillshade_rt.xarray`` only: the command line's
    start-up does not pay for them."""
    import subprocess
    import sys
    code = ("import sys, hillshade_rt, hillshade_rt.cli, hillshade_rt.api, hillshade_rt.engine.arrays\n"
            "print(sorted(m for m in ('xarray', 'rioxarray') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"
    code = ("import sys, hillshade_rt.xarray, xarray\n"
            "print(hasattr(xarray.DataArray([[1.0]], dims=('y', 'x')), 'hrt'))")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True).stdout.strip() == "True"


@pytest.mark.slow
def test_the_docs_example_runs(tmp_path, monkeypatch):
    """docs/usage.md, "In xarray": its example, run from the repository's root as it says
    (the GeoTIFF it writes goes to a temporary folder here)."""
    import os
    import re

    from hillshade_rt.testing import repo_root
    text = open(os.path.join(repo_root(), "docs", "usage.md"), encoding="utf-8").read()
    section = text.split("## In xarray", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    code = code.replace('"examples/', '"' + os.path.join(repo_root(), "examples", ""))
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    exec(compile(code, "usage.md", "exec"), scope)
    written = rioxarray.open_rasterio(tmp_path / "sun_hours.tif")
    assert written.rio.crs == scope["dem"].rio.crs
    assert float(written.max()) > 10.0 and scope["day"].sizes["time"] == 2
