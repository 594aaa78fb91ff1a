"""``irradiance --time`` / ``--instant`` (``run.irradiance_instant``, r.sun's mode 1): at each
instant the beam, diffuse, reflected and global irradiance (W/m²) and the sun's elevation above
each cell's surface. Checked against pvlib's clear sky at solar noon on a flat plane, DNI cos Z
for the beam, the shadow command's mask for cast shadows, pvlib's angle of incidence on tilted
planes, and against the period run: a day's instants times the step are its Wh/m²."""

import datetime as dt
import json
import math

import numpy as np
import pandas as pd
import pvlib
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.io import read_dem
from hillshade_rt.testing import box_terrain, fractal_terrain, read_band, write_geotiff

# pvlib 0.16 asks pandas 3 for DatetimeIndex.dayofyear (deprecated there), inside pvlib
pytestmark = pytest.mark.filterwarnings("ignore:DatetimeIndex.dayofyear:DeprecationWarning")

QUANTITIES = ("beam", "diffuse", "reflected", "global", "incidence")
UTM11 = CRS.from_epsg(32611)
# easting 500000: on zone 11's central meridian (-117), grid north is true north there
CM = Affine(10.0, 0, 499800.0, 0, -10.0, 3800200.0)


def _run(runner, args, code=0):
    r = runner.invoke(cli, ["irradiance"] + [str(a) for a in args])
    assert r.exit_code == code, r.output
    return r


def _bands(path):
    """(the bands as (times, 5, rows, cols), the descriptions, the band tags)."""
    with rasterio.open(path) as ds:
        v = ds.read()
        return (v.reshape(-1, 5, *v.shape[1:]), ds.descriptions,
                [ds.tags(b) for b in range(1, ds.count + 1)])


def _flat_geographic(tmp_path, height=800.0):
    """A flat EPSG:4326 DEM (3 arc-second cells) around 46.5 N, 7.5 E."""
    z = np.full((30, 30), height, np.float32)
    tr = Affine(1 / 1200, 0, 7.5, 0, -1 / 1200, 46.5)
    return write_geotiff(tmp_path / "flat.tif", z, tr, CRS.from_epsg(4326))


def _noon(date, lat, lon):
    """Local solar noon (the sun's transit) at (lat, lon) on ``date``, pvlib's SPA."""
    idx = pd.DatetimeIndex([pd.Timestamp(date, tz="UTC")])
    t = pvlib.solarposition.sun_rise_set_transit_spa(idx, lat, lon)["transit"].iloc[0]
    return t.floor("s").to_pydatetime().astimezone(dt.timezone.utc)


def test_flat_plane_at_solar_noon_is_pvlibs_clear_sky(tmp_path, runner):
    """A flat plane at local solar noon: global is pvlib's Ineichen GHI with the same Linke
    turbidity (at the run's own solar position: to float32 rounding; at pvlib's own SPA
    position: within 1e-5), diffuse its DHI, reflected 0 (the plane sees no terrain), beam
    DNI cos Z; the incidence angle is the sun's elevation."""
    dem = _flat_geographic(tmp_path)
    lat, lon = 46.5 - 15 / 1200, 7.5 + 15 / 1200
    noon = _noon("2026-06-21", lat, lon)
    out, rep = tmp_path / "noon.tif", tmp_path / "noon.json"
    _run(runner, [dem, out, "--time", noon.isoformat(), "--linke-turbidity", "3", "-q",
                  "--no-earth-curvature", "--skyview-directions", "8", "--report", rep])
    doc = json.loads(rep.read_text())
    assert doc["site"]["latitude"] == pytest.approx(lat) and doc["mode"] == "instants"
    (b, d, r, g, inc), = _bands(out)[0]
    el = doc["times"][0]["sun"]["elevation"]
    assert 66.0 < el < 67.5                          # 90 - 46.49 + 23.44
    idx = pd.DatetimeIndex([pd.Timestamp(noon)])
    loc = pvlib.location.Location(lat, lon, altitude=800.0)
    # the run's solar position (NREL SPA, apparent zenith): pvlib's Ineichen on it
    pos = pd.DataFrame({"apparent_zenith": [90.0 - el], "zenith": [90.0 - el],
                        "apparent_elevation": [el]}, index=idx)
    cs = loc.get_clearsky(idx, model="ineichen", solar_position=pos, linke_turbidity=3.0)
    ghi, dni, dhi = (float(cs[k].iloc[0]) for k in ("ghi", "dni", "dhi"))
    assert 850.0 < ghi < 1100.0
    np.testing.assert_allclose(g, ghi, rtol=2.5e-7)
    np.testing.assert_allclose(d, dhi, rtol=2.5e-7)
    assert (r == 0.0).all()
    np.testing.assert_allclose(b, dni * math.cos(math.radians(90.0 - el)), rtol=2.5e-7)
    np.testing.assert_allclose(inc, el, atol=2e-3)
    # pvlib's own solar position, independent of the run's code path
    sp = pvlib.solarposition.get_solarposition(idx, lat, lon, altitude=800.0, temperature=12.0)
    theirs = loc.get_clearsky(idx, model="ineichen", solar_position=sp, linke_turbidity=3.0)
    np.testing.assert_allclose(g, float(theirs["ghi"].iloc[0]), rtol=1e-5)


