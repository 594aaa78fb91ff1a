"""Dozier's sky view factor kept in a file (``run.sky_view_file``): ``skyview --definition
dozier`` writes what ``irradiance`` computes, bit for bit; ``irradiance --sky-view FILE``
reads it instead (the same output bytes), refuses a file of another grid or other settings with
one line; ``--sky-view-out`` writes the Vd a later run reads."""

import json

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.engine import irradiance as ir
from hillshade_rt.io import read_dem
from hillshade_rt.model.earth import dem_body
from hillshade_rt.testing import fractal_terrain, write_geotiff

pytestmark = pytest.mark.filterwarnings("ignore:DatetimeIndex.dayofyear:DeprecationWarning")

UTM11 = CRS.from_epsg(32611)
DAY = ["--date", "2026-06-21", "--step", "2h", "--skyview-directions", "8", "-q"]


def _dem(tmp_path, name="dem.tif", n=48, seed=5, x0=400000.0):
    z = fractal_terrain(n, n, seed, relief=400.0).astype(np.float32)
    z[7, 9] = np.nan                        # a void: NaN in Vd, -9999 in the file
    return write_geotiff(tmp_path / name, z, Affine(30.0, 0, x0, 0, -30.0, 3800000.0), UTM11)


def _ok(runner, args):
    r = runner.invoke(cli, [str(a) for a in args])
    assert r.exit_code == 0, r.output
    return r


def _one_line(r, code, words):
    assert r.exit_code == code, (r.exit_code, r.output)
    assert words in r.stderr, r.stderr
    assert len(r.stderr.strip().splitlines()) == 1, r.stderr


def _bits(path, band=1):
    with rasterio.open(path) as ds:
        return ds.read(band).view(np.uint32)


def test_skyview_dozier_is_the_vd_irradiance_computes(tmp_path, runner):
    """skyview --definition dozier (in memory, and in windows) writes exactly the Vd of
    ``engine.irradiance.dozier_view`` with the same directions (-9999 on the void), and tags
    how it was made."""
    dem = _dem(tmp_path, n=150)
    _ok(runner, ["skyview", dem, tmp_path / "s.tif", "--definition", "dozier", "--directions",
                 "12", "-q"])
    _ok(runner, ["skyview", dem, tmp_path / "w.tif", "--definition", "dozier", "--directions",
                 "12", "--window-size", "64", "-q"])
    d = read_dem(dem)
    vd = ir.dozier_view(d.heights, d.grid, 12, "cpu", "auto", None, dem_body(d), 0.0)
    want = np.where(np.isnan(vd), np.float32(-9999.0), vd).view(np.uint32)
    assert np.array_equal(_bits(tmp_path / "s.tif"), want)
    assert np.array_equal(_bits(tmp_path / "w.tif"), want)
    with rasterio.open(tmp_path / "s.tif") as ds:
        tags = ds.tags()
    assert tags["DEFINITION"] == "dozier" and tags["DIRECTIONS"] == "12"
    assert tags["CONTEXT"] == "none" and tags["REFRACTION_K"] == "0.13"
    assert tags["BODY"].startswith("WGS84") and tags["HEIGHTS_DIGEST"].startswith("sha256:")


def test_sky_view_read_gives_the_computed_output_bytes(tmp_path, runner):
    """--sky-view-out, then --sky-view of that file, and of skyview's own file: the same
    output bytes as computing it (Perez, soft shadows: every band reads Vd); the file written
    equals skyview's bit for bit; the report says where Vd came from."""
    dem = _dem(tmp_path)
    sv, sk = tmp_path / "sv.tif", tmp_path / "sk.tif"
    extra = ["--perez", "--soft", "--albedo", "0.3"]
    _ok(runner, ["irradiance", dem, tmp_path / "a.tif", *DAY, *extra, "--sky-view-out", sv,
                 "--report", tmp_path / "a.json"])
    _ok(runner, ["irradiance", dem, tmp_path / "b.tif", *DAY, *extra, "--sky-view", sv,
                 "--report", tmp_path / "b.json"])
    _ok(runner, ["skyview", dem, sk, "--definition", "dozier", "--directions", "8", "-q"])
    _ok(runner, ["irradiance", dem, tmp_path / "c.tif", *DAY, *extra, "--sky-view", sk])
    ref = (tmp_path / "a.tif").read_bytes()
    assert (tmp_path / "b.tif").read_bytes() == ref
    assert (tmp_path / "c.tif").read_bytes() == ref
    assert np.array_equal(_bits(sv), _bits(sk))
    with rasterio.open(sv) as a, rasterio.open(sk) as b:
        ta, tb = a.tags(), b.tags()
    assert {k: v for k, v in ta.items() if k != "HILLSHADE_RT_VERSION"} == \
        {k: v for k, v in tb.items() if k != "HILLSHADE_RT_VERSION"}
    ra, rb = (json.loads((tmp_path / f"{x}.json").read_text()) for x in "ab")
    assert ra["sky_view_from"] == "computed" and ra["sky_view_file"] == str(sv)
    assert rb["sky_view_from"] == "read" and rb["sky_view_file"] == str(sv)
    assert ra["bands"] == rb["bands"] and ra["sky_view"] == rb["sky_view"]


