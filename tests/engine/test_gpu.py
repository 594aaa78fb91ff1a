"""The CUDA backend: the same masks as the CPU for every algorithm.

These run on numba's CUDA simulator (conftest sets NUMBA_ENABLE_CUDASIM=1 unless the environment
says otherwise), which executes the kernels as Python, thread by thread: the grids are small. On
a machine with a GPU, ``NUMBA_ENABLE_CUDASIM=0`` runs them on the device. Sizes and suns are
chosen so that the algorithms' special cases are met: voids, rays that leave the raster, the
axes and diagonals, non-special azimuths where sweep differs from brute.
"""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from hillshade_rt.engine import gpu
from hillshade_rt.algorithms import ALGORITHMS, GPU_ALGORITHMS, horizon
from hillshade_rt.errors import HillshadeError
from hillshade_rt.model.geometry import Grid, sun_rays
from hillshade_rt.testing import box_terrain, fractal_terrain, read_band, write_geotiff

AZIMUTHS = (0.0, 45.0, 90.0, 135.0, 163.0, 203.7, 270.0, 315.0)


def _terrain(rows=17, cols=21, seed=5):
    z = fractal_terrain(rows, cols, seed, relief=150.0, octaves=4)
    z[6:8, 9:11] = np.nan          # a void inside
    z[0, 3] = np.nan               # and one on the edge
    return z


@pytest.fixture(scope="module")
def dem():
    z = _terrain()
    return z, gpu.GpuDem(z)


def test_backend_is_there():
    ok, what = gpu.status()
    assert ok, what


@pytest.mark.parametrize("algorithm", [pytest.param(a, marks=pytest.mark.slow)
                                       if a in ("smap", "sweep") else a
                                       for a in sorted(GPU_ALGORITHMS)])
@pytest.mark.parametrize("elevation", [4.0, 25.0])
def test_gpu_mask_equals_cpu(dem, algorithm, elevation):
    z, g = dem
    grid = Grid.uniform(*z.shape, 30.0, 20.0)   # rectangular cells: s is not 1 on the diagonals
    differs_from_brute = 0
    for az in AZIMUTHS:
        rays = sun_rays(grid, az, elevation)
        cpu = ALGORITHMS[algorithm](z, rays, g.zmax, None)
        out = g.shadow_mask(rays, algorithm)
        assert out.dtype == np.uint8 and out.shape == z.shape
        np.testing.assert_array_equal(out, cpu, err_msg=f"{algorithm} az {az} el {elevation}")
        differs_from_brute += int((cpu != ALGORITHMS["brute"](z, rays, g.zmax, None)).sum())
        assert (out == 1).any() and (out == 0).any()
    if algorithm == "brute":
        assert differs_from_brute == 0


def test_sweep_gpu_is_the_sweep_not_brute():
    """Where the sweep's interpolation errs, the GPU errs the same way: it runs the sweep."""
    z = fractal_terrain(19, 23, 3, 30.0, 4)
    z[5:7, 8:10] = np.nan
    g = gpu.GpuDem(z)
    grid = Grid.uniform(19, 23, 1.0)
    seen = 0
    for az, el in ((163.0, 5.0), (203.7, 20.0)):
        rays = sun_rays(grid, az, el)
        cpu = ALGORITHMS["sweep"](z, rays, g.zmax, None, exact_steps=2)
        out = g.shadow_mask(rays, "sweep", exact_steps=2)
        np.testing.assert_array_equal(out, cpu)
        seen += int((out != ALGORITHMS["brute"](z, rays, g.zmax, None)).sum())
    assert seen > 0   # these suns are chosen where sweep K=2 differs from brute


