"""The per-cell-sun mask (algorithms.subsolar through arrays.subsolar_mask): the terminator on
a sphere, the plain reference with each cell's own sun, the directional mask on a small window,
the GPU twin under the simulator."""

import math

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.engine import arrays, cell_suns
from hillshade_rt.algorithms.pyramid import MaxPyramid
from hillshade_rt.model.earth import dem_body
from hillshade_rt.errors import HillshadeError
from hillshade_rt.testing import (MOON_GEOGRAPHIC, MOON_NORTH_POLAR, fractal_terrain, memory_dem,
                                  reference_mask)

FAR = 1e16


def _subsolar_at(lat0, lon0, azimuth, elevation):
    """The subsolar point (far sun, sphere) that gives a cell at (lat0, lon0) the sun at
    ``azimuth`` (true) and ``elevation``: 90 - elevation degrees away along that bearing."""
    p, l, b = math.radians(lat0), math.radians(lon0), math.radians(azimuth)
    d = math.radians(90.0 - elevation)
    ps = math.asin(math.sin(p) * math.cos(d) + math.cos(p) * math.sin(d) * math.cos(b))
    ls = l + math.atan2(math.sin(b) * math.sin(d) * math.cos(p),
                        math.cos(d) - math.sin(p) * math.sin(ps))
    return math.degrees(ps), math.degrees(ls)


def _cos_distance(dem, lat_s, lon_s):
    """cos of the angular distance from every cell centre to the subsolar point (plain numpy,
    lat/lon from pyproj)."""
    from pyproj import CRS, Transformer
    rows, cols = dem.shape
    t = dem.transform
    xx, yy = np.meshgrid(t.c + t.a * (np.arange(cols) + 0.5), t.f + t.e * (np.arange(rows) + 0.5))
    pcrs = CRS.from_user_input(dem.crs.to_wkt())
    if pcrs.is_geographic:
        lon, lat = xx, yy
    else:
        lon, lat = Transformer.from_crs(pcrs, pcrs.geodetic_crs, always_xy=True).transform(xx, yy)
    p, l = np.radians(lat), np.radians(lon)
    ps, ls = math.radians(lat_s), math.radians(lon_s)
    return np.sin(p) * math.sin(ps) + np.cos(p) * math.cos(ps) * np.cos(l - ls)


@pytest.mark.parametrize("crs, transform, shape, sub", [
    (MOON_GEOGRAPHIC, Affine(0.5, 0, -30.0, 0, -0.5, 30.0), (60, 120), (10.0, 100.0)),
    (MOON_GEOGRAPHIC, Affine(0.5, 0, -30.0, 0, -0.5, 30.0), (60, 120), (-23.4, -83.3)),
    (MOON_NORTH_POLAR, Affine(10000.0, 0, -300000.0, 0, -10000.0, 300000.0), (60, 60),
     (-5.0, 30.0)),
    (MOON_NORTH_POLAR, Affine(10000.0, 0, -305000.0, 0, -10000.0, 305000.0), (61, 61),
     (3.0, -131.3))])                                   # a cell centre on the pole
def test_terminator_on_a_flat_sphere(crs, transform, shape, sub):
    """No relief on the lunar sphere, curvature on: lit exactly where the subsolar point is
    less than 90 degrees away (flat terrain on a sphere never shadows itself)."""
    dem = memory_dem(np.zeros(shape, np.float32), transform, crs)
    cosd = _cos_distance(dem, *sub)
    lit = cosd > 0
    assert lit.any() and (~lit).any()                    # the terminator crosses the DEM
    assert np.abs(cosd).min() > 1e-6                     # and no cell is on it
    m = arrays.subsolar_mask(dem, *sub, sun_distance=FAR)
    np.testing.assert_array_equal(m, np.where(lit, 0, 1).astype(np.uint8))


def test_relief_on_a_sphere_casts_shadows_near_the_terminator():
    """A ridge near the terminator shadows the cells beyond it only with the sun low; the mask
    stays the terminator's where the sun is high."""
    z = np.zeros((60, 120), np.float32)
    z[:, 40] = 8000.0                        # a meridian wall at lon -9.75
    dem = memory_dem(z, Affine(0.5, 0, -30.0, 0, -0.5, 30.0), MOON_GEOGRAPHIC)
    m = arrays.subsolar_mask(dem, 0.0, -95.0, sun_distance=FAR)   # sun in the west, low
    flat = arrays.subsolar_mask(memory_dem(np.zeros_like(z), dem.transform, MOON_GEOGRAPHIC),
                                0.0, -95.0, sun_distance=FAR)
    extra = (m == 1) & (flat == 0)
    assert extra[:, 41:].any() and not extra[:, :40].any()


@pytest.mark.parametrize("crs, transform, centre, sun", [
    (MOON_GEOGRAPHIC, Affine(0.001, 0, 23.0, 0, -0.001, 41.0), (40.993, 23.0085), (203.7, 15.0)),
    (MOON_NORTH_POLAR, Affine(30.0, 0, 60000.0, 0, -30.0, -20000.0), (88.02, 108.43),
     (163.0, 9.0))])
