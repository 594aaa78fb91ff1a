"""The sky's inputs of ``irradiance`` as r.sun users give them (``run.sky_inputs``): numbers,
12 monthly numbers, rasters and monthly rasters of albedo; monthly Linke turbidity; the
period's months as bands (``--monthly``) and the daily mean."""

import datetime as dt
import json

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.errors import UsageProblem
from hillshade_rt.model.times import zone
from hillshade_rt.run.sky_inputs import SkyValue, local_months, month_keys
from hillshade_rt.testing import fractal_terrain, read_band, write_geotiff

pytestmark = pytest.mark.filterwarnings("ignore:DatetimeIndex.dayofyear:DeprecationWarning")

UTM11 = CRS.from_epsg(32611)
T0 = Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0)
# a fortnight across January and February, hourly: two months, quickly
SPAN = ["--date", "2027-01-30", "--end-date", "2027-02-02", "--step", "1h",
        "--skyview-directions", "8", "-q"]


@pytest.fixture(scope="module")
def dem(tmp_path_factory):
    z = fractal_terrain(36, 44, 11, relief=600.0)
    return write_geotiff(tmp_path_factory.mktemp("sky") / "dem.tif", np.asarray(z, np.float32),
                         T0, UTM11)


def _run(runner, args, code=0):
    r = runner.invoke(cli, ["irradiance"] + [str(a) for a in args])
    assert r.exit_code == code, r.output
    return r


def _bands(path):
    with rasterio.open(path) as ds:
        return ds.read(), ds.descriptions, ds.tags()


# ---------------------------------------------------------------------------------------------
# parsing

def test_values_parse_as_numbers_months_rasters_and_patterns(tmp_path):
    assert SkyValue.parse("--albedo", None, 0, 1) is None
    assert SkyValue.parse("--albedo", 0.25, 0, 1).number == 0.25
    assert SkyValue.parse("--albedo", "0.25", 0, 1).number == 0.25
    months = ",".join(f"{0.1 + 0.01 * m:g}" for m in range(12))
    v = SkyValue.parse("--albedo", months, 0, 1)
    assert v.monthly[0] == 0.1 and v.monthly[11] == pytest.approx(0.21) and v.by_month
    assert v.value_of_month(3) == pytest.approx(0.12)
    # twelve times one number is that number
    assert SkyValue.parse("--albedo", ",".join(["0.3"] * 12), 0, 1).number == 0.3
    assert SkyValue.parse("--albedo", [0.2] * 11 + [0.4], 0, 1).monthly[11] == 0.4
    r = write_geotiff(tmp_path / "a.tif", np.full((3, 3), 0.2, np.float32), T0, UTM11)
    v = SkyValue.parse("--albedo", r, 0, 1)
    assert v.path == str(r) and v.rasters and not v.by_month and v.inputs() == [str(r)]
    for m in range(1, 13):
        write_geotiff(tmp_path / f"al_{m:02d}.tif", np.full((3, 3), 0.2, np.float32), T0,
                      UTM11)
    v = SkyValue.parse("--albedo", str(tmp_path / "al_{month:02d}.tif"), 0, 1)
    assert v.by_month and v.inputs()[11].endswith("al_12.tif")


