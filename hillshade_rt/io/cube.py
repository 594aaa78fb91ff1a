"""Time cubes: a (time, y, x) stack of rasters on one grid written as one CF-1.8 NetCDF4 file
(``OUT.nc``, through Unidata's netCDF4) or one Zarr store (``OUT.zarr``, through xarray and
zarr), whole or not at all.

The layout is the one xarray, rioxarray, GDAL's netCDF driver and CF readers (Panoply, CDO,
ncview) understand without being told:

- dimensions ``time``, ``y``, ``x``; the coordinate variable ``time`` in whole seconds (or
  microseconds) since 1970-01-01 00:00:00 UTC, calendar "standard"; ``x`` and ``y`` the cells'
  centres in the CRS's units (``projection_x_coordinate`` / ``projection_y_coordinate``, or
  ``longitude`` / ``latitude`` in degrees_east / degrees_north for a geographic CRS);
- a grid-mapping variable ``spatial_ref`` (pyproj's CF attributes, ``crs_wkt``, GDAL's
  ``spatial_ref`` and ``GeoTransform``) named by the data variable's ``grid_mapping`` (and its
  ``coordinates``, where rioxarray looks);
- the data variable (``name``: the product), or several on the same axes (``variables``: the
  irradiance instants' ``beam_rad``, ``diff_rad``, ``refl_rad``, ``glob_rad``, ``incidout``),
  each with its ``_FillValue`` (the nodata value), chunked one time step per chunk (at most
  :data:`CHUNK` cells a side), compressed (NetCDF: zlib with the shuffle filter; Zarr: the zarr
  library's default codec);
- per-time variables (the sun's azimuth and elevation of a lighting series, ...) on ``time``;
- optionally the time steps' cell bounds ``time_bnds`` (``time``, ``nv``: CF's ``bounds`` of
  ``time``: a month of a period's sums, clipped to the period), auxiliary coordinates on
  ``time`` (``month`` labels "YYYY-MM", ...), and data variables on (``y``, ``x``) only beside
  the (``time``, ``y``, ``x``) ones (a period's totals beside its months; a cube of such
  variables only has no ``time`` at all);
- global attributes ``Conventions`` "CF-1.8", ``title``, ``history``, ``source``, ...

The data may be written a time step at a time or a window of a time step at a time (the runs
in windows of rasters larger than memory): :class:`CubeWriter` takes the calls
:class:`.raster.BandWriter` takes. A NetCDF file goes through :func:`.write.atomic_path` (a
temporary file beside it, synced, published by a rename that replaces nothing without
``overwrite``); a Zarr store is a folder: written into a hidden temporary folder beside it,
every file synced, then renamed into place (``renameat2(RENAME_NOREPLACE)`` where there is
one; with ``overwrite`` an existing store is moved aside first and removed after). On any
failure or interruption the temporary file or folder is removed.

References
----------
Eaton, B. et al. (2020). NetCDF Climate and Forecast (CF) Metadata Conventions, version 1.8.
https://cfconventions.org/Data/cf-conventions/cf-conventions-1.8/cf-conventions.html
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import os
import sys
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import HillshadeError
from .write import (atomic_folder, atomic_path, check_output_path, disk_full, is_virtual,
                    os_error)

CUBE_SUFFIXES = {".nc": "netcdf", ".zarr": "zarr"}
CHUNK = 1024          # a chunk's largest side, cells (one time step per chunk)
ZLIB_LEVEL = 4        # NetCDF's zlib level (netCDF4's default, with the shuffle filter)
GRID_MAPPING = "spatial_ref"
_EPOCH = _dt.datetime(1970, 1, 1, tzinfo=_dt.timezone.utc)


def cube_format(path) -> str | None:
    """"netcdf" for ``*.nc``, "zarr" for ``*.zarr`` (any case, a trailing slash allowed), else
    None."""
    if path is None:
        return None
    p = os.fspath(path).rstrip("/\\")
    return CUBE_SUFFIXES.get(os.path.splitext(p)[1].lower())


def check_cube_support(path) -> str:
    """The cube's format (:func:`cube_format`) once its libraries are known to be there and
    the path is a local one: a one-line :class:`HillshadeError` naming what to install (or
    that GDAL's virtual files are not for cubes) otherwise, before any work."""
    import importlib.util
    fmt = cube_format(path)
    if fmt is not None and is_virtual(os.fspath(path)):
        raise HillshadeError(f"{path}: a time cube is written to a local file or folder "
                             "(netCDF4 and zarr, not GDAL's virtual files)")
    if fmt == "netcdf" and importlib.util.find_spec("netCDF4") is None:
        raise HillshadeError(f"{path}: a NetCDF time cube needs netCDF4: pip install netCDF4")
    if fmt == "zarr" and any(importlib.util.find_spec(m) is None
                             for m in ("xarray", "zarr", "dask")):
        raise HillshadeError(f"{path}: a Zarr time cube needs xarray, zarr and dask: "
                             "pip install 'hillshade-rt[xarray]'")
    return fmt


def cube_output(output, fmt, creation_options, refused=()) -> str | None:
    """The cube's format (:func:`check_cube_support`) where OUTPUT is a CF time cube: named
    ``*.nc`` or ``*.zarr`` and no --format (which names GDAL's driver, ``-f netCDF`` its bands);
    None otherwise. --co (GDAL's creation options) is refused with a cube (a usage error), then
    each given option of ``refused`` (its message; None: not given), then a missing library is
    named: before any work when a run asks first."""
    if output is None or fmt is not None or cube_format(output) is None:
        return None
    from ..errors import UsageProblem
    if creation_options:
        raise UsageProblem(f"{output}: --co sets GDAL's creation options; a time cube (.nc, "
                           ".zarr) is written compressed, chunked, without them: drop --co, "
                           "or write a GeoTIFF (.tif)")
    for why in refused:
        if why:
            raise UsageProblem(why)
    return check_cube_support(output)


def time_values(times) -> tuple[np.ndarray, str]:
    """``times`` (aware datetimes, naive ones taken as UTC, or numpy datetime64) as CF numbers:
    (int64 values, units): whole seconds since 1970-01-01 00:00:00 UTC where every time is a
    whole second, else microseconds."""
    us = []
    for t in times:
        if isinstance(t, np.datetime64):
            us.append(int(t.astype("datetime64[us]").astype(np.int64)))
            continue
        if t.tzinfo is None:
            t = t.replace(tzinfo=_dt.timezone.utc)
        us.append((t - _EPOCH) // _dt.timedelta(microseconds=1))
    us = np.asarray(us, np.int64)
    if (us % 1_000_000 == 0).all():
        return us // 1_000_000, "seconds since 1970-01-01 00:00:00"
    return us, "microseconds since 1970-01-01 00:00:00"


def _geotransform(transform) -> str:
    """GDAL's GeoTransform attribute: "c a b f d e" (origin x, pixel width, row rotation, origin
    y, column rotation, pixel height)."""
    t = tuple(transform)[:6]
    a, b, c, d, e, f = t
    return " ".join(f"{v:.17g}" for v in (c, a, b, f, d, e))


def _crs_wkt(crs) -> str | None:
    if crs is None:
        return None
    if isinstance(crs, str):
        return crs
    to_wkt = getattr(crs, "to_wkt", None)
    return to_wkt() if to_wkt is not None else str(crs)


def grid_variables(shape, transform, crs) -> tuple[dict, dict | None]:
    """The coordinate variables of a grid: ({"y": (values, attrs), "x": (values, attrs)}, the
    grid-mapping variable's attributes or None without a CRS). ``transform``: an
    affine.Affine (north-up or not, no rotation) or None (the cells' indices + 0.5)."""
    rows, cols = shape
    j, i = np.arange(cols) + 0.5, np.arange(rows) + 0.5
    if transform is None:
        return ({"y": (i, {"long_name": "row (cell centres)", "units": "1"}),
                 "x": (j, {"long_name": "column (cell centres)", "units": "1"})}, None)
    a, b, c, d, e, f = tuple(transform)[:6]
    if b or d:
        raise HillshadeError("a rotated or sheared grid cannot be a CF time cube; write a "
                             "GeoTIFF (.tif)")
    x, y = c + j * a, f + i * e
    wkt = _crs_wkt(crs)
    geographic, cf, units = False, {}, None
    if wkt:
        from pyproj import CRS
        pc = CRS.from_wkt(wkt)
        geographic = pc.is_geographic
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")     # "you will likely lose important projection
            cf = pc.to_cf()                     # information": the WKT below keeps it whole
        if not geographic and pc.axis_info:
            units = pc.axis_info[0].unit_name
    if geographic:
        xa = {"standard_name": "longitude", "long_name": "longitude", "units": "degrees_east",
              "axis": "X"}
        ya = {"standard_name": "latitude", "long_name": "latitude", "units": "degrees_north",
              "axis": "Y"}
    else:
        xa = {"standard_name": "projection_x_coordinate",
              "long_name": "x coordinate of projection", "axis": "X"}
        ya = {"standard_name": "projection_y_coordinate",
              "long_name": "y coordinate of projection", "axis": "Y"}
        if units:
            u = {"metre": "m", "meter": "m", "US survey foot": "US_survey_foot",
                 "foot": "ft"}.get(units, units)
            xa["units"] = ya["units"] = u
    gm = None
    if wkt:
        gm = {k: v for k, v in cf.items() if k != "crs_wkt"}
        gm.update(crs_wkt=wkt, spatial_ref=wkt, GeoTransform=_geotransform(transform))
    return {"y": (y, ya), "x": (x, xa)}, gm


@dataclass(frozen=True)
class CubeVariable:
    """One data variable of a cube with several (:class:`CubeWriter`'s ``variables``).

    Parameters
    ----------
    name : str
        The variable's name ("glob_rad", ...).
    dtype : str
        numpy's name of its type ("float32", ...).
    nodata : float or int or None
        Its ``_FillValue`` (None: none).
    attrs : dict
        Its attributes (``units``, ``long_name``, ``standard_name``, ...).
    timed : bool
        On (``time``, ``y``, ``x``), one layer per time step (the default); False: on (``y``,
        ``x``), one layer (a period's total beside its months).
    """

    name: str
    dtype: str
    nodata: object = None
    attrs: dict = field(default_factory=dict)
    timed: bool = True


class CubeWriter:
    """A (time, y, x) cube georeferenced like ``dem`` (anything with ``shape``, ``transform``:
    affine.Affine or None, ``crs``: rasterio's or pyproj's CRS, WKT, or None) written one time
    step, or one window of one, at a time, published under ``path`` when complete; the calls
    of :class:`.raster.BandWriter`::

        with CubeWriter("out.nc", dem, times, name="shadow", dtype="uint8", nodata=255) as w:
            w.write(1, mask)                           # time step 1 (1-based), whole
            w.write(2, part, window=(r0, r1, c0, c1))  # or a window of it

    With several data variables (``variables`` instead of ``name``, ``dtype``, ``nodata`` and
    ``attrs``) the bands are taken in a multi-band GeoTIFF's order: first one band per
    variable on (``y``, ``x``) only (``timed`` False), in order, then the (``time``, ``y``,
    ``x``) ones time by time: with ``u`` of the first kind and ``n`` of the second, band ``b``
    (1-based) past ``u`` is timed variable ``(b - u - 1) % n`` at time step
    ``(b - u - 1) // n``, so the writer stands in for :class:`.raster.BandWriter` of a run that
    writes ``n`` bands per time (or a period's totals, then a band per month); ``bands`` gives
    another order, :meth:`write_variable` names the variable instead::

        variables = [CubeVariable("beam_rad", "float32", -9999.0, {"units": "W m-2"}), ...]
        with CubeWriter("out.nc", dem, times, variables=variables) as w:
            w.write(1, beam_at_t0)                     # band 1: beam_rad, time step 1
            w.write_variable("glob_rad", 2, glob_at_t1)

        total = CubeVariable("glob_rad", "float32", -9999.0, {"units": "Wh m-2"}, timed=False)
        months = CubeVariable("glob_rad_monthly", "float32", -9999.0, {"units": "Wh m-2"})
        with CubeWriter("out.nc", dem, month_starts, variables=[total, months],
                        time_bounds=[(start, end), ...]) as w:
            w.write(1, period_total)                   # band 1: glob_rad (y, x)
            w.write(2, first_month)                    # band 2: glob_rad_monthly, time step 1

    Parameters
    ----------
    path : str
        ``*.nc`` (NetCDF4, netCDF4) or ``*.zarr`` (a Zarr store, xarray and zarr).
    dem : object
        The grid: ``shape`` (rows, cols), ``transform``, ``crs``.
    times : sequence of datetime.datetime or numpy.datetime64
        One per time step (aware; naive ones are UTC), written as CF times in UTC; none when
        every data variable is on (``y``, ``x``) only (then the cube has no ``time``).
    name : str
        The data variable's name (the product: "shadow", "hillshade", ...); None with
        ``variables``.
    dtype : str
        "uint8", "uint16", "int16", "float32", ... (numpy's name).
    nodata : float or int or None
        The ``_FillValue`` (None: none).
    attrs : dict, optional
        The data variable's attributes (``units``, ``long_name``, ``flag_values``, ...).
    variables : sequence of CubeVariable, optional
        Several data variables on the same (time, y, x) axes, in this order (instead of
        ``name``, ``dtype``, ``nodata`` and ``attrs``).
    time_variables : dict, optional
        ``{name: (values, attrs)}``: a value per time step each (the sun's ``azimuth`` and
        ``elevation`` in degrees, ...), float64 unless the values say otherwise.
    time_coords : dict, optional
        ``{name: (values, attrs)}``: a value per time step each, auxiliary coordinates of the
        timed data variables (named by their ``coordinates``, so xarray makes them coordinates):
        numbers, or strings ("YYYY-MM" month labels).
    time_bounds : sequence of (start, end), optional
        Each time step's cell bounds (as ``times``: aware, or naive read as UTC): the variable
        ``time_bnds`` (``time``, ``nv``) in ``time``'s units, named by its ``bounds``.
    time_attrs : dict, optional
        Attributes of ``time`` replacing or added to the defaults (``long_name`` "time (UTC)",
        ...): a ``comment`` on the clock of times that are local labels, ...
    bands : sequence of (name, step), optional
        Each band's data variable and time step (1-based; None for a variable on (``y``,
        ``x``) only), band 1 first, instead of the default order above.
    global_attrs : dict, optional
        Global attributes (``title``, ``history``, ``source``, ...) after
        ``Conventions = "CF-1.8"``.
    overwrite : bool
        Replace an existing file or Zarr store at ``path`` (else it is an error, also when
        one appears while the cube is written).
    chunk : int
        A chunk's largest side in cells (one time step per chunk).
    """

    def __init__(self, path, dem, times, *, name: str | None = None, dtype: str | None = None,
                 nodata=None, attrs: dict | None = None, variables=None,
                 time_variables: dict | None = None, global_attrs: dict | None = None,
                 overwrite: bool = False, chunk: int = CHUNK, time_coords: dict | None = None,
                 time_bounds=None, time_attrs: dict | None = None, bands=None):
        if variables is None:
            if name is None or dtype is None:
                raise ValueError("a cube's data variable needs a name and a dtype")
            variables = [CubeVariable(name, dtype, nodata, dict(attrs or {}))]
        elif name is not None or dtype is not None or nodata is not None or attrs is not None:
            raise ValueError("give the data variables one way: name, dtype, nodata and attrs, "
                             "or variables")
        variables = list(variables)
        names = [v.name for v in variables]
        if not names or len(set(names)) != len(names):
            raise ValueError(f"a cube's data variables need distinct names, got {names}")
        per_time = set(time_variables or {}) | set(time_coords or {})
        if set(time_variables or {}) & set(time_coords or {}):
            raise ValueError("a per-time variable and a time coordinate of the same name")
        reserved = {"time", "time_bnds", "nv", "x", "y", GRID_MAPPING} | per_time
        if reserved & set(names) or per_time & {"time", "time_bnds", "nv", "x", "y",
                                                GRID_MAPPING}:
            raise ValueError(f"{sorted(reserved & (set(names) | per_time))[0]!r}: the name of a "
                             "coordinate or per-time variable")
        self.timed = any(v.timed for v in variables)
        self._timed = {v.name: bool(v.timed) for v in variables}
        if not self.timed and (len(times) or per_time or time_bounds is not None):
            raise ValueError("a cube whose data variables are all on (y, x) has no time axis: "
                             "give no times, per-time variables or bounds")
        if self.timed and not len(times):
            raise ValueError("a cube's time axis needs a time at least")
        self.path = os.fspath(path)
        self.format = check_cube_support(self.path)
        if self.format is None:
            raise HillshadeError(f"{self.path}: a time cube is a .nc or .zarr path")
        check_output_path(self.path, overwrite)     # (exists, no folder, ...: before any work)
        self.shape = tuple(int(n) for n in dem.shape)
        self.count = len(times)
        self.bounds = None
        if time_bounds is not None:
            time_bounds = [tuple(b) for b in time_bounds]
            if len(time_bounds) != self.count or any(len(b) != 2 for b in time_bounds):
                raise ValueError(f"time bounds: {len(time_bounds)} pairs for {self.count} times")
            # (one set of units for the times and their bounds)
            both, self.time_units = time_values(list(times) + [t for b in time_bounds
                                                               for t in b])
            self.time = both[:self.count]
            self.bounds = both[self.count:].reshape(self.count, 2)
        else:
            self.time, self.time_units = time_values(times)
        self.time_attrs = dict(time_attrs or {})
        self.coords, self.grid_mapping = grid_variables(self.shape, dem.transform, dem.crs)
        # (name, numpy dtype, nodata of that type or None, attrs) of each data variable
        self.variables = []
        for v in variables:
            dt = np.dtype(v.dtype)
            self.variables.append((v.name, dt, None if v.nodata is None else dt.type(v.nodata),
                                   dict(v.attrs or {})))
        self.name, self.dtype, self.nodata, self.attrs = self.variables[0]    # (the first)
        self.time_variables = {}
        for k, (values, a) in (time_variables or {}).items():
            v = np.asarray(values)
            if v.shape != (self.count,):
                raise ValueError(f"time variable {k}: {v.shape[0] if v.ndim else 0} values for "
                                 f"{self.count} times")
            if v.dtype.kind not in "iuf":
                v = v.astype(np.float64)
            self.time_variables[k] = (v, dict(a))
        self.time_coords = {}
        for k, (values, a) in (time_coords or {}).items():
            v = np.asarray(values)
            if v.shape != (self.count,):
                raise ValueError(f"time coordinate {k}: {v.shape[0] if v.ndim else 0} values "
                                 f"for {self.count} times")
            if v.dtype.kind in "US":
                v = v.astype(object)        # (variable-length strings)
            elif v.dtype.kind not in "iufO":
                v = v.astype(np.float64)
            self.time_coords[k] = (v, dict(a))
        self.layout = self._layout(bands)
        self.global_attrs = {"Conventions": "CF-1.8", **(global_attrs or {})}
        self.overwrite = overwrite
        rows, cols = self.shape
        self.chunks = (1, max(1, min(rows, chunk)), max(1, min(cols, chunk)))
        self._stack = contextlib.ExitStack()
        self._nc = self._zarr = None
        self._vars: dict = {}     # each data variable's netCDF4 variable or zarr array
        self._tmp = None
        self._finished = False

    def _layout(self, bands) -> list:
        """Each band's (data variable, time step or None), band 1 first."""
        timed = self._timed
        if bands is None:
            flat = [n for n, *_ in self.variables if not timed[n]]
            steps = [n for n, *_ in self.variables if timed[n]]
            return [(n, None) for n in flat] + [(n, k + 1) for k in range(self.count)
                                                for n in steps]
        out = []
        for n, step in bands:
            if n not in timed:
                raise ValueError(f"{self.path}: bands: no data variable {n!r}")
            if (step is None) == timed[n] or (step is not None
                                              and not 1 <= step <= self.count):
                raise ValueError(f"{self.path}: bands: {n!r} at time step {step}")
            out.append((n, step))
        return out

    # -- the layout, shared by both formats --------------------------------------------------

    def _dims(self, name: str) -> tuple:
        return ("time", "y", "x") if self._timed[name] else ("y", "x")

    def _chunks(self, name: str) -> tuple:
        return self.chunks if self._timed[name] else self.chunks[1:]

    def _time_attrs(self) -> dict:
        a = {"standard_name": "time", "long_name": "time (UTC)", "axis": "T",
             "units": self.time_units, "calendar": "standard"}
        if self.bounds is not None:
            a["bounds"] = "time_bnds"
        a.update(self.time_attrs)
        return a

    def _data_attrs(self, attrs: dict, timed: bool = True) -> dict:
        a = dict(attrs)
        coords = [GRID_MAPPING] if self.grid_mapping is not None else []
        if timed:
            coords += list(self.time_coords)
        if self.grid_mapping is not None:
            a["grid_mapping"] = GRID_MAPPING
        if coords:      # (rioxarray finds the CRS through it; xarray the time coordinates)
            a["coordinates"] = " ".join(coords)
        return a

    # -- opening -----------------------------------------------------------------------------

    def __enter__(self):
        try:
            if self.format == "netcdf":
                self._open_netcdf()
            else:
                self._open_zarr()
        except BaseException:
            if not self._stack.__exit__(*sys.exc_info()):
                raise
        return self

    def _open_netcdf(self):
        import netCDF4
        self._tmp = self._stack.enter_context(atomic_path(self.path, ".nc",
                                                          overwrite=self.overwrite))
        self._stack.callback(self._close_quietly)   # (an error: closed, then removed)
        with self._checked():
            nc = self._nc = netCDF4.Dataset(self._tmp, "w", format="NETCDF4")
            nc.set_auto_maskandscale(False)          # the values as given, bit for bit
            nc.setncatts(self.global_attrs)
            rows, cols = self.shape
            if self.timed:
                nc.createDimension("time", self.count)
            nc.createDimension("y", rows)
            nc.createDimension("x", cols)
            if self.bounds is not None:
                nc.createDimension("nv", 2)
            if self.timed:
                t = nc.createVariable("time", self.time.dtype, ("time",))
                t.setncatts(self._time_attrs())
                t[:] = self.time
            if self.bounds is not None:     # (CF: a bounds variable takes its time's units)
                b = nc.createVariable("time_bnds", self.bounds.dtype, ("time", "nv"))
                b[:] = self.bounds
            for k in ("y", "x"):
                values, a = self.coords[k]
                v = nc.createVariable(k, "f8", (k,))
                v.setncatts(a)
                v[:] = values
            if self.grid_mapping is not None:
                g = nc.createVariable(GRID_MAPPING, "i4")
                g.setncatts(self.grid_mapping)
            for k, (values, a) in self.time_variables.items():
                v = nc.createVariable(k, values.dtype, ("time",))
                v.setncatts(a)
                v[:] = values
            for k, (values, a) in self.time_coords.items():
                v = nc.createVariable(k, str if values.dtype == object else values.dtype,
                                      ("time",))
                v.setncatts(a)
                if values.dtype == object:
                    for i, text in enumerate(values):
                        v[i] = str(text)
                else:
                    v[:] = values
            for name, dtype, nodata, attrs in self.variables:
                d = nc.createVariable(name, dtype, self._dims(name), zlib=True,
                                      complevel=ZLIB_LEVEL, shuffle=True,
                                      chunksizes=self._chunks(name),
                                      fill_value=nodata if nodata is not None else False)
                d.setncatts(self._data_attrs(attrs, self._timed[name]))
                self._vars[name] = d

    def _open_zarr(self):
        import xarray as xr
        import zarr

        self._tmp = self._stack.enter_context(atomic_folder(self.path, ".zarr",
                                                            self.overwrite))
        coords = {"time": ("time", self.time, self._time_attrs())} if self.timed else {}
        for k in ("y", "x"):
            values, a = self.coords[k]
            coords[k] = (k, values, a)
        import dask.array as da
        variables, enc = {}, {}
        for name, dtype, nodata, attrs in self.variables:
            fill = nodata if nodata is not None else dtype.type(0)
            # the data variable's metadata only (a lazy array never computed: compute=False),
            # its chunks written by write()
            timed = self._timed[name]
            blank = da.full(((self.count,) if timed else ()) + self.shape, fill, dtype=dtype,
                            chunks=self._chunks(name))
            attrs = self._data_attrs(attrs, timed)
            attrs.pop("coordinates", None)      # xarray writes it from the coordinates
            variables[name] = (self._dims(name), blank, attrs)
            enc[name] = {"chunks": self._chunks(name), "_FillValue": nodata}
        for k, (values, a) in self.time_variables.items():
            variables[k] = ("time", values, a)
        for k, (values, a) in self.time_coords.items():
            coords[k] = ("time", values, a)
            if values.dtype != object:
                enc[k] = {"_FillValue": None}
        if self.bounds is not None:
            variables["time_bnds"] = (("time", "nv"), self.bounds, {})
            enc["time_bnds"] = {"dtype": self.bounds.dtype, "_FillValue": None}
        if self.grid_mapping is not None:
            coords[GRID_MAPPING] = ((), np.int32(0), self.grid_mapping)
        ds = xr.Dataset(variables, coords=coords, attrs=self.global_attrs)
        enc.update({"x": {"_FillValue": None}, "y": {"_FillValue": None}})
        if self.timed:
            enc["time"] = {"dtype": self.time.dtype, "_FillValue": None}
        with self._checked(), warnings.catch_warnings():
            warnings.simplefilter("ignore")    # zarr v3's note on consolidated metadata
            ds.to_zarr(self._tmp, mode="w", encoding=enc, compute=False)
            self._zarr = zarr.open_group(self._tmp, mode="r+")
            self._vars = {name: self._zarr[name] for name, *_ in self.variables}

    # -- writing -----------------------------------------------------------------------------

    @contextlib.contextmanager
    def _checked(self):
        """netCDF4's, HDF5's and zarr's failures as one line naming the cube (a full disk
        says so)."""
        try:
            yield
        except HillshadeError:
            raise
        except OSError as exc:
            if disk_full(self.path):
                raise HillshadeError(f"{self.path}: cannot write (no space left on device)"
                                     ) from None
            raise os_error(self.path, exc) from None
        except (RuntimeError, ValueError, TypeError) as exc:
            if disk_full(self.path):
                raise HillshadeError(f"{self.path}: cannot write (no space left on device)"
                                     ) from None
            said = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise HillshadeError(f"{self.path}: cannot write ({said})") from None

    def write(self, band: int, data: np.ndarray, description: str = "",
              tags: dict | None = None, window: tuple[int, int, int, int] | None = None):
        """Band ``band`` (1-based), whole or its ``window`` (r0, r1, c0, c1): the data variable
        and time step of the layout (``layout[band - 1]``: with one data variable its time step
        ``band``; with several, those on (``y``, ``x``) first, then the others time by time, a
        GeoTIFF's bands). The band's description and tags are the cube's time, per-time
        variables and attributes (ignored here)."""
        if not 1 <= band <= len(self.layout):
            raise ValueError(f"{self.path}: band {band} of {len(self.layout)}")
        name, step = self.layout[band - 1]
        self.write_variable(name, step, data, window)

    def write_variable(self, name: str, step: int | None, data: np.ndarray,
                       window: tuple[int, int, int, int] | None = None):
        """Time step ``step`` (1-based; None for a data variable on (``y``, ``x``) only) of
        the data variable ``name``, whole or its ``window`` (r0, r1, c0, c1)."""
        r0, r1, c0, c1 = window if window is not None else (0, self.shape[0], 0, self.shape[1])
        if data.shape != (r1 - r0, c1 - c0):
            raise ValueError(f"{self.path}: data of shape {data.shape} for a window of "
                             f"{(r1 - r0, c1 - c0)}")
        if name not in self._vars:
            raise ValueError(f"{self.path}: no data variable {name!r}")
        if not self._timed[name]:
            if step is not None:
                raise ValueError(f"{self.path}: {name!r} has no time axis (step {step})")
            key = (slice(r0, r1), slice(c0, c1))
        elif step is None or not 1 <= step <= self.count:
            raise ValueError(f"{self.path}: time step {step} of {self.count}")
        else:
            key = (step - 1, slice(r0, r1), slice(c0, c1))
        dtype = next(dt for k, dt, *_ in self.variables if k == name)
        data = np.asarray(data, dtype)
        with self._checked():
            self._vars[name][key] = data

    def describe(self, band: int, description: str = "", tags: dict | None = None):
        """(The time step's description and tags: the cube's time and per-time variables.)"""

    def _close_quietly(self):
        if self._nc is not None:
            nc, self._nc = self._nc, None
            with contextlib.suppress(Exception):
                nc.close()

    def finish(self) -> None:
        """Close the cube and publish it now (not at the end of the ``with`` block)."""
        self.__exit__(None, None, None)

    def __exit__(self, *exc):
        if self._finished:
            return False
        self._finished = True
        if exc[0] is None:
            try:
                if self._nc is not None:
                    nc, self._nc = self._nc, None
                    with self._checked():
                        nc.close()
            except BaseException as err:
                self._stack.__exit__(type(err), err, err.__traceback__)
                raise
        return self._stack.__exit__(*exc)


def write_cube(path, data, dem, times, *, name: str, nodata=None, attrs: dict | None = None,
               time_variables: dict | None = None, global_attrs: dict | None = None,
               overwrite: bool = False) -> str:
    """Write the stack ``data`` (time, rows, cols) on the grid of ``dem`` as a CF-1.8 time
    cube at ``path`` (``*.nc``: NetCDF4; ``*.zarr``: Zarr), atomically.

    Parameters
    ----------
    path : str
        The cube: ``*.nc`` or ``*.zarr``.
    data : numpy.ndarray
        (time, rows, cols) values, any numeric type (uint8 masks, float32 fractions, W m-2, ...);
        its type is the data variable's.
    dem : object
        The grid: ``shape`` (rows, cols), ``transform`` (affine.Affine, cell corners in the
        CRS's units, or None), ``crs`` (rasterio's or pyproj's CRS, WKT, or None).
    times : sequence of datetime.datetime or numpy.datetime64
        One per time step; aware datetimes in any zone (naive ones are UTC); stored in UTC.
    name : str
        The data variable's name.
    nodata : float or int, optional
        Its ``_FillValue``.
    attrs : dict, optional
        Its attributes (``units``, ``long_name``, ``standard_name``, ...).
    time_variables : dict, optional
        ``{name: (values, attrs)}``: one value per time step each (e.g. ``"elevation":
        (degrees, {"units": "degree"})``).
    global_attrs : dict, optional
        ``title``, ``history``, ``source``, ... (``Conventions`` is "CF-1.8").
    overwrite : bool
        Replace an existing file or store at ``path``.

    Returns
    -------
    str
        ``path``.

    Raises
    ------
    HillshadeError
        One line: the path cannot be written (exists without ``overwrite``, no space, ...),
        the libraries are missing, the grid is rotated. Nothing is left at ``path`` then.
    """
    data = np.asarray(data)
    if data.ndim != 3 or data.shape[1:] != tuple(dem.shape):
        raise ValueError(f"data of shape {data.shape} for a grid of {tuple(dem.shape)}: give "
                         "(time, rows, cols)")
    if data.shape[0] != len(times):
        raise ValueError(f"{data.shape[0]} time steps of data for {len(times)} times")
    with CubeWriter(path, dem, times, name=name, dtype=data.dtype.name, nodata=nodata,
                    attrs=attrs, time_variables=time_variables, global_attrs=global_attrs,
                    overwrite=overwrite) as w:
        for i in range(data.shape[0]):
            w.write(i + 1, data[i])
    return os.fspath(path)
