"""cli/irradiance.py, ``hillshade-rt irradiance``: every option reaches
``run.config.IrradianceConfig``; one DEM goes to ``run.irradiance_instant.irradiance_or_instants``
(a period's sums or instants), several (--each) to ``run.batch.irradiance_each``. (The run:
tests/run/test_irradiance*.py.)"""

from hillshade_rt.cli import cli
from hillshade_rt.cli.errors import say
from hillshade_rt.run.config import IrradianceConfig, ReadOptions, RunOptions

RUN = ("hillshade_rt.run.irradiance_instant", "irradiance_or_instants")


def test_every_option_of_a_period_reaches_the_config(calls, runner):
    runs = calls(*RUN)
    r = runner.invoke(cli, [
        "irradiance", "dem.tif", "out.tif", "--date", "2026-03-01", "--end-date", "2026-03-31",
        "--step", "20min", "--clear-sky", "haurwitz", "--linke-turbidity", "3.5", "--albedo",
        "0.3", "--ghi", "g.csv", "--daily-mean", "--monthly", "--perez", "--skyview-directions",
        "16", "--sky-view", "v.tif", "--sky-view-out", "w.tif", "--tz", "UTC", "--lat", "45",
        "--lon", "7", "--pressure", "95000", "--temperature", "10", "--no-refraction",
        "--sun-tolerance", "0.2", "--algorithm", "smap", "--earth-curvature",
        "--refraction-coefficient", "0.1", "--soft", "--height-above-ground", "3", "--preview",
        "p.png", "--backend", "cpu", "--threads", "2", "--report", "r.json", "--max-memory",
        "1GB", "--window-size", "200", "--overwrite", "-q", "-f", "GTiff", "--co", "TILED=YES",
        "-b", "2"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert isinstance(cfg, IrradianceConfig)
    assert (cfg.dem, cfg.output, cfg.date, cfg.end_date, cfg.start, cfg.end, cfg.step) == (
        "dem.tif", "out.tif", "2026-03-01", "2026-03-31", None, None, "20min")
    assert (cfg.clear_sky, cfg.linke_turbidity, cfg.albedo, cfg.ghi) == (
        "haurwitz", "3.5", "0.3", "g.csv")
    assert (cfg.mean, cfg.daily_mean, cfg.monthly, cfg.perez, cfg.soft) == (
        False, True, True, True, True)
    assert (cfg.skyview_directions, cfg.sky_view, cfg.sky_view_out) == (16, "v.tif", "w.tif")
    assert cfg.place == {"tz": "UTC", "lat": 45.0, "lon": 7.0, "pressure": 95000.0,
                         "temperature": 10.0, "no_refraction": True, "sun_tolerance": 0.2}
    assert (cfg.algorithm, cfg.curvature, cfg.refraction_k, cfg.height_above_ground) == (
        "smap", True, 0.1, 3.0)
    assert (cfg.max_memory, cfg.window_size, cfg.scheduler) == ("1GB", "200", None)
    assert (cfg.times, cfg.instant) == ((), False)
    assert cfg.read == ReadOptions(band=2)
    assert cfg.run == RunOptions(backend="cpu", threads=2, report_path="r.json", overwrite=True,
                                 quiet=True, fmt="GTiff", preview="p.png", say=say,
                                 creation_options={"TILED": "YES"})


def test_instants_and_defaults(calls, runner):
    """--time (repeated) and --instant reach the config as the times given and the flag; what
    is left unset keeps the documented defaults."""
    runs = calls(*RUN)
    r = runner.invoke(cli, ["irradiance", "dem.tif", "out.tif", "--start", "2026-03-01T06:00Z",
                            "--end", "2026-03-01T18:00Z", "--instant", "--mean", "--time",
                            "2026-03-01T12:00Z", "--time", "2026-03-01T13:00Z"])
    assert r.exit_code == 0, r.output
    [(cfg,)] = runs
    assert cfg.times == ("2026-03-01T12:00Z", "2026-03-01T13:00Z") and cfg.instant is True
    assert (cfg.start, cfg.end, cfg.mean, cfg.date) == (
        "2026-03-01T06:00Z", "2026-03-01T18:00Z", True, None)
    assert (cfg.step, cfg.clear_sky, cfg.albedo, cfg.skyview_directions, cfg.perez) == (
        "15min", None, "0.2", 32, False)
    assert cfg.read == ReadOptions() and cfg.run == RunOptions(say=say)


def test_each_goes_to_the_batch(calls, runner):
    runs = calls(*RUN)
    each = calls("hillshade_rt.run.batch", "irradiance_each")
    r = runner.invoke(cli, ["irradiance", "a.tif", "b.tif", "--each", "--output-pattern",
                            "{stem}_irr.tif", "--date", "2026-06-21"])
    assert r.exit_code == 0, r.output
    assert runs == []
    [(cfg, dems, pattern)] = each
    assert dems == ["a.tif", "b.tif"] and pattern == "{stem}_irr.tif"
    assert cfg.date == "2026-06-21"