@pytest.mark.parametrize("value, words", [
    ("1.2", "--albedo must be between 0 and 1, got 1.2"),
    ("0.1,0.2", "one number or 12 monthly numbers"),
    (",".join(["0.1"] * 11 + ["x"]), "must be numbers"),
    (",".join(["0.1"] * 11 + ["1.5"]), "got 1.5"),
    ("nosuch.tif", "neither a number nor an existing raster"),
    ("al_{month}.tif", "no such file: al_1.tif"),
    ("al_{mon}.tif", "a pattern takes {month}"),
])
def test_bad_values_are_usage_problems(value, words, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(UsageProblem, match=words.replace("{", r"\{").replace("}", r"\}")):
        SkyValue.parse("--albedo", value, 0.0, 1.0)


def test_months_are_local():
    """A sample's month in the DEM's zone, else in local mean solar time at its longitude."""
    t = [dt.datetime(2027, 1, 31, 23, 30, tzinfo=dt.timezone.utc),
         dt.datetime(2027, 2, 1, 6, 30, tzinfo=dt.timezone.utc)]
    # Los Angeles (UTC-8): both still January 31 .. February 1 at 22:30
    assert local_months(t, zone("America/Los_Angeles"), -118.0).tolist() == [1, 1]
    assert local_months(t, None, 120.0).tolist() == [2, 2]     # 8 h ahead: February
    assert month_keys(t, None, 0.0) == [(2027, 1), (2027, 2)]


# ---------------------------------------------------------------------------------------------
# runs

@pytest.mark.slow
def test_monthly_bands_sum_to_the_total_and_equal_the_daily_runs(tmp_path, runner, dem):
    """--monthly: the four bands are the bits of the run without it; then one global band per
    month (YYYY-MM) which sum to the global band, each the sum of its days' own runs."""
    plain, monthly = tmp_path / "p.tif", tmp_path / "m.tif"
    _run(runner, [dem, plain] + SPAN)
    _run(runner, [dem, monthly, "--monthly", "--report", tmp_path / "m.json"] + SPAN)
    p, _, _ = _bands(plain)
    m, desc, tags = _bands(monthly)
    assert m.shape[0] == 6 and desc == ("beam", "diffuse", "reflected", "global", "2027-01",
                                        "2027-02")
    np.testing.assert_array_equal(m[:4], p)
    np.testing.assert_allclose(m[4].astype(np.float64) + m[5], m[3], rtol=2e-6)
    assert "MONTHS" in tags
    days = []
    for d in ("2027-01-30", "2027-01-31", "2027-02-01", "2027-02-02"):
        out = tmp_path / f"{d}.tif"
        _run(runner, [dem, out, "--date", d] + SPAN[4:])
        days.append(read_band(out, 4).astype(np.float64))
    np.testing.assert_allclose(m[4], days[0] + days[1], rtol=2e-6)
    np.testing.assert_allclose(m[5], days[2] + days[3], rtol=2e-6)
    rep = json.loads((tmp_path / "m.json").read_text())
    assert [x["month"] for x in rep["months"]] == ["2027-01", "2027-02"]
    assert [x["hours"] for x in rep["months"]] == [48.0, 48.0]


def test_daily_mean_divides_by_the_days_and_each_month_by_its_own(tmp_path, runner, dem):
    e, d = tmp_path / "e.tif", tmp_path / "d.tif"
    _run(runner, [dem, e, "--monthly"] + SPAN)
    _run(runner, [dem, d, "--monthly", "--daily-mean"] + SPAN)
    ev, _, _ = _bands(e)
    dv, _, tags = _bands(d)
    np.testing.assert_allclose(dv[:4] * 4.0, ev[:4], rtol=1e-6)
    np.testing.assert_allclose(dv[4:] * 2.0, ev[4:], rtol=1e-6)
    assert tags["UNITS"].startswith("Wh/m2 per day")
    r = runner.invoke(cli, ["irradiance", str(dem), str(tmp_path / "x.tif"), "--mean",
                            "--daily-mean"] + SPAN)
    assert r.exit_code == 2 and "--daily-mean" in r.stderr


def test_resample_writes_into_a_given_array_with_the_same_bits(tmp_path, dem):
    """``resample(..., out=)`` (a run in windows passes a float64 array mapped from a file)
    writes what it returns without ``out``, to the bit, NaN outside the raster; an ``out`` of
    another shape or type is refused."""
    from rasterio.warp import transform_bounds

    from hillshade_rt.errors import HillshadeError
    from hillshade_rt.run.sky_inputs import resample
    with rasterio.open(dem) as ds:
        w, s, e, n = transform_bounds(ds.crs, "EPSG:4326", *ds.bounds)
        tr, crs, shape = ds.transform, ds.crs, ds.shape
    y, x = np.mgrid[0:13, 0:11]
    geo = write_geotiff(tmp_path / "g.tif", (0.2 + 0.03 * x + 0.011 * y * y).astype(np.float32),
                        Affine((e - w) / 11 * 0.8, 0, w + 0.002, 0, -(n - s) / 13 * 1.1,
                               n + 0.003), CRS.from_epsg(4326))
    want = resample(geo, tr, crs, shape)
    out = np.lib.format.open_memmap(tmp_path / "g.npy", mode="w+", dtype=np.float64,
                                    shape=shape)
    out[...] = 7.0
    got = resample(geo, tr, crs, shape, out=out)
    assert got is out
    np.testing.assert_array_equal(np.asarray(out), want)
    assert np.isnan(want).any() and np.isfinite(want).sum() > 0.5 * want.size
    assert np.nanstd(want) > 0.05
    with pytest.raises(HillshadeError, match="not float64"):
        resample(geo, tr, crs, shape, out=np.zeros(shape, np.float32))


@pytest.mark.slow
def test_a_constant_albedo_raster_is_the_number(tmp_path, runner, dem):
    """A raster of one value gives the bits of that number, on the DEM's grid or on another
    (a coarser one in geographic coordinates, resampled bilinearly). (The raster's value is
    the number: float64 here; 0.35 in a float32 raster is 0.3499999940...)"""
    num, same, other = (tmp_path / f"{n}.tif" for n in ("num", "same", "other"))
    _run(runner, [dem, num, "--albedo", "0.35"] + SPAN)
    on_grid = write_geotiff(tmp_path / "a.tif", np.full((36, 44), 0.35), T0, UTM11)
    _run(runner, [dem, same, "--albedo", on_grid] + SPAN)
    with rasterio.open(dem) as ds:
        from rasterio.warp import transform_bounds
        w, s, e, n = transform_bounds(ds.crs, "EPSG:4326", *ds.bounds)
    geo = write_geotiff(tmp_path / "g.tif", np.full((20, 20), 0.35),
                        Affine((e - w + 0.02) / 20, 0, w - 0.01, 0, -(n - s + 0.02) / 20,
                               n + 0.01), CRS.from_epsg(4326))
    _run(runner, [dem, other, "--albedo", geo] + SPAN)
    ref = _bands(num)[0]
    np.testing.assert_array_equal(_bands(same)[0], ref)
    np.testing.assert_array_equal(_bands(other)[0], ref)


@pytest.mark.slow
def test_an_albedo_raster_weights_each_cell(tmp_path, runner, dem):
    """The reflected band is linear in the albedo, cell by cell: a raster of 0.1 on the west
    half and 0.5 on the east gives the two numbers' runs there."""
    a = np.full((36, 44), 0.1)              # float64: the numbers' values
    a[:, 22:] = 0.5
    ras = write_geotiff(tmp_path / "a.tif", a, T0, UTM11)
    outs = {}
    for name, val in (("r", ras), ("lo", "0.1"), ("hi", "0.5")):
        outs[name] = tmp_path / f"{name}.tif"
        _run(runner, [dem, outs[name], "--albedo", val] + SPAN)
    r, lo, hi = (read_band(outs[k], 3) for k in ("r", "lo", "hi"))
    # bilinear between the halves touches the two columns at the seam only
    np.testing.assert_array_equal(r[:, :21], lo[:, :21])
    np.testing.assert_array_equal(r[:, 23:], hi[:, 23:])
    np.testing.assert_array_equal(read_band(outs["r"], 1), read_band(outs["lo"], 1))


@pytest.mark.slow
def test_monthly_albedo_applies_each_month_its_value(tmp_path, runner, dem):
    """12 monthly albedo values (or 12 rasters by a pattern): each month's reflected light with
    its month's value, the total their sum."""
    months = ["0.1"] + ["0.6"] + ["0.3"] * 10
    mo, jan, feb = tmp_path / "mo.tif", tmp_path / "jan.tif", tmp_path / "feb.tif"
    _run(runner, [dem, mo, "--albedo", ",".join(months), "--monthly"] + SPAN)
    for m, v in ((1, 0.1), (2, 0.6)):
        write_geotiff(tmp_path / f"alb{m}.tif", np.full((36, 44), v), T0, UTM11)
    for m in range(3, 13):
        write_geotiff(tmp_path / f"alb{m}.tif", np.full((36, 44), 0.3), T0, UTM11)
    pat = tmp_path / "pat.tif"
    _run(runner, [dem, pat, "--albedo", tmp_path / "alb{month}.tif", "--monthly"] + SPAN)
    np.testing.assert_array_equal(_bands(pat)[0], _bands(mo)[0])
    _run(runner, [dem, jan, "--date", "2027-01-30", "--end-date", "2027-01-31", "--albedo",
                  "0.1"] + SPAN[4:])
    _run(runner, [dem, feb, "--date", "2027-02-01", "--end-date", "2027-02-02", "--albedo",
                  "0.6"] + SPAN[4:])
    refl = read_band(jan, 3).astype(np.float64) + read_band(feb, 3)
    np.testing.assert_allclose(read_band(mo, 3), refl, rtol=2e-6)
    np.testing.assert_allclose(read_band(mo, 5), read_band(jan, 4), rtol=2e-6)
    np.testing.assert_allclose(read_band(mo, 6), read_band(feb, 4), rtol=2e-6)


@pytest.mark.slow
def test_monthly_linke_turbidity_gives_each_sample_its_month(tmp_path, runner, dem):
    """Each sample's clear sky with its month's Linke turbidity: the run over January and
    February is the runs of its January days with January's value and of its February days
    with February's."""
    lt = ["2"] + ["5"] + ["3"] * 10
    both, jan, feb = tmp_path / "b.tif", tmp_path / "j.tif", tmp_path / "f.tif"
    _run(runner, [dem, both, "--linke-turbidity", ",".join(lt), "--report",
                  tmp_path / "b.json"] + SPAN)
    _run(runner, [dem, jan, "--date", "2027-01-30", "--end-date", "2027-01-31",
                  "--linke-turbidity", "2"] + SPAN[4:])
    _run(runner, [dem, feb, "--date", "2027-02-01", "--end-date", "2027-02-02",
                  "--linke-turbidity", "5"] + SPAN[4:])
    for b in (1, 2, 4):
        np.testing.assert_allclose(read_band(both, b),
                                   read_band(jan, b).astype(np.float64) + read_band(feb, b),
                                   rtol=2e-6, atol=1e-3)
    assert "monthly" in json.loads((tmp_path / "b.json").read_text())["turbidity"]


@pytest.mark.parametrize("extra, words", [
    (["--albedo", "{raster}"], "does not cover the DEM"),
    (["--albedo", "{bad}"], "values must be between 0 and 1"),
    (["--linke-turbidity", "{raster}"], "does not cover the DEM"),
    (["--linke-turbidity", "{turbid}"], "values must be between 1 and 10, found 11"),
    (["--linke-turbidity", "3,3"], "12 monthly numbers"),
    (["--beam-index", "{bad}"], "--beam-index {bad}: values must be between 0 and 1"),
    (["--diffuse-index", "{raster}"], "does not cover the DEM"),
    (["--beam-index", "1.2"], "--beam-index must be between 0 and 1, got 1.2"),
    (["--diffuse-index", "0.5,0.5"], "one number or 12 monthly numbers"),
    (["--beam-index", "0.5", "--ghi", "{csv}"], "--beam-index and --diffuse-index do not go"),
    # in windows (the rasters resampled to the grid once): the same lines
    (["--linke-turbidity", "{raster}", "--window-size", "64"], "does not cover the DEM"),
    (["--linke-turbidity", "{turbid}", "--window-size", "64"],
     "values must be between 1 and 10, found 11"),
    (["--diffuse-index", "{bad}", "--window-size", "64"],
     "--diffuse-index {bad}: values must be between 0 and 1"),
])
def test_bad_sky_inputs_are_one_line_usage_errors(tmp_path, runner, dem, extra, words):
    small = write_geotiff(tmp_path / "small.tif", np.full((5, 5), 0.2, np.float32), T0, UTM11)
    bad = write_geotiff(tmp_path / "bad.tif", np.full((36, 44), 1.5, np.float32), T0, UTM11)
    turbid = write_geotiff(tmp_path / "turbid.tif", np.full((36, 44), 11.0), T0, UTM11)
    two = np.full((36, 44), 0.5)
    two[:, 22:] = 0.8
    half = write_geotiff(tmp_path / "half.tif", two, T0, UTM11)
    two = write_geotiff(tmp_path / "two.tif", two * 4.0, T0, UTM11)   # Linke 2 and 3.2
    csv = tmp_path / "sky.csv"
    csv.write_text("time,ghi\n2027-01-29T00:00Z,0\n2027-02-04T00:00Z,0\n")
    values = dict(raster=small, bad=bad, turbid=turbid, two=two, half=half, csv=csv)
    extra = [e.format(**values) for e in extra]
    words = words.format(**values)
    out = tmp_path / "o.tif"
    r = runner.invoke(cli, ["irradiance", str(dem), str(out)] + extra + SPAN)
    assert r.exit_code == 2, r.output
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert not out.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]   # no grids left


