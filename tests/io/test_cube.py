"""Time cubes (io.cube): a (time, y, x) stack as a CF-1.8 NetCDF4 file or a Zarr store that
xarray decodes (times as datetime64) and rioxarray georeferences, written whole or not at all."""

import datetime as dt
import os
from types import SimpleNamespace
from zoneinfo import ZoneInfo

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError
from hillshade_rt.io import cube
from hillshade_rt.io import write as writes

xr = pytest.importorskip("xarray")
pytest.importorskip("rioxarray")

UTM = CRS.from_epsg(32615)
ZONE = ZoneInfo("America/Chicago")
TIMES = [dt.datetime(2026, 6, 21, h, m, tzinfo=ZONE) for h, m in ((9, 0), (10, 30), (16, 45))]
AZ, EL = [163.0, 203.7, 290.0], [40.5, 61.25, 12.0]


def _grid(rows=37, cols=53, crs=UTM, transform=Affine(2.0, 0, 500000.0, 0, -3.0, 4200000.0)):
    return SimpleNamespace(shape=(rows, cols), crs=crs, transform=transform)


def _stack(rows=37, cols=53, dtype=np.uint8):
    rng = np.random.default_rng(7)
    if dtype == np.uint8:
        a = rng.integers(0, 2, (len(TIMES), rows, cols)).astype(np.uint8)
        a[:, :3, :4] = 255
        return a
    a = rng.random((len(TIMES), rows, cols)).astype(np.float32)
    a[:, -2:, -5:] = -9999.0
    return a


def _write(path, data, grid=None, **kw):
    kw.setdefault("nodata", 255 if data.dtype == np.uint8 else -9999.0)
    return cube.write_cube(
        path, data, grid or _grid(*data.shape[1:]), TIMES, name="shadow",
        attrs={"long_name": "cast shadow"},
        time_variables={"azimuth": (AZ, {"units": "degree"}),
                        "elevation": (EL, {"units": "degree"})},
        global_attrs={"title": "a test", "history": "pytest", "source": "hillshade-rt"}, **kw)


def _utc64(times):
    return np.array([t.astimezone(dt.timezone.utc).replace(tzinfo=None) for t in times],
                    "datetime64[ns]")


def _open(path):
    if str(path).endswith(".zarr"):
        return xr.open_zarr(path)
    return xr.open_dataset(path)


def test_cube_format_by_name():
    assert cube.cube_format("a/b.NC") == "netcdf" and cube.cube_format("s.zarr/") == "zarr"
    assert cube.cube_format("x.tif") is None and cube.cube_format(None) is None


FORMATS = ["out.nc", pytest.param("out.zarr", marks=pytest.mark.skipif(
    __import__("importlib").util.find_spec("zarr") is None, reason="zarr not installed"))]


@pytest.mark.parametrize("name", FORMATS)
def test_cube_decodes_times_values_crs_and_suns(tmp_path, name):
    data = _stack()
    path = tmp_path / name
    _write(path, data)
    with _open(path) as ds:
        assert ds.attrs["Conventions"] == "CF-1.8" and ds.attrs["title"] == "a test"
        assert ds["shadow"].dims == ("time", "y", "x")
        assert ds["time"].dtype.kind == "M"
        np.testing.assert_array_equal(ds["time"].values, _utc64(TIMES))
        # the values as written, nodata masked by _FillValue when decoded
        raw = ds["shadow"].values
        np.testing.assert_array_equal(np.isnan(raw), data == 255)
        np.testing.assert_array_equal(raw[data != 255], data[data != 255])
        assert ds["shadow"].encoding["_FillValue"] == 255
        np.testing.assert_array_equal(ds["azimuth"].values, AZ)
        np.testing.assert_array_equal(ds["elevation"].values, EL)
        # cell centres; CF names; the CRS through the grid mapping, as rioxarray finds it
        np.testing.assert_allclose(ds["x"].values, 500000.0 + 2.0 * (np.arange(53) + 0.5))
        np.testing.assert_allclose(ds["y"].values, 4200000.0 - 3.0 * (np.arange(37) + 0.5))
        assert ds["x"].attrs["standard_name"] == "projection_x_coordinate"
        assert ds["y"].attrs["standard_name"] == "projection_y_coordinate"
        assert ds["x"].attrs["units"] == "m"
        assert ds["shadow"].encoding.get("grid_mapping", ds["shadow"].attrs.get(
            "grid_mapping")) == "spatial_ref"
        assert ds.rio.crs == UTM and ds["shadow"].rio.crs == UTM
        gt = [float(v) for v in ds["spatial_ref"].attrs["GeoTransform"].split()]
        assert gt == [500000.0, 2.0, 0.0, 4200000.0, 0.0, -3.0]
        assert ds["spatial_ref"].attrs["grid_mapping_name"] == "transverse_mercator"
        assert tuple(ds.rio.transform())[:6] == (2.0, 0.0, 500000.0, 0.0, -3.0, 4200000.0)
    with xr.open_dataset(path, mask_and_scale=False, engine="zarr" if name.endswith(".zarr")
                         else None) as ds:
        assert ds["shadow"].dtype == np.uint8
        np.testing.assert_array_equal(ds["shadow"].values, data)      # bit for bit


