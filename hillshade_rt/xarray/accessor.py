"""The ``da.hrt`` accessor and the functions it calls on a DataArray: :func:`shadow`,
:func:`horizon`, :func:`skyview`, :func:`sun_hours`, :func:`irradiance` (the command's run on
the heights in memory, ``run.irradiance_arrays``), :func:`shadow_polygons` (the commands' runs
on arrays: the same
``engine.shader.Shader`` and ``render``, the sun through ``model.sun.SunRequest``), in memory
or, for a Dask-backed input, lazily through ``lazy``'s windows."""

from __future__ import annotations

import datetime as _dt
import functools

import numpy as np
import xarray as xr

from .. import __version__
from ..errors import HillshadeError
from .dataarray import as_dem, as_input, series_dim, sun_attrs, time_list, utc64, with_heights, wrap
from .lazy import (LazySource, horizon_settings, horizon_window, lazy_job, lazy_reach,
                   lazy_render, skyview_window, whole)


# the command line's options named in the library's messages, and their keywords here
_KEYWORDS = {"lat", "lon", "time", "tz", "pressure", "temperature", "sun-tolerance",
             "height-above-ground", "azimuth", "elevation", "date", "end-date", "step",
             "max-distance", "directions", "algorithm", "self-shadow", "soft", "start", "end",
             "angle-unit", "instant", "mean", "daily-mean", "monthly", "perez", "albedo",
             "linke-turbidity", "clear-sky", "ghi", "skyview-directions"}
# options whose keyword here is another name
_RENAMED = {"time": "times"}


def _keywords(fn, renamed=None):
    """``fn`` with the command line's options in its errors' messages named as its keywords
    (``--lat`` -> ``lat=``; ``renamed``: {option: keyword} where they differ)."""
    import functools
    import re

    def word(m):
        name = m.group(1)
        if renamed and name in renamed:
            return renamed[name] + "="
        return name.replace("-", "_") + "=" if name in _KEYWORDS else m.group(0)

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        try:
            return fn(*args, **kwargs)
        except HillshadeError as exc:
            text = re.sub(r"--([a-z][a-z-]*)", word, str(exc))
            if text == str(exc):
                raise
            try:
                new = type(exc)(text)
            except TypeError:
                new = HillshadeError(text)
            raise new from None
    return wrapper


def _request(azimuth, elevation, time, tz, lat, lon, pressure, temperature, refraction,
             sun_tolerance):
    from ..model.sun import DEFAULT_TOLERANCE, SunRequest
    direction = azimuth is not None or elevation is not None
    if direction and time is not None:
        raise HillshadeError("give the sun one way: azimuth and elevation, or time")
    if not direction and time is None:
        raise HillshadeError("no sun given: give azimuth and elevation, or time")
    if direction and (azimuth is None or elevation is None):
        raise HillshadeError("azimuth and elevation go together")
    texts, series = time_list(time, tz) if time is not None else ((), False)
    req = SunRequest.from_options(
        azimuth=azimuth, elevation=elevation, time=texts, tz=tz, lat=lat, lon=lon,
        pressure=pressure, temperature=temperature, no_refraction=not refraction,
        sun_tolerance=DEFAULT_TOLERANCE if sun_tolerance is None else sun_tolerance)
    return req, series


@_keywords
def shadow(da, azimuth: float | None = None, elevation: float | None = None, *, time=None,
           tz: str | None = None, lat: float | None = None, lon: float | None = None,
           crs=None, spacing=None, nodata: float | None = None, algorithm: str = "auto",
           backend: str = "auto", curvature="auto", refraction_k: float | None = None,
           height_above_ground: float = 0.0, soft: bool = False, self_shadow: bool = False,
           pressure: float | None = None, temperature: float | None = None,
           refraction: bool = True, sun_tolerance: float | None = None,
           **options) -> xr.DataArray:
    """Cast shadows of the DataArray ``da``, as ``hillshade-rt shadow``.

    A Dask-backed input gives a lazy, Dask-backed result, computed window by window (see the
    module's notes).

    Parameters
    ----------
    da : xarray.DataArray
        Heights in metres (the accessor's own DataArray for ``da.hrt``): 2-D, or with a ``band``
        dimension of size 1, on regularly spaced x/y coordinates; NumPy- or Dask-backed.
    azimuth : float, optional
        Sun azimuth, degrees (grid azimuth, clockwise from north); with ``elevation``.
    elevation : float, optional
        Sun elevation above the horizon, degrees, 0 < elevation <= 90; with ``azimuth``.
    time : str, datetime or sequence, optional
        Instead of ``azimuth``/``elevation``: one time (ISO 8601 text with an offset or an aware
        datetime; a naive one in ``tz``; naive numpy datetime64 and pandas times in ``tz``, else
        UTC as xarray's time coordinates) or a sequence of them (a list, a DatetimeIndex,
        ``ds.time.values``), which gives a ``time`` dimension. The sun of a time is the SPA's at
        the DEM's centre, per tile where it varies across the raster, as on the command line.
    tz : str, optional
        IANA time zone of naive times (e.g. "Europe/Vienna").
    lat, lon : float, optional
        The place of the sun, degrees (elsewhere than the DEM's centre, or for a DataArray
        without a CRS).
    crs : optional
        The CRS (anything rasterio takes); else rioxarray's ``da.rio.crs``, else
        ``da.attrs["crs"]``.
    spacing : float or (float, float), optional
        Ground metres per cell, ``d`` or ``(dx, dy)``; required without a CRS.
    nodata : float, optional
        Nodata value (else ``da.rio.nodata`` or ``_FillValue``); NaN and infinities are voids
        too.
    algorithm : str, default "auto"
        As :func:`hillshade_rt.engine.arrays.shadow_mask`.
    backend : {"auto", "cpu", "gpu"}, default "auto"
        As :func:`hillshade_rt.engine.arrays.shadow_mask`.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto``: on when rays can run longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on other
        bodies.
    height_above_ground : float, default 0.0
        Metres (>= 0) above every cell that its ray starts from.
    soft : bool, default False
        float32 visible fraction of the solar disk instead of the hard mask.
    self_shadow : bool, default False
        Surfaces facing away from the sun count as shadow.
    pressure : float, optional
        Air pressure, hPa, for the refraction (default the standard atmosphere at the place's
        height).
    temperature : float, optional
        Air temperature, °C, for the refraction (default 12).
    refraction : bool, default True
        Apparent sun elevation (the SPA's refraction).
    sun_tolerance : float, optional
        Degrees: the sun is computed per tile where its direction varies by more than this
        across the raster (default 0.05).
    **options
        Passed to the algorithm, as :func:`hillshade_rt.engine.arrays.shadow_mask`.

    Returns
    -------
    xarray.DataArray
        On ``da``'s x/y coordinates with its CRS and transform, attributes naming the product and
        the sun: uint8 1 shadow, 0 lit, 255 nodata (``soft``: float32 visible fraction 0..1, NaN
        nodata); a ``time`` dimension for a sequence of times.

    Raises
    ------
    HillshadeError
        The sun given both ways, neither way or half (``azimuth`` without ``elevation``); a
        DataArray that is not 2-D on regular coordinates; no CRS and no ``spacing``; an
        unknown algorithm or a bad option.
    """
    return _lighting(da, "shadow", azimuth, elevation, time, tz, lat, lon, crs, spacing, nodata,
                     algorithm, backend, curvature, refraction_k, height_above_ground, soft,
                     self_shadow, pressure, temperature, refraction, sun_tolerance, options)


