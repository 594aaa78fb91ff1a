"""The CUDA backend: finding a GPU, building the CUDA kernels, keeping a DEM on the device.

Kernels are written next to their CPU versions in ``algorithms/<name>.py`` as plain functions
decorated with :func:`kernel`. Nothing CUDA is imported until a GPU kernel is first launched: the
package works without numba-cuda, and ``--backend gpu`` then fails with one line saying so.

**One source for both backends.** A CUDA kernel calls the same ``njit`` functions as the CPU
kernel (the per-ray math of ``raymath``, the per-cell bodies of each algorithm). :func:`device`
compiles such a function again with ``numba.cuda.jit(device=True)`` from its plain source
(``.py_func``), after pointing every ``njit`` function it calls at its own device version. One
substitution is made on the way: ``raymath.madd`` (``a + b*c``) becomes libdevice's
``dadd_rn(a, dmul_rn(b, c))``, which the CUDA compiler never fuses into an FMA, so the GPU rounds
every sample like the CPU and the masks agree bit for bit.

**numba's CUDA simulator.** With ``NUMBA_ENABLE_CUDASIM=1`` the kernels run as Python on the CPU,
thread by thread (slow: small grids only). The tests use it; ``--backend gpu`` runs on it when it
is switched on, ``--backend auto`` never picks it.
"""

from __future__ import annotations

import contextlib
import os
import time
import types

import numpy as np

from .errors import HillshadeError

INSTALL_HINT = "pip install 'hillshade-rt[gpu]'"
PINNED_MIN_BYTES = 1 << 20   # transfers at least this large go through page-locked host memory
BLOCK_2D = (32, 8)           # threads per block of the per-cell kernels (x: along DEM rows)


class _NotLoaded:
    """Stands for ``numba.cuda`` in the algorithm modules, where kernels are only written; the
    kernels that :func:`kernel` builds see the real module."""

    def __getattr__(self, name):
        raise RuntimeError("CUDA kernels run only through hillshade_rt.gpu.kernel")


cuda = _NotLoaded()


# ------------------------------------------------------------------------------------------
# finding a GPU

def simulator_enabled() -> bool:
    return os.environ.get("NUMBA_ENABLE_CUDASIM", "0") not in ("", "0")


def _numba_cuda():
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


def _no_driver_here() -> bool:
    """True on Linux when no NVIDIA driver is loaded (no /dev/nvidiactl, /dev/dxg of WSL or
    /proc/driver/nvidia, and no NUMBA_CUDA_DRIVER): then there is no GPU to find, and importing
    numba-cuda to learn that would cost a third of a second of every run."""
    import sys
    if not sys.platform.startswith("linux") or os.environ.get("NUMBA_CUDA_DRIVER"):
        return False
    return not any(os.path.exists(p) for p in ("/dev/nvidiactl", "/dev/dxg",
                                               "/proc/driver/nvidia"))


def _runtime():
    """The module whose arrays, streams and events ``GpuDem`` uses (numba.cuda; a test that
    compiles the kernels without a GPU puts a stand-in here)."""
    return _numba_cuda()


def _first_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    if text.startswith("Error at driver init"):
        text = text.split(": ", 1)[-1]
    return text.rstrip(" :")


_STATUS: list = []


def status() -> tuple[bool, str]:
    """(usable, what): whether the GPU backend can run here, and the device's name or what is
    missing (no numba-cuda, no driver, no device, no CUDA toolkit libraries). Cached."""
    if _STATUS:
        return _STATUS[0]
    try:
        if not simulator_enabled() and _no_driver_here():
            import importlib.util
            if importlib.util.find_spec("numba_cuda") is not None:
                raise HillshadeError("no usable CUDA GPU: no NVIDIA driver on this machine "
                                     "(no /dev/nvidiactl)")
        nc = _numba_cuda()
        if simulator_enabled():
            res = (True, "numba CUDA simulator (NUMBA_ENABLE_CUDASIM=1)")
        else:
            try:
                devs = list(nc.gpus)
            except Exception as exc:   # numba raises its own CudaSupportError subclasses
                raise HillshadeError(f"no usable CUDA GPU: {_first_line(exc)}") from None
            if not devs:
                raise HillshadeError("no usable CUDA GPU: the CUDA driver found no device")
            try:
                from numba.cuda.cudadrv.nvvm import NVVM
                NVVM()
            except Exception as exc:
                raise HillshadeError(f"CUDA toolkit libraries are missing ({_first_line(exc)}); "
                                     f"{INSTALL_HINT} installs them") from None
            name = nc.get_current_device().name
            res = (True, name.decode() if isinstance(name, bytes) else str(name))
    except HillshadeError as exc:
        res = (False, str(exc))
    _STATUS.append(res)
    return res