def test_netcdf_chunks_a_time_step_each_and_compresses(tmp_path):
    netCDF4 = pytest.importorskip("netCDF4")
    path = tmp_path / "c.nc"
    _write(path, _stack(300, 1500), _grid(300, 1500))
    with netCDF4.Dataset(path) as nc:
        v = nc["shadow"]
        assert v.chunking() == [1, 300, 1024]
        f = v.filters()
        assert f["zlib"] and f["shuffle"] and f["complevel"] == cube.ZLIB_LEVEL
        assert nc["time"].units == "seconds since 1970-01-01 00:00:00"
        assert nc["time"].calendar == "standard"
        assert nc.data_model == "NETCDF4"


def test_windows_of_a_time_step(tmp_path):
    data = _stack(dtype=np.float32)
    grid = _grid()
    path = tmp_path / "w.nc"
    with cube.CubeWriter(path, grid, TIMES, name="f", dtype="float32", nodata=-9999.0) as w:
        for i in range(len(TIMES)):
            for r0, r1 in ((0, 20), (20, 37)):
                for c0, c1 in ((0, 30), (30, 53)):
                    w.write(i + 1, data[i, r0:r1, c0:c1], window=(r0, r1, c0, c1))
    with xr.open_dataset(path, mask_and_scale=False) as ds:
        np.testing.assert_array_equal(ds["f"].values, data)


def test_geographic_grid_and_sub_second_times(tmp_path):
    grid = _grid(10, 12, CRS.from_epsg(4326), Affine(0.001, 0, 7.5, 0, -0.001, 46.2))
    times = [dt.datetime(2026, 3, 1, 12, 0, 0, 250000, tzinfo=dt.timezone.utc),
             dt.datetime(2026, 3, 1, 12, 0, 1, tzinfo=dt.timezone.utc)]
    path = tmp_path / "g.nc"
    cube.write_cube(path, np.zeros((2, 10, 12), np.float32), grid, times, name="v")
    with xr.open_dataset(path) as ds:
        assert ds["x"].attrs["standard_name"] == "longitude"
        assert ds["x"].attrs["units"] == "degrees_east"
        assert ds["y"].attrs["units"] == "degrees_north"
        assert ds.rio.crs == CRS.from_epsg(4326)
        np.testing.assert_array_equal(ds["time"].values, _utc64(times))
        assert ds["time"].encoding["units"].startswith("microseconds since 1970")


def test_no_georeferencing_no_grid_mapping(tmp_path):
    path = tmp_path / "n.nc"
    cube.write_cube(path, np.ones((1, 3, 4), np.uint8), _grid(3, 4, None, None), TIMES[:1],
                    name="v")
    with xr.open_dataset(path) as ds:
        assert "spatial_ref" not in ds.variables
        np.testing.assert_array_equal(ds["x"].values, [0.5, 1.5, 2.5, 3.5])


