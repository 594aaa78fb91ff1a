"""Many unrelated DEMs in one call (run/batch.py, ``--each``): each output equal to the
single-DEM call's, failures named while the others are written, all-nodata DEMs written as
nodata, the report, the usage errors, an interruption."""

import json
import os

import numpy as np
import pytest
import rasterio
from affine import Affine

from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError, Interrupted, UsageProblem
from hillshade_rt.run.batch import BatchFailed, check_pattern, fill_stem
from hillshade_rt.testing import data_path, fractal_terrain, write_geotiff

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")            # UTM 15N, float32
EVEREST = data_path("everest_srtm3_voids_crop200.tif")          # geographic, int16, voids
SUN = ["--azimuth", "203.7", "--elevation", "10"]


@pytest.fixture
def dems(tmp_path):
    """Three unrelated DEMs (UTM lidar, geographic SRTM with voids, a small float64 fractal in
    another UTM zone), one all-nodata (sea) and one corrupt file, in one folder."""
    d = tmp_path / "in"
    d.mkdir()
    paths = {}
    for name, src in (("lidar", LIDAR), ("everest", EVEREST)):
        paths[name] = str(d / f"{name}.tif")
        with open(src, "rb") as fi, open(paths[name], "wb") as fo:
            fo.write(fi.read())
    z = fractal_terrain(70, 90, seed=5, relief=300.0).astype(np.float64)
    paths["fractal"] = write_geotiff(d / "fractal.tif", z, Affine(25, 0, 400000, 0, -25, 5200000),
                                     "EPSG:32632")
    paths["sea"] = write_geotiff(d / "sea.tif", np.full((40, 50), -9999, np.float32),
                                 Affine(30, 0, 500000, 0, -30, 4000000), "EPSG:32633",
                                 nodata=-9999)
    paths["corrupt"] = str(d / "corrupt.tif")
    with open(paths["corrupt"], "wb") as fo:
        fo.write(b"II*\x00 this is no TIFF")
    return paths


def _raster(path):
    with rasterio.open(path) as ds:
        return ds.read(), ds.crs, ds.transform, ds.nodata, ds.dtypes[0]


def _same_raster(a, b):
    ra, rb = _raster(a), _raster(b)
    np.testing.assert_array_equal(ra[0], rb[0])
    assert ra[1:] == rb[1:]


def test_shadow_each_equals_single_runs_failures_named_sea_written(tmp_path, runner, dems):
    out = tmp_path / "out"
    out.mkdir()
    order = ["lidar", "corrupt", "everest", "sea", "fractal"]
    rep_path = tmp_path / "run.json"
    r = runner.invoke(cli, ["shadow", *[dems[k] for k in order], "--each", "--output-pattern",
                            str(out / "{stem}_shadow.tif"), *SUN, "--report", str(rep_path)])
    assert r.exit_code == 1, r.output
    err = r.stderr.splitlines()
    # the failing DEM named on one line, the others written, the summary, the final error
    failed = [ln for ln in err if dems["corrupt"] in ln and ln.startswith("hillshade-rt: error:")]
    assert len(failed) == 2 and "1 of 5 DEM(s) failed" in failed[1]
    assert any("4 of 5 DEM(s) done (1 all nodata" in ln and "1 failed" in ln for ln in err)
    assert any(ln.startswith("hillshade-rt: note:") and dems["sea"] in ln and "nodata" in ln
               for ln in err)
    assert sorted(os.listdir(out)) == sorted(f"{k}_shadow.tif" for k in order if k != "corrupt")
    # each output equal (pixels, CRS, transform, nodata, type) to the single-DEM call's
    single = tmp_path / "single"
    single.mkdir()
    for k in ("lidar", "everest", "fractal"):
        one = single / f"{k}.tif"
        r1 = runner.invoke(cli, ["shadow", dems[k], str(one), *SUN, "-q"])
        assert r1.exit_code == 0, r1.output
        _same_raster(out / f"{k}_shadow.tif", one)
    # the all-nodata DEM: all nodata on its own grid
    z, crs, transform, nodata, dtype = _raster(out / "sea_shadow.tif")
    assert dtype == "uint8" and nodata == 255 and (z == 255).all() and z.shape == (1, 40, 50)
    assert crs == "EPSG:32633" and transform == Affine(30, 0, 500000, 0, -30, 4000000)
    # the report: each input, its outputs, its status and its run's figures
    rep = json.loads(rep_path.read_text())
    assert rep["mode"] == "each" and rep["command"] == "shadow"
    assert rep["count"] == {"inputs": 5, "ok": 3, "empty": 1, "failed": 1}
    by = {os.path.splitext(os.path.basename(e["input"]))[0]: e for e in rep["inputs"]}
    assert [os.path.basename(e["input"]) for e in rep["inputs"]] == [f"{k}.tif" for k in order]
    assert by["corrupt"]["status"] == "failed" and dems["corrupt"] in by["corrupt"]["message"]
    assert by["corrupt"]["outputs"] == []
    assert by["sea"]["status"] == "empty" and "nodata" in by["sea"]["message"]
    assert by["sea"]["outputs"] == [str(out / "sea_shadow.tif")]
    for k, crs, shape in (("lidar", "EPSG:26915", [400, 400]), ("everest", "EPSG:4326",
                                                                 [200, 200]),
                          ("fractal", "EPSG:32632", [70, 90])):
        e = by[k]
        assert e["status"] == "ok" and e["outputs"] == [str(out / f"{k}_shadow.tif")]
        assert e["report"]["crs"] == crs and e["report"]["shape"] == shape
        m = _raster(out / f"{k}_shadow.tif")[0]
        assert e["report"]["shadow_fraction"] == pytest.approx((m == 1).sum() / (m != 255).sum())


