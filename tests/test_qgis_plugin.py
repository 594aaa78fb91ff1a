"""The QGIS plugin (qgis/hillshade_rt_qgis, docs/qgis.md).

Without QGIS: ``make qgis-plugin``'s zip (one top folder, metadata.txt with
hasProcessingProvider=yes, the code, reproducible), the plugin's imports (never hillshade_rt or
numba), its command lines (commands.py: parameters -> ``hillshade-rt`` argv, each parsed by the
real CLI), finding the program, running it (stderr lines, the one-line error, cancel).

With QGIS (marker ``qgis``): ``qgis_process run hillshade_rt:shadow`` of the zip's plugin on the
repo's test DEM, with this venv's ``hillshade-rt`` as the provider's program setting, gives the
pixels of ``hillshade-rt shadow`` with the same sun; a bad parameter gives the program's one-line
error. Skipped only when ``qgis_process`` is not on PATH; with HILLSHADE_RT_REQUIRE_QGIS=1 (CI,
once it installs QGIS) a missing qgis_process fails instead.
"""

from __future__ import annotations

import ast
import configparser
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import time
import zipfile

import numpy as np
import pytest

from hillshade_rt.testing import data_path, read_band, repo_root

PLUGIN = os.path.join(repo_root(), "qgis", "hillshade_rt_qgis")
DEM = data_path("lidar_dem_1m_utm15n_400x400.tif")
LINKE_MONTHLY = "2.1,2.4,2.9,3.3,3.5,3.6,3.7,3.6,3.2,2.8,2.4,2.1"


def this_checkouts_program() -> str:
    """This venv's ``hillshade-rt`` when it runs this checkout's code; else (the venv installed
    from another checkout, this one on PYTHONPATH) a script that runs this checkout's: the
    plugin removes PYTHONPATH from the program's environment (QGIS's Python must not reach
    it), so the venv's program alone would run the other checkout's code."""
    import atexit
    import tempfile

    import hillshade_rt
    venv_program = os.path.join(os.path.dirname(sys.executable), "hillshade-rt")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    where = subprocess.run([sys.executable, "-c",
                            "import hillshade_rt; print(hillshade_rt.__file__)"],
                           env=env, capture_output=True, text=True, cwd="/").stdout.strip()
    if where and os.path.samefile(where, hillshade_rt.__file__):
        return venv_program
    folder = tempfile.mkdtemp(prefix="hrt-program-")
    atexit.register(shutil.rmtree, folder, True)
    script = os.path.join(folder, "hillshade-rt")
    with open(script, "w") as f:
        f.write(f"#!/bin/sh\nPYTHONPATH={repo_root()} exec {sys.executable} -m hillshade_rt "
                '"$@"\n')
    os.chmod(script, 0o755)
    return script


PROGRAM = this_checkouts_program()
PLUGIN_FILES = {"__init__.py", "plugin.py", "provider.py", "algorithms.py", "commands.py",
                "metadata.txt", "icon.svg"}


def load_commands():
    """qgis/hillshade_rt_qgis/commands.py, imported by its path (pure Python: no qgis)."""
    spec = importlib.util.spec_from_file_location("hillshade_rt_qgis_commands",
                                                  os.path.join(PLUGIN, "commands.py"))
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module          # dataclasses look the module up
    spec.loader.exec_module(module)
    return module


cmd = load_commands()


def make_zip(tmp_path, name="plugin.zip") -> str:
    target = str(tmp_path / name)
    subprocess.run(["make", "-s", "-C", repo_root(), "qgis-plugin", f"QGIS_ZIP={target}",
                    f"PYTHON={sys.executable}"], check=True, capture_output=True, timeout=120)
    return target


# --- the zip

def test_make_qgis_plugin_zip(tmp_path):
    import hillshade_rt
    target = make_zip(tmp_path)
    with zipfile.ZipFile(target) as z:
        names = z.namelist()
        assert z.testzip() is None
        meta_text = z.read("hillshade_rt_qgis/metadata.txt").decode()
        init = z.read("hillshade_rt_qgis/__init__.py").decode()
        stamps = {i.date_time for i in z.infolist()}
    # one top folder, the plugin's; its files and nothing else (no caches)
    assert {n.split("/")[0] for n in names} == {"hillshade_rt_qgis"}
    assert {n.split("/", 1)[1] for n in names} == PLUGIN_FILES
    assert stamps == {(1980, 1, 1, 0, 0, 0)}
    meta = configparser.ConfigParser()
    meta.read_string(meta_text)
    general = meta["general"]
    assert general["hasProcessingProvider"] == "yes"
    assert general["qgisMinimumVersion"] == "3.22"
    assert general["version"] == hillshade_rt.__version__
    for key in ("name", "description", "about", "author", "email", "repository"):
        assert general[key].strip(), key
    assert "def classFactory(iface)" in init
    # reproducible: the same bytes twice
    again = make_zip(tmp_path, "again.zip")
    with open(target, "rb") as a, open(again, "rb") as b:
        assert a.read() == b.read()