@pytest.mark.slow
def test_geographic_rays_per_row():
    """Per-row spacing (a geographic CRS): brute, horizon, sweep (and smap via brute) on GPU."""
    z = _terrain(15, 19, seed=8)
    lat = np.linspace(61.0, 59.0, 15)
    dx = 111320.0 * np.cos(np.radians(lat)) / 1200.0
    grid = Grid(15, 19, dx, np.full(15, 92.6), 1, -1, "test")
    g = gpu.GpuDem(z)
    for az in (45.0, 203.7):
        rays = sun_rays(grid, az, 6.0)
        assert len(set(np.round(rays.step_other, 9))) > 1
        for algorithm in ("brute", "horizon", "sweep", "smap"):
            np.testing.assert_array_equal(g.shadow_mask(rays, algorithm),
                                          ALGORITHMS[algorithm](z, rays, g.zmax, None),
                                          err_msg=f"{algorithm} az {az}")


@pytest.mark.slow
def test_box_on_gpu_casts_the_analytic_shadow():
    """A 10 m box on flat ground, sun at 163 deg / 30 deg, 1 m cells: the shadow reaches
    h / tan(e) = 17.3 m beyond the box along the sun's direction (north-north-west of it)."""
    z = box_terrain(26, 24, h=10.0, r0=20, r1=23, c0=14, c1=17)
    g = gpu.GpuDem(z)
    rays = sun_rays(Grid.uniform(26, 24, 1.0), 163.0, 30.0)
    for algorithm in ("brute", "smap", "horizon", "sweep"):
        m = g.shadow_mask(rays, algorithm)
        np.testing.assert_array_equal(m, ALGORITHMS[algorithm](z, rays, 10.0, None))
        rr, cc = np.nonzero((m == 1) & (z == 0))
        assert (rr <= 22).all() and (cc <= 16).all()   # sun from the SSE: shadow falls NNW
        br, bc = np.nonzero(z > 0)
        gap = np.hypot(rr[:, None] - br[None, :], cc[:, None] - bc[None, :]).min(axis=1)
        length = 10.0 / np.tan(np.radians(30.0))   # 17.3 m
        assert length - 1.5 < gap.max() <= length + 0.5


def test_horizon_angles_equal_cpu(dem):
    z, g = dem
    for az in (0.0, 163.0, 315.0):
        rays = sun_rays(Grid.uniform(*z.shape, 30.0), az, 45.0)
        for sp in (1, 3):
            np.testing.assert_array_equal(horizon.horizon_angles_gpu(g, rays, "scan", sp),
                                          horizon.horizon_angles(z, rays, "scan", sp))
        # a maximum distance (issue 20): the same last step per row on both
        d_gpu, d_cpu = np.empty(z.shape, np.float32), np.empty(z.shape, np.float32)
        got = horizon.horizon_angles_gpu(g, rays, distance=d_gpu, max_distance=95.0)
        want = horizon.horizon_angles(z, rays, distance=d_cpu, max_distance=95.0)
        np.testing.assert_array_equal(got, want)
        np.testing.assert_array_equal(d_gpu, d_cpu)
        assert (got != horizon.horizon_angles(z, rays)).any()
    with pytest.raises(HillshadeError, match="hull"):
        horizon.horizon_angles_gpu(g, rays, "hull")


@pytest.mark.slow
def test_horizon_windows_equal_cpu(dem):
    """The scan in windows (run.horizon_windows): a region's rays carried through windows on the device
    give the CPU's state and angles, which are the march in memory's."""
    z, _ = dem
    rows, cols = z.shape
    grid = Grid.uniform(rows, cols, 30.0, 20.0)
    wins = [(0, 10, 0, 12), (9, rows, 0, 12), (0, 10, 11, cols), (9, rows, 11, cols)]
    for az in (163.0, 290.0):
        rays = sun_rays(grid, az, 45.0, 1e-7)
        out = {}
        for name, dev in (("cpu", None), ("gpu", gpu.GpuDem)):
            m = horizon.Marches(z[4:12, 5:15], (4, 12, 5, 15), rays, z.shape,
                                float(np.nanmax(z)), max_distance=150.0)
            for _ in range(6):
                for w in wins:
                    m.march(horizon.ScanWindow(np.ascontiguousarray(z[w[0]:w[1], w[2]:w[3]]),
                                               w, z.shape, True, dev))
            assert not m.open().any()
            out[name] = (m.angles(), m.kbest.copy())
        np.testing.assert_array_equal(out["gpu"][0], out["cpu"][0])
        np.testing.assert_array_equal(out["gpu"][1], out["cpu"][1])
        want = horizon.horizon_angles(z, rays, max_distance=150.0)[4:12, 5:15]
        np.testing.assert_array_equal(out["cpu"][0], want)