def _lighting(da, kind, azimuth, elevation, time, tz, lat, lon, crs, spacing, nodata, algorithm,
              backend, curvature, refraction_k, lift, soft, self_shadow, pressure, temperature,
              refraction, sun_tolerance, options):
    from ..algorithms import lookup
    from ..engine.products import product
    from ..run.config import check_lift
    from ..engine.lighting import Lighting
    from ..engine.shader import choose_backend
    lookup(algorithm)
    algorithm = check_lift(lift, algorithm, soft)
    lift = float(lift)
    req, series = _request(azimuth, elevation, time, tz, lat, lon, pressure, temperature,
                           refraction, sun_tolerance)
    inp = as_input(da, crs, spacing, nodata)
    lighting = Lighting(algorithm=algorithm, options=options,
                        backend=choose_backend(backend, algorithm, options),
                        curvature=curvature, refraction_k=refraction_k, soft=soft,
                        self_shadow=self_shadow, lift=lift)
    prod = product(kind, soft)
    nd = np.nan if soft else prod.nodata
    attrs = {"product": kind + (" (soft)" if soft else ""), "description": prod.what,
             "values": prod.values, "algorithm": algorithm, "hillshade_rt_version": __version__,
             "height_above_ground_m": lift or None}
    if inp.lazy:
        job, stats, suns, info = lazy_job(inp, req, lighting, kind)
        arrays = [lazy_render(job, s, stats, inp.heights, prod.dtype) for s in suns]
        import dask.array as dka
        stack = dka.stack
    else:
        from ..model.earth import dem_body
        from ..engine.shader import render
        dem = as_dem(inp)
        suns, info = req.suns(dem)
        shader = lighting.shader(dem.heights, dem.grid, body=dem_body(dem, req.lat),
                                 zrange=dem.height_range(), survey=dem.survey())
        arrays = [render(shader, s, kind, soft=soft, self_shadow=self_shadow) for s in suns]
        stack = np.stack
    if info is not None:
        attrs["sun_site"] = (f"{info['site']['latitude']:.6f}, {info['site']['longitude']:.6f}"
                             f" ({info['site']['source'].replace('--lat/--lon', 'lat/lon')})")
    if series:
        return wrap(stack(arrays), inp, attrs, nd, kind, series_dim(suns))
    out = wrap(arrays[0], inp, {**attrs, **sun_attrs(suns[0])}, nd, kind)
    if suns[0].time is not None:
        out = out.assign_coords(time=utc64(suns[0].time))
    return out