def test_hillshade_each_all_good_exit_0(tmp_path, runner, dems):
    r = runner.invoke(cli, ["hillshade", dems["everest"], dems["fractal"], dems["sea"], "--each",
                            "--output-pattern", str(tmp_path / "{stem}.hs.tif"), "-q"])
    assert r.exit_code == 0, r.output
    assert r.stderr == ""           # -q: no summary, no note
    for k in ("everest", "fractal"):
        one = tmp_path / f"{k}.single.tif"
        assert runner.invoke(cli, ["hillshade", dems[k], str(one), "-q"]).exit_code == 0
        _same_raster(tmp_path / f"{k}.hs.tif", one)
    z = _raster(tmp_path / "sea.hs.tif")[0]
    assert (z == 0).all()           # hillshade's nodata


def test_times_from_each_dems_own_place(tmp_path, runner, dems):
    """--time: each DEM's sun from its own place, a band per time (the pattern left with no
    field is the single call's OUTPUT) or a file per time ({time} kept for the run)."""
    times = ["--time", "2026-06-21T06:00Z", "--time", "2026-06-21T18:00Z"]
    rep_path = tmp_path / "r.json"
    r = runner.invoke(cli, ["shadow", dems["everest"], dems["lidar"], "--each", "-q",
                            "--output-pattern", str(tmp_path / "{stem}.tif"), *times,
                            "--report", str(rep_path)])
    assert r.exit_code == 0, r.output
    rep = json.loads(rep_path.read_text())
    sites = [e["report"]["site"] for e in rep["inputs"]]
    assert sites[0]["latitude"] == pytest.approx(27.7, abs=0.2)  # Everest
    assert sites[1]["latitude"] == pytest.approx(45, abs=4)    # Minnesota
    for k in ("everest", "lidar"):
        one = tmp_path / f"{k}.single.tif"
        assert runner.invoke(cli, ["shadow", dems[k], str(one), *times, "-q"]).exit_code == 0
        _same_raster(tmp_path / f"{k}.tif", one)
        assert _raster(one)[0].shape[0] == 2
    (tmp_path / "t").mkdir()
    r = runner.invoke(cli, ["shadow", dems["everest"], dems["fractal"], "--each", "-q",
                            "--output-pattern", str(tmp_path / "t" / "{stem}_{time:%H}.tif"),
                            *times[:2]])
    assert r.exit_code == 0, r.output
    assert sorted(os.listdir(tmp_path / "t")) == ["everest_06.tif", "fractal_06.tif"]