def resolve_backend(backend: str) -> str:
    """'cpu' or 'gpu' for a requested backend: ``auto`` is the GPU when numba finds a real CUDA
    device (never the simulator), else the CPU; ``gpu`` without one is an error naming what is
    missing."""
    if backend == "cpu":
        return "cpu"
    if backend == "auto":
        if simulator_enabled():
            return "cpu"
        ok, _ = status()
        return "gpu" if ok else "cpu"
    if backend == "gpu":
        ok, what = status()
        if not ok:
            raise HillshadeError(what)
        return "gpu"
    raise HillshadeError(f"backend must be cpu, gpu or auto, got {backend!r}")


# ------------------------------------------------------------------------------------------
# one source, two targets

_DEVICE: dict = {}


def _madd_gpu():
    from numba.cuda import libdevice

    def madd(a, b, c):
        return libdevice.dadd_rn(a, libdevice.dmul_rn(b, c))
    return madd


def _retarget(pyfunc):
    """A copy of ``pyfunc`` whose global names point at device versions of the njit functions it
    calls, and ``cuda`` at numba.cuda."""
    from numba.core.registry import CPUDispatcher

    nc = _numba_cuda()
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
        from .algorithms import raymath
        nc = _numba_cuda()
        if fn is raymath.madd and not simulator_enabled():
            _DEVICE[key] = nc.jit(device=True)(_madd_gpu())
        else:
            _DEVICE[key] = nc.jit(device=True)(_retarget(fn.py_func))
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
            nc = _numba_cuda()
            self._compiled = nc.jit(_retarget(self.py_func))
        return self._compiled

    def __getitem__(self, config):
        return self.build()[config]