# ---------------------------------------------------------------------------------------------
# a Linke turbidity raster and r.sun's clear-sky indices (coeff_bh, coeff_dh): the sky per cell

def _zones(tmp_path, name, west, east, cols=44):
    """A raster on the DEM's grid of ``west`` on columns 0..21 and ``east`` on 22.. (float64:
    the numbers' values); bilinear resampling changes the two columns at the seam only."""
    a = np.full((36, cols), float(west))
    a[:, 22:] = float(east)
    return write_geotiff(tmp_path / name, a, T0, UTM11)


# the bands of a zone of a raster and of the number's run differ by float rounding only: the
# per-cell clear sky is pvlib's Ineichen formula in numba (exp within an ulp of numpy's), the
# per-cell sums add each sample in order where the number's run sums the open sky with numpy
ROUNDING = dict(rtol=1e-6, atol=1e-3)


def _zone_equal(got, west, east):
    np.testing.assert_allclose(got[..., :21], west[..., :21], **ROUNDING)
    np.testing.assert_allclose(got[..., 23:], east[..., 23:], **ROUNDING)


@pytest.mark.slow
@pytest.mark.parametrize("extra", [[], ["--perez", "--soft"]])
def test_a_linke_raster_gives_each_cell_its_own_clear_sky(tmp_path, runner, dem, extra):
    """A Linke turbidity raster of 2.3 west and 4.7 east: each zone's four bands are those of
    the run with that number (isotropic, and Perez with each cell's own coefficients)."""
    ras = _zones(tmp_path, "tl.tif", 2.3, 4.7)
    outs = {}
    for name, val in (("r", ras), ("lo", "2.3"), ("hi", "4.7")):
        outs[name] = tmp_path / f"{name}.tif"
        _run(runner, [dem, outs[name], "--linke-turbidity", val, "--report",
                      tmp_path / f"{name}.json"] + extra + SPAN)
    r, lo, hi = (_bands(outs[k])[0] for k in ("r", "lo", "hi"))
    _zone_equal(r, lo, hi)
    # the two turbidities differ enough to tell: the clearer sky's beam is larger
    assert np.nanmean(lo[0]) > 1.05 * np.nanmean(hi[0])
    seam = r[3, :, 21:23]
    assert np.all((seam >= np.minimum(lo[3], hi[3])[:, 21:23] - 1e-3)
                  & (seam <= np.maximum(lo[3], hi[3])[:, 21:23] + 1e-3))
    rep = json.loads((tmp_path / "r.json").read_text())
    assert "each cell its own, 2.30..4.70" in rep["turbidity"]
    tags = _bands(outs["r"])[2]
    assert tags["LINKE_TURBIDITY"].startswith("raster tl.tif")