@_keywords
def horizon(da, azimuth=None, *, directions: int | None = None, start: float | None = None,
            end: float | None = None, step: float | None = None, angle_unit: str = "degrees",
            crs=None, spacing=None, nodata: float | None = None,
            method: str = "scan", sample_spacing: int = 1, backend: str = "auto",
            curvature="auto", refraction_k: float | None = None,
            max_distance: float | None = None,
            height_above_ground: float = 0.0) -> xr.DataArray:
    """Horizon angle of every cell toward ``azimuth`` (or the azimuths of ``directions`` or
    ``start``/``end``/``step``), as ``hillshade-rt horizon``.

    As :func:`hillshade_rt.engine.arrays.horizon_angles`. A Dask-backed input gives a lazy
    result, one task per chunk whose window holds every cell toward the azimuth (within ``max_distance``,
    else to the raster's edge), curvature and body decided for the whole raster: the in-memory
    angles (``method="hull"``, an approximation over the whole raster: one task).

    Parameters
    ----------
    da : xarray.DataArray
        Heights in metres (the accessor's own DataArray for ``da.hrt``): 2-D, or with a ``band``
        dimension of size 1, on regularly spaced x/y coordinates; NumPy- or Dask-backed.
    azimuth : float or sequence of float, optional
        Degrees clockwise from the raster's north; a sequence gives an ``azimuth`` dimension.
        Or give ``directions``, or ``step`` (with ``start``, ``end``).
    directions : int, optional
        Instead of ``azimuth``: this many azimuths (8..360) equally spaced clockwise from
        north, 0 first (the command's ``--directions``); an ``azimuth`` dimension.
    start : float, optional
        With ``step``: the first azimuth, degrees clockwise from north, in [0, 360) (default 0;
        r.horizon's ``start`` counts counter-clockwise from east: ours is 90 - theirs).
    end : float, optional
        With ``step``: the azimuths come before this one, degrees (default ``start`` + 360; at
        most one turn after ``start``).
    step : float, optional
        Degrees between azimuths clockwise from ``start``: floor((end - start) / step) of
        them, as r.horizon's ``step`` (the command's ``--start/--end/--step``); an ``azimuth``
        dimension.
    angle_unit : {"degrees", "radians"}, default "degrees"
        The unit of the angles returned (r.horizon's default is radians, its ``-d`` degrees).
    crs : optional
        The CRS (anything rasterio takes); else rioxarray's ``da.rio.crs``, else
        ``da.attrs["crs"]``.
    spacing : float or (float, float), optional
        Ground metres per cell, ``d`` or ``(dx, dy)``; required without a CRS.
    nodata : float, optional
        Nodata value (else ``da.rio.nodata`` or ``_FillValue``); NaN and infinities are voids
        too.
    method : {"scan", "hull"}, default "scan"
        ``scan`` is exact on the model; ``hull`` the faster approximation.
    sample_spacing : int, default 1
        The scan takes every n-th sample only (n > 1: faster, approximate).
    backend : {"auto", "cpu", "gpu"}, default "auto"
        As :func:`hillshade_rt.engine.arrays.shadow_mask`.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto``: on for the scan of a raster more than 1 km across.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth.
    max_distance : float, optional
        Metres of ground distance: terrain farther along a ray is ignored.
    height_above_ground : float, default 0.0
        Metres (>= 0): the horizon seen from that high above each cell.

    Returns
    -------
    xarray.DataArray
        float32 degrees (``angle_unit="radians"``: radians) above the horizontal, NaN on voids,
        -90 degrees (-pi/2) where no terrain lies ahead, on ``da``'s x/y coordinates (an
        ``azimuth`` dimension, degrees clockwise from north, for a sequence of azimuths,
        ``directions`` or ``step``).

    Raises
    ------
    HillshadeError
        No azimuth, a non-finite one, more than one of ``azimuth``, ``directions`` and
        ``step``, ``start``/``end`` without ``step`` or out of range, an unknown
        ``angle_unit``, no CRS and no ``spacing``, a negative height above the ground.
    """
    from ..engine.arrays import horizon_angles
    from ..model.geometry import normalize_azimuth
    from ..run.config import HorizonConfig
    from ..run.horizon_windows import in_unit
    if azimuth is not None and not np.isscalar(azimuth):    # a sequence of azimuths
        if directions is not None or step is not None or start is not None or end is not None:
            raise HillshadeError("give azimuth, directions or start/end/step, one of them")
        series = True
        azimuths = [normalize_azimuth(float(a)) for a in np.atleast_1d(azimuth)]
        if not azimuths:
            raise HillshadeError("azimuth: no azimuths given")
        HorizonConfig(dem="", output="", azimuth=0.0, angle_unit=angle_unit).azimuths()
    else:       # the command line's choice: --azimuth, --directions or --start/--end/--step
        series = azimuth is None
        azimuths = HorizonConfig(dem="", output="", azimuth=azimuth, directions=directions,
                                 start=start, end=end, step=step,
                                 angle_unit=angle_unit).azimuths()
    inp = as_input(da, crs, spacing, nodata)

    def compute(z):
        dem = as_dem(with_heights(inp, z))
        return np.stack([horizon_angles(dem, a, None, method, sample_spacing, backend,
                                        curvature=curvature, refraction_k=refraction_k,
                                        max_distance=max_distance,
                                        height_above_ground=height_above_ground)
                         for a in azimuths])
    if inp.lazy and method == "scan":    # exact: windows toward each azimuth
        import dask.array as dka
        curv, body = horizon_settings(inp, curvature, method)
        arr = dka.stack([lazy_reach(inp, [a], max_distance, functools.partial(
            horizon_window, grid=inp.grid, azimuth=a, method=method,
            sample_spacing=sample_spacing, backend=backend, curvature=curv,
            refraction_k=refraction_k, body=body, max_distance=max_distance,
            lift=height_above_ground)) for a in azimuths])
    else:
        arr = whole(compute, inp, (len(azimuths),) + inp.shape)
    arr = in_unit(arr, angle_unit)
    attrs = {"product": "horizon", "units": f"{angle_unit} above the horizontal",
             "no_terrain_ahead": float(in_unit(np.float32(-90.0), angle_unit)),
             "method": method,
             "max_distance_m": max_distance, "height_above_ground_m":
             float(height_above_ground) or None, "hillshade_rt_version": __version__}
    if series:
        return wrap(arr, inp, attrs, np.nan, "horizon",
                    ("azimuth", {"azimuth": ("azimuth", np.array(azimuths))}))
    return wrap(arr[0], inp, {**attrs, "azimuth": azimuths[0]}, np.nan, "horizon")


