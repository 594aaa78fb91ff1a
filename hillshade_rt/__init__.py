"""hillshade-rt: terrain cast-shadow masks from DEMs.

The public names are imported when first used (PEP 562): ``import hillshade_rt`` and the command
line start without loading numpy, numba or GDAL, so that the command line can take over SIGINT,
SIGTERM and SIGHUP before any of that work begins (``cli.errors.OneLineErrors.main``).
"""

from ._lazy import lazy_names

__version__ = "0.1.0"

_EXPORTS = {"HillshadeError": "errors", "Grid": "geometry", "sun_rays": "geometry",
            "Dem": "io", "read_dem": "io", "shadow_mask": "arrays", "horizon_angles": "arrays",
            "is_shadowed": "arrays", "sky_view": "arrays", "horizon_profile": "arrays",
            "sun_at_points": "arrays",
            "Shader": "shading", "render": "shading",
            "solar_position": "sun", "parse_time": "sun", "sun_over": "sun", "shade": "api",
            "animate": "api"}

__all__ = list(_EXPORTS) + ["__version__"]


__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())
