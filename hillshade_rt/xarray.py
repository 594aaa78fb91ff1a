"""hillshade-rt on xarray DataArrays (rioxarray's CRS and transform): ``import hillshade_rt.xarray``
registers the ``da.hrt`` accessor, with :func:`shadow`, :func:`horizon`, :func:`skyview` and
:func:`sun_hours` as its methods (``da.hrt.shadow(azimuth=203.7, elevation=12)``).

The input is a 2-D DataArray (or one with a ``band`` dimension of size 1) whose x/y coordinates
are regularly spaced. Its CRS is ``crs=``, else rioxarray's ``da.rio.crs``, else
``da.attrs["crs"]``; its transform rioxarray's ``da.rio.transform()`` (from the coordinates
where the stored one disagrees with them). Without a CRS the ground
spacing must be given (``spacing=``: metres per cell, ``d`` or ``(dx, dy)``), as the array API
(``hillshade_rt.engine.arrays``) requires. Nodata (``da.rio.nodata``, ``_FillValue``, or ``nodata=``),
NaN and infinities are voids.

Every result is a DataArray on the input's x/y coordinates with its CRS and transform written by
rioxarray, a ``time`` dimension for a series of times, and attributes naming the product and the
sun (the GeoTIFF tags of the command line). The computation is the command line's: the same
``engine.shader.Shader`` and ``render``, the sun from ``--time`` through ``sun.SunRequest`` (the SPA on
a lattice, per tile where it varies across the raster).

A **Dask-backed** DataArray gives a lazy, Dask-backed result, computed window by window as the
command line's windowed runs do (``engine.windows``): each output region's window holds the region
and the halo **toward the sun** that can shadow it (from the heights' block ranges), so the
windows are exactly what the planner reads, whatever the input's chunks (a chunk smaller than
the halo is fine: a task reads the slices of every chunk its window covers). One pass over the
input (the block height ranges the halos come from, and the centre height for a sun from a
time) runs when the function is called; the shadows when the result is computed. Horizons
take windows toward their azimuth (to the edge, or within ``max_distance``), sky views within
``max_distance`` all round (without it: one task over the whole raster).
"""

from __future__ import annotations

import datetime as _dt
import functools
import math
import threading
from dataclasses import dataclass

import numpy as np
import rioxarray  # noqa: F401 -- registers the ``.rio`` accessor
import xarray as xr

from . import __version__
from .errors import HillshadeError
from .model.geometry import Grid

# one numba computation at a time in this process (Dask's threads would otherwise call the
# parallel kernels concurrently, which numba's default threading layer does not allow)
_LOCK = threading.Lock()


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


# ---------------------------------------------------------------------------------------------
# the input

@dataclass(eq=False)
class _Input:
    """A DataArray turned into what the library takes: float32 heights (numpy, or a Dask array
    for a Dask-backed input), their Grid, transform, CRS, and the coordinates of the output."""

    heights: object          # np.ndarray or dask.array.Array, float32, NaN voids
    grid: Grid
    transform: object        # affine.Affine
    crs: object              # rasterio CRS or None
    nodata: float | None
    path: str
    y_dim: str
    x_dim: str
    coords: dict             # the y and x coordinates of the output

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.heights.shape)

    @property
    def lazy(self) -> bool:
        return not isinstance(self.heights, np.ndarray)


def _is_dask(data) -> bool:
    return type(data).__module__.startswith("dask.")


def _heights_block(block, nodata):
    """float32 heights of one block of values: nodata, NaN and +-inf as NaN."""
    from .io.dem import heights_into
    out = np.empty(block.shape, np.float32)
    heights_into(np.asarray(block), nodata, out)
    return out


def _regular(values: np.ndarray, name: str) -> None:
    """Refuse coordinates that are not evenly spaced (beyond a ten-thousandth of a cell, or
    the rounding of their own type: float32 coordinates of a UTM raster are rounded to
    centimetres)."""
    if values.size < 2:
        return
    v = values.astype(np.float64)
    d = (v[-1] - v[0]) / (v.size - 1)
    eps = np.finfo(values.dtype).eps if values.dtype.kind == "f" else 0.0
    off = np.abs(v - (v[0] + d * np.arange(v.size)))
    if not (np.isfinite(d) and d != 0
            and float(off.max()) <= max(1e-4 * abs(d), 4 * eps * float(np.abs(v).max()))):
        raise HillshadeError(f"the {name} coordinates are not regularly spaced: hillshade-rt "
                             "needs a regular grid")


