"""hillshade-rt: terrain cast-shadow masks from DEMs."""

__version__ = "0.1.0"

from .errors import HillshadeError  # noqa: E402
from .geometry import Grid, sun_rays  # noqa: E402
from .io import Dem, read_dem  # noqa: E402
from .shadow import horizon_angles, is_shadowed, shadow_mask  # noqa: E402

__all__ = ["HillshadeError", "Grid", "sun_rays", "Dem", "read_dem", "shadow_mask", "horizon_angles",
           "is_shadowed", "__version__"]