def test_plugin_never_imports_hillshade_rt_or_numba():
    """numba inside QGIS's Python breaks plugins (UMEP-processing #23, #79): the plugin imports
    only the standard library, qgis, processing and itself."""
    allowed = {"qgis", "processing"} | set(sys.stdlib_module_names)
    for name in sorted(os.listdir(PLUGIN)):
        if not name.endswith(".py"):
            continue
        with open(os.path.join(PLUGIN, name)) as f:
            tree = ast.parse(f.read(), name)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                tops = [a.name.split(".")[0] for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                tops = [node.module.split(".")[0]]
            else:
                continue
            assert set(tops) <= allowed, f"{name}:{node.lineno} imports {tops}"


def test_algorithm_names_are_the_registry():
    from hillshade_rt.algorithms import REGISTRY
    assert cmd.ALGORITHMS == tuple(REGISTRY)


# --- the command lines

def parse(argv):
    """The params the real CLI parses from ``argv`` (the program's subcommand and options);
    an unknown option or bad value raises click's error."""
    from hillshade_rt.cli import cli
    command = cli.commands[argv[1]]
    with command.make_context(argv[1], list(argv[2:])) as ctx:
        return ctx.params


def test_shadow_argv_azimuth():
    argv = cmd.shadow_argv("/opt/hr/bin/hillshade-rt", "/d/dem.tif", "/o/out.tif",
                           azimuth=225.0, elevation=20.5, algorithm="brute", soft=True,
                           self_shadow=True)
    assert argv == ["/opt/hr/bin/hillshade-rt", "shadow", "/d/dem.tif", "/o/out.tif",
                    "--azimuth", "225", "--elevation", "20.5", "--self-shadow",
                    "--algorithm", "brute", "--soft", "--overwrite"]
    p = parse(argv)
    assert (p["azimuth"], p["elevation"], p["algorithm"], p["soft"], p["self_shadow"],
            p["overwrite"]) == (225.0, 20.5, "brute", True, True, True)
    assert p["files"] == ("/d/dem.tif", "/o/out.tif")      # DEM... OUTPUT: the last is written


def test_shadow_argv_time_zone_band_extra():
    argv = cmd.shadow_argv("hillshade-rt", "dem.tif", "out.tif", band=2, sun="time",
                           time_="2026-06-21T14:30:00", tz=" Europe/Zurich ",
                           extra=cmd.split_extra("--no-earth-curvature --threads 2"))
    assert argv == ["hillshade-rt", "shadow", "dem.tif", "out.tif", "--band", "2",
                    "--time", "2026-06-21T14:30:00", "--tz", "Europe/Zurich",
                    "--algorithm", "auto", "--no-earth-curvature", "--threads", "2",
                    "--overwrite"]
    p = parse(argv)
    assert p["time"] == ("2026-06-21T14:30:00",) and p["tz"] == "Europe/Zurich"
    assert p["band"] == 2 and p["curvature"] is False and p["threads"] == 2
    # no zone: UTC (the program refuses a time without offset or zone)
    assert cmd.sun_args("time", time_="2026-06-21T12:00:00", tz="")[-2:] == ["--tz", "UTC"]


def test_hillshade_sun_hours_skyview_argv():
    argv = cmd.hillshade_argv("hr", "dem.tif", "hs.tif", azimuth=300, elevation=30,
                              ambient=0.35)
    assert argv == ["hr", "hillshade", "dem.tif", "hs.tif", "--azimuth", "300", "--elevation",
                    "30", "--ambient", "0.35", "--algorithm", "auto", "--overwrite"]
    assert parse(argv)["ambient"] == 0.35

    argv = cmd.sun_hours_argv("hr", "dem.tif", "h.tif", date="2026-12-01",
                              end_date="2026-12-31", step_minutes=15, tz="Europe/Vienna",
                              algorithm="bounds")
    assert argv == ["hr", "sun-hours", "dem.tif", "h.tif", "--date", "2026-12-01",
                    "--end-date", "2026-12-31", "--step", "15min", "--tz", "Europe/Vienna",
                    "--algorithm", "bounds", "--overwrite"]
    p = parse(argv)
    assert p["files"] == ("dem.tif", "h.tif")       # DEM OUTPUT (or DEM... --each)
    assert (p["date_"], p["end_date"], p["step"], p["tz"]) == ("2026-12-01", "2026-12-31",
                                                                "15min", "Europe/Vienna")
    # a step that is not whole minutes: seconds; no zone: no --tz (local mean solar time)
    argv = cmd.sun_hours_argv("hr", "dem.tif", "h.tif", date="2026-06-21", step_minutes=0.5)
    assert argv[argv.index("--step") + 1] == "30s" and "--tz" not in argv
    parse(argv)

    argv = cmd.skyview_argv("hr", "dem.tif", "svf.tif", directions=16, definition="dozier",
                            max_distance=500.0)
    assert argv == ["hr", "skyview", "dem.tif", "svf.tif", "--directions", "16",
                    "--definition", "dozier", "--max-distance", "500", "--overwrite"]
    p = parse(argv)
    assert (p["directions"], p["definition"], p["max_distance"]) == (16, "dozier", 500.0)
    assert "--max-distance" not in cmd.skyview_argv("hr", "d.tif", "o.tif", max_distance=0)


def test_shadow_argv_vector():
    """The optional shadow polygons: --vector after the mask's options; not with soft."""
    argv = cmd.shadow_argv("hr", "dem.tif", "out.tif", azimuth=203.7, elevation=12,
                           vector="/o/shadow.gpkg")
    assert argv == ["hr", "shadow", "dem.tif", "out.tif", "--azimuth", "203.7", "--elevation",
                    "12", "--vector", "/o/shadow.gpkg", "--algorithm", "auto", "--overwrite"]
    p = parse(argv)
    assert p["vector"] == "/o/shadow.gpkg" and p["vector_connectivity"] == "4"
    assert "--vector" not in cmd.shadow_argv("hr", "d.tif", "o.tif", vector=None)
    with pytest.raises(cmd.ProgramError, match="not with soft shadows"):
        cmd.shadow_argv("hr", "d.tif", "o.tif", soft=True, vector="/o/s.gpkg")


def test_argv_refusals():
    with pytest.raises(cmd.ProgramError, match="algorithm must be one of"):
        cmd.shadow_argv("hr", "d.tif", "o.tif", algorithm="fastest")
    with pytest.raises(cmd.ProgramError, match="needs the date and time"):
        cmd.shadow_argv("hr", "d.tif", "o.tif", sun="time", time_=None)
    with pytest.raises(cmd.ProgramError, match="definition must be one of"):
        cmd.skyview_argv("hr", "d.tif", "o.tif", definition="rvt")
    with pytest.raises(cmd.ProgramError, match="additional options"):
        cmd.split_extra('--tz "Europe/Zurich')
    with pytest.raises(cmd.ProgramError, match="step"):
        cmd.sun_hours_argv("hr", "d.tif", "o.tif", date="2026-06-21", step_minutes=0)


def test_horizon_profile_query_argv(tmp_path):
    argv = cmd.horizon_argv("hr", "dem.tif", "hz.tif", azimuth=135.5, max_distance=300,
                            height_above_ground=1.5)
    assert argv == ["hr", "horizon", "dem.tif", "hz.tif", "--azimuth", "135.5", "--method",
                    "scan", "--max-distance", "300", "--height-above-ground", "1.5",
                    "--overwrite"]
    p = parse(argv)
    assert (p["azimuth"], p["max_distance"], p["height_above_ground"]) == (135.5, 300.0, 1.5)
    argv = cmd.horizon_argv("hr", "dem.tif", "hz.tif", mode="directions", directions=16,
                            distance="/o/d.tif", method="hull", band=2)
    assert argv == ["hr", "horizon", "dem.tif", "hz.tif", "--band", "2", "--directions", "16",
                    "--distance", "/o/d.tif", "--method", "hull", "--overwrite"]
    p = parse(argv)
    assert (p["directions"], p["distance"], p["method"], p["azimuth"]) == (16, "/o/d.tif",
                                                                            "hull", None)

    argv = cmd.profile_argv("hr", "dem.tif", "/o/prof.geojson", points="/t/p.csv", step=5,
                            height_above_ground=2)
    assert argv == ["hr", "profile", "dem.tif", "--points", "/t/p.csv", "--step", "5",
                    "--height-above-ground", "2", "--format", "geojson", "-o",
                    "/o/prof.geojson", "--overwrite"]
    p = parse(argv)
    assert (p["points"], p["step"], p["fmt"] if "fmt" in p else p["format"],
            p["output"]) == ("/t/p.csv", 5.0, "geojson", "/o/prof.geojson")
    assert cmd.profile_argv("hr", "d.tif", "o.CSV", points="p.csv")[-5:-3] == ["--format",
                                                                              "csv"]
    assert cmd.table_format("o.txt", cmd.QUERY_FORMATS) == "csv"

    argv = cmd.query_argv("hr", "dem.tif", "q.csv", points="p.csv", azimuth=200,
                          elevation=20)
    assert argv == ["hr", "query", "dem.tif", "--points", "p.csv", "--azimuth", "200",
                    "--elevation", "20", "--format", "csv", "-o", "q.csv", "--overwrite"]
    parse(argv)
    argv = cmd.query_argv("hr", "dem.tif", "q.json", points="p.csv", sun="series",
                          time_="2026-06-21T08:00:00", end_time="2026-06-21T18:00:00",
                          step_minutes=90, tz="America/Chicago", irradiance=True, band=3)
    assert argv == ["hr", "query", "dem.tif", "--points", "p.csv", "--start",
                    "2026-06-21T08:00:00", "--end", "2026-06-21T18:00:00", "--step", "90min",
                    "--tz", "America/Chicago", "--irradiance", "--format", "json", "-o",
                    "q.json", "--band", "3", "--overwrite"]
    p = parse(argv)
    assert (p["start"], p["end"], p["step"], p["irradiance"], p["band"]) == (
        "2026-06-21T08:00:00", "2026-06-21T18:00:00", "90min", True, 3)
    argv = cmd.query_argv("hr", "dem.tif", "q.csv", points="p.csv", sun="time",
                          time_="2026-06-21T08:00:00")
    assert argv[4:8] == ["p.csv", "--time", "2026-06-21T08:00:00", "--tz"]
    parse(argv)

    pts = tmp_path / "p.csv"
    assert cmd.write_points_csv(str(pts), [("a", 1, 2.5), (7, 429400.125, 5150600.0)]) == 2
    assert pts.read_text().splitlines() == ["id,x,y", "a,1.0,2.5", "7,429400.125,5150600.0"]
    with pytest.raises(cmd.ProgramError, match="no points"):
        cmd.write_points_csv(str(pts), [])


def test_irradiance_animate_illumination_argv():
    argv = cmd.irradiance_argv("hr", "dem.tif", "irr.tif", date="2026-06-21",
                               end_date="2026-06-22", step_minutes=30, tz="Europe/Zurich",
                               clear_sky="ineichen", linke_turbidity=3.5, albedo=0.3,
                               mean=True, perez=True, skyview_directions=16,
                               height_above_ground=1, algorithm="brute", soft=True)
    assert argv == ["hr", "irradiance", "dem.tif", "irr.tif", "--date", "2026-06-21",
                    "--end-date", "2026-06-22", "--step", "30min", "--tz", "Europe/Zurich",
                    "--clear-sky", "ineichen", "--linke-turbidity", "3.5", "--albedo", "0.3",
                    "--mean", "--perez", "--skyview-directions", "16",
                    "--height-above-ground", "1", "--algorithm", "brute", "--soft",
                    "--overwrite"]
    p = parse(argv)
    assert (p["clear_sky"], p["linke_turbidity"], p["albedo"], p["mean"], p["perez"],
            p["skyview_directions"]) == ("ineichen", "3.5", "0.3", True, True, 16)
    argv = cmd.irradiance_argv("hr", "dem.tif", "irr.tif", date="2026-06-21")
    assert argv == ["hr", "irradiance", "dem.tif", "irr.tif", "--date", "2026-06-21",
                    "--step", "15min", "--clear-sky", "ineichen", "--albedo", "0.2",
                    "--skyview-directions", "32", "--algorithm", "auto", "--overwrite"]
    parse(argv)
    # a measured sky: no clear-sky model (the program refuses --clear-sky with --ghi)
    argv = cmd.irradiance_argv("hr", "dem.tif", "irr.tif", date="2026-06-21",
                               clear_sky="haurwitz", ghi="/m/ghi.csv")
    assert "--clear-sky" not in argv and argv[argv.index("--ghi") + 1] == "/m/ghi.csv"
    assert parse(argv)["clear_sky"] is None
    argv = cmd.animate_argv("hr", "dem.tif", "a.gif", date="2026-06-21", step_minutes=60,
                            tz="America/Chicago", fps=4, size=128, label=False)
    assert argv == ["hr", "animate", "dem.tif", "a.gif", "--date", "2026-06-21", "--step",
                    "60min", "--tz", "America/Chicago", "--fps", "4", "--size", "128",
                    "--no-label", "--algorithm", "auto", "--overwrite"]
    p = parse(argv)
    assert (p["date_"], p["fps"], p["size"], p["label"]) == ("2026-06-21", 4.0, 128, False)
    argv = cmd.animate_argv("hr", "dem.tif", "a.mp4", mode="series",
                            start="2026-06-21T06:00:00", end="2026-06-21T20:00:00")
    assert argv[4:10] == ["--start", "2026-06-21T06:00:00", "--end", "2026-06-21T20:00:00",
                          "--step", "30min"]
    parse(argv)

    argv = cmd.illumination_argv("hr", "dem.tif", "il.tif", subsolar_file="/s/sun.csv",
                                 body=" moon ", sun_distance=1.5e11, height_above_ground=2,
                                 soft=True)
    assert argv == ["hr", "illumination", "dem.tif", "il.tif", "--subsolar-file",
                    "/s/sun.csv", "--body", "moon", "--sun-distance", "1.5e+11",
                    "--height-above-ground", "2", "--soft", "--overwrite"]
    p = parse(argv)
    assert (p["subsolar_file"], p["body"], p["sun_distance"], p["soft"]) == (
        "/s/sun.csv", "moon", 1.5e11, True)
    parse(cmd.illumination_argv("hr", "dem.tif", "il.tif", subsolar_file="s.csv"))


def test_new_argv_refusals():
    with pytest.raises(cmd.ProgramError, match="horizon must be one of"):
        cmd.horizon_argv("hr", "d.tif", "o.tif", mode="both")
    with pytest.raises(cmd.ProgramError, match="no points"):
        cmd.profile_argv("hr", "d.tif", "o.csv", points="")
    with pytest.raises(cmd.ProgramError, match="first and last time"):
        cmd.query_argv("hr", "d.tif", "o.csv", points="p.csv", sun="series",
                       time_="2026-06-21T08:00:00")
    with pytest.raises(cmd.ProgramError, match="needs the date"):
        cmd.animate_argv("hr", "d.tif", "o.gif")
    with pytest.raises(cmd.ProgramError, match="subsolar"):
        cmd.illumination_argv("hr", "d.tif", "o.tif", subsolar_file="")
    with pytest.raises(cmd.ProgramError, match="clear sky must be one of"):
        cmd.irradiance_argv("hr", "d.tif", "o.tif", date="2026-06-21", clear_sky="perez")


def test_irradiance_sky_inputs_monthly_instants_argv():
    """The albedo as a raster or 12 monthly numbers, the Linke turbidity by month, --monthly
    and --daily-mean, and instants (repeated --time) as the program parses them."""
    linke = cmd.sky_value("linke", 0 or None, "2.1, 2.4 2.9;3.3,3.5,3.6,3.7,3.6,3.2,2.8,2.4,2.1")
    assert linke == "2.1,2.4,2.9,3.3,3.5,3.6,3.7,3.6,3.2,2.8,2.4,2.1"
    albedo = cmd.sky_value("albedo", 0.25, "0.6 " * 12, "/r/albedo.tif")
    assert albedo == "/r/albedo.tif"                    # the raster overrides the numbers
    assert cmd.sky_value("albedo", 0.25, " ", None) == "0.25"
    assert cmd.sky_value("albedo", 0.25, "0.15", None) == "0.15"
    assert cmd.sky_value("linke", None, "") is None
    argv = cmd.irradiance_argv("hr", "dem.tif", "year.tif", date="2027-01-01",
                               end_date="2027-12-31", step_minutes=120, tz="Europe/Vienna",
                               linke_turbidity=linke, albedo=albedo, daily_mean=True,
                               monthly=True)
    assert argv == ["hr", "irradiance", "dem.tif", "year.tif", "--date", "2027-01-01",
                    "--end-date", "2027-12-31", "--step", "120min", "--tz", "Europe/Vienna",
                    "--clear-sky", "ineichen", "--linke-turbidity", linke,
                    "--albedo", "/r/albedo.tif", "--daily-mean", "--monthly",
                    "--skyview-directions", "32", "--algorithm", "auto", "--overwrite"]
    p = parse(argv)
    assert (p["linke_turbidity"], p["albedo"], p["daily_mean"], p["monthly"],
            p["mean"]) == (linke, "/r/albedo.tif", True, True, False)
    assert p["beam_index"] is None and p["diffuse_index"] is None   # none given: not passed

    # a Linke raster over its numbers; r.sun's clear-sky indices: a raster over the number,
    # the number alone (0 is an index, not "none"), none at all
    linke = cmd.sky_value("the Linke turbidity by month", 3.3, LINKE_MONTHLY, "/r/linke.tif")
    assert linke == "/r/linke.tif"
    beam = cmd.sky_value("the beam index", 0.55, None, "/r/kb.tif")
    diffuse = cmd.sky_value("the diffuse index", 0.0, None, None)
    assert (beam, diffuse) == ("/r/kb.tif", "0")
    argv = cmd.irradiance_argv("hr", "dem.tif", "real.tif", date="2027-03-01", tz="Europe/Vienna",
                               linke_turbidity=linke, albedo=0.3, beam_index=beam,
                               diffuse_index=diffuse)
    assert argv == ["hr", "irradiance", "dem.tif", "real.tif", "--date", "2027-03-01",
                    "--step", "15min", "--tz", "Europe/Vienna", "--clear-sky", "ineichen",
                    "--linke-turbidity", "/r/linke.tif", "--albedo", "0.3",
                    "--beam-index", "/r/kb.tif", "--diffuse-index", "0",
                    "--skyview-directions", "32", "--algorithm", "auto", "--overwrite"]
    p = parse(argv)
    assert (p["linke_turbidity"], p["beam_index"], p["diffuse_index"]) == (
        "/r/linke.tif", "/r/kb.tif", "0")
    argv = cmd.irradiance_argv("hr", "dem.tif", "o.tif", date="2027-03-01",
                               beam_index=0.625, diffuse_index="/r/kd.tif")
    assert argv[argv.index("--beam-index"):argv.index("--beam-index") + 4] == [
        "--beam-index", "0.625", "--diffuse-index", "/r/kd.tif"]
    assert parse(argv)["beam_index"] == "0.625"
    none = cmd.irradiance_argv("hr", "dem.tif", "o.tif", date="2027-03-01",
                               beam_index=cmd.sky_value("kb", None, None, None),
                               diffuse_index="")
    assert not {"--beam-index", "--diffuse-index"} & set(none)

    times = cmd.instants("2026-06-21T09:30, 15:05;\n 7:00:30 ,2026-06-22T12:00+02:00,",
                         "2026-06-21")
    assert times == ["2026-06-21T09:30", "2026-06-21T15:05", "2026-06-21T07:00:30",
                     "2026-06-22T12:00+02:00"]
    argv = cmd.irradiance_argv("hr", "dem.tif", "now.tif", date="2026-06-21",
                               end_date="2026-06-30", step_minutes=10, times=times,
                               tz="Europe/Zurich", albedo=0.3)
    # instants instead of the period: no --date, --end-date or --step
    assert argv[:12] == ["hr", "irradiance", "dem.tif", "now.tif", "--time", times[0],
                         "--time", times[1], "--time", times[2], "--time", times[3]]
    assert not {"--date", "--end-date", "--step"} & set(argv)
    p = parse(argv)
    assert p["time"] == tuple(times) and p["date_"] is None and p["tz"] == "Europe/Zurich"
    # instants alone (no date) are enough
    parse(cmd.irradiance_argv("hr", "dem.tif", "o.tif", times=["2026-03-20T12:00:00Z"]))

    with pytest.raises(cmd.ProgramError, match="12 monthly numbers .January first., not 3"):
        cmd.sky_value("the albedo by month", 0.2, "0.1,0.2,0.3")
    with pytest.raises(cmd.ProgramError, match="the Linke turbidity by month: a number or 12"):
        cmd.sky_value("the Linke turbidity by month", None, "3,x")
    with pytest.raises(cmd.ProgramError, match="'12:00' has no date"):
        cmd.instants("12:00", None)
    with pytest.raises(cmd.ProgramError, match="needs a date .or instants."):
        cmd.irradiance_argv("hr", "d.tif", "o.tif", date=None, times=[])


def test_irradiance_index_with_measured_sky_is_the_programs_error(tmp_path):
    """An index with a measured sky (GHI): passed on as a Linke turbidity with GHI is, and the
    program's one-line refusal (exit 2, nothing written) is the run's error line, as the
    algorithm raises it."""
    ghi = tmp_path / "ghi.csv"
    ghi.write_text("time,ghi\n2026-06-21T00:00Z,0\n2026-06-22T00:00Z,0\n")
    out = tmp_path / "never.tif"
    argv = cmd.irradiance_argv(PROGRAM, DEM, str(out), date="2026-06-21", ghi=str(ghi),
                               clear_sky="ineichen", beam_index=0.5,
                               diffuse_index=cmd.sky_value("kd", 0.4, None, None))
    assert "--clear-sky" not in argv
    assert argv[argv.index("--beam-index") + 1] == "0.5"
    assert argv[argv.index("--diffuse-index") + 1] == "0.4"
    result = cmd.run(argv)
    assert result.returncode == 2 and not result.canceled
    error = result.error_line()
    assert cmd.is_error_line(error), result.lines
    assert "--ghi" in error and "--beam-index" in error and "--diffuse-index" in error
    assert not out.exists() and os.listdir(tmp_path) == ["ghi.csv"]


def test_sun_hours_monthly_and_horizon_range_argv():
    argv = cmd.sun_hours_argv("hr", "dem.tif", "h.tif", date="2027-01-01",
                              end_date="2027-12-31", step_minutes=20, monthly=True)
    assert argv == ["hr", "sun-hours", "dem.tif", "h.tif", "--date", "2027-01-01",
                    "--end-date", "2027-12-31", "--step", "20min", "--monthly", "--algorithm",
                    "auto", "--overwrite"]
    assert parse(argv)["monthly"] is True
    assert "--monthly" not in cmd.sun_hours_argv("hr", "d.tif", "o.tif", date="2027-01-01")

    argv = cmd.horizon_argv("hr", "dem.tif", "hz.tif", mode="range", start=92.5, end=272.5,
                            step=22.5, angle_unit="radians", max_distance=150)
    assert argv == ["hr", "horizon", "dem.tif", "hz.tif", "--start", "92.5", "--end",
                    "272.5", "--step", "22.5", "--angle-unit", "radians", "--method", "scan",
                    "--max-distance", "150", "--overwrite"]
    p = parse(argv)
    assert (p["start"], p["end"], p["step"], p["angle_unit"], p["azimuth"],
            p["directions"]) == (92.5, 272.5, 22.5, "radians", None, None)
    # no end: a whole turn from the start; degrees are the default, not written
    argv = cmd.horizon_argv("hr", "dem.tif", "hz.tif", mode="range", start=10, step=45)
    assert argv[4:8] == ["--start", "10", "--step", "45"]
    assert "--end" not in argv and "--angle-unit" not in argv
    assert parse(argv)["end"] is None
    with pytest.raises(cmd.ProgramError, match="step between azimuths"):
        cmd.horizon_argv("hr", "d.tif", "o.tif", mode="range", step=0)
    with pytest.raises(cmd.ProgramError, match="angle unit must be one of"):
        cmd.horizon_argv("hr", "d.tif", "o.tif", angle_unit="gon")


def test_progress_commands_are_the_clis():
    """--progress json goes to the commands that take it, and only to those; the argv still
    parses."""
    from hillshade_rt.cli import cli
    takes = {name for name, c in cli.commands.items()
             if any("--progress" in p.opts for p in c.params)}
    assert takes == set(cmd.PROGRESS_COMMANDS)
    argv = cmd.with_progress(cmd.shadow_argv("hr", "d.tif", "o.tif",
                                             extra=["--progress", "bar"]))
    assert argv[-3:] == ["--progress", "json", "--overwrite"]
    assert parse(argv)["progress"] == "json"       # the last one given wins
    argv = cmd.profile_argv("hr", "d.tif", "o.csv", points="p.csv")
    assert cmd.with_progress(argv) == argv


def test_parse_progress_lines():
    assert cmd.parse_progress('{"progress": 0.42}') == pytest.approx(42.0)
    assert cmd.parse_progress('{"progress": 1.0}\n') == 100.0
    assert cmd.parse_progress('{"progress": 0}') == 0.0
    assert cmd.parse_progress('{"progress": 1.5}') == 100.0
    for other in ("hillshade-rt: o.tif: 400x400, ...", "", "{", '{"progress": "x"}',
                  '{"progress": 0.5, "eta": 3}', '["progress"]', '{"progress": true}',
                  '{"progress": NaN}'):
        assert cmd.parse_progress(other) is None, other


@pytest.mark.slow
def test_run_program_progress_lines(tmp_path):
    """The real program over many suns: its progress lines, read by the plugin's parser,
    increase to 100 %."""
    argv = cmd.with_progress(cmd.sun_hours_argv(PROGRAM, DEM, str(tmp_path / "h.tif"),
                                                date="2026-06-21", step_minutes=120))
    result = cmd.run(argv)
    assert result.returncode == 0, result.lines
    got = [cmd.parse_progress(line) for line in result.lines]
    got = [p for p in got if p is not None]
    assert len(got) >= 4 and got == sorted(set(got)) and got[-1] == 100.0, result.lines


# --- finding and running the program

def _executable(path):
    path.write_text("#!/bin/sh\nexit 0\n")
    path.chmod(0o755)
    return str(path)


def test_find_program(tmp_path):
    home, on_path, elsewhere = tmp_path / "home", tmp_path / "bin", tmp_path / "opt"
    for d in (home / ".local" / "bin", on_path, elsewhere):
        d.mkdir(parents=True)
    local = _executable(home / ".local" / "bin" / "hillshade-rt")
    # nothing on PATH: ~/.local/bin
    assert cmd.find_program("", path=str(tmp_path / "empty"), home=str(home)) == local
    # on PATH first
    first = _executable(on_path / "hillshade-rt")
    assert cmd.find_program(None, path=str(on_path), home=str(home)) == first
    # the setting wins: a file, or a folder holding it
    given = _executable(elsewhere / "hillshade-rt")
    assert cmd.find_program(given, path=str(on_path), home=str(home)) == given
    assert cmd.find_program(str(elsewhere), path=str(on_path), home=str(home)) == given
    with pytest.raises(cmd.ProgramError, match="no such executable"):
        cmd.find_program(str(tmp_path / "missing"), path=str(on_path), home=str(home))
    with pytest.raises(cmd.ProgramError, match="not found on PATH nor in"):
        cmd.find_program("", path=str(tmp_path / "empty"), home=str(tmp_path / "nohome"))


def test_child_env_drops_qgis_python_and_gdal():
    env = cmd.child_env({"PATH": "/usr/bin", "PYTHONPATH": "/usr/share/qgis/python",
                         "PYTHONHOME": "/usr", "GDAL_DATA": "/usr/share/gdal",
                         "PROJ_LIB": "/usr/share/proj", "HOME": "/root"})
    assert env == {"PATH": "/usr/bin", "HOME": "/root"}


def test_run_program_error_line(tmp_path):
    """The real program, a bad elevation: exit 2, its one-line error; no output."""
    out = tmp_path / "o.tif"
    lines = []
    argv = cmd.shadow_argv(PROGRAM, DEM, str(out), azimuth=225, elevation=-5)
    # QGIS's PYTHONHOME would stop the venv's Python from starting: run() drops it
    result = cmd.run(argv, on_line=lines.append, env={**os.environ, "PYTHONHOME": "/nowhere"})
    assert result.returncode == 2 and not result.canceled
    assert result.error_line().startswith("hillshade-rt: error: ")
    assert "elevation" in result.error_line()
    assert lines == result.lines and result.error_line() in lines
    assert not out.exists()


def test_run_program_canceled(tmp_path):
    """Cancelling terminates the child at once (no waiting for it to finish)."""
    script = tmp_path / "slow.py"
    script.write_text("import sys, time\nprint('started', flush=True)\n"
                      "print('on stderr', file=sys.stderr, flush=True)\ntime.sleep(60)\n")
    seen = []
    t0 = time.monotonic()
    result = cmd.run([sys.executable, str(script)], on_line=seen.append,
                     is_canceled=lambda: len(seen) >= 2)
    assert time.monotonic() - t0 < 20
    assert result.canceled and result.returncode != 0
    assert sorted(seen) == ["on stderr", "started"]


def test_run_program_missing():
    with pytest.raises(cmd.ProgramError, match="cannot start"):
        cmd.run(["/nonexistent/hillshade-rt", "--version"])


# --- in QGIS (qgis_process)

def qgis_process_binary() -> str | None:
    """qgis_process on PATH; Debian's /usr/bin/qgis_process is a wrapper script that passes
    --noversioncheck, which 3.22's qgis_process refuses (qgis/QGIS#57683): its
    qgis_process.bin beside it is the program itself."""
    found = shutil.which("qgis_process")
    if found is None:
        return None
    beside = found + ".bin"
    return beside if os.access(beside, os.X_OK) else found


@pytest.fixture(scope="module")
def qgis(tmp_path_factory):
    """A QGIS profile with the zip's plugin installed and enabled and the provider's program
    setting pointing at this venv's hillshade-rt: returns run(args) -> CompletedProcess."""
    binary = qgis_process_binary()
    if binary is None:
        if os.environ.get("HILLSHADE_RT_REQUIRE_QGIS"):
            pytest.fail("qgis_process not on PATH (HILLSHADE_RT_REQUIRE_QGIS is set)")
        pytest.skip("qgis_process not on PATH (apt-get install qgis qgis-providers "
                    "python3-qgis)")
    base = tmp_path_factory.mktemp("qgis")
    plugins, config = base / "plugins", base / "config"
    with zipfile.ZipFile(make_zip(base)) as z:
        z.extractall(plugins)
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", QGIS_CUSTOM_CONFIG_PATH=str(config),
               QGIS_PLUGINPATH=str(plugins), XDG_RUNTIME_DIR=str(base))
    # QGIS's embedded Python takes its prefix from the first python3 on PATH: this venv's (or
    # pyenv's) there would leave it without its qgis module; QGIS's own folder goes first
    env.pop("VIRTUAL_ENV", None)
    env["PATH"] = os.pathsep.join([os.path.dirname(binary)] + [
        d for d in env.get("PATH", "").split(os.pathsep)
        if d and not os.path.exists(os.path.join(os.path.dirname(d), "pyvenv.cfg"))])

    def run(*args, timeout=600):
        return subprocess.run([binary, *args], env=env, capture_output=True, text=True,
                              timeout=timeout, cwd=str(base))
    run.env = env
    # QGIS writes statistics beside the rasters it opens (.aux.xml): the DEMs it reads are
    # copies, and the checkout stays as it was
    run.dem = shutil.copy(DEM, base / "dem.tif")

    enabled = run("plugins", "enable", "hillshade_rt_qgis")
    assert enabled.returncode == 0, enabled.stdout + enabled.stderr
    # the provider setting, as Settings > Options > Processing > Providers saves it
    ini = config / "profiles" / "default" / "QGIS" / "QGIS3.ini"
    line = f"Configuration\\{cmd.SETTING_PROGRAM}={PROGRAM}"
    text = ini.read_text() if ini.exists() else ""
    if "[Processing]\n" in text:
        text = text.replace("[Processing]\n", f"[Processing]\n{line}\n", 1)
    else:
        text += f"\n[Processing]\n{line}\n"
    ini.write_text(text)
    listed = run("list")
    assert "hillshade_rt:shadow" in listed.stdout, listed.stdout + listed.stderr
    return run