def test_beam_on_a_flat_plane_is_dni_cos_zenith_at_any_time(tmp_path, runner):
    """Three instants (morning, afternoon, night) on a flat plane: beam = DNI cos Z with the
    open sky and the sun the report gives for each; global = beam + diffuse + reflected; the
    night all 0; the descriptions and tags name each band's quantity and time."""
    dem = _flat_geographic(tmp_path, 1200.0)
    times = ["2026-03-02T08:07:00+01:00", "2026-03-02T15:41:00+01:00",
             "2026-03-02T23:20:00+01:00"]
    out, rep = tmp_path / "t.tif", tmp_path / "t.json"
    _run(runner, [dem, out, "-q", "--no-earth-curvature", "--skyview-directions", "8",
                  "--report", rep] + [x for t in times for x in ("--time", t)])
    doc = json.loads(rep.read_text())
    v, desc, tags = _bands(out)
    assert v.shape[:2] == (3, 5) and doc["instants"] == 3 and doc["instants_with_sun"] == 2
    for k in range(3):
        sky, el = doc["times"][k]["open_sky"], doc["times"][k]["sun"]["elevation"]
        b, d, r, g, inc = v[k]
        want = sky["dni_w_m2"] * max(math.sin(math.radians(el)), 0.0)
        np.testing.assert_allclose(b, want, rtol=3e-7, atol=1e-9)
        np.testing.assert_allclose(g, b + d + r, rtol=1e-6)
        np.testing.assert_allclose(inc, el, atol=2e-3)
    assert (v[2, :4] == 0.0).all() and (v[0, 0] > 50.0).all()
    assert desc[:5] == tuple(f"{n} 2026-03-02T08:07+01:00" for n in
                             ("beam_rad", "diff_rad", "refl_rad", "glob_rad", "incidout"))
    assert [t["NAME"] for t in tags[5:10]] == list(QUANTITIES)
    assert tags[13]["TIME"] == "2026-03-02T23:20+01:00" and tags[13]["UNITS"] == "W/m2"
    assert tags[14]["UNITS"] == "degrees"


def test_a_cell_in_a_cast_shadow_has_no_beam(tmp_path, runner):
    """A 60 m block on a plain at a low morning sun: on the plain the beam is 0 exactly where
    the shadow command (the same time) says shadow, positive elsewhere; the diffuse light
    stays."""
    z = box_terrain(60, 60, 60.0, 24, 34, 26, 36)
    dem = write_geotiff(tmp_path / "box.tif", z, Affine(5.0, 0, 400000.0, 0, -5.0, 3800000.0),
                        UTM11)
    t = "2026-06-21T06:47:00-07:00"
    out, mask = tmp_path / "i.tif", tmp_path / "m.tif"
    _run(runner, [dem, out, "--time", t, "-q", "--skyview-directions", "8"])
    r = runner.invoke(cli, ["shadow", str(dem), str(mask), "--time", t, "-q"])
    assert r.exit_code == 0, r.output
    (b, d, refl, g, _), = _bands(out)[0]
    m = read_band(mask)
    from numpy.lib.stride_tricks import sliding_window_view
    plain = (sliding_window_view(np.pad(z, 1, mode="edge"), (3, 3)) == 0.0).all(axis=(2, 3))
    shadow = plain & (m == 1)
    assert 20 < shadow.sum() < plain.sum() // 2
    assert (b[shadow] == 0.0).all() and (b[plain & (m == 0)] > 50.0).all()
    assert (d[shadow] > 10.0).all()
    np.testing.assert_allclose(g[shadow], d[shadow] + refl[shadow], rtol=1e-6)