@pytest.mark.slow
def test_a_constant_linke_raster_is_the_number(tmp_path, runner, dem):
    """A raster of one value (on the DEM's grid, or a coarser geographic one resampled) gives
    the bits of that number; twelve of them (a pattern) the bits of the twelve numbers."""
    num, same, other = (tmp_path / f"{n}.tif" for n in ("num", "same", "other"))
    _run(runner, [dem, num, "--linke-turbidity", "3.7"] + SPAN)
    _run(runner, [dem, same, "--linke-turbidity",
                  write_geotiff(tmp_path / "t.tif", np.full((36, 44), 3.7), T0, UTM11)] + SPAN)
    with rasterio.open(dem) as ds:
        from rasterio.warp import transform_bounds
        w, s, e, n = transform_bounds(ds.crs, "EPSG:4326", *ds.bounds)
    geo = write_geotiff(tmp_path / "g.tif", np.full((20, 20), 3.7),
                        Affine((e - w + 0.02) / 20, 0, w - 0.01, 0, -(n - s + 0.02) / 20,
                               n + 0.01), CRS.from_epsg(4326))
    _run(runner, [dem, other, "--linke-turbidity", geo] + SPAN)
    ref = _bands(num)[0]
    np.testing.assert_array_equal(_bands(same)[0], ref)
    np.testing.assert_array_equal(_bands(other)[0], ref)
    lt = ["2.5", "4.5"] + ["3"] * 10
    for m in range(1, 13):
        write_geotiff(tmp_path / f"lt{m}.tif", np.full((36, 44), float(lt[m - 1])), T0, UTM11)
    nums, pat = tmp_path / "nums.tif", tmp_path / "pat.tif"
    _run(runner, [dem, nums, "--linke-turbidity", ",".join(lt)] + SPAN)
    _run(runner, [dem, pat, "--linke-turbidity", tmp_path / "lt{month}.tif"] + SPAN)
    np.testing.assert_array_equal(_bands(pat)[0], _bands(nums)[0])


