"""engine/irradiance.py: the bands' sums against pvlib's plane-of-array model on an open plane
(isotropic and Perez 1990), Haurwitz's formula, the period's samples, measured series (CSV,
interpolation, refusals) and the options' checks."""

import datetime as dt
import math
import types
import zoneinfo

import numpy as np
import pytest

from hillshade_rt.engine import irradiance as irr
from hillshade_rt.errors import HillshadeError

UTC = dt.timezone.utc


def test_check_options():
    irr.check_options(0.2, 3.0, 32)
    for args, why in [((1.5,), "--albedo must be between 0 and 1"),
                      ((float("nan"),), "--albedo"),
                      ((0.2, 0.5), "--linke-turbidity must be between 1 and 10"),
                      ((0.2, None, 3), "--skyview-directions must be between 4 and 360")]:
        with pytest.raises(HillshadeError, match=why):
            irr.check_options(*args)


def test_period_samples_midpoints_and_weights():
    tz = zoneinfo.ZoneInfo("Europe/Zurich")
    start = dt.datetime(2026, 3, 29, 0, 0, tzinfo=tz)       # the clocks go forward at 02:00
    end = dt.datetime(2026, 3, 29, 5, 0, tzinfo=tz)        # four hours of elapsed time
    times, w = irr.period_samples(start, end, dt.timedelta(hours=1.5))
    assert w == [1.5, 1.5, 1.0]
    assert [t.astimezone(UTC).strftime("%H:%M") for t in times] == ["23:45", "01:15", "02:30"]
    assert all(t.tzinfo is tz for t in times)
    with pytest.raises(HillshadeError, match="is not after --start"):
        irr.period_samples(end, start, dt.timedelta(hours=1))
    with pytest.raises(HillshadeError, match="--step must be positive"):
        irr.period_samples(start, end, dt.timedelta(0))
    with pytest.raises(HillshadeError, match="more than 3 samples"):
        irr.period_samples(start, end, dt.timedelta(minutes=30), limit=3)


def test_haurwitz_is_its_formula_and_split_by_erbs():
    """Haurwitz's model as pvlib writes it (Reno, Hansen & Stein 2012, SAND2012-2389):
    GHI = 1098 cos Z exp(-0.059 / cos Z); zero with the sun down."""
    times = [dt.datetime(2026, 6, 21, h, tzinfo=UTC) for h in (9, 12, 23)]
    zen = np.array([60.0, 30.0, 100.0])
    sky = irr.clear_sky(times, zen, 46.0, 8.0, 500.0, model="haurwitz")
    cz = np.cos(np.radians(zen[:2]))
    np.testing.assert_allclose(sky.ghi[:2], 1098.0 * cz * np.exp(-0.059 / cz), rtol=1e-9)
    assert sky.ghi[2] == 0 and sky.dni[2] == 0 and sky.split == irr.ERBS
    # the split closes: GHI = DNI cos Z + DHI
    np.testing.assert_allclose(sky.dni[:2] * cz + sky.dhi[:2], sky.ghi[:2], rtol=1e-6)
    with pytest.raises(HillshadeError, match="--clear-sky must be one of ineichen, haurwitz"):
        irr.clear_sky(times, zen, 46.0, 8.0, 500.0, model="solis")


def test_measured_sky():
    times = [dt.datetime(2026, 6, 21, 12, tzinfo=UTC)] * 2
    sky = irr.measured_sky(times, [30.0, 40.0], [-3.0, 700.0], [-1.0, 600.0], [5.0, 150.0])
    np.testing.assert_array_equal(sky.ghi, [0.0, 700.0])
    np.testing.assert_array_equal(sky.dni, [0.0, 600.0])
    assert sky.split is None
    with pytest.raises(HillshadeError, match="give both dni and dhi"):
        irr.measured_sky(times, [30.0, 40.0], [1.0, 2.0], dni=[1.0, 2.0])
    with pytest.raises(HillshadeError, match="one value per time"):
        irr.measured_sky(times, [30.0, 40.0], [1.0, 2.0], [1.0], [1.0])
    assert irr.measured_sky(times, [30.0, 40.0], [500.0, 600.0]).split == irr.ERBS