def test_rotated_grid_and_bad_shapes_refused(tmp_path):
    with pytest.raises(HillshadeError, match="rotated"):
        cube.write_cube(tmp_path / "r.nc", np.zeros((1, 3, 4), np.uint8),
                        _grid(3, 4, UTM, Affine(1, 0.2, 0, 0, -1, 0)), TIMES[:1], name="v")
    with pytest.raises(ValueError, match="time"):
        cube.write_cube(tmp_path / "r.nc", np.zeros((2, 3, 4), np.uint8), _grid(3, 4),
                        TIMES, name="v")
    with pytest.raises(ValueError, match="azimuth"):
        cube.write_cube(tmp_path / "r.nc", np.zeros((3, 3, 4), np.uint8), _grid(3, 4),
                        TIMES, name="v", time_variables={"azimuth": ([1.0], {})})
    with pytest.raises(HillshadeError, match="local file"):
        cube.write_cube("/vsimem/c.nc", np.zeros((1, 3, 4), np.uint8), _grid(3, 4), TIMES[:1],
                        name="v")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("name", FORMATS)
def test_exists_refused_without_overwrite_replaced_with_it(tmp_path, name):
    path = tmp_path / name
    _write(path, _stack())
    with pytest.raises(HillshadeError, match="already exists"):
        _write(path, _stack())
    data = _stack()
    data[:] = 0
    _write(path, data, overwrite=True)
    with _open(path) as ds:
        assert float(ds["shadow"].max()) == 0.0
    assert os.listdir(tmp_path) == [name]       # no temporary left, no old store


def test_a_folder_that_is_no_zarr_store_is_not_replaced(tmp_path):
    pytest.importorskip("zarr")
    path = tmp_path / "mine.zarr"
    path.mkdir()
    (path / "notes.txt").write_text("keep me")
    with pytest.raises(HillshadeError, match="no Zarr store"):
        _write(path, _stack(), overwrite=True)
    assert (path / "notes.txt").read_text() == "keep me"


@pytest.mark.parametrize("name", FORMATS)
def test_a_failure_while_writing_leaves_nothing(tmp_path, name):
    path = tmp_path / name
    with pytest.raises(RuntimeError, match="stop"):
        with cube.CubeWriter(path, _grid(), TIMES, name="v", dtype="uint8", nodata=255) as w:
            w.write(1, _stack()[0])
            raise RuntimeError("stop")
    assert os.listdir(tmp_path) == []


class _Failing:
    def __setitem__(self, key, value):
        raise RuntimeError("NetCDF: HDF error")


@pytest.mark.parametrize("full", [True, False])
def test_a_write_error_is_one_line_and_leaves_nothing(tmp_path, monkeypatch, full):
    path = tmp_path / "e.nc"
    said = r"no space left on device" if full else r"NetCDF: HDF error"
    with pytest.raises(HillshadeError, match=rf"e\.nc: cannot write \({said}\)"):
        with cube.CubeWriter(path, _grid(), TIMES, name="v", dtype="uint8", nodata=255) as w:
            monkeypatch.setattr(cube, "disk_full", lambda p: full)
            w._vars["v"] = _Failing()
            w.write(1, np.zeros((37, 53), np.uint8))
    assert os.listdir(tmp_path) == []


def test_an_interruption_at_publish_leaves_nothing(tmp_path, monkeypatch):
    from hillshade_rt.errors import Interrupted

    def interrupted(*a, **k):
        raise Interrupted(2)
    monkeypatch.setattr(writes, "publish", interrupted)
    with pytest.raises(Interrupted):
        _write(tmp_path / "i.nc", _stack())
    assert os.listdir(tmp_path) == []


