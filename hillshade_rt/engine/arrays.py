"""The array API: shadows and horizons of heights already in memory (numpy arrays), one
function per operation.

Units throughout: heights and distances in metres, angles in degrees (azimuths clockwise from
the raster's north), irradiance in W/m² (Wh/m² summed over hours).
"""

from __future__ import annotations

import math

import numpy as np

from ..algorithms import lookup
from ..errors import AllNodata, HillshadeError
from ..model.geometry import (
    Grid, check_elevation, equal_azimuths, heights_and_grid, normalize_azimuth
)
from .shader import choose_backend


def _dem_parts(heights, spacing, body):
    """(float32 heights, Grid, Body) of ``heights`` (an array, or a DEM from ``read_dem``, whose
    grid and body are the defaults) and ``spacing``, which an array requires."""
    if hasattr(heights, "heights") and hasattr(heights, "grid"):
        dem = heights
        heights = dem.heights
        spacing = dem.grid if spacing is None else spacing
        if body is None:
            from ..model.earth import dem_body
            body = dem_body(dem)
    if spacing is None:
        raise HillshadeError("give the ground spacing of the heights: a Grid (e.g. "
                             "read_dem(path).grid), d or (dx, dy) metres per cell")
    z, grid = heights_and_grid(heights, spacing)
    if body is None:
        from ..model.earth import mean_earth
        body = mean_earth()
    return z, grid, body


def shadow_mask(heights, azimuth: float, elevation: float,
                spacing: float | tuple[float, float] | Grid | None = None,
                algorithm: str = "auto", stats: dict | None = None, backend: str = "auto", *,
                curvature="auto", refraction_k: float | None = None, body=None,
                height_above_ground: float = 0.0, **options) -> np.ndarray:
    """Cast-shadow mask of a DEM, as ``hillshade-rt shadow`` gives it.

    With the command line's defaults: the same mask as ``hillshade-rt shadow`` for the same DEM
    and sun.

    Parameters
    ----------
    heights : numpy.ndarray or Dem
        2-D heights in metres (row 0 the northern edge, NaN nodata), or a DEM from
        :func:`~hillshade_rt.io.read_dem` (its grid and its body are then the defaults).
        Converted to float32 once if it is not float32 already; a float32 array is used in
        place, never copied.
    azimuth : float
        Sun azimuth, degrees clockwise from the raster's north (any real value wraps).
    elevation : float
        Sun elevation above the horizon, degrees, 0 < elevation <= 90.
    spacing : float, (float, float) or Grid, optional
        Required for an array: the ground spacing, metres per cell ``d``, ``(dx, dy)`` metres,
        or a :class:`~hillshade_rt.model.geometry.Grid` (per-row spacing, orientation) such as
        ``read_dem(...).grid``.
    algorithm : str, default "auto"
        One of ``algorithms.REGISTRY``: ``auto`` (the fastest exact method), ``bounds``,
        ``brute`` (the exact reference), ``smap`` (exact), ``horizon`` (exact with its default
        ``method="scan"``), ``sweep`` (approximate).
    stats : dict, optional
        Receives the algorithm's figures (e.g. smap's ``black_fraction``); on the GPU also
        ``stats["gpu"]`` (device, ``kernel_ms`` and ``transfer_ms`` in milliseconds, bytes moved).
    backend : {"auto", "cpu", "gpu"}, default "auto"
        ``auto``: the GPU when numba-cuda finds a CUDA device and the options have a GPU
        kernel, else the CPU.
        To keep a DEM on the GPU for many suns, use :class:`hillshade_rt.engine.gpu.GpuDem`.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto`` (as the command line): on when rays can run
        longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on
        other bodies.
    body : earth.Body, optional
        The body the DEM lies on (its radius of curvature, metres); default a DEM's from its
        CRS, an array's the Earth's mean sphere.
    height_above_ground : float, default 0.0
        Metres (>= 0) above every cell that its ray starts from, as ``--height-above-ground``.
        ``auto`` then runs brute; another algorithm is an error.
    **options
        Passed to the algorithm (smap: ``nextv``, ``better_nextv``; horizon: ``method``,
        ``sample_spacing``; sweep: ``exact_steps``).

    Returns
    -------
    numpy.ndarray
        uint8, the heights' shape: 1 shadow, 0 lit, 255 nodata (all 255 when every height is
        nodata).

    Raises
    ------
    HillshadeError
        No spacing for an array, an unknown algorithm or option, an elevation outside (0, 90],
        a non-finite azimuth, ``backend="gpu"`` without a GPU kernel for the options, a negative
        height above the ground.
    """
    from .shader import Shader, render
    from ..model.sun import SunOver
    z, grid, body = _dem_parts(heights, spacing, body)
    lookup(algorithm)     # an unknown name: the error lists the known ones
    azimuth, elevation = normalize_azimuth(azimuth), check_elevation(elevation)
    ran_on = choose_backend(backend, algorithm, options)
    if not np.isfinite(z).any():
        return np.full(z.shape, 255, dtype=np.uint8)
    shader = Shader(z, grid, algorithm, options, ran_on, curvature, refraction_k, body,
                    lift=height_above_ground)
    out = render(shader, SunOver(None, azimuth, elevation), "shadow", stats=stats)
    if stats is not None and ran_on == "gpu":
        stats["gpu"] = shader.gpu_report()
    return out


