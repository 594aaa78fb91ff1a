"""run/config.py: the runs' configurations and the checks of the options' combinations (usage
errors, exit status 2): run options, the shade and sun-hours checks and the Lighting they make,
the height above the ground, horizon azimuths, paths, window sizes, --scale, --threads."""

import types

import numba
import pytest
from affine import Affine

from hillshade_rt.errors import HillshadeError, UsageProblem
from hillshade_rt.run import config


def test_run_options_parse_creation_options_and_the_worker_timeout():
    ro = config.RunOptions(creation_options=["compress=zstd"], worker_timeout="12.5")
    assert ro.creation_options == {"COMPRESS": "zstd"} and ro.worker_timeout == 12.5
    assert config.RunOptions().worker_timeout == config.DEFAULT_WORKER_TIMEOUT
    for bad in (0, -1, "soon", float("inf"), None):
        with pytest.raises(UsageProblem, match="--worker-timeout must be a positive number"):
            config.RunOptions(worker_timeout=bad)
    with pytest.raises(UsageProblem, match="expected NAME=VALUE"):
        config.RunOptions(creation_options=["COMPRESS"])


def test_shade_check_and_its_lighting():
    c = config.ShadeConfig(files=["a.tif", "b.tif"], kind="hillshade", algorithm="smap",
                           options={"nextv": "quad"}, curvature=False, soft=True, ambient=0.3)
    c.check()
    lt = c.lighting("cpu")
    assert (lt.algorithm, dict(lt.options), lt.backend, lt.curvature, lt.soft, lt.ambient) == (
        "smap", {"nextv": "quad"}, "cpu", False, True, 0.3)
    with pytest.raises(HillshadeError, match="product must be one of shadow, classes, hillshade"):
        config.ShadeConfig(files=["a"], kind="relief").check()
    with pytest.raises(UsageProblem, match="--classes and --soft do not go together"):
        config.ShadeConfig(files=["a"], kind="classes", soft=True).check()
    with pytest.raises(UsageProblem, match="--scale must be a positive number"):
        config.ShadeConfig(files=["a"], scale=0.0).check()
    ro = config.ReadOptions(pixel_size=(1.0, 1.0))
    with pytest.raises(UsageProblem, match="--scale and --pixel-size do not go together"):
        config.ShadeConfig(files=["a"], scale=2.0, read=ro).check()


def test_a_height_above_the_ground_takes_the_algorithm_that_marches_it():
    c = config.ShadeConfig(files=["a"], height_above_ground=3.0)
    c.check()
    assert c.algorithm == "brute" and c.lighting("cpu").lift == 3.0
    with pytest.raises(UsageProblem, match="--algorithm smap cannot start the rays"):
        config.ShadeConfig(files=["a"], algorithm="smap", height_above_ground=3.0).check()
    assert config.check_lift(0.0, "smap", False) == "smap"
    for bad, why in [("x", "must be a number of metres"), (-1.0, ">= 0"),
                     (float("nan"), ">= 0")]:
        with pytest.raises(UsageProblem, match=why):
            config.check_lift(bad, "auto", False)


def test_sun_hours_self_shadow_follows_the_height():
    on_ground = config.SunHoursConfig(dem="d", output="o", date="2026-06-21", self_shadow=None)
    on_ground.check()
    above = config.SunHoursConfig(dem="d", output="o", date="2026-06-21", self_shadow=None,
                                  height_above_ground=2.0)
    above.check()
    assert on_ground.self_shadow is True and above.self_shadow is False
    assert above.algorithm == "brute" and above.lighting("gpu").backend == "gpu"
    given = config.SunHoursConfig(dem="d", output="o", date="2026-06-21", self_shadow=True,
                                  height_above_ground=2.0)
    given.check()
    assert given.self_shadow is True and given.lighting("cpu").self_shadow


def test_horizon_azimuths():
    assert config.HorizonConfig(dem="d", output="o", azimuth=-156.3).azimuths() == [pytest.approx(203.7)]
    assert config.HorizonConfig(dem="d", output="o", directions=8).azimuths() == [
        0.0, 45.0, 90.0, 135.0, 180.0, 225.0, 270.0, 315.0]
    for kw in ({}, {"azimuth": 10.0, "directions": 8}, {"directions": 8, "step": 10.0},
               {"azimuth": 10.0, "step": 10.0}):
        with pytest.raises(UsageProblem, match="give --azimuth A .*, --directions N or "
                                               "--start/--end/--step, one of them"):
            config.HorizonConfig(dem="d", output="o", **kw).azimuths()
    with pytest.raises(UsageProblem, match="--directions must be between 8 and 360"):
        config.HorizonConfig(dem="d", output="o", directions=4).azimuths()