def test_equals_the_plain_reference_with_each_cells_own_sun(crs, transform, centre, sun):
    """Curvature off: every cell is the plain-Python reference's cell for its own azimuth
    (grid: true + theta) and elevation."""
    z = fractal_terrain(14, 17, 7, relief=150.0)
    z[5, 6] = np.nan
    sub = _subsolar_at(*centre, *sun)
    dem = memory_dem(z, transform, crs)
    body = dem_body(dem)
    fr = cell_suns.CellFrames.of_dem(dem)
    s = cell_suns.sun_vector(body, *sub)
    m = arrays.subsolar_mask(dem, *sub, curvature=False, frames=fr, sun_xyz=s)
    az, el = cell_suns.cell_suns(fr, body, s, z)
    gaz = cell_suns.grid_azimuth(fr, az)
    assert 3.0 < el[np.isfinite(z)].min() and el.max() < 40.0
    assert np.ptp(gaz) > 1e-4                              # the suns differ from cell to cell
    g = dem.grid
    ref = np.empty_like(m)
    for r in range(z.shape[0]):
        for c in range(z.shape[1]):
            ref[r, c] = reference_mask(z, g.dx, g.dy, gaz[r, c], el[r, c], g.col_sign,
                                       g.row_sign)[r, c]
    np.testing.assert_array_equal(m, ref)
    assert (m == 1).any() and (m == 0).any() and m[5, 6] == 255


def test_small_window_equals_the_directional_mask_at_its_centre_sun():
    """A 1.2 km UTM window far from its central meridian: the mask of the window's centre sun
    (brute, grid azimuth) but for a handful of cells, whose suns differ by < 0.01 degree."""
    z = fractal_terrain(30, 30, 11, relief=200.0)
    dem = memory_dem(z, Affine(20.0, 0, 250000.0, 0, -20.0, 5200000.0), "EPSG:32633")
    body = dem_body(dem)
    sub = (-12.0, -48.0)
    fr = cell_suns.CellFrames.of_dem(dem)
    s = cell_suns.sun_vector(body, *sub)
    m = arrays.subsolar_mask(dem, *sub, curvature=False, frames=fr, sun_xyz=s)
    az, el = cell_suns.cell_suns(fr, body, s, z)
    gaz = cell_suns.grid_azimuth(fr, az)
    caz, cel = gaz[15, 15], el[15, 15]
    assert np.ptp(gaz) < 0.01 and np.ptp(el) < 0.01
    assert abs(caz % 90) > 5 and 5 < cel < 60                # a non-special sun
    d = arrays.shadow_mask(dem.heights, caz, cel, dem.grid, algorithm="brute", curvature=False)
    differ = int((m != d).sum())
    assert (d == 1).sum() > 50 and differ <= 8, differ


def test_many_suns_with_frames_and_pyramid_prepared_once():
    z = fractal_terrain(30, 33, 3, relief=2000.0)
    z[3:5, 7:9] = np.nan
    dem = memory_dem(z, Affine(0.01, 0, -5.0, 0, -0.01, 10.0), MOON_GEOGRAPHIC)
    fr = cell_suns.CellFrames.of_dem(dem)
    pyr = MaxPyramid(dem.heights)
    for sun in ((163.0, 8.0), (203.7, 12.0), (290.0, 6.0)):
        sub = _subsolar_at(9.85, -4.835, *sun)
        a = arrays.subsolar_mask(dem, *sub, frames=fr, pyramid=pyr)
        b = arrays.subsolar_mask(dem, *sub, pyramid=False)
        np.testing.assert_array_equal(a, b)
        assert (a == 255).sum() == 4 and (a == 1).any() and (a == 0).any()


def test_lift_and_curvature_only_light_more():
    z = fractal_terrain(30, 33, 5, relief=3000.0)
    dem = memory_dem(z, Affine(0.01, 0, -5.0, 0, -0.01, 10.0), MOON_GEOGRAPHIC)
    sub = (2.0, 80.0)
    flat = arrays.subsolar_mask(dem, *sub, curvature=False)
    curved = arrays.subsolar_mask(dem, *sub)
    lifted = arrays.subsolar_mask(dem, *sub, curvature=False, height_above_ground=200.0)
    assert ((curved == 1) <= (flat == 1)).all() and ((lifted == 1) <= (flat == 1)).all()
    assert (lifted != flat).any()


def test_bad_input():
    dem = memory_dem(np.zeros((4, 4), np.float32), Affine(0.1, 0, 0, 0, -0.1, 0),
                     MOON_GEOGRAPHIC)
    with pytest.raises(HillshadeError, match="latitude"):
        arrays.subsolar_mask(dem, 95.0, 0.0)
    with pytest.raises(HillshadeError, match="radius"):
        arrays.subsolar_mask(dem, 5.0, 0.0, sun_distance=1000.0)
    with pytest.raises(HillshadeError, match="read_dem"):
        arrays.subsolar_mask(np.zeros((4, 4)), 5.0, 0.0)


