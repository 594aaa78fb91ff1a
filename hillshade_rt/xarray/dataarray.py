"""A DataArray in and out: the input checked and turned into what the library takes (float32
heights, NumPy or Dask, their ``Grid``, transform, CRS, nodata) and the results wrapped on the
input's coordinates with its CRS and transform (rioxarray), the sun's attributes and a
``time`` dimension for a series."""

from __future__ import annotations

import datetime as _dt
from dataclasses import dataclass

import numpy as np
import rioxarray  # noqa: F401 -- registers the ``.rio`` accessor
import xarray as xr

from ..errors import HillshadeError
from ..model.geometry import Grid


@dataclass(eq=False)
class Input:
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
    from ..io.dem import heights_into
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


def as_input(da, crs=None, spacing=None, nodata=None) -> Input:
    """The DataArray ``da`` checked and converted (see the module's notes)."""
    from rasterio.crs import CRS

    from ..io.dem import grid_of
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
    return Input(z, grid, transform, crs, nodata, path, y_dim, x_dim, coords)


def as_dem(inp: Input):
    """The heights in memory as an ``io.Dem`` (what the command line reads)."""
    from ..io.dem import Dem
    dem = Dem(heights=inp.heights, grid=inp.grid, path=inp.path, kind="xarray",
              transform=inp.transform, crs=inp.crs, nodata=inp.nodata, driver="xarray",
              source_dtype="float32")
    if dem.heights.size == 0:
        raise HillshadeError(f"{inp.path}: the DataArray is empty")
    if dem.valid_count() == 0:
        raise HillshadeError(f"{inp.path}: every cell is nodata, nothing to shade")
    return dem


def with_heights(inp: Input, z) -> Input:
    """``inp`` with the heights ``z`` (a window's, or the computed whole of a Dask input)."""
    return Input(z, inp.grid, inp.transform, inp.crs, inp.nodata, inp.path, inp.y_dim,
                 inp.x_dim, inp.coords)


# ---------------------------------------------------------------------------------------------
# the output

def wrap(arr, inp: Input, attrs: dict, nodata, name: str, extra_dim=None) -> xr.DataArray:
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


def time_list(time, tz=None):
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


def utc64(t: _dt.datetime) -> np.datetime64:
    return np.datetime64(t.astimezone(_dt.timezone.utc).replace(tzinfo=None), "ns")


def sun_attrs(sun) -> dict:
    """The command line's tags of one sun (``run.outputs.sun_tags``) as numbers and texts."""
    from ..model.times import iso
    d = {"sun_azimuth": float(sun.azimuth), "sun_elevation": float(sun.elevation),
         "night": "yes" if sun.night else "no"}
    if sun.time is not None:
        d["time"] = iso(sun.time)
    if sun.tiles:
        d["sun_mode"] = f"per tile ({len(sun.tiles)} tiles)"
    return d


def series_dim(suns):
    """The ``time`` dimension of a series: UTC times, with each sun's azimuth, elevation and
    the time with its offset as coordinates along it."""
    from ..model.times import iso
    t = [utc64(s.time) for s in suns]
    return ("time", {"time": ("time", np.array(t, "datetime64[ns]")),
                     "sun_azimuth": ("time", np.array([s.azimuth for s in suns])),
                     "sun_elevation": ("time", np.array([s.elevation for s in suns])),
                     "time_local": ("time", np.array([iso(s.time) for s in suns], object))})

