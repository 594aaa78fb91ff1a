"""Shadow algorithms.

Each module exposes ``shadow_mask(z, rays, zmax=None, stats=None, **options) -> uint8 mask``:
``z`` 2-D float32 heights (NaN voids, never copied), ``rays`` a ``geometry.SunRays``, ``zmax`` the
highest valid height, ``stats`` an optional dict the algorithm fills with figures for the report.
"""

from ._jitcache import kernel_cache

with kernel_cache():
    from . import brute, horizon, raymath, smap, sweep  # noqa: F401

ALGORITHMS = {
    "brute": brute.shadow_mask,
    "smap": smap.shadow_mask,
    "horizon": horizon.shadow_mask,
    "sweep": sweep.shadow_mask,
}