def _input(da, crs=None, spacing=None, nodata=None) -> _Input:
    """The DataArray ``da`` checked and converted (see the module's notes)."""
    from rasterio.crs import CRS

    from .io.dem import grid_of
    if not isinstance(da, xr.DataArray):
        raise HillshadeError(f"expected an xarray.DataArray, got {type(da).__name__}")
    if "band" in da.dims:
        if da.sizes["band"] != 1:
            raise HillshadeError(
                f"the DataArray has {da.sizes['band']} bands (dims {tuple(da.dims)}): give one "
                "band of heights, e.g. da.sel(band=1)")
        da = da.isel(band=0, drop=True)
    if da.ndim != 2:
        raise HillshadeError(f"expected a 2-D DataArray of heights (y, x), got dims "
                             f"{tuple(da.dims)}")
    try:
        x_dim, y_dim = da.rio.x_dim, da.rio.y_dim
    except Exception:  # noqa: BLE001 -- rioxarray's MissingSpatialDimensionError
        raise HillshadeError(f"the DataArray's dims {tuple(da.dims)} are not x/y (or lon/lat) "
                             "coordinates") from None
    for dim in (x_dim, y_dim):
        if dim not in da.coords:
            raise HillshadeError(f"the DataArray has no {dim} coordinates: hillshade-rt needs "
                                 "x/y coordinates (or rioxarray's transform) to place the cells")
    da = da.transpose(y_dim, x_dim)
    _regular(np.asarray(da[x_dim].values), x_dim)
    _regular(np.asarray(da[y_dim].values), y_dim)
    if crs is None:
        crs = da.rio.crs
    if crs is None:
        crs = da.attrs.get("crs")
    if crs is not None:
        try:
            crs = CRS.from_user_input(crs)
        except Exception as exc:  # noqa: BLE001 -- CRSError and the like
            raise HillshadeError(f"crs {crs!r}: not a CRS ({exc})") from None
    # rioxarray: the stored GeoTransform's resolution (else the coordinates'), the origin from
    # the coordinates (a slice of a raster has its own); the coordinates' own where they
    # disagree with the stored one beyond rounding (e.g. rows flipped to run south to north)
    try:
        transform = da.rio.transform()
    except Exception as exc:  # noqa: BLE001 -- rioxarray's errors (one row, no resolution)
        raise HillshadeError(f"the DataArray's transform is unknown: {exc}") from None
    if da.shape[0] > 1 and da.shape[1] > 1:
        fresh = da.rio.transform(recalc=True)
        if not np.allclose([transform.a, transform.e, transform.c, transform.f],
                           [fresh.a, fresh.e, fresh.c, fresh.f], rtol=1e-9, atol=0.0):
            transform = fresh
    if nodata is None:
        nodata = da.rio.nodata
        if nodata is None:
            nodata = da.attrs.get("_FillValue", da.encoding.get("_FillValue"))
    nodata = None if nodata is None else float(nodata)
    path = str(da.name) if da.name is not None else "DataArray"
    if isinstance(spacing, Grid):
        grid = spacing
        if (grid.rows, grid.cols) != da.shape:
            raise HillshadeError(f"spacing: a Grid of {grid.rows}x{grid.cols} cells for heights "
                                 f"of {da.shape[0]}x{da.shape[1]}")
    elif crs is None and spacing is None:
        raise HillshadeError(
            f"{path}: no CRS (crs=, rioxarray's da.rio.crs or attrs['crs']), so the ground "
            "spacing is unknown: give crs= or spacing= (metres per cell, d or (dx, dy))")
    else:
        pixel = None
        if spacing is not None:
            try:
                dxy = np.broadcast_to(np.asarray(spacing, np.float64), (2,))
            except (TypeError, ValueError):
                dxy = np.array([np.nan])
            if not (np.all(np.isfinite(dxy)) and np.all(dxy > 0)):
                raise HillshadeError(f"spacing must be positive metres, d or (dx, dy), got "
                                     f"{spacing!r}")
            pixel = (float(dxy[0]), float(dxy[1]))
        grid = grid_of(path, transform, crs, da.shape, pixel)
    data = da.data
    if _is_dask(data):
        z = data.map_blocks(_heights_block, nodata, dtype=np.float32)
    else:
        z = _heights_block(np.asarray(data), nodata)
    coords = {y_dim: da[y_dim], x_dim: da[x_dim]}
    return _Input(z, grid, transform, crs, nodata, path, y_dim, x_dim, coords)


