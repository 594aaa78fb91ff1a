"""hillshade_rt.shade: whole runs from Python, the command line's code and report."""

import datetime as _dt
import json
import os

import numpy as np
import pytest
from affine import Affine
from rasterio.crs import CRS

import hillshade_rt as hr
from hillshade_rt.testing import fractal_terrain, read_band, split_geotiff, write_geotiff

UTM = CRS.from_epsg(32611)


@pytest.fixture
def tiles(tmp_path):
    z = fractal_terrain(200, 240, 8, relief=250.0)
    tr = Affine(5, 0, 400000, 0, -5, 3800000)
    whole = write_geotiff(tmp_path / "whole.tif", z, tr, UTM)
    return whole, split_geotiff(tmp_path, z, tr, UTM, [(0, 100), (100, 200)],
                                [(0, 120), (120, 240)])


@pytest.mark.slow
def test_shade_in_memory_windows_and_dask_client(tmp_path, tiles):
    """One DEM in memory, the same as tiles in windows, and on a Dask client the caller owns:
    identical masks; the report comes back as a dict (and as the file asked for)."""
    from distributed import Client, LocalCluster
    whole, parts = tiles
    sun = dict(azimuth=203.7, elevation=9.0)
    a = hr.shade(whole, tmp_path / "a.tif", **sun)
    assert a["processing"]["mode"] == "in memory" and 0.05 < a["sun"]["shadow_fraction"] < 0.9
    b = hr.shade(parts, tmp_path / "b.tif", window_size=(64, 96), report=str(tmp_path / "b.json"),
                 **sun)
    assert b["processing"]["mode"] == "tiled" and b["processing"]["windows"] >= 8
    assert json.loads((tmp_path / "b.json").read_text())["processing"] == b["processing"]
    np.testing.assert_array_equal(read_band(tmp_path / "a.tif"), read_band(tmp_path / "b.tif"))
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        c = hr.shade(parts, tmp_path / "c.tif", window_size=96, client=client, **sun)
        assert c["processing"]["mode"] == "dask" and c["processing"]["workers"] == 2
        assert client.status == "running"          # the caller's client is left open
    np.testing.assert_array_equal(read_band(tmp_path / "a.tif"), read_band(tmp_path / "c.tif"))


def test_shade_products_times_and_tiles(tmp_path, tiles):
    whole, parts = tiles
    rep = hr.shade(parts, output_pattern=str(tmp_path / "{tile}_{index}.tif"), product="hillshade",
                   times=["2026-03-02T07:40-08:00", "2026-03-02T16:50-08:00"], max_memory="2GB")
    assert len(rep["times"]) == 2 and len(rep["times"][0]["outputs"]) == 4
    ref = hr.shade(whole, tmp_path / "ref.tif", product="hillshade",
                   times=["2026-03-02T07:40-08:00", "2026-03-02T16:50-08:00"])
    assert ref["product"]["kind"] == "hillshade"
    import rasterio
    with rasterio.open(tmp_path / "ref.tif") as r:
        np.testing.assert_array_equal(read_band(tmp_path / "tile_11_1.tif"),
                                      r.read(2)[100:, 120:])
    cls = hr.shade(whole, tmp_path / "cls.tif", product="classes", azimuth=163, elevation=12,
                   algorithm_options={"nextv": "quad"})
    assert set(np.unique(read_band(tmp_path / "cls.tif"))) <= {0, 1, 2}
    assert cls["algorithm_options"] == {"nextv": "quad"}