@_keywords
def skyview(da, *, directions: int = 32, definition: str = "zaksek", openness: str | None = None,
            crs=None, spacing=None, nodata: float | None = None, curvature="auto",
            refraction_k: float | None = None, max_distance: float | None = None,
            height_above_ground: float = 0.0) -> xr.DataArray:
    """Sky view factor (or openness) of every cell, as ``hillshade-rt skyview``.

    From the exact horizon in ``directions`` azimuths
    (:func:`hillshade_rt.engine.arrays.sky_view`). A Dask-backed input gives a lazy result: with ``max_distance``, one task per chunk with the
    cells within it all round; without, one task over the whole raster (every direction reaches
    its edges).

    Parameters
    ----------
    da : xarray.DataArray
        Heights in metres (the accessor's own DataArray for ``da.hrt``): 2-D, or with a ``band``
        dimension of size 1, on regularly spaced x/y coordinates; NumPy- or Dask-backed.
    directions : int, default 32
        Number of azimuths, equally spaced over 360 degrees (>= 1).
    definition : {"zaksek", "dozier"}, default "zaksek"
        Zakšek et al.'s 1 - mean sin of the clipped horizon elevation, or Dozier & Frew's
        cosine-weighted view from the tilted surface.
    openness : {"positive", "negative"}, optional
        Yokoyama's openness in degrees instead.
    crs : optional
        The CRS (anything rasterio takes); else rioxarray's ``da.rio.crs``, else
        ``da.attrs["crs"]``.
    spacing : float or (float, float), optional
        Ground metres per cell, ``d`` or ``(dx, dy)``; required without a CRS.
    nodata : float, optional
        Nodata value (else ``da.rio.nodata`` or ``_FillValue``); NaN and infinities are voids
        too.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto``: on when rays can run longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth.
    max_distance : float, optional
        Metres of ground distance: terrain farther along a ray is ignored (Yokoyama's L).
    height_above_ground : float, default 0.0
        Metres (>= 0): the horizons seen from that high above each cell.

    Returns
    -------
    xarray.DataArray
        float32 on ``da``'s x/y coordinates: the sky view factor (dimensionless, 0..1), or with
        ``openness`` degrees; NaN on voids.

    Raises
    ------
    HillshadeError
        ``directions`` < 1, an unknown definition or openness, ``openness`` with
        ``definition="dozier"``, no CRS and no ``spacing``, a negative height above the ground.
    """
    from ..engine.arrays import sky_view
    inp = as_input(da, crs, spacing, nodata)

    def compute(z):
        dem = as_dem(with_heights(inp, z))
        return sky_view(dem, None, directions, definition, curvature=curvature,
                        refraction_k=refraction_k, openness=openness,
                        max_distance=max_distance, height_above_ground=height_above_ground)
    if inp.lazy and max_distance is not None:   # windows: each chunk and max_distance around
        from ..model.geometry import equal_azimuths
        n = int(directions)
        if n < 1:
            raise HillshadeError(f"directions must be 1 or more, got {directions}")
        curv, body = horizon_settings(inp, curvature, "scan")
        arr = lazy_reach(inp, equal_azimuths(360.0 / n), max_distance, functools.partial(
            skyview_window, grid=inp.grid, directions=n, definition=definition,
            curvature=curv, refraction_k=refraction_k, body=body, openness=openness,
            max_distance=max_distance, lift=height_above_ground))
    else:
        arr = whole(compute, inp, inp.shape)
    attrs = {"product": "openness" if openness else "skyview",
             "definition": f"{openness} openness" if openness else definition,
             "units": "degrees" if openness else "fraction of the sky (0..1)",
             "directions": int(directions), "max_distance_m": max_distance,
             "height_above_ground_m": float(height_above_ground) or None,
             "hillshade_rt_version": __version__}
    return wrap(arr, inp, attrs, np.nan, "skyview")