def horizon_angles(heights, azimuth: float,
                   spacing: float | tuple[float, float] | Grid | None = None,
                   method: str = "scan", sample_spacing: int = 1, backend: str = "auto", *,
                   curvature="auto", refraction_k: float | None = None,
                   body=None, max_distance: float | None = None,
                   height_above_ground: float = 0.0) -> np.ndarray:
    """Horizon angle of every cell toward ``azimuth``, as ``hillshade-rt horizon``.

    A cell is lit by a sun at that azimuth iff its angle <= the sun's elevation.

    Parameters
    ----------
    heights : numpy.ndarray or Dem
        2-D heights in metres (row 0 the northern edge, NaN nodata), or a DEM from
        :func:`~hillshade_rt.io.read_dem` (its grid and its body are then the defaults).
        Converted to float32 once if it is not float32 already; a float32 array is used in
        place, never copied.
    azimuth : float
        Degrees clockwise from the raster's north (any real value wraps).
    spacing : float, (float, float) or Grid, optional
        Required for an array: the ground spacing, metres per cell ``d``, ``(dx, dy)`` metres,
        or a :class:`~hillshade_rt.model.geometry.Grid` (per-row spacing, orientation) such as
        ``read_dem(...).grid``.
    method : {"scan", "hull"}, default "scan"
        ``scan`` is exact on the model; ``hull`` is the faster approximation.
    sample_spacing : int, default 1
        The scan takes every n-th sample only (n > 1: faster, approximate).
    backend : {"auto", "cpu", "gpu"}, default "auto"
        ``auto``: the GPU when numba-cuda finds a CUDA device and the options have a GPU
        kernel, else the CPU.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto``: on for the scan of a raster more than 1 km
        across.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on
        other bodies.
    body : earth.Body, optional
        The body the DEM lies on (its radius of curvature, metres); default a DEM's from its
        CRS, an array's the Earth's mean sphere.
    max_distance : float, optional
        Metres of ground distance (the scan): terrain farther along a ray is ignored.
    height_above_ground : float, default 0.0
        Metres (>= 0): the horizon seen from that high above each cell.

    Returns
    -------
    numpy.ndarray
        float32 degrees above the horizontal, the heights' shape; NaN on voids, -90 where no
        terrain lies ahead.

    Raises
    ------
    HillshadeError
        No spacing for an array, a non-finite azimuth, a negative height above the ground.
    """
    from ..algorithms import horizon as hz
    from .shader import horizon_shader
    z, grid, body = _dem_parts(heights, spacing, body)
    azimuth = normalize_azimuth(azimuth)
    lift = _lift(height_above_ground)
    ran_on = choose_backend(backend, "horizon", {"method": method})
    shader = horizon_shader(z, grid, ran_on, curvature, refraction_k, body, method)
    rays = shader.rays(grid, azimuth, 45.0)
    if ran_on == "gpu":
        from .gpu import GpuDem
        return hz.horizon_angles_gpu(GpuDem(z), rays, method, sample_spacing,
                                     max_distance=max_distance, lift=lift)
    return hz.horizon_angles(z, rays, method=method, sample_spacing=sample_spacing,
                             max_distance=max_distance, lift=lift)


def _lift(height_above_ground) -> float:
    """``height_above_ground`` checked: finite metres >= 0."""
    h = float(height_above_ground)
    if not (np.isfinite(h) and h >= 0.0):
        raise HillshadeError(f"height_above_ground must be finite metres >= 0, got "
                             f"{height_above_ground}")
    return h


def is_shadowed(heights, points, azimuth: float, elevation: float,
                spacing: float | tuple[float, float] | Grid | None = None) -> np.ndarray:
    """Whether the ray toward the sun from each of some 3-D points passes below the terrain.

    The ray passes strictly below the terrain (no curvature). Uses an SMap; build
    ``algorithms.smap.SMap`` yourself to query one sun many times.

    Parameters
    ----------
    heights : numpy.ndarray or Dem
        2-D heights in metres (row 0 the northern edge, NaN nodata), or a DEM from
        :func:`~hillshade_rt.io.read_dem` (its grid and its body are then the defaults).
        Converted to float32 once if it is not float32 already; a float32 array is used in
        place, never copied.
    points : array_like, shape (N, 3)
        ``(row, col, height)`` in array coordinates (cell centres at whole rows and columns),
        heights in metres (the DEM's units); above, on or off the terrain.
    azimuth : float
        Sun azimuth, degrees clockwise from the raster's north.
    elevation : float
        Sun elevation above the horizon, degrees, 0 < elevation <= 90.
    spacing : float, (float, float) or Grid, optional
        Required for an array: the ground spacing, metres per cell ``d``, ``(dx, dy)`` metres,
        or a :class:`~hillshade_rt.model.geometry.Grid` (per-row spacing, orientation) such as
        ``read_dem(...).grid``.

    Returns
    -------
    numpy.ndarray
        bool, shape (N,): True where the point is in shadow.

    Raises
    ------
    HillshadeError
        No spacing for an array, points not an (N, 3) array of finite numbers, an elevation
        outside (0, 90], a grid whose spacing varies per row (geographic CRS).
    """
    from ..algorithms.smap import SMap
    z, grid, _ = _dem_parts(heights, spacing, None)
    return SMap(z, azimuth, elevation, grid).is_shadowed(points)