def test_sun_hours_each_equals_single(tmp_path, runner, dems):
    args = ["--date", "2026-06-21", "--step", "3h", "-q"]
    r = runner.invoke(cli, ["sun-hours", dems["everest"], dems["fractal"], dems["corrupt"],
                            "--each", "--output-pattern", str(tmp_path / "{stem}_hours.tif"),
                            *args])
    assert r.exit_code == 1 and dems["corrupt"] in r.stderr
    for k in ("everest", "fractal"):
        one = tmp_path / f"{k}.single.tif"
        assert runner.invoke(cli, ["sun-hours", dems[k], str(one), *args]).exit_code == 0
        _same_raster(tmp_path / f"{k}_hours.tif", one)


def test_skyview_and_horizon_each(tmp_path, runner, dems):
    for cmd, extra in (("skyview", ["--directions", "8"]), ("horizon", ["--azimuth", "120"])):
        r = runner.invoke(cli, [cmd, dems["fractal"], dems["sea"], "--each", "-q",
                                "--output-pattern", str(tmp_path / f"{{stem}}_{cmd}.tif"),
                                *extra])
        assert r.exit_code == 0, r.output
        one = tmp_path / f"single_{cmd}.tif"
        assert runner.invoke(cli, [cmd, dems["fractal"], str(one), *extra, "-q"]).exit_code == 0
        _same_raster(tmp_path / f"fractal_{cmd}.tif", one)
        z, *_, nodata, dtype = _raster(tmp_path / f"sea_{cmd}.tif")
        assert dtype == "float32" and nodata == -9999 and (z == -9999).all()


@pytest.mark.parametrize("args, words", [
    (["--each", "-o", "x.tif"], "not -o/--output"),
    (["--each"], "--each needs --output-pattern"),
    (["--each", "--output-pattern", "{index}.tif"], "needs {stem}"),
    (["--output-pattern", "{stem}.tif"], "add --each"),
    (["--each", "--output-pattern", "{stem}_{tile}.tif"], "{tile}"),
    (["--each", "--output-pattern", "{stem}_{colour}.tif"], "unknown field"),
    (["--each", "--output-pattern", "{stem}.tif", "--preview", "p.png"], "--preview"),
    (["--each", "--output-pattern", "{stem}.tif", "--stac-item", "i.json"], "--stac-item"),
    (["--each", "--output-pattern", "{stem}.tif", "--elevation", "10"], "azimuth"),
])
def test_usage_errors_exit_2_before_any_work(tmp_path, runner, dems, args, words, monkeypatch):
    monkeypatch.chdir(tmp_path)
    base = args if "--elevation" in args else args + SUN
    r = runner.invoke(cli, ["shadow", dems["lidar"], dems["everest"], *base])
    assert r.exit_code == 2, r.output
    assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert sorted(os.listdir(tmp_path)) == ["in"]


def test_same_stem_output_is_input_or_report(tmp_path, runner, dems):
    other = tmp_path / "other"
    other.mkdir()
    twin = write_geotiff(other / "lidar.tif", np.zeros((8, 8), np.float32),
                         Affine(1, 0, 0, 0, -1, 8), "EPSG:32615")
    cases = [
        ([dems["lidar"], twin], str(tmp_path / "{stem}.tif"), [], "same file name"),
        # the output of fractal.tif would be everest's input
        ([dems["fractal"], dems["everest"]], str(tmp_path / "in" / "{stem}.tif"), [],
         "also an input"),
        ([dems["fractal"], dems["everest"]], str(tmp_path / "{stem}.tif"),
         ["--report", str(tmp_path / "everest.tif")], "name the same file"),
    ]
    for files, pattern, extra, words in cases:
        r = runner.invoke(cli, ["shadow", *files, "--each", "--output-pattern", pattern, *SUN,
                                *extra])
        assert r.exit_code == 2, r.output
        assert words in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert sorted(os.listdir(tmp_path)) == ["in", "other"]
    # sun-hours takes DEM OUTPUT, or DEMs with --each
    r = runner.invoke(cli, ["sun-hours", dems["lidar"], dems["everest"], "x.tif", "--date",
                            "2026-06-21"])
    assert r.exit_code == 2 and "--each" in r.stderr