def direct(dem, *args) -> subprocess.CompletedProcess:
    return subprocess.run([PROGRAM, "shadow", str(dem), *args], capture_output=True, text=True,
                          timeout=600)


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_shadow_equals_program(qgis, tmp_path):
    out, ref = tmp_path / "qgis.tif", tmp_path / "ref.tif"
    done = qgis("run", "hillshade_rt:shadow", "--json", "--", f"INPUT={qgis.dem}",
                "AZIMUTH=225", "ELEVATION=20", f"OUTPUT={out}")
    assert done.returncode == 0, done.stdout + done.stderr
    report = json.loads(done.stdout)
    assert report["results"]["OUTPUT"] == str(out)
    # the command and the program's stderr (its summary line) in the feedback
    info = report["log"]["info"]
    assert info[0].startswith(PROGRAM + " shadow ") and "--azimuth 225 --elevation 20" in info[0]
    assert any(line.startswith(f"hillshade-rt: {out}: 400x400, sun az 225 el 20")
               for line in info), info
    assert direct(qgis.dem, str(ref), "--azimuth", "225", "--elevation", "20").returncode == 0
    got, want = read_band(out), read_band(ref)
    assert got.dtype == want.dtype == np.uint8
    assert {0, 1} <= set(np.unique(want).tolist())
    np.testing.assert_array_equal(got, want)


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_time_zone_equals_program(qgis, tmp_path):
    out, ref = tmp_path / "qgis.tif", tmp_path / "ref.tif"
    done = qgis("run", "hillshade_rt:shadow", "--", f"INPUT={qgis.dem}", "SUN=1",
                "DATETIME=2026-12-21T08:40:00", "TIMEZONE=America/Chicago", "ALGORITHM=bounds",
                f"OUTPUT={out}")
    assert done.returncode == 0, done.stdout + done.stderr
    assert direct(qgis.dem, str(ref), "--time", "2026-12-21T08:40", "--tz", "America/Chicago",
                  "--algorithm", "bounds").returncode == 0
    want = read_band(ref)
    assert 0 < (want == 1).mean() < 1
    np.testing.assert_array_equal(read_band(out), want)


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_bad_parameter_gives_program_error(qgis, tmp_path):
    out = tmp_path / "never.tif"
    done = qgis("run", "hillshade_rt:shadow", "--", f"INPUT={qgis.dem}", "SUN=1",
                "DATETIME=2026-06-21T14:30:00", "TIMEZONE=Mars/Olympus", f"OUTPUT={out}")
    assert done.returncode != 0
    own = direct(qgis.dem, str(out), "--time", "2026-06-21T14:30:00", "--tz", "Mars/Olympus")
    assert own.returncode == 2
    error = own.stderr.strip().splitlines()[-1]
    assert error.startswith("hillshade-rt: error: --tz 'Mars/Olympus'")
    assert f"ERROR:\t{error}" in done.stdout + done.stderr, done.stdout + done.stderr
    assert not out.exists()