def test_shade_errors_are_one_line_hillshade_errors(tmp_path, tiles):
    whole, _ = tiles
    out = tmp_path / "o.tif"
    cases = [
        (dict(azimuth=90), "azimuth and elevation go together"),
        (dict(azimuth=90, elevation=10, max_memory="lots"), "max_memory"),
        (dict(azimuth=90, elevation=10, algorithm_options={"exact_steps": 4}), "applies to"),
        (dict(azimuth=90, elevation=10, algorithm_options={"speed": 4}), "unknown algorithm"),
        (dict(azimuth=90, elevation=10, product="contours"), "product must be one of"),
        (dict(azimuth=90, elevation=10, client="local:0", window_size=64), "N must be 1"),
        (dict(azimuth=90, elevation=10, product="classes", soft=True), "do not go together"),
        (dict(product="hillshade", scale=-2.0), "must be a positive number"),
        (dict(product="hillshade", scale=111120.0, pixel_size="1"), "pixel_size do not go"),
    ]
    for kw, msg in cases:
        with pytest.raises(hr.HillshadeError, match=msg) as e:
            hr.shade(whole, out, **kw)
        assert "\n" not in str(e.value)
    assert not out.exists()
    with pytest.raises(hr.HillshadeError, match="missing.tif: no such file"):
        hr.shade(str(tmp_path / "missing.tif"), out, azimuth=90, elevation=10)
    with pytest.raises(TypeError, match="colour"):
        hr.shade(whole, out, azimuth=90, elevation=10, colour="red")
    # nothing half-written beside the inputs
    assert sorted(os.listdir(tmp_path)) == ["tile_00.tif", "tile_01.tif", "tile_10.tif",
                                            "tile_11.tif", "whole.tif"]


@pytest.mark.slow
def test_cli_api_and_array_function_agree_at_default_settings(tmp_path):
    """Issue 19: the command line, ``shade`` and ``shadow_mask`` give the same mask at their
    default settings on a UTM DEM (Big Tujunga, 36 km across: Earth curvature is on by
    default, and changes cells at this sun, so the test would see a default that differs)."""
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    dem = os.path.join(os.path.dirname(__file__), "..", "examples",
                       "bigtujunga_srtm30m_utm11n_1197x643.tif")
    sun = ["--azimuth", "135", "--elevation", "15"]
    r = CliRunner().invoke(cli, ["shadow", dem, str(tmp_path / "cli.tif")] + sun)
    assert r.exit_code == 0, r.output
    hr.shade(dem, tmp_path / "api.tif", azimuth=135, elevation=15)
    d = hr.read_dem(dem)
    arr = hr.shadow_mask(d, 135, 15)
    flat = hr.shadow_mask(d, 135, 15, curvature=False)
    cli_mask = read_band(tmp_path / "cli.tif")
    np.testing.assert_array_equal(cli_mask, read_band(tmp_path / "api.tif"))
    np.testing.assert_array_equal(cli_mask, arr)
    assert (flat != arr).sum() > 0          # the default is not the flat model
    # an array needs its spacing (it once defaulted to 1 m); with the DEM's grid and body it is
    # the same mask
    with pytest.raises(hr.HillshadeError, match="spacing"):
        hr.shadow_mask(d.heights, 135, 15)
    from hillshade_rt.model.earth import dem_body
    np.testing.assert_array_equal(arr, hr.shadow_mask(d.heights, 135, 15, d.grid,
                                                      body=dem_body(d)))


def test_api_errors_name_keywords_not_command_line_options(tmp_path):
    from hillshade_rt import api
    from hillshade_rt.errors import UsageProblem
    dem = write_geotiff(tmp_path / "d.tif", fractal_terrain(40, 40, 3),
                        Affine(30, 0, 476000, 0, -30, 4400000), CRS.from_epsg(32613))
    out = tmp_path / "o.tif"
    out.write_bytes(b"old")
    with pytest.raises(hr.HillshadeError) as e:
        hr.shade(dem, out, azimuth=200, elevation=10)
    assert "use overwrite=True to replace it" in str(e.value) and "--" not in str(e.value)
    cases = [(dict(azimuth=200, elevation=10, window_size=(16, 16)), "window_size 16x16"),
             (dict(azimuth=200, elevation=10, algorithm="brute",
                   algorithm_options={"nextv": "quad"}),
              "algorithm_options['nextv'] applies to algorithm smap"),
             (dict(times=["2026-06-21T12:00Z"], lat=45), "lat and lon go together"),
             (dict(start="2026-06-21T12:00Z"), "start"),
             (dict(azimuth=200, elevation=10, report=str(dem), overwrite=True),
              "report is also an input")]
    for kw, words in cases:
        with pytest.raises(hr.HillshadeError) as e:
            hr.shade(dem, tmp_path / "n.tif", **kw)
        assert words in str(e.value) and "--" not in str(e.value), str(e.value)
    with pytest.raises(UsageProblem) as e:                 # the class is kept
        hr.shade(dem, dem, azimuth=200, elevation=10, overwrite=True)
    assert "output is also an input" in str(e.value)
    with pytest.raises(hr.HillshadeError) as e:
        api.irradiance(dem, tmp_path / "i.tif", date="2026-06-21", end_date="2026-06-01")
    assert "--" not in str(e.value) and "end_date" in str(e.value), str(e.value)
    assert api.in_keywords("use --earth-curvature or --no-earth-curvature, --co, --time") == \
        "use curvature=True or curvature=False, creation_options, times"
    assert not (tmp_path / "n.tif").exists()


