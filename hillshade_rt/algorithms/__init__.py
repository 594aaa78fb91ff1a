"""Shadow algorithms. Each module exposes ``shadow_mask(z, rays, zmax=None) -> uint8 mask``."""

from . import brute

ALGORITHMS = {
    "brute": brute.shadow_mask,
}