def sky_view(heights, spacing: float | tuple[float, float] | Grid | None = None,
             directions: int = 32, definition: str = "zaksek", *, curvature="auto",
             refraction_k: float | None = None, body=None, openness: str | None = None,
             max_distance: float | None = None,
             height_above_ground: float = 0.0) -> np.ndarray:
    """Sky view factor (or openness) of every cell, as ``hillshade-rt skyview``.

    From each cell's exact horizon in ``directions`` azimuths.

    Parameters
    ----------
    heights : numpy.ndarray or Dem
        2-D heights in metres (row 0 the northern edge, NaN nodata), or a DEM from
        :func:`~hillshade_rt.io.read_dem` (its grid and its body are then the defaults).
        Converted to float32 once if it is not float32 already; a float32 array is used in
        place, never copied.
    spacing : float, (float, float) or Grid, optional
        Required for an array: the ground spacing, metres per cell ``d``, ``(dx, dy)`` metres,
        or a :class:`~hillshade_rt.model.geometry.Grid` (per-row spacing, orientation) such as
        ``read_dem(...).grid``.
    directions : int, default 32
        Number of azimuths, equally spaced over 360 degrees (>= 1).
    definition : {"zaksek", "dozier"}, default "zaksek"
        ``zaksek``: 1 - mean sin of the horizon elevation clipped at the horizontal (Zakšek et
        al. 2011); ``dozier``: cosine-weighted, from the tilted surface (Dozier & Frew 1990).
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto`` (as the command line): on when rays can run
        longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on
        other bodies.
    body : earth.Body, optional
        The body the DEM lies on (its radius of curvature, metres); default a DEM's from its
        CRS, an array's the Earth's mean sphere.
    openness : {"positive", "negative"}, optional
        Yokoyama's openness instead (with the default ``definition`` only).
    max_distance : float, optional
        Metres of ground distance: terrain farther along a ray is ignored (Yokoyama's L).
    height_above_ground : float, default 0.0
        Metres (>= 0): the horizons seen from that high above each cell.

    Returns
    -------
    numpy.ndarray
        float32, the heights' shape: the sky view factor (dimensionless, 0..1, NaN on voids), or
        with ``openness`` degrees (NaN where no direction has terrain ahead).

    Raises
    ------
    HillshadeError
        No spacing for an array, an unknown definition or openness, ``openness`` with
        ``definition="dozier"``, ``directions`` < 1, a negative height above the ground.
    """
    from ..algorithms.skyview import definition_of, floor_deg, inverted, sky_view as _sky_view
    from .shader import horizon_shader
    name = definition_of(definition, openness)
    if openness is not None and definition != "zaksek":
        raise HillshadeError("openness is a product of its own: give it without definition")
    z, grid, body = _dem_parts(heights, spacing, body)
    n = int(directions)
    if n < 1:
        raise HillshadeError(f"directions must be 1 or more, got {directions}")
    from ..algorithms import horizon as hz
    shader = horizon_shader(z, grid, "cpu", curvature, refraction_k, body)
    zm = np.negative(z) if inverted(name) else z    # negative openness: the horizons of -z
    pyramid = shader.pyramid(zm, True)           # one for every direction
    # the observer at z + H; over the inverted -z (negative openness) at -(z + H)
    lift = -_lift(height_above_ground) if inverted(name) else _lift(height_above_ground)
    return _sky_view(z, grid, equal_azimuths(360.0 / n),
                     lambda a: hz.horizon_angles(zm, shader.rays(grid, a, 45.0),
                                                 pyramid=pyramid, max_distance=max_distance,
                                                 floor_deg=floor_deg(name), lift=lift),
                     name)


def horizon_profile(heights, rows, cols, spacing: float | tuple[float, float] | Grid | None = None,
                    height_above_ground=0.0, step: float = 1.0, *, curvature="auto",
                    refraction_k: float | None = None, body=None):
    """Horizon profiles of points, as ``hillshade-rt profile``.

    Parameters
    ----------
    heights : numpy.ndarray or Dem
        2-D heights in metres (row 0 the northern edge, NaN nodata), or a DEM from
        :func:`~hillshade_rt.io.read_dem` (its grid and its body are then the defaults).
        Converted to float32 once if it is not float32 already; a float32 array is used in
        place, never copied.
    rows, cols : array_like
        Fractional array coordinates of the points (cell centres at whole numbers), same length.
    spacing : float, (float, float) or Grid, optional
        Required for an array: the ground spacing, metres per cell ``d``, ``(dx, dy)`` metres,
        or a :class:`~hillshade_rt.model.geometry.Grid` (per-row spacing, orientation) such as
        ``read_dem(...).grid``.
    height_above_ground : float or array_like, default 0.0
        Metres of the observer above the terrain, interpolated bilinearly at the point (one for
        all points or one per point).
    step : float, default 1.0
        Degrees between azimuths, clockwise from north, 0 < step <= 90.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto`` (as the command line): on when rays can run
        longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on
        other bodies.
    body : earth.Body, optional
        The body the DEM lies on (its radius of curvature, metres); default a DEM's from its
        CRS, an array's the Earth's mean sphere.

    Returns
    -------
    azimuths : numpy.ndarray
        Degrees clockwise from north, every ``step``.
    angles : numpy.ndarray
        Horizon elevation, degrees, points x azimuths (-90: nothing ahead).
    distances : numpy.ndarray
        Ground metres to the horizon point, points x azimuths (NaN: nothing ahead).

    Raises
    ------
    HillshadeError
        No spacing for an array, ``rows`` and ``cols`` of different lengths, a point outside the
        cell centres or on nodata, a step outside (0, 90].
    """
    from ..algorithms import horizon as hz
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
    """The core of :func:`horizon_profile` and ``hillshade-rt profile``, for placed observers.

    Parameters
    ----------
    z : numpy.ndarray
        float32 heights in metres (NaN nodata).
    grid : Grid
        Their ground geometry.
    rows, cols : numpy.ndarray
        Fractional array coordinates of the observers.
    observer : numpy.ndarray
        The observers' heights, metres (the DEM's datum).
    step : float
        Degrees between azimuths, 0 < step <= 90.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto`` (as the command line): on when rays can run
        longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on
        other bodies.
    body : earth.Body, optional
        The body the DEM lies on (its radius of curvature, metres); default a DEM's from its
        CRS, an array's the Earth's mean sphere.

    Returns
    -------
    azimuths : list of float
        Degrees clockwise from north, every ``step``.
    angles : numpy.ndarray
        Horizon elevation, degrees, observers x azimuths (-90: nothing ahead).
    distances : numpy.ndarray
        Ground metres to the horizon point (NaN: nothing ahead).
    curved : bool
        Whether the rays were curved.

    Raises
    ------
    HillshadeError
        A step outside (0, 90].
    """
    from ..algorithms import horizon as hz
    from .shader import horizon_shader
    if not (0.0 < step <= 90.0):
        raise HillshadeError(f"step must be in (0, 90] degrees, got {step}")
    azimuths = equal_azimuths(step)
    shader = horizon_shader(z, grid, "cpu", curvature, refraction_k, body)
    rays = [shader.rays(grid, a, 45.0) for a in azimuths]
    ang, dist = hz.profile(z, rows, cols, observer, rays,
                           max(float(np.nanmax(z)), float(np.max(observer))))
    return azimuths, ang, dist, bool(shader.curvature)