def test_irradiance_takes_height_above_ground(tmp_path, monkeypatch):
    """The command's --height-above-ground is a keyword of api.irradiance, passed to the run."""
    from hillshade_rt import api
    from hillshade_rt.run import irradiance as run_irradiance

    seen = []
    monkeypatch.setattr(run_irradiance, "irradiance", lambda cfg: seen.append(cfg) or {})
    api.irradiance(tmp_path / "d.tif", tmp_path / "o.tif", date="2026-06-21",
                   height_above_ground=2)
    assert seen[0].height_above_ground == 2


# The command line's parameters (click's param.name) that are another keyword of the API, each
# with why; every other parameter of the command must be a keyword of the function of the
# same name (test_api_takes_every_option_of_its_command).
RENAMED = {
    "files": None,        # the positional DEM... [OUTPUT]: the function's dems/dem and output
    "date_": "date",      # click's name keeps the command's body off datetime.date
    "time": "times",      # one or many times: a list in Python, --time repeated on the line
    "report_path": "report",
    "scheduler": "client",      # a distributed.Client (or an address, "local:N")
    "quiet": "progress",        # --quiet is progress=False
    "classes": "product",       # --classes is product="classes"
}
# the shadow command's algorithm flags (--nextv, --no-pyramid, ...): algorithm_options entries
ALGORITHM_FLAGS = {"no_pyramid", "nextv", "better_nextv", "horizon_method", "sample_spacing",
                   "exact_steps"}
# each API function and the commands it stands for
FRONT_DOORS = {"shade": ("shadow", "hillshade"), "irradiance": ("irradiance",),
               "animate": ("animate",), "sun_hours": ("sun-hours",), "horizon": ("horizon",)}


def _keywords(function) -> set:
    """The keywords ``function`` accepts: its named parameters, and ``api.FORWARDED`` (the
    documented set it passes on) when it takes ``**more``."""
    import inspect

    from hillshade_rt import api
    params = inspect.signature(function).parameters.values()
    named = {p.name for p in params if p.kind is not p.VAR_KEYWORD}
    more = any(p.kind is p.VAR_KEYWORD for p in params)
    return named | (set(api.FORWARDED) if more else set())


def test_api_takes_every_option_of_its_command():
    """Every option of ``shadow``/``hillshade``, ``irradiance``, ``animate``, ``sun-hours`` and
    ``horizon`` is a keyword of the function of FRONT_DOORS (or one of RENAMED's), read from
    the click commands themselves: an option added to a command without its keyword fails
    here."""
    from hillshade_rt import api
    from hillshade_rt.cli import cli
    from hillshade_rt.algorithms import OPTIONS
    assert ALGORITHM_FLAGS == {opt.param for _, opt in OPTIONS.values()}
    missing = {}
    for name, commands in FRONT_DOORS.items():
        function = getattr(api, name)
        assert getattr(hr, name) is function               # exported at the top
        accepted = _keywords(function)
        for command in commands:
            for param in cli.commands[command].params:
                # (horizon's own --sample-spacing is a keyword of its own)
                keyword = ("algorithm_options" if param.name in ALGORITHM_FLAGS
                           and command in ("shadow", "hillshade")
                           else RENAMED.get(param.name, param.name))
                if keyword is not None and keyword not in accepted:
                    missing.setdefault(name, []).append(f"{command} {param.opts[0]}")
    assert not missing, missing
    # RENAMED names only real parameters (a stale entry would hide nothing but mislead)
    every = {p.name for c in ("shadow", "hillshade", "irradiance", "animate", "sun-hours")
             for p in cli.commands[c].params}
    assert set(RENAMED) <= every and ALGORITHM_FLAGS <= every