@_keywords
def sun_hours(da, date, *, end_date=None, step: str = "10min", tz: str | None = None,
              lat: float | None = None, lon: float | None = None, crs=None, spacing=None,
              nodata: float | None = None, algorithm: str = "auto", backend: str = "auto",
              curvature="auto", refraction_k: float | None = None, soft: bool = False,
              self_shadow: bool | None = None, height_above_ground: float = 0.0,
              pressure: float | None = None, temperature: float | None = None,
              refraction: bool = True, sun_tolerance: float | None = None,
              monthly: bool = False) -> xr.DataArray:
    """Hours of direct sun per cell over one day or several, as ``hillshade-rt sun-hours``.

    Each sample with the sun up counts for its interval. A Dask-backed input: each sample's
    windows as in :func:`shadow`, summed lazily. Earth only (a DEM of another body is lit with
    :func:`shadow`, which takes the sun's direction).

    Parameters
    ----------
    da : xarray.DataArray
        Heights in metres (the accessor's own DataArray for ``da.hrt``): 2-D, or with a ``band``
        dimension of size 1, on regularly spaced x/y coordinates; NumPy- or Dask-backed.
    date : str or datetime.date
        The first day (ISO 8601 text or a date).
    end_date : str or datetime.date, optional
        The last day (default ``date``).
    step : str, default "10min"
        Time between sun samples ("10min", "1h30min", "PT30M").
    tz : str, optional
        IANA time zone of the days (midnight to midnight there); default local mean solar time
        at the DEM's longitude.
    lat, lon : float, optional
        The place of the sun, degrees (elsewhere than the DEM's centre, or for a DataArray
        without a CRS).
    crs : optional
        The CRS (anything rasterio takes); else rioxarray's ``da.rio.crs``, else
        ``da.attrs["crs"]``.
    spacing : float or (float, float), optional
        Ground metres per cell, ``d`` or ``(dx, dy)``; required without a CRS.
    nodata : float, optional
        Nodata value (else ``da.rio.nodata`` or ``_FillValue``); NaN and infinities are voids
        too.
    algorithm : str, default "auto"
        As :func:`hillshade_rt.engine.arrays.shadow_mask`.
    backend : {"auto", "cpu", "gpu"}, default "auto"
        As :func:`hillshade_rt.engine.arrays.shadow_mask`.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto``: on when rays can run longer than 1 km.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0 on other
        bodies.
    soft : bool, default False
        Count the visible fraction of the solar disk instead of lit/unlit.
    self_shadow : bool, optional
        Surfaces facing away from the sun get no sun (default: on for an observer on the
        ground, off with ``height_above_ground``).
    height_above_ground : float, default 0.0
        Metres (>= 0) above every cell that its ray starts from.
    pressure : float, optional
        Air pressure, hPa, for the refraction (default the standard atmosphere at the place's
        height).
    temperature : float, optional
        Air temperature, °C, for the refraction (default 12).
    refraction : bool, default True
        Apparent sun elevation (the SPA's refraction).
    sun_tolerance : float, optional
        Degrees: the sun is computed per tile where its direction varies by more than this
        across the raster (default 0.05).
    monthly : bool, default False
        The hours of each month the days touch instead of the period's total (the command's
        ``--monthly`` bands after the total): one layer per month on a ``time`` dimension
        (each month's first day, in the days' zone), each month's own float32 sum.

    Returns
    -------
    xarray.DataArray
        float32 hours of direct sun, NaN on voids, on ``da``'s x/y coordinates, with attributes
        naming the days, the step and the samples; with ``monthly`` a ``time`` dimension (the
        months' first days, a ``month`` coordinate "YYYY-MM" along it).

    Raises
    ------
    HillshadeError
        An unparsable date or step, ``end_date`` before ``date``, no CRS and no ``spacing``, an
        unknown algorithm, a DEM of another body.
    """
    from ..algorithms import lookup
    from ..model.earth import dem_body
    from ..run.config import check_lift
    from ..engine.lighting import Lighting
    from ..engine.shader import choose_backend, render
    from ..model.solar import SUN_RADIUS_DEG, daylight_samples
    from ..model.sun import SunRequest
    from ..model.times import parse_date, parse_step
    lookup(algorithm)
    algorithm = check_lift(height_above_ground, algorithm, soft)
    lift = float(height_above_ground)
    if self_shadow is None:
        self_shadow = lift == 0.0
    first = parse_date(date.isoformat() if isinstance(date, _dt.date) else str(date), "date")
    last = (first if end_date is None else
            parse_date(end_date.isoformat() if isinstance(end_date, _dt.date) else str(end_date),
                       "end_date"))
    if last < first:
        raise HillshadeError("end_date is before date")
    parse_step(step)
    from ..model.sun import DEFAULT_TOLERANCE
    req = SunRequest.at_place([], tz, lat, lon, pressure, temperature, not refraction,
                              DEFAULT_TOLERANCE if sun_tolerance is None else sun_tolerance)
    inp = as_input(da, crs, spacing, nodata)
    lighting = Lighting(algorithm=algorithm, backend=choose_backend(backend, algorithm, {}),
                        curvature=curvature, refraction_k=refraction_k, soft=soft,
                        self_shadow=self_shadow, lift=lift)
    other = ("sun_hours computes the Earth's sun only (light a DEM of another body with "
             "shadow, which takes the sun's direction)")

    def dark(s):
        top = max([r.elevation for r in s.tiles] if s.tiles else [s.elevation])
        return top + (SUN_RADIUS_DEG if soft else 0.0) <= 0.0
    months = _months(first, last) if monthly else None
    if inp.lazy:
        src = LazySource(inp.heights, inp.grid, inp.transform, inp.crs, inp.path)
        site = req.site(src, other)
        req.times, weights = daylight_samples(first, last, step, req.tz, site, req.atmosphere)
        job, stats, suns, _ = lazy_job(inp, req, lighting, "sun")
        hours = inp.heights * np.float32(0.0)      # NaN on voids, 0 elsewhere
        per, keys = _month_sums(months, hours, suns, req.tz, site.lon)
        for s, w, key in zip(suns, weights, keys):
            if w > 0 and not dark(s):
                lit = np.float32(w) * lazy_render(job, s, stats, inp.heights, np.float32)
                hours = hours + lit
                if per is not None:
                    per[key] = per[key] + lit
    else:
        dem = as_dem(inp)
        site = req.site(dem, other)
        req.times, weights = daylight_samples(first, last, step, req.tz, site, req.atmosphere)
        suns, _ = req.suns(dem, site)
        shader = lighting.shader(dem.heights, dem.grid, body=dem_body(dem, req.lat),
                                 zrange=dem.height_range(), survey=dem.survey())
        hours = np.where(np.isnan(dem.heights), np.float32(np.nan), np.float32(0.0))
        per, keys = _month_sums(months, hours, suns, req.tz, site.lon)
        for s, w, key in zip(suns, weights, keys):
            if w > 0 and not dark(s):
                lit = np.float32(w) * render(shader, s, "sun", soft=soft,
                                             self_shadow=self_shadow)
                hours += lit
                if per is not None:
                    per[key] += lit
    attrs = {"product": "sun_hours", "units": "hours of direct sun",
             "date_first": first.isoformat(), "date_last": last.isoformat(),
             "days": (last - first).days + 1, "step": step, "algorithm": algorithm,
             "soft": str(soft), "self_shadow": str(self_shadow),
             "height_above_ground_m": lift or None, "samples": len(suns),
             "day": (f"midnight to midnight, {req.tz.key}" if req.tz is not None
                     else f"local mean solar time at longitude {site.lon:.4f}"),
             "hillshade_rt_version": __version__}
    if per is None:
        return wrap(hours, inp, attrs, np.nan, "sun_hours")
    if inp.lazy:
        import dask.array as dka
        stack = dka.stack
    else:
        stack = np.stack
    return wrap(stack([per[k] for k in months]), inp, {**attrs, "monthly": "hours of each month"},
                np.nan, "sun_hours", _month_dim(months))


def _months(first: _dt.date, last: _dt.date) -> list:
    """(year, month) of every month the days ``first`` .. ``last`` touch, in order (the
    command's ``--monthly`` bands)."""
    out, d = [], first
    while d <= last:
        if (d.year, d.month) not in out:
            out.append((d.year, d.month))
        d += _dt.timedelta(days=1)
    return out