# QGIS's own Python: the zip's provider in a QgsApplication, the program's path set
PRELUDE = r"""
import os, sys, time
from qgis.core import (QgsApplication, QgsProcessingException, QgsProcessingFeedback,
                       QgsProject)
app = QgsApplication([], False)
app.initQgis()
plugins, program, dem, out = sys.argv[1:5]
sys.path[:0] = [plugins, os.path.join(QgsApplication.pkgDataPath(), "python", "plugins")]
from processing.core.Processing import Processing
Processing.initialize()
from processing.core.ProcessingConfig import ProcessingConfig
from hillshade_rt_qgis.provider import HillshadeRtProvider
provider = HillshadeRtProvider()            # kept: the registry does not own it from Python
assert QgsApplication.processingRegistry().addProvider(provider)
ProcessingConfig.setSettingValue("HILLSHADE_RT_PROGRAM", program)
import processing
"""


def qgis_python(qgis, tmp_path, body: str, dem: str) -> list:
    """Run PRELUDE + ``body`` with QGIS's Python (the python3 beside qgis_process) on a copy
    of ``dem``, the output in tmp_path/out; its stdout's lines."""
    python = os.path.join(os.path.dirname(qgis_process_binary()), "python3")
    script, out_dir, plugins = tmp_path / "script.py", tmp_path / "out", tmp_path / "plugins"
    script.write_text(PRELUDE + body)
    out_dir.mkdir()
    with zipfile.ZipFile(make_zip(tmp_path)) as z:
        z.extractall(plugins)
    done = subprocess.run([python, str(script), str(plugins), PROGRAM,
                           shutil.copy(dem, tmp_path / "dem.tif"), str(out_dir / "out.tif")],
                          env=qgis.env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout.splitlines()


CANCEL = r"""
class Feedback(QgsProcessingFeedback):
    started = None
    def pushCommandInfo(self, info):
        print("COMMAND", info, flush=True)
        Feedback.started = time.monotonic()
    def isCanceled(self):
        return self.started is not None and time.monotonic() - self.started > 2

try:
    processing.run("hillshade_rt:skyview", {"INPUT": dem, "DIRECTIONS": 360, "OUTPUT": out},
                   feedback=Feedback())
    print("FINISHED")
except QgsProcessingException as e:
    print("EXCEPTION", e)
print("AFTER_CANCEL", round(time.monotonic() - Feedback.started, 1))
"""


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_cancel_terminates_program(qgis, tmp_path):
    """Cancelling in QGIS (the feedback's isCanceled) stops the program at once: the
    algorithm fails with 'canceled', the program leaves nothing in the output folder."""
    lines = qgis_python(qgis, tmp_path, CANCEL, os.path.join(
        repo_root(), "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif"))
    assert lines[0].startswith(f"COMMAND {PROGRAM} skyview "), lines
    assert "EXCEPTION canceled: hillshade-rt was stopped (no output written)" in lines, lines
    after = float(lines[-1].split()[-1])
    assert after < 2 + 10, lines       # cancelled after 2 s; terminated within its grace
    assert os.listdir(tmp_path / "out") == []


LOAD = r"""
processing.runAndLoadResults("hillshade_rt:shadow", {"INPUT": dem, "OUTPUT": out})
processing.runAndLoadResults("hillshade_rt:shadow", {"INPUT": dem, "SOFT": True,
                                                     "OUTPUT": out[:-4] + "_soft.tif"})
for layer in sorted(QgsProject.instance().mapLayers().values(), key=lambda l: l.source()):
    r = layer.renderer()
    print(os.path.basename(layer.source()), r.type(),
          [(c.value, c.color.alpha()) for c in r.classes()] if r.type() == "paletted" else "")
"""


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_shadow_mask_loads_styled(qgis, tmp_path):
    """A shadow mask that QGIS loads on completion gets the plugin's style: shadow (1)
    translucent, lit (0) transparent; a soft shadow stays QGIS's grey."""
    lines = qgis_python(qgis, tmp_path, LOAD, DEM)
    assert lines == ["out.tif paletted [(1.0, 120), (0.0, 0)]",
                     "out_soft.tif singlebandgray "], lines


# --- the other commands in QGIS: each output equals the command's own

def program(*args) -> None:
    done = subprocess.run([PROGRAM, *map(str, args)], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr


def qgis_run(qgis, algorithm, **params) -> dict:
    """``qgis_process run hillshade_rt:ALGORITHM --json -- NAME=VALUE...``: its report."""
    done = qgis("run", f"hillshade_rt:{algorithm}", "--json", "--",
                *[f"{k}={v}" for k, v in params.items()])
    assert done.returncode == 0, done.stdout + done.stderr
    return json.loads(done.stdout)


def read_bands(path):
    import rasterio
    with rasterio.open(path) as ds:
        return ds.read(), [ds.descriptions, str(ds.nodata), ds.crs, ds.transform]


def assert_same_raster(got, want):
    (a, meta_a), (b, meta_b) = read_bands(got), read_bands(want)
    assert a.dtype == b.dtype and a.shape == b.shape
    np.testing.assert_array_equal(a, b)
    assert meta_a == meta_b


POINTS = [("a", 429400.0, 5150600.0), ("b", 429500.5, 5150700.25), ("c", 429300.0, 5150800.0)]


def points_files(folder):
    """The same points as a GeoJSON layer in the DEM's CRS (QGIS's input) and as the
    program's --points CSV."""
    geojson, csv = folder / "points.geojson", folder / "points.csv"
    geojson.write_text(json.dumps({
        "type": "FeatureCollection",
        "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::26915"}},
        "features": [{"type": "Feature", "properties": {"name": n},
                      "geometry": {"type": "Point", "coordinates": [x, y]}}
                     for n, x, y in POINTS]}))
    cmd.write_points_csv(str(csv), POINTS)
    return geojson, csv


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_shadow_polygons(qgis, tmp_path):
    """The optional VECTOR output: the program's --vector polygons, the same as its own run's;
    left out, no --vector."""
    import fiona
    out, vec = tmp_path / "m.tif", tmp_path / "m.gpkg"
    report = qgis_run(qgis, "shadow", INPUT=qgis.dem, AZIMUTH=203.7, ELEVATION=12, OUTPUT=out,
                      VECTOR=vec)
    assert report["results"] == {"OUTPUT": str(out), "VECTOR": str(vec)}
    program("shadow", qgis.dem, tmp_path / "ref.tif", "--azimuth", 203.7, "--elevation", 12,
            "--vector", tmp_path / "ref.gpkg")
    with fiona.open(vec) as a, fiona.open(tmp_path / "ref.gpkg") as b:
        assert len(a) == len(b) > 0 and a.crs == b.crs
    report = qgis_run(qgis, "shadow", INPUT=qgis.dem, OUTPUT=tmp_path / "n.tif")
    assert "--vector" not in report["log"]["info"][0] and "VECTOR" not in report["results"]


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_horizon_directions_and_distance(qgis, tmp_path):
    out, dist = tmp_path / "hz.tif", tmp_path / "dist.tif"
    report = qgis_run(qgis, "horizon", INPUT=qgis.dem, MODE=1, DIRECTIONS=8,
                      MAX_DISTANCE=150, OUTPUT=out, DISTANCE=dist)
    assert report["results"] == {"OUTPUT": str(out), "DISTANCE": str(dist)}
    program("horizon", qgis.dem, tmp_path / "ref.tif", "--directions", 8, "--max-distance",
            150, "--distance", tmp_path / "ref_dist.tif")
    assert_same_raster(out, tmp_path / "ref.tif")
    assert_same_raster(dist, tmp_path / "ref_dist.tif")
    assert read_bands(out)[0].shape[0] == 8
    # one azimuth, no distance raster
    one = tmp_path / "one.tif"
    report = qgis_run(qgis, "horizon", INPUT=qgis.dem, AZIMUTH=135, METHOD="hull",
                      OUTPUT=one)
    assert "--distance" not in report["log"]["info"][0]
    program("horizon", qgis.dem, tmp_path / "ref1.tif", "--azimuth", 135, "--method", "hull")
    assert_same_raster(one, tmp_path / "ref1.tif")


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_profile_and_query_tables(qgis, tmp_path):
    """Points of a layer -> the tables of ``profile`` and ``query``, row for row the
    program's own with the same points."""
    layer, csv = points_files(tmp_path)
    out = tmp_path / "profile.csv"
    qgis_run(qgis, "profile", INPUT=qgis.dem, POINTS=layer, ID_FIELD="name", STEP=30,
             HEIGHT_ABOVE_GROUND=1.5, OUTPUT=out)
    program("profile", qgis.dem, "--points", csv, "--step", 30, "--height-above-ground", 1.5,
            "-o", tmp_path / "ref.csv")
    rows = out.read_text().splitlines()
    assert rows == (tmp_path / "ref.csv").read_text().splitlines()
    assert sum(1 for r in rows if r[:2] in ("a,", "b,", "c,")) == 3 * 12

    out = tmp_path / "query.geojson"
    qgis_run(qgis, "query", INPUT=qgis.dem, POINTS=layer, ID_FIELD="name", SUN=2,
             DATETIME="2026-06-21T07:00:00", END_DATETIME="2026-06-21T19:00:00", STEP=120,
             TIMEZONE="America/Chicago", OUTPUT=out)
    program("query", qgis.dem, "--points", csv, "--start", "2026-06-21T07:00:00", "--end",
            "2026-06-21T19:00:00", "--step", "120min", "--tz", "America/Chicago", "-o",
            tmp_path / "ref.geojson")
    got = json.loads(out.read_text())
    assert got == json.loads((tmp_path / "ref.geojson").read_text())
    assert [f["properties"]["id"] for f in got["features"]] == ["a", "b", "c"]
    assert len(got["features"][0]["properties"]["lit"]) == 7


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_irradiance_equals_program(qgis, tmp_path):
    out = tmp_path / "irr.tif"
    qgis_run(qgis, "irradiance", INPUT=qgis.dem, DATE="2026-06-21", STEP=120,
             TIMEZONE="America/Chicago", ALBEDO=0.3, SKYVIEW_DIRECTIONS=8, MEAN=True,
             OUTPUT=out)
    program("irradiance", qgis.dem, tmp_path / "ref.tif", "--date", "2026-06-21", "--step",
            "120min", "--tz", "America/Chicago", "--albedo", 0.3, "--skyview-directions", 8,
            "--mean")
    assert_same_raster(out, tmp_path / "ref.tif")