@pytest.mark.slow
def test_dem_stays_on_the_device():
    z = fractal_terrain(48, 40, 2, 20.0, 3)
    g = gpu.GpuDem(z)
    after_upload = g.stats["h2d_bytes"]
    assert after_upload == z.nbytes
    rays = sun_rays(Grid.uniform(48, 40, 10.0), 203.7, 12.0)
    g.shadow_mask(rays, "brute")
    first = g.stats["h2d_bytes"] - after_upload   # the rays and, once, the max-height pyramid
    assert 0 < first < z.nbytes
    g.shadow_mask(sun_rays(Grid.uniform(48, 40, 10.0), 20.0, 12.0), "brute")
    per_sun = g.stats["h2d_bytes"] - after_upload - first
    assert 0 < per_sun < z.nbytes / 2          # the rays only, not the heights or the pyramid
    assert g.stats["d2h_bytes"] == 2 * z.size  # one uint8 mask back per sun
    for az in (10.0, 100.0, 250.0):
        g.shadow_mask(sun_rays(Grid.uniform(48, 40, 10.0), az, 12.0), "brute")
    assert g.stats["h2d_bytes"] == after_upload + first + 4 * per_sun
    assert g.stats["d2h_bytes"] == 5 * z.size


def test_all_void_and_zenith():
    g = gpu.GpuDem(np.full((5, 6), np.nan, np.float32))
    rays = sun_rays(Grid.uniform(5, 6, 1.0), 100.0, 30.0)
    for algorithm in GPU_ALGORITHMS:
        assert (g.shadow_mask(rays, algorithm) == 255).all()
    z = fractal_terrain(9, 8, 1, 10.0, 2)
    g = gpu.GpuDem(z)
    rays = sun_rays(Grid.uniform(9, 8, 1.0), 100.0, 90.0)
    for algorithm in GPU_ALGORITHMS:
        assert (g.shadow_mask(rays, algorithm) == 0).all(), algorithm


def test_unsupported_options_are_refused():
    g = gpu.GpuDem(fractal_terrain(6, 6, 1, 5.0, 2))
    rays = sun_rays(Grid.uniform(6, 6, 1.0), 100.0, 30.0)
    with pytest.raises(HillshadeError, match="better-nextv"):
        g.shadow_mask(rays, "smap", better_nextv=True)
    with pytest.raises(HillshadeError, match="hull"):
        g.shadow_mask(rays, "horizon", method="hull")


def test_out_of_memory_is_a_clear_error(monkeypatch):
    g = gpu.GpuDem(fractal_terrain(6, 6, 1, 5.0, 2))

    class Ctx:
        def get_memory_info(self):
            return 100 * 2**20, 80 * 2**30

    monkeypatch.setattr(g, "simulator", False)
    monkeypatch.setattr(g.cuda, "current_context", lambda: Ctx(), raising=False)
    with pytest.raises(HillshadeError, match=r"GPU out of memory: .* 0\.10 GiB free"):
        g.check_memory(13 * 8192 * 8192)
    g.check_memory(13 * 1024 * 1024)   # fits


# ------------------------------------------------------------------------------------------
# the command line

def _tile(tmp_path, rows=14, cols=18):
    from affine import Affine
    z = fractal_terrain(rows, cols, 4, 40.0, 3)
    return write_geotiff(tmp_path / "dem.tif", z, transform=Affine(30, 0, 500000, 0, -30, 4e6),
                         crs="EPSG:32611")