def _month_sums(months, zero, suns, tz, lon):
    """With ``months``: ({(year, month): ``zero``'s copy} to sum each month's samples into,
    each sun's (year, month): its time's, in ``tz`` or local mean solar time at ``lon``, as the
    command's ``run.sky_inputs.month_keys``); without: (None, a None per sun)."""
    if months is None:
        return None, [None] * len(suns)
    from ..run.sky_inputs import month_keys
    return ({k: zero.copy() for k in months},
            month_keys([s.time for s in suns], tz, lon))


def _month_dim(months, hours=None):
    """The ``time`` dimension of monthly layers: each month's first day (datetime64, a label of
    the month in the period's local time), its "YYYY-MM" as ``month`` (and the sampled
    ``hours`` of each month)."""
    coords = {"time": ("time", np.array([f"{y:04d}-{m:02d}-01" for y, m in months],
                                        "datetime64[ns]")),
              "month": ("time", np.array([f"{y:04d}-{m:02d}" for y, m in months], object))}
    if hours is not None:
        coords["hours"] = ("time", np.asarray(hours, np.float64))
    return ("time", coords)


# the period sums' variables (r.sun's names, engine.irradiance.RSUN_NAMES) and what they are
_PERIOD_WHAT = {"beam": "beam (direct) irradiation on the cell's surface, 0 in cast shadow",
                "diffuse": "diffuse sky irradiation on the cell's surface",
                "reflected": "irradiation reflected by the terrain onto the cell's surface",
                "global": "global irradiation on the cell's surface (beam + diffuse + "
                          "reflected)"}
_CF_UNITS = {"Wh/m2": "Wh m-2", "W/m2": "W m-2", "Wh/m2/day": "Wh m-2 day-1"}


def _irradiance_keywords(fn):
    return _keywords(fn, _RENAMED)


