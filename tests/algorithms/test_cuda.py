"""algorithms/_cuda.py: one source, two targets. ``kernel`` builds a CUDA kernel from a plain
function on its first launch, each ``njit`` function it calls compiled again for the device
(``device``, ``retarget``); ``numba_cuda`` finds numba-cuda or the simulator, or says in one line
what is missing; ``grid_2d`` covers a grid. The kernels run on numba's CUDA simulator
(tests/conftest.py sets NUMBA_ENABLE_CUDASIM=1 unless the environment says otherwise; with 0,
on the GPU). (Every algorithm's kernels against the CPU: tests/engine/test_gpu.py.)"""

import types

import numba
import numpy as np
import pytest

from hillshade_rt.algorithms import _cuda, raymath
from hillshade_rt.algorithms._cuda import cuda, grid_2d, kernel
from hillshade_rt.algorithms.raymath import madd
from hillshade_rt.errors import HillshadeError


@numba.njit
def _half_step(x, k):
    """A plain njit function a kernel calls (calling another: ``madd``)."""
    return madd(x, k, 0.5)


@kernel
def _fill(z, out):
    """A kernel written as the algorithm modules write theirs."""
    c, r = cuda.grid(2)
    if r < z.shape[0] and c < z.shape[1]:
        out[r, c] = _half_step(z[r, c], np.float64(r))


def test_a_kernel_runs_with_its_njit_callees_on_the_device():
    rows, cols = 6, 11
    z = np.arange(rows * cols, dtype=np.float64).reshape(rows, cols) * 1.25 - 7.0
    out = np.full((rows, cols), np.nan)
    _fill[grid_2d(rows, cols, block=(4, 4))](z, out)
    assert np.array_equal(out, z + np.arange(rows)[:, None] * 0.5)
    assert _fill.build() is _fill.build()                    # compiled once
    assert _fill.__name__ == "_fill" and "algorithm modules" in _fill.__doc__


def test_retarget_points_njit_callees_and_cuda_at_the_device():
    f = _cuda.retarget(_fill.py_func)
    nc = _cuda.numba_cuda()
    assert f.__code__ is _fill.py_func.__code__ and f.__name__ == "_fill"
    assert f.__globals__["cuda"] is nc
    assert f.__globals__["_half_step"] is _cuda.device(_half_step)
    assert f.__globals__["np"] is np                         # other names untouched
    assert globals()["cuda"] is cuda and isinstance(cuda, _cuda._NotLoaded)   # ours unchanged
    assert _cuda.device(_half_step) is _cuda.device(_half_step)          # built once
    helper = _cuda.retarget(_half_step.py_func)
    assert helper.__globals__["madd"] is _cuda.device(raymath.madd)


def test_the_stand_in_refuses_to_be_used_on_the_cpu():
    with pytest.raises(RuntimeError, match="only through hillshade_rt.algorithms._cuda.kernel"):
        cuda.grid(2)
    with pytest.raises(RuntimeError):
        _fill.py_func(np.zeros((1, 1)), np.zeros((1, 1)))


@pytest.mark.parametrize("value, on", [(None, False), ("", False), ("0", False), ("1", True),
                                       ("yes", True)])
def test_simulator_enabled(monkeypatch, value, on):
    if value is None:
        monkeypatch.delenv("NUMBA_ENABLE_CUDASIM", raising=False)
    else:
        monkeypatch.setenv("NUMBA_ENABLE_CUDASIM", value)
    assert _cuda.simulator_enabled() is on


def test_numba_cuda_says_what_is_missing(monkeypatch):
    """Without the simulator: no numba-cuda package is one line naming the extra to install,
    and so is numba's own deprecated CUDA target; numba-cuda's is returned."""
    import importlib.util
    monkeypatch.setenv("NUMBA_ENABLE_CUDASIM", "0")
    find_spec = importlib.util.find_spec
    installed = []
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: (
        (object() if installed else None) if name == "numba_cuda" else find_spec(name, *a)))
    with pytest.raises(HillshadeError, match=r"numba-cuda is not installed \(pip install "
                                             r"'hillshade-rt\[gpu\]'\)$"):
        _cuda.numba_cuda()
    installed.append(True)
    monkeypatch.setattr(numba, "cuda", types.SimpleNamespace(implementation="numba's own"),
                        raising=False)
    with pytest.raises(HillshadeError, match="numba's own deprecated CUDA target is not used"):
        _cuda.numba_cuda()
    nvidia = types.SimpleNamespace(implementation="NVIDIA")
    monkeypatch.setattr(numba, "cuda", nvidia)
    assert _cuda.numba_cuda() is nvidia


@pytest.mark.parametrize("rows, cols", [(1, 1), (8, 32), (9, 33), (17, 21), (1000, 7)])
def test_grid_2d_covers_the_grid_with_no_spare_block(rows, cols):
    (bx, by), (tx, ty) = grid_2d(rows, cols)
    assert (tx, ty) == _cuda.BLOCK_2D == (32, 8)          # x along a row
    assert bx * tx >= cols > (bx - 1) * tx and by * ty >= rows > (by - 1) * ty
    assert grid_2d(rows, cols, block=(4, 2)) == (((cols + 3) // 4, (rows + 1) // 2), (4, 2))
