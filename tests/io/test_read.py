"""Reading every input kind, georeferenced output, orientation and CRS handling."""

import os

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt import HillshadeError, read_dem, shadow_mask
from hillshade_rt.io import parse_pixel_size, parse_raw_shape
from hillshade_rt.testing import box_terrain, data_path, fractal_terrain, write_geotiff

UTM = CRS.from_epsg(32611)


def _mask_of(path, az=203.7, el=12.0, **kw):
    d = read_dem(path, **kw)
    return shadow_mask(d.heights, az, el, spacing=d.grid)


def test_geotiff_reads_heights_nodata_and_spacing(tmp_path):
    z = fractal_terrain(30, 40, seed=1, relief=50).astype(np.int16)
    z[3, 4] = -9999
    p = write_geotiff(tmp_path / "a.tif", z, Affine(10, 0, 400000, 0, -10, 3800000), UTM, -9999)
    d = read_dem(p)
    assert d.heights.dtype == np.float32 and d.shape == (30, 40)
    assert np.isnan(d.heights[3, 4]) and d.valid_count() == 30 * 40 - 1
    assert d.grid.dx[0] == pytest.approx(10.0, rel=1e-3)


def test_nodata_override_and_nan(tmp_path):
    z = fractal_terrain(20, 20, seed=2).astype(np.float32)
    z[0, 0] = np.nan
    z[5, 5] = -1.0
    p = write_geotiff(tmp_path / "a.tif", z, Affine(10, 0, 400000, 0, -10, 3800000), UTM)
    assert read_dem(p).valid_count() == 399
    assert read_dem(p, nodata=-1.0).valid_count() == 398


def test_nodata_the_type_cannot_hold_matches_nothing(tmp_path):
    z = np.full((4, 4), 65535, np.uint16)
    z[0, 0] = 7
    p = write_geotiff(tmp_path / "u.tif", z, Affine(1, 0, 400000, 0, -1, 3800000), UTM)
    assert read_dem(p, nodata=-1).valid_count() == 16      # -1 must not wrap to 65535
    assert read_dem(p, nodata=65535).valid_count() == 1


@pytest.mark.parametrize("nodata", [None, -9999.0, -3.4028234663852886e38, 0.0])
def test_the_reads_one_pass_equals_numpy(tmp_path, nodata):
    """Float32 DEMs of 2^16 cells or more take one parallel nodata pass (``counts.
    clean_heights``) that also finds the valid count and height range: the same heights (NaN
    where numpy's passes put them) and the survey of the result; z_factor drops the survey."""
    rng = np.random.default_rng(4)
    z = (rng.random((300, 310)) * 900 - 100).astype(np.float32)
    z[rng.random(z.shape) < 0.05] = -9999.0
    z[rng.random(z.shape) < 0.02] = np.float32(-3.4028234663852886e38)
    z[3, 3], z[4, 4], z[5, 5], z[6, 6] = np.nan, np.inf, -np.inf, 0.0
    p = write_geotiff(tmp_path / "f.tif", z, Affine(10, 0, 400000, 0, -10, 3800000), UTM, nodata)
    d = read_dem(p)
    want = z.copy()
    want[~np.isfinite(want)] = np.nan
    if nodata is not None:
        want[z == np.float32(nodata)] = np.nan
    np.testing.assert_array_equal(d.heights, want)
    assert d._survey is not None            # found by the read's pass
    assert d.survey() == (int(np.isfinite(want).sum()), float(np.nanmin(want)),
                          float(np.nanmax(want)))
    d2 = read_dem(p, z_factor=2.0)
    with np.errstate(over="ignore"):
        want2 = want * np.float32(2.0)
    want2[~np.isfinite(want2)] = np.nan      # beyond float32: no height
    np.testing.assert_array_equal(d2.heights, want2)
    assert d2.survey() == (int(np.isfinite(want2).sum()), float(np.nanmin(want2)),
                           float(np.nanmax(want2)))


def test_band_selection(tmp_path):
    z = np.stack([np.zeros((10, 10), np.float32), box_terrain(10, 10, 5.0, 4, 6, 4, 6)])
    p = write_geotiff(tmp_path / "two.tif", z, Affine(1, 0, 400000, 0, -1, 3800000), UTM)
    assert np.nanmax(read_dem(p, band=2).heights) == 5.0
    assert np.nanmax(read_dem(p).heights) == 0.0
    with pytest.raises(HillshadeError, match="2 band"):
        read_dem(p, band=3)