@_irradiance_keywords
def irradiance(da, date=None, *, end_date=None, start=None, end=None, step: str = "15min",
               times=None, instant: bool = False, tz: str | None = None,
               lat: float | None = None, lon: float | None = None, crs=None, spacing=None,
               nodata: float | None = None, clear_sky: str | None = None,
               linke_turbidity=None, albedo=0.2, ghi: str | None = None, mean: bool = False,
               daily_mean: bool = False, monthly: bool = False, perez: bool = False,
               soft: bool = False, skyview_directions: int = 32, algorithm: str = "auto",
               backend: str = "auto", curvature="auto", refraction_k: float | None = None,
               height_above_ground: float = 0.0, pressure: float | None = None,
               temperature: float | None = None, refraction: bool = True,
               sun_tolerance: float | None = None) -> xr.Dataset:
    """Beam, diffuse, reflected and global irradiation over a period (or the irradiance at
    instants) on every cell, as ``hillshade-rt irradiance``.

    The command's run on the heights in memory (``run.irradiance_arrays``: the same samples,
    open sky, cast shadows, Horn normals, Dozier sky view and
    ``engine.irradiance.accumulate`` / ``instant``), so each variable equals the command's
    band for the same inputs. A Dask-backed input is computed first (the whole DEM in memory).

    Parameters
    ----------
    da : xarray.DataArray
        Heights in metres (the accessor's own DataArray for ``da.hrt``): 2-D, or with a ``band``
        dimension of size 1, on regularly spaced x/y coordinates.
    date : str or datetime.date, optional
        The day (or first day), midnight to midnight in ``tz`` (else local mean solar time).
    end_date : str or datetime.date, optional
        The last day of a range (included).
    start, end : str or datetime.datetime, optional
        Or the period from ``start`` to ``end`` (ISO 8601 with an offset, or aware datetimes).
    step : str, default "15min"
        Sampling interval; each sample, at its middle, stands for its interval.
    times : str, datetime or sequence, optional
        Instead of a period: the instants (r.sun's mode 1), as :func:`shadow`'s ``time``.
    instant : bool, default False
        The period's sample times (``date``) or ``start``, ``start + step``, ... ``end`` as
        instants instead of the period's sums.
    tz : str, optional
        IANA time zone of the days and of naive times.
    lat, lon : float, optional
        The place of the sun, degrees (elsewhere than the DEM's centre, or without a CRS).
    crs : optional
        The CRS (anything rasterio takes); else rioxarray's ``da.rio.crs``, else
        ``da.attrs["crs"]``.
    spacing : float or (float, float), optional
        Ground metres per cell, ``d`` or ``(dx, dy)``; required without a CRS.
    nodata : float, optional
        Nodata value (else ``da.rio.nodata`` or ``_FillValue``); NaN and infinities are voids.
    clear_sky : {"ineichen", "haurwitz"}, optional
        pvlib's clear-sky model (default ineichen).
    linke_turbidity : float, str or sequence of 12 floats, optional
        Linke turbidity (dimensionless) for ineichen: a number or 12 monthly numbers; default
        pvlib's climatological monthly value at the place.
    albedo : float, str or sequence of 12 floats, default 0.2
        Ground reflectance (0..1): a number, 12 monthly numbers, a raster file, or a pattern
        of 12 monthly rasters with ``{month}``.
    ghi : str, optional
        A measured sky instead: a CSV file with columns time, ghi (and dni, dhi), W/m².
    mean : bool, default False
        Mean W/m² over the period instead of Wh/m².
    daily_mean : bool, default False
        Wh/m² per day instead of Wh/m².
    monthly : bool, default False
        Also the global irradiation of each month (the command's ``--monthly`` bands): the
        variable ``glob_rad_monthly`` on a ``time`` dimension (each month's first day).
    perez : bool, default False
        Perez (1990) anisotropic sky instead of the isotropic one.
    soft : bool, default False
        The visible fraction of the solar disk instead of lit/unlit.
    skyview_directions : int, default 32
        Azimuths of Dozier's sky view factor (4..360).
    algorithm : str, default "auto"
        As :func:`hillshade_rt.engine.arrays.shadow_mask`.
    backend : {"auto", "cpu", "gpu"}, default "auto"
        As :func:`hillshade_rt.engine.arrays.shadow_mask`.
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13.
    height_above_ground : float, default 0.0
        Metres (>= 0): the receiving surface of every cell stands this high (a panel).
    pressure : float, optional
        Air pressure, hPa, for the refraction.
    temperature : float, optional
        Air temperature, °C, for the refraction (default 12).
    refraction : bool, default True
        Apparent sun elevation (the SPA's refraction).
    sun_tolerance : float, optional
        Degrees: the sun is computed per tile where its direction varies by more than this.

    Returns
    -------
    xarray.Dataset
        On ``da``'s x/y coordinates with its CRS, NaN on voids, float32. A period:
        ``beam_rad``, ``diff_rad``, ``refl_rad``, ``glob_rad`` in Wh m-2 (``mean``: W m-2;
        ``daily_mean``: Wh m-2 day-1), and with ``monthly`` ``glob_rad_monthly`` (time, y, x)
        with the sampled ``hours`` of each month. Instants: the same four in W m-2 and
        ``incidout`` (the sun's elevation above each cell's surface, degrees), each on
        (time, y, x), ``time`` in UTC with the sun's ``sun_azimuth``, ``sun_elevation`` and
        ``time_local`` along it, and the open sky's ``open_sky_ghi``, ``open_sky_dni``,
        ``open_sky_dhi`` (W m-2) per time.

        A Dataset rather than one DataArray with a ``band`` dimension: the four are different
        quantities (each its own long name, and units that differ in the instants), as the
        command's time cube and r.sun's separate maps have them; ``ds.glob_rad`` names what a
        ``band`` index would not, and ``ds.to_array("band")`` stacks them when wanted.

    Raises
    ------
    HillshadeError
        The period given no way or two ways, a bad date, step, time or sky option (named by
        its keyword), no CRS and no ``spacing``, a DEM of another body.
    """
    from ..engine import irradiance as ir
    from ..model.sun import DEFAULT_TOLERANCE
    from ..run import irradiance as period_run
    from ..run import irradiance_instant as instant_run
    from ..run.config import IrradianceConfig, RunOptions

    def day(v):
        return v.isoformat() if isinstance(v, _dt.date) else v
    texts = ()
    if times is not None:
        texts = tuple(time_list(times, tz)[0])
    cfg = IrradianceConfig(
        dem="", output="", date=day(date), end_date=day(end_date), start=day(start),
        end=day(end), step=step, clear_sky=clear_sky,
        linke_turbidity=(",".join(str(v) for v in linke_turbidity)
                         if isinstance(linke_turbidity, (list, tuple)) else linke_turbidity),
        albedo=(",".join(str(v) for v in albedo) if isinstance(albedo, (list, tuple))
                else albedo),
        ghi=ghi, mean=mean, daily_mean=daily_mean, monthly=monthly, soft=soft, perez=perez,
        skyview_directions=skyview_directions,
        place=dict(tz=tz, lat=lat, lon=lon, pressure=pressure, temperature=temperature,
                   no_refraction=not refraction,
                   sun_tolerance=DEFAULT_TOLERANCE if sun_tolerance is None else sun_tolerance),
        algorithm=algorithm, curvature=curvature, refraction_k=refraction_k,
        run=RunOptions(backend=backend, quiet=True), height_above_ground=height_above_ground,
        times=texts, instant=instant)
    inp = as_input(da, crs, spacing, nodata)
    if inp.lazy:
        inp = with_heights(inp, inp.heights.compute())
    dem = as_dem(inp)
    common = {"hillshade_rt_version": __version__, "sky_model": "perez" if perez else
              "isotropic", "skyview_directions": int(skyview_directions),
              "height_above_ground_m": float(height_above_ground) or None}
    if cfg.instants():
        got = instant_run.in_memory(cfg, dem)
        dim = series_dim(got["suns"])
        out = {}
        for q in ir.INSTANT_BANDS:
            what, units = instant_run.CUBE_QUANTITIES[q]
            out[ir.RSUN_NAMES[q]] = wrap(np.stack(got["bands"][q]), inp,
                                         {"long_name": what, "units": units, "quantity": q},
                                         np.nan, ir.RSUN_NAMES[q], dim)
        ds = xr.Dataset(out)
        n = len(got["times"])
        for k, what in (("ghi", "global horizontal irradiance"),
                        ("dni", "direct normal irradiance"),
                        ("dhi", "diffuse horizontal irradiance")):
            ds[f"open_sky_{k}"] = ("time", np.asarray(getattr(got["sky"], k)[:n], np.float64),
                                   {"long_name": f"{what} of the open sky at the instant",
                                    "units": "W m-2"})
        ds.attrs.update({k: v for k, v in {**common, "mode": "instants (r.sun mode 1)",
                                           "sky": got["sky"].source}.items() if v is not None})
        return ds
    got = period_run.in_memory(cfg, dem)
    units = _CF_UNITS[got["units"]]
    out = {ir.RSUN_NAMES[q]: wrap(got["bands"][q], inp, {"long_name": _PERIOD_WHAT[q],
                                                      "units": units, "quantity": q},
                                  np.nan, ir.RSUN_NAMES[q]) for q in ir.BANDS}
    if got["months"] is not None:
        keys = [k for k, _, _ in got["months"]]
        out["glob_rad_monthly"] = wrap(
            np.stack([v for _, _, v in got["months"]]), inp,
            {"long_name": "global irradiation of each month", "units": units,
             "quantity": "global"}, np.nan, "glob_rad_monthly",
            _month_dim(keys, [h for _, h, _ in got["months"]]))
    ds = xr.Dataset(out)
    ds.attrs.update({**common, **{k: got[k] for k in ("period", "hours", "samples",
                                                      "samples_with_sun", "sky",
                                                      "turbidity")}})
    ds.attrs = {k: v for k, v in ds.attrs.items() if v is not None}
    return ds


