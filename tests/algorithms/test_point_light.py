"""A point light (issue 21, item 1): the ray from each cell ends at the light."""

import math

import numpy as np
import pytest

from hillshade_rt.algorithms import brute, point_light
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.algorithms.horizon import bilinear
from hillshade_rt.algorithms.pyramid import MaxPyramid
from hillshade_rt.testing import fractal_terrain, spectral


@pytest.mark.parametrize("row_l", [40.0, 17.3, 71.9])
def test_a_wall_shadows_to_d_h_over_l_minus_h(row_l):
    """A wall of height h along column 50 of flat ground, the light D = 20 columns east of it at
    height L > h, at several rows (rays at non-special angles): every cell x columns west of
    the wall whose ray runs along the columns is shadowed iff x < D h / (L - h), whatever its
    row; nothing east of the wall is shadowed."""
    h, L, D = 30.0, 80.0, 20.0
    z = np.zeros((90, 100), np.float32)
    z[:, 50] = h
    m = point_light.shadow_mask(z, row_l, 50.0 + D, L)
    reach = D * h / (L - h)                     # 12 columns
    for r in range(90):
        for c in range(0, 50):
            x = 50 - c
            if abs(r - row_l) > x + D:          # the ray runs along the rows: not this case
                continue
            assert m[r, c] == (1 if x < reach else 0), (r, c)
    assert not m[:, 51:].any()
    assert m[:, 50].sum() == 0                  # the wall's top is lit


def test_a_light_right_above_lights_the_cell_and_beyond_the_light_nothing_shadows():
    z = fractal_terrain(40, 40, 3, relief=50.0)
    top = float(z.max()) + 10.0
    m = point_light.shadow_mask(z, 20.0, 20.0, top)
    assert m[20, 20] == 0
    # a light on the ground far below every cell, in a pit: the terrain beyond it casts nothing
    z2 = np.zeros((30, 30), np.float32)
    z2[:, 25] = 100.0                         # a wall beyond the light (light at column 20)
    m2 = point_light.shadow_mask(z2, 15.0, 20.0, 5.0)
    assert not m2[:, :20].any()


@pytest.mark.parametrize("az, el", [(163.0, 12.0), (203.7, 7.0), (290.0, 15.0)])
def test_a_far_light_is_the_directional_sun(az, el):
    """A light 10^9 m away along (az, el) from the raster's centre gives brute's mask for that
    sun, cell for cell."""
    z = fractal_terrain(120, 130, 5, relief=1500.0)
    z[10:14, 20:25] = np.nan
    dx = dy = 30.0
    far = 1e9
    rc, cc = 59.5, 64.5
    e = far * math.sin(math.radians(az)) * math.cos(math.radians(el))
    n = far * math.cos(math.radians(az)) * math.cos(math.radians(el))
    m = point_light.shadow_mask(z, rc - n / dy, cc + e / dx, far * math.sin(math.radians(el)))
    ref = brute.shadow_mask(z, sun_rays(Grid.uniform(120, 130, dx, dy), az, el, 0.0))
    assert np.array_equal(m, ref)
    assert 0.05 < (ref == 1).mean() < 0.95


def _reference(z, row_l, col_l, height_l, lift=0.0):
    """Plain Python: every crossing of the line from each centre to the light with the grid lines
    of its dominant axis, strictly before the light, linear interpolation on the line."""
    rows, cols = z.shape
    out = np.zeros(z.shape, np.uint8)
    for r in range(rows):
        for c in range(cols):
            if math.isnan(z[r, c]):
                out[r, c] = 255
                continue
            h0 = float(z[r, c]) + lift
            dr, dc = row_l - r, col_l - c
            along_cols = abs(dc) >= abs(dr)
            d = abs(dc) if along_cols else abs(dr)
            k = 1
            while k < d:
                f = k / d
                rr, cc = r + f * dr, c + f * dc
                if along_cols:
                    cc = round(cc)
                    if not (0 <= cc < cols) or not (-1e-9 <= rr <= rows - 1 + 1e-9):
                        break
                    rr = min(max(rr, 0.0), rows - 1.0)
                    i = min(int(math.floor(rr)), rows - 2)
                    t = z[i, cc] + (rr - i) * (z[i + 1, cc] - z[i, cc])
                else:
                    rr = round(rr)
                    if not (0 <= rr < rows) or not (-1e-9 <= cc <= cols - 1 + 1e-9):
                        break
                    cc = min(max(cc, 0.0), cols - 1.0)
                    i = min(int(math.floor(cc)), cols - 2)
                    t = z[rr, i] + (cc - i) * (z[rr, i + 1] - z[rr, i])
                if t > h0 + f * (height_l - h0):
                    out[r, c] = 1
                    break
                k += 1
    return out