@pytest.mark.slow
def test_monthly_linke_rasters_give_each_sample_its_months_raster(tmp_path, runner, dem):
    """12 Linke rasters by a pattern: January's of two zones (2 | 5), February's of one value
    (3.5): the run over January and February is the January days' runs with each zone's
    number plus the February days' run with 3.5 (and --monthly's bands those parts)."""
    for m in range(1, 13):
        if m == 1:
            _zones(tmp_path, "lt1.tif", 2.0, 5.0)
        else:
            write_geotiff(tmp_path / f"lt{m}.tif", np.full((36, 44), 3.5), T0, UTM11)
    both = tmp_path / "b.tif"
    _run(runner, [dem, both, "--linke-turbidity", tmp_path / "lt{month}.tif", "--monthly"]
         + SPAN)
    jan = {}
    for v in ("2", "5"):
        jan[v] = tmp_path / f"j{v}.tif"
        _run(runner, [dem, jan[v], "--date", "2027-01-30", "--end-date", "2027-01-31",
                      "--linke-turbidity", v] + SPAN[4:])
    feb = tmp_path / "f.tif"
    _run(runner, [dem, feb, "--date", "2027-02-01", "--end-date", "2027-02-02",
                  "--linke-turbidity", "3.5"] + SPAN[4:])
    b = _bands(both)[0]
    f = _bands(feb)[0].astype(np.float64)
    lo, hi = (_bands(jan[v])[0].astype(np.float64) for v in ("2", "5"))
    _zone_equal(b[:4], lo + f, hi + f)
    _zone_equal(b[4], lo[3], hi[3])                 # January's global band
    np.testing.assert_allclose(b[5], f[3], **ROUNDING)   # February's