def test_point_light_subsolar_and_irradiance_each_as_the_command_line(tmp_path):
    """The keywords the API gained run what their options run: a point light's shadow and
    lightmap, every cell's own sun, irradiance of each DEM: files equal to the command's."""
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    z = fractal_terrain(48, 56, 5, relief=300.0)
    dem = write_geotiff(tmp_path / "d.tif", z, Affine(30, 0, 476000, 0, -30, 4400000),
                        CRS.from_epsg(32613))
    top = float(z[23, 33]) + 20.0          # 20 m above the cell under the light
    light = f"477000,4399300,{top}"
    runs = [(["shadow", "--light-position", light], dict(light_position=light)),
            (["hillshade", "--light-position", light, "--falloff", "inverse-square",
              "--bits", "16"],
             dict(product="hillshade", light_position=(477000, 4399300, top),
                  falloff="inverse-square", bits=16)),
            (["shadow", "--subsolar", "5.5,-17.3", "--body", "moon"],
             dict(subsolar=(5.5, -17.3), body="moon"))]
    for i, (args, kw) in enumerate(runs):
        cli_out, api_out = tmp_path / f"cli{i}.tif", tmp_path / f"api{i}.tif"
        r = CliRunner().invoke(cli, [args[0], dem, str(cli_out), "-q"] + args[1:])
        assert r.exit_code == 0, r.output
        rep = hr.shade(dem, api_out, **kw)
        a, b = read_band(cli_out), read_band(api_out)
        np.testing.assert_array_equal(a, b)
        assert len(np.unique(a)) > 1 and isinstance(rep, dict), args
    with pytest.raises(hr.HillshadeError, match="a point light does not take soft=True"):
        hr.shade(dem, tmp_path / "x.tif", light_position=light, soft=True)
    with pytest.raises(hr.HillshadeError, match="falloff and bits go with a point light"):
        hr.shade(dem, tmp_path / "x.tif", product="hillshade", falloff="inverse-square")
    # irradiance --each: each DEM into the pattern's {stem}, as the command writes it
    other = write_geotiff(tmp_path / "e.tif", z[::-1].copy(),
                          Affine(30, 0, 476000, 0, -30, 4400000), CRS.from_epsg(32613))
    period = dict(start="2026-06-21T10:00Z", end="2026-06-21T20:00Z", step="2h")
    rep = hr.irradiance([dem, other], each=True, progress=False,
                        output_pattern=str(tmp_path / "api_{stem}.tif"), **period)
    r = CliRunner().invoke(cli, ["irradiance", dem, other, "--each", "-q", "--output-pattern",
                                 str(tmp_path / "cli_{stem}.tif"), "--start", period["start"],
                                 "--end", period["end"], "--step", "2h"])
    assert r.exit_code == 0, r.output
    for stem in ("d", "e"):
        np.testing.assert_array_equal(read_band(tmp_path / f"api_{stem}.tif"),
                                      read_band(tmp_path / f"cli_{stem}.tif"))
    assert json.dumps(rep) and not (tmp_path / "x.tif").exists()
    with pytest.raises(hr.HillshadeError, match="output_pattern goes with each"):
        hr.irradiance(dem, tmp_path / "x.tif", output_pattern="o.tif", **period)


def test_progress_json_lines_and_quiet(tmp_path, capsys):
    """progress="json" is --progress json: only {"progress": F} lines on stderr, ending at 1.0;
    progress=False is --quiet: nothing."""
    dem = write_geotiff(tmp_path / "d.tif", fractal_terrain(40, 40, 3),
                        Affine(30, 0, 476000, 0, -30, 4400000), CRS.from_epsg(32613))
    times = ["2026-06-21T15:00Z", "2026-06-21T18:30Z"]
    hr.shade(dem, tmp_path / "a.tif", times=times, progress="json")
    lines = capsys.readouterr().err.splitlines()
    assert lines and [json.loads(x)["progress"] for x in lines][-1] == 1.0
    hr.shade(dem, tmp_path / "b.tif", times=times, progress=False)
    assert capsys.readouterr().err == ""
    with pytest.raises(hr.HillshadeError, match="progress must be"):
        hr.shade(dem, tmp_path / "c.tif", times=times, progress="dots")


