"""``engine.gpu.resolve_backend``: one rule for every run. ``auto`` takes the GPU whenever a
real device is found and the kernels have a GPU twin: the subsolar run too (it used to keep to
the CPU on ``auto``)."""

import pytest

from hillshade_rt.engine import gpu
from hillshade_rt.engine.shader import choose_backend
from hillshade_rt.errors import HillshadeError


@pytest.fixture
def fake_gpu(monkeypatch):
    monkeypatch.setattr(gpu, "simulator_enabled", lambda: False)
    monkeypatch.setattr(gpu, "status", lambda: (True, "fake device"))


@pytest.fixture
def no_gpu(monkeypatch):
    monkeypatch.setattr(gpu, "simulator_enabled", lambda: False)
    monkeypatch.setattr(gpu, "status", lambda: (False, "no usable CUDA GPU: fake"))


def test_auto_takes_the_gpu_when_there_is_one(fake_gpu):
    assert gpu.resolve_backend("auto") == "gpu"
    assert gpu.resolve_backend("auto", "brute", {}) == "gpu"
    assert choose_backend("auto", "brute", {}) == gpu.resolve_backend("auto", "brute", {})
    assert gpu.resolve_backend("cpu", "brute", {}) == "cpu"


def test_auto_keeps_to_the_cpu_without_one(no_gpu):
    assert gpu.resolve_backend("auto") == "cpu"
    with pytest.raises(HillshadeError, match="fake"):
        gpu.resolve_backend("gpu")


def test_subsolar_run_asks_the_one_rule(fake_gpu, monkeypatch, tmp_path, runner):
    """The subsolar run's backend comes from resolve_backend (stopped there: no device here)."""
    from affine import Affine
    from rasterio.crs import CRS

    from hillshade_rt.cli import cli
    from hillshade_rt.testing import fractal_terrain, write_geotiff

    asked = []

    def rule(backend, *a, **k):
        asked.append(backend)
        raise HillshadeError("stopped: " + ("gpu" if backend == "auto" else backend))

    monkeypatch.setattr(gpu, "resolve_backend", rule)
    dem = write_geotiff(tmp_path / "d.tif", fractal_terrain(20, 30, 6, relief=300.0) + 200.0,
                        Affine(10, 0, 500000, 0, -10, 4000000), CRS.from_epsg(32633))
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "o.tif"), "--subsolar", "-20.5,97.3"])
    assert asked == ["auto"] and "stopped: gpu" in r.output, r.output


def test_bad_backend_is_refused():
    with pytest.raises(HillshadeError, match="cpu, gpu or auto"):
        gpu.resolve_backend("tpu")