@pytest.mark.parametrize("algorithm", ["smap", "sweep"])
def test_cli_gpu_equals_cpu_and_reports(tmp_path, runner, algorithm):
    from hillshade_rt.cli import cli
    dem = _tile(tmp_path)
    outs = {}
    for backend in ("cpu", "gpu"):
        out = tmp_path / f"{backend}.tif"
        rep = tmp_path / f"{backend}.json"
        res = runner.invoke(cli, ["shadow", dem, str(out), "--azimuth", "203.7", "--elevation",
                                  "9", "--algorithm", algorithm, "--backend", backend,
                                  "--report", str(rep)])
        assert res.exit_code == 0, res.output
        outs[backend] = read_band(out)
        doc = json.loads(rep.read_text())
        assert doc["backend"] == backend and doc["backend_requested"] == backend
    np.testing.assert_array_equal(outs["cpu"], outs["gpu"])
    g = doc["gpu"]
    assert g["device"].startswith("numba CUDA simulator") and g["simulator"] is True
    assert g["kernel_ms"] is None   # the simulator times nothing
    assert g["h2d_bytes"] >= 14 * 18 * 4 and 14 * 18 <= g["d2h_bytes"] <= 14 * 18 + 8  # + count
    assert "gpu (numba CUDA simulator" in res.output


def test_cli_auto_never_picks_the_simulator(tmp_path, runner):
    from hillshade_rt.cli import cli
    rep = tmp_path / "r.json"
    res = runner.invoke(cli, ["shadow", _tile(tmp_path), str(tmp_path / "o.tif"), "--azimuth",
                              "100", "--elevation", "20", "--report", str(rep)])
    assert res.exit_code == 0, res.output
    doc = json.loads(rep.read_text())
    assert doc["backend"] == "cpu" and doc["backend_requested"] == "auto" and doc["gpu"] is None


def test_cli_gpu_refuses_cpu_only_options(tmp_path, runner):
    from hillshade_rt.cli import cli
    res = runner.invoke(cli, ["shadow", _tile(tmp_path), str(tmp_path / "o.tif"), "--azimuth",
                              "100", "--elevation", "20", "--better-nextv", "--backend", "gpu"])
    assert res.exit_code == 1
    assert "better-nextv has no GPU kernel" in res.output and "--backend cpu" in res.output
    assert not (tmp_path / "o.tif").exists()


def test_cli_horizon_gpu(tmp_path, runner):
    from hillshade_rt.cli import cli
    dem = _tile(tmp_path)
    for backend in ("cpu", "gpu"):
        res = runner.invoke(cli, ["horizon", dem, str(tmp_path / f"{backend}.tif"), "--azimuth",
                                  "163", "--backend", backend])
        assert res.exit_code == 0, res.output
    np.testing.assert_array_equal(read_band(tmp_path / "cpu.tif"), read_band(tmp_path / "gpu.tif"))


@pytest.mark.parametrize("command, args", [
    # (163, not 203.7: numba's float() leaves a float32 a float32, so the model's b - a is float32
    # on the CPU and the device but float64 in the simulator, which runs plain Python: at 203.7
    # one cell of this tile differs by an ulp there, for the march in memory as well)
    ("horizon", ["--azimuth", "163", "--max-distance", "200"]),
    ("skyview", ["--directions", "6", "--openness", "negative"]),
])
def test_cli_horizon_windows_on_the_gpu(tmp_path, runner, command, args):
    """The windowed run (run.horizon_windows) marching on the device gives the CPU's run in memory."""
    from hillshade_rt.cli import cli
    dem = _tile(tmp_path)
    for name, extra in (("cpu", ["--backend", "cpu"]),
                        ("gpu", ["--backend", "gpu", "--window-size", "64"])):
        res = runner.invoke(cli, [command, dem, str(tmp_path / f"{name}.tif")] + args + extra)
        assert res.exit_code == 0, res.output
    assert "1 windows" in res.stderr
    np.testing.assert_array_equal(read_band(tmp_path / "cpu.tif"), read_band(tmp_path / "gpu.tif"))