@_keywords
def shadow_polygons(da, azimuth: float | None = None, elevation: float | None = None, *,
                    time=None, connectivity: int = 4, **kwargs):
    """The cast shadows of :func:`shadow` as polygons, as ``hillshade-rt shadow --vector``.

    Each region of shadow cells (value 1 of the mask; lit cells and voids are not traced) is
    one polygon with its holes, traced by GDAL (``rasterio.features.shapes``, as
    ``io.vector.write_polygons`` traces the command's rasters), its cells joined through their
    edges (``connectivity=4``) or also their corners (8).

    Parameters
    ----------
    da : xarray.DataArray
        Heights in metres, as :func:`shadow`'s.
    azimuth, elevation : float, optional
        The sun's direction, degrees, as :func:`shadow`'s.
    time : str, datetime or sequence, optional
        Instead: one time or a sequence of times, as :func:`shadow`'s.
    connectivity : {4, 8}, default 4
        Cells of a polygon touch through their edges (4) or also their corners (8).
    **kwargs
        The other keywords of :func:`shadow` (``tz``, ``lat``, ``lon``, ``crs``, ``spacing``,
        ``nodata``, ``algorithm``, ``self_shadow``, ...; not ``soft``: a visible fraction has
        no polygons).

    Returns
    -------
    geopandas.GeoDataFrame or list of dict
        A GeoDataFrame (in the DEM's CRS) where geopandas can be imported, else a list of
        GeoJSON-like features (``{"type": "Feature", "geometry": {...}, "properties":
        {...}}``, coordinates in the CRS's units). Each polygon's properties: the sun's
        ``azimuth`` and ``elevation`` (degrees), with a time its ``time`` (ISO 8601 with its
        offset), in a series its ``index`` (0-based), its ``area`` in the
        CRS's units squared (cells without a CRS) and ``area_m2`` in square metres (None without
        a CRS), as the command's layer and report have them.

    Raises
    ------
    HillshadeError
        A bad ``connectivity``, ``soft=True``, or what :func:`shadow` raises.
    """
    from rasterio.features import shapes

    from ..io.vector import PolygonArea, check_connectivity
    try:
        connectivity = check_connectivity(connectivity)
    except HillshadeError as exc:
        raise HillshadeError(str(exc).replace("--vector-connectivity", "connectivity")) from None
    if kwargs.get("soft"):
        raise HillshadeError("soft: a visible fraction has no polygons (shadow_polygons traces "
                             "the hard mask)")
    mask = shadow(da, azimuth, elevation, time=time, **kwargs)
    series = "time" in mask.dims
    layers = [mask.isel(time=i) for i in range(mask.sizes["time"])] if series else [mask]
    crs = mask.rio.crs
    transform = mask.rio.transform()
    measure = PolygonArea(crs)
    features = []
    for i, layer in enumerate(layers):
        m = np.asarray(layer.values, np.uint8)
        props = {"azimuth": float(layer.attrs.get("sun_azimuth", layer.coords.get(
                     "sun_azimuth", np.nan))),
                 "elevation": float(layer.attrs.get("sun_elevation", layer.coords.get(
                     "sun_elevation", np.nan)))}
        t = _layer_time(layer)
        if t is not None:
            props["time"] = t
        if series:
            props["index"] = i
        for geom, value in shapes(m, mask=m == 1, transform=transform,
                                  connectivity=connectivity):
            if int(value) != 1:
                continue
            area, m2 = measure(geom)
            features.append({"type": "Feature", "geometry": geom,
                             "properties": {**props, "area": area, "area_m2": m2}})
    import importlib
    try:        # (by name: geopandas is used where it is installed, never required)
        geopandas = importlib.import_module("geopandas")
    except ImportError:
        return features
    return geopandas.GeoDataFrame.from_features(features, crs=crs)


def _layer_time(layer) -> str | None:
    """The time of one layer of :func:`shadow`'s result, ISO 8601 with its offset, or None."""
    if "time_local" in layer.coords:
        return str(layer.coords["time_local"].values)
    return layer.attrs.get("time")


# ---------------------------------------------------------------------------------------------
# the accessor

@xr.register_dataarray_accessor("hrt")
class HrtAccessor:
    """``da.hrt``: :func:`shadow`, :func:`horizon`, :func:`skyview`, :func:`sun_hours`,
    :func:`irradiance`, :func:`shadow_polygons` of this DataArray (registered by
    ``import hillshade_rt.xarray``)."""

    def __init__(self, da: xr.DataArray):
        self._da = da

    def shadow(self, *args, **kwargs) -> xr.DataArray:
        return shadow(self._da, *args, **kwargs)

    def horizon(self, *args, **kwargs) -> xr.DataArray:
        return horizon(self._da, *args, **kwargs)

    def skyview(self, *args, **kwargs) -> xr.DataArray:
        return skyview(self._da, *args, **kwargs)

    def sun_hours(self, *args, **kwargs) -> xr.DataArray:
        return sun_hours(self._da, *args, **kwargs)

    def irradiance(self, *args, **kwargs) -> xr.Dataset:
        return irradiance(self._da, *args, **kwargs)

    def shadow_polygons(self, *args, **kwargs):
        return shadow_polygons(self._da, *args, **kwargs)


for _name in ("shadow", "horizon", "skyview", "sun_hours", "irradiance", "shadow_polygons"):
    getattr(HrtAccessor, _name).__doc__ = globals()[_name].__doc__