def ground_height(heights: np.ndarray, row: float, col: float) -> float:
    """The terrain height at a fractional (row, col) of the heights.

    Bilinear between the cell centres around it, only those with a weight (a cell centre is its
    own height, a point on the line between two centres their interpolation, whatever lies
    beside them).

    Parameters
    ----------
    heights : numpy.ndarray
        2-D heights, metres (NaN nodata).
    row, col : float
        Fractional array coordinates (cell centres at whole numbers).

    Returns
    -------
    float
        Metres; NaN outside the cell centres or where a centre it needs is nodata.
    """
    z = heights
    rows, cols = z.shape
    if not (0.0 <= row <= rows - 1 and 0.0 <= col <= cols - 1):
        return math.nan
    r0, c0 = int(math.floor(row)), int(math.floor(col))
    fr, fc = row - r0, col - c0

    def along(r):
        v = float(z[r, c0])
        return v if fc == 0.0 else v + fc * (float(z[r, c0 + 1]) - v)
    top = along(r0)
    return top if fr == 0.0 else top + fr * (along(r0 + 1) - top)


def sun_at_points(heights, rows, cols, azimuth, elevation,
                  spacing: float | tuple[float, float] | Grid | None = None,
                  height_above_ground=0.0, *, curvature="auto",
                  refraction_k: float | None = None, body=None) -> dict:
    """Whether the sun reaches observers at points, as ``hillshade-rt query``.

    For each point and each sun: the exact horizon toward the sun's azimuth (the model's march
    from the point: ``algorithms.horizon.profile``) against the sun's elevation. Curvature is
    decided for each sun as :func:`shadow_mask` decides it, so that at a cell centre with no
    height above the ground ``lit`` is the shadow mask's value for that cell (up to the rounding
    of the angle where the horizon is within ~1e-12 degrees of the sun).

    Parameters
    ----------
    heights : numpy.ndarray or Dem
        2-D heights in metres (row 0 the northern edge, NaN nodata), or a DEM from
        :func:`~hillshade_rt.io.read_dem` (its grid and its body are then the defaults).
        Converted to float32 once if it is not float32 already; a float32 array is used in
        place, never copied.
    rows, cols : array_like
        1-D fractional array coordinates of the points (cell centres at whole numbers).
    azimuth, elevation : float or array_like
        The suns, degrees: grid azimuth clockwise from north, elevation above the horizontal
        (within [-90, 90]; <= 0 is night). m suns shared by every point (scalars or 1-D), or one
        sun per point and column (2-D, points x m).
    spacing : float, (float, float) or Grid, optional
        Required for an array: the ground spacing, metres per cell ``d``, ``(dx, dy)`` metres,
        or a :class:`~hillshade_rt.model.geometry.Grid` (per-row spacing, orientation) such as
        ``read_dem(...).grid``.
    height_above_ground : float or array_like, default 0.0
        Metres (>= 0) of the observer above the terrain interpolated bilinearly at the point, one
        for all or one per point.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto`` (as the command line): on when rays can run
        longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on
        other bodies.
    body : earth.Body, optional
        The body the DEM lies on (its radius of curvature, metres); default a DEM's from its
        CRS, an array's the Earth's mean sphere.

    Returns
    -------
    dict of numpy.ndarray
        Points x suns unless said: ``azimuth``, ``elevation`` (the suns, degrees),
        ``horizon_deg`` (degrees; -90: no terrain ahead inside the raster), ``distance_m``
        (ground metres to the horizon point; NaN: none), ``margin_deg`` (elevation - horizon,
        degrees), ``lit`` (bool: the sun is up and margin >= 0: a ray that grazes the terrain is
        lit, as in the mask), ``curved`` (bool: the rays were curved), and per point ``ground_m``
        and ``observer_m`` (metres). ``pandas.DataFrame({k: v.ravel() for k, v in r.items() if
        v.ndim == 2})`` makes one row per point and sun.

    Raises
    ------
    HillshadeError
        No spacing for an array, rows and cols not 1-D of one length, suns of the wrong shape or
        not finite, an elevation outside [-90, 90], a negative height above the ground, a point
        outside the cell centres or beside nodata.
    """
    import numba

    from ..algorithms import horizon as hz
    from ..model.geometry import SunRays, ray_steps, sincos_deg, sun_rays
    from .shader import Shader
    z, grid, body = _dem_parts(heights, spacing, body)
    rr = np.atleast_1d(np.asarray(rows, np.float64))
    cc = np.atleast_1d(np.asarray(cols, np.float64))
    if rr.ndim != 1 or rr.shape != cc.shape:
        raise HillshadeError("rows and cols must be 1-D and of the same length")
    n = rr.size
    try:
        az, el = np.broadcast_arrays(np.asarray(azimuth, np.float64),
                                     np.asarray(elevation, np.float64))
    except ValueError:
        raise HillshadeError("azimuth and elevation must have the same shape") from None
    shared = az.ndim <= 1
    if shared:
        az, el = np.atleast_1d(az), np.atleast_1d(el)
    elif az.ndim != 2 or az.shape[0] != n:
        raise HillshadeError(f"one sun per point and column: azimuth and elevation must be "
                             f"{n} x m, got {az.shape}")
    if not (np.isfinite(az).all() and np.isfinite(el).all()):
        raise HillshadeError("azimuths and elevations must be finite numbers of degrees")
    if (np.abs(el) > 90.0).any():
        raise HillshadeError("elevations must be within [-90, 90] degrees")
    az = np.mod(az, 360.0)
    lift = np.broadcast_to(np.asarray(height_above_ground, np.float64), (n,))
    if not (np.isfinite(lift).all() and (lift >= 0.0).all()):
        raise HillshadeError("the height above the ground must be a number of metres >= 0")
    ground = np.array([ground_height(z, r, c) for r, c in zip(rr, cc)], np.float64)
    if not np.isfinite(ground).all():
        bad = int(np.flatnonzero(~np.isfinite(ground))[0])
        raise HillshadeError(f"point {bad} ({rr[bad]:g}, {cc[bad]:g}) lies outside the cell "
                             "centres or on nodata")
    obs = ground + lift
    # the curvature of each sun as the mask decides it (the whole raster's range and extent)
    shader = Shader(z, grid, "brute", {}, "cpu", curvature, refraction_k, body)

    def rays_of(a: float, e: float):
        """The rays of this sun (the elevation does not enter the horizon, its rays' rise is
        not used: at night any will do)."""
        return sun_rays(grid, a, e if 0.0 < e <= 90.0 else 45.0, shader.curvature_for(a, e))

    def point_rays(row: int, a: np.ndarray, e: np.ndarray) -> list:
        """The rays of the suns ``a``, ``e`` (one point's) from the cells of ``row`` (the row
        ``horizon.profile`` takes them from: the point's nearest), as ``rays_of`` makes them
        (``geometry.ray_steps``), each broadcast over the rows: one point's many suns without
        a ``sun_rays`` of the whole grid for each."""
        east, north = np.array([sincos_deg(v) for v in a]).T
        dom, sd, so, sm = ray_steps(east, north, float(grid.dx[row]), float(grid.dy[row]),
                                    grid.col_sign, grid.row_sign)
        curv = np.array([shader.curvature_for(x, y) for x, y in zip(a, e)]) * sm * sm
        rise = np.array([math.tan(math.radians(y)) if 0.0 < y < 90.0 else 1.0 for y in e]) * sm
        cols = [np.broadcast_to(v[:, None], (v.size, grid.rows))
                for v in (dom, sd, so, rise, sm, curv)]
        return [SunRays(float(a[j]), float(e[j]), *(v[j] for v in cols)) for j in range(a.size)]

    # no early exit below an observer above the highest cell (the march's bound is the highest
    # of the terrain and the observers, as ``observer_profiles``)
    zmax = max(float(np.nanmax(z)), float(np.max(obs)))
    if shared:
        rays = [rays_of(a, e) for a, e in zip(az, el)]
        ang, dist = hz.profile(z, rr, cc, obs, rays, zmax)
        az, el = (np.broadcast_to(a, (n, a.size)).copy() for a in (az, el))
        curved = np.broadcast_to([r.curved for r in rays], az.shape).copy()
    else:
        ang, dist = np.empty(az.shape), np.empty(az.shape)
        curved = np.zeros(az.shape, bool)
        near = np.clip(np.rint(rr), 0, z.shape[0] - 1).astype(np.int64)
        threads = numba.get_num_threads()
        try:    # one point per call: its rays in this thread (waking the others costs more)
            numba.set_num_threads(1)
            for i in range(n):
                rays = point_rays(int(near[i]), az[i], el[i])
                ang[i], dist[i] = (v[0] for v in hz.profile(z, rr[i:i + 1], cc[i:i + 1],
                                                            obs[i:i + 1], rays, zmax))
                curved[i] = [bool(r.curv[0] != 0.0) for r in rays]
        finally:
            numba.set_num_threads(threads)
    margin = el - ang
    return {"azimuth": az, "elevation": el, "horizon_deg": ang, "distance_m": dist,
            "margin_deg": margin, "lit": (el > 0.0) & (margin >= 0.0), "curved": curved,
            "ground_m": ground, "observer_m": obs}


