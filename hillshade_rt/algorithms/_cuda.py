"""One source, two targets: what the algorithm modules need to write CUDA kernels.

Kernels are written next to their CPU versions in ``algorithms/<name>.py`` as plain functions
decorated with :func:`kernel`, calling ``cuda.grid(2)`` and friends through the stand-in
:data:`cuda`. Nothing CUDA is imported until a GPU kernel is first launched: the package works
without numba-cuda, and ``--backend gpu`` then fails with one line saying so.

**One source for both backends.** A CUDA kernel calls the same ``njit`` functions as the CPU
kernel (the per-ray math of ``raymath``, the per-cell bodies of each algorithm). :func:`device`
compiles such a function again with ``numba.cuda.jit(device=True)`` from its plain source
(``.py_func``), after pointing every ``njit`` function it calls at its own device version. One
substitution is made on the way: ``raymath.madd`` (``a + b*c``) becomes libdevice's
``dadd_rn(a, dmul_rn(b, c))``, which the CUDA compiler never fuses into an FMA, so the GPU rounds
every sample like the CPU and the masks agree bit for bit.

**numba's CUDA simulator.** With ``NUMBA_ENABLE_CUDASIM=1`` the kernels run as Python on the CPU,
thread by thread (slow: small grids only). The tests use it.

This module sits below the algorithms (it imports none of them at import time, and nothing
above ``algorithms/`` but ``errors``), so that they can import it; the device runtime that finds
a GPU and keeps a DEM on it (``hillshade_rt.engine.gpu``) sits above them and imports from here.
"""

from __future__ import annotations

import os
import types

from ..errors import HillshadeError

INSTALL_HINT = "pip install 'hillshade-rt[gpu]'"
BLOCK_2D = (32, 8)           # threads per block of the per-cell kernels (x: along DEM rows)


class _NotLoaded:
    """Stands for ``numba.cuda`` in the algorithm modules, where kernels are only written; the
    kernels that :func:`kernel` builds see the real module."""

    def __getattr__(self, name):
        raise RuntimeError("CUDA kernels run only through hillshade_rt.algorithms._cuda.kernel")


cuda = _NotLoaded()


def simulator_enabled() -> bool:
    """Whether numba's CUDA simulator is switched on (``NUMBA_ENABLE_CUDASIM``)."""
    return os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")


def numba_cuda():
    """``numba.cuda`` (numba-cuda's, or the simulator) or a HillshadeError naming what is
    missing. Without the numba-cuda package nothing is imported (numba's own deprecated CUDA
    target is refused anyway, and importing it costs a third of a second of every run)."""
    import importlib.util
    if not simulator_enabled() and importlib.util.find_spec("numba_cuda") is None:
        raise HillshadeError(f"no GPU backend: numba-cuda is not installed ({INSTALL_HINT})")
    try:
        from numba import cuda as nc
    except ImportError:
        raise HillshadeError(f"no GPU backend: numba-cuda is not installed ({INSTALL_HINT})") \
            from None
    if not simulator_enabled() and getattr(nc, "implementation", "") != "NVIDIA":
        raise HillshadeError(
            f"no GPU backend: numba-cuda is not installed, and numba's own deprecated CUDA target "
            f"is not used ({INSTALL_HINT})")
    return nc


_DEVICE: dict = {}


def _madd_gpu():
    from numba.cuda import libdevice

    def madd(a, b, c):
        return libdevice.dadd_rn(a, libdevice.dmul_rn(b, c))
    return madd


def retarget(pyfunc):
    """A copy of ``pyfunc`` whose global names point at device versions of the njit functions it
    calls, and ``cuda`` at numba.cuda."""
    from numba.core.registry import CPUDispatcher

    nc = numba_cuda()
    g = dict(pyfunc.__globals__)
    for name in pyfunc.__code__.co_names:
        obj = g.get(name)
        if isinstance(obj, CPUDispatcher):
            g[name] = device(obj)
        elif isinstance(obj, _NotLoaded):
            g[name] = nc
    return types.FunctionType(pyfunc.__code__, g, pyfunc.__name__, pyfunc.__defaults__,
                              pyfunc.__closure__)


def device(fn):
    """The CUDA device function of the ``njit`` function ``fn`` (built once)."""
    key = id(fn)
    if key not in _DEVICE:
        from . import raymath
        nc = numba_cuda()
        if fn is raymath.madd and not simulator_enabled():
            _DEVICE[key] = nc.jit(device=True)(_madd_gpu())
        else:
            _DEVICE[key] = nc.jit(device=True)(retarget(fn.py_func))
    return _DEVICE[key]


class kernel:
    """Decorator for a CUDA kernel written as a plain function next to its CPU twin; compiled
    (for the device this process uses) on its first launch: ``k[grid, block, stream](*args)``."""

    def __init__(self, fn):
        self.py_func = fn
        self.__doc__ = fn.__doc__
        self.__name__ = fn.__name__
        self._compiled = None

    def build(self):
        if self._compiled is None:
            nc = numba_cuda()
            self._compiled = nc.jit(retarget(self.py_func))
        return self._compiled

    def __getitem__(self, config):
        return self.build()[config]


def grid_2d(rows: int, cols: int, block=BLOCK_2D):
    """(blocks, threads) covering a rows x cols grid; x runs along a row (coalesced)."""
    bx, by = block
    return ((cols + bx - 1) // bx, (rows + by - 1) // by), block
