"""The CUDA backend's device runtime: finding a GPU, choosing the backend, keeping a DEM on the
device (:class:`GpuDem`).

The kernels themselves are written next to their CPU versions in ``algorithms/<name>.py``, with
the one-source machinery of ``algorithms/_cuda.py`` (:func:`kernel`, :func:`device`: the same
``njit`` bodies compiled for the GPU, ``raymath.madd`` never fused into an FMA). This module
sits above the algorithms: it imports them (the registry, the pyramid, the frames), they never
import it. Nothing CUDA is imported until a GPU is looked for or a kernel first launched.

**numba's CUDA simulator.** With ``NUMBA_ENABLE_CUDASIM=1`` the kernels run as Python on the CPU,
thread by thread (slow: small grids only). The tests use it; ``--backend gpu`` runs on it when it
is switched on, ``--backend auto`` never picks it.
"""

from __future__ import annotations

import contextlib
import os
import time

import numpy as np

from ..algorithms._cuda import INSTALL_HINT, grid_2d, kernel, numba_cuda, simulator_enabled
from ..errors import HillshadeError

PINNED_MIN_BYTES = 1 << 20   # transfers at least this large go through page-locked host memory


# ------------------------------------------------------------------------------------------
# finding a GPU

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
    return numba_cuda()


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
        nc = numba_cuda()
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


def resolve_backend(backend: str, algorithm: str | None = None,
                    options: dict | None = None) -> str:
    """'cpu' or 'gpu' for a requested backend: the one rule of every run.

    ``auto`` is the GPU when numba finds a real CUDA device (never the simulator) and the
    algorithm with its options has GPU kernels (``algorithms.gpu_unsupported``; no algorithm:
    a run whose kernels all have a GPU twin, such as the per-cell sun of a subsolar point),
    else the CPU; ``gpu`` without a device, or with options that have no GPU kernels, is an
    error naming what is missing.
    """
    if backend not in ("cpu", "gpu", "auto"):
        raise HillshadeError(f"backend must be cpu, gpu or auto, got {backend!r}")
    why = None
    if algorithm is not None:
        from ..algorithms import gpu_unsupported
        why = gpu_unsupported(algorithm, options or {})
    if backend == "gpu" and why:
        raise HillshadeError(f"{why}; use --backend cpu")
    if backend == "cpu" or why:
        return "cpu"
    if backend == "auto":
        if simulator_enabled():
            return "cpu"
        ok, _ = status()
        return "gpu" if ok else "cpu"
    ok, what = status()
    if not ok:
        raise HillshadeError(what)
    return "gpu"


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
            from ..algorithms.counts import z_range
            zrange = z_range(z)
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
        self._host_pyramid = None   # the pyramid's host copy (``update`` patches it)
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
        from ..algorithms import pyramid
        if not use:
            if getattr(self, "_no_pyramid", None) is None:
                self._no_pyramid = tuple(self.upload(a) for a in pyramid.NO_PYRAMID[:3]) + (
                    np.int64(0),)
            return self._no_pyramid
        if self._pyramid is None:
            # kept on the host too: ``update`` patches the blocks over an edit and uploads those
            self._host_pyramid = pyramid.MaxPyramid(self._host_z)
            data, off, widths, nlev = self._host_pyramid.args
            self.check_memory(data.nbytes)
            with self._oom_errors():
                self._pyramid = (self.upload(data), self.upload(off), self.upload(widths), nlev)
        return self._pyramid

    def update(self, row: int, col: int, heights: np.ndarray,
               zrange: tuple[float, float, bool] | None = None) -> None:
        """Replace the heights of the window at (``row``, ``col``) by ``heights`` (float32,
        h x w) on the device: only the window is uploaded (and put into place by a kernel); the
        canonical copy in use is refreshed on the device, the pyramid's blocks over the window
        patched on the host and only those uploaded. The host array the GpuDem was made of is
        written too (``engine.shader.Shader.update`` has done so already: the same array). ``zrange``
        (lowest, highest, any void) of the edited DEM when the caller knows it, else computed."""
        from ..algorithms import frames
        heights = np.ascontiguousarray(heights, dtype=np.float32)
        h, w = heights.shape
        rows, cols = self.shape
        if not (0 <= row and 0 <= col and row + h <= rows and col + w <= cols):
            raise HillshadeError(f"the window {h} x {w} at ({row}, {col}) is not inside the "
                                 f"{rows} x {cols} DEM")
        if h == 0 or w == 0:
            return
        self._host_z[row:row + h, col:col + w] = heights
        with self._oom_errors():
            d = self.upload(heights)
            self.launch(frames.paste_gpu, h, w, self.z, d, np.int64(row), np.int64(col))
            if self._canon is not None:
                self._canon_key, key = None, self._canon_key
                L, P = self._canon.shape
                self.launch(frames.canonical_copy_gpu, L, P, self.z, self._canon, key[0],
                            key[1], key[2], True)
                self._canon_key = key
            if self._pyramid is not None:
                ranges = self._host_pyramid.update(self._host_z, (row, row + h, col, col + w))
                data = self._host_pyramid.args[0]
                for a, b in ranges[1:]:
                    if b > a:
                        self.stats["h2d_bytes"] += int(4 * (b - a))
                        self._pyramid[0][a:b].copy_to_device(data[a:b], stream=self.stream)
            self.stream.synchronize()
        if zrange is None:
            from ..algorithms.counts import z_range
            zrange = z_range(self._host_z)
        self.zmin, self.zmax, self.void = float(zrange[0]), float(zrange[1]), bool(zrange[2])

    def canonical(self, frame):
        """The heights in the canonical (line, position) order of ``frame`` (``frames.Frame``),
        as a contiguous device array: lines are contiguous, so kernels that walk along them read
        coalesced memory. Kept for the next sun position in the same octant."""
        from ..algorithms import frames
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
        from ..algorithms import REGISTRY, gpu_unsupported
        why = gpu_unsupported(algorithm, options)
        if why:
            raise HillshadeError(why)
        if not np.isfinite(self.zmax):     # nothing but voids
            return np.full(self.shape, 255, np.uint8)
        return REGISTRY[algorithm].gpu(self, rays, self.zmax if zmax is None else zmax, stats,
                                       **options)

    def report(self) -> dict:
        """What the run report shows of the GPU."""
        return dict(self.stats)