def test_horizon_start_end_step_as_r_horizon_counts_them():
    """r.horizon's start/end/step, clockwise from north: floor((end - start) / step)
    directions; start 0, end 360 and a step that divides 360: --directions' azimuths, bit for
    bit; a remainder gives no direction; a range may wrap past north."""
    def az(**kw):
        return config.HorizonConfig(dem="d", output="o", **kw).azimuths()
    for n in (8, 11, 13, 360):
        assert az(step=360.0 / n) == az(directions=n)
        assert az(start=0.0, end=360.0, step=360.0 / n) == az(directions=n)
    assert az(step=40.7, start=163.0) == [pytest.approx((163.0 + 40.7 * k) % 360.0)
                                          for k in range(8)]          # 360 / 40.7 = 8.8
    assert az(start=0.0, end=100.0, step=30.0) == [0.0, 30.0, 60.0]   # 90: the remainder
    assert az(start=290.0, end=430.0, step=35.0) == [290.0, 325.0, 0.0, 35.0]
    assert az(start=45.0, end=46.0, step=0.25) == [45.0, 45.25, 45.5, 45.75]
    cases = [(dict(start=10.0), "--start and --end go with --step"),
             (dict(step=0.0), "--step must be a positive"),
             (dict(step=-5.0), "--step must be a positive"),
             (dict(step=10.0, start=360.0), "--start must be in [0, 360)"),
             (dict(step=10.0, start=-1.0), "--start must be in [0, 360)"),
             (dict(step=10.0, start=20.0, end=20.0), "--end must be after --start"),
             (dict(step=10.0, start=20.0, end=381.0), "--end must be after --start"),
             (dict(step=50.0, start=20.0, end=60.0), "larger than --end - --start"),
             (dict(step=0.01), "more than 3600"),
             (dict(step=10.0, angle_unit="grads"), "--angle-unit must be one of")]
    for kw, words in cases:
        with pytest.raises(UsageProblem) as e:
            az(**kw)
        assert words in str(e.value), (kw, str(e.value))


def test_inputs_and_output(tmp_path):
    a, b = tmp_path / "a.tif", tmp_path / "b.tif"
    a.write_bytes(b"")
    b.write_bytes(b"")
    assert config.inputs_and_output([str(a), "out.tif"], None, None) == ([str(a)], "out.tif")
    assert config.inputs_and_output([str(a), str(b)], "o.tif", None) == ([str(a), str(b)],
                                                                         "o.tif")
    assert config.inputs_and_output([str(a), "/vsizip/x.zip/d.tif"], None, "{stem}_s.tif") == (
        [str(a), "/vsizip/x.zip/d.tif"], None)
    with pytest.raises(UsageProblem, match="not both"):
        config.inputs_and_output([str(a)], "o.tif", "{stem}.tif")
    with pytest.raises(UsageProblem, match="out.tif does not exist: give OUTPUT or "
                                           "--output-pattern, not both"):
        config.inputs_and_output([str(a), "out.tif"], None, "{stem}.tif")
    with pytest.raises(UsageProblem, match="give OUTPUT or --output-pattern"):
        config.inputs_and_output([str(a)], None, None)


def test_parse_window_size():
    assert config.parse_window_size(None) is None
    assert config.parse_window_size("2048") == (2048, 2048)
    assert config.parse_window_size(" 128 x 96 ") == (128, 96)
    assert config.parse_window_size(256) == (256, 256)
    assert config.parse_window_size((64, 80)) == (64, 80)
    with pytest.raises(UsageProblem, match="must be ROWS or ROWSxCOLS"):
        config.parse_window_size("big")
    with pytest.raises(UsageProblem, match="at least 64 cells on each side"):
        config.parse_window_size("128x32")


def test_apply_scale():
    d = types.SimpleNamespace(transform=Affine(-0.5, 0, 0, 0, 2.0, 0), shape=(3, 4), grid=None)
    config.apply_scale(d, 10.0)
    assert (d.grid.rows, d.grid.cols, d.grid.col_sign, d.grid.row_sign) == (3, 4, -1, 1)
    assert list(d.grid.dx) == [5.0] * 3 and list(d.grid.dy) == [20.0] * 3
    with pytest.raises(UsageProblem, match="--scale needs a georeferenced DEM"):
        config.apply_scale(types.SimpleNamespace(transform=None, shape=(3, 4)), 10.0)


def test_set_threads():
    before = numba.get_num_threads()
    try:
        assert config.set_threads(config.RunOptions(threads=1)) == 1
        assert config.set_threads(config.RunOptions(threads=10_000)) == \
            numba.config.NUMBA_NUM_THREADS
        assert config.set_threads(config.RunOptions()) == numba.config.NUMBA_NUM_THREADS
    finally:
        numba.set_num_threads(before)


def test_every_config_is_keyword_only_and_here():
    """The configs of every command live in run/config.py and take keywords only (a
    positional call cannot bind a value to the wrong field)."""
    import dataclasses
    names = [n for n in dir(config) if n.endswith("Config") or n in ("ReadOptions",
                                                                     "RunOptions")]
    assert len(names) >= 15
    for name in names:
        cls = getattr(config, name)
        assert cls.__module__ == config.__name__, name
        assert all(f.kw_only for f in dataclasses.fields(cls)), name