def grid_2d(rows: int, cols: int, block=BLOCK_2D):
    """(blocks, threads) covering a rows x cols grid; x runs along a row (coalesced)."""
    bx, by = block
    return ((cols + bx - 1) // bx, (rows + by - 1) // by), block


# ------------------------------------------------------------------------------------------
# the DEM on the device

class GpuDem:
    """Heights resident on the GPU for any number of sun positions (a time series uploads them
    once). Results come back as uint8 masks (or float32 angles) through page-locked buffers.

    ``stats`` accumulates what the report shows: ``device``, ``kernel_ms`` (CUDA events around the
    kernels), ``transfer_ms`` (host<->device copies), ``h2d_bytes``, ``d2h_bytes``.
    """

    def __init__(self, z: np.ndarray, zrange: tuple[float, float, bool] | None = None):
        ok, what = status()
        if not ok:
            raise HillshadeError(what)
        self.cuda = _runtime()
        if z.dtype != np.float32 or z.ndim != 2:
            raise TypeError("heights must be a 2-D float32 array")
        if zrange is None:
            from .algorithms.sweep import _z_range
            zrange = _z_range(z)
        self.zmin, self.zmax, self.void = float(zrange[0]), float(zrange[1]), bool(zrange[2])
        self.shape = z.shape
        self.simulator = simulator_enabled()
        self.stats = {"device": what, "simulator": self.simulator, "kernel_ms": 0.0,
                      "transfer_ms": 0.0, "h2d_bytes": 0, "d2h_bytes": 0}
        self.stream = self.cuda.stream()
        self._canon_key = None
        self._canon = None
        self._staging: dict = {}
        self._host_z = z           # for the pyramid, built at its first use (no copy)
        self._pyramid = None
        self.check_memory(13 * z.size)
        with self._oom_errors():
            self.z = self.upload(z)

    # -- memory -------------------------------------------------------------------------------
    def check_memory(self, nbytes: int) -> None:
        """Refuse up front when the device cannot hold ``nbytes`` (a clear error, not a crash
        halfway: use the CPU backend, or tiles, for such a DEM)."""
        if self.simulator:
            return
        free, total = self.cuda.current_context().get_memory_info()
        if nbytes > 0.95 * free:
            raise HillshadeError(
                f"GPU out of memory: this DEM needs about {nbytes / 2**30:.2f} GiB on "
                f"{self.stats['device']}, which has {free / 2**30:.2f} GiB free of "
                f"{total / 2**30:.2f}; use --backend cpu")

    @contextlib.contextmanager
    def _oom_errors(self):
        try:
            yield
        except Exception as exc:
            if "OUT_OF_MEMORY" in str(exc) or "out of memory" in str(exc).lower():
                raise HillshadeError(f"GPU out of memory on {self.stats['device']}: "
                                     f"{_first_line(exc)}; use --backend cpu") from None
            raise

    def empty(self, shape, dtype):
        with self._oom_errors():
            return self.cuda.device_array(shape, dtype=dtype, stream=self.stream)

    # -- transfers ----------------------------------------------------------------------------
    def upload(self, a: np.ndarray):
        nc = self.cuda
        a = np.ascontiguousarray(a)
        t = time.perf_counter()
        if a.nbytes >= PINNED_MIN_BYTES and not self.simulator:
            with nc.pinned(a):   # page-lock the caller's array in place: no staging copy
                d = nc.to_device(a, stream=self.stream)
                self.stream.synchronize()
        else:
            d = nc.to_device(a, stream=self.stream)
            self.stream.synchronize()
        self.stats["transfer_ms"] += 1e3 * (time.perf_counter() - t)
        self.stats["h2d_bytes"] += int(a.nbytes)
        return d

    def download(self, d, out: np.ndarray | None = None) -> np.ndarray:
        """Copy device array ``d`` back: into ``out`` when given, else into a new array (through
        a page-locked staging buffer kept for the next sun position)."""
        nc = self.cuda
        key = (d.shape, np.dtype(d.dtype).str)
        t = time.perf_counter()
        if out is None and d.nbytes >= PINNED_MIN_BYTES and not self.simulator:
            if key not in self._staging:
                self._staging[key] = nc.pinned_array(d.shape, dtype=d.dtype)
            buf = self._staging[key]
            d.copy_to_host(buf, stream=self.stream)
            self.stream.synchronize()
            out = buf.copy()
        else:
            host = d.copy_to_host(stream=self.stream)
            self.stream.synchronize()
            if out is None:
                out = host
            else:
                out[...] = host
        self.stats["transfer_ms"] += 1e3 * (time.perf_counter() - t)
        self.stats["d2h_bytes"] += int(d.nbytes)
        return out

    def rays(self, rays):
        """The per-row ray arrays of a ``SunRays`` on the device (small)."""
        return tuple(self.upload(np.ascontiguousarray(a)) for a in
                     (rays.dom_col, rays.step_dom, rays.step_other, rays.rise, rays.step_m,
                      rays.curv))

    # -- kernels ------------------------------------------------------------------------------
    @contextlib.contextmanager
    def timed(self):
        """Time the kernels launched inside with CUDA events (added to ``kernel_ms``)."""
        nc = self.cuda
        start, end = nc.event(), nc.event()
        start.record(self.stream)
        with self._oom_errors():
            yield
        end.record(self.stream)
        end.synchronize()
        if self.simulator:   # the simulator's events record no time
            self.stats["kernel_ms"] = None
        else:
            self.stats["kernel_ms"] += start.elapsed_time(end)

    def launch(self, k: kernel, rows: int, cols: int, *args):
        """Launch a per-cell kernel over a rows x cols grid on this DEM's stream."""
        blocks, threads = grid_2d(rows, cols)
        k[blocks, threads, self.stream](*args)

    def pyramid_args(self, use: bool = True) -> tuple:
        """The maximum-height pyramid's kernel arguments (``algorithms.pyramid``) on the device,
        built on the host and uploaded once for all suns; with ``use`` False, the plain march's
        placeholders."""
        from .algorithms import pyramid
        if not use:
            if getattr(self, "_no_pyramid", None) is None:
                self._no_pyramid = tuple(self.upload(a) for a in pyramid.NO_PYRAMID[:3]) + (
                    np.int64(0),)
            return self._no_pyramid
        if self._pyramid is None:
            data, off, widths, nlev = pyramid.MaxPyramid(self._host_z).args
            self.check_memory(data.nbytes)
            with self._oom_errors():
                self._pyramid = (self.upload(data), self.upload(off), self.upload(widths), nlev)
        return self._pyramid

    def canonical(self, frame):
        """The heights in the canonical (line, position) order of ``frame`` (``frames.Frame``),
        as a contiguous device array: lines are contiguous, so kernels that walk along them read
        coalesced memory. Kept for the next sun position in the same octant."""
        from .algorithms import frames
        key = (frame.dom_col, frame.flip_line, frame.flip_pos)
        if key != self._canon_key:
            rows, cols = self.shape
            L, P = (cols, rows) if frame.dom_col else (rows, cols)
            self._canon = None
            zc = self.empty((L, P), np.float32)
            self.launch(frames.canonical_copy_gpu, L, P, self.z, zc, frame.dom_col,
                        frame.flip_line, frame.flip_pos, True)
            self._canon, self._canon_key = zc, key
        return self._canon

    def shadow_mask(self, rays, algorithm: str = "auto", zmax: float | None = None,
                    stats: dict | None = None, **options) -> np.ndarray:
        """The mask for one sun (``geometry.sun_rays``) by ``algorithm``; the heights stay on the
        device for the next call."""
        from .algorithms import GPU_ALGORITHMS, gpu_unsupported
        why = gpu_unsupported(algorithm, options)
        if why:
            raise HillshadeError(why)
        if not np.isfinite(self.zmax):     # nothing but voids
            return np.full(self.shape, 255, np.uint8)
        return GPU_ALGORITHMS[algorithm](self, rays, self.zmax if zmax is None else zmax, stats,
                                         **options)

    def report(self) -> dict:
        """What the run report shows of the GPU."""
        return dict(self.stats)
