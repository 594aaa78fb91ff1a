"""How the terrain is lit, as one value: the settings every lighting run passes whole, from the
front door (command line, ``api``, xarray, QGIS: each builds a config, the config builds this)
down to the window job and the :class:`~.shader.Shader`.

It holds what decides the product's values, and nothing about where they come from (the DEM,
the suns) or go (the outputs): the algorithm and its options, the backend that runs them, Earth
curvature and refraction, soft shadows (the sun's disc), self-shadowing (the surface facing
away), the ambient term of a hillshade and the observer's height above the ground.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Mapping

from ..errors import HillshadeError


def _frozen(options) -> Mapping:
    return MappingProxyType(dict(options or {}))


@dataclass(frozen=True, kw_only=True)
class Lighting:
    """The settings of a lighting run.

    Parameters
    ----------
    algorithm : str
        The shadow algorithm (``algorithms.lookup``: ``auto``, ``bounds``, ``brute``, ``smap``,
        ``sweep``, ``horizon`` ...).
    options : mapping
        The algorithm's options (read only).
    backend : str
        ``cpu`` or ``gpu``: the backend that runs (``engine.gpu.resolve_backend`` has decided
        ``auto``).
    curvature : bool or str
        Earth curvature: ``True``, ``False`` or ``"auto"`` (on where it changes a shadow).
    refraction_k : float or None
        Refraction coefficient (dimensionless; None: the body's default).
    soft : bool
        Soft shadows: the fraction of the sun's disc in view.
    self_shadow : bool
        Cells facing away from the sun are shadowed too.
    ambient : float
        The light of a hillshade's shadowed cells (0..1).
    lift : float
        The height of the observer above each cell, m (``--height-above-ground``).
    """

    algorithm: str = "auto"
    options: Mapping = field(default_factory=dict)
    backend: str = "cpu"
    curvature: object = "auto"
    refraction_k: float | None = None
    soft: bool = False
    self_shadow: bool = False
    ambient: float = 0.2
    lift: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "options", _frozen(self.options))
        if self.curvature is None:
            object.__setattr__(self, "curvature", "auto")
        if self.curvature not in (True, False, "auto"):
            raise HillshadeError(f"curvature must be True, False or 'auto', got "
                                 f"{self.curvature!r}")
        if self.backend not in ("cpu", "gpu"):
            raise HillshadeError(f"a run's backend is cpu or gpu (auto resolved before), got "
                                 f"{self.backend!r}")
        lift = float(self.lift)
        if not (math.isfinite(lift) and lift >= 0.0):
            raise HillshadeError(f"the height above the ground must be a number of metres "
                                 f">= 0, got {self.lift}")
        object.__setattr__(self, "lift", lift)

    def __reduce__(self):
        # picklable for Dask tasks (a mappingproxy is not): rebuilt from plain values
        return (_rebuild, (self.as_dict(),))

    def as_dict(self) -> dict:
        """The settings as plain values (the options a plain dict)."""
        return {"algorithm": self.algorithm, "options": dict(self.options),
                "backend": self.backend, "curvature": self.curvature,
                "refraction_k": self.refraction_k, "soft": self.soft,
                "self_shadow": self.self_shadow, "ambient": self.ambient, "lift": self.lift}

    def but(self, **changes) -> Lighting:
        """A copy with ``changes`` (``dataclasses.replace``)."""
        return replace(self, **changes)

    def shader(self, z, grid, *, body=None, zrange=None, **where):
        """A :class:`~.shader.Shader` of the heights ``z`` on ``grid`` lit so; ``where``: the
        Shader's other keywords (``extent_m``, ``halo_ready``, ``local_range``, ``carry``,
        ``place``, ``sun_field``, ``survey``)."""
        from .shader import Shader
        return Shader(z, grid, self.algorithm, dict(self.options), self.backend,
                      self.curvature, self.refraction_k, body, zrange, lift=self.lift, **where)


def _rebuild(values: dict) -> Lighting:
    return Lighting(**values)
