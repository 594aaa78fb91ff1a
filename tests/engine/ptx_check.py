"""Compile every CUDA kernel of hillshade-rt to PTX for a real GPU, on a machine without one.

numba's CUDA simulator (tests/engine/test_gpu.py) runs the kernels as Python: it proves the arithmetic,
not that numba-cuda can type and compile them. This script runs the real GPU drivers
(``GpuDem.shadow_mask`` for every algorithm, horizon angles) with a stand-in for the device
runtime: arrays stay numpy arrays, and each kernel launch compiles the kernel with numba-cuda's
compiler and NVVM for compute capability 9.0 (H100) with the launch's own argument types instead
of running it. Run by tests/engine/test_gpu.py in a subprocess (NUMBA_ENABLE_CUDASIM=0); prints one
JSON line: kernel name -> {"ptx_bytes", "fma"} (fused multiply-adds in the PTX).
"""

import contextlib
import json
import re
import sys
import types

import numpy as np

CC = (9, 0)


def main() -> int:
    import numba
    import numba.cuda.dispatcher as dispatcher
    from numba import cuda

    from hillshade_rt.engine import gpu
    from hillshade_rt.algorithms import GPU_ALGORITHMS, _cuda, horizon, point_light
    from hillshade_rt.model.geometry import Grid, sun_rays

    # device functions are compiled for "the current device": make that an H100 without a GPU
    dispatcher.get_current_device = lambda: types.SimpleNamespace(compute_capability=CC)
    compiled = {}

    class HostArray(np.ndarray):
        def copy_to_host(self, ary=None, stream=0):
            if ary is None:
                return np.array(self)
            ary[...] = self
            return ary

        def copy_to_device(self, ary, stream=0):
            self[...] = ary

    def host(a):
        return np.ascontiguousarray(a).view(HostArray)

    class Event:
        def record(self, stream=0):
            pass

        def synchronize(self):
            pass

        def elapsed_time(self, other):
            return 0.0

    runtime = types.SimpleNamespace(
        stream=lambda: types.SimpleNamespace(synchronize=lambda: None),
        to_device=lambda a, stream=0: host(a),
        device_array=lambda shape, dtype, stream=0: host(np.zeros(shape, dtype)),
        pinned=lambda a: contextlib.nullcontext(),
        pinned_array=lambda shape, dtype: np.zeros(shape, dtype),
        event=Event,
        current_context=lambda: types.SimpleNamespace(get_memory_info=lambda: (2**40, 2**40)),
    )

    def launch(self, config):
        def run(*args):
            sig = tuple(numba.typeof(a.view(np.ndarray) if isinstance(a, HostArray) else a)
                        for a in args)
            if (self.__name__, sig) not in compiled:
                ptx, _ = cuda.compile_ptx(_cuda.retarget(self.py_func), sig, cc=CC)
                compiled[(self.__name__, sig)] = ptx
        return run

    gpu._STATUS[:] = [(True, "PTX check (no device)")]
    gpu._runtime = lambda: runtime
    _cuda.kernel.__getitem__ = launch

    z = np.random.default_rng(1).random((12, 14), dtype=np.float32) * 50
    z[3, 4] = np.nan
    g = gpu.GpuDem(z)
    uniform = Grid.uniform(12, 14, 30.0)
    lat = np.linspace(61.0, 59.0, 12)
    geographic = Grid(12, 14, 111320.0 * np.cos(np.radians(lat)) / 1200.0, np.full(12, 92.6), 1,
                      -1, "test")
    for grid in (uniform, geographic):
        rays = sun_rays(grid, 203.7, 10.0)
        for name in GPU_ALGORITHMS:
            g.shadow_mask(rays, name)
        horizon.horizon_angles_gpu(g, rays)
        point_light.shadow_mask_gpu(g, 3.7, 20.2, 80.0, 1.5)
        point_light.shadow_mask_gpu(g, 3.7, 20.2, 80.0, pyramid=False)
        horizon.horizon_angles_gpu(g, rays, max_distance=250.0)
        # the scan in windows (run.horizon_windows): a region's rays through a window on the device
        m = horizon.Marches(z[2:6, 3:9], (2, 6, 3, 9), rays, z.shape, 50.0)
        m.march(horizon.ScanWindow(z[0:8].copy(), (0, 8, 0, 14), z.shape, True, gpu.GpuDem))
    # dynamic terrain: a window of new heights put into place (GpuDem.update)
    g.update(2, 3, z[2:5, 3:7] + 1.0)
    # per-cell suns (algorithms.subsolar): the frames of a geographic lunar grid, curved rays
    from hillshade_rt.algorithms import subsolar
    f32 = np.float32
    frames = tuple(g.upload(np.full(z.shape, v, f32)) for v in (0.5, 0.866, 0.2, 0.98, 1.0, 0.0))
    subsolar.shadow_mask_gpu(g, frames, geographic, 1737400.0, 0.0, (1e11, 2e10, 5e10), 0.0)
    subsolar.soft_fraction_gpu(g, frames, geographic, 1737400.0, 0.0, (1e11, 2e10, 5e10), 0.27,
                               0.0)
    out = {}
    for (name, _), ptx in compiled.items():
        prev = out.get(name, {"ptx_bytes": 0, "fma": 0})
        out[name] = {"ptx_bytes": max(prev["ptx_bytes"], len(ptx)),
                     "fma": max(prev["fma"], len(re.findall(r"\bfma\.rn\.f64", ptx)))}
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
