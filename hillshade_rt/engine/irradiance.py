"""Irradiance on terrain: the sun's beam, the sky's diffuse light and the light the terrain
reflects, per cell of a DEM, summed over a period (``hillshade-rt irradiance``,
``arrays.irradiance``; the user's page: docs/irradiance.md).

Per sample time t (weight w_t hours), with DNI, DHI, GHI the open sky's irradiance (W/m²) at
the DEM's place:

* beam      = DNI · max(cos i, 0) · lit            i: incidence on the cell's tilted surface
                                                   (Horn normals, ``algorithms.relief``), lit:
                                                   1/0 from the exact cast-shadow mask, or the
                                                   visible fraction of the solar disk (soft)
* diffuse   = DHI · Vd                              isotropic sky; Vd: Dozier's sky view factor
                                                   of the tilted surface [1]_ [2]_, computed
                                                   once
            or Perez (1990) [3]_, per time:
              max(0, DHI · [(1 - F1) · Vd + F1 · max(cos i, 0) · lit / b
                            + F2 · sin S · min(1, Vd / ((1 + cos S) / 2))])
* reflected = GHI · albedo · (1 - Vd)               1 - Vd: the terrain's configuration factor
* global    = beam + diffuse + reflected

and the energy is the sum of w_t times each (Wh/m²). On an open plane of slope S, Vd is
(1 + cos S) / 2 and 1 - Vd is (1 - cos S) / 2, so every band is pvlib's
``get_total_irradiance`` (isotropic, or Perez) for that plane.

The open sky's irradiance comes from pvlib's clear-sky models [8]_ (Ineichen [4]_ with a Linke
turbidity, given or pvlib's climatological lookup; Haurwitz [5]_, GHI only, split by Erbs [6]_) or
from a measured series (a CSV of time, ghi[, dni, dhi], interpolated linearly in time; GHI alone
split by Erbs). Perez's air mass is Kasten & Young's [7]_. The sun is the project's (``sun``: NREL
SPA, apparent elevation unless refraction is off), the same suns as ``sun-hours``: its zenith at
the DEM's centre feeds the clear-sky model.

GRASS r.sun's real sky [9]_ (its coeff_bh, coeff_dh: clear-sky indices kb, kd of 0..1) is the
clear sky's DNI · kb and DHI · kd, its global horizontal kb · (GHI - DHI) + kd · DHI
(:func:`real_sky`). Where the Linke turbidity or the indices are rasters the open sky differs
from cell to cell (:class:`CellSky`): Ineichen's formula is evaluated per cell and sample (the
parts that depend on the sun alone computed once per sample as pvlib computes them), and the
diffuse and reflected light summed per cell as the beam is (``sums``' ``cells``).

References
----------
.. [1] J. Dozier, J. Frew, "Rapid calculation of terrain parameters for radiation modeling from
       digital elevation data," IEEE Trans. Geosci. Remote Sens., vol. 28, no. 5, pp. 963-969,
       1990. :doi:`10.1109/36.58986`
.. [2] J. Dozier, "Revisiting Topographic Horizons in the Era of Big Data and Parallel Computing,"
       IEEE Geosci. Remote Sens. Lett., vol. 19, art. 8024605, 2022.
       :doi:`10.1109/LGRS.2021.3125278`
.. [3] R. Perez, P. Ineichen, R. Seals, J. Michalsky, R. Stewart, "Modeling daylight availability
       and irradiance components from direct and global irradiance," Solar Energy, vol. 44, no. 5,
       pp. 271-289, 1990. :doi:`10.1016/0038-092X(90)90055-H`
.. [4] P. Ineichen, R. Perez, "A new airmass independent formulation for the Linke turbidity
       coefficient," Solar Energy, vol. 73, no. 3, pp. 151-157, 2002.
       :doi:`10.1016/S0038-092X(02)00045-2`
.. [5] B. Haurwitz, "Insolation in Relation to Cloudiness and Cloud Density," Journal of
       Meteorology, vol. 2, pp. 154-166, 1945.
.. [6] D. G. Erbs, S. A. Klein, J. A. Duffie, "Estimation of the diffuse radiation fraction for
       hourly, daily and monthly-average global radiation," Solar Energy, vol. 28, no. 4,
       pp. 293-302, 1982. :doi:`10.1016/0038-092X(82)90302-4`
.. [7] F. Kasten, A. T. Young, "Revised optical air mass tables and approximation formula," Applied
       Optics, vol. 28, no. 22, pp. 4735-4738, 1989. :doi:`10.1364/AO.28.004735`
.. [8] W. F. Holmgren, C. W. Hansen, M. A. Mikofski, "pvlib python: a python package for modeling
       solar energy systems," Journal of Open Source Software, vol. 3, no. 29, p. 884, 2018.
       :doi:`10.21105/joss.00884`
.. [9] M. Šúri, J. Hofierka, "A new GIS-based solar radiation model and its application to
       photovoltaic assessments," Transactions in GIS, vol. 8, no. 2, pp. 175-190, 2004.
       :doi:`10.1111/j.1467-9671.2004.00174.x`
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from dataclasses import dataclass

import numpy as np

from ..errors import HillshadeError

CLEAR_SKY_MODELS = ("ineichen", "haurwitz")
SKY_MODELS = ("isotropic", "perez")
BANDS = ("beam", "diffuse", "reflected", "global")
# GRASS r.sun's names of the same quantities (its outputs beam_rad, diff_rad, refl_rad, glob_rad:
# W/m² in its mode 1, an instant; Wh/m² per day in its mode 2) and of the instant's incidence
# angle (incidout: the sun's elevation above the surface, degrees)
RSUN_NAMES = {"beam": "beam_rad", "diffuse": "diff_rad", "reflected": "refl_rad",
              "global": "glob_rad", "incidence": "incidout"}
# the bands of one instant (``instant``): the four irradiances, then the incidence angle
INSTANT_BANDS = BANDS + ("incidence",)

# Perez, Ineichen, Seals, Michalsky & Stewart (1990), Solar Energy 44(5), table 6, "all sites
# composite" (pvlib's default coefficients, 'allsitescomposite1990'): per sky-clearness bin
# (epsilon below 1.065, 1.23, 1.5, 1.95, 2.8, 4.5, 6.2, above), f11 f12 f13 f21 f22 f23
PEREZ_1990 = np.array([
    [-0.0080, 0.5880, -0.0620, -0.0600, 0.0720, -0.0220],
    [0.1300, 0.6830, -0.1510, -0.0190, 0.0660, -0.0290],
    [0.3300, 0.4870, -0.2210, 0.0550, -0.0640, -0.0260],
    [0.5680, 0.1870, -0.2950, 0.1090, -0.1520, -0.0140],
    [0.8730, -0.3920, -0.3620, 0.2260, -0.4620, 0.0010],
    [1.1320, -1.2370, -0.4120, 0.2880, -0.8230, 0.0560],
    [1.0600, -1.6000, -0.3590, 0.2640, -1.1270, 0.1310],
    [0.6780, -0.3270, -0.2500, 0.1560, -1.3770, 0.2510]])
PEREZ_EPSILON_BINS = (1.065, 1.23, 1.5, 1.95, 2.8, 4.5, 6.2)
PEREZ_KAPPA = 1.041          # for the zenith in radians
COS_85 = math.cos(math.radians(85.0))


def check_options(albedo: float, linke_turbidity: float | None = None,
                  directions: int = 32) -> None:
    """The numbers a run takes, checked (HillshadeError naming the option)."""
    if not (math.isfinite(albedo) and 0.0 <= albedo <= 1.0):
        raise HillshadeError(f"--albedo must be between 0 and 1, got {albedo:g}")
    if linke_turbidity is not None and not (math.isfinite(linke_turbidity)
                                            and 1.0 <= linke_turbidity <= 10.0):
        raise HillshadeError(f"--linke-turbidity must be between 1 and 10 (clean, dry air ~2, "
                             f"hazy ~5), got {linke_turbidity:g}")
    if not 4 <= int(directions) <= 360:
        raise HillshadeError(f"--skyview-directions must be between 4 and 360, got {directions}")


# --------------------------------------------------------------------------------------------
# sample times

def period_samples(start: _dt.datetime, end: _dt.datetime, step: _dt.timedelta,
                   limit: int = 2_000_000) -> tuple[list[_dt.datetime], list[float]]:
    """The period ``start``..``end`` (aware datetimes) cut into intervals of ``step`` (elapsed
    time; the last one shorter when the step does not divide the period), a sample at the middle
    of each, its weight the interval in hours (as ``times.day_samples`` cuts days). Each time is
    shown in ``start``'s zone."""
    u0, u1 = start.astimezone(_dt.timezone.utc), end.astimezone(_dt.timezone.utc)
    if u1 <= u0:
        raise HillshadeError(f"--end {end.isoformat()} is not after --start {start.isoformat()}")
    if step <= _dt.timedelta(0):
        raise HillshadeError("--step must be positive")
    n = -((u0 - u1) // step)        # ceil
    if n > limit:
        raise HillshadeError(f"more than {limit} samples: use a longer --step")
    times, weights = [], []
    t = u0
    while t < u1:
        e = min(t + step, u1)
        times.append((t + (e - t) / 2).astimezone(start.tzinfo))
        weights.append((e - t).total_seconds() / 3600.0)
        t = e
    return times, weights


def _index(times):
    """A UTC pandas DatetimeIndex of aware datetimes (what pvlib takes)."""
    import pandas as pd
    return pd.DatetimeIndex([pd.Timestamp(t).tz_convert("UTC") for t in times])


# --------------------------------------------------------------------------------------------
# the open sky's irradiance at each sample

@dataclass
class Sky:
    """The open sky's irradiance at each sample time (W/m², float64 over the samples) and what
    it is; with Perez, the model's coefficients per sample."""

    dni: np.ndarray
    dhi: np.ndarray
    ghi: np.ndarray
    source: str                       # the clear-sky model, or the measured series
    turbidity: str | None = None      # the Linke turbidity used (Ineichen)
    split: str | None = None          # how DNI and DHI were had from GHI, when they were
    f1: np.ndarray | None = None      # Perez's circumsolar coefficient (perez only)
    f2: np.ndarray | None = None      # Perez's horizon-brightening coefficient
    b: np.ndarray | None = None       # max(cos Z, cos 85°)
    perez_on: np.ndarray | None = None   # the air mass is defined (the sun above the horizon)


def _erbs(ghi, zenith, times):
    from pvlib.irradiance import erbs
    out = erbs(np.asarray(ghi, np.float64), np.asarray(zenith, np.float64),
               _index(times).day_of_year.to_numpy())
    return (np.nan_to_num(np.asarray(out["dni"], np.float64)),
            np.nan_to_num(np.asarray(out["dhi"], np.float64)))


ERBS = "DNI and DHI split from GHI by Erbs et al. (1982), pvlib.irradiance.erbs"


def clear_sky(times, zenith, lat: float, lon: float, altitude: float, model: str = "ineichen",
              linke_turbidity=None) -> Sky:
    """pvlib's clear-sky irradiance at ``times`` (aware datetimes) for the sun's ``zenith``
    (degrees, the project's SPA: the same suns as the shadows) at (lat, lon, altitude m).
    Ineichen-Perez with ``linke_turbidity`` (a number; an array: one per sample time, e.g.
    each sample its month's value; None: pvlib's climatological monthly lookup,
    shipped with pvlib, interpolated to the day), or Haurwitz (GHI only: DNI and DHI by Erbs)."""
    import pandas as pd
    from pvlib.location import Location
    if model not in CLEAR_SKY_MODELS:
        raise HillshadeError(f"--clear-sky must be one of {', '.join(CLEAR_SKY_MODELS)}, got "
                             f"{model!r}")
    zenith = np.asarray(zenith, np.float64)
    idx = _index(times)
    pos = pd.DataFrame({"apparent_zenith": zenith, "zenith": zenith,
                        "apparent_elevation": 90.0 - zenith}, index=idx)
    loc = Location(lat, lon, altitude=altitude)
    if model == "haurwitz":
        cs = loc.get_clearsky(idx, model="haurwitz", solar_position=pos)
        ghi = np.nan_to_num(cs["ghi"].to_numpy(np.float64))
        dni, dhi = _erbs(ghi, zenith, times)
        return Sky(dni, dhi, ghi, "clear sky: Haurwitz (1945), pvlib", split=ERBS)
    if linke_turbidity is None:
        from pvlib.clearsky import lookup_linke_turbidity
        try:
            lt = np.asarray(lookup_linke_turbidity(idx, lat, lon), np.float64)
        except Exception as exc:      # the table (an HDF5 file shipped with pvlib), h5py
            raise HillshadeError(f"pvlib's Linke turbidity table could not be read ({exc}); "
                                 "give --linke-turbidity") from None
        what = (f"{float(np.mean(lt)):.2f} (pvlib's climatological monthly lookup at "
                f"{lat:.4f}, {lon:.4f}, interpolated to the day; range "
                f"{float(np.min(lt)):.2f}..{float(np.max(lt)):.2f})")
    elif np.ndim(linke_turbidity):     # one value per sample (monthly values)
        lt = np.asarray(linke_turbidity, np.float64)
        if lt.shape != zenith.shape:
            raise HillshadeError("one Linke turbidity per sample time")
        vals = np.unique(lt)
        what = (f"{float(np.mean(lt)):.2f} mean of the samples' monthly values (given: "
                f"{', '.join(f'{v:g}' for v in vals)})")
    else:
        lt = float(linke_turbidity)
        what = f"{lt:g} (given)"
    cs = loc.get_clearsky(idx, model="ineichen", solar_position=pos, linke_turbidity=lt)
    return Sky(*(np.nan_to_num(cs[k].to_numpy(np.float64)) for k in ("dni", "dhi", "ghi")),
               "clear sky: Ineichen & Perez (2002), pvlib", turbidity=what)


def measured_sky(times, zenith, ghi, dni=None, dhi=None, source: str = "measured") -> Sky:
    """A measured sky at the sample ``times``: GHI, with DNI and DHI (both) or split by Erbs
    from GHI and the sun's ``zenith``. Negative values (pyranometers' night offsets) count as
    0."""
    ghi = np.maximum(np.asarray(ghi, np.float64), 0.0)
    if (dni is None) != (dhi is None):
        raise HillshadeError("give both dni and dhi, or neither (then they are split from ghi)")
    if dni is None:
        dni, dhi = _erbs(ghi, zenith, times)
        return Sky(dni, dhi, ghi, source, split=ERBS)
    dni = np.maximum(np.asarray(dni, np.float64), 0.0)
    dhi = np.maximum(np.asarray(dhi, np.float64), 0.0)
    if not (dni.shape == dhi.shape == ghi.shape):
        raise HillshadeError("ghi, dni and dhi must have one value per time")
    return Sky(dni, dhi, ghi, source)


def read_series(path: str, tz=None):
    """A measured series from a CSV file: a header row naming the columns ``time`` and ``ghi``
    (and optionally ``dni`` and ``dhi``, both), then one row per time (ISO 8601, with a UTC
    offset, or local times in zone ``tz``), strictly increasing; values in W/m². Returns
    (unix seconds, ghi, dni or None, dhi or None)."""
    import csv
    from ..model.times import parse_time
    name = os.path.basename(path)
    try:
        fh = open(path, newline="", encoding="utf-8-sig")
    except FileNotFoundError:
        raise HillshadeError(f"{path}: no such file") from None
    except OSError as exc:
        raise HillshadeError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    with fh:
        rows = [r for r in csv.reader(fh)]
    lines = [(i + 1, r) for i, r in enumerate(rows) if r and any(c.strip() for c in r)
             and not r[0].lstrip().startswith("#")]
    if not lines:
        raise HillshadeError(f"{path}: empty (a header row with time and ghi columns, then "
                             "one row per time)")
    head_line, head = lines[0]
    cols = [c.strip().lower() for c in head]
    missing = [c for c in ("time", "ghi") if c not in cols]
    if missing:
        raise HillshadeError(f"{path}: no {' or '.join(missing)} column in its header (line "
                             f"{head_line}: {', '.join(c.strip() for c in head)}); the columns "
                             "are time, ghi and optionally dni and dhi")
    if ("dni" in cols) != ("dhi" in cols):
        raise HillshadeError(f"{path}: give both dni and dhi columns, or neither (then DNI and "
                             "DHI are split from ghi)")
    keys = ["ghi"] + (["dni", "dhi"] if "dni" in cols else [])
    at = {c: cols.index(c) for c in ["time"] + keys}
    unix, values = [], {k: [] for k in keys}
    for n, r in lines[1:]:
        if len(r) < len(cols):
            raise HillshadeError(f"{name} line {n}: {len(r)} fields, the header has {len(cols)}")
        where = f"{name} line {n}"
        try:
            t = parse_time(r[at["time"]], tz, f"{where}: time")
        except HillshadeError as exc:       # (not every message names the option)
            msg = str(exc)
            raise HillshadeError(msg if msg.startswith(where) else f"{where}: {msg}") from None
        unix.append(t.timestamp())
        for k in keys:
            text = r[at[k]].strip()
            try:
                v = float(text)
            except ValueError:
                v = math.nan
            if not math.isfinite(v):
                raise HillshadeError(f"{name} line {n}: {k} {text!r} is not a number of W/m2")
            values[k].append(v)
    if len(unix) < 2:
        raise HillshadeError(f"{path}: needs at least two rows of values (it is interpolated "
                             "in time)")
    u = np.array(unix, np.float64)
    if not (np.diff(u) > 0).all():
        k = int(np.argmin(np.diff(u) > 0))
        raise HillshadeError(f"{path}: times must increase, but row {k + 2} is not after row "
                             f"{k + 1}")
    out = [np.array(values[k], np.float64) for k in keys]
    return (u, out[0]) + ((out[1], out[2]) if len(out) == 3 else (None, None))


def series_at(times, unix, *columns, path: str = "the series"):
    """Each of ``columns`` (values at ``unix`` seconds) linearly interpolated at the sample
    ``times``; a sample outside the series' first..last time is an error (nothing is
    extrapolated)."""
    from ..model.times import iso
    ts = np.array([t.timestamp() for t in times], np.float64)
    if ts.size and (ts.min() < unix[0] or ts.max() > unix[-1]):
        show = times[0].tzinfo

        def at(u):
            return iso(_dt.datetime.fromtimestamp(u, _dt.timezone.utc).astimezone(show))
        raise HillshadeError(f"{path} runs from {at(unix[0])} to {at(unix[-1])}, but the "
                             f"period's samples run from {at(ts.min())} to {at(ts.max())}: "
                             "give a series that covers the period")
    return tuple(None if c is None else np.interp(ts, unix, c) for c in columns)


def with_perez(sky: Sky, times, zenith) -> Sky:
    """``sky`` with the Perez (1990) coefficients per sample: F1 (circumsolar), F2 (horizon
    brightening) from the sky's clearness and brightness (pvlib's air mass, Kasten & Young
    1989, and extraterrestrial irradiance), as ``pvlib.irradiance.perez`` computes them; where
    the air mass is undefined (the sun below the horizon) the model gives no sky diffuse, as
    pvlib's."""
    from pvlib.atmosphere import get_relative_airmass
    from pvlib.irradiance import get_extra_radiation
    zenith = np.asarray(zenith, np.float64)
    am = np.asarray(get_relative_airmass(zenith), np.float64)
    extra = np.asarray(get_extra_radiation(_index(times)), np.float64)
    z = np.radians(zenith)
    on = np.isfinite(am) & (sky.dhi > 0)
    dhi = np.where(on, sky.dhi, 1.0)
    delta = np.where(on, sky.dhi * np.where(on, am, 0.0) / extra, 0.0)
    kz3 = PEREZ_KAPPA * z ** 3
    eps = ((dhi + np.where(on, sky.dni, 0.0)) / dhi + kz3) / (1.0 + kz3)
    c = PEREZ_1990[np.digitize(eps, PEREZ_EPSILON_BINS)]
    f1 = np.maximum(c[:, 0] + c[:, 1] * delta + c[:, 2] * z, 0.0)
    f2 = c[:, 3] + c[:, 4] * delta + c[:, 5] * z
    sky.f1, sky.f2 = np.where(on, f1, 0.0), np.where(on, f2, 0.0)
    sky.b = np.maximum(np.cos(z), COS_85)
    sky.perez_on = np.isfinite(am)
    return sky


def real_sky(sky: Sky, beam_index, diffuse_index) -> Sky:
    """The real sky of GRASS r.sun's clear-sky indices (its coeff_bh, coeff_dh [9]_): DNI times
    ``beam_index``, DHI times ``diffuse_index`` (numbers, or one per sample), and the global
    horizontal their sum, kb · (GHI - DHI) + kd · DHI (kb · GHI where kb = kd: index 1 leaves
    the sky's bits). None: 1."""
    from dataclasses import replace
    n = len(sky.dni)
    kb = np.broadcast_to(np.asarray(1.0 if beam_index is None else beam_index, np.float64),
                         (n,))
    kd = np.broadcast_to(np.asarray(1.0 if diffuse_index is None else diffuse_index,
                                    np.float64), (n,))
    ghi = np.where(kb == kd, kb * sky.ghi, kb * (sky.ghi - sky.dhi) + kd * sky.dhi)
    return replace(sky, dni=kb * sky.dni, dhi=kd * sky.dhi, ghi=ghi)


@dataclass
class SampleSky:
    """The per-sample terms of an open sky that differs from cell to cell: the clear sky before
    the indices (``ghi``, ``dni``, ``dhi``), pvlib's absolute air mass ``am`` (NaN: the sun
    down), the extraterrestrial irradiance ``extra``, max(cos Z, 0) ``cosz``, the altitude's
    terms ``consts`` (fh1, fh2, cg1, cg2, b), and for Perez the zenith ``z`` (radians) and
    ``am_rel`` (Kasten & Young)."""

    ghi: np.ndarray
    dni: np.ndarray
    dhi: np.ndarray
    am: np.ndarray
    extra: np.ndarray
    cosz: np.ndarray
    consts: tuple
    z: np.ndarray
    am_rel: np.ndarray

    def sample(self, k: int) -> "SampleSky":
        """Sample ``k`` alone (an instant)."""
        def one(v):
            return v[k:k + 1]
        return SampleSky(one(self.ghi), one(self.dni), one(self.dhi), one(self.am),
                         one(self.extra), one(self.cosz), self.consts, one(self.z),
                         one(self.am_rel))


@dataclass
class CellSky:
    """The open sky where it differs from cell to cell: a Linke turbidity raster (Ineichen's
    clear sky per cell) or clear-sky index rasters (r.sun's coeff_bh, coeff_dh), for
    :func:`sums` (``algorithms.irradiance.add_sample_cells``). ``at(k)``: sample k's
    (Linke turbidity, the cells' Ineichen correction (:func:`ineichen_correction`), beam
    index, diffuse index) on the cells, each a float64 raster of the cells or, for the
    indices, a number; the turbidity and its correction None where the sky's own values
    serve (``terms``' ``ghi``, ``dni``, ``dhi``). ``terms``: the per-sample terms
    (:class:`SampleSky`)."""

    at: object
    terms: SampleSky

    def sample(self, k: int) -> "CellSky":
        """Sample ``k`` alone (an instant)."""
        at = self.at
        return CellSky(lambda _j: at(k), self.terms.sample(k))


def ineichen_terms(times, zenith, lat: float, lon: float, altitude: float):
    """(absolute air mass, extraterrestrial irradiance, max(cos Z, 0), (fh1, fh2, cg1, cg2, b)):
    the parts of pvlib's Ineichen clear sky (``Location.get_clearsky``) that do not depend on
    the Linke turbidity, at ``times`` for the sun's ``zenith`` (degrees), computed as pvlib
    computes them."""
    import pandas as pd
    from pvlib import tools
    from pvlib.irradiance import get_extra_radiation
    from pvlib.location import Location
    zenith = np.asarray(zenith, np.float64)
    idx = _index(times)
    pos = pd.DataFrame({"apparent_zenith": zenith, "zenith": zenith,
                        "apparent_elevation": 90.0 - zenith}, index=idx)
    loc = Location(lat, lon, altitude=altitude)
    am = np.asarray(loc.get_airmass(idx, solar_position=pos)["airmass_absolute"], np.float64)
    extra = np.asarray(get_extra_radiation(idx), np.float64)
    cosz = np.asarray(np.maximum(tools.cosd(zenith), 0), np.float64)
    alt = loc.altitude
    fh1 = np.exp(-alt / 8000.)
    fh2 = np.exp(-alt / 1250.)
    cg1 = 5.09e-05 * alt + 0.868
    cg2 = 3.92e-05 * alt + 0.0387
    return am, extra, cosz, tuple(float(v) for v in (fh1, fh2, cg1, cg2, 0.664 + 0.163 / fh1))


def ineichen_correction(tl: np.ndarray, consts: tuple) -> np.ndarray:
    """1 - (0.1 - 0.2 exp(-TL)) / (0.1 + 0.882 / fh1) of each cell's Linke turbidity: the part
    of Ineichen's beam correction that does not change with the sun (pvlib's expression)."""
    return 1 - (0.1 - 0.2 * np.exp(-tl)) / (0.1 + 0.882 / consts[0])


def perez_terms(times, zenith):
    """(zenith in radians, Kasten & Young's relative air mass) per sample, as
    :func:`with_perez` has them."""
    from pvlib.atmosphere import get_relative_airmass
    zenith = np.asarray(zenith, np.float64)
    return np.radians(zenith), np.asarray(get_relative_airmass(zenith), np.float64)


# --------------------------------------------------------------------------------------------
# the terrain: what does not change with the sun

def dozier_view(z, grid, directions: int, backend: str = "cpu", curvature="auto",
                refraction_k: float | None = None, body=None, lift: float = 0.0,
                pyramid=None, normals=None) -> np.ndarray:
    """Dozier's sky view factor Vd of every cell's tilted surface (float32, NaN voids) from its
    exact horizon in ``directions`` azimuths, as ``hillshade-rt skyview --definition dozier``
    (curvature "auto": on for a raster more than 1 km across); the horizons seen from ``lift``
    metres above each cell (--height-above-ground), the surface's slope and aspect the cell's.
    ``pyramid``: the maximum-height pyramid of ``z`` to march over (``algorithms.pyramid.
    MaxPyramid``, e.g. the lighting Shader's, so that the shadows reuse the one built here;
    None or False: one of its own); ``normals``: Horn's normals of ``z``
    (``algorithms.irradiance.normals``, shared with the sums) for the surface's slope and
    aspect (None: from the heights, the same values)."""
    from ..algorithms import horizon as hz
    from ..algorithms.skyview import sky_view
    from ..model.geometry import equal_azimuths
    from .shader import horizon_shader
    shader = horizon_shader(z, grid, backend, curvature, refraction_k, body)
    if backend == "gpu":
        from .gpu import GpuDem
        g = GpuDem(z)

        def angles_of(a):     # floored at the horizontal, all Vd reads (algorithms.skyview)
            return hz.horizon_angles_gpu(g, shader.rays(grid, a, 45.0), floor_deg=0.0,
                                         lift=lift)
    else:
        if not pyramid:
            pyramid = shader.pyramid(z, True)      # one for every direction

        def angles_of(a):
            return hz.horizon_angles(z, shader.rays(grid, a, 45.0), pyramid=pyramid,
                                     floor_deg=0.0, lift=lift)
    return sky_view(z, grid, equal_azimuths(360.0 / int(directions)), angles_of, "dozier",
                    normals=normals)


def slope_terms(z, grid) -> tuple[np.ndarray, np.ndarray]:
    """(cos S, sin S) of every cell's slope S (Horn's normals, float64, NaN voids)."""
    from ..algorithms.relief import incidence
    cos_s = incidence(z, grid, 0.0, 90.0).astype(np.float64)
    return cos_s, np.sqrt(np.maximum(1.0 - cos_s * cos_s, 0.0))


def cos_incidence(shader, sun) -> np.ndarray:
    """cos i of the sun on every cell (float32, NaN voids), tile by tile where the sun is per
    tile (each tile's own sun, as the shadows' incidence)."""
    regions = sun.regions(shader.z.shape)
    if len(regions) == 1:
        return shader.incidence(regions[0])
    out = np.empty(shader.z.shape, np.float32)
    for r in regions:
        out[r.rows, r.cols] = shader.incidence(r)
    return out


def is_dark(sun, soft: bool) -> bool:
    """The sun (or its disk, with ``soft``) is below the horizon everywhere: nothing is lit."""
    from ..model.solar import SUN_RADIUS_DEG
    top = max([r.elevation for r in sun.tiles] if sun.tiles else [sun.elevation])
    return top + (SUN_RADIUS_DEG if soft else 0.0) <= 0.0


# --------------------------------------------------------------------------------------------
# the sums

def casts(sky: Sky, k: int, sun, soft: bool = False, perez: bool = False) -> bool:
    """Whether sample ``k`` (``sun``, the ``sky`` at it) has direct light to cast: a beam, or
    Perez's circumsolar part, and the sun (its disk, ``soft``) up somewhere. ``sums`` asks for
    the direct term of these samples only, in their order."""
    dhi = float(sky.dhi[k])
    circ = perez and dhi > 0 and bool(sky.perez_on[k]) and sky.f1[k] > 0
    return bool((float(sky.dni[k]) > 0 or circ) and not is_dark(sun, soft))


def accumulate(shader, suns, weights, sky: Sky, vd: np.ndarray, albedo: float, *,
               soft: bool = False, perez: bool = False, per_time: bool = False,
               stats: dict | None = None, timer=None, progress=None, normals=None,
               groups: "Groups | None" = None, cells: "CellSky | None" = None) -> dict:
    """The four bands (``BANDS``, float32, NaN voids) over ``shader``'s DEM: with ``per_time``
    each a (times, rows, cols) stack of W/m² at each sun, else the sums of W/m² times
    ``weights`` (hours): Wh/m². ``suns``: ``sun.SunOver`` per sample (the shadows' and the
    incidence's suns), ``sky`` the open sky at each, ``vd`` Dozier's sky view factor. The cast
    shadows (``engine.shader.render``) are computed only for samples with the sun up and light to
    cast; ``timer`` (``run.report.Timer``-like) times them as "shadows" and the rest as
    "irradiance"; ``progress`` wraps the loop (a progress bar). The sums take Horn's normals once
    (``algorithms.irradiance.normals``) and add each sample in place; the stacks go as before,
    sun by sun through numpy. ``normals``: those normals when the caller has them (the sky
    view's). ``groups``, ``cells``: as ``sums``' (not with ``per_time``)."""
    from .shader import render, threads_for
    if per_time:
        def direct(s, timed):
            with timed("shadows"):
                lit = render(shader, s, "sun", soft=soft, stats=stats)
            with timed("irradiance"):
                return np.maximum(cos_incidence(shader, s), np.float32(0.0)) * lit
        return sums(direct, np.isnan(shader.z), lambda: slope_terms(shader.z, shader.grid),
                    suns, weights, sky, vd, albedo, soft=soft, perez=perez, per_time=True,
                    stats=stats, timer=timer, progress=progress)
    from ..algorithms.irradiance import normals as horn_normals
    from ..algorithms.relief import sun_vector
    nrm = normals
    if nrm is None:
        with (timer("irradiance") if timer is not None else _nothing()):
            nrm = horn_normals(shader.z, shader.grid)   # once: every sun's incidence reads them

    def lit_of(s, timed):
        with timed("shadows"):     # hard: the uint8 mask itself (add_sample reads it)
            return render(shader, s, "sun" if soft else "shadow", soft=soft, stats=stats)

    def slopes():
        from ..algorithms.irradiance import incidence_of
        cos_s = incidence_of(nrm, *sun_vector(0.0, 90.0)).astype(np.float64)
        return cos_s, np.sqrt(np.maximum(1.0 - cos_s * cos_s, 0.0))
    with threads_for(shader.z.size):   # each sample's sum, as its shadows (render)
        return sums(lit_of, np.isnan(shader.z), slopes, suns, weights, sky, vd, albedo,
                    soft=soft, perez=perez, stats=stats, timer=timer, progress=progress,
                    normals=nrm, groups=groups, cells=cells)


def _nothing():
    import contextlib
    return contextlib.nullcontext()


def tile_suns(sun, shape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(row_tile, col_tile, vectors): the sun of every cell of a raster of ``shape`` as the
    tile it lies in, ``vectors[row_tile[r], col_tile[c]]`` its (lx, ly, lz)
    (``relief.sun_vector``: the incidence's); the tiles of ``sun.regions`` (one: the whole
    raster) on the grid of their edges."""
    from ..algorithms.relief import sun_vector
    rows, cols = shape
    regions = [(r.rows.indices(rows)[:2], r.cols.indices(cols)[:2], r) for r in
               sun.regions(shape)]
    rb = sorted({0, rows} | {x for (a, _, _) in regions for x in a})
    cb = sorted({0, cols} | {x for (_, b, _) in regions for x in b})
    ri = {x: i for i, x in enumerate(rb)}
    ci = {x: i for i, x in enumerate(cb)}
    vec = np.full((len(rb) - 1, len(cb) - 1, 3), np.nan)
    for (r0, r1), (c0, c1), reg in regions:
        vec[ri[r0]:ri[r1], ci[c0]:ci[c1]] = sun_vector(reg.azimuth, reg.elevation)
    if np.isnan(vec).any():
        raise HillshadeError("the sun's tiles do not cover the raster")
    row_tile = (np.searchsorted(rb, np.arange(rows), side="right") - 1).astype(np.int64)
    col_tile = (np.searchsorted(cb, np.arange(cols), side="right") - 1).astype(np.int64)
    return row_tile, col_tile, vec


@dataclass
class Groups:
    """Samples grouped by period (the months of ``irradiance --monthly``, or of monthly sky
    inputs): ``index`` each sample's group (0, 1, ..., never decreasing), ``albedo`` each
    group's albedo (a number, or a float64 raster of the cells), ``bands`` whether ``sums``
    returns each group's global band (``"groups"``: float32 Wh/m², NaN voids). ``albedo``
    None: the run's single albedo for every group."""

    index: np.ndarray
    albedo: list | None = None
    bands: bool = True


def sums(direct, void: np.ndarray, slopes, suns, weights, sky: Sky, vd: np.ndarray,
         albedo, *, soft: bool = False, perez: bool = False, per_time: bool = False,
         stats: dict | None = None, timer=None, progress=None, normals=None,
         groups: Groups | None = None, cells: CellSky | None = None) -> dict:
    """``accumulate``'s bands over any cells: ``direct(sun, timed)`` gives max(cos i, 0) · lit
    of the cells (float32, NaN voids) for a sun with light to cast (``timed(stage)``: the
    timer's context), or with ``normals`` (``algorithms.irradiance.normals`` of the cells) lit
    alone (float32, or the uint8 hard mask: 0 lit), cos i then worked out from the normals;
    ``void`` marks their voids, ``slopes()`` gives their (cos S, sin S) (Perez only). The cells
    may be a whole DEM (``accumulate``) or a tile of a larger raster whose shadows and incidence
    come from its windows (``run.irradiance`` with --context): the arithmetic per cell is the
    same, cell by cell, in the same order and types. The sums are added in place sample by
    sample (``algorithms.irradiance.add_sample``: the bits of numpy's w · (DNI · d) and
    w · max(DHI · (...), 0) sums); the stacks (``per_time``) are numpy's. ``albedo``: a number
    or a float64 raster of the cells (constant in time). ``groups`` (:class:`Groups`): each
    group's global band too (its beam and Perez diffuse the difference of the float64 running
    sums at its ends; its isotropic diffuse and reflected light from its own samples' sky), and
    with ``groups.albedo`` the reflected light of each group with its own albedo, the total
    their sum; the total bands are otherwise the bits of a run without groups. ``cells``
    (:class:`CellSky`): the open sky per cell (a Linke turbidity raster, clear-sky index
    rasters), every sample with light added cell by cell (``algorithms.irradiance.
    add_sample_cells``), the diffuse and reflected light too (float64 sums of each cell's DHI
    and GHI); ``sky`` then only says which samples cast shadows (not with ``per_time``)."""
    import contextlib
    w = np.asarray(weights, np.float64)
    n = len(suns)
    if not (len(w) == n == len(sky.dni)):
        raise HillshadeError("one weight and one sky value per sun")
    if perez and sky.f1 is None:
        raise HillshadeError("the sky has no Perez coefficients (with_perez)")

    def timed(stage):
        return timer(stage) if timer is not None else contextlib.nullcontext()
    shape = void.shape
    vd64 = vd.astype(np.float64)
    if perez:
        cos_s, sin_s = slopes()
        # the horizon band's share left by the terrain, relative to the open plane's
        horizon_share = np.minimum(vd64 / ((1.0 + cos_s) / 2.0), 1.0)
    counted = {"samples": n, "samples_with_shadows": 0}
    loop = progress(range(n)) if progress is not None else range(n)
    if per_time and cells is not None:
        raise HillshadeError("an open sky per cell is summed, not stacked (per_time)")
    if per_time:
        stacks = _stacks(direct, void, loop, suns, sky, vd, vd64, albedo, soft, perez,
                         sin_s if perez else None, horizon_share if perez else None, counted,
                         timed)
        if stats is not None:
            stats.update(counted)
        return stacks
    if cells is not None:
        return _sums_cells(direct, void, loop, suns, w, sky, vd64, albedo, cells, soft, perez,
                           sin_s if perez else None, horizon_share if perez else None, counted,
                           stats, timed, normals, groups)
    from ..algorithms.irradiance import add_sample
    beam = np.zeros(shape, np.float64)
    diffuse = np.zeros(shape, np.float64)
    none2, none1, none3, no_lit, no_cast, rows0 = _stand_ins(shape)
    if not perez:
        sin_s = horizon_share = none2
    gi = _group_index(groups, n)
    ends = []                    # (group, its beam sum, its diffuse sum)
    prev = [beam.copy(), diffuse.copy() if perez else None] if gi is not None else None

    def close(g):
        ends.append((g, beam - prev[0], diffuse - prev[1] if perez else None))
        prev[0], prev[1] = beam.copy(), diffuse.copy() if perez else None
    for k in loop:
        if gi is not None and k > 0 and gi[k] != gi[k - 1]:
            close(int(gi[k - 1]))
        s = suns[k]
        dni, dhi = float(sky.dni[k]), float(sky.dhi[k])
        lit = None
        if casts(sky, k, s, soft, perez):
            lit = _light_of(direct, s, timed, shape, normals)
            counted["samples_with_shadows"] += 1
        diffuse_on = bool(perez and dhi > 0 and sky.perez_on[k])
        if lit is None and not diffuse_on:
            continue
        with timed("irradiance"):
            if lit is not None and normals is not None:
                row_tile, col_tile, vec = tile_suns(s, shape)
                ge, gn, length = normals
            else:
                row_tile, col_tile, vec, ge, gn, length = rows0, none1, none3, none2, none2, none2
            f1 = float(sky.f1[k]) if diffuse_on else 0.0
            mask = lit is not None and lit.dtype == np.uint8
            add_sample(no_lit if lit is None or mask else lit, lit if mask else no_cast, mask,
                       ge, gn, length, row_tile, col_tile, vec,
                       lit is not None and normals is not None, lit is not None,
                       np.float32(dni), float(w[k]), beam, diffuse_on,
                       bool(diffuse_on and lit is not None and sky.f1[k] > 0), f1,
                       float(sky.f1[k] / sky.b[k]) if diffuse_on else 0.0,
                       float(sky.f2[k]) if diffuse_on else 0.0, dhi,
                       vd64, sin_s, horizon_share, diffuse)
    if gi is not None and n:
        close(int(gi[-1]))
    if stats is not None:
        stats.update(counted)
    with timed("irradiance"):
        per_group = None
        if gi is not None:
            per_group = _group_bands(ends, gi, w, sky, vd64, albedo, groups, perez, void)
        if not perez:
            diffuse = float(np.sum(w * sky.dhi)) * vd64
        if groups is not None and groups.albedo is not None:
            reflected = per_group[1]
        else:
            reflected = float(np.sum(w * sky.ghi)) * albedo * (1.0 - vd64)
        beam[void] = np.nan
        diffuse[void] = np.nan
        bands = {"beam": beam, "diffuse": diffuse, "reflected": reflected,
                 "global": beam + diffuse + reflected}
        out = {k: v.astype(np.float32) for k, v in bands.items()}
        if groups is not None and groups.bands:
            out["groups"] = per_group[0]
        return out


def cell_light(cells, k: int, tl_on: bool) -> tuple[bool, bool]:
    """(any open sky, a beam) at sample ``k`` of the open sky per cell, whose per-sample terms
    are ``cells`` (:class:`SampleSky`): with each cell's Linke turbidity (``tl_on``) the sun up (an air mass and cos Z >
    0), else the sample's clear sky before the indices."""
    if tl_on:
        up = bool(np.isfinite(cells.am[k]) and cells.cosz[k] > 0)
        return up, up
    return (bool(cells.ghi[k] > 0 or cells.dni[k] > 0 or cells.dhi[k] > 0),
            bool(cells.dni[k] > 0))


def cell_casts(cells, k: int, tl_on: bool, sun, soft: bool = False,
               perez: bool = False) -> bool:
    """Whether ``sums`` with the open sky per cell (``cells``, :func:`cell_light`) asks for the
    direct term of sample ``k`` (``sun``): a beam, or Perez's circumsolar part, and the sun
    (its disk, ``soft``) up somewhere; :func:`casts` where the sky is one for all cells."""
    up, beam_up = cell_light(cells, k, tl_on)
    return bool(up and (beam_up or perez) and not is_dark(sun, soft))


def _light_of(direct, s, timed, shape, normals) -> np.ndarray:
    """Sun ``s``'s light from ``direct`` (contiguous), checked: float32 of ``shape`` (the lit
    fraction, or max(cos i, 0) · lit), or the uint8 cast mask where the kernel takes the
    incidence from the ``normals``."""
    lit = np.ascontiguousarray(direct(s, timed))
    if lit.shape != shape or not (lit.dtype == np.float32 or (
            lit.dtype == np.uint8 and normals is not None)):
        raise HillshadeError(f"the light of a sun is {lit.dtype} {lit.shape}, not float32 "
                             f"{shape}")
    return lit


def _stand_ins(shape) -> tuple:
    """The arrays a kernel call does not read (its options off) and the rows' tile 0: (float64
    2-D, int64 1-D, float64 (1, 1, 3), float32 lit, uint8 cast, the rows of ``shape``)."""
    return (np.empty((1, 1), np.float64), np.zeros(1, np.int64), np.zeros((1, 1, 3), np.float64),
            np.empty((1, 1), np.float32), np.empty((1, 1), np.uint8),
            np.zeros(shape[0], np.int64))


def _group_index(groups, n: int):
    """Each of the ``n`` suns' group (int64; None without groups), checked: numbered from 0 in
    the suns' order, never decreasing."""
    if groups is None:
        return None
    gi = np.asarray(groups.index, np.int64)
    if len(gi) != n or (n and (gi[0] != 0 or np.any(np.diff(gi) < 0))):
        raise HillshadeError("one group per sun, numbered from 0 in the suns' order")
    return gi


def _sums_cells(direct, void, loop, suns, w, sky, vd64, albedo, cells: CellSky, soft, perez,
                sin_s, horizon_share, counted, stats, timed, normals, groups) -> dict:
    """``sums`` with the open sky per cell (``cells``): each sample with light added cell by
    cell, its beam, its diffuse (isotropic: each cell's DHI, times Vd at the end; Perez: the
    cell's own coefficients) and each cell's GHI (the reflected light's, times albedo · (1 -
    Vd) at the end)."""
    from ..algorithms.irradiance import add_sample_cells
    shape = void.shape
    n = len(suns)
    beam = np.zeros(shape, np.float64)
    diffuse = np.zeros(shape, np.float64)
    ghi_sum = np.zeros(shape, np.float64)
    none2, none1, none3, no_lit, no_cast, rows0 = _stand_ins(shape)
    if not perez:
        sin_s = horizon_share = none2
    t = cells.terms
    kz3 = PEREZ_KAPPA * t.z ** 3
    bfac = np.maximum(np.cos(t.z), COS_85)
    table = np.ascontiguousarray(PEREZ_1990, np.float64)
    bins = np.array(PEREZ_EPSILON_BINS, np.float64)
    gi = _group_index(groups, n)
    if len(t.am) != n:
        raise HillshadeError("one open sky per cell per sun")
    ends = []
    prev = [beam.copy(), diffuse.copy(), ghi_sum.copy()] if gi is not None else None

    def close(g):
        ends.append((g, beam - prev[0], diffuse - prev[1], ghi_sum - prev[2]))
        prev[0], prev[1], prev[2] = beam.copy(), diffuse.copy(), ghi_sum.copy()
    for k in loop:
        if gi is not None and k > 0 and gi[k] != gi[k - 1]:
            close(int(gi[k - 1]))
        tl, corr, kb, kd = cells.at(k)
        tl_on = tl is not None
        up, beam_up = cell_light(t, k, tl_on)
        if not up:
            continue
        s = suns[k]
        lit = None
        if cell_casts(t, k, tl_on, s, soft, perez):
            lit = _light_of(direct, s, timed, shape, normals)
            counted["samples_with_shadows"] += 1
        with timed("irradiance"):
            if lit is not None and normals is not None:
                row_tile, col_tile, vec = tile_suns(s, shape)
                ge, gn, length = normals
            else:
                row_tile, col_tile, vec, ge, gn, length = rows0, none1, none3, none2, none2, none2
            mask = lit is not None and lit.dtype == np.uint8
            kb_on, kd_on = isinstance(kb, np.ndarray), isinstance(kd, np.ndarray)
            add_sample_cells(
                no_lit if lit is None or mask else lit, lit if mask else no_cast, mask,
                ge, gn, length, row_tile, col_tile, vec, lit is not None and normals is not None,
                lit is not None, float(w[k]),
                np.array([t.ghi[k], t.dni[k], t.dhi[k]], np.float64),
                tl_on, tl if tl_on else none2, corr if tl_on else none2,
                np.array([t.am[k], t.extra[k], t.cosz[k], *t.consts],
                         np.float64),
                kb_on, kb if kb_on else none2, 1.0 if kb_on else float(kb),
                kd_on, kd if kd_on else none2, 1.0 if kd_on else float(kd),
                perez, np.array([t.z[k], kz3[k], t.am_rel[k], t.extra[k], bfac[k],
                                 1.0 if np.isfinite(t.am_rel[k]) else 0.0], np.float64),
                table, bins, vd64, sin_s, horizon_share, beam, diffuse, ghi_sum)
    if gi is not None and n:
        close(int(gi[-1]))
    if stats is not None:
        stats.update(counted)
    with timed("irradiance"):
        per_group, refl_total = [], None
        for g, b, d, gh in ends:
            ag = albedo if groups.albedo is None else groups.albedo[g]
            refl = gh * ag * (1.0 - vd64)
            if groups.albedo is not None:
                refl_total = refl if refl_total is None else refl_total + refl
            if groups.bands:
                glob = (b + (d if perez else d * vd64) + refl).astype(np.float32)
                glob[void] = np.nan
                per_group.append(glob)
        if not perez:
            diffuse = diffuse * vd64
        reflected = (refl_total if groups is not None and groups.albedo is not None
                     else ghi_sum * albedo * (1.0 - vd64))
        beam[void] = np.nan
        diffuse[void] = np.nan
        reflected = np.where(void, np.nan, reflected)
        bands = {"beam": beam, "diffuse": diffuse, "reflected": reflected,
                 "global": beam + diffuse + reflected}
        out = {k: v.astype(np.float32) for k, v in bands.items()}
        if groups is not None and groups.bands:
            out["groups"] = per_group
        return out


def _group_bands(ends, gi, w, sky, vd64, albedo, groups: Groups, perez, void):
    """(each group's global band (float32, NaN voids), the reflected light summed over the
    groups with their own albedo (float64; None without ``groups.albedo``))."""
    out, refl_total = [], None
    for g, b, d in ends:
        sel = gi == g
        ag = albedo if groups.albedo is None else groups.albedo[g]
        refl = float(np.sum(w[sel] * sky.ghi[sel])) * ag * (1.0 - vd64)
        if groups.albedo is not None:
            refl_total = refl if refl_total is None else refl_total + refl
        if groups.bands:
            dif = d if perez else float(np.sum(w[sel] * sky.dhi[sel])) * vd64
            glob = (b + dif + refl).astype(np.float32)
            glob[void] = np.nan
            out.append(glob)
    return out, refl_total


def _stacks(direct, void, loop, suns, sky, vd, vd64, albedo, soft, perez, sin_s,
            horizon_share, counted, timed) -> dict:
    """``sums``' (times, rows, cols) stacks of W/m² (``per_time``), sun by sun in numpy."""
    n = len(suns)
    shape = void.shape
    stacks = {k: np.empty((n,) + shape, np.float32) for k in BANDS}
    zero = np.where(void, np.float32(np.nan), np.float32(0.0))
    for k in loop:
        s = suns[k]
        dni, dhi, ghi = float(sky.dni[k]), float(sky.dhi[k]), float(sky.ghi[k])
        d_k = None
        if casts(sky, k, s, soft, perez):
            d_k = direct(s, timed)
            counted["samples_with_shadows"] += 1
        with timed("irradiance"):
            b_t = zero if d_k is None else np.float32(dni) * d_k
            if perez:
                if dhi > 0 and sky.perez_on[k]:
                    d_t = (1.0 - sky.f1[k]) * vd64 + sky.f2[k] * sin_s * horizon_share
                    if d_k is not None and sky.f1[k] > 0:
                        d_t += (sky.f1[k] / sky.b[k]) * d_k
                    d_t = np.maximum(dhi * d_t, 0.0)
                else:
                    d_t = zero
            stacks["beam"][k] = b_t
            stacks["diffuse"][k] = d_t if perez else np.float32(dhi) * vd
            stacks["reflected"][k] = np.float32(ghi * albedo) * (1.0 - vd)
            stacks["global"][k] = (stacks["beam"][k] + stacks["diffuse"][k]
                                   + stacks["reflected"][k])
    return stacks


def definitions(sky_model: str, directions: int, soft: bool) -> str:
    """The bands' formulas, for the output's tags."""
    lit = "visible fraction of the solar disk" if soft else "1 lit, 0 in cast shadow"
    diffuse = (f"DHI * Vd (isotropic; Vd: Dozier sky view factor of the tilted surface, "
               f"{directions} directions)" if sky_model == "isotropic" else
               f"Perez 1990: max(0, DHI * ((1 - F1) Vd + F1 max(cos i, 0) lit / max(cos Z, "
               f"cos 85) + F2 sin S min(1, Vd / ((1 + cos S) / 2)))), Vd: Dozier sky view "
               f"factor of the tilted surface, {directions} directions")
    return (f"beam = DNI * max(cos i, 0) * lit (i: incidence on the cell's surface, Horn "
            f"normals; lit: {lit}); diffuse = {diffuse}; reflected = GHI * albedo * (1 - Vd); "
            "global = beam + diffuse + reflected")


# --------------------------------------------------------------------------------------------
# one instant (r.sun's mode 1)

def sky_at(sky: Sky, k: int) -> Sky:
    """The open sky of sample ``k`` alone: a one-sample :class:`Sky` (Perez's coefficients
    too, where it has them)."""
    from dataclasses import replace

    def one(v):
        return None if v is None else v[k:k + 1]
    return replace(sky, dni=one(sky.dni), dhi=one(sky.dhi), ghi=one(sky.ghi), f1=one(sky.f1),
                   f2=one(sky.f2), b=one(sky.b), perez_on=one(sky.perez_on))


def surface_elevation(cos_i: np.ndarray) -> np.ndarray:
    """The sun's elevation above each cell's surface plane, degrees (float32, NaN voids), from
    cos i (i: the angle of incidence from the surface's normal): 90 - i = asin(cos i), in
    float64 then rounded. 90: the sun along the normal; 0 or less: the sun behind the surface.
    GRASS r.sun's incidout is this angle (NULL where it is not positive or in cast shadow)."""
    c = np.clip(cos_i.astype(np.float64), -1.0, 1.0)
    return np.degrees(np.arcsin(c)).astype(np.float32)


def instant(shader, sun, sky: Sky, k: int, vd: np.ndarray, albedo: float, *,
            soft: bool = False, perez: bool = False, stats: dict | None = None, timer=None,
            normals=None, cells: CellSky | None = None) -> dict:
    """The irradiance at one instant (r.sun's mode 1): sample ``k`` of ``sky`` under ``sun``
    (a ``sun.SunOver``) as ``accumulate`` adds it, alone and with weight 1, so each band is
    that sample's contribution in W/m² (the same formulas and arithmetic as the period's sums,
    which add w_k times these in float64), float32, NaN voids; "incidence" (``INSTANT_BANDS``)
    is :func:`surface_elevation` of the sun on every cell, tile by tile where the sun is per
    tile (the incidence the beam uses). ``stats``: "samples_with_shadows" counts the instants
    whose cast shadows were computed. ``cells``: the open sky per cell of every sample
    (:class:`CellSky`), sample ``k``'s taken."""
    one: dict = {}
    bands = accumulate(shader, [sun], [1.0], sky_at(sky, k), vd, albedo, soft=soft, perez=perez,
                       stats=one, timer=timer, normals=normals,
                       cells=None if cells is None else cells.sample(k))
    if stats is not None:
        stats["samples_with_shadows"] = (stats.get("samples_with_shadows", 0)
                                         + one.get("samples_with_shadows", 0))
    with (timer("irradiance") if timer is not None else _nothing()):
        bands["incidence"] = surface_elevation(cos_incidence(shader, sun))
    return bands
