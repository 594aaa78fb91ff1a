"""The array API: shadows and horizons of heights already in memory (numpy arrays), one
function per operation."""

from __future__ import annotations

import numpy as np

from .algorithms import lookup
from .errors import HillshadeError
from .geometry import Grid, check_elevation, equal_azimuths, heights_and_grid, normalize_azimuth
from .shading import choose_backend


def _dem_parts(heights, spacing, body):
    """(float32 heights, Grid, Body) of ``heights`` (an array, or a DEM from ``read_dem``, whose
    grid and body are the defaults) and ``spacing``, which an array requires."""
    if hasattr(heights, "heights") and hasattr(heights, "grid"):
        dem = heights
        heights = dem.heights
        spacing = dem.grid if spacing is None else spacing
        if body is None:
            from .earth import dem_body
            body = dem_body(dem)
    if spacing is None:
        raise HillshadeError("give the ground spacing of the heights: a Grid (e.g. "
                             "read_dem(path).grid), d or (dx, dy) metres per cell")
    z, grid = heights_and_grid(heights, spacing)
    if body is None:
        from .earth import mean_earth
        body = mean_earth()
    return z, grid, body


def shadow_mask(heights, azimuth: float, elevation: float,
                spacing: float | tuple[float, float] | Grid | None = None,
                algorithm: str = "auto", stats: dict | None = None, backend: str = "auto", *,
                curvature="auto", refraction_k: float | None = None, body=None,
                **options) -> np.ndarray:
    """Cast-shadow mask of a DEM: uint8, 1 = shadow, 0 = lit, 255 = nodata; with the command
    line's defaults (the same mask as ``hillshade-rt shadow`` for the same DEM and sun).

    heights: 2-D array, row 0 the northern edge (NaN = nodata), or a DEM from ``read_dem``
    (then its grid and its body are the defaults). Converted to float32 once if it is not
    float32 already; a float32 array is used in place, never copied.
    azimuth, elevation: degrees (clockwise from north; above the horizon, 0 < E <= 90).
    spacing: required for an array: ground metres per cell, ``d``, ``(dx, dy)`` or a
    :class:`Grid` (per-row spacing, orientation) such as ``read_dem(...).grid``.
    algorithm: one of ``algorithms.REGISTRY``: ``auto`` (default: the fastest exact method), ``bounds``,
    ``brute`` (exact reference), ``smap`` (exact),
    ``horizon`` (exact with its default ``method="scan"``), ``sweep`` (approximate).
    stats: optional dict that receives the algorithm's figures (e.g. smap's ``black_fraction``);
    on the GPU also ``stats["gpu"]`` (device, kernel and transfer times, bytes moved).
    backend: ``"cpu"``, ``"gpu"`` or ``"auto"`` (the GPU when numba-cuda finds a CUDA device and
    the options have a GPU kernel, else the CPU). To keep a DEM on the GPU for many suns, use
    :class:`hillshade_rt.gpu.GpuDem`.
    curvature: True, False or "auto" (the default, as the command line: on when rays can run
    longer than 1 km); refraction_k: terrestrial refraction (default 0.13 on the Earth); body:
    an ``earth.Body`` (default: a DEM's from its CRS, an array's the Earth's mean sphere).
    options: passed to the algorithm (smap: ``nextv``, ``better_nextv``; horizon: ``method``,
    ``sample_spacing``; sweep: ``exact_steps``).
    """
    from .shading import Shader, render
    from .sun import SunOver
    z, grid, body = _dem_parts(heights, spacing, body)
    lookup(algorithm)     # an unknown name: the error lists the known ones
    azimuth, elevation = normalize_azimuth(azimuth), check_elevation(elevation)
    ran_on = choose_backend(backend, algorithm, options)
    if not np.isfinite(z).any():
        return np.full(z.shape, 255, dtype=np.uint8)
    shader = Shader(z, grid, algorithm, options, ran_on, curvature, refraction_k, body)
    out = render(shader, SunOver(None, azimuth, elevation), "shadow", stats=stats)
    if stats is not None and ran_on == "gpu":
        stats["gpu"] = shader.gpu_report()
    return out


def horizon_angles(heights, azimuth: float,
                   spacing: float | tuple[float, float] | Grid | None = None,
                   method: str = "scan", sample_spacing: int = 1, backend: str = "auto", *,
                   curvature="auto", refraction_k: float | None = None,
                   body=None, max_distance: float | None = None) -> np.ndarray:
    """Horizon angle (degrees, float32) of every cell toward ``azimuth``: lit by a sun at that
    azimuth iff angle <= its elevation. NaN on voids, -90 where no terrain lies ahead.
    ``method="scan"`` is exact on the model; ``"hull"`` is the faster approximation. As
    ``hillshade-rt horizon``: curvature "auto" is on for the scan of a raster more than 1 km
    across; ``max_distance`` (metres, the scan): terrain farther along a ray is ignored;
    ``heights``, ``spacing`` and ``body`` as for :func:`shadow_mask`."""
    from .algorithms import horizon as hz
    from .shading import horizon_shader
    z, grid, body = _dem_parts(heights, spacing, body)
    azimuth = normalize_azimuth(azimuth)
    ran_on = choose_backend(backend, "horizon", {"method": method})
    shader = horizon_shader(z, grid, ran_on, curvature, refraction_k, body, method)
    rays = shader.rays(grid, azimuth, 45.0)
    if ran_on == "gpu":
        from .gpu import GpuDem
        return hz.horizon_angles_gpu(GpuDem(z), rays, method, sample_spacing,
                                     max_distance=max_distance)
    return hz.horizon_angles(z, rays, method=method, sample_spacing=sample_spacing,
                             max_distance=max_distance)


