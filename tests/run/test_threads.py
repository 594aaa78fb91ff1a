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