def irradiance(heights, times, spacing: float | tuple[float, float] | Grid | None = None, *,
               lat: float | None = None, lon: float | None = None, weights=None,
               mean: bool = False, altitude: float | None = None, clear_sky: str = "ineichen",
               linke_turbidity: float | None = None, ghi=None, dni=None, dhi=None,
               albedo: float = 0.2, perez: bool = False, soft: bool = False,
               sky_view_directions: int = 32, algorithm: str = "auto", backend: str = "auto",
               curvature="auto", refraction_k: float | None = None, body=None,
               refraction: bool = True, pressure: float | None = None,
               temperature: float = 12.0, sun_tolerance: float | None = None,
               sky_view=None) -> dict:
    """Beam, diffuse, reflected and global irradiance on every cell, as ``hillshade-rt irradiance``.

    Formulas: ``hillshade_rt.engine.irradiance``, docs/irradiance.md.

    Parameters
    ----------
    heights : numpy.ndarray or Dem
        2-D heights in metres (row 0 the northern edge, NaN nodata), or a DEM from
        :func:`~hillshade_rt.io.read_dem` (its grid and its body are then the defaults).
        Converted to float32 once if it is not float32 already; a float32 array is used in
        place, never copied.
    times : str, datetime or sequence of them
        Aware datetimes, or ISO 8601 strings with a UTC offset.
    spacing : float, (float, float) or Grid, optional
        Required for an array: the ground spacing, metres per cell ``d``, ``(dx, dy)`` metres,
        or a :class:`~hillshade_rt.model.geometry.Grid` (per-row spacing, orientation) such as
        ``read_dem(...).grid``.
    lat, lon : float, optional
        The place, degrees (required for an array; a DEM from ``read_dem`` has its own, per tile
        on large rasters).
    weights : array_like, optional
        Hours each time stands for (>= 0, one per time, e.g. from ``times.day_samples``).
    mean : bool, default False
        With ``weights``: divide the sums by the hours (W/m²).
    altitude : float, optional
        The place's height, metres (default the centre cell's height).
    clear_sky : {"ineichen", "haurwitz"}, default "ineichen"
        pvlib's clear-sky model of the open sky.
    linke_turbidity : float, optional
        Linke turbidity (dimensionless) for ``ineichen``; None: pvlib's climatological lookup.
    ghi, dni, dhi : array_like, optional
        A measured sky instead, W/m², one value per time: ``ghi`` alone (split into DNI and DHI by
        Erbs) or with ``dni`` and ``dhi``.
    albedo : float, default 0.2
        Ground reflectance (dimensionless, 0..1).
    perez : bool, default False
        The Perez (1990) sky instead of the isotropic one.
    soft : bool, default False
        The visible fraction of the solar disk instead of hard shadows.
    sky_view_directions : int, default 32
        Azimuths of the sky view factor.
    algorithm : str, default "auto"
        As for :func:`shadow_mask`.
    backend : {"auto", "cpu", "gpu"}, default "auto"
        ``auto``: the GPU when numba-cuda finds a CUDA device and the options have a GPU
        kernel, else the CPU.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto`` (as the command line): on when rays can run
        longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on
        other bodies.
    body : earth.Body, optional
        The body the DEM lies on (its radius of curvature, metres); default a DEM's from its
        CRS, an array's the Earth's mean sphere.
    refraction : bool, default True
        Apparent sun elevation (the SPA's refraction).
    pressure : float, optional
        Air pressure, hPa (default the standard atmosphere at ``altitude``).
    temperature : float, default 12.0
        Air temperature, °C.
    sun_tolerance : float, optional
        Degrees: on a georeferenced DEM the sun is computed per tile where its direction varies
        by more than this across the raster (default 0.05).
    sky_view : numpy.ndarray, optional
        Dozier's sky view factor Vd of every cell (the heights' shape, NaN voids), e.g. the
        band ``hillshade-rt skyview --definition dozier`` wrote (-9999 as NaN), used instead
        of computing it (``sky_view_directions`` then unused); the caller sees to it that it
        was made with the same settings.

    Returns
    -------
    dict of numpy.ndarray
        float32 arrays under "beam", "diffuse", "reflected", "global" (NaN on voids). Without
        ``weights``: (times, rows, cols) stacks of W/m² at each time; with ``weights``: the sums
        of W/m² times hours, Wh/m² (``mean``: W/m²), the heights' shape.

    Raises
    ------
    HillshadeError
        No spacing for an array; no times, naive times, weights not one number of hours >= 0 per
        time, ``mean`` without weights or with no hours; ``dni``/``dhi`` without ``ghi``, ``ghi``
        not one value per time; no ``lat``/``lon`` for an array, or out of range; bad options
        (albedo, turbidity, directions, algorithm); ``sky_view`` not of the heights' shape.
    AllNodata
        Every height is nodata.
    """
    import datetime as _dt
    import math
    from . import irradiance as ir
    from .shader import Shader
    from ..model.site import Site, centre_height_of, dem_site
    from ..model.solar import Atmosphere
    from ..model.sun import DEFAULT_TOLERANCE, sun_over
    from ..model.times import parse_time
    z, grid, body = _dem_parts(heights, spacing, body)
    lookup(algorithm)
    ir.check_options(albedo, linke_turbidity, sky_view_directions)
    times = [t if isinstance(t, _dt.datetime) else parse_time(str(t), None, "time")
             for t in ([times] if isinstance(times, (str, _dt.datetime)) else times)]
    if not times:
        raise HillshadeError("no times given")
    if any(t.tzinfo is None for t in times):
        raise HillshadeError("times must be aware datetimes (with a zone or a UTC offset)")
    if weights is not None:
        weights = np.asarray(weights, np.float64)
        if weights.shape != (len(times),) or not (np.isfinite(weights).all()
                                                  and (weights >= 0).all()):
            raise HillshadeError("weights: one number of hours >= 0 per time")
    elif mean:
        raise HillshadeError("mean needs weights (the hours each time stands for)")
    if ghi is None and (dni is not None or dhi is not None):
        raise HillshadeError("dni and dhi go with ghi")
    if not np.isfinite(z).any():
        raise AllNodata("every height is nodata")
    height = altitude if altitude is not None else centre_height_of(z)[0]
    if hasattr(heights, "heights") and hasattr(heights, "crs"):
        site = dem_site(heights, lat, lon)
        if altitude is not None:
            site.height = float(altitude)
    else:
        if lat is None or lon is None:
            raise HillshadeError("give lat and lon (degrees) for heights without a CRS")
        if not (-90.0 <= lat <= 90.0) or not math.isfinite(lon):
            raise HillshadeError(f"lat must be within [-90, 90] and lon finite, got {lat}, {lon}")
        site = Site(float(lat), float((lon + 180.0) % 360.0 - 180.0), float(height), "lat/lon")
    suns = sun_over(site, z.shape, times, Atmosphere(refraction, pressure, temperature),
                    DEFAULT_TOLERANCE if sun_tolerance is None else sun_tolerance)
    zen = np.array([s.zenith for s in suns], np.float64)
    if ghi is None:
        sky = ir.clear_sky(times, zen, site.lat, site.lon, site.height, clear_sky,
                           linke_turbidity)
    else:
        sky = ir.measured_sky(times, zen, *(None if v is None else np.asarray(v, np.float64)
                                            for v in (ghi, dni, dhi)))
        if sky.ghi.shape != (len(times),):
            raise HillshadeError("ghi: one value per time")
    if perez:
        ir.with_perez(sky, times, zen)
    ran_on = choose_backend(backend, algorithm, {})
    shader = Shader(z, grid, algorithm, {}, ran_on, curvature, refraction_k, body)
    if sky_view is not None:
        vd = np.ascontiguousarray(sky_view, np.float32)
        if vd.shape != z.shape:
            raise HillshadeError(f"sky_view: shape {vd.shape}, the heights' is {z.shape}")
    from ..algorithms.irradiance import normals
    nrm = normals(z, grid)          # Horn's normals once: the sky view's and the sums'
    if sky_view is None:            # (one pyramid for the sky view and the shadows: the Shader's)
        vd = ir.dozier_view(z, grid, sky_view_directions, ran_on, curvature, refraction_k,
                            body, pyramid=shader.pyramid(z, True) if ran_on == "cpu" else None,
                            normals=nrm)
    out = ir.accumulate(shader, suns, np.ones(len(times)) if weights is None else weights, sky,
                        vd, albedo, soft=soft, perez=perez, per_time=weights is None,
                        normals=nrm)
    if mean:
        hours = float(weights.sum())
        if hours <= 0:
            raise HillshadeError("mean: the weights add up to no hours")
        out = {k: (v / np.float32(hours)).astype(np.float32) for k, v in out.items()}
    return out


