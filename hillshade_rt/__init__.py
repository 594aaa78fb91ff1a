"""hillshade-rt: terrain cast-shadow masks from DEMs."""

__version__ = "0.1.0"

from .errors import HillshadeError  # noqa: E402
from .geometry import Grid, sun_rays  # noqa: E402
from .io import Dem, read_dem  # noqa: E402
from .shadow import horizon_angles, is_shadowed, shadow_mask  # noqa: E402
from .engine import Shader, render  # noqa: E402
from .sun import parse_time, solar_position, sun_over  # noqa: E402
from .api import shade  # noqa: E402

__all__ = ["HillshadeError", "Grid", "sun_rays", "Dem", "read_dem", "shadow_mask", "horizon_angles",
           "is_shadowed", "Shader", "render", "solar_position", "parse_time", "sun_over",
           "shade", "__version__"]
