"""OUTPUT of a period's sums (``irradiance``'s four bands, ``sun-hours``' hours; with --monthly a
band per month after them) named ``*.nc`` or ``*.zarr`` without --format: one CF-1.8 dataset
(``io.cube.CubeWriter``) with the variables and coordinates ``da.hrt.irradiance`` and
``da.hrt.sun_hours(monthly=True)`` give an xarray user, instead of GDAL's netCDF bands.

- the period's totals on (``y``, ``x``): ``beam_rad``, ``diff_rad``, ``refl_rad``, ``glob_rad``
  (``Wh m-2``; ``W m-2`` with --mean; ``Wh m-2 day-1`` with --daily-mean), or ``insol_time``
  (``h``), each with its ``long_name``, ``units``, ``cell_methods``, the grid mapping and the
  ``_FillValue`` -9999;
- with --monthly the months' bands as one variable on (``time``, ``y``, ``x``):
  ``glob_rad_monthly`` or ``insol_time_monthly``, ``time`` each month's first day at 00:00
  (as the accessor's: a label of the month in the period's local time, the zone of --tz or
  local mean solar time, said by ``time``'s ``comment``) with CF cell bounds ``time_bnds``
  (the month's start and end, clipped to the period's), the coordinates ``month``
  ("YYYY-MM") and, for irradiance, ``hours`` (the month's sampled hours); one time step per
  chunk;
- the period as global attributes: ``period_start`` and ``period_end`` (ISO 8601: the first
  and last day of --date/--end-date, or --start and --end with their offsets), ``period``
  (the GeoTIFF's PERIOD tag, or sun-hours' DAY), and the GeoTIFF's other tags lower-cased.

The runs open their writer with :func:`period_writer` (in memory, in windows: it takes
:class:`.raster.BandWriter`'s ``write(band, array, description, tags, window)``) or, on Dask,
:func:`period_parts` (it takes ``horizon_windows.VrtOutput``'s ``write(bands)`` of the
workers' parts); both pick the cube by OUTPUT's name (:func:`use_period_cube`). The bands go
to the variables in the GeoTIFF's order (the totals, then a band per month), so a cube's
variable is the GeoTIFF's band of the same command line bit for bit.

References
----------
Eaton, B. et al. (2020). NetCDF Climate and Forecast (CF) Metadata Conventions, version 1.8,
section 7.1 (cell boundaries) and 7.3 (cell methods).
https://cfconventions.org/Data/cf-conventions/cf-conventions-1.8/cf-conventions.html
"""

from __future__ import annotations

import datetime as _dt


NODATA = -9999.0
# the period's quantities (engine.irradiance.BANDS, r.sun's names) and what they are
_IRRADIATION = {
    "beam": "beam (direct) irradiation on the cell's surface, 0 in cast shadow",
    "diffuse": "diffuse sky irradiation on the cell's surface",
    "reflected": "irradiation reflected by the terrain onto the cell's surface",
    "global": "global irradiation on the cell's surface (beam + diffuse + reflected)"}
# sun-hours' variable: r.sun's insol_time (``run.sun_hours_windows.RSUN_NAME``), its long name
SUN_HOURS = ("insol_time", "hours of direct sun")
# the GeoTIFF's tags that name its bands (their order, units, names): the variables' now
_BAND_TAGS = ("UNITS", "MONTHS", "NAME", "RSUN_NAME")


def use_period_cube(cfg) -> bool:
    """Whether OUTPUT is a CF dataset (``io.cube.cube_output``: ``*.nc`` or ``*.zarr`` without
    --format; --co refused then, a missing library named: before any work when the run calls
    it first)."""
    from ..io.cube import cube_output
    return cube_output(cfg.output, cfg.run.fmt, cfg.run.creation_options) is not None


def period_writer(cfg, geom, tags: dict, months=(), *, dem=None, resampling=None):
    """OUTPUT's writer of a period's bands (the totals, then a band per month of ``months``):
    ``io.BandWriter`` (float32, -9999 nodata, ``tags``, ``resampling`` its overviews'), or the
    CF dataset (``io.cube.CubeWriter``) where :func:`use_period_cube`; either takes
    ``write(band, array, description, tags, window)`` and ``finish()``.

    Parameters
    ----------
    cfg : IrradianceConfig or SunHoursConfig
        The run's (OUTPUT, --format, --co, --overwrite, the period, --mean, --daily-mean).
    geom : object
        The output's grid: ``shape``, ``transform``, ``crs``.
    tags : dict
        The GeoTIFF's dataset tags (PERIOD, DATE_FIRST, ...).
    months : sequence
        --monthly: each month's (year, month), or ((year, month), sampled hours).
    dem : object, optional
        The DEM the run's place comes from (its site), needed only for the local mean solar
        time of a --start/--end period's months without --tz.
    resampling : str, optional
        The GeoTIFF's overviews' resampling.
    """
    months = [_month(m) for m in months]
    if not use_period_cube(cfg):
        from ..io import BandWriter
        ro = cfg.run
        kw = {} if resampling is None else {"overview_resampling": resampling}
        return BandWriter(cfg.output, geom, len(_quantities(cfg)) + len(months), "float32",
                          NODATA, tags, overwrite=ro.overwrite, fmt=ro.fmt,
                          co=ro.creation_options, **kw)
    from ..io.cube import CubeWriter
    return CubeWriter(cfg.output, geom, **cube_layout(cfg, tags, months, dem),
                      overwrite=cfg.run.overwrite)