def point_light_mask(heights, x: float, y: float, z: float, *,
                     height_above_ground: float = 0.0, backend: str = "auto",
                     pyramid=True, stats: dict | None = None) -> np.ndarray:
    """Cast-shadow mask of a DEM lit by a point light (``algorithms.point_light``).

    A lamp, a mast's floodlight, a near sun: each cell's ray runs straight to the light and ends
    there. A light above a cell lights it.

    Parameters
    ----------
    heights : Dem or numpy.ndarray
        A DEM from :func:`~hillshade_rt.io.read_dem` (the light in its CRS), or an array of
        heights in metres (the light in array coordinates).
    x, y : float
        The light's position: in the DEM's CRS units; for an array, ``x`` the fractional column,
        ``y`` the row (cell centres at whole numbers).
    z : float
        The light's height, metres above the DEM's datum.
    height_above_ground : float, default 0.0
        Metres (>= 0) above every cell that its ray starts from.
    backend : {"auto", "cpu", "gpu"}, default "auto"
        ``auto``: the GPU when numba-cuda finds a CUDA device and the options have a GPU
        kernel, else the CPU.
    pyramid : bool, default True
        False marches without the maximum-height pyramid (the same mask).
    stats : dict, optional
        Receives ``backend`` (and on the GPU ``gpu``: ``kernel_ms``, ``transfer_ms`` in
        milliseconds, bytes moved).

    Returns
    -------
    numpy.ndarray
        uint8, the heights' shape: 1 shadow, 0 lit, 255 nodata.

    Raises
    ------
    HillshadeError
        A DEM without a geotransform, a position that is not finite, a light inside the
        terrain, a negative height above the ground.
    """
    from ..algorithms import point_light
    from ..algorithms.horizon import bilinear
    if hasattr(heights, "heights") and hasattr(heights, "transform"):
        z_arr, t = heights.heights, heights.transform
        if t is None:
            raise HillshadeError("the DEM has no geotransform: give the light in array "
                                 "coordinates with the heights as an array")
        col, row = ~t @ (x, y)
        col, row = col - 0.5, row - 0.5          # the transform's cell centres at +0.5
    else:
        z_arr = np.asarray(heights)
        if z_arr.dtype != np.float32:
            z_arr = z_arr.astype(np.float32)
        col, row = float(x), float(y)
    if not all(np.isfinite(v) for v in (row, col, z)):
        raise HillshadeError("the light's position must be finite numbers")
    ground = bilinear(z_arr, row, col)
    if np.isfinite(ground) and z <= ground:
        raise HillshadeError(f"the light is inside the terrain ({z:g} m at a ground of "
                             f"{ground:g} m)")
    lift = _lift(height_above_ground)
    from .gpu import resolve_backend
    ran_on = resolve_backend(backend)
    if stats is not None:
        stats["backend"] = ran_on
    if ran_on == "gpu":
        from .gpu import GpuDem
        g = GpuDem(z_arr)
        out = point_light.shadow_mask_gpu(g, row, col, float(z), lift, pyramid)
        if stats is not None:
            stats["gpu"] = g.report()
        return out
    return point_light.shadow_mask(z_arr, row, col, float(z), lift, pyramid)