def test_interrupted_keeps_finished_outputs_and_removes_the_unfinished(tmp_path, runner, dems,
                                                                      monkeypatch):
    from hillshade_rt.io import raster
    real = raster.BandWriter.write
    calls = []

    def write(self, *a, **k):
        calls.append(1)
        if len(calls) == 2:         # the second DEM's band: Ctrl-C while it is written
            raise Interrupted(2)
        return real(self, *a, **k)

    monkeypatch.setattr(raster.BandWriter, "write", write)
    out = tmp_path / "out"
    out.mkdir()
    r = runner.invoke(cli, ["shadow", dems["everest"], dems["fractal"], dems["lidar"], "--each",
                            "--output-pattern", str(out / "{stem}.tif"), *SUN, "-q"])
    assert r.exit_code == 130, r.output
    assert os.listdir(out) == ["everest.tif"]          # no partial file of fractal.tif
    assert "interrupted" in r.stderr and "1 output(s) complete and kept" in r.stderr


def test_api_each(tmp_path, dems):
    import hillshade_rt as hr
    rep = hr.shade([dems["everest"], dems["fractal"], dems["sea"]], each=True,
                   output_pattern=str(tmp_path / "{stem}.tif"), azimuth=203.7, elevation=10)
    assert [e["status"] for e in rep["inputs"]] == ["ok", "ok", "empty"]
    one = tmp_path / "single.tif"
    hr.shade(dems["fractal"], str(one), azimuth=203.7, elevation=10)
    _same_raster(tmp_path / "fractal.tif", one)
    with pytest.raises(BatchFailed) as info:
        hr.shade([dems["corrupt"], dems["everest"]], each=True, azimuth=203.7, elevation=10,
                 output_pattern=str(tmp_path / "b_{stem}.tif"))
    assert isinstance(info.value, HillshadeError) and dems["corrupt"] in str(info.value)
    assert [e["status"] for e in info.value.report["inputs"]] == ["failed", "ok"]
    assert os.path.exists(tmp_path / "b_everest.tif")
    with pytest.raises(UsageProblem, match="add each=True"):
        hr.shade([dems["everest"]], output_pattern=str(tmp_path / "{stem}.tif"), azimuth=1,
                 elevation=10)


def test_fill_stem_keeps_the_other_fields():
    assert fill_stem("out/{stem}_{time:%Y%m%dT%H%M}.tif", "n46e007") == \
        "out/n46e007_{time:%Y%m%dT%H%M}.tif"
    assert fill_stem("{stem!s:>6}_{{x}}_{index}.tif", "a{b}") == "  a{{b}}_{{x}}_{index}.tif"
    assert fill_stem("{stem!s:>6}_{{x}}_{index}.tif", "a{b}").format(index=3) == \
        "  a{b}_{x}_3.tif"
    with pytest.raises(UsageProblem):
        check_pattern("{stem", True)


def test_kernels_warmed_once_per_kind_of_grid(tmp_path, dems, monkeypatch):
    """One process, one warm-up per kind of run (here: a projected and a geographic grid), not
    one per DEM; a later run of the same kind in the process (a server's worker) none."""
    import hillshade_rt as hr
    from hillshade_rt.engine import shader
    calls = []
    real = shader.Shader._warm_up

    def counted(self, *a, **k):
        calls.append(self.grid.method)
        return real(self, *a, **k)

    monkeypatch.setattr(shader.Shader, "_warm_up", counted)
    monkeypatch.setattr(shader, "_WARMED", set())      # what earlier tests warmed aside
    twin = str(tmp_path / "in" / "everest2.tif")
    with open(dems["everest"], "rb") as fi, open(twin, "wb") as fo:
        fo.write(fi.read())
    hr.shade([dems["everest"], dems["fractal"], twin, dems["lidar"]], each=True,
             output_pattern=str(tmp_path / "{stem}.tif"), azimuth=203.7, elevation=10)
    assert len(calls) == 2 and len(set(calls)) == 2
    hr.shade(dems["fractal"], str(tmp_path / "one.tif"), azimuth=203.7, elevation=10)
    assert len(calls) == 2
    hr.shade(dems["fractal"], str(tmp_path / "two.tif"), azimuth=20.0, elevation=10)
    assert len(calls) == 3          # another octant of the sun: the frames' other views