def test_output_path_check_knows_zarr_stores(tmp_path):
    pytest.importorskip("zarr")
    path = tmp_path / "s.zarr"
    _write(path, _stack())
    with pytest.raises(HillshadeError, match="already exists"):
        writes.check_output_path(str(path), False)
    assert writes.check_output_path(str(path), True) == str(path)
    (tmp_path / "f.zarr").mkdir()
    with pytest.raises(HillshadeError, match="no Zarr store"):
        writes.check_output_path(str(tmp_path / "f.zarr"), True)
    (tmp_path / "d").mkdir()
    with pytest.raises(HillshadeError, match="is a folder"):
        writes.check_output_path(str(tmp_path / "d"), True)


def test_the_zarr_folders_of_dead_runs_are_swept(tmp_path):
    tag = writes.owner_tag()
    pid, rest = tag.split("-", 1)
    start = rest.split("-", 1)[0]
    other = f"{pid}-{int(start) + 1}-{rest.split('-', 1)[1]}"       # the pid reused
    reused = tmp_path / f".s.zarr.abcdefgh~{other}.part.zarr"
    mine = tmp_path / f".t.zarr.abcdefgh~{tag}.part.zarr"
    for f in (reused, mine):
        f.mkdir()
        (f / "zarr.json").write_text("{}")
    writes.reset()
    _write(tmp_path / "n.nc", _stack())
    assert not reused.exists() and mine.exists()        # dead (pid reused); alive