def subsolar_mask(dem, lat: float, lon: float, *, sun_distance: float | None = None,
                  body=None, height_above_ground: float = 0.0, curvature=True,
                  refraction_k: float | None = None, frames=None, pyramid=None,
                  sun_xyz=None, soft: bool = False, backend: str = "cpu") -> np.ndarray:
    """Cast-shadow mask of a DEM lit by the sun given by its subsolar point.

    Every cell with its own sun direction from its own place on the body (``engine.cell_suns``,
    ``algorithms.subsolar``). A cell whose sun is at or below its horizon is in shadow (the
    body hides the sun: the terminator). The sun's elevation itself is geometric (no
    refraction).

    Parameters
    ----------
    dem : Dem
        A DEM from :func:`~hillshade_rt.io.read_dem` with a geotransform and a CRS (heights in
        metres).
    lat, lon : float
        The subsolar point, degrees on the body.
    sun_distance : float, optional
        Metres from the body's centre to the sun (default the body's mean distance).
    body : earth.Body or str, optional
        Or ``--body``'s text ('moon', 'mars', 'earth', a radius in metres); default the DEM's
        CRS's.
    height_above_ground : float, default 0.0
        Metres (>= 0) above every cell that its ray starts from.
    curvature : bool or "auto", default True
        The rays curve with the body's radius of curvature in their azimuth at each cell;
        ``auto``: on when the raster is more than 1 km across.
    refraction_k : float, optional
        Terrestrial refraction coefficient bending the rays back (dimensionless); default 0.13
        on the Earth, 0 elsewhere (``earth.refraction_for``).
    frames : engine.cell_suns.CellFrames, optional
        Prepared once for many suns (costly).
    pyramid : algorithms.pyramid.MaxPyramid, optional
        Prepared once for many suns (costly).
    sun_xyz : array_like, optional
        The sun's position in the body-fixed frame, metres (else from ``lat``, ``lon`` and
        ``sun_distance``). With prepared parts pass ``body`` as an ``earth.Body`` too: finding
        the CRS's costs about 10 ms a call.
    soft : bool, default False
        The visible fraction of the solar disk instead (the disk's angular radius
        asin(R_sun / distance), the horizon from the cell's own ray).
    backend : {"cpu", "gpu", "auto"}, default "cpu"
        ``auto`` runs on the CPU.

    Returns
    -------
    numpy.ndarray
        The DEM's shape: uint8, 1 shadow, 0 lit, 255 nodata; with ``soft`` float32, 0..1, NaN
        nodata.

    Raises
    ------
    HillshadeError
        Not a DEM from ``read_dem``, or one without a geotransform or CRS; frames of another
        shape; a bad ``curvature``, ``backend`` or ``body``; a negative height above the ground.
    """
    from . import cell_suns
    from ..algorithms import pyramid as pyr_mod, subsolar
    from ..model.earth import dem_body, refraction_for
    if not (hasattr(dem, "heights") and hasattr(dem, "transform")):
        raise HillshadeError("subsolar_mask takes a DEM from read_dem (its transform and CRS "
                             "place every cell on the body)")
    if dem.transform is None or dem.crs is None:
        raise HillshadeError("per-cell suns need a DEM with a geotransform and a CRS")
    z = dem.heights
    if z.dtype != np.float32:
        z = z.astype(np.float32)
    if body is None or isinstance(body, (str, int, float)):
        body = cell_suns.body_from_option(None if body is None else str(body), dem_body(dem))
    lift = _lift(height_above_ground)
    if sun_xyz is None:
        sun_xyz = cell_suns.sun_vector(body, lat, lon, sun_distance)
    if frames is None:
        frames = cell_suns.CellFrames.of_dem(dem)
    if frames.shape != z.shape:
        raise HillshadeError(f"frames are {frames.shape} but heights are {z.shape}")
    grid = dem.grid
    if curvature == "auto":
        extent = max(float(np.max(grid.dx)) * grid.cols, float(np.max(grid.dy)) * grid.rows)
        curvature = extent > 1000.0
    elif curvature not in (True, False):
        raise HillshadeError(f"curvature must be True, False or 'auto', got {curvature!r}")
    k = refraction_for(body, refraction_k) if curvature else -1.0
    e2 = 1.0 - (body.b * body.b) / (body.a * body.a)
    radius = cell_suns.sun_radius_deg(float(np.linalg.norm(sun_xyz)))
    if backend == "gpu":
        from .gpu import GpuDem
        g = GpuDem(z)
        fr = tuple(g.upload(a) for a in frames.args())
        if soft:
            return subsolar.soft_fraction_gpu(g, fr, grid, body.a, e2, sun_xyz, radius, k,
                                              lift=lift)
        return subsolar.shadow_mask_gpu(g, fr, grid, body.a, e2, sun_xyz, k, lift=lift)
    if backend not in ("cpu", "auto"):
        raise HillshadeError(f"backend must be cpu, gpu or auto, got {backend!r}")
    if not np.isfinite(z).any():
        return (np.full(z.shape, np.nan, np.float32) if soft
                else np.full(z.shape, 255, dtype=np.uint8))
    pyr = pyr_mod.pyramid_args(z, True if pyramid is None else pyramid)
    zmax = float(np.nanmax(z))
    if soft:
        return subsolar.soft_fraction(z, pyr, frames.args(), grid, body.a, e2, sun_xyz, radius,
                                      k, zmax, lift)
    return subsolar.shadow_mask(z, pyr, frames.args(), grid, body.a, e2, sun_xyz, k, zmax, lift)