@pytest.mark.parametrize("light", [(-7.3, 12.6, 900.0), (20.4, 33.1, 260.0), (55.0, 61.7, 600.0)])
def test_equals_the_plain_python_reference(light):
    """On a small fractal, lights inside and outside the raster, low and high: the kernel equals
    an independent plain-Python march (all but rounding ties: none here)."""
    z = fractal_terrain(44, 50, 11, relief=300.0)
    z[30, 5] = np.nan
    got = point_light.shadow_mask(z, *light)
    ref = _reference(z, *light)
    assert (got != ref).sum() == 0
    assert np.array_equal(point_light.shadow_mask(z, *light, pyramid=False), ref)
    assert np.array_equal(point_light.shadow_mask(z, *light, lift=2.5),
                          _reference(z, *light, lift=2.5))
    assert 0.02 < (ref == 1).mean() < 0.98 or light[2] > 800


def test_the_array_api_takes_the_light_in_the_dems_crs(tmp_path):
    """arrays.point_light_mask: a DEM from read_dem and the light in its CRS give the kernel's
    mask at the light's fractional cell; a light below the ground is an error."""
    from affine import Affine
    from rasterio.crs import CRS
    from hillshade_rt.engine.arrays import point_light_mask
    from hillshade_rt.errors import HillshadeError
    from hillshade_rt.io import read_dem
    from hillshade_rt.testing import write_geotiff
    z = fractal_terrain(60, 70, 4, relief=200.0)
    path = write_geotiff(tmp_path / "d.tif", z, Affine(10, 0, 500000, 0, -10, 4000000),
                         CRS.from_epsg(32633))
    d = read_dem(path)
    x, y = 500000 + 10 * (33.25 + 0.5), 4000000 - 10 * (21.5 + 0.5)
    got = point_light_mask(d, x, y, 260.0)
    assert np.array_equal(got, point_light.shadow_mask(d.heights, 21.5, 33.25, 260.0))
    assert (got == 1).any() and (got == 0).any()
    with pytest.raises(HillshadeError, match="inside the terrain"):
        point_light_mask(d, x, y, float(np.nanmin(z)) - 1.0)


def _lights(z):
    """Lights over spectral terrain ``z``: a high lamp, low lamps a few metres over the ground
    (below many cells: rays that descend), lights off the raster (high, and low: below the
    highest cells), and far lights along non-special azimuths (163, 203.7, 290 deg)."""
    rows, cols = z.shape
    zmax = float(np.nanmax(z))
    out = [(97.3, 121.6, zmax + 150.0)]
    for r, c in ((60.2, 150.7), (181.5, 33.4), (128.0, 64.0)):
        out.append((r, c, float(bilinear(z, r, c)) + 4.0))
    out += [(-40.3, 260.9, zmax + 60.0), (250.4, -30.2, 0.5 * zmax), (-3.7, 100.2, 0.3 * zmax)]
    for az, dist, height in ((163.0, 300.0, 0.8 * zmax), (203.7, 170.0, 1.3 * zmax),
                             (290.0, 420.0, 0.6 * zmax)):
        a = math.radians(az)
        out.append((rows / 2 - dist * math.cos(a), cols / 2 + dist * math.sin(a), height))
    return out