def period_parts(cfg, src, descriptions, tags: dict, band_tags=None, months=(), *, dem=None,
                 resampling: str = "nearest"):
    """A Dask run's OUTPUT from its workers' parts: ``horizon_windows.VrtOutput`` (GDAL's copy
    of a VRT of the parts, as before), or where :func:`use_period_cube` the CF dataset written
    part by part (:class:`_PartsToCube`); either takes ``write(bands)``, a list of
    ``io.vrt.VrtSource`` per band."""
    if not use_period_cube(cfg):
        from .horizon_windows import VrtOutput
        ro = cfg.run
        return VrtOutput(cfg.output, src.shape, src.transform, src.crs, descriptions, tags,
                         band_tags=band_tags, resampling=resampling, overwrite=ro.overwrite,
                         fmt=ro.fmt, co=ro.creation_options)
    return _PartsToCube(lambda: period_writer(cfg, src, tags, months, dem=dem))


class _PartsToCube:
    """``VrtOutput.write``'s bands (each a list of ``io.vrt.VrtSource``: a part's band and
    where it goes) read part by part into the cube of ``open_writer()``."""

    def __init__(self, open_writer):
        self.open_writer = open_writer

    def write(self, bands) -> None:
        import rasterio
        from rasterio.windows import Window

        from ..io import gdal_checked
        with self.open_writer() as w:
            for b, sources in enumerate(bands, 1):
                for s in sources:
                    (r0, c0), (h, wd), (sr, sc) = s.offset, s.shape, s.src_offset
                    with gdal_checked(s.path, "cannot read"), rasterio.open(s.path) as part:
                        v = part.read(s.band, window=Window(sc, sr, wd, h))
                    w.write(b, v, window=(r0, r0 + h, c0, c0 + wd))


def _month(m) -> tuple:
    """((year, month), hours or None) of a month given either way."""
    if len(m) == 2 and isinstance(m[0], tuple):
        return (int(m[0][0]), int(m[0][1])), None if m[1] is None else float(m[1])
    return (int(m[0]), int(m[1])), None


def _irradiance(cfg) -> bool:
    from .config import IrradianceConfig
    return isinstance(cfg, IrradianceConfig)


def _quantities(cfg) -> list:
    """The totals' bands: engine.irradiance.BANDS, or the one of sun-hours."""
    if _irradiance(cfg):
        from ..engine.irradiance import BANDS
        return list(BANDS)
    return ["hours"]


def _units(cfg) -> tuple[str, str]:
    """(CF units, cell_methods) of the totals and the months."""
    if not _irradiance(cfg):
        return "h", "time: sum"
    if cfg.mean:
        return "W m-2", "time: mean"
    if cfg.daily_mean:
        return "Wh m-2 day-1", "time: mean (of the daily sums)"
    return "Wh m-2", "time: sum"


def cube_variables(cfg, monthly: bool) -> list:
    """The data variables (``io.cube.CubeVariable``), in the GeoTIFF's band order: the totals
    on (y, x), then with ``monthly`` the months' on (time, y, x)."""
    from ..io.cube import CubeVariable
    units, methods = _units(cfg)
    if _irradiance(cfg):
        from ..engine.irradiance import BANDS, RSUN_NAMES
        out = [CubeVariable(RSUN_NAMES[q], "float32", NODATA,
                            {"long_name": _IRRADIATION[q], "units": units,
                             "cell_methods": methods, "quantity": q}, timed=False)
               for q in BANDS]
        month = CubeVariable(RSUN_NAMES["global"] + "_monthly", "float32", NODATA,
                             {"long_name": "global irradiation of each month", "units": units,
                              "cell_methods": methods, "quantity": "global"})
    else:
        RSUN_NAME, DESCRIPTION = SUN_HOURS
        out = [CubeVariable(RSUN_NAME, "float32", NODATA,
                            {"long_name": f"{DESCRIPTION} over the period", "units": units,
                             "cell_methods": methods}, timed=False)]
        month = CubeVariable(RSUN_NAME + "_monthly", "float32", NODATA,
                             {"long_name": f"{DESCRIPTION} of each month", "units": units,
                              "cell_methods": methods})
    return out + ([month] if monthly else [])