def _dem(inp: _Input):
    """The heights in memory as an ``io.Dem`` (what the command line reads)."""
    from .io.dem import Dem
    dem = Dem(heights=inp.heights, grid=inp.grid, path=inp.path, kind="xarray",
              transform=inp.transform, crs=inp.crs, nodata=inp.nodata, driver="xarray",
              source_dtype="float32")
    if dem.heights.size == 0:
        raise HillshadeError(f"{inp.path}: the DataArray is empty")
    if dem.valid_count() == 0:
        raise HillshadeError(f"{inp.path}: every cell is nodata, nothing to shade")
    return dem


@dataclass(eq=False)
class _LazySource:
    """A Dask-backed input as the windowed runs see a DEM (``engine.windows.WindowLighting``, ``sun.dem_site``):
    its shape, grid, transform, CRS, and the centre height read from the centre only."""

    heights: object
    grid: Grid
    transform: object
    crs: object
    path: str

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.heights.shape)

    def centre_height(self) -> tuple[float, str]:
        from .model.site import centre_height_of
        rows, cols = self.shape
        r, c = rows // 2, cols // 2
        r0, c0 = max(0, r - 128), max(0, c - 128)
        z = np.asarray(self.heights[r0:min(rows, r + 129), c0:min(cols, c + 129)].compute())
        if not np.isfinite(z).any():
            return 0.0, "sea level (no valid cell within 128 cells of the centre)"
        return centre_height_of(z, r - r0, c - c0)


@dataclass(frozen=True)
class _Frame:
    """What ``engine.windows.WindowLighting`` reads of its DEM: the shape and the grid. Not the Dask array
    itself: Dask looks inside a task's dataclass arguments, and the whole input would become a
    dependency of every window's task."""

    shape: tuple[int, int]
    grid: Grid


