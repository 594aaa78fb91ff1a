"""hillshade-rt: terrain cast-shadow masks from DEMs.

The public names are imported when first used (PEP 562): ``import hillshade_rt`` and the command
line start without loading numpy, numba or GDAL, so that the command line can take over SIGINT,
SIGTERM and SIGHUP before any of that work begins (``cli.errors.OneLineErrors.main``).
"""

from ._lazy import lazy_names

__version__ = "0.1.0"

_EXPORTS = {"HillshadeError": "errors", "Grid": "model.geometry", "sun_rays": "model.geometry",
            "solar_position": "model.solar", "parse_time": "model.times", "sun_over": "model.sun",
            "Dem": "io", "read_dem": "io",
            "shadow_mask": "engine.arrays", "horizon_angles": "engine.arrays",
            "is_shadowed": "engine.arrays", "sky_view": "engine.arrays",
            "horizon_profile": "engine.arrays", "sun_at_points": "engine.arrays",
            "Shader": "engine.shader", "render": "engine.shader",
            "shade": "api", "irradiance": "api", "animate": "api",
            "sun_hours": "api", "horizon": "api"}

__all__ = list(_EXPORTS) + ["__version__"]


__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())