@pytest.mark.slow
def test_clear_sky_indices_of_one_are_the_clear_sky(tmp_path, runner, dem):
    """--beam-index and --diffuse-index 1 (numbers, or rasters of 1) leave the bits of the run
    without them."""
    plain, ones, ras = tmp_path / "p.tif", tmp_path / "o.tif", tmp_path / "r.tif"
    one = write_geotiff(tmp_path / "one.tif", np.ones((36, 44)), T0, UTM11)
    _run(runner, [dem, plain] + SPAN)
    _run(runner, [dem, ones, "--beam-index", "1", "--diffuse-index", "1"] + SPAN)
    _run(runner, [dem, ras, "--beam-index", one, "--diffuse-index", one] + SPAN)
    np.testing.assert_array_equal(_bands(ones)[0], _bands(plain)[0])
    np.testing.assert_array_equal(_bands(ras)[0], _bands(plain)[0])


@pytest.mark.slow
@pytest.mark.parametrize("extra", [[], ["--perez"]])
def test_clear_sky_index_rasters_weight_each_cell(tmp_path, runner, dem, extra):
    """A beam index raster of 0.35 west and 0.8 east, a diffuse index raster of 0.9 west and
    0.55 east, with a Linke raster (2.3 | 4.7): each zone's bands are those of the run with the
    zone's three numbers (Perez: each cell's coefficients from its own real sky)."""
    kb, kd = _zones(tmp_path, "kb.tif", 0.35, 0.8), _zones(tmp_path, "kd.tif", 0.9, 0.55)
    tl = _zones(tmp_path, "tl.tif", 2.3, 4.7)
    r, lo, hi = (tmp_path / f"{n}.tif" for n in ("r", "lo", "hi"))
    _run(runner, [dem, r, "--beam-index", kb, "--diffuse-index", kd, "--linke-turbidity", tl]
         + extra + SPAN)
    _run(runner, [dem, lo, "--beam-index", "0.35", "--diffuse-index", "0.9",
                  "--linke-turbidity", "2.3"] + extra + SPAN)
    _run(runner, [dem, hi, "--beam-index", "0.8", "--diffuse-index", "0.55",
                  "--linke-turbidity", "4.7"] + extra + SPAN)
    _zone_equal(_bands(r)[0], _bands(lo)[0], _bands(hi)[0])
    tags = _bands(r)[2]
    assert "coeff_bh" in tags["BEAM_INDEX"] and tags["DIFFUSE_INDEX"].startswith("raster kd")