def test_z_factor(tmp_path):
    z = fractal_terrain(10, 10, seed=3, relief=10)
    p = write_geotiff(tmp_path / "a.tif", z, Affine(1, 0, 400000, 0, -1, 3800000), UTM)
    np.testing.assert_allclose(read_dem(p, z_factor=0.3048).heights, z * np.float32(0.3048))


def test_raw_and_geotiff_of_the_same_grid_give_the_same_mask(tmp_path):
    src = data_path("lidar_dem_1m_utm15n_400x400.tif")
    d = read_dem(src)
    raw = tmp_path / "lidar.f32"
    d.heights.astype("<f4").tofile(raw)
    tif_mask = shadow_mask(d.heights, 163.0, 4.0, spacing=1.0)  # 1 m pixels, as given
    raw_mask = _mask_of(str(raw), az=163.0, el=4.0, raw_shape=(400, 400), raw_dtype="float32",
                        raw_byteorder="little", pixel_size=(1.0, 1.0))
    assert tif_mask.any() and np.array_equal(tif_mask, raw_mask)
    # big-endian int16 (SRTM style) of the same heights in decimetres
    dm = np.round(d.heights * 10).astype(">i2")
    be = tmp_path / "lidar_dm.bin"
    dm.tofile(be)
    got = read_dem(str(be), raw_shape=(400, 400), raw_dtype="int16", raw_byteorder="big",
                   pixel_size=(1.0, 1.0), z_factor=0.1)
    np.testing.assert_allclose(got.heights, dm.astype(np.float32) * np.float32(0.1))


def test_hgt_by_extension(tmp_path):
    """An SRTM .hgt tile (1201x1201 big-endian int16) is read georeferenced from its name,
    with -32768 as nodata, whether GDAL reads it or the raw reader does."""
    z = (fractal_terrain(1201, 1201, seed=4, relief=3000) + 100).astype(">i2")
    z[100, 100] = -32768
    p = tmp_path / "N46E010.hgt"
    z.tofile(p)
    d = read_dem(str(p))
    assert d.shape == (1201, 1201) and np.isnan(d.heights[100, 100])
    assert d.crs is not None and d.crs.to_epsg() == 4326
    assert d.transform.c == pytest.approx(10 - 0.5 / 1200)
    assert d.transform.f == pytest.approx(47 + 0.5 / 1200)
    assert 60.0 < d.grid.dx[600] < 66.0 and 92.0 < d.grid.dy[600] < 93.0  # 3" at 46.5 N
    # the raw reader's own georeferencing gives the same geometry
    raw = read_dem(str(p), raw_byteorder="big")     # any raw_* option: the raw reader
    assert raw.kind == "raw" and d.kind == "gdal"
    np.testing.assert_allclose(raw.grid.dx, d.grid.dx, rtol=1e-9)
    np.testing.assert_array_equal(np.isnan(raw.heights), np.isnan(d.heights))


def test_plain_tiff_through_tifffile_needs_pixel_size(tmp_path):
    import tifffile

    z = fractal_terrain(50, 60, seed=5, relief=40)
    p = str(tmp_path / "plain.tif")
    tifffile.imwrite(p, z)
    with pytest.raises(HillshadeError, match="--pixel-size"):
        read_dem(p)
    d = read_dem(p, pixel_size=(2.0, 2.0))
    assert d.kind == "tiff" and d.transform is None
    np.testing.assert_array_equal(d.heights, z)
    assert np.array_equal(shadow_mask(d.heights, 203.7, 10, spacing=d.grid),
                          shadow_mask(z, 203.7, 10, spacing=2.0))