def is_shadowed(heights, points, azimuth: float, elevation: float,
                spacing: float | tuple[float, float] | Grid | None = None) -> np.ndarray:
    """For 3-D points ``(row, col, height)`` in array coordinates (cell centres at whole row/col,
    heights in the DEM's units; above, on or off the terrain), whether the ray toward the sun
    passes strictly below the terrain (no curvature). Uses an SMap; build
    ``algorithms.smap.SMap`` yourself to query one sun many times."""
    from .algorithms.smap import SMap
    z, grid, _ = _dem_parts(heights, spacing, None)
    return SMap(z, azimuth, elevation, grid).is_shadowed(points)


def sky_view(heights, spacing: float | tuple[float, float] | Grid | None = None,
             directions: int = 32, definition: str = "zaksek", *, curvature="auto",
             refraction_k: float | None = None, body=None, openness: str | None = None,
             max_distance: float | None = None) -> np.ndarray:
    """Sky view factor of every cell (float32 0..1, NaN on voids) from its exact horizon in
    ``directions`` azimuths, as ``hillshade-rt skyview``: ``definition`` "zaksek" (1 - mean sin
    of the horizon elevation clipped at the horizontal) or "dozier" (cosine-weighted, from the
    tilted surface). ``openness`` "positive" or "negative": Yokoyama's openness instead
    (float32 degrees; NaN where no direction has terrain ahead). ``max_distance``: metres,
    terrain farther along a ray is ignored (Yokoyama's L). ``heights``, ``spacing``,
    ``curvature``, ``body`` as for :func:`horizon_angles`."""
    from .algorithms.skyview import definition_of, inverted, sky_view as _sky_view
    from .shading import horizon_shader
    name = definition_of(definition, openness)
    if openness is not None and definition != "zaksek":
        raise HillshadeError("openness is a product of its own: give it without definition")
    z, grid, body = _dem_parts(heights, spacing, body)
    n = int(directions)
    if n < 1:
        raise HillshadeError(f"directions must be 1 or more, got {directions}")
    from .algorithms import horizon as hz
    shader = horizon_shader(z, grid, "cpu", curvature, refraction_k, body)
    zm = np.negative(z) if inverted(name) else z    # negative openness: the horizons of -z
    pyramid = shader.pyramid(zm, True)           # one for every direction
    return _sky_view(z, grid, equal_azimuths(360.0 / n),
                     lambda a: hz.horizon_angles(zm, shader.rays(grid, a, 45.0),
                                                 pyramid=pyramid, max_distance=max_distance),
                     name)


def horizon_profile(heights, rows, cols, spacing: float | tuple[float, float] | Grid | None = None,
                    height_above_ground=0.0, step: float = 1.0, *, curvature="auto",
                    refraction_k: float | None = None, body=None):
    """Horizon profiles of points in array coordinates (fractional ``rows``, ``cols``: cell
    centres at whole numbers), the observer ``height_above_ground`` above the terrain
    interpolated bilinearly there, every ``step`` degrees clockwise from north: (azimuths,
    angles in degrees (points x azimuths; -90: nothing ahead), distances in metres (NaN:
    nothing ahead)), as ``hillshade-rt profile``. ``heights``, ``spacing``, ``curvature``,
    ``body`` as for :func:`horizon_angles`; a point outside the cell centres or on nodata is
    an error."""
    from .algorithms import horizon as hz
    z, grid, body = _dem_parts(heights, spacing, body)
    rr = np.atleast_1d(np.asarray(rows, np.float64))
    cc = np.atleast_1d(np.asarray(cols, np.float64))
    if rr.shape != cc.shape:
        raise HillshadeError("rows and cols must have the same length")
    ground = np.array([hz.bilinear(z, r, c) for r, c in zip(rr, cc)], np.float64)
    if not np.isfinite(ground).all():
        raise HillshadeError("a point lies outside the cell centres or on nodata")
    obs = ground + np.broadcast_to(np.asarray(height_above_ground, np.float64), ground.shape)
    azimuths, ang, dist, _ = observer_profiles(z, grid, rr, cc, obs, step, curvature=curvature,
                                               refraction_k=refraction_k, body=body)
    return np.array(azimuths), ang, dist


def observer_profiles(z: np.ndarray, grid: Grid, rows: np.ndarray, cols: np.ndarray,
                      observer: np.ndarray, step: float, *, curvature="auto",
                      refraction_k: float | None = None, body=None):
    """The core of :func:`horizon_profile` and ``hillshade-rt profile``, for observers already
    placed (float32 heights ``z`` on ``grid``; fractional ``rows``, ``cols``; ``observer``
    heights): (azimuths every ``step`` degrees, angles, distances, whether the rays are
    curved)."""
    from .algorithms import horizon as hz
    from .shading import horizon_shader
    if not (0.0 < step <= 90.0):
        raise HillshadeError(f"step must be in (0, 90] degrees, got {step}")
    azimuths = equal_azimuths(step)
    shader = horizon_shader(z, grid, "cpu", curvature, refraction_k, body)
    rays = [shader.rays(grid, a, 45.0) for a in azimuths]
    ang, dist = hz.profile(z, rows, cols, observer, rays,
                           max(float(np.nanmax(z)), float(np.max(observer))))
    return azimuths, ang, dist, bool(shader.curvature)