def test_read_series_and_interpolate(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("# a station\nTime,GHI,dni,dhi\n2026-06-21T10:00+02:00,100,50,60\n\n"
                 "2026-06-21T09:00Z,300,250,70\n")
    unix, ghi, dni, dhi = irr.read_series(str(p))
    assert list(unix) == [dt.datetime(2026, 6, 21, 8, tzinfo=UTC).timestamp(),
                          dt.datetime(2026, 6, 21, 9, tzinfo=UTC).timestamp()]
    np.testing.assert_array_equal(ghi, [100.0, 300.0])
    t = [dt.datetime(2026, 6, 21, 8, 15, tzinfo=UTC)]
    g, none = irr.series_at(t, unix, ghi, None)
    assert g[0] == pytest.approx(150.0) and none is None
    with pytest.raises(HillshadeError, match="runs from .* but the period's samples run"):
        irr.series_at([dt.datetime(2026, 6, 21, 9, 1, tzinfo=UTC)], unix, ghi)
    q = tmp_path / "g.csv"
    q.write_text("time,ghi\n2026-06-21 10:00,1\n2026-06-21 11:00,2\n")
    unix, ghi, dni, dhi = irr.read_series(str(q), zoneinfo.ZoneInfo("Europe/Zurich"))
    assert dni is None and dhi is None
    assert unix[0] == dt.datetime(2026, 6, 21, 8, tzinfo=UTC).timestamp()


@pytest.mark.parametrize("text, why", [
    ("", "empty"),
    ("time,dni\n", "no ghi column"),
    ("time,ghi,dni\n", "give both dni and dhi columns"),
    ("time,ghi\n2026-06-21T10:00Z\n", "line 2: 1 fields, the header has 2"),
    ("time,ghi\n2026-06-21T10:00Z,x\n2026-06-21T11:00Z,1\n", "line 2: ghi 'x' is not a number"),
    ("time,ghi\n2026-06-21T10:00Z,1\n", "needs at least two rows"),
    ("time,ghi\n2026-06-21T10:00Z,1\n2026-06-21T10:00Z,2\n", "row 2 is not after row 1"),
    ("time,ghi\nnoon,1\n2026-06-21T10:00Z,2\n", "s.csv line 2: "),
])
def test_read_series_refusals(tmp_path, text, why):
    p = tmp_path / "s.csv"
    p.write_text(text)
    with pytest.raises(HillshadeError, match=why):
        irr.read_series(str(p))


def _plane_case():
    """An open plane (slope 25 deg facing 203.7 deg) under suns of one day: what pvlib needs
    and what ``sums`` needs (the plane's cos i as the direct term, Vd = (1 + cos S) / 2)."""
    from pvlib.irradiance import aoi
    tilt, aspect = 25.0, 203.7
    times = [dt.datetime(2026, 5, 2, h, 30, tzinfo=UTC) for h in (6, 9, 11, 14, 17, 21)]
    zen = np.array([80.0, 50.0, 35.0, 42.0, 70.0, 95.0])
    saz = np.array([80.0, 130.0, 163.0, 220.0, 275.0, 300.0])
    ghi = np.array([60.0, 550.0, 800.0, 700.0, 200.0, 0.0])
    dhi = np.array([40.0, 120.0, 100.0, 150.0, 90.0, 0.0])
    dni = np.array([120.0, 660.0, 860.0, 740.0, 320.0, 0.0])
    cos_i = np.cos(np.radians(aoi(tilt, aspect, zen, saz)))
    suns = [types.SimpleNamespace(tiles=[], elevation=90.0 - z) for z in zen]
    cos_s = math.cos(math.radians(tilt))
    vd = np.full((1, 2), (1.0 + cos_s) / 2.0, np.float32)
    slopes = (np.full((1, 2), cos_s), np.full((1, 2), math.sin(math.radians(tilt))))
    sky = irr.measured_sky(times, zen, ghi, dni, dhi)

    def direct(s, timed):
        k = [x.elevation for x in suns].index(s.elevation)
        return np.full((1, 2), max(cos_i[k], 0.0), np.float32)
    return locals()


def test_isotropic_bands_on_an_open_plane_are_pvlibs():
    from pvlib.irradiance import get_total_irradiance
    c = _plane_case()
    bands = irr.sums(c["direct"], np.zeros((1, 2), bool), lambda: c["slopes"], c["suns"],
                     np.ones(6), c["sky"], c["vd"], 0.2, per_time=True)
    poa = get_total_irradiance(c["tilt"], c["aspect"], c["zen"], c["saz"], c["dni"],
                               c["ghi"], c["dhi"], albedo=0.2, model="isotropic")
    np.testing.assert_allclose(bands["beam"][:, 0, 0], poa["poa_direct"], rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(bands["diffuse"][:, 0, 0], poa["poa_sky_diffuse"], rtol=1e-5)
    np.testing.assert_allclose(bands["reflected"][:, 0, 0], poa["poa_ground_diffuse"],
                               rtol=1e-5)
    np.testing.assert_allclose(bands["global"][:, 0, 0], poa["poa_global"], rtol=1e-5,
                               atol=1e-3)


def test_perez_diffuse_on_an_open_plane_is_pvlibs():
    import pandas as pd
    from pvlib.atmosphere import get_relative_airmass
    from pvlib.irradiance import get_extra_radiation, perez
    c = _plane_case()
    sky = irr.with_perez(c["sky"], c["times"], c["zen"])
    stats = {}
    bands = irr.sums(c["direct"], np.zeros((1, 2), bool), lambda: c["slopes"], c["suns"],
                     np.ones(6), sky, c["vd"], 0.2, perez=True, per_time=True, stats=stats)
    idx = pd.DatetimeIndex(c["times"])
    want = perez(c["tilt"], c["aspect"], c["dhi"], c["dni"], get_extra_radiation(idx),
                 c["zen"], c["saz"], get_relative_airmass(c["zen"]))
    np.testing.assert_allclose(bands["diffuse"][:, 0, 0], np.nan_to_num(np.asarray(want)),
                               rtol=1e-5, atol=1e-3)
    assert stats == {"samples": 6, "samples_with_shadows": 5}


def test_summed_bands_are_the_weighted_per_time_bands():
    c = _plane_case()
    w = np.array([0.5, 1.0, 1.0, 2.0, 1.5, 1.0])
    void = np.array([[False, True]])
    args = (c["direct"], void, lambda: c["slopes"], c["suns"], w, c["sky"], c["vd"], 0.3)
    per = irr.sums(*args, per_time=True)
    tot = irr.sums(*args)
    for k in irr.BANDS:
        assert tot[k].dtype == np.float32
        assert tot[k][0, 0] == pytest.approx(float(np.sum(w * per[k][:, 0, 0])), rel=1e-5)
    assert np.isnan(tot["beam"][0, 1]) and np.isnan(tot["global"][0, 1])
    with pytest.raises(HillshadeError, match="one weight and one sky value per sun"):
        irr.sums(c["direct"], void, None, c["suns"], w[:3], c["sky"], c["vd"], 0.3)
    with pytest.raises(HillshadeError, match="no Perez coefficients"):
        irr.sums(*args, perez=True)


def test_is_dark_and_definitions():
    assert irr.is_dark(types.SimpleNamespace(tiles=[], elevation=-0.1), False)
    assert not irr.is_dark(types.SimpleNamespace(tiles=[], elevation=-0.1), True)   # the disk
    tiles = [types.SimpleNamespace(elevation=e) for e in (-3.0, 0.5)]
    assert not irr.is_dark(types.SimpleNamespace(tiles=tiles, elevation=-3.0), False)
    text = irr.definitions("perez", 16, True)
    assert "Perez 1990" in text and "16 directions" in text and "visible fraction" in text
    assert "DHI * Vd (isotropic" in irr.definitions("isotropic", 32, False)


def _old_sums(shader, suns, w, sky, vd, albedo, soft, perez):
    """The sums as numpy made them sun by sun (the reference the in-place kernel keeps)."""
    from hillshade_rt.engine.shader import render
    void = np.isnan(shader.z)
    vd64 = vd.astype(np.float64)
    if perez:
        cos_s, sin_s = irr.slope_terms(shader.z, shader.grid)
        share = np.minimum(vd64 / ((1.0 + cos_s) / 2.0), 1.0)
    beam, diffuse = np.zeros(void.shape), np.zeros(void.shape)
    for k, s in enumerate(suns):
        dni, dhi = float(sky.dni[k]), float(sky.dhi[k])
        circ = perez and dhi > 0 and bool(sky.perez_on[k]) and sky.f1[k] > 0
        d_k = None
        if (dni > 0 or circ) and not irr.is_dark(s, soft):
            lit = render(shader, s, "sun", soft=soft)
            d_k = np.maximum(irr.cos_incidence(shader, s), np.float32(0.0)) * lit
            beam += w[k] * (np.float32(dni) * d_k)
        if perez and dhi > 0 and sky.perez_on[k]:
            d_t = (1.0 - sky.f1[k]) * vd64 + sky.f2[k] * sin_s * share
            if d_k is not None and sky.f1[k] > 0:
                d_t += (sky.f1[k] / sky.b[k]) * d_k
            diffuse += w[k] * np.maximum(dhi * d_t, 0.0)
    if not perez:
        diffuse = float(np.sum(w * sky.dhi)) * vd64
    reflected = float(np.sum(w * sky.ghi)) * albedo * (1.0 - vd64)
    beam[void] = np.nan
    diffuse[void] = np.nan
    return {k: v.astype(np.float32) for k, v in (("beam", beam), ("diffuse", diffuse),
                                                ("reflected", reflected),
                                                ("global", beam + diffuse + reflected))}


@pytest.mark.parametrize("soft, perez", [(False, False), (True, True), (False, True)])
def test_accumulate_in_place_is_the_numpy_sums(soft, perez):
    """``accumulate`` (Horn's normals once, every sample added in place, each tile's own sun)
    gives the bits of the numpy sums sun by sun, on a geographic DEM whose suns vary per tile
    (a tolerance of 0.001 deg), with voids."""
    from hillshade_rt.engine.shader import Shader
    from hillshade_rt.model.geometry import Grid
    from hillshade_rt.model.site import Site
    from hillshade_rt.model.sun import sun_over
    from hillshade_rt.testing import fractal_terrain
    z = fractal_terrain(64, 80, 11, relief=900.0).astype(np.float32)
    z[10, 12] = z[40:43, 60:62] = np.nan
    grid = Grid(64, 80, np.linspace(76.0, 78.0, 64), np.full(64, 92.6), 1, -1, "test")
    tz = zoneinfo.ZoneInfo("America/Los_Angeles")
    times, w = irr.period_samples(dt.datetime(2026, 6, 21, 4, tzinfo=tz),
                                  dt.datetime(2026, 6, 21, 21, tzinfo=tz), dt.timedelta(hours=2))
    site = Site(34.3, -118.2, 900.0, "test",
                to_lonlat=lambda r, c: (-118.2 + 0.2 * (c / 80.0 - 0.5),
                                        34.3 - 0.2 * (r / 64.0 - 0.5)),
                convergence=lambda r, c: 0.0 * np.asarray(r))
    suns = sun_over(site, z.shape, times, tolerance=0.001)
    assert any(s.tiles and len(s.tiles) > 1 for s in suns)
    zen = np.array([s.zenith for s in suns])
    sky = irr.clear_sky(times, zen, 34.3, -118.2, 900.0, "ineichen", 3.0)
    if perez:
        irr.with_perez(sky, times, zen)
    vd = (0.6 + 0.4 * np.random.default_rng(1).random(z.shape)).astype(np.float32)
    vd[np.isnan(z)] = np.nan
    got = irr.accumulate(Shader(z, grid, "auto", {}, "cpu", False), suns, w, sky, vd, 0.25,
                         soft=soft, perez=perez)
    want = _old_sums(Shader(z, grid, "auto", {}, "cpu", False), suns, np.asarray(w), sky, vd,
                     0.25, soft, perez)
    for k in irr.BANDS:
        assert np.array_equal(got[k].view(np.uint32), want[k].view(np.uint32)), k
    assert np.isnan(got["beam"][10, 12]) and np.nanmax(got["beam"]) > 0


def test_tile_suns_is_each_cells_tile():
    """Each cell's vector is the sun of the region it lies in."""
    from hillshade_rt.algorithms.relief import sun_vector
    from hillshade_rt.model.sun import Region, SunOver
    tiles = [Region(slice(0, 3), slice(0, 4), 163.0, 20.0), Region(slice(0, 3), slice(4, 7),
                                                                    203.7, 21.0),
             Region(slice(3, 5), slice(0, 4), 290.0, 22.0), Region(slice(3, 5), slice(4, 7),
                                                                   291.0, 23.0)]
    rt, ct, vec = irr.tile_suns(SunOver(None, 0.0, 20.0, tiles=tiles), (5, 7))
    for t in tiles:
        for r in range(t.rows.start, t.rows.stop):
            for c in range(t.cols.start, t.cols.stop):
                assert tuple(vec[rt[r], ct[c]]) == sun_vector(t.azimuth, t.elevation)
    rt, ct, vec = irr.tile_suns(SunOver(None, 203.7, 10.0), (5, 7))
    assert (rt == 0).all() and (ct == 0).all() and tuple(vec[0, 0]) == sun_vector(203.7, 10.0)
    with pytest.raises(HillshadeError, match="do not cover"):
        irr.tile_suns(SunOver(None, 0.0, 20.0, tiles=tiles[:3]), (5, 7))


def test_surface_elevation_is_90_minus_the_incidence_angle():
    cos_i = np.array([[1.0, 0.5, 0.0, -0.5, np.nan, 1.0000001]], np.float32)
    got = irr.surface_elevation(cos_i)
    assert got.dtype == np.float32
    np.testing.assert_allclose(got[0, :4], [90.0, 30.0, 0.0, -30.0], atol=1e-5)
    assert np.isnan(got[0, 4]) and got[0, 5] == 90.0          # rounding past 1 is clipped


@pytest.mark.parametrize("perez", [False, True])
def test_an_instant_is_one_sample_of_the_sums(perez):
    """``instant``: sample k alone with weight 1 (the numpy sums of that one sun, bit for bit,
    as ``accumulate`` gives them), so the period's sums are the weighted instants (to float32
    rounding); "incidence" is the sun's elevation above each cell's surface, per tile; on a
    geographic DEM whose suns vary per tile, with voids."""
    from hillshade_rt.engine.shader import Shader
    from hillshade_rt.model.geometry import Grid
    from hillshade_rt.model.site import Site
    from hillshade_rt.model.sun import sun_over
    from hillshade_rt.testing import fractal_terrain
    z = fractal_terrain(48, 56, 13, relief=700.0).astype(np.float32)
    z[7, 9] = np.nan
    grid = Grid(48, 56, np.linspace(76.0, 78.0, 48), np.full(48, 92.6), 1, -1, "test")
    tz = zoneinfo.ZoneInfo("America/Los_Angeles")
    times, w = irr.period_samples(dt.datetime(2026, 3, 2, 5, tzinfo=tz),
                                  dt.datetime(2026, 3, 2, 19, tzinfo=tz), dt.timedelta(hours=2))
    site = Site(34.3, -118.2, 900.0, "test",
                to_lonlat=lambda r, c: (-118.2 + 0.2 * (c / 56.0 - 0.5),
                                        34.3 - 0.2 * (r / 48.0 - 0.5)),
                convergence=lambda r, c: 0.0 * np.asarray(r))
    suns = sun_over(site, z.shape, times, tolerance=0.001)
    zen = np.array([s.zenith for s in suns])
    sky = irr.clear_sky(times, zen, 34.3, -118.2, 900.0, "ineichen", 3.0)
    if perez:
        irr.with_perez(sky, times, zen)
    vd = (0.6 + 0.4 * np.random.default_rng(2).random(z.shape)).astype(np.float32)
    vd[np.isnan(z)] = np.nan
    shader = Shader(z, grid, "auto", {}, "cpu", False)
    total = {k: np.zeros(z.shape) for k in irr.BANDS}
    stats = {}
    for k, s in enumerate(suns):
        one = irr.sky_at(sky, k)
        assert one.dni.shape == (1,) and one.dni[0] == sky.dni[k]
        assert (one.f1 is None) == (not perez)
        got = irr.instant(shader, s, sky, k, vd, 0.25, perez=perez, stats=stats)
        want = _old_sums(shader, [s], np.ones(1), one, vd, 0.25, False, perez)
        for q in irr.BANDS:
            assert np.array_equal(got[q].view(np.uint32), want[q].view(np.uint32)), (k, q)
            total[q] += w[k] * got[q]
        inc = irr.surface_elevation(irr.cos_incidence(shader, s))
        assert np.array_equal(got["incidence"], inc, equal_nan=True)
        assert np.isnan(got["incidence"][7, 9]) and np.isnan(got["beam"][7, 9])
    assert set(got) == set(irr.INSTANT_BANDS) and stats["samples_with_shadows"] >= 5
    period = irr.accumulate(shader, suns, w, sky, vd, 0.25, perez=perez)
    for q in irr.BANDS:
        np.testing.assert_allclose(total[q], period[q], rtol=1e-6, atol=1e-3)
    assert irr.RSUN_NAMES["global"] == "glob_rad" and irr.RSUN_NAMES["incidence"] == "incidout"


def test_real_sky_is_r_suns_indices():
    """r.sun's coeff_bh, coeff_dh: DNI times kb, DHI times kd, the global horizontal
    kb (GHI - DHI) + kd DHI; indices of 1 (or kb = kd) keep the sky's bits up to the factor."""
    c = _plane_case()
    sky = c["sky"]
    real = irr.real_sky(sky, 0.4, 0.7)
    np.testing.assert_array_equal(real.dni, 0.4 * sky.dni)
    np.testing.assert_array_equal(real.dhi, 0.7 * sky.dhi)
    np.testing.assert_allclose(real.ghi, 0.4 * (sky.ghi - sky.dhi) + 0.7 * sky.dhi, rtol=1e-15)
    one = irr.real_sky(sky, 1.0, None)
    for k in ("dni", "dhi", "ghi"):
        np.testing.assert_array_equal(getattr(one, k), getattr(sky, k))
    np.testing.assert_array_equal(irr.real_sky(sky, 0.5, 0.5).ghi, 0.5 * sky.ghi)
    months = np.array([0.2, 0.9, 0.9, 0.3, 0.3, 0.3])        # one per sample
    np.testing.assert_array_equal(irr.real_sky(sky, months, None).dni, months * sky.dni)


def _cells_case(perez):
    """Four cells on the open plane of ``_plane_case`` with Linke turbidities 1.5, 2.8, 4.4,
    7.1 and beam indices 1, 0.3, 0.75, 0.5 (diffuse index 0.6): the ``CellSky`` of the suns of
    its times at 34°N 118°W, 900 m."""
    c = _plane_case()
    times, zen = c["times"], c["zen"]
    tl = np.array([[1.5, 2.8, 4.4, 7.1]])
    kb = np.array([[1.0, 0.3, 0.75, 0.5]])
    am, extra, cosz, consts = irr.ineichen_terms(times, zen, 34.0, -118.0, 900.0)
    z, am_rel = irr.perez_terms(times, zen)
    corr = irr.ineichen_correction(tl, consts)
    raw = irr.clear_sky(times, zen, 34.0, -118.0, 900.0, "ineichen", 3.0)
    cells = irr.CellSky(lambda k: (tl, corr, kb, 0.6),
                        irr.SampleSky(raw.ghi, raw.dni, raw.dhi, am, extra, cosz, consts, z,
                                      am_rel))
    sky = irr.real_sky(raw, 0.6, 0.6)
    if perez:
        irr.with_perez(sky, times, zen)
    suns = c["suns"]

    def direct(s, timed):
        k = [x.elevation for x in suns].index(s.elevation)
        return np.full((1, 4), max(c["cos_i"][k], 0.0), np.float32)
    vd = np.full((1, 4), c["vd"][0, 0], np.float32)
    slopes = (np.full((1, 4), c["slopes"][0][0, 0]), np.full((1, 4), c["slopes"][1][0, 0]))
    return c, tl, kb, cells, sky, direct, vd, slopes


@pytest.mark.parametrize("perez", [False, True])
def test_an_open_sky_per_cell_is_each_cells_numbers_sky(perez):
    """``sums`` with a ``CellSky`` (each cell's Linke turbidity, beam index): each cell's
    bands are those of the sums under pvlib's Ineichen sky with its numbers (``clear_sky``,
    ``real_sky``, ``with_perez``), up to float rounding (the per-cell clear sky is pvlib's
    formula evaluated in numba: within an ulp of pvlib's)."""
    c, tl, kb, cells, sky, direct, vd, slopes = _cells_case(perez)
    w = np.array([0.5, 1.0, 1.0, 2.0, 1.5, 1.0])
    void = np.zeros((1, 4), bool)
    stats = {}
    got = irr.sums(direct, void, lambda: slopes, c["suns"], w, sky, vd, 0.25, perez=perez,
                   cells=cells, stats=stats)
    assert stats["samples_with_shadows"] == 5      # the sun down in the last: no sky at all
    for j in range(4):
        one = irr.real_sky(irr.clear_sky(c["times"], c["zen"], 34.0, -118.0, 900.0,
                                         "ineichen", float(tl[0, j])), float(kb[0, j]), 0.6)
        if perez:
            irr.with_perez(one, c["times"], c["zen"])
        want = irr.sums(direct, void, lambda: slopes, c["suns"], w, one, vd, 0.25,
                        perez=perez)
        for k in irr.BANDS:
            np.testing.assert_allclose(got[k][0, j], want[k][0, j], rtol=1e-6, err_msg=k)
    # the turbidities tell: the clearest cell's beam (per unit index) is the largest
    per_index = got["beam"][0] / kb[0]
    assert np.all(np.diff(per_index) < 0)
    with pytest.raises(HillshadeError, match="summed, not stacked"):
        irr.sums(direct, void, lambda: slopes, c["suns"], w, sky, vd, 0.25, per_time=True,
                 cells=cells)


def test_the_per_cell_clear_sky_is_pvlibs_ineichen():
    """The kernel's clear sky of each cell against ``pvlib.clearsky.ineichen`` at its Linke
    turbidity: GHI (the reflected light's sum with albedo 1 and 1 - Vd = 1), DHI (the
    isotropic diffuse with Vd = 1) and DNI (the beam with a direct term of 1, float32)."""
    from pvlib.clearsky import ineichen
    c, tl, kb, cells, sky, direct, vd, slopes = _cells_case(False)
    for k in range(5):                                  # the samples with the sun up
        one = cells.sample(k)
        one.at = (lambda t: lambda _k: (t, irr.ineichen_correction(t, cells.terms.consts), 1.0,
                                        1.0))(tl)
        def run(v):
            return irr.sums(lambda s, timed: np.ones((1, 4), np.float32),
                            np.zeros((1, 4), bool), None, [c["suns"][k]], [1.0],
                            irr.sky_at(sky, k), np.full((1, 4), v, np.float32), 1.0, cells=one)
        dark, bright = run(0.0), run(1.0)
        ref = ineichen(c["zen"][k], cells.terms.am[k], tl[0], 900.0, cells.terms.extra[k])
        np.testing.assert_allclose(dark["reflected"][0], ref["ghi"], rtol=1e-7)
        np.testing.assert_allclose(bright["diffuse"][0], ref["dhi"], rtol=1e-7)
        np.testing.assert_allclose(dark["beam"][0], ref["dni"], rtol=1e-7)
        assert np.all(dark["diffuse"][0] == 0.0) and np.all(bright["reflected"][0] == 0.0)
        assert ref["ghi"][0] > ref["ghi"][-1] > 0.0
