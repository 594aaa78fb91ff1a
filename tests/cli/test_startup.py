"""What starting the command line costs and shows: the modules ``--help``, ``--version`` and a
plain az/el run import (pvlib, pandas and Dask only when used), ``--version``'s lines, and shell
completion."""

import json
import os
import subprocess
import sys
from importlib.metadata import version

import pytest

from hillshade_rt.testing import data_path

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
LAZY = {"pvlib", "pandas", "dask", "distributed"}


def modules_after(*args) -> tuple[int, set[str]]:
    """(exit status, top-level modules imported) of one ``hillshade-rt ARGS`` in a fresh
    interpreter."""
    code = ("import json, sys\n"
            "from hillshade_rt.cli import cli\n"
            f"try:\n    cli.main({list(map(str, args))!r}, prog_name='hillshade-rt')\n"
            "except SystemExit as e:\n    code = e.code or 0\n"
            "print(json.dumps([code, sorted({m.split('.')[0] for m in sys.modules})]))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    status, mods = json.loads(r.stdout.strip().splitlines()[-1])
    return status, set(mods)


def test_help_imports_nothing_heavy():
    status, mods = modules_after("--help")
    assert status == 0
    assert not mods & (LAZY | {"numpy", "numba", "rasterio", "scipy"}), mods & LAZY


def test_an_az_el_run_imports_no_pvlib_pandas_or_dask(tmp_path):
    status, mods = modules_after("shadow", LIDAR, tmp_path / "m.tif", "--azimuth", "203.7",
                                 "--elevation", "10", "-q")
    assert status == 0 and (tmp_path / "m.tif").exists()
    assert {"numba", "rasterio"} <= mods            # it did run
    assert not mods & LAZY, mods & LAZY


def test_a_run_from_a_time_imports_pvlib(tmp_path):
    """The other side of the check above: pvlib is imported where it is used."""
    status, mods = modules_after("shadow", LIDAR, tmp_path / "m.tif",
                                 "--time", "2026-06-21T16:00Z", "-q")
    assert status == 0 and "pvlib" in mods


def test_version_names_what_it_runs_on():
    exe = os.path.join(os.path.dirname(sys.executable), "hillshade-rt")
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_ENABLE_CUDASIM"}
    r = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=120, env=env)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    import rasterio
    from hillshade_rt import __version__
    assert lines[0] == f"hillshade-rt {__version__}"
    assert f"numba {version('numba')}," in r.stdout
    assert f"GDAL {rasterio.__gdal_version__} (rasterio {rasterio.__version__})" in r.stdout
    assert f"numpy {version('numpy')}" in r.stdout
    cpu = next(ln for ln in lines if ln.startswith("backend cpu: numba, "))
    assert int(cpu.split(", ")[1].split()[0]) >= 1
    gpu = next(ln for ln in lines if ln.startswith("backend gpu: "))
    try:
        assert f"numba-cuda {version('numba-cuda')}" in gpu
    except Exception:       # PackageNotFoundError: installed without the gpu extra
        assert "not installed" in gpu


def test_version_initialises_no_cuda_and_loads_no_numba_nor_gdal():
    """GDAL's version comes from the name of the libgdal rasterio's wheel carries: --version
    imports neither rasterio nor numpy (the version test above checks the line is GDAL's)."""
    status, mods = modules_after("--version")
    assert status == 0
    assert not mods & {"numba", "numba_cuda", "llvmlite", "rasterio", "numpy"}
    assert not mods & LAZY


@pytest.mark.parametrize("shell, words", [
    ("bash", ["_hillshade_rt_completion()", "complete -o nosort -F _hillshade_rt_completion"
              " hillshade-rt"]),
    ("zsh", ["#compdef hillshade-rt", "compdef _hillshade_rt_completion hillshade-rt"]),
    ("fish", ["function _hillshade_rt_completion", "complete --no-files --command hillshade-rt"]),
])
def test_shell_completion_script(shell, words):
    exe = os.path.join(os.path.dirname(sys.executable), "hillshade-rt")
    env = dict(os.environ, _HILLSHADE_RT_COMPLETE=f"{shell}_source")
    r = subprocess.run([exe], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    for w in words:
        assert w in r.stdout


def test_shell_completion_completes_commands_and_options():
    exe = os.path.join(os.path.dirname(sys.executable), "hillshade-rt")
    env = dict(os.environ, _HILLSHADE_RT_COMPLETE="bash_complete",
               COMP_WORDS="hillshade-rt sun", COMP_CWORD="1")
    r = subprocess.run([exe], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.split() == ["plain,sun-hours"], r.stdout
    env.update(COMP_WORDS="hillshade-rt shadow --azi", COMP_CWORD="2")
    r = subprocess.run([exe], env=env, capture_output=True, text=True, timeout=120)
    assert "plain,--azimuth" in r.stdout.split()
