"""cli/version.py: ``--version``'s lines (the GPU and thread lines moved here from
test_startup), GDAL's version without loading it, the GPUs the driver lists, the eager flag.
(The program's own --version in a fresh process: test_startup.)"""

import os

import click
from click.testing import CliRunner

from hillshade_rt.cli import version as v


def test_version_gpu_and_thread_lines(monkeypatch):
    monkeypatch.delenv("NUMBA_ENABLE_CUDASIM", raising=False)
    monkeypatch.setattr(v, "gpus_seen", lambda: [])
    monkeypatch.setattr(v, "_installed", lambda d: None if d == "numba-cuda" else "1.0")
    assert "backend gpu: not installed (pip install 'hillshade-rt[gpu]'" in v.version_text()
    monkeypatch.setattr(v, "_installed", lambda d: "9.9")
    assert "numba-cuda 9.9; no NVIDIA driver loaded, no GPU" in v.version_text()
    monkeypatch.setattr(v, "gpus_seen", lambda: ["NVIDIA H200"])
    assert "1 GPU(s) listed by the driver: NVIDIA H200" in v.version_text()
    monkeypatch.setenv("NUMBA_NUM_THREADS", "3")
    assert "backend cpu: numba, 3 threads (NUMBA_NUM_THREADS)" in v.version_text()


def test_the_simulator_line_and_the_first_lines(monkeypatch):
    monkeypatch.setenv("NUMBA_ENABLE_CUDASIM", "1")
    lines = v.version_text().splitlines()
    from hillshade_rt import __version__
    assert lines[0] == f"hillshade-rt {__version__}" and lines[1].startswith("python ")
    assert lines[-1] == "backend gpu: numba's CUDA simulator (NUMBA_ENABLE_CUDASIM=1)"


def test_cpu_threads(monkeypatch):
    monkeypatch.setenv("NUMBA_NUM_THREADS", "5")
    assert v.cpu_threads() == (5, "NUMBA_NUM_THREADS")
    monkeypatch.setenv("NUMBA_NUM_THREADS", "many")
    assert v.cpu_threads() == (len(os.sched_getaffinity(0)), "CPUs available")


def test_gdal_version_is_rasterios():
    import rasterio
    assert v.gdal_version() == rasterio.__gdal_version__


def test_gpus_seen_reads_the_drivers_files(monkeypatch, tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.write_text("Model:           NVIDIA H100 80GB HBM3\nIRQ: 1\n")
    b.write_text("IRQ: 2\n")
    monkeypatch.setattr(v.glob, "glob", lambda pattern: [str(b), str(a)])
    assert v.gpus_seen() == ["NVIDIA H100 80GB HBM3", "NVIDIA GPU"]
    monkeypatch.setattr(v.glob, "glob", lambda pattern: [])
    monkeypatch.setattr(v.os.path, "exists", lambda p: False)
    assert v.gpus_seen() == []
    monkeypatch.setattr(v.sys, "platform", "darwin")
    assert v.gpus_seen() is None


def test_the_eager_flag():
    @click.command()
    @v.version_option
    def cmd():
        click.echo("ran")
    r = CliRunner().invoke(cmd, ["--version"])
    assert r.exit_code == 0 and r.output.startswith("hillshade-rt ") and "ran" not in r.output
    assert CliRunner().invoke(cmd, []).output == "ran\n"