@pytest.mark.parametrize("extra", [[], ["--perez"]])
def test_a_days_instants_times_the_step_are_the_period_run(tmp_path, runner, extra):
    """The period run (--date, every hour: samples at hh:30) against its instants: --instant
    --date writes the same times as --instant --start 00:30 --end 23:30 --step 1h (bit for
    bit), and the sum of each band over them times one hour is the period's Wh/m² (to float32
    rounding), isotropic and Perez: the two paths are the same physics."""
    dem = write_geotiff(tmp_path / "f.tif", fractal_terrain(40, 48, 7, relief=300.0),
                        Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0), UTM11)
    common = ["--tz", "UTC", "--step", "1h", "-q", "--skyview-directions", "8"] + extra
    period, a, b = tmp_path / "p.tif", tmp_path / "a.tif", tmp_path / "b.tif"
    _run(runner, [dem, period, "--date", "2026-06-21"] + common)
    _run(runner, [dem, a, "--date", "2026-06-21", "--instant"] + common)
    _run(runner, [dem, b, "--instant", "--start", "2026-06-21T00:30Z", "--end",
                  "2026-06-21T23:30Z"] + common)
    va, da, _ = _bands(a)
    vb, db, _ = _bands(b)
    assert va.shape[0] == 24 and da == db
    np.testing.assert_array_equal(va, vb)
    with rasterio.open(period) as ds:
        p = ds.read()
    total = va[:, :4].astype(np.float64).sum(axis=0) * 1.0
    np.testing.assert_allclose(total, p, rtol=2e-6, atol=1e-3)
    assert p[0].max() > 3000.0 and len(np.unique(p[0])) > 100   # beam varies: shadows, slopes


def test_incidence_on_tilted_planes(tmp_path, runner):
    """A plane tilted 25 deg toward the sun: the sun stands its elevation + 25 deg above it;
    a plane of 30 deg facing 163 at another time: 90 - pvlib's angle of incidence (interior
    cells; the DEM on the UTM zone's central meridian, so grid north is true north)."""
    from hillshade_rt.model.solar import solar_position
    t = dt.datetime(2026, 6, 21, 8, 40, tzinfo=dt.timezone(dt.timedelta(hours=-7)))
    t2 = dt.datetime(2026, 9, 3, 16, 13, tzinfo=dt.timezone(dt.timedelta(hours=-7)))
    az, el, _ = solar_position([t], 34.3, -117.0, 500.0)
    x = np.arange(40)[None, :] * 10.0
    y = -np.arange(40)[:, None] * 10.0
    for name, slope, aspect, when in (("facing", 25.0, float(az[0]), t),
                                      ("other", 30.0, 163.0, t2)):
        s, a = math.tan(math.radians(slope)), math.radians(aspect)
        z = (-s * (x * math.sin(a) + y * math.cos(a)))
        z = (z - z.min() + 500.0).astype(np.float32)
        dem = write_geotiff(tmp_path / f"{name}.tif", z, CM, UTM11)
        out, rep = tmp_path / f"{name}_i.tif", tmp_path / f"{name}.json"
        _run(runner, [dem, out, "--time", when.isoformat(), "-q", "--no-earth-curvature",
                      "--skyview-directions", "8", "--report", rep])
        sun = json.loads(rep.read_text())["times"][0]["sun"]
        inc = _bands(out)[0][0, 4][2:-2, 2:-2]
        # the plane on the ground: the model's cells are ground metres on the ellipsoid (10 m
        # of UTM grid are 10 / 0.9996 m of ground on the central meridian)
        dx, dy = read_dem(dem).grid.centre_spacing()
        ge, gn = s * math.sin(a) * 10.0 / dx, s * math.cos(a) * 10.0 / dy
        tilt = math.degrees(math.atan(math.hypot(ge, gn)))
        facing = math.degrees(math.atan2(ge, gn)) % 360.0
        aoi = float(pvlib.irradiance.aoi(tilt, facing, 90.0 - sun["elevation"],
                                         sun["azimuth"]))
        np.testing.assert_allclose(inc, 90.0 - aoi, atol=2e-3)
        if name == "facing":
            assert sun["elevation"] == pytest.approx(float(el[0]), abs=0.05)
            np.testing.assert_allclose(inc, sun["elevation"] + tilt, atol=2e-3)
        else:
            assert 5.0 < 90.0 - aoi < 60.0


