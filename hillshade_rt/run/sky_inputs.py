"""The sky's inputs of ``irradiance`` as GRASS r.sun users give them: a number for the whole
DEM, twelve monthly numbers, a raster, or twelve monthly rasters (a file name pattern with
``{month}``).

``--albedo 0.2``, ``--albedo 0.3,0.3,0.25,...`` (12 values, January first), ``--albedo
albedo.tif``, ``--albedo 'albedo_{month:02d}.tif'`` (``{month}``: 1..12, Python's format, so
``{month:02d}`` gives 01..12). A raster is resampled to the DEM's grid bilinearly
(``rasterio.warp.reproject``, its own nodata and the cells outside it NaN); a raster that does
not cover every valid cell of the DEM is refused (one line, exit 2), as is a value out of the
option's range. A sample's month is its local month (the DEM's zone with ``--tz``, else local
mean solar time at the DEM's longitude).

``--linke-turbidity`` takes the same four forms (each sample's clear sky with its month's value,
as r.sun users loop over days with monthly Linke values; a raster: each cell's clear sky with
its own value, as r.sun's ``linke`` map), and so do r.sun's real-sky clear-sky indices
``--beam-index`` and ``--diffuse-index`` (its ``coeff_bh``, ``coeff_dh``: 0..1). A raster of
one value over the DEM is that number: the same bits.

References
----------
.. [1] M. Šúri, J. Hofierka, "A new GIS-based solar radiation model and its application to
       photovoltaic assessments," Transactions in GIS, vol. 8, no. 2, pp. 175-190, 2004.
       :doi:`10.1111/j.1467-9671.2004.00174.x`
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass

import numpy as np

from ..errors import UsageProblem

MONTHS = 12


@dataclass(frozen=True)
class SkyValue:
    """One sky input: ``number`` (the whole DEM, the whole period), ``monthly`` (12 numbers),
    ``path`` (one raster) or ``pattern`` (12 rasters, ``{month}`` formatted 1..12)."""

    option: str
    low: float
    high: float
    number: float | None = None
    monthly: tuple | None = None
    path: str | None = None
    pattern: str | None = None

    @classmethod
    def parse(cls, option: str, value, low: float, high: float,
              hint: str = "") -> "SkyValue | None":
        """The option's value (a number, "a,b,...", a path or a pattern; None: not given)
        checked: numbers within [low, high], 12 of them for months, the files there."""
        if value is None:
            return None
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return cls(option, low, high, number=cls._check(option, float(value), low, high, hint))
        if isinstance(value, (list, tuple)):
            parts = [str(v) for v in value]
        else:
            text = os.fspath(value) if isinstance(value, os.PathLike) else str(value)
            if "{" in text and "}" in text:
                try:
                    names = [text.format(month=m) for m in range(1, MONTHS + 1)]
                except (KeyError, IndexError, ValueError) as exc:
                    raise UsageProblem(f"{option} {text!r}: a pattern takes {{month}} (1..12) "
                                       f"or {{month:02d}} (01..12) only ({exc})") from None
                missing = [n for n in names if not _exists(n)]
                if missing:
                    raise UsageProblem(f"{option} {text!r}: no such file: {missing[0]} (the "
                                       f"pattern names one raster per month)")
                return cls(option, low, high, pattern=text)
            parts = text.split(",")
            if len(parts) == 1:
                try:
                    return cls(option, low, high,
                               number=cls._check(option, float(text), low, high, hint))
                except ValueError:
                    if not _exists(text):
                        raise UsageProblem(f"{option}: {text!r} is neither a number nor an "
                                           "existing raster") from None
                    return cls(option, low, high, path=text)
        if len(parts) != MONTHS:
            raise UsageProblem(f"{option} takes one number or {MONTHS} monthly numbers "
                               f"(January first), got {len(parts)}")
        try:
            vals = tuple(cls._check(option, float(p), low, high, hint) for p in parts)
        except ValueError:
            raise UsageProblem(f"{option}: the monthly values must be numbers, got "
                               f"{','.join(parts)!r}") from None
        if len(set(vals)) == 1:           # twelve times one number: that number
            return cls(option, low, high, number=vals[0])
        return cls(option, low, high, monthly=vals)

    @staticmethod
    def _check(option, v, low, high, hint=""):
        if not (math.isfinite(v) and low <= v <= high):
            raise UsageProblem(f"{option} must be between {low:g} and {high:g}{hint}, got "
                               f"{v:g}")
        return v

    @property
    def rasters(self) -> bool:
        return self.path is not None or self.pattern is not None

    @property
    def by_month(self) -> bool:
        return self.monthly is not None or self.pattern is not None

    def inputs(self) -> list:
        """The files read (for the run's input/output checks)."""
        if self.path is not None:
            return [self.path]
        if self.pattern is not None:
            return [self.pattern.format(month=m) for m in range(1, MONTHS + 1)]
        return []

    def describe(self) -> str:
        """The tag's text."""
        if self.number is not None:
            return f"{self.number:g}"
        if self.monthly is not None:
            return "monthly " + ",".join(f"{v:g}" for v in self.monthly)
        if self.path is not None:
            return f"raster {os.path.basename(self.path)} (bilinear to the DEM's grid)"
        return f"monthly rasters {os.path.basename(self.pattern)} (bilinear to the DEM's grid)"

    def value_of_month(self, month: int) -> float:
        """The number of ``month`` (1..12): ``number`` or ``monthly[month - 1]``."""
        return self.number if self.monthly is None else self.monthly[month - 1]

    def on_grid(self, month: int, transform, crs, shape, valid: np.ndarray | None):
        """The value of ``month`` on the grid (``transform``, ``crs``, ``shape``): a float, or a
        float64 raster resampled bilinearly; cells of ``valid`` it does not cover: refused."""
        if not self.rasters:
            return self.value_of_month(month)
        path = self.path if self.path is not None else self.pattern.format(month=month)
        out = resample(path, transform, crs, shape)
        lacking = np.isnan(out) if valid is None else (np.isnan(out) & valid)
        if lacking.any():
            raise UsageProblem(f"{self.option} {path}: the raster does not cover the DEM "
                               f"({int(lacking.sum())} of its cells lie outside or on its "
                               "nodata)")
        seen = out[~np.isnan(out)]
        if seen.size and (seen.min() < self.low or seen.max() > self.high):
            raise UsageProblem(f"{self.option} {path}: values must be between {self.low:g} and "
                               f"{self.high:g}, found {seen.min():g}..{seen.max():g}")
        return out


    def resolved(self, month: int, transform, crs, shape, valid: np.ndarray | None):
        """The value of ``month`` on the grid as :meth:`on_grid` has it, a raster of one value
        over the cells of ``valid`` being that value (a float: the number's path, its bits);
        a raster's cells outside ``valid`` take the mean of those inside (they are voids)."""
        v = self.on_grid(month, transform, crs, shape, valid)
        if not isinstance(v, np.ndarray):
            return v
        inside = v if valid is None else v[valid]
        inside = inside[~np.isnan(inside)]
        if not inside.size:
            return float(np.nanmean(v)) if np.isfinite(v).any() else self.low
        lo, hi = float(inside.min()), float(inside.max())
        if lo == hi:
            return lo
        if valid is not None:
            v = np.where(valid, v, float(inside.mean()))
        return np.ascontiguousarray(v, np.float64)


@dataclass
class CellInputs:
    """What the open sky per cell takes (``engine.irradiance.CellSky``), whatever the cells
    (the whole grid in memory, or a region of it in windows); picklable (a Dask task gets
    it). ``months``: each sample's month (1..12); ``by_month``: whether --linke-turbidity,
    --beam-index, --diffuse-index (in this order, ``i`` 0, 1, 2) go by month; ``varies``:
    the (i, month) whose raster varies over the DEM's valid cells (those of one value are
    that number: ``numbers`` has them); ``numbers``: the samples' (Linke turbidity, beam
    index, diffuse index), each None (not given), a number or one per sample; ``terms`` the
    samples' terms (``engine.irradiance.SampleSky``: the clear sky before the indices, ...)."""

    months: np.ndarray
    by_month: tuple
    varies: frozenset
    numbers: tuple
    terms: object           # engine.irradiance.SampleSky: the samples' terms

    def key(self, i: int, k: int) -> tuple:
        """(i, the month whose raster input ``i`` takes at sample ``k``: 1 when not by
        month)."""
        return i, (int(self.months[k]) if self.by_month[i] else 1)

    def tl_on(self, k: int) -> bool:
        """Whether sample ``k`` takes the Linke turbidity of each cell (``CellSky.at``'s
        turbidity not None)."""
        return self.key(0, k) in self.varies

    def cells(self, raster):
        """The ``engine.irradiance.CellSky`` of the cells that ``raster(i, month)`` gives the
        rasters of (float64, the cells' shape): each sample's month's rasters, read as the
        samples reach the month (one month's held at a time, the last month's let go)."""
        from ..engine import irradiance as ir
        held: dict = {}

        def number(per, k):
            return 1.0 if per is None else float(per) if np.ndim(per) == 0 else float(per[k])

        def get(i, k):
            key = self.key(i, k)
            return raster(*key) if key in self.varies else None

        def at(k):
            m = int(self.months[k])
            if held.get("month") != m:
                held.clear()
                tl = get(0, k)
                held.update(month=m, tl=tl, kb=get(1, k), kd=get(2, k),
                            corr=None if tl is None else ir.ineichen_correction(
                                tl, self.terms.consts))
            kbk, kdk = held["kb"], held["kd"]
            return (held["tl"], held["corr"],
                    number(self.numbers[1], k) if kbk is None else kbk,
                    number(self.numbers[2], k) if kdk is None else kdk)
        return ir.CellSky(at, self.terms)


def _exists(path: str) -> bool:
    return path.startswith("/vsi") or os.path.exists(path)


def resample(path: str, transform, crs, shape, out: np.ndarray | None = None) -> np.ndarray:
    """Band 1 of the raster ``path`` on the grid (``transform``, ``crs``, ``shape``), bilinear
    (``rasterio.warp.reproject``), float64, NaN where it has no value (outside, nodata).
    ``out``: the float64 array of ``shape`` to write into (a run in windows passes one mapped
    from a file: ``run.irradiance_windows.SkyGrids``), the same call, the same bits; returned."""
    import contextlib

    import rasterio
    from rasterio.warp import Resampling, reproject

    from ..errors import HillshadeError
    from ..io.gdal import open_raster, read_error
    if out is None:
        out = np.full(shape, np.nan, np.float64)
    else:
        if out.dtype != np.float64 or tuple(out.shape) != tuple(shape):
            raise HillshadeError(f"resample: out is {out.dtype} {out.shape}, not float64 "
                                 f"{tuple(shape)} (a bug)")
        out[...] = np.nan
    with contextlib.ExitStack() as stack:
        try:
            src = open_raster(path, stack)
        except HillshadeError as exc:
            raise UsageProblem(str(exc)) from None
        if src.crs is None or src.transform.is_identity:
            raise UsageProblem(f"{path}: the raster has no georeferencing (a CRS and a "
                               "geotransform): it cannot be put on the DEM's grid")
        try:
            reproject(rasterio.band(src, 1), out, src_nodata=src.nodata,
                      dst_transform=transform, dst_crs=crs if crs is not None else src.crs,
                      dst_nodata=np.nan, resampling=Resampling.bilinear)
        except Exception as exc:      # noqa: BLE001 -- GDAL's read errors, one line
            raise read_error(path, exc) from None
    return out


def local_months(times, tz, lon: float) -> np.ndarray:
    """Each sample time's month (1..12) where the DEM is (:func:`month_keys`)."""
    return np.array([m for _, m in month_keys(times, tz, lon)], np.int64)


def month_keys(times, tz, lon: float) -> list:
    """Each sample time's (year, month) where the DEM is: in ``tz`` (a zone), else in local
    mean solar time at longitude ``lon`` (degrees east)."""
    if tz is not None:
        loc = [t.astimezone(tz) for t in times]
    else:
        shift = _dt.timedelta(hours=lon / 15.0)
        loc = [t.astimezone(_dt.timezone.utc) + shift for t in times]
    return [(t.year, t.month) for t in loc]
