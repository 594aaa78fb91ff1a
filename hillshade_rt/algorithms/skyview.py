"""The sky view factor of every cell from its horizon angles in N directions (the definitions:
``run.skyview``'s docstring): Zakšek's 1 - mean sin γ, and Dozier & Frew's cosine-weighted view
from the tilted surface. Numpy over whole rasters, one direction's angles at a time."""

from __future__ import annotations

import numpy as np

DEFINITIONS = ("zaksek", "dozier")


def sky_view(z, grid, azimuths, angles_of, definition: str) -> np.ndarray:
    """The sky view factor (float32, NaN on voids) from ``angles_of(azimuth)`` (horizon
    elevation in degrees per cell, NaN on voids, -90 with nothing ahead) at each azimuth."""
    from .relief import incidence
    acc = np.zeros(z.shape, np.float64)
    cos_s = incidence(z, grid, 0.0, 90.0).astype(np.float64) if definition == "dozier" else None
    for a in azimuths:
        g = np.radians(np.maximum(angles_of(a).astype(np.float64), 0.0))   # NaN stays NaN
        if definition == "zaksek":
            acc += np.sin(g)
        else:
            # sin S cos(φ - A): the normal's horizontal part along φ (incidence of a sun on
            # the horizon at azimuth φ)
            sc = incidence(z, grid, a, 0.0).astype(np.float64)
            h = np.pi / 2.0 - g
            acc += cos_s * np.cos(g) ** 2 + sc * (h - np.sin(h) * np.cos(h))
    n = len(azimuths)
    out = (1.0 - acc / n) if definition == "zaksek" else acc / n
    return out.astype(np.float32)