@pytest.mark.parametrize("args, words", [
    (["--time", "2026-06-21T12:00Z", "--date", "2026-06-21"], "--time gives the instants"),
    (["--instant", "--date", "2026-06-21", "--mean"], "--mean averages a period"),
    (["--time", "2026-06-21T12:00Z", "--mean"], "--mean averages a period"),
    (["--instant"], "give the period one way"),
    (["--time", "2026-06-21T12:00"], "has no UTC offset"),
    (["--time", "2026-06-21"], "a date without a time of day"),
])
def test_bad_instants_are_one_line_usage_errors(tmp_path, runner, args, words):
    dem = write_geotiff(tmp_path / "f.tif", fractal_terrain(20, 20, 3, relief=50.0),
                        Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0), UTM11)
    out = tmp_path / "o.tif"
    r = _run(runner, [dem, out] + args, code=2)
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not out.exists()


@pytest.mark.parametrize("name, args, words", [
    ("o.nc", ["--co", "COMPRESS=DEFLATE"], "drop --co"),
    ("o.zarr", ["--co", "COMPRESS=DEFLATE"], "drop --co"),
    ("o.tif", ["--monthly"], "are a period's sums"),
    ("o.tif", ["--daily-mean"], "are a period's sums"),
])
def test_instants_refuse_cube_creation_options_and_period_options(tmp_path, runner, name, args,
                                                                   words):
    """A time cube takes no GDAL creation options; instants have no months or daily means (a
    period's sums)."""
    dem = write_geotiff(tmp_path / "f.tif", fractal_terrain(20, 20, 3, relief=50.0),
                        Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0), UTM11)
    out = tmp_path / name
    r = _run(runner, [dem, out, "--time", "2026-06-21T19:00Z"] + args, code=2)
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not out.exists()


def test_instants_from_python(tmp_path, runner):
    """hillshade_rt.irradiance(times=...) and instant=True: the command line's files."""
    import hillshade_rt as hr
    dem = write_geotiff(tmp_path / "f.tif", fractal_terrain(30, 30, 5, relief=200.0),
                        Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0), UTM11)
    times = ["2026-06-21T10:05-07:00", dt.datetime(2026, 6, 21, 17, 50, tzinfo=dt.timezone.utc)]
    _run(runner, [dem, tmp_path / "cli.tif", "-q", "--skyview-directions", "8", "--time",
                  times[0], "--time", times[1].isoformat()])
    rep = hr.irradiance(dem, tmp_path / "api.tif", times=times, skyview_directions=8)
    assert rep["instants"] == 2
    np.testing.assert_array_equal(_bands(tmp_path / "api.tif")[0],
                                  _bands(tmp_path / "cli.tif")[0])
    hr.irradiance(dem, tmp_path / "one.tif", times=times[0], skyview_directions=8)
    np.testing.assert_array_equal(_bands(tmp_path / "one.tif")[0][0],
                                  _bands(tmp_path / "cli.tif")[0][0])
    rep = hr.irradiance(dem, tmp_path / "series.tif", start="2026-06-21T10:00-07:00",
                        end="2026-06-21T11:00-07:00", step="30min", instant=True,
                        skyview_directions=8)
    assert [t["time"] for t in rep["times"]] == ["2026-06-21T10:00-07:00",
                                                 "2026-06-21T10:30-07:00",
                                                 "2026-06-21T11:00-07:00"]
    with pytest.raises(hr.HillshadeError) as e:
        hr.irradiance(dem, tmp_path / "x.tif", times=times, mean=True)
    assert "mean=True averages" in str(e.value) and "--" not in str(e.value)


CUBES = ["c.nc", pytest.param("c.zarr", marks=pytest.mark.skipif(
    __import__("importlib").util.find_spec("zarr") is None, reason="zarr not installed"))]