def test_sun_hours_as_the_command_line_in_memory_and_in_windows(tmp_path):
    """``sun_hours`` writes the command's file, in memory and in windows (the same bits), and
    says what it needs."""
    from click.testing import CliRunner

    from hillshade_rt.cli import cli
    z = fractal_terrain(90, 110, 7, relief=400.0)
    dem = write_geotiff(tmp_path / "d.tif", z, Affine(30, 0, 476000, 0, -30, 4400000),
                        CRS.from_epsg(32613))
    r = CliRunner().invoke(cli, ["sun-hours", dem, str(tmp_path / "cli.tif"), "-q", "--date",
                                 "2026-12-21", "--step", "1h"])
    assert r.exit_code == 0, r.output
    ref = read_band(tmp_path / "cli.tif")
    rep = hr.sun_hours(dem, tmp_path / "api.tif", date="2026-12-21", step="1h")
    np.testing.assert_array_equal(read_band(tmp_path / "api.tif"), ref)
    hr.sun_hours(dem, tmp_path / "win.tif", date=_dt.date(2026, 12, 21), step="1h",
                 window_size="64x64")
    np.testing.assert_array_equal(read_band(tmp_path / "win.tif"), ref)
    assert len(np.unique(ref)) > 3 and isinstance(rep, dict)
    with pytest.raises(hr.HillshadeError, match="needs date"):
        hr.sun_hours(dem, tmp_path / "x.tif")
    with pytest.raises(TypeError, match="azimuth"):
        hr.sun_hours(dem, tmp_path / "x.tif", date="2026-12-21", azimuth=3)
    assert not (tmp_path / "x.tif").exists()


def test_shade_of_times_into_nc_is_a_time_cube(tmp_path):
    xr = pytest.importorskip("xarray")
    dem = write_geotiff(tmp_path / "d.tif", fractal_terrain(60, 70, 4, relief=300.0),
                        Affine(10, 0, 400000, 0, -10, 3800000), UTM)
    times = [_dt.datetime(2026, 6, 21, 15, 30, tzinfo=_dt.timezone.utc),
             _dt.datetime(2026, 6, 21, 22, 10, tzinfo=_dt.timezone.utc)]
    rep = hr.shade(dem, str(tmp_path / "t.tif"), times=times, progress=False)
    hr.shade(dem, str(tmp_path / "t.nc"), times=times, progress=False)
    with xr.open_dataset(tmp_path / "t.nc", mask_and_scale=False) as ds:
        np.testing.assert_array_equal(ds["time"].values,
                                      np.array(["2026-06-21T15:30", "2026-06-21T22:10"],
                                               "datetime64[ns]"))
        np.testing.assert_array_equal(ds["shadow"].values[1], read_band(tmp_path / "t.tif", 2))
        assert ds["azimuth"].values.tolist() == [s["azimuth"] for s in rep["times"]]
        assert "Python API" in ds.attrs["history"]


def test_shade_writes_shadow_polygons_with_or_without_output(tmp_path):
    """vector= is --vector: the polygons of the output's shadow cells, output optional; its
    errors name the keywords."""
    import fiona
    dem = write_geotiff(tmp_path / "d.tif", fractal_terrain(60, 70, 9, relief=300.0),
                        Affine(30, 0, 476000, 0, -30, 4400000), CRS.from_epsg(32613))
    both = hr.shade(dem, tmp_path / "m.tif", azimuth=290, elevation=10,
                    vector=tmp_path / "m.gpkg")
    only = hr.shade(dem, azimuth=290, elevation=10, vector=str(tmp_path / "o.fgb"))
    cells = (read_band(tmp_path / "m.tif") == 1).sum()
    for rep, name in ((both, "m.gpkg"), (only, "o.fgb")):
        assert rep["vector"]["area_m2"] == pytest.approx(cells * 900.0, rel=1e-9)
        with fiona.open(tmp_path / name) as src:
            assert len(src) == rep["vector"]["polygons"] > 0
    assert only["output"] is None and sorted(os.listdir(tmp_path)) == [
        "d.tif", "m.gpkg", "m.tif", "o.fgb"]
    with pytest.raises(hr.HillshadeError) as e:
        hr.shade(dem, azimuth=290, elevation=10, vector=tmp_path / "o.fgb",
                 vector_connectivity=5)
    assert "vector_connectivity must be 4 or 8" in str(e.value) and "--" not in str(e.value)
    with pytest.raises(hr.HillshadeError, match="give output or output_pattern"):
        hr.shade(dem, azimuth=290, elevation=10)
