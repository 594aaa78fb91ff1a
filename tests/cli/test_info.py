"""cli/info.py, ``hillshade-rt info``: its options reach ``run.describe``, and what it prints of a
DEM as text and as JSON."""

import json
import math

from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.run.config import ReadOptions
from hillshade_rt.testing import data_path, fractal_terrain, write_geotiff

MOON_R = 1737400.0
MOON_SPS = CRS.from_proj4(f"+proj=stere +lat_0=-90 +R={MOON_R:.0f} +units=m +no_defs")


def test_info(runner):
    r = runner.invoke(cli, ["info", data_path("jacksboro_fault_srtm3_mpl_403x344.tif"), "--json"])
    assert r.exit_code == 0, r.output
    doc = json.loads(r.stdout)
    assert doc["shape"] == [344, 403] and doc["crs"] == "EPSG:4326"
    dx, dy = doc["spacing_m"]["centre"]
    assert 74 < dx < 75.5 and 92 < dy < 93  # 3" at 36.3 N, in metres
    assert doc["height_range_m"] == [236.0, 1076.0]
    r = runner.invoke(cli, ["info", data_path("everest_srtm3_voids_crop200.tif")])
    assert r.exit_code == 0 and "nodata" in r.stdout and "-32768" in r.stdout


def test_info_names_the_body_of_a_crs_without_a_name(tmp_path, runner):
    dem = write_geotiff(tmp_path / "sps.tif", fractal_terrain(40, 40, 2, relief=2000),
                        Affine(240, 0, -4800, 0, -240, 4800), MOON_SPS)
    r = runner.invoke(cli, ["info", dem])
    assert r.exit_code == 0, r.output
    line = next(l for l in r.stdout.splitlines() if l.strip().startswith("crs"))
    assert "Moon" in line and "Stereographic" in line and "unknown" not in line


def test_the_options_reach_describe(monkeypatch, runner, tmp_path):
    """DEM, --preview, --overwrite and the DEM options go to ``run.describe`` as given; --json
    prints the description it returns, nothing else."""
    import hillshade_rt.run as run
    seen = []

    def describe(dem, read, preview, overwrite):
        seen.append((dem, read, preview, overwrite))
        return {"shape": [3, 5], "note": "from the fake"}, None
    monkeypatch.setattr(run, "describe", describe)
    preview = str(tmp_path / "p.png")
    r = runner.invoke(cli, ["info", "dem.tif", "--json", "--preview", preview, "--overwrite",
                            "-b", "2", "--nodata", "-32767", "-z", "0.3048",
                            "--pixel-size", "2.5,3"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout) == {"shape": [3, 5], "note": "from the fake"}
    [(dem, read, got_preview, overwrite)] = seen
    assert (dem, got_preview, overwrite) == ("dem.tif", preview, True)
    assert isinstance(read, ReadOptions)
    assert (read.band, read.nodata, read.z_factor) == (2, -32767.0, 0.3048)
    assert read.pixel_size == "2.5,3"
    seen.clear()
    r = runner.invoke(cli, ["info", "dem.tif", "--json"])
    assert r.exit_code == 0, r.output
    [(_, read, got_preview, overwrite)] = seen
    assert got_preview is None and overwrite is False
    assert (read.band, read.nodata, read.z_factor, read.pixel_size) == (1, None, 1.0, None)


def test_text_and_json_say_the_same(runner):
    """The text lines carry the JSON's numbers (spacing to 4 decimals, heights to 2)."""
    dem = data_path("jacksboro_fault_srtm3_mpl_403x344.tif")
    doc = json.loads(runner.invoke(cli, ["info", dem, "--json"]).stdout)
    r = runner.invoke(cli, ["info", dem])
    assert r.exit_code == 0, r.output
    lines = {ln.split()[0]: ln for ln in r.stdout.splitlines()[1:] if ln.startswith("  ") and
             not ln.startswith("   ")}
    dx, dy = doc["spacing_m"]["centre"]
    assert f"dx {dx:.4f}  dy {dy:.4f}" in lines["spacing"]
    lo, hi = doc["height_range_m"]
    assert f"{lo:.2f} .. {hi:.2f}" in lines["heights"]
    assert "403 x 344 (cols x rows), 138,632 cells" in lines["size"]
    assert doc["crs"] == "EPSG:4326" and "(EPSG:4326)" in lines["crs"]
    assert math.isclose(float(lines["nodata"].split("; ")[1].split("%")[0]),
                        100 * doc["nodata_fraction"], abs_tol=0.005)