def cube_layout(cfg, tags: dict, months, dem=None) -> dict:
    """CubeWriter's keywords for the period's dataset (:func:`period_writer`): the times, the
    variables, the months' bounds and coordinates, the global attributes."""
    from .outputs import cube_globals
    months = [_month(m) for m in months]
    (p0, p1), (start, end), clock = period_of(cfg, tags, dem if months else None)
    what = ("irradiation over a period" if _irradiance(cfg) else
            "hours of direct sun over a period")
    attrs = {"period_start": p0, "period_end": p1}
    if "PERIOD" not in tags and "DAY" in tags:
        attrs["period"] = f"{tags['DATE_FIRST']} to {tags['DATE_LAST']} ({tags['DAY']})"
    glob = cube_globals(f"hillshade-rt: {what}",
                        {k: v for k, v in tags.items() if k not in _BAND_TAGS},
                        getattr(cfg, "command", None))
    kw = {"variables": cube_variables(cfg, bool(months)),
          "global_attrs": {**glob, **attrs}}
    if not months:
        return {"times": [], **kw}
    firsts, bounds = month_bounds([k for k, _ in months], start, end)
    coords = {"month": ([f"{y:04d}-{m:02d}" for (y, m), _ in months],
                        {"long_name": "month (YYYY-MM, in the period's local time)"})}
    if all(h is not None for _, h in months):
        coords["hours"] = ([h for _, h in months],
                           {"long_name": "hours of the period sampled in the month",
                            "units": "h"})
    return {"times": firsts, **kw, "time_bounds": bounds, "time_coords": coords,
            "time_attrs": {"long_name": "month (its first day at 00:00, local time)",
                           "comment": f"the months and their bounds are in {clock}, not "
                                      "UTC: a month's first day at 00:00 labels it, time_bnds "
                                      "are its start and end clipped to the period's"}}


def month_bounds(keys, start: _dt.datetime, end: _dt.datetime) -> tuple[list, list]:
    """(each month's first day at 00:00, its (start, end) clipped to ``start`` .. ``end``):
    naive datetimes of one local clock."""
    firsts, bounds = [], []
    for y, m in keys:
        first = _dt.datetime(y, m, 1)
        after = _dt.datetime(y + (m == 12), m % 12 + 1, 1)
        firsts.append(first)
        bounds.append((max(first, start), min(after, end)))
    return firsts, bounds


def period_of(cfg, tags: dict, dem=None) -> tuple:
    """((period_start, period_end) as ISO 8601 texts, (start, end) as naive datetimes of the
    months' local clock, that clock in words). --date [--end-date]: the first and last day,
    midnight to midnight; --start/--end: as the PERIOD tag shows them (in --tz's zone, else
    with their offsets); their months' clock then the zone's, or without --tz the local mean
    solar time at the site of ``dem``."""
    from ..model.times import parse_date
    place = dict(getattr(cfg, "place", None) or {})
    day = tags.get("DAY") or tags.get("PERIOD", "")
    if getattr(cfg, "date", None) is not None:
        first = parse_date(tags.get("DATE_FIRST", cfg.date))
        last = parse_date(tags.get("DATE_LAST", cfg.end_date or cfg.date))
        clock = (day[day.find("(") + 1:day.rfind(")")] if "(" in day else day) or \
            "the period's local time"
        clock = clock.replace("midnight to midnight, ", "")
        return ((first.isoformat(), last.isoformat()),
                (_dt.datetime.combine(first, _dt.time()),
                 _dt.datetime.combine(last + _dt.timedelta(days=1), _dt.time())), clock)
    if " to " in tags.get("PERIOD", ""):
        a, b = tags["PERIOD"].split(" to ", 1)
    else:           # (a DEM of voids only: the command line's)
        a, b = str(cfg.start), str(cfg.end)
    if dem is None:         # (no months: their clock is not needed)
        return (a, b), (None, None), "the period's local time"
    t0, t1 = _dt.datetime.fromisoformat(a), _dt.datetime.fromisoformat(b)
    if t0.tzinfo is None:
        return (a, b), (t0.replace(tzinfo=None), t1.replace(tzinfo=None)), \
            "the offsets of --start and --end"
    from ..model.sun import SunRequest
    req = SunRequest.at_place([], **place)
    lon = req.site(dem).lon             # (and --tz auto's zone there)
    if req.tz is not None:      # the PERIOD tag shows the times in it
        return (a, b), (t0.replace(tzinfo=None), t1.replace(tzinfo=None)), \
            getattr(req.tz, "key", str(req.tz))
    shift = _dt.timedelta(hours=lon / 15.0)

    def solar(t):
        return t.astimezone(_dt.timezone.utc).replace(tzinfo=None) + shift
    return (a, b), (solar(t0), solar(t1)), f"local mean solar time at longitude {lon:.4f}"