def test_gpu_without_a_device_is_one_line(tmp_path):
    """No simulator and no visible device (CUDA_VISIBLE_DEVICES empty; here there is no driver
    either): one line naming what is missing, exit status 1, no output file."""
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="0", CUDA_VISIBLE_DEVICES="")
    out = tmp_path / "o.tif"
    p = subprocess.run([sys.executable, "-m", "hillshade_rt", "shadow", _tile(tmp_path), str(out),
                        "--azimuth", "100", "--elevation", "20", "--backend", "gpu"],
                       capture_output=True, text=True, env=env)
    assert p.returncode == 1
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hillshade-rt: error: ")
    assert "CUDA" in lines[0] or "numba-cuda" in lines[0]
    assert not out.exists()
    # auto falls back to the CPU in the same environment
    p = subprocess.run([sys.executable, "-m", "hillshade_rt", "shadow", _tile(tmp_path), str(out),
                        "--azimuth", "100", "--elevation", "20"], capture_output=True, text=True,
                       env=env)
    assert p.returncode == 0 and "/cpu" in p.stderr


def test_missing_numba_cuda_is_named(monkeypatch):
    import numba
    monkeypatch.setitem(sys.modules, "numba.cuda", None)
    monkeypatch.delattr(numba, "cuda", raising=False)
    monkeypatch.setattr(gpu, "_STATUS", [])
    ok, what = gpu.status()
    assert not ok and "numba-cuda is not installed" in what and "hillshade-rt[gpu]" in what


@pytest.mark.slow
def test_kernels_compile_for_a_real_gpu():
    """The simulator does not type-check: compile every kernel, through the real drivers and with
    the launches' own argument types, to PTX for an H100 (numba-cuda + NVVM, no GPU needed).
    The exact decisions must contain no fused multiply-add (``raymath.madd``): with them the
    GPU would round samples differently from the CPU. (The horizon kernel's FMAs are libdevice's
    atan, on the angle output only; smap's Black pass compares with a tolerance.)"""
    env = dict(os.environ, NUMBA_ENABLE_CUDASIM="0")
    p = subprocess.run([sys.executable, os.path.join(os.path.dirname(__file__), "ptx_check.py")],
                       capture_output=True, text=True, env=env)
    assert p.returncode == 0, p.stderr[-3000:]
    kernels = json.loads(p.stdout.strip().splitlines()[-1])
    assert set(kernels) == {"_brute_gpu", "_mask_gpu", "_colour_gpu", "_nextv_pass_gpu",
                            "_scan_gpu", "_sweep_gpu", "canonical_copy_gpu", "_span_gpu",
                            "_point_gpu", "_subsolar_gpu", "_soft_gpu", "paste_gpu"}
    assert all(k["ptx_bytes"] > 1000 for k in kernels.values())
    for name in ("_brute_gpu", "_mask_gpu", "_sweep_gpu", "_nextv_pass_gpu", "_point_gpu",
                 "_subsolar_gpu"):
        assert kernels[name]["fma"] == 0, name


@pytest.mark.slow
def test_gpu_curvature_soft_and_tiles_equal_cpu():
    """Earth curvature (brute and the horizon scan march the curved ray on the device), soft
    shadows (horizon angles on the device) and a per-tile sun, through the Shader, GPU vs CPU."""
    from hillshade_rt.engine.shader import Shader, render
    from hillshade_rt.model.sun import Region, SunOver

    z = fractal_terrain(16, 18, 7, relief=2000.0)
    z[4, 5] = np.nan
    grid = Grid.uniform(16, 18, 900.0)
    tiles = SunOver(None, 203.7, 4.0, tiles=[
        Region(slice(0, 8), slice(0, 18), 203.7, 4.0),
        Region(slice(8, 16), slice(0, 18), 201.9, 3.5)])
    for algorithm in ("brute", "smap", "horizon"):
        for sun in (SunOver(None, 163.0, 3.0), tiles):
            cpu = Shader(z, grid, algorithm, backend="cpu", curvature=True)
            dev = Shader(z, grid, algorithm, backend="gpu", curvature=True)
            want = render(cpu, sun, "shadow")
            np.testing.assert_array_equal(render(dev, sun, "shadow"), want)
            assert (want == 1).any() and (want == 0).any()
            assert cpu.report()["applied"] and dev.report()["applied"]
    sun = SunOver(None, 163.0, 3.0)
    np.testing.assert_allclose(render(Shader(z, grid, backend="gpu", curvature=True), sun,
                                      "shadow", soft=True),
                               render(Shader(z, grid, curvature=True), sun, "shadow", soft=True),
                               atol=1e-6)


