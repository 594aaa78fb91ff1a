"""``--threads``: every command that takes it sets numba's thread count, through one function
(``run.config.set_threads``), whichever path the command takes (a sun, a point light, a
subsolar point)."""

import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.cli import cli
from hillshade_rt.testing import fractal_terrain, write_geotiff

X, Y = 500000.0, 4000000.0


class Stop(Exception):
    """Raised by the recording set_num_threads: the run has set its threads; nothing else is
    needed from it."""


@pytest.fixture
def dem(tmp_path):
    z = fractal_terrain(40, 50, 6, relief=300.0) + 200.0
    return write_geotiff(tmp_path / "d.tif", z, Affine(10, 0, X, 0, -10, Y),
                         CRS.from_epsg(32633))


COMMANDS = {
    "shadow sun": ["shadow", "--azimuth", "203.7", "--elevation", "12"],
    "shadow light": ["shadow", "--light-position", f"{X + 163},{Y - 290},650"],
    "shadow subsolar": ["shadow", "--subsolar", "-20.5,97.3"],
    "hillshade sun": ["hillshade", "--azimuth", "163", "--elevation", "20"],
    "hillshade light": ["hillshade", "--light-position", f"{X + 163},{Y - 290},650"],
    "horizon": ["horizon", "--directions", "8"],
    "skyview": ["skyview", "--directions", "8"],
}


@pytest.mark.parametrize("name", list(COMMANDS))
def test_threads_reach_numba(name, tmp_path, runner, dem, monkeypatch):
    import numba

    seen = []

    def record(n):
        seen.append(n)
        raise Stop

    monkeypatch.setattr(numba, "set_num_threads", record)
    cmd, *rest = COMMANDS[name]
    r = runner.invoke(cli, [cmd, dem, str(tmp_path / "o.tif"), *rest, "--threads", "1"])
    assert seen == [1], (r.exit_code, r.output)
    assert r.exit_code == 1 and "(Stop)" in r.output, r.output   # stopped there, not before


# the commands without --threads: they refuse it as a usage error (exit status 2); query and
# profile march with numba all the same, so their runs set the threads of a Python caller's
# RunOptions (the one function), and the value reaches numba inside the run
NO_THREADS = {
    "query": ["query", "--at-xy", f"{X + 163},{Y - 290}", "--azimuth", "203.7",
              "--elevation", "12"],
    "profile": ["profile", "--at-xy", f"{X + 163},{Y - 290}"],
    "view": ["view", "--no-browser"],
    "info": ["info"],
}


@pytest.mark.parametrize("name", list(NO_THREADS))
def test_commands_without_threads_refuse_it(name, runner, dem):
    cmd, *rest = NO_THREADS[name]
    r = runner.invoke(cli, [cmd, dem, *rest, "--threads", "1"])
    assert r.exit_code == 2 and "--threads" in r.output, r.output


@pytest.fixture
def threads_back():
    """numba's thread count as it was, after the test."""
    import numba

    before = numba.get_num_threads()
    yield before
    numba.set_num_threads(before)


@pytest.mark.parametrize("name", ["query", "query light", "profile"])
def test_point_runs_set_the_threads_of_their_run_options(name, dem, monkeypatch, threads_back):
    import numba

    from hillshade_rt.run.config import RunOptions
    from hillshade_rt.run.config import ProfileConfig
    from hillshade_rt.run.profile import profile
    from hillshade_rt.run.config import QueryConfig
    from hillshade_rt.run.query import query

    if numba.config.NUMBA_NUM_THREADS > 1:
        numba.set_num_threads(2)       # not 1 before the run: the run makes it 1
    seen = []
    ro = RunOptions(threads=1, quiet=True)
    at = [(X + 163.0, Y - 290.0)]
    if name == "profile":
        import hillshade_rt.engine.arrays as arrays
        march = arrays.observer_profiles

        def spy(*a, **k):
            seen.append(numba.get_num_threads())
            return march(*a, **k)
        monkeypatch.setattr(arrays, "observer_profiles", spy)
        doc = profile(ProfileConfig(dem=dem, at_xy=at, step=7.3, run=ro))
        assert len(doc["points"][0]["horizon_deg"]) == len(doc["points"][0]["azimuth"])
    elif name == "query":
        import hillshade_rt.engine.arrays as arrays
        march = arrays.sun_at_points

        def spy(*a, **k):
            seen.append(numba.get_num_threads())
            return march(*a, **k)
        monkeypatch.setattr(arrays, "sun_at_points", spy)
        doc = query(QueryConfig(dem=dem, at_xy=at, sun={"azimuth": 203.7, "elevation": 12.0},
                                run=ro))
        assert doc["points"] == 1 and doc["suns"] == 1
    else:
        import hillshade_rt.algorithms.lightmap as lightmap
        march = lightmap.light_at_points

        def spy(*a, **k):
            seen.append(numba.get_num_threads())
            return march(*a, **k)
        monkeypatch.setattr(lightmap, "light_at_points", spy)
        doc = query(QueryConfig(dem=dem, at_xy=at, light_position=f"{X + 290},{Y - 163},900",
                                run=ro))
        assert doc["points"] == 1
    assert seen == [1]