def test_zarr_without_its_libraries_names_the_extra(tmp_path, monkeypatch):
    import importlib.util
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "zarr" else real(name, *a))
    with pytest.raises(HillshadeError, match=r"pip install 'hillshade-rt\[xarray\]'"):
        _write(tmp_path / "s.zarr", _stack())
    assert cube.check_cube_support(tmp_path / "s.nc") == "netcdf"
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
@pytest.mark.parametrize("name", FORMATS)
def test_a_signal_leaves_no_half_written_cube(tmp_path, name):
    """SIGTERM while a long series is written into a cube: exit 143, one line, nothing left
    (the temporary file or folder removed)."""
    import signal
    import subprocess
    import sys
    import time

    from hillshade_rt.testing import fractal_terrain, write_geotiff
    dem = write_geotiff(tmp_path / "big.tif", fractal_terrain(900, 900, 7, relief=1500),
                        Affine(10, 0, 400000, 0, -10, 3800000), CRS.from_epsg(32611))
    out = tmp_path / "out"
    out.mkdir()
    p = subprocess.Popen([sys.executable, "-m", "hillshade_rt", "shadow", dem, str(out / name),
                          "--algorithm", "brute", "--start", "2026-06-21T06:00-07:00", "--end",
                          "2026-06-21T19:00-07:00", "--step", "10min", "-q", "--threads", "1"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        t0 = time.time()
        while not any(".part" in n for n in os.listdir(out)):      # writing has begun
            assert time.time() - t0 < 120 and p.poll() is None, os.listdir(out)
            time.sleep(0.02)
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 143, err
    assert err.strip().count("\n") == 0 and "Traceback" not in err, err
    assert os.listdir(out) == [], os.listdir(out)


# -- several data variables on the same axes (the irradiance instants) ----------------------

VARIABLES = [cube.CubeVariable("beam_rad", "float32", -9999.0,
                               {"units": "W m-2", "long_name": "beam irradiance"}),
             cube.CubeVariable("incidout", "float32", -9999.0,
                               {"units": "degree", "long_name": "incidence"}),
             cube.CubeVariable("flags", "uint8", 255, {"long_name": "a mask"})]


def _three(rows=37, cols=53):
    """(beam, incidence, flags) stacks, each (time, rows, cols), different values, voids."""
    rng = np.random.default_rng(11)
    beam = (rng.random((len(TIMES), rows, cols)) * 900.0).astype(np.float32)
    beam[:, -2:, -5:] = -9999.0
    inc = (rng.random((len(TIMES), rows, cols)) * 180.0 - 90.0).astype(np.float32)
    inc[1, 4, 7] = -9999.0
    flags = rng.integers(0, 3, (len(TIMES), rows, cols)).astype(np.uint8)
    flags[:, 0, :] = 255
    return beam, inc, flags


@pytest.mark.parametrize("name", FORMATS)
def test_several_variables_each_with_its_type_fill_and_attrs(tmp_path, name):
    """Three data variables written in a GeoTIFF's band order (band 3k + j + 1: variable j at
    time k), windows included: each decodes on (time, y, x) with its own type, _FillValue,
    units and grid mapping; the per-time variables and the times as with one variable."""
    data = _three()
    path = tmp_path / name
    with cube.CubeWriter(path, _grid(), TIMES, variables=VARIABLES,
                         time_variables={"azimuth": (AZ, {"units": "degree"})},
                         global_attrs={"title": "instants"}) as w:
        for k in range(len(TIMES)):
            for j, stack in enumerate(data):
                if j == 1:      # in two windows
                    w.write(3 * k + j + 1, stack[k, :20], window=(0, 20, 0, 53))
                    w.write(3 * k + j + 1, stack[k, 20:], window=(20, 37, 0, 53))
                else:
                    w.write(3 * k + j + 1, stack[k])
    with _open(path) as ds:
        assert set(ds.data_vars) >= {"beam_rad", "incidout", "flags", "azimuth"}
        np.testing.assert_array_equal(ds["time"].values, _utc64(TIMES))
        np.testing.assert_array_equal(ds["azimuth"].values, AZ)
        for v, stack in zip(VARIABLES, data):
            da = ds[v.name]
            assert da.dims == ("time", "y", "x")
            assert da.attrs["long_name"] == v.attrs["long_name"]
            assert da.attrs.get("units") == v.attrs.get("units")
            assert da.encoding["_FillValue"] == v.nodata
            assert da.encoding.get("grid_mapping", da.attrs.get("grid_mapping")) == \
                "spatial_ref"
            assert da.rio.crs == UTM
            void = stack == v.nodata
            np.testing.assert_array_equal(np.isnan(da.values), void)
            np.testing.assert_array_equal(da.values[~void], stack[~void])
    with xr.open_dataset(path, mask_and_scale=False, engine="zarr" if name.endswith(".zarr")
                         else None) as ds:
        for v, stack in zip(VARIABLES, data):
            assert ds[v.name].dtype == np.dtype(v.dtype)
            np.testing.assert_array_equal(ds[v.name].values, stack)    # bit for bit


def test_several_variables_by_name_and_chunked_a_time_step_each(tmp_path):
    """write_variable names the variable and the time step (any order); NetCDF chunks each
    variable one time step per chunk, compressed."""
    netCDF4 = pytest.importorskip("netCDF4")
    data = _three(40, 1100)
    path = tmp_path / "n.nc"
    with cube.CubeWriter(path, _grid(40, 1100), TIMES, variables=VARIABLES) as w:
        for k in reversed(range(len(TIMES))):
            for v, stack in zip(reversed(VARIABLES), reversed(data)):
                w.write_variable(v.name, k + 1, stack[k])
    with netCDF4.Dataset(path) as nc:
        for v, stack in zip(VARIABLES, data):
            assert nc[v.name].chunking() == [1, 40, 1024]
            assert nc[v.name].filters()["zlib"]
            nc[v.name].set_auto_mask(False)
            np.testing.assert_array_equal(nc[v.name][:], stack)


def test_several_variables_bad_calls(tmp_path):
    grid = _grid(3, 4)
    with pytest.raises(ValueError, match="distinct names"):
        cube.CubeWriter(tmp_path / "a.nc", grid, TIMES, variables=VARIABLES[:1] * 2)
    with pytest.raises(ValueError, match="one way"):
        cube.CubeWriter(tmp_path / "a.nc", grid, TIMES, name="v", variables=VARIABLES)
    with pytest.raises(ValueError, match="azimuth"):
        cube.CubeWriter(tmp_path / "a.nc", grid, TIMES,
                        variables=[cube.CubeVariable("azimuth", "float32")],
                        time_variables={"azimuth": (AZ, {})})
    with pytest.raises(ValueError, match="band 10 of 9"):
        with cube.CubeWriter(tmp_path / "a.nc", grid, TIMES, variables=VARIABLES) as w:
            w.write(10, np.zeros((3, 4), np.float32))
    with pytest.raises(ValueError, match="no data variable 'glob_rad'"):
        with cube.CubeWriter(tmp_path / "a.nc", grid, TIMES, variables=VARIABLES) as w:
            w.write_variable("glob_rad", 1, np.zeros((3, 4), np.float32))
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("name", FORMATS)
def test_one_variable_either_way_is_the_same_cube(tmp_path, name):
    """name/dtype/nodata/attrs and variables=[CubeVariable(...)] of the same variable write
    the same cube, file for file and byte for byte (the one-variable cubes of the series are
    what they were)."""
    data = _stack()
    common = dict(time_variables={"azimuth": (AZ, {"units": "degree"})},
                  global_attrs={"title": "a test", "history": "pytest"})
    a, b = tmp_path / "a" / name, tmp_path / "b" / name
    a.parent.mkdir()
    b.parent.mkdir()
    with cube.CubeWriter(a, _grid(), TIMES, name="shadow", dtype="uint8", nodata=255,
                         attrs={"long_name": "cast shadow"}, **common) as w:
        for i in range(len(TIMES)):
            w.write(i + 1, data[i])
    with cube.CubeWriter(b, _grid(), TIMES, variables=[cube.CubeVariable(
            "shadow", "uint8", 255, {"long_name": "cast shadow"})], **common) as w:
        for i in range(len(TIMES)):
            w.write_variable("shadow", i + 1, data[i])

    def files(root):
        out = {}
        for dirpath, _, names in os.walk(root):
            for n in names:
                p = os.path.join(dirpath, n)
                with open(p, "rb") as f:
                    out[os.path.relpath(p, root)] = f.read()
        return out
    fa, fb = files(a.parent), files(b.parent)
    assert len(fa) >= 1 and fa == fb


# -- totals on (y, x) beside months on (time, y, x): a period's sums --------------------------

MONTHS = [dt.datetime(2026, 1, 1), dt.datetime(2026, 2, 1), dt.datetime(2026, 3, 1)]
BOUNDS = [(dt.datetime(2026, 1, 30, 0, 0), dt.datetime(2026, 2, 1)),
          (dt.datetime(2026, 2, 1), dt.datetime(2026, 3, 1)),
          (dt.datetime(2026, 3, 1), dt.datetime(2026, 3, 2, 6, 30))]
PERIOD = [cube.CubeVariable("beam_rad", "float32", -9999.0,
                            {"units": "Wh m-2", "long_name": "beam"}, timed=False),
          cube.CubeVariable("glob_rad", "float32", -9999.0,
                            {"units": "Wh m-2", "long_name": "global"}, timed=False),
          cube.CubeVariable("glob_rad_monthly", "float32", -9999.0,
                            {"units": "Wh m-2", "long_name": "global of each month"})]


def _period(rows=37, cols=53):
    """(beam, global) totals (rows, cols) and the months (3, rows, cols): distinct values, a
    void in each."""
    rng = np.random.default_rng(29)
    beam = (rng.random((rows, cols)) * 3000.0).astype(np.float32)
    glob = beam + np.float32(1234.5)
    months = (rng.random((len(MONTHS), rows, cols)) * 2000.0).astype(np.float32)
    for a in (beam, glob, *months):
        a[5:7, 9:12] = -9999.0
    return beam, glob, months


@pytest.mark.parametrize("name", FORMATS)
def test_totals_and_months_in_a_geotiffs_band_order(tmp_path, name):
    """Two variables on (y, x) and one on (time, y, x) written through write(band, ...) in a
    GeoTIFF's order (the totals, then a band per month; windows for one month): xarray gives the
    totals without time, the months on time with the bounds decoded (time_bnds named by
    time's bounds, in its units), the month labels and hours as coordinates of the monthly
    variable only, the comment on time's clock; every value bit for bit."""
    beam, glob, months = _period()
    path = tmp_path / name
    labels = ["2026-01", "2026-02", "2026-03"]
    with cube.CubeWriter(path, _grid(), MONTHS, variables=PERIOD, time_bounds=BOUNDS,
                         time_coords={"month": (labels, {"long_name": "month"}),
                                      "hours": ([48.0, 672.0, 30.5], {"units": "h"})},
                         time_attrs={"comment": "local time"},
                         global_attrs={"period_start": "2026-01-30"}) as w:
        assert w.layout == [("beam_rad", None), ("glob_rad", None), ("glob_rad_monthly", 1),
                            ("glob_rad_monthly", 2), ("glob_rad_monthly", 3)]
        w.write(1, beam, "beam_rad", {"UNITS": "Wh/m2"})
        w.write(2, glob[:20], window=(0, 20, 0, 53))
        w.write(2, glob[20:], window=(20, 37, 0, 53))
        for k in range(3):
            w.write(3 + k, months[k], f"2026-0{k + 1}")
    with _open(path) as ds:
        assert ds.attrs["period_start"] == "2026-01-30"
        assert ds["beam_rad"].dims == ds["glob_rad"].dims == ("y", "x")
        assert "time" not in ds["glob_rad"].coords and "month" not in ds["glob_rad"].coords
        mo = ds["glob_rad_monthly"]
        assert mo.dims == ("time", "y", "x")
        np.testing.assert_array_equal(ds["time"].values, np.array(MONTHS, "datetime64[ns]"))
        np.testing.assert_array_equal(ds["time_bnds"].values,
                                      np.array(BOUNDS, "datetime64[ns]"))
        assert ds["time"].attrs["comment"] == "local time"
        assert ds["time"].attrs.get("bounds", ds["time"].encoding.get("bounds")) == "time_bnds"
        assert list(mo.coords["month"].values) == labels
        np.testing.assert_array_equal(mo.coords["hours"].values, [48.0, 672.0, 30.5])
        for v in ("beam_rad", "glob_rad", "glob_rad_monthly"):
            assert ds[v].rio.crs == UTM and ds[v].attrs["units"] == "Wh m-2"
            assert ds[v].encoding["_FillValue"] == -9999.0
        assert np.isnan(ds["glob_rad"].values[5, 9]) and ds["glob_rad"].values[0, 0] == glob[0, 0]
    with xr.open_dataset(path, mask_and_scale=False, engine="zarr" if name.endswith(".zarr")
                         else None) as ds:
        np.testing.assert_array_equal(ds["beam_rad"].values, beam)       # bit for bit
        np.testing.assert_array_equal(ds["glob_rad"].values, glob)
        np.testing.assert_array_equal(ds["glob_rad_monthly"].values, months)


def test_period_cube_chunks_and_units_in_netcdf(tmp_path):
    """NetCDF: the totals chunked (rows, cols) as one layer, the months one time step per chunk;
    time and time_bnds in whole seconds of one set of units; half a second in a bound: both in
    microseconds."""
    netCDF4 = pytest.importorskip("netCDF4")
    beam, glob, months = _period(40, 1100)
    path = tmp_path / "p.nc"
    with cube.CubeWriter(path, _grid(40, 1100), MONTHS, variables=PERIOD,
                         time_bounds=BOUNDS) as w:
        for b, a in enumerate([beam, glob, *months], 1):
            w.write(b, a)
    with netCDF4.Dataset(path) as nc:
        assert nc["glob_rad"].chunking() == [40, 1024] and nc["glob_rad"].dimensions == ("y", "x")
        assert nc["glob_rad_monthly"].chunking() == [1, 40, 1024]
        assert nc["time"].units == "seconds since 1970-01-01 00:00:00"
        assert nc["time"].bounds == "time_bnds" and nc["time_bnds"].dimensions == ("time", "nv")
        assert nc["time_bnds"][2, 1] - nc["time"][2] == 30 * 3600 + 1800
    half = [b for b in BOUNDS[:2]] + [(BOUNDS[2][0], BOUNDS[2][1] + dt.timedelta(seconds=0.5))]
    with cube.CubeWriter(tmp_path / "h.nc", _grid(40, 1100), MONTHS, variables=PERIOD,
                         time_bounds=half) as w:
        pass
    with xr.open_dataset(tmp_path / "h.nc") as ds:
        assert ds["time"].encoding["units"].startswith("microseconds since 1970")
        assert ds["time_bnds"].values[2, 1] == np.datetime64("2026-03-02T06:30:00.5")
        assert ds["time"].values[1] == np.datetime64("2026-02-01")


@pytest.mark.parametrize("name", FORMATS)
def test_totals_only_have_no_time(tmp_path, name):
    """Variables on (y, x) only (a period's totals without --monthly): no time dimension,
    coordinate or bounds at all; write(band) takes them in order; write_variable with None."""
    beam, glob, _ = _period()
    path = tmp_path / name
    with cube.CubeWriter(path, _grid(), [], variables=PERIOD[:2]) as w:
        w.write(2, glob)
        w.write_variable("beam_rad", None, beam)
    with _open(path) as ds:
        assert "time" not in ds.dims and "time" not in ds.variables
        assert "time_bnds" not in ds.variables
        assert ds["beam_rad"].dims == ("y", "x") and ds.rio.crs == UTM
    with xr.open_dataset(path, mask_and_scale=False, engine="zarr" if name.endswith(".zarr")
                         else None) as ds:
        np.testing.assert_array_equal(ds["beam_rad"].values, beam)
        np.testing.assert_array_equal(ds["glob_rad"].values, glob)


def test_an_explicit_band_layout(tmp_path):
    """bands=[(name, step), ...]: band 1 the last month, band 2 a total, ...: each where it is
    named."""
    beam, glob, months = _period()
    path = tmp_path / "o.nc"
    bands = [("glob_rad_monthly", 3), ("beam_rad", None), ("glob_rad_monthly", 1),
             ("glob_rad", None), ("glob_rad_monthly", 2)]
    with cube.CubeWriter(path, _grid(), MONTHS, variables=PERIOD, bands=bands) as w:
        for b, a in enumerate([months[2], beam, months[0], glob, months[1]], 1):
            w.write(b, a)
    with xr.open_dataset(path, mask_and_scale=False) as ds:
        np.testing.assert_array_equal(ds["glob_rad_monthly"].values, months)
        np.testing.assert_array_equal(ds["beam_rad"].values, beam)
        np.testing.assert_array_equal(ds["glob_rad"].values, glob)


def test_period_layout_bad_calls(tmp_path):
    grid = _grid(3, 4)
    with pytest.raises(ValueError, match="no time axis"):
        cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD[:2])
    with pytest.raises(ValueError, match="a time at least"):
        cube.CubeWriter(tmp_path / "a.nc", grid, [], variables=PERIOD)
    with pytest.raises(ValueError, match="2 pairs for 3 times"):
        cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD,
                        time_bounds=BOUNDS[:2])
    with pytest.raises(ValueError, match="time coordinate month: 2 values"):
        cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD,
                        time_coords={"month": (["a", "b"], {})})
    with pytest.raises(ValueError, match="'time_bnds'"):
        cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS,
                        variables=[cube.CubeVariable("time_bnds", "float32")])
    with pytest.raises(ValueError, match=r"bands: 'beam_rad' at time step 1"):
        cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD,
                        bands=[("beam_rad", 1)])
    with pytest.raises(ValueError, match=r"bands: 'glob_rad_monthly' at time step 4"):
        cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD,
                        bands=[("glob_rad_monthly", 4)])
    with pytest.raises(ValueError, match="no time axis"):
        with cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD) as w:
            w.write_variable("beam_rad", 1, np.zeros((3, 4), np.float32))
    with pytest.raises(ValueError, match="time step None of 3"):
        with cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD) as w:
            w.write_variable("glob_rad_monthly", None, np.zeros((3, 4), np.float32))
    with pytest.raises(ValueError, match="band 6 of 5"):
        with cube.CubeWriter(tmp_path / "a.nc", grid, MONTHS, variables=PERIOD) as w:
            w.write(6, np.zeros((3, 4), np.float32))
    assert os.listdir(tmp_path) == []