def test_south_up_raster_shadows_fall_on_the_same_ground(tmp_path):
    z = fractal_terrain(60, 50, seed=6, relief=300)
    north = write_geotiff(tmp_path / "n.tif", z, Affine(30, 0, 400000, 0, -30, 3800000), UTM)
    south = write_geotiff(tmp_path / "s.tif", z[::-1].copy(),
                          Affine(30, 0, 400000, 0, 30, 3800000 - 60 * 30), UTM)
    west = write_geotiff(tmp_path / "w.tif", z[:, ::-1].copy(),
                         Affine(-30, 0, 400000 + 50 * 30, 0, -30, 3800000), UTM)
    for az in (0.0, 163.0, 203.7, 300.0):
        mn = _mask_of(north, az=az, el=10.0)
        assert mn.any()
        assert np.array_equal(_mask_of(south, az=az, el=10.0)[::-1], mn), az
        assert np.array_equal(_mask_of(west, az=az, el=10.0)[:, ::-1], mn), az


def test_geographic_dem_matches_the_same_terrain_projected(tmp_path):
    """The same heights on a 3" geographic grid at 45 N and on a projected grid (transverse
    Mercator with k=1 centred on the DEM) whose cells have the geographic grid's metric size."""
    rows, cols = 60, 60
    z = fractal_terrain(rows, cols, seed=8, relief=2000)
    geo_t = Affine(3 / 3600, 0, 10.0, 0, -3 / 3600, 45.0 + rows * 1.5 / 3600)
    geo = write_geotiff(tmp_path / "geo.tif", z, geo_t, CRS.from_epsg(4326))
    g = read_dem(geo).grid
    dx, dy = g.centre_spacing()
    assert 65 < dx < 66 and 92 < dy < 93  # 3" at 45 N: degrees were converted to metres
    tm = CRS.from_proj4("+proj=tmerc +lat_0=45 +lon_0=10.025 +k=1 +datum=WGS84 +units=m")
    prj = write_geotiff(tmp_path / "tm.tif", z, Affine(dx, 0, -cols * dx / 2, 0, -dy,
                                                       rows * dy / 2), tm)
    for az, el in ((163.0, 8.0), (203.7, 15.0), (70.0, 5.0)):
        mg, mp = _mask_of(geo, az=az, el=el), _mask_of(prj, az=az, el=el)
        assert mg.any()
        # per-row spacing differs by < 1e-4 between the two: allow grazing cells only
        assert np.count_nonzero(mg != mp) <= 2, (az, el)


def test_output_is_georeferenced_like_the_input(tmp_path, runner):
    from hillshade_rt.cli import cli
    import rasterio

    src = data_path("everest_srtm3_voids_crop200.tif")
    out = tmp_path / "m.tif"
    r = runner.invoke(cli, ["shadow", src, str(out), "--azimuth", "203.7", "--elevation", "15"])
    assert r.exit_code == 0, r.output
    with rasterio.open(src) as a, rasterio.open(out) as b:
        assert b.crs == a.crs and b.transform == a.transform and b.shape == a.shape
        assert b.nodata == 255 and b.dtypes[0] == "uint8"
        assert b.profile["compress"].lower() == "deflate" and b.profile["tiled"]
        m = b.read(1)
        voids = a.read(1) == a.nodata
    assert voids.any() and np.array_equal(m == 255, voids)
    assert set(np.unique(m)) <= {0, 1, 255} and (m == 1).any()


def test_parsers():
    assert parse_pixel_size("2") == (2.0, 2.0) and parse_pixel_size("2,3.5") == (2.0, 3.5)
    assert parse_raw_shape("1201x1201") == (1201, 1201) and parse_raw_shape("3X4") == (3, 4)
    for bad in ("0", "-1", "a,b", "1,2,3"):
        with pytest.raises(HillshadeError):
            parse_pixel_size(bad)
    for bad in ("12", "0x5", "axb"):
        with pytest.raises(HillshadeError):
            parse_raw_shape(bad)


def test_read_while_numba_starts_returns_or_raises_in_the_caller():
    """``_preload.while_numba_starts``: the read runs in a thread while numba starts in this
    one; its value comes back, and its exception is raised here (the read's errors stay the
    one-line errors of read_dem)."""
    import threading

    from hillshade_rt import _preload
    was = _preload._done
    try:
        _preload._done = False
        seen = []
        assert _preload.while_numba_starts(lambda: seen.append(threading.current_thread())
                                           or 42) == 42
        assert seen and seen[0] is not threading.main_thread() and _preload._done
        _preload._done = False

        def fail():
            raise OSError("disk on fire")
        with pytest.raises(OSError, match="disk on fire"):
            _preload.while_numba_starts(fail)
    finally:
        _preload._done = was