def test_sky_view_of_a_context_tile(tmp_path, runner):
    """With --context: skyview of the tile in its context is the Vd irradiance computes there
    (the same output bytes); a file of the tile alone (no context) is refused."""
    big = _dem(tmp_path, "big.tif", n=64)
    with rasterio.open(big) as ds:
        prof = ds.profile
        z = ds.read(1)
    prof.update(width=40, height=40)
    tile = tmp_path / "tile.tif"
    with rasterio.open(tile, "w", **prof) as ds:
        ds.write(z[:40, :40], 1)
    ctx = ["--context", big]
    _ok(runner, ["skyview", tile, tmp_path / "sk.tif", "--definition", "dozier",
                 "--directions", "8", "-q", *ctx])
    _ok(runner, ["irradiance", tile, tmp_path / "a.tif", *DAY, "--perez", *ctx])
    _ok(runner, ["irradiance", tile, tmp_path / "b.tif", *DAY, "--perez", *ctx, "--sky-view",
                 tmp_path / "sk.tif"])
    assert (tmp_path / "a.tif").read_bytes() == (tmp_path / "b.tif").read_bytes()
    r = runner.invoke(cli, ["irradiance", str(tile), str(tmp_path / "c.tif"), *DAY,
                            "--sky-view", str(tmp_path / "sk.tif")])
    _one_line(r, 1, "CONTEXT")
    assert not (tmp_path / "c.tif").exists()


@pytest.mark.parametrize("extra, words", [
    (["--skyview-directions", "16"], "DIRECTIONS '8', this run has '16'"),
    (["--no-earth-curvature"], "EARTH_CURVATURE 'on', this run has 'off'"),
    (["--height-above-ground", "2"], "--height-above-ground"),
    (["--refraction-coefficient", "0.2"], "REFRACTION_K '0.13', this run has '0.2'"),
    (["--z-factor", "1.5"], "HEIGHTS_DIGEST"),
])
def test_sky_view_of_other_settings_is_refused(tmp_path, runner, extra, words):
    """A file made with other directions, curvature, observer height, refraction or heights
    than the run's: one line naming the difference, exit status 1, no output."""
    dem = _dem(tmp_path)
    sk = tmp_path / "sk.tif"
    _ok(runner, ["skyview", dem, sk, "--definition", "dozier", "--directions", "8", "-q"])
    r = runner.invoke(cli, ["irradiance", str(dem), str(tmp_path / "o.tif"), *DAY, *extra,
                            "--sky-view", str(sk)])
    _one_line(r, 1, words)
    assert not (tmp_path / "o.tif").exists()


def test_sky_view_of_another_grid_or_kind_is_refused(tmp_path, runner):
    """Another shape, another transform (the same shape moved), a zaksek sky view, the
    terrain configuration, irradiance's own 4-band output, a missing file: one line, exit 1;
    --sky-view with --sky-view-out, or naming OUTPUT: usage errors (exit 2)."""
    dem = _dem(tmp_path)
    small = _dem(tmp_path, "small_dem.tif", n=40)
    moved = _dem(tmp_path, "moved_dem.tif", x0=400030.0)
    files = {}
    for name, src, more in (("small", small, ["--definition", "dozier"]),
                            ("moved", moved, ["--definition", "dozier"]),
                            ("zaksek", dem, []),
                            ("tc", dem, ["--definition", "dozier", "--terrain-configuration"])):
        files[name] = tmp_path / f"{name}.tif"
        _ok(runner, ["skyview", src, files[name], "--directions", "8", "-q", *more])
    _ok(runner, ["irradiance", dem, tmp_path / "irr.tif", *DAY])
    out = str(tmp_path / "o.tif")
    for f, code, words in ((files["small"], 1, "40x40 cells"),
                           (files["moved"], 1, "transform"),
                           (files["zaksek"], 1, "definition zaksek"),
                           (files["tc"], 1, "terrain configuration"),
                           (tmp_path / "irr.tif", 1, "4 band(s)"),
                           (tmp_path / "none.tif", 1, "no such file")):
        r = runner.invoke(cli, ["irradiance", str(dem), out, *DAY, "--sky-view", str(f)])
        _one_line(r, code, words)
    r = runner.invoke(cli, ["irradiance", str(dem), out, *DAY, "--sky-view",
                            str(files["moved"]), "--sky-view-out", str(tmp_path / "x.tif")])
    _one_line(r, 2, "give one of them")
    r = runner.invoke(cli, ["irradiance", str(dem), out, *DAY, "--sky-view-out", out])
    _one_line(r, 2, "name the same file")
    r = runner.invoke(cli, ["irradiance", str(dem), out, *DAY, "--sky-view-out", str(dem),
                            "--overwrite"])
    _one_line(r, 2, "is also an input")
    assert not (tmp_path / "o.tif").exists()


def test_api_keywords(tmp_path):
    """``hillshade_rt.irradiance(sky_view=..., sky_view_out=...)`` as the options."""
    import hillshade_rt
    dem = _dem(tmp_path)
    kw = dict(date="2026-06-21", step="2h", skyview_directions=8)
    a = hillshade_rt.irradiance(dem, tmp_path / "a.tif", sky_view_out=tmp_path / "sv.tif", **kw)
    b = hillshade_rt.irradiance(dem, tmp_path / "b.tif", sky_view=tmp_path / "sv.tif", **kw)
    assert a["sky_view_from"] == "computed" and b["sky_view_from"] == "read"
    assert (tmp_path / "a.tif").read_bytes() == (tmp_path / "b.tif").read_bytes()


def test_sky_view_with_each_is_a_usage_error(tmp_path, runner):
    """--each runs many DEMs: one sky view file cannot serve them (exit 2, nothing written)."""
    a, b = _dem(tmp_path, "a.tif"), _dem(tmp_path, "b.tif", seed=6)
    for opt in ("--sky-view", "--sky-view-out"):
        r = runner.invoke(cli, ["irradiance", str(a), str(b), "--each", "--output-pattern",
                                str(tmp_path / "{stem}_irr.tif"), *DAY, opt,
                                str(tmp_path / "sv.tif")])
        _one_line(r, 2, "run each DEM on its own")
    assert not list(tmp_path.glob("*_irr.tif")) and not (tmp_path / "sv.tif").exists()
