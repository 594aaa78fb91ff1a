import os

# GPU kernels run through numba's CUDA simulator unless the caller says otherwise: on a machine
# with a GPU, `NUMBA_ENABLE_CUDASIM=0 make test` runs the same tests on the device. Set before
# anything imports numba (it reads the variable once).
os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")

import pytest  # noqa: E402


@pytest.fixture(autouse=True, scope="session")
def _stats_cache(tmp_path_factory):
    """The --context statistics cache (run.statscache) in a folder of the test session, not
    the user's ~/.cache (tests that look at it set HILLSHADE_RT_STATS_DIR themselves)."""
    if "HILLSHADE_RT_STATS_DIR" not in os.environ:
        os.environ["HILLSHADE_RT_STATS_DIR"] = str(tmp_path_factory.mktemp("stats-cache"))
    yield

# Fixtures only: the helpers the tests share (terrains, the plain-Python reference, GeoTIFF
# writing, the repository's data) are plain functions in hillshade_rt.testing; tests import them
# from there, never from this file or from another test file (tests/test_testing.py checks).


@pytest.fixture
def runner():
    from click.testing import CliRunner

    return CliRunner()


@pytest.fixture
def calls(monkeypatch):
    """``calls(module, name)``: ``module``'s function ``name`` replaced, for the test, by one that
    runs nothing and records the (positional) arguments of each call; returns the list they go
    to (what a command hands its run: tests/cli/test_<command>.py)."""
    import importlib

    def replace(module: str, name: str) -> list:
        seen = []
        monkeypatch.setattr(importlib.import_module(module), name, lambda *args: seen.append(args))
        return seen
    return replace