def test_gpu_twin_equals_cpu():
    """The CUDA kernel (the simulator here) gives the CPU's mask, curvature on and off."""
    from hillshade_rt.engine import gpu
    ok, what = gpu.status()
    if not ok:
        pytest.skip(what)
    z = fractal_terrain(12, 15, 9, relief=2500.0)
    z[4, 4] = np.nan
    dem = memory_dem(z, Affine(0.01, 0, -5.0, 0, -0.01, 10.0), MOON_GEOGRAPHIC)
    for curv in (True, False):
        cpu = arrays.subsolar_mask(dem, 1.0, 83.7, curvature=curv)
        out = arrays.subsolar_mask(dem, 1.0, 83.7, curvature=curv, backend="gpu")
        np.testing.assert_array_equal(out, cpu)
        assert (cpu == 1).any() and (cpu == 0).any()


def test_soft_on_a_flat_sphere_is_the_disk_above_the_astronomical_horizon():
    """Across the terminator (0.02 degree cells on the lunar sphere) the visible fraction is
    the disk above each cell's horizontal plane: solar.disk_fraction(0, el, asin(R_sun / d))."""
    from hillshade_rt.model.solar import disk_fraction
    dem = memory_dem(np.zeros((10, 60), np.float32), Affine(0.02, 0, -0.6, 0, -0.02, 10.1),
                     MOON_GEOGRAPHIC)
    body = dem_body(dem)
    sub = (3.0, 90.53)                       # the terminator at lon 0, lat 10
    f = arrays.subsolar_mask(dem, *sub, soft=True)
    fr = cell_suns.CellFrames.of_dem(dem)
    _, el = cell_suns.cell_suns(fr, body, cell_suns.sun_vector(body, *sub), dem.heights)
    radius = cell_suns.sun_radius_deg(cell_suns.AU)
    assert abs(radius - 0.2666) < 1e-3
    want = disk_fraction(0.0, el, radius)
    assert f.dtype == np.float32
    np.testing.assert_allclose(f, want, atol=1e-5)
    partial = (f > 0) & (f < 1)
    assert partial.sum() >= 10 and (f == 0).any() and (f == 1).any()


def test_soft_agrees_with_the_hard_mask_and_the_plain_horizon():
    """On relief: fraction > 1/2 exactly where the hard mask is lit; the partly lit cells'
    fractions are the disk above the plain reference's horizon along the cell's own ray."""
    from hillshade_rt.model.solar import disk_fraction
    from hillshade_rt.testing import reference_horizon
    z = fractal_terrain(24, 30, 4, relief=600.0)
    z[2, 3] = np.nan
    dem = memory_dem(z, Affine(0.002, 0, 12.0, 0, -0.002, -20.0), MOON_GEOGRAPHIC)
    body = dem_body(dem)
    sub = _subsolar_at(-20.024, 12.03, 203.7, 6.0)
    hard = arrays.subsolar_mask(dem, *sub, curvature=False)
    f = arrays.subsolar_mask(dem, *sub, curvature=False, soft=True)
    valid = np.isfinite(z)
    assert np.isnan(f[~valid]).all() and (hard[~valid] == 255).all()
    np.testing.assert_array_equal(f[valid] > 0.5, hard[valid] == 0)
    fr = cell_suns.CellFrames.of_dem(dem)
    az, el = cell_suns.cell_suns(fr, body, cell_suns.sun_vector(body, *sub), z)
    gaz = cell_suns.grid_azimuth(fr, az)
    radius = cell_suns.sun_radius_deg(cell_suns.AU)
    g = dem.grid
    partial = np.argwhere((f > 0) & (f < 1))
    assert len(partial) >= 5
    for r, c in partial[:25]:
        h = reference_horizon(z, g.dx, g.dy, gaz[r, c], g.col_sign, g.row_sign)[0][r, c]
        assert abs(f[r, c] - disk_fraction(h, el[r, c], radius)) < 1e-4, (r, c)


def test_soft_gpu_twin_equals_cpu():
    """The CUDA soft kernel (the simulator here) against the CPU's, far and near suns."""
    from hillshade_rt.engine import gpu
    ok, what = gpu.status()
    if not ok:
        pytest.skip(what)
    z = fractal_terrain(10, 13, 4, relief=600.0)
    z[2, 3] = np.nan
    dem = memory_dem(z, Affine(0.002, 0, 12.0, 0, -0.002, -20.0), MOON_GEOGRAPHIC)
    sub = _subsolar_at(-20.01, 12.013, 290.0, 9.0)
    for distance in (None, 3e9):       # a near sun: a disk 13 degrees across, many cells partly lit
        cpu = arrays.subsolar_mask(dem, *sub, soft=True, sun_distance=distance)
        out = arrays.subsolar_mask(dem, *sub, soft=True, sun_distance=distance, backend="gpu")
        # the decisions bit for bit; the partial fractions up to the backends' acos and atan
        whole = np.isnan(cpu) | (cpu == 0) | (cpu == 1)
        np.testing.assert_array_equal(out[whole], cpu[whole])
        np.testing.assert_allclose(out, cpu, atol=1e-6)
        assert ((cpu > 0) & (cpu < 1)).any() and np.isnan(cpu[2, 3])