@pytest.mark.slow
@pytest.mark.parametrize("lift", [0.0, 3.0])
def test_the_pyramid_march_is_the_plain_march(lift):
    """The march over the pyramid gives the plain march's mask cell for cell (rough and smooth
    fractals with voids; every light of ``_lights``), also with a MaxPyramid reused."""
    shadowed = []
    for z in (spectral(200, 2.4, seed=4, relief=120.0, cols=230),
              fractal_terrain(200, 230, 8, relief=150.0, octaves=6)):
        z[40:44, 70:75] = np.nan
        z[0, 17] = np.nan
        pyr = MaxPyramid(z)
        for light in _lights(z):
            plain = point_light.shadow_mask(z, *light, lift=lift, pyramid=False)
            assert np.array_equal(point_light.shadow_mask(z, *light, lift=lift), plain), light
            assert np.array_equal(point_light.shadow_mask(z, *light, lift=lift, pyramid=pyr), plain)
            shadowed.append(float((plain == 1).mean()))
    assert sum(0.05 < s < 0.95 for s in shadowed) >= len(shadowed) // 2   # not all trivial


def test_the_pyramid_march_equals_the_reference_with_lights_low_and_off_the_raster():
    z = spectral(48, 2.4, seed=9, relief=40.0, cols=56)
    z[20, 30] = np.nan
    for light in ((20.4, 11.2, float(bilinear(z, 20.4, 11.2)) + 2.0), (-9.5, 70.3, 20.0),
                  (60.1, -4.4, 35.0)):
        assert np.array_equal(point_light.shadow_mask(z, *light), _reference(z, *light)), light


@pytest.mark.parametrize("pyramid", [True, False])
def test_a_descending_ray_is_shadowed_by_a_wall_just_before_a_low_light(pyramid):
    """Flat ground at 0, a wall 3.5 high along column 98, a lamp 2 m high at (64, 100), a ridge
    60 high along column 20 (rows 0-63) and another along column 25 (rows 64-127; no ray from
    one ridge crosses the other). From the ridges the rays descend to the lamp: at the wall the
    ray from column c is 2 + 58 * 2 / (100 - c) high, 3.45 from column 20 (shadowed), 3.55 from
    column 25 (lit). A march that compared a block with the ray at its first sample (right for
    rising rays) skips the wall from column 20."""
    z = np.zeros((128, 128), np.float32)
    z[:, 98] = 3.5
    z[:64, 20] = 60.0
    z[64:, 25] = 60.0
    m = point_light.shadow_mask(z, 64.0, 100.0, 2.0, pyramid=pyramid)
    assert (m[:64, 20] == 1).all() and (m[64:, 25] == 0).all()
    west = m[64, :98]                          # the ground west of the wall, a ridge
    assert (west[np.arange(98) != 25] == 1).all() and west[25] == 0
    assert (m[:, 99:] == 0).all()


def test_a_window_with_its_halo_gives_the_whole_rasters_cells():
    """Each window of a raster, lit through ``halo`` (the box around it and the light, one cell
    more) at its origin, gets the whole raster's mask bit for bit: lights inside, low, and off
    the raster, with the pyramid and without."""
    z = spectral(150, 2.4, seed=2, relief=90.0, cols=170)
    z[70:73, 80:84] = np.nan
    for light in ((71.3, 90.6, float(bilinear(z, 71.3, 90.6)) + 3.0), (-25.2, 200.7, 140.0),
                  (160.4, -8.9, 60.0)):
        whole = point_light.shadow_mask(z, *light)
        for pyramid in (True, False):
            got = np.full(z.shape, 7, np.uint8)
            for r0 in range(0, 150, 64):
                for c0 in range(0, 170, 48):
                    region = (r0, min(150, r0 + 64), c0, min(170, c0 + 48))
                    a, b, c, d = point_light.halo(region, light[0], light[1], z.shape)
                    m = point_light.shadow_mask(np.ascontiguousarray(z[a:b, c:d]), *light,
                                          pyramid=pyramid, origin=(a, c), shape=z.shape)
                    got[region[0]:region[1], region[2]:region[3]] = \
                        m[region[0] - a:region[1] - a, region[2] - c:region[3] - c]
            assert np.array_equal(got, whole), (light, pyramid)
        assert 0.05 < (whole == 1).mean() < 0.99