@pytest.mark.slow
def test_linke_and_index_rasters_with_context_and_instants(tmp_path, runner, dem):
    """--context: a tile's bands are the bits of the whole DEM's run on its cells; --time: each
    instant's bands per zone those of the numbers' instants."""
    tl, kb = _zones(tmp_path, "tl.tif", 2.3, 4.7), _zones(tmp_path, "kb.tif", 0.35, 0.8)
    with rasterio.open(dem) as ds:
        z = ds.read(1)
    tile = write_geotiff(tmp_path / "tile.tif", z[10:30, 15:40].copy(),
                         T0 @ Affine.translation(15, 10), UTM11)
    args = ["--linke-turbidity", tl, "--beam-index", kb, "--perez"] + SPAN
    whole, part = tmp_path / "w.tif", tmp_path / "t.tif"
    _run(runner, [dem, whole] + args)
    _run(runner, [tile, part, "--context", dem] + args)
    np.testing.assert_array_equal(_bands(part)[0], _bands(whole)[0][:, 10:30, 15:40])
    inst = ["--time", "2027-01-30T20:00Z", "--time", "2027-02-01T22:30Z",
            "--skyview-directions", "8", "-q"]
    r, lo, hi = (tmp_path / f"i{n}.tif" for n in ("r", "lo", "hi"))
    _run(runner, [dem, r, "--linke-turbidity", tl, "--beam-index", kb] + inst)
    _run(runner, [dem, lo, "--linke-turbidity", "2.3", "--beam-index", "0.35"] + inst)
    _run(runner, [dem, hi, "--linke-turbidity", "4.7", "--beam-index", "0.8"] + inst)
    _zone_equal(_bands(r)[0], _bands(lo)[0], _bands(hi)[0])
    assert _bands(r)[2]["LINKE_TURBIDITY"].startswith("raster tl.tif")


@pytest.mark.parametrize("option", ["--linke-turbidity", "--beam-index", "--diffuse-index"])
def test_the_sky_rasters_are_inputs_of_the_run(tmp_path, runner, dem, option):
    """An output may not overwrite a raster the run reads (--overwrite or not), for the sums and
    the instants alike; a pattern's twelve files are each an input."""
    value = "3" if option == "--linke-turbidity" else "0.5"
    ras = write_geotiff(tmp_path / "in.tif", np.full((36, 44), float(value)), T0, UTM11)
    for m in range(1, 13):
        write_geotiff(tmp_path / f"p{m}.tif", np.full((36, 44), float(value)), T0, UTM11)
    for out, val, when in ((ras, ras, SPAN), (tmp_path / "p7.tif", tmp_path / "p{month}.tif",
                                              SPAN),
                           (ras, ras, ["--time", "2027-01-30T20:00Z", "-q"])):
        r = runner.invoke(cli, ["irradiance", str(dem), str(out), option, str(val),
                                "--overwrite"] + when)
        assert r.exit_code == 2 and "is also an input" in r.stderr, r.output
        assert len(r.stderr.strip().splitlines()) == 1
    with rasterio.open(ras) as ds:
        assert ds.count == 1 and float(ds.read(1)[0, 0]) == float(value)
