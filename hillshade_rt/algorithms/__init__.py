"""Shadow algorithms. Each module exposes ``shadow_mask(z, rays, zmax=None) -> uint8 mask``."""

from ._jitcache import kernel_cache

with kernel_cache():
    from . import brute, raymath  # noqa: F401

ALGORITHMS = {
    "brute": brute.shadow_mask,
}