@pytest.mark.slow
@pytest.mark.parametrize("name", CUBES)
def test_instants_as_a_time_cube_are_the_geotiffs_bands(tmp_path, runner, name):
    """The same command line to OUTPUT.tif and to OUTPUT.nc / OUTPUT.zarr: xarray decodes the
    cube's times (the instants in UTC) and its five variables under r.sun's names, each at each
    time the GeoTIFF's band bit for bit (voids: the _FillValue -9999, NaN decoded), with its
    units, the grid mapping of the DEM's CRS, and the sun and open sky of the report per
    time."""
    xr = pytest.importorskip("xarray")
    pytest.importorskip("rioxarray")
    z = fractal_terrain(30, 36, 5, relief=250.0)
    z[3:6, 20:24] = -32768.0                          # voids
    dem = write_geotiff(tmp_path / "f.tif", z, Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0),
                        UTM11, nodata=-32768.0)
    times = ["2026-06-21T07:35-07:00", "2026-06-21T13:10-07:00", "2026-06-21T18:55-07:00"]
    common = ["-q", "--skyview-directions", "8"] + [x for t in times for x in ("--time", t)]
    tif, cube, rep = tmp_path / "g.tif", tmp_path / name, tmp_path / "c.json"
    _run(runner, [dem, tif] + common)
    _run(runner, [dem, cube, "--report", rep] + common)
    v, _, _ = _bands(tif)
    doc = json.loads(rep.read_text())
    assert doc["output"] == str(cube) and v.shape == (3, 5, 30, 36)
    names = ("beam_rad", "diff_rad", "refl_rad", "glob_rad", "incidout")
    engine = "zarr" if name.endswith(".zarr") else None
    with xr.open_dataset(cube, engine=engine) as ds:
        assert ds["time"].dtype.kind == "M"
        want = [pd.Timestamp(t).tz_convert("UTC").tz_localize(None) for t in times]
        np.testing.assert_array_equal(ds["time"].values, np.array(want, "datetime64[ns]"))
        assert ds.attrs["Conventions"] == "CF-1.8" and "--time" in ds.attrs["history"]
        assert ds.rio.crs == UTM11
        for j, n in enumerate(names):
            da = ds[n]
            assert da.dims == ("time", "y", "x")
            assert da.attrs["units"] == ("degree" if n == "incidout" else "W m-2")
            assert da.attrs["long_name"] and da.encoding["_FillValue"] == -9999.0
            assert da.rio.crs == UTM11
            for k in range(3):
                band = v[k, j]
                void = band == -9999.0
                assert void.sum() == 12                   # the DEM's voids, no other
                np.testing.assert_array_equal(np.isnan(da.values[k]), void)
                np.testing.assert_array_equal(da.values[k][~void], band[~void])
        for k in range(3):
            assert ds["elevation"].values[k] == doc["times"][k]["sun"]["elevation"]
            assert ds["azimuth"].values[k] == doc["times"][k]["sun"]["azimuth"]
            assert ds["open_sky_ghi"].values[k] == doc["times"][k]["open_sky"]["ghi_w_m2"]
        assert float(ds["glob_rad"].max()) > 500.0
    with xr.open_dataset(cube, engine=engine, mask_and_scale=False) as ds:
        raw = np.stack([ds[n].values for n in names], axis=1)
        assert raw.dtype == np.float32
        np.testing.assert_array_equal(raw, v)                 # bit for bit, voids included
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        ["c.json", "f.tif", "g.tif", name])                  # no temporary left


@pytest.mark.slow
def test_instants_cube_from_python_and_refused_without_overwrite(tmp_path, runner):
    """hillshade_rt.irradiance(times=..., output .nc): the cube (its history says the Python
    API); the same path again: refused, the cube untouched; overwrite=True replaces it."""
    xr = pytest.importorskip("xarray")
    import hillshade_rt as hr
    dem = write_geotiff(tmp_path / "f.tif", fractal_terrain(20, 24, 3, relief=80.0),
                        Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0), UTM11)
    out = tmp_path / "a.nc"
    rep = hr.irradiance(dem, out, times=["2026-06-21T09:20-07:00"], skyview_directions=8)
    assert rep["instants"] == 1
    before = out.read_bytes()
    with xr.open_dataset(out) as ds:
        assert ds["glob_rad"].shape == (1, 20, 24) and "Python API" in ds.attrs["history"]
    with pytest.raises(hr.HillshadeError, match="exists"):
        hr.irradiance(dem, out, times=["2026-06-21T11:20-07:00"], skyview_directions=8)
    assert out.read_bytes() == before
    hr.irradiance(dem, out, times=["2026-06-21T11:20-07:00"], skyview_directions=8,
                  overwrite=True)
    with xr.open_dataset(out) as ds:
        assert str(ds["time"].values[0]).startswith("2026-06-21T18:20")
