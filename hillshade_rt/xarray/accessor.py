"""The ``da.hrt`` accessor and the functions it calls on a DataArray: :func:`shadow`,
:func:`horizon`, :func:`skyview`, :func:`sun_hours` (the commands' runs on arrays: the same
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
             "max-distance", "directions", "algorithm", "self-shadow", "soft"}


def _keywords(fn):
    """``fn`` with the command line's options in its errors' messages named as its keywords
    (``--lat`` -> ``lat=``)."""
    import functools
    import re

    def word(m):
        name = m.group(1)
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
def horizon(da, azimuth, *, crs=None, spacing=None, nodata: float | None = None,
            method: str = "scan", sample_spacing: int = 1, backend: str = "auto",
            curvature="auto", refraction_k: float | None = None,
            max_distance: float | None = None,
            height_above_ground: float = 0.0) -> xr.DataArray:
    """Horizon angle of every cell toward ``azimuth``, as ``hillshade-rt horizon``.

    As :func:`hillshade_rt.engine.arrays.horizon_angles`. A Dask-backed input gives a lazy
    result, one task per chunk whose window holds every cell toward the azimuth (within ``max_distance``,
    else to the raster's edge), curvature and body decided for the whole raster: the in-memory
    angles (``method="hull"``, an approximation over the whole raster: one task).

    Parameters
    ----------
    da : xarray.DataArray
        Heights in metres (the accessor's own DataArray for ``da.hrt``): 2-D, or with a ``band``
        dimension of size 1, on regularly spaced x/y coordinates; NumPy- or Dask-backed.
    azimuth : float or sequence of float
        Degrees clockwise from the raster's north; a sequence gives an ``azimuth`` dimension.
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
        float32 degrees above the horizontal, NaN on voids, -90 where no terrain lies ahead, on
        ``da``'s x/y coordinates (an ``azimuth`` dimension for a sequence of azimuths).

    Raises
    ------
    HillshadeError
        No azimuth, a non-finite one, no CRS and no ``spacing``, a negative height above the
        ground.
    """
    from ..engine.arrays import horizon_angles
    from ..model.geometry import normalize_azimuth
    series = not np.isscalar(azimuth)
    azimuths = [normalize_azimuth(float(a)) for a in np.atleast_1d(azimuth)]
    if not azimuths:
        raise HillshadeError("azimuth: no azimuths given")
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
    attrs = {"product": "horizon", "units": "degrees above the horizontal",
             "no_terrain_ahead": -90.0, "method": method,
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
              refraction: bool = True, sun_tolerance: float | None = None) -> xr.DataArray:
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

    Returns
    -------
    xarray.DataArray
        float32 hours of direct sun, NaN on voids, on ``da``'s x/y coordinates, with attributes
        naming the days, the step and the samples.

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
    if inp.lazy:
        src = LazySource(inp.heights, inp.grid, inp.transform, inp.crs, inp.path)
        site = req.site(src, other)
        req.times, weights = daylight_samples(first, last, step, req.tz, site, req.atmosphere)
        job, stats, suns, _ = lazy_job(inp, req, lighting, "sun")
        hours = inp.heights * np.float32(0.0)      # NaN on voids, 0 elsewhere
        for s, w in zip(suns, weights):
            if w > 0 and not dark(s):
                hours = hours + np.float32(w) * lazy_render(job, s, stats, inp.heights,
                                                            np.float32)
    else:
        dem = as_dem(inp)
        site = req.site(dem, other)
        req.times, weights = daylight_samples(first, last, step, req.tz, site, req.atmosphere)
        suns, _ = req.suns(dem, site)
        shader = lighting.shader(dem.heights, dem.grid, body=dem_body(dem, req.lat),
                                 zrange=dem.height_range(), survey=dem.survey())
        hours = np.where(np.isnan(dem.heights), np.float32(np.nan), np.float32(0.0))
        for s, w in zip(suns, weights):
            if w > 0 and not dark(s):
                hours += np.float32(w) * render(shader, s, "sun", soft=soft,
                                                self_shadow=self_shadow)
    attrs = {"product": "sun_hours", "units": "hours of direct sun",
             "date_first": first.isoformat(), "date_last": last.isoformat(),
             "days": (last - first).days + 1, "step": step, "algorithm": algorithm,
             "soft": str(soft), "self_shadow": str(self_shadow),
             "height_above_ground_m": lift or None, "samples": len(suns),
             "day": (f"midnight to midnight, {req.tz.key}" if req.tz is not None
                     else f"local mean solar time at longitude {site.lon:.4f}"),
             "hillshade_rt_version": __version__}
    return wrap(hours, inp, attrs, np.nan, "sun_hours")


# ---------------------------------------------------------------------------------------------
# the accessor

@xr.register_dataarray_accessor("hrt")
class HrtAccessor:
    """``da.hrt``: :func:`shadow`, :func:`horizon`, :func:`skyview`, :func:`sun_hours` of this
    DataArray (registered by ``import hillshade_rt.xarray``)."""

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


for _name in ("shadow", "horizon", "skyview", "sun_hours"):
    getattr(HrtAccessor, _name).__doc__ = globals()[_name].__doc__