def albedo_raster(path, dem, low=0.1, high=0.6):
    """An albedo raster (or any sky input's) covering ``dem`` on a coarser grid of its own (20 m
    cells, a margin around it), float64, varying from ``low`` to ``high`` across it: the
    program resamples it."""
    import rasterio
    from affine import Affine
    with rasterio.open(dem) as src:
        b, crs = src.bounds, src.crs
    n = int((b.right - b.left + 40) // 20) + 1
    y, x = np.mgrid[0:n, 0:n]
    with rasterio.open(path, "w", driver="GTiff", width=n, height=n, count=1, dtype="float64",
                       crs=crs, transform=Affine(20, 0, b.left - 20, 0, -20, b.top + 20)) as d:
        d.write(low + (high - low) * (x + 2 * y) / (3 * (n - 1)), 1)
    return path


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_irradiance_monthly_albedo_raster_equals_program(qgis, tmp_path):
    """MONTHLY, DAILY_MEAN, an albedo raster layer (over the number) and the Linke turbidity
    by month: the program's --monthly --daily-mean --albedo FILE --linke-turbidity T1,...,T12,
    band for band; a month band per month of the period."""
    albedo = albedo_raster(tmp_path / "albedo.tif", qgis.dem)
    out = tmp_path / "irr.tif"
    report = qgis_run(qgis, "irradiance", INPUT=qgis.dem, DATE="2026-01-30",
                      END_DATE="2026-03-02", STEP=180, TIMEZONE="America/Chicago",
                      ALBEDO=0.9, ALBEDO_RASTER=albedo, LINKE_MONTHLY=LINKE_MONTHLY,
                      SKYVIEW_DIRECTIONS=8, MONTHLY=True, DAILY_MEAN=True, OUTPUT=out)
    assert f"--albedo {albedo}" in report["log"]["info"][0]
    program("irradiance", qgis.dem, tmp_path / "ref.tif", "--date", "2026-01-30",
            "--end-date", "2026-03-02", "--step", "180min", "--tz", "America/Chicago",
            "--albedo", albedo, "--linke-turbidity", LINKE_MONTHLY, "--skyview-directions", 8,
            "--monthly", "--daily-mean")
    assert_same_raster(out, tmp_path / "ref.tif")
    import rasterio
    with rasterio.open(out) as ds:
        assert ds.descriptions == ("beam", "diffuse", "reflected", "global", "2026-01",
                                   "2026-02", "2026-03")
        assert ds.tags()["ALBEDO"].startswith("raster albedo.tif")
        assert ds.tags()["UNITS"].startswith("Wh/m2 per day")
        glob = ds.read(4)
        assert np.isfinite(glob).all() and glob.min() > 0


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_irradiance_linke_and_index_rasters_equal_program(qgis, tmp_path):
    """LINKE_RASTER over the Linke numbers, BEAM_INDEX_RASTER over the beam index's number,
    DIFFUSE_INDEX_RASTER: the program's --linke-turbidity FILE --beam-index FILE
    --diffuse-index FILE, pixel for pixel."""
    linke = albedo_raster(tmp_path / "linke.tif", qgis.dem, 2.2, 5.3)
    kb = albedo_raster(tmp_path / "kb.tif", qgis.dem, 0.35, 0.9)
    kd = albedo_raster(tmp_path / "kd.tif", qgis.dem, 0.95, 0.45)
    out = tmp_path / "irr.tif"
    report = qgis_run(qgis, "irradiance", INPUT=qgis.dem, DATE="2026-05-14", STEP=120,
                      TIMEZONE="America/Chicago", LINKE_TURBIDITY=7.5,
                      LINKE_MONTHLY=LINKE_MONTHLY, LINKE_RASTER=linke, BEAM_INDEX=0.1,
                      BEAM_INDEX_RASTER=kb, DIFFUSE_INDEX_RASTER=kd, SKYVIEW_DIRECTIONS=8,
                      OUTPUT=out)
    command = report["log"]["info"][0]
    assert (f"--linke-turbidity {linke}" in command and f"--beam-index {kb}" in command
            and f"--diffuse-index {kd}" in command), command
    program("irradiance", qgis.dem, tmp_path / "ref.tif", "--date", "2026-05-14", "--step",
            "120min", "--tz", "America/Chicago", "--linke-turbidity", linke, "--beam-index",
            kb, "--diffuse-index", kd, "--skyview-directions", 8)
    assert_same_raster(out, tmp_path / "ref.tif")
    import rasterio
    with rasterio.open(out) as ds:
        tags = ds.tags()
        assert tags["LINKE_TURBIDITY"].startswith("raster linke.tif"), tags
        assert tags["BEAM_INDEX"].startswith("raster kb.tif"), tags
        assert tags["DIFFUSE_INDEX"].startswith("raster kd.tif"), tags
        assert np.isfinite(ds.read(4)).all()


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_irradiance_instants_equals_program(qgis, tmp_path):
    """TIMES: a time of day on DATE and a full date and time, each an instant of 5 bands (the
    program's repeated --time), with the albedo by month."""
    out = tmp_path / "now.tif"
    monthly_albedo = "0.05 0.1 0.15 0.2 0.25 0.3 0.35 0.4 0.45 0.5 0.55 0.6"
    report = qgis_run(qgis, "irradiance", INPUT=qgis.dem, DATE="2026-06-21",
                      TIMES="9:30, 2026-07-02T15:05", TIMEZONE="America/Chicago",
                      ALBEDO_MONTHLY=monthly_albedo, SKYVIEW_DIRECTIONS=8, OUTPUT=out)
    assert "--date" not in report["log"]["info"][0]
    program("irradiance", qgis.dem, tmp_path / "ref.tif", "--time", "2026-06-21T09:30",
            "--time", "2026-07-02T15:05", "--tz", "America/Chicago", "--albedo",
            monthly_albedo.replace(" ", ","), "--skyview-directions", 8)
    assert_same_raster(out, tmp_path / "ref.tif")
    bands, (descriptions, *_) = read_bands(out)
    assert bands.shape[0] == 10
    assert descriptions[4] == "incidout 2026-06-21T09:30-05:00"
    assert descriptions[8] == "glob_rad 2026-07-02T15:05-05:00"


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_sun_hours_monthly_and_horizon_range_equal_program(qgis, tmp_path):
    """Sun hours' MONTHLY (a band per month after the total) and the horizon's r.horizon
    range (MODE=2: START, END, STEP degrees; ANGLE_UNIT radians)."""
    out = tmp_path / "hours.tif"
    qgis_run(qgis, "sunhours", INPUT=qgis.dem, DATE="2026-01-31", END_DATE="2026-03-01",
             STEP=120, TIMEZONE="America/Chicago", MONTHLY=True, OUTPUT=out)
    program("sun-hours", qgis.dem, tmp_path / "ref_hours.tif", "--date", "2026-01-31",
            "--end-date", "2026-03-01", "--step", "120min", "--tz", "America/Chicago",
            "--monthly")
    assert_same_raster(out, tmp_path / "ref_hours.tif")
    bands, (descriptions, *_) = read_bands(out)
    assert descriptions[1:] == ("2026-01", "2026-02", "2026-03")
    valid = bands[0] >= 0
    np.testing.assert_allclose(bands[1:].sum(axis=0)[valid], bands[0][valid], atol=1e-3)

    out = tmp_path / "hz.tif"
    qgis_run(qgis, "horizon", INPUT=qgis.dem, MODE=2, START=92.5, END=272.5, STEP=22.5,
             ANGLE_UNIT="radians", MAX_DISTANCE=150, OUTPUT=out)
    program("horizon", qgis.dem, tmp_path / "ref_hz.tif", "--start", 92.5, "--end", 272.5,
            "--step", 22.5, "--angle-unit", "radians", "--max-distance", 150)
    assert_same_raster(out, tmp_path / "ref_hz.tif")
    bands, (descriptions, *_) = read_bands(out)
    assert bands.shape[0] == 8          # floor((272.5 - 92.5) / 22.5)
    assert descriptions[1] == "horizon angle toward azimuth 115"
    valid = bands[0] != -9999
    assert np.abs(bands[:, valid]).max() <= np.pi / 2


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_animate_equals_program(qgis, tmp_path):
    out = tmp_path / "day.gif"
    report = qgis_run(qgis, "animate", INPUT=qgis.dem, DATE="2026-06-21", STEP=180,
                      TIMEZONE="America/Chicago", SIZE=64, FPS=4, OUTPUT=out)
    assert report["results"]["OUTPUT"] == str(out)
    program("animate", qgis.dem, tmp_path / "ref.gif", "--date", "2026-06-21", "--step",
            "180min", "--tz", "America/Chicago", "--size", 64, "--fps", 4)
    assert out.read_bytes() == (tmp_path / "ref.gif").read_bytes()
    assert out.read_bytes()[:6] == b"GIF89a"


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_illumination_equals_program(qgis, tmp_path):
    """A subsolar series on the Earth over the DEM's afternoon."""
    series = tmp_path / "subsolar.csv"
    series.write_text("time,lat,lon\n" + "".join(
        f"2026-06-21T{h:02d}:00:00Z,23.44,{-(h - 12) * 15.0}\n" for h in range(13, 24)))
    out = tmp_path / "il.tif"
    qgis_run(qgis, "illumination", INPUT=qgis.dem, SUBSOLAR_FILE=series, SOFT=True,
             OUTPUT=out)
    program("illumination", qgis.dem, tmp_path / "ref.tif", "--subsolar-file", series,
            "--soft")
    assert_same_raster(out, tmp_path / "ref.tif")
    assert read_bands(out)[0].shape[0] == 4


PROGRESS = r"""
seen = []
feedback = QgsProcessingFeedback()
feedback.progressChanged.connect(seen.append)
processing.run("hillshade_rt:sunhours", {"INPUT": dem, "DATE": "2026-06-21", "STEP": 60,
                                         "OUTPUT": out}, feedback=feedback)
print("PROGRESS", " ".join(format(p, "g") for p in seen))
"""


@pytest.mark.slow
@pytest.mark.qgis
def test_qgis_progress_reaches_feedback(qgis, tmp_path):
    """The program's {"progress": F} lines become the feedback's percentages."""
    lines = qgis_python(qgis, tmp_path, PROGRESS, DEM)
    seen = [float(p) for p in lines[-1].split()[1:]]
    assert lines[-1].startswith("PROGRESS"), lines
    assert len(seen) >= 5 and seen == sorted(seen) and seen[-1] == 100.0, seen
    assert (tmp_path / "out" / "out.tif").exists()