def _block_range(block):
    """(lowest, highest valid height, valid cells) of each STAT_BLOCK² block of ``block``."""
    from .engine.windows import STAT_BLOCK as B
    rows, cols = block.shape
    nr, nc = -(-rows // B), -(-cols // B)
    z = np.full((nr * B, nc * B), np.nan, np.float32)
    z[:rows, :cols] = block
    z = z.reshape(nr, B, nc, B)
    ok = np.isfinite(z)
    out = np.empty((nr, nc, 3), np.float32)
    out[..., 0] = np.where(ok, z, np.inf).min(axis=(1, 3))
    out[..., 1] = np.where(ok, z, -np.inf).max(axis=(1, 3))
    out[..., 2] = ok.sum(axis=(1, 3))
    return out


def _block_stats(z):
    """``engine.windows.BlockStats`` of a Dask array of heights: the statistics pass of a windowed
    run, as one Dask reduction (computed now: the windows depend on it)."""
    from .engine.windows import STAT_BLOCK as B, BlockStats
    size = 8 * B
    zz = z.rechunk((size, size))
    parts = zz.map_blocks(_block_range, dtype=np.float32, new_axis=2,
                          chunks=(tuple(-(-c // B) for c in zz.chunks[0]),
                                  tuple(-(-c // B) for c in zz.chunks[1]), (3,)))
    st = np.asarray(parts.compute())
    valid = int(st[..., 2].astype(np.int64).sum())
    return BlockStats(B, st[..., 0].copy(), st[..., 1].copy(), valid)


# ---------------------------------------------------------------------------------------------
# the output

def _wrap(arr, inp: _Input, attrs: dict, nodata, name: str, extra_dim=None) -> xr.DataArray:
    """A DataArray of ``arr`` on the input's coordinates, CRS, transform and nodata.
    ``extra_dim``: (name, coordinates dict) of a leading dimension (time, azimuth)."""
    dims = (inp.y_dim, inp.x_dim)
    coords = dict(inp.coords)
    if extra_dim is not None:
        dims = (extra_dim[0],) + dims
        coords.update(extra_dim[1])
    out = xr.DataArray(arr, dims=dims, coords=coords, name=name,
                       attrs={k: v for k, v in attrs.items() if v is not None})
    if inp.crs is not None:
        out = out.rio.write_crs(inp.crs)
    out = out.rio.write_transform(inp.transform)
    if nodata is not None:
        out = out.rio.write_nodata(nodata, encoded=False)
    return out


def _time_list(time, tz=None):
    """(ISO texts for ``SunRequest``, whether a series was given) of ``time``: a text or a
    datetime (naive ones in ``tz``), a numpy datetime64 or pandas Timestamp (naive ones in
    ``tz``, else UTC, as xarray's time coordinates), or a sequence of them."""
    series = not isinstance(time, (str, _dt.datetime, np.datetime64))
    if series:
        try:
            items = list(time)
        except TypeError:
            items, series = [time], False
    else:
        items = [time]
    texts = []
    for t in items:
        if isinstance(t, str):
            texts.append(t)
        elif isinstance(t, _dt.datetime) and type(t).__module__ == "datetime":
            texts.append(t.isoformat())
        else:   # numpy datetime64, pandas Timestamp
            import pandas as pd
            ts = pd.Timestamp(t)
            if ts.tzinfo is None and tz is None:
                ts = ts.tz_localize("UTC")
            texts.append(ts.isoformat())
    if not texts:
        raise HillshadeError("time: no times given")
    return texts, series


def _utc64(t: _dt.datetime) -> np.datetime64:
    return np.datetime64(t.astimezone(_dt.timezone.utc).replace(tzinfo=None), "ns")


def _sun_attrs(sun) -> dict:
    """The command line's tags of one sun (``run.outputs.sun_tags``) as numbers and texts."""
    from .model.times import iso
    d = {"sun_azimuth": float(sun.azimuth), "sun_elevation": float(sun.elevation),
         "night": "yes" if sun.night else "no"}
    if sun.time is not None:
        d["time"] = iso(sun.time)
    if sun.tiles:
        d["sun_mode"] = f"per tile ({len(sun.tiles)} tiles)"
    return d


def _series_dim(suns):
    """The ``time`` dimension of a series: UTC times, with each sun's azimuth, elevation and
    the time with its offset as coordinates along it."""
    from .model.times import iso
    t = [_utc64(s.time) for s in suns]
    return ("time", {"time": ("time", np.array(t, "datetime64[ns]")),
                     "sun_azimuth": ("time", np.array([s.azimuth for s in suns])),
                     "sun_elevation": ("time", np.array([s.elevation for s in suns])),
                     "time_local": ("time", np.array([iso(s.time) for s in suns], object))})


# ---------------------------------------------------------------------------------------------
# Dask: windows with the planner's halos

def _light_piece(job, piece, z):
    """One task: the product over ``piece.region`` from its window's heights ``z``."""
    z = np.array(z, dtype=np.float32, copy=True)
    with _LOCK:
        return job.light(z, piece)


def _mosaic(blocks):
    """``blocks`` [(bounds (r0, r1, c0, c1), dask array)] tiling a rectangle as a grid -> one
    dask array."""
    import dask.array as dka
    rows = sorted({b[0] for b, _ in blocks})
    cols = sorted({b[2] for b, _ in blocks})
    at = {(b[0], b[2]): a for b, a in blocks}
    if len(at) != len(rows) * len(cols):
        raise HillshadeError("internal: the windows do not form a grid")
    return dka.block([[at[(r, c)] for c in cols] for r in rows])


def _lazy_render(job, sun, stats, z, dtype):
    """One sun's product over the raster as a lazy Dask array: one task per window of the
    planner (``WindowLighting.pieces``: regions of about the input's chunk size, each window with its halo
    toward the sun), each reading its window from ``z`` (slices of the input's chunks)."""
    import dask
    import dask.array as dka
    rows, cols = z.shape
    shape = (int(max(z.chunks[0])), int(max(z.chunks[1])))
    pieces = job.pieces(sun, stats, rows * cols, window_shape=shape, in_order=False)
    task = dask.delayed(_light_piece, pure=True)
    blocks = []
    for p in pieces:
        r0, r1, c0, c1 = p.region
        w0, w1, v0, v1 = p.window
        part = dka.from_delayed(task(job, p, z[w0:w1, v0:v1]), shape=(r1 - r0, c1 - c0),
                                dtype=dtype)
        blocks.append((p.region, part))
    tiles = []
    for reg in sun.regions((rows, cols)):
        r0, r1, _ = reg.rows.indices(rows)
        c0, c1, _ = reg.cols.indices(cols)
        inside = [(b, a) for b, a in blocks
                  if r0 <= b[0] and b[1] <= r1 and c0 <= b[2] and b[3] <= c1]
        tiles.append(((r0, r1, c0, c1), _mosaic(inside)))
    return _mosaic(tiles).rechunk(z.chunks)


def _lazy_job(inp: _Input, req, algorithm, options, ran_on, curvature, refraction_k, kind,
              soft, self_shadow, lift):
    """(job, block statistics, suns, sun info) of a Dask-backed input."""
    from .model.earth import dem_body
    from .engine.lighting import Lighting
    from .engine.windows import WindowLighting
    src = _LazySource(inp.heights, inp.grid, inp.transform, inp.crs, inp.path)
    stats = _block_stats(inp.heights)
    if stats.valid == 0:
        raise HillshadeError(f"{inp.path}: every cell is nodata, nothing to shade")
    suns, info = req.suns(src)
    rows, cols = inp.shape
    dx, dy = inp.grid.centre_spacing()
    lighting = Lighting(algorithm=algorithm, options=options, backend=ran_on,
                        curvature=curvature, refraction_k=refraction_k, soft=soft,
                        self_shadow=self_shadow, lift=lift)
    job = WindowLighting(_Frame(inp.shape, inp.grid), lighting, dem_body(src, req.lat),
                         (stats.zmin, stats.zmax), math.hypot(cols * dx, rows * dy), kind)
    return job, stats, suns, info


# ---------------------------------------------------------------------------------------------
# the products

def _request(azimuth, elevation, time, tz, lat, lon, pressure, temperature, refraction,
             sun_tolerance):
    from .model.sun import DEFAULT_TOLERANCE, SunRequest
    direction = azimuth is not None or elevation is not None
    if direction and time is not None:
        raise HillshadeError("give the sun one way: azimuth and elevation, or time")
    if not direction and time is None:
        raise HillshadeError("no sun given: give azimuth and elevation, or time")
    if direction and (azimuth is None or elevation is None):
        raise HillshadeError("azimuth and elevation go together")
    texts, series = _time_list(time, tz) if time is not None else ((), False)
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
    from .algorithms import lookup
    from .engine.products import product
    from .run.config import check_lift
    from .engine.shader import choose_backend
    lookup(algorithm)
    algorithm = check_lift(lift, algorithm, soft)
    lift = float(lift)
    req, series = _request(azimuth, elevation, time, tz, lat, lon, pressure, temperature,
                           refraction, sun_tolerance)
    inp = _input(da, crs, spacing, nodata)
    ran_on = choose_backend(backend, algorithm, options)
    prod = product(kind, soft)
    nd = np.nan if soft else prod.nodata
    attrs = {"product": kind + (" (soft)" if soft else ""), "description": prod.what,
             "values": prod.values, "algorithm": algorithm, "hillshade_rt_version": __version__,
             "height_above_ground_m": lift or None}
    if inp.lazy:
        job, stats, suns, info = _lazy_job(inp, req, algorithm, options, ran_on, curvature,
                                           refraction_k, kind, soft, self_shadow, lift)
        arrays = [_lazy_render(job, s, stats, inp.heights, prod.dtype) for s in suns]
        import dask.array as dka
        stack = dka.stack
    else:
        from .model.earth import dem_body
        from .engine.shader import Shader, render
        dem = _dem(inp)
        suns, info = req.suns(dem)
        shader = Shader(dem.heights, dem.grid, algorithm, options, ran_on, curvature,
                        refraction_k, dem_body(dem, req.lat), dem.height_range(),
                        survey=dem.survey(), lift=lift)
        arrays = [render(shader, s, kind, soft=soft, self_shadow=self_shadow) for s in suns]
        stack = np.stack
    if info is not None:
        attrs["sun_site"] = (f"{info['site']['latitude']:.6f}, {info['site']['longitude']:.6f}"
                             f" ({info['site']['source'].replace('--lat/--lon', 'lat/lon')})")
    if series:
        return _wrap(stack(arrays), inp, attrs, nd, kind, _series_dim(suns))
    out = _wrap(arrays[0], inp, {**attrs, **_sun_attrs(suns[0])}, nd, kind)
    if suns[0].time is not None:
        out = out.assign_coords(time=_utc64(suns[0].time))
    return out


@_keywords
def horizon(da, azimuth, *, crs=None, spacing=None, nodata: float | None = None,
            method: str = "scan", sample_spacing: int = 1, backend: str = "auto",
            curvature="auto", refraction_k: float | None = None,
            max_distance: float | None = None,
            height_above_ground: float = 0.0) -> xr.DataArray:
    """Horizon angle of every cell toward ``azimuth``, as ``hillshade-rt horizon``.

    As :func:`hillshade_rt.engine.arrays.horizon_angles`. A Dask-backed input gives a lazy result, one
    task per chunk whose window holds every cell toward the azimuth (within ``max_distance``,
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
    from .engine.arrays import horizon_angles
    from .model.geometry import normalize_azimuth
    series = not np.isscalar(azimuth)
    azimuths = [normalize_azimuth(float(a)) for a in np.atleast_1d(azimuth)]
    if not azimuths:
        raise HillshadeError("azimuth: no azimuths given")
    inp = _input(da, crs, spacing, nodata)

    def compute(z):
        dem = _dem(_with_heights(inp, z))
        return np.stack([horizon_angles(dem, a, None, method, sample_spacing, backend,
                                        curvature=curvature, refraction_k=refraction_k,
                                        max_distance=max_distance,
                                        height_above_ground=height_above_ground)
                         for a in azimuths])
    if inp.lazy and method == "scan":    # exact: windows toward each azimuth
        import dask.array as dka
        curv, body = _horizon_settings(inp, curvature, method)
        arr = dka.stack([_lazy_reach(inp, [a], max_distance, functools.partial(
            _horizon_window, grid=inp.grid, azimuth=a, method=method,
            sample_spacing=sample_spacing, backend=backend, curvature=curv,
            refraction_k=refraction_k, body=body, max_distance=max_distance,
            lift=height_above_ground)) for a in azimuths])
    else:
        arr = _whole(compute, inp, (len(azimuths),) + inp.shape)
    attrs = {"product": "horizon", "units": "degrees above the horizontal",
             "no_terrain_ahead": -90.0, "method": method,
             "max_distance_m": max_distance, "height_above_ground_m":
             float(height_above_ground) or None, "hillshade_rt_version": __version__}
    if series:
        return _wrap(arr, inp, attrs, np.nan, "horizon",
                     ("azimuth", {"azimuth": ("azimuth", np.array(azimuths))}))
    return _wrap(arr[0], inp, {**attrs, "azimuth": azimuths[0]}, np.nan, "horizon")


@_keywords
def skyview(da, *, directions: int = 32, definition: str = "zaksek", openness: str | None = None,
            crs=None, spacing=None, nodata: float | None = None, curvature="auto",
            refraction_k: float | None = None, max_distance: float | None = None,
            height_above_ground: float = 0.0) -> xr.DataArray:
    """Sky view factor (or openness) of every cell, as ``hillshade-rt skyview``.

    From the exact horizon in ``directions`` azimuths (:func:`hillshade_rt.engine.arrays.sky_view`). A
    Dask-backed input gives a lazy result: with ``max_distance``, one task per chunk with the
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
    from .engine.arrays import sky_view
    inp = _input(da, crs, spacing, nodata)

    def compute(z):
        dem = _dem(_with_heights(inp, z))
        return sky_view(dem, None, directions, definition, curvature=curvature,
                        refraction_k=refraction_k, openness=openness,
                        max_distance=max_distance, height_above_ground=height_above_ground)
    if inp.lazy and max_distance is not None:   # windows: each chunk and max_distance around
        from .model.geometry import equal_azimuths
        n = int(directions)
        if n < 1:
            raise HillshadeError(f"directions must be 1 or more, got {directions}")
        curv, body = _horizon_settings(inp, curvature, "scan")
        arr = _lazy_reach(inp, equal_azimuths(360.0 / n), max_distance, functools.partial(
            _skyview_window, grid=inp.grid, directions=n, definition=definition,
            curvature=curv, refraction_k=refraction_k, body=body, openness=openness,
            max_distance=max_distance, lift=height_above_ground))
    else:
        arr = _whole(compute, inp, inp.shape)
    attrs = {"product": "openness" if openness else "skyview",
             "definition": f"{openness} openness" if openness else definition,
             "units": "degrees" if openness else "fraction of the sky (0..1)",
             "directions": int(directions), "max_distance_m": max_distance,
             "height_above_ground_m": float(height_above_ground) or None,
             "hillshade_rt_version": __version__}
    return _wrap(arr, inp, attrs, np.nan, "skyview")


def _horizon_settings(inp: _Input, curvature, method: str):
    """(curvature, body) of the horizon products over the whole raster, decided once for its
    windows as ``shading.horizon_shader`` decides them for the whole (curvature "auto": on for
    the scan of a raster more than 1 km across; the body at the DEM's centre)."""
    from .model.earth import dem_body
    if curvature in ("auto", None):
        rows, cols = inp.shape
        dx, dy = inp.grid.centre_spacing()
        curvature = math.hypot(cols * dx, rows * dy) > 1000.0 and method == "scan"
    src = _LazySource(inp.heights, inp.grid, inp.transform, inp.crs, inp.path)
    return curvature, dem_body(src)


def _horizon_window(z, window, *, grid, azimuth, method, sample_spacing, backend, curvature,
                    refraction_k, body, max_distance, lift):
    from .engine.arrays import horizon_angles
    from .engine.windows import window_grid
    return horizon_angles(z, azimuth, window_grid(grid, window), method, sample_spacing,
                          backend, curvature=curvature, refraction_k=refraction_k, body=body,
                          max_distance=max_distance, height_above_ground=lift)


def _skyview_window(z, window, *, grid, directions, definition, curvature, refraction_k, body,
                    openness, max_distance, lift):
    from .engine.arrays import sky_view
    from .engine.windows import window_grid
    return sky_view(z, window_grid(grid, window), directions, definition, curvature=curvature,
                    refraction_k=refraction_k, body=body, openness=openness,
                    max_distance=max_distance, height_above_ground=lift)


def _reach_part(part, z, window, region):
    """One task of :func:`_lazy_reach`: ``part`` over the window, cut to the region."""
    r0, r1, c0, c1 = region
    w0, _, v0, _ = window
    z = np.array(z, dtype=np.float32, copy=True)
    inner = (slice(r0 - w0, r1 - w0), slice(c0 - v0, c1 - v0))
    if not np.isfinite(z[inner]).any():
        return np.full((r1 - r0, c1 - c0), np.nan, np.float32)
    with _LOCK:
        return np.asarray(part(z, window)[inner], np.float32)


def _lazy_reach(inp: _Input, azimuths, max_distance, part):
    """A lazy float32 product of a Dask-backed input (horizon angles, sky view), one task per
    chunk of the input: the chunk's window holds, toward each of ``azimuths``, every cell
    within ``max_distance`` metres (to the raster's edge without one; ``shading.halo_bounds``,
    as the planner's halos) and a cell all round; ``part(heights, window)`` makes the product
    over the window, of which the task keeps the chunk."""
    import dask
    import dask.array as dka

    from .engine.shader import halo_bounds
    z = inp.heights
    reach = math.inf if max_distance is None else float(max_distance)
    task = dask.delayed(_reach_part, pure=True)
    redges = np.cumsum((0,) + tuple(z.chunks[0]))
    cedges = np.cumsum((0,) + tuple(z.chunks[1]))
    blocks = []
    for r0, r1 in zip(redges[:-1], redges[1:]):
        row = []
        for c0, c1 in zip(cedges[:-1], cedges[1:]):
            region = (int(r0), int(r1), int(c0), int(c1))
            wins = [halo_bounds(region, inp.shape, inp.grid, a, reach, 1) for a in azimuths]
            w = (min(x[0] for x in wins), max(x[1] for x in wins), min(x[2] for x in wins),
                 max(x[3] for x in wins))
            row.append(dka.from_delayed(task(part, z[w[0]:w[1], w[2]:w[3]], w, region),
                                        shape=(region[1] - region[0], region[3] - region[2]),
                                        dtype=np.float32))
        blocks.append(row)
    return dka.block(blocks)


def _with_heights(inp: _Input, z) -> _Input:
    return _Input(z, inp.grid, inp.transform, inp.crs, inp.nodata, inp.path, inp.y_dim,
                  inp.x_dim, inp.coords)


def _whole(compute, inp: _Input, shape):
    """``compute(heights)`` now, or as one Dask task over the whole input (rechunked to the
    input's chunks) for a Dask-backed one."""
    if not inp.lazy:
        return compute(inp.heights)
    import dask
    import dask.array as dka

    def task(z):
        with _LOCK:
            return compute(np.array(z, np.float32, copy=True))
    arr = dka.from_delayed(dask.delayed(task, pure=True)(inp.heights), shape=shape,
                           dtype=np.float32)
    return arr.rechunk(((shape[0],),) * (len(shape) - 2) + inp.heights.chunks
                       if len(shape) == 3 else inp.heights.chunks)


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
    from .algorithms import lookup
    from .model.earth import dem_body
    from .run.config import check_lift
    from .engine.shader import Shader, choose_backend, render
    from .model.solar import SUN_RADIUS_DEG, daylight_samples
    from .model.sun import SunRequest
    from .model.times import parse_date, parse_step
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
    from .model.sun import DEFAULT_TOLERANCE
    req = SunRequest.at_place([], tz, lat, lon, pressure, temperature, not refraction,
                              DEFAULT_TOLERANCE if sun_tolerance is None else sun_tolerance)
    inp = _input(da, crs, spacing, nodata)
    ran_on = choose_backend(backend, algorithm, {})
    other = ("sun_hours computes the Earth's sun only (light a DEM of another body with "
             "shadow, which takes the sun's direction)")

    def dark(s):
        top = max([r.elevation for r in s.tiles] if s.tiles else [s.elevation])
        return top + (SUN_RADIUS_DEG if soft else 0.0) <= 0.0
    if inp.lazy:
        src = _LazySource(inp.heights, inp.grid, inp.transform, inp.crs, inp.path)
        site = req.site(src, other)
        req.times, weights = daylight_samples(first, last, step, req.tz, site, req.atmosphere)
        job, stats, suns, _ = _lazy_job(inp, req, algorithm, {}, ran_on, curvature,
                                        refraction_k, "sun", soft, self_shadow, lift)
        hours = inp.heights * np.float32(0.0)      # NaN on voids, 0 elsewhere
        for s, w in zip(suns, weights):
            if w > 0 and not dark(s):
                hours = hours + np.float32(w) * _lazy_render(job, s, stats, inp.heights,
                                                             np.float32)
    else:
        dem = _dem(inp)
        site = req.site(dem, other)
        req.times, weights = daylight_samples(first, last, step, req.tz, site, req.atmosphere)
        suns, _ = req.suns(dem, site)
        shader = Shader(dem.heights, dem.grid, algorithm, {}, ran_on, curvature, refraction_k,
                        dem_body(dem, req.lat), dem.height_range(), survey=dem.survey(),
                        lift=lift)
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
    return _wrap(hours, inp, attrs, np.nan, "sun_hours")


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
