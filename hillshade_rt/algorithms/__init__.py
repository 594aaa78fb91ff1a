"""Shadow algorithms.

Each module exposes ``shadow_mask(z, rays, zmax=None, stats=None, **options) -> uint8 mask``:
``z`` 2-D float32 heights (NaN voids, never copied), ``rays`` a ``geometry.SunRays``, ``zmax`` the
highest valid height, ``stats`` an optional dict the algorithm fills with figures for the report.

Each also has ``shadow_mask_gpu(g, rays, zmax, stats=None, **options)``, the same on the CUDA
backend, where ``g`` is a ``gpu.GpuDem`` holding the heights on the device (``GPU_ALGORITHMS``).
"""

from ._jitcache import kernel_cache

with kernel_cache():
    from . import (auto, bounds, brute, counts, field, horizon, pyramid, raymath, relief,  # noqa: F401
                   smap, sweep)

ALGORITHMS = {
    "auto": auto.shadow_mask,
    "bounds": bounds.shadow_mask,
    "brute": brute.shadow_mask,
    "smap": smap.shadow_mask,
    "horizon": horizon.shadow_mask,
    "sweep": sweep.shadow_mask,
}

GPU_ALGORITHMS = {
    "auto": auto.shadow_mask_gpu,
    "brute": brute.shadow_mask_gpu,
    "smap": smap.shadow_mask_gpu,
    "horizon": horizon.shadow_mask_gpu,
    "sweep": sweep.shadow_mask_gpu,
}


def gpu_unsupported(algorithm: str, options: dict) -> str | None:
    """Why these options cannot run on the GPU backend (None when they can)."""
    if algorithm == "bounds":
        return ("--algorithm bounds has no GPU kernel (its sweep runs line after line); "
                "--algorithm auto or brute use the pyramid march on the GPU")
    if algorithm == "smap" and options.get("better_nextv"):
        return "--better-nextv has no GPU kernel (its per-beam stacks are as long as a beam)"
    if algorithm == "horizon" and options.get("method") == "hull":
        return "--horizon-method hull has no GPU kernel (its per-line hulls are as long as a line)"
    return None