@pytest.mark.slow
def test_pyramid_march_on_the_gpu_equals_the_plain_march():
    """Issue 18: the GPU kernel marches over the max-height pyramid (built and uploaded once per
    DEM) and gives the plain march's mask: rough terrain with voids, per-row spacing (rows of a
    geographic grid), Earth curvature, non-special azimuths; ``pyramid=False`` on the GPU is the
    plain march too."""
    from hillshade_rt.algorithms import brute
    from hillshade_rt.model.geometry import curvature_per_m2
    rng = np.random.default_rng(3)
    z = (rng.random((20, 26)) * 300).astype(np.float32)
    z[5:7, 8:11] = np.nan
    grids = [Grid.uniform(20, 26, 30.0),
             Grid(20, 26, 90.0 * np.cos(np.radians(np.linspace(60, 62, 20))), np.full(20, 92.5),
                  1, -1, "per row")]
    g = gpu.GpuDem(z)
    for grid in grids:
        for az, el, curved in [(163.0, 3.0, False), (203.7, 8.0, True), (290.0, 20.0, False)]:
            rays = sun_rays(grid, az, el, curvature_per_m2(2e4, 0.13) if curved else 0.0)
            ref = brute.shadow_mask(z, rays, pyramid=False)
            np.testing.assert_array_equal(brute.shadow_mask_gpu(g, rays, g.zmax), ref)
            np.testing.assert_array_equal(brute.shadow_mask_gpu(g, rays, g.zmax, pyramid=False),
                                          ref)
            np.testing.assert_array_equal(g.shadow_mask(rays, "auto"), ref)
    assert g._pyramid is not None and g.pyramid_args() is g.pyramid_args()   # uploaded once


@pytest.mark.slow
@pytest.mark.parametrize("pyramid", [True, False])
def test_point_light_gpu_equals_cpu(pyramid):
    """The point light's CUDA kernel (one per-cell body with the CPU's): the same mask on a small
    DEM with voids, for lights high, low (descending rays), off the raster, with a lift; and
    arrays.point_light_mask(backend="gpu") is that kernel."""
    from hillshade_rt.algorithms import point_light
    from hillshade_rt.algorithms.horizon import bilinear
    from hillshade_rt.engine.arrays import point_light_mask
    z = _terrain(19, 23, seed=8)
    g = gpu.GpuDem(z)
    lights = [(9.3, 11.6, 400.0), (4.2, 17.5, float(bilinear(z, 4.2, 17.5)) + 3.0),
              (-6.1, 30.7, 120.0), (25.4, -3.3, 60.0)]
    for light in lights:
        for lift in (0.0, 2.0):
            cpu = point_light.shadow_mask(z, *light, lift=lift, pyramid=pyramid)
            out = point_light.shadow_mask_gpu(g, *light, lift=lift, pyramid=pyramid)
            np.testing.assert_array_equal(out, cpu, err_msg=f"{light} lift {lift}")
    for light in lights[1:3]:           # a window with its halo, the raster's arithmetic
        h = point_light.halo((0, 8, 12, 23), light[0], light[1], z.shape)
        w = np.ascontiguousarray(z[h[0]:h[1], h[2]:h[3]])
        out = point_light.shadow_mask_gpu(gpu.GpuDem(w), *light, pyramid=pyramid, origin=(h[0], h[2]),
                                    shape=z.shape)
        np.testing.assert_array_equal(out, point_light.shadow_mask(w, *light, pyramid=pyramid,
                                                             origin=(h[0], h[2]), shape=z.shape))
    stats = {}
    got = point_light_mask(z, 17.5, 4.2, lights[1][2], backend="gpu", stats=stats)
    np.testing.assert_array_equal(got, point_light.shadow_mask(z, 4.2, 17.5, lights[1][2]))
    assert stats["backend"] == "gpu" and (got == 1).any() and (got == 0).any()
