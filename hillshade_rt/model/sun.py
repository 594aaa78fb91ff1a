"""The sun's position from a time and a place: NREL's SPA (through pvlib), times, zones, series.

* Times are ISO 8601 instants. A time without a UTC offset is refused unless an IANA zone is
  named (``tz``), which then also decides daylight saving; ambiguous and non-existent local times
  (the hour that repeats or is skipped when clocks change) are refused, naming the gap or the
  repeated span and, for a repeated one, the two offsets to choose from.
* Series (:func:`time_range`) and sun-hours days (:func:`day_samples`) step in elapsed time,
  computed in UTC; their times are shown in the zone with each instant's own offset.
* The solar position is NREL's Solar Position Algorithm (Reda & Andreas 2004 [1]_ [2]_) as
  implemented by ``pvlib.spa`` (its numpy version) [3]_: topocentric azimuth (clockwise from true
  north) and elevation, apparent (with the SPA's refraction) unless refraction is turned off.
* A DEM's sun is computed at its centre, converted from true north to the raster's grid north
  (meridian convergence of its projection), and, where the direction differs across the raster by
  more than a tolerance, per tile (:func:`sun_over`).

References
----------
.. [1] I. Reda, A. Andreas, "Solar position algorithm for solar radiation applications," Solar
       Energy, vol. 76, no. 5, pp. 577-589, 2004. :doi:`10.1016/j.solener.2003.12.003`
.. [2] I. Reda, A. Andreas, "Solar Position Algorithm for Solar Radiation Applications," National
       Renewable Energy Laboratory, Technical Report NREL/TP-560-34302.
.. [3] W. F. Holmgren, C. W. Hansen, M. A. Mikofski, "pvlib python: a python package for modeling
       solar energy systems," Journal of Open Source Software, vol. 3, no. 29, p. 884, 2018.
       :doi:`10.21105/joss.00884`
"""

from __future__ import annotations

import datetime as _dt
import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import HillshadeError, HillshadeWarning, UsageProblem

UTC = _dt.timezone.utc
STANDARD_PRESSURE_HPA = 1013.25
STANDARD_TEMPERATURE_C = 12.0      # the SPA's (and pvlib's) default
ATMOS_REFRACT = 0.5667             # the SPA's refraction at sunrise/sunset, degrees
SUN_RADIUS_DEG = 0.533 / 2         # the solar disk: 0.533 degrees across
DEFAULT_TOLERANCE = 0.05           # degrees: above this the sun is computed per tile
MAX_TILES = 4096
# the years NREL's SPA is valid for (Reda & Andreas 2004, NREL/TP-560-34302: "for the period
# from the year -2000 to 6000"); ΔT (TT - UT) is known for -1999..3000 only (pvlib.spa
# extrapolates it beyond, with a warning this module turns into one line)
SPA_YEARS = (-2000, 6000)
DELTA_T_YEARS = (-1999, 3000)


# --------------------------------------------------------------------------------------------
# times

AUTO_ZONE = "auto"      # --tz auto: the zone of the DEM's centre (:func:`zone_at`)


def zone(name: str | None):
    """An IANA time zone (``zoneinfo``), or None (also for ``auto``, the DEM's zone, which only
    the DEM's place decides: :func:`zone_at`)."""
    if name is None or is_auto(name):
        return None
    from zoneinfo import ZoneInfo, ZoneInfoNotFoundError
    try:
        return ZoneInfo(name)
    except (ZoneInfoNotFoundError, ValueError, TypeError):
        raise HillshadeError(f"--tz {name!r}: not an IANA time zone name "
                             "(e.g. Europe/Zurich, America/Denver, UTC)") from None


def is_auto(name) -> bool:
    """Whether a --tz value asks for the DEM's own zone."""
    return isinstance(name, str) and name.strip().lower() == AUTO_ZONE


_FINDER = []


def zone_name_at(lon: float, lat: float) -> str | None:
    """The IANA zone name at (``lon``, ``lat``) (WGS84 degrees) from timezonefinder's polygons
    (timezone-boundary-builder, shipped in its wheel: offline); at sea the nautical
    ``Etc/GMT+N`` zone it gives; None where it has nothing or is not installed."""
    try:
        from timezonefinder import TimezoneFinder
    except ImportError:
        return None
    if not _FINDER:
        _FINDER.append(TimezoneFinder())
    lon = (float(lon) + 180.0) % 360.0 - 180.0
    lat = min(max(float(lat), -90.0), 90.0)
    try:
        return _FINDER[0].timezone_at(lng=lon, lat=lat)
    except ValueError:
        return None


def zone_at(lon: float, lat: float):
    """(tzinfo, name) of the place (``lon``, ``lat``): its IANA zone (``zoneinfo``, daylight
    saving included), or, where none is known (no zone data, or timezonefinder missing), the
    whole-hour offset nearest the longitude (``Etc/GMT-1`` east of Greenwich, as the nautical
    zones are named; a fixed offset)."""
    from zoneinfo import ZoneInfo, ZoneInfoNotFoundError
    name = zone_name_at(lon, lat)
    if name is not None:
        try:
            return ZoneInfo(name), name
        except (ZoneInfoNotFoundError, ValueError):
            pass
    hours = int(round(((float(lon) + 180.0) % 360.0 - 180.0) / 15.0))
    name = "Etc/GMT" + (f"{-hours:+d}" if hours else "")
    try:
        return ZoneInfo(name), name
    except (ZoneInfoNotFoundError, ValueError):
        return _dt.timezone(_dt.timedelta(hours=hours)), f"UTC{hours:+03d}:00"


def zone_label(tz, name: str, when: _dt.datetime | None = None) -> str:
    """``Europe/Zurich (UTC+02:00, CEST)``: a zone's name with its offset at ``when`` (aware;
    default now)."""
    when = (when or _dt.datetime.now(UTC)).astimezone(tz)
    abbr = when.tzname() or ""
    off = "UTC" + _offset(when.utcoffset())
    extra = f", {abbr}" if abbr and abbr[0].isalpha() and abbr != "UTC" else ""
    return f"{name} ({off}{extra})"


def _transition(tz, lo: _dt.datetime, hi: _dt.datetime) -> _dt.datetime:
    """The first instant (UTC, whole seconds) in (lo, hi] whose offset in ``tz`` is that of
    ``hi``: where the zone's clocks change, found by bisection (``zoneinfo`` has no public list of
    transitions)."""
    target = hi.astimezone(tz).utcoffset()
    a, b = math.floor(lo.timestamp()), math.ceil(hi.timestamp())
    while b - a > 1:
        m = (a + b) // 2
        if _dt.datetime.fromtimestamp(m, UTC).astimezone(tz).utcoffset() == target:
            b = m
        else:
            a = m
    return _dt.datetime.fromtimestamp(b, UTC)


def _clock(t: _dt.datetime) -> str:
    return t.strftime("%H:%M:%S" if t.second else "%H:%M")


def clock_change(naive: _dt.datetime, tz):
    """How zone ``tz`` treats the local time ``naive``: None when it happens exactly once, else
    ``(kind, first, last, before, after, at)`` with ``kind`` "gap" (clocks jump forward over
    [first, last)) or "fold" (clocks go back and [first, last) happens twice), the offsets
    ``before`` and ``after`` the change and ``at``, the instant of the change (UTC)."""
    a = naive.replace(tzinfo=tz, fold=0)
    b = naive.replace(tzinfo=tz, fold=1)
    if a.utcoffset() == b.utcoffset():
        return None
    ua, ub = a.astimezone(UTC), b.astimezone(UTC)
    at = _transition(tz, min(ua, ub), max(ua, ub))
    before = (at - _dt.timedelta(seconds=1)).astimezone(tz).utcoffset()
    after = at.astimezone(tz).utcoffset()
    wall_before, wall_after = ((at + o).replace(tzinfo=None) for o in (before, after))
    if after > before:
        kind, first, last = "gap", wall_before, wall_after
    else:
        kind, first, last = "fold", wall_after, wall_before
    if not first <= naive < last:      # a zone whose fold/gap flags disagree with the bisection
        return None
    return kind, first, last, before, after, at


def _offset(td: _dt.timedelta) -> str:
    """A UTC offset as ISO 8601 writes it: +02:00, -05:00, +10:30."""
    sec = round(td.total_seconds())
    sign, sec = ("+" if sec >= 0 else "-"), abs(sec)
    h, rest = divmod(sec, 3600)
    m, sec = divmod(rest, 60)
    return f"{sign}{h:02d}:{m:02d}" + (f":{sec:02d}" if sec else "")


def localize(naive: _dt.datetime, tz, what: str) -> _dt.datetime:
    """Attach zone ``tz`` to a naive local time. A local time that the zone skips (clocks jump
    forward over it) is refused, naming the gap; one that happens twice (clocks go back) is
    refused too, naming both instants with their offsets: an hour's difference moves the sun by
    about 15 degrees, so neither is picked silently."""
    change = clock_change(naive, tz)
    if change is None:
        return naive.replace(tzinfo=tz, fold=0)
    kind, first, last, before, after, _ = change
    same_day = first.date() == last.date()
    a, b = (_clock(first), _clock(last)) if same_day else (iso(first), iso(last))
    span = f"{a}-{b} on {first.date().isoformat()}" if same_day else f"{a} to {b}"
    local = iso(naive)
    if kind == "gap":
        raise HillshadeError(
            f"{what} does not exist in {tz.key}: clocks jump from {a} ({_offset(before)}) to "
            f"{b} ({_offset(after)}), skipping {span}; give a time outside the gap, or one with "
            "a UTC offset")
    raise HillshadeError(
        f"{what} happens twice in {tz.key}: clocks go back from {b} ({_offset(before)}) to "
        f"{a} ({_offset(after)}), so {span} repeats; give a UTC offset: "
        f"{local}{_offset(before)} (the first) or {local}{_offset(after)} (the second)")


def parse_time(text: str, tz=None, what: str = "--time", spa: bool = True) -> _dt.datetime:
    """An ISO 8601 time (``2026-06-21T14:30:00+02:00``, ``...Z``, or local time with ``tz``) as
    an aware datetime. A time with an offset keeps its instant; ``tz`` then only names the zone
    outputs are labelled in. A date without a time of day is refused (it is not an instant:
    midnight is rarely what was meant). ``what``: the option named in errors. ``spa``: the sun
    is computed for it, so its year must be within the SPA's range (:func:`check_year`)."""
    s = str(text).strip()
    try:
        _dt.date.fromisoformat(s)
    except ValueError:
        pass
    else:
        raise HillshadeError(f"{what} {text!r} is a date without a time of day: give a time, "
                             f"e.g. {s}T12:00 (for whole days: sun-hours --date)")
    try:
        t = _dt.datetime.fromisoformat(s.replace("z", "Z"))
    except ValueError:
        raise HillshadeError(f"{what} {text!r}: not an ISO 8601 time "
                             "(e.g. 2026-06-21T14:30:00+02:00)") from None
    if spa:
        check_year(t.year, f"{what} {text!r}")
    if t.tzinfo is None:
        if tz is None:
            raise HillshadeError(f"time {text!r} has no UTC offset: add one (e.g. +02:00 or Z) or "
                                 "name the zone with --tz (e.g. --tz Europe/Zurich)")
        return localize(t, tz, f"{what} {text!r}")
    return t.astimezone(tz) if tz is not None else t


def check_year(year: int, what: str) -> None:
    """Refuse a year outside the SPA's validity (:data:`SPA_YEARS`): :class:`UsageProblem`
    naming ``what`` (the option and its value)."""
    lo, hi = SPA_YEARS
    if not lo <= year <= hi:
        raise UsageProblem(f"{what}: year {year} is outside the solar position algorithm's range "
                           f"(NREL SPA: years {lo} to {hi})")


_STEP_UNITS = {"s": 1, "sec": 1, "second": 1, "seconds": 1, "m": 60, "min": 60, "mins": 60,
               "minute": 60, "minutes": 60, "h": 3600, "hr": 3600, "hour": 3600, "hours": 3600,
               "d": 86400, "day": 86400, "days": 86400}


def parse_step(text: str) -> _dt.timedelta:
    """A step such as ``30min``, ``1h``, ``1h30min``, ``90s``, ``1d`` or ISO 8601 ``PT30M``."""
    s = str(text).strip().lower()
    iso = re.fullmatch(r"p(?:(\d+(?:\.\d+)?)d)?(?:t(?:(\d+(?:\.\d+)?)h)?(?:(\d+(?:\.\d+)?)m)?"
                       r"(?:(\d+(?:\.\d+)?)s)?)?", s)
    seconds = None
    if iso and s not in ("p", "pt"):
        d, h, m, sec = (float(g) if g else 0.0 for g in iso.groups())
        seconds = d * 86400 + h * 3600 + m * 60 + sec
    else:
        parts = re.findall(r"(\d+(?:\.\d+)?)\s*([a-z]+)", s)
        if parts and re.fullmatch(r"(?:\s*\d+(?:\.\d+)?\s*[a-z]+)+\s*", s) and \
                all(u in _STEP_UNITS for _, u in parts):
            seconds = sum(float(v) * _STEP_UNITS[u] for v, u in parts)
    if seconds is None:
        raise HillshadeError(f"--step {text!r}: not a duration (e.g. 30min, 1h, 10min, PT30M)")
    if seconds < 1:
        raise HillshadeError(f"--step {text!r}: must be at least one second")
    return _dt.timedelta(seconds=seconds)


def time_range(start: _dt.datetime, end: _dt.datetime, step: _dt.timedelta,
               limit: int = 1_000_000) -> list[_dt.datetime]:
    """start, start + step, start + 2 step, ... while not after ``end`` (included when a step
    lands on it exactly), all as instants: steps are elapsed time, so a series across a
    daylight-saving change keeps equal intervals and covers the hour the clocks skip or repeat
    once as it passes (e.g. 00:30 to 04:30 by 1h in America/New_York gives 4 times on the day
    clocks spring forward, 6 on the day they fall back). Each time is shown in ``start``'s zone
    with its own offset. The arithmetic and comparisons are done in UTC: Python subtracts and
    compares two datetimes that share a zone object by their wall clocks."""
    u0, u1 = start.astimezone(UTC), end.astimezone(UTC)
    if u1 < u0:
        raise HillshadeError(f"--end {iso(end)} is before --start {iso(start)}")
    if step <= _dt.timedelta(0):
        raise HillshadeError("--step must be positive")
    n = (u1 - u0) // step + 1          # exact: timedeltas divide in whole microseconds
    if n > limit:
        raise HillshadeError(f"{n} times from --start to --end at this --step: more than {limit}")
    tz = start.tzinfo
    return [(u0 + i * step).astimezone(tz) for i in range(n)]


def parse_date(text: str, what: str = "--date") -> _dt.date:
    try:
        day = _dt.date.fromisoformat(str(text).strip())
    except ValueError:
        raise HillshadeError(f"{what} {text!r}: not a date (YYYY-MM-DD)") from None
    check_year(day.year, f"{what} {text!r}")
    return day


def day_start(day: _dt.date, tz) -> _dt.datetime:
    """The first instant (UTC) of ``day`` in zone ``tz``: local midnight; where the clocks skip
    midnight (a gap that contains it, as in America/Santiago) the instant they jump, where
    midnight happens twice its first occurrence."""
    naive = _dt.datetime.combine(day, _dt.time(0))
    change = clock_change(naive, tz)
    if change is not None and change[0] == "gap":
        return change[5]
    return naive.replace(tzinfo=tz, fold=0).astimezone(UTC)


def day_samples(first: _dt.date, last: _dt.date, step: str, tz, lon: float,
                limit: int = 2_000_000) -> tuple[list[_dt.datetime], list[float]]:
    """Sample times and their weights in hours for the days ``first``..``last``: each day cut
    into intervals of ``step`` (elapsed time; the last one shorter if the step does not divide
    the day), a sample at the middle of each. Days run from midnight to midnight in zone ``tz``
    (:func:`day_start`), so a day on which the clocks change has as many hours as elapse: 23 or
    25 for a one-hour change, 23.5 or 24.5 in Australia/Lord_Howe; or in local mean solar time at
    ``lon`` when ``tz`` is None (always 24 hours)."""
    dt = parse_step(step)
    times, weights = [], []
    day = first
    one = _dt.timedelta(days=1)
    while day <= last:
        if tz is not None:
            t0, t1 = day_start(day, tz), day_start(day + one, tz)
        else:
            t0 = _dt.datetime.combine(day, _dt.time(0), UTC) - _dt.timedelta(hours=lon / 15.0)
            t1 = t0 + one
        t = t0
        while t < t1:
            e = min(t + dt, t1)
            mid = t + (e - t) / 2
            times.append(mid.astimezone(tz) if tz is not None else mid)
            weights.append((e - t).total_seconds() / 3600.0)
            t = e
        if len(times) > limit:
            raise HillshadeError(f"more than {limit} samples: use a longer --step")
        day += one
    return times, weights


def daylight_samples(first: _dt.date, last: _dt.date, step: str, tz, site, atmosphere=None,
                     limit: int = 2_000_000) -> tuple[list[_dt.datetime], list[float]]:
    """Sun hours' samples: the intervals of :func:`day_samples`, each weighted by the part of
    it during which the sun's centre is up at ``site`` (its apparent elevation, the SPA's
    refraction unless ``atmosphere`` turns it off, above 0: the tool's sunrise and sunset), and
    sampled at the middle of that part (the middle of the interval when the sun is up
    throughout; of the longest up stretch when it rises and sets inside one interval). An
    interval without the sun has weight 0 (its time the middle). So on flat open ground the
    hours are the day length, and nowhere more: a sample lit or not counts at most the time
    the sun is up within its interval. Sunrise and sunset inside an interval are found by
    bisection on the SPA (to under a second); the sun checked at each interval's ends and
    middle, so a sun that rises and sets within half a step (a polar day's edge with a step of
    hours) is missed, which only ever counts less."""
    atmosphere = Atmosphere() if atmosphere is None else atmosphere
    mids, hours = day_samples(first, last, step, tz, site.lon, limit)
    mid = np.array([t.timestamp() for t in mids], np.float64)
    half = np.asarray(hours, np.float64) * 1800.0        # half an interval, seconds
    a, b = mid - half, mid + half

    def up(ts):
        if ts.size == 0:
            return np.zeros(0, bool)
        return solar_position(ts, site.lat, site.lon, site.height, atmosphere)[1] > 0.0

    ua, um, ub = np.split(up(np.concatenate([a, mid, b])), 3)
    weights = np.where(ua & um & ub, hours, 0.0).astype(np.float64)
    times = list(mids)
    edge = np.flatnonzero((ua | um | ub) & ~(ua & um & ub))
    if edge.size:
        # each half interval with a change: its crossing by bisection (all edges at once)
        lo = np.concatenate([a[edge], mid[edge]])
        hi = np.concatenate([mid[edge], b[edge]])
        up_lo = np.concatenate([ua[edge], um[edge]])
        up_hi = np.concatenate([um[edge], ub[edge]])
        change = up_lo != up_hi
        x0, x1 = lo[change].copy(), hi[change].copy()
        u0 = up_lo[change]
        while x0.size and np.max(x1 - x0) > 0.5:
            xm = (x0 + x1) / 2.0
            um_ = up(xm)
            same = um_ == u0
            x0 = np.where(same, xm, x0)
            x1 = np.where(same, x1, xm)
        cross = np.full(lo.shape, np.nan)
        cross[change] = (x0 + x1) / 2.0
        n = edge.size
        for k, i in enumerate(edge):
            pieces = []          # the stretches with the sun up, in order, merged when they touch
            for j in (k, k + n):
                s0, s1 = lo[j], hi[j]
                if up_lo[j] and up_hi[j]:
                    part = (s0, s1)
                elif up_lo[j]:
                    part = (s0, cross[j])
                elif up_hi[j]:
                    part = (cross[j], s1)
                else:
                    continue
                if pieces and abs(pieces[-1][1] - part[0]) < 1e-6:
                    pieces[-1] = (pieces[-1][0], part[1])
                else:
                    pieces.append(part)
            if not pieces:
                continue
            weights[i] = sum(p1 - p0 for p0, p1 in pieces) / 3600.0
            p0, p1 = max(pieces, key=lambda p: p[1] - p[0])
            t = _dt.datetime.fromtimestamp((p0 + p1) / 2.0, UTC)
            times[i] = t.astimezone(tz) if tz is not None else t
    return times, [float(w) for w in weights]


def iso(t: _dt.datetime) -> str:
    """ISO 8601 with the offset, seconds only when needed."""
    return t.isoformat(timespec="seconds" if t.second or t.microsecond else "minutes")


# --------------------------------------------------------------------------------------------
# solar position

@dataclass(frozen=True)
class Atmosphere:
    """Refraction settings: apparent positions with the SPA's refraction at this pressure and
    temperature, or true positions (``refraction=False``)."""

    refraction: bool = True
    pressure_hpa: float | None = None      # None: standard atmosphere at the observer's height
    temperature_c: float = STANDARD_TEMPERATURE_C

    def pressure_at(self, height_m):
        """hPa at ``height_m`` (a number or an array)."""
        if self.pressure_hpa is not None:
            return np.full(np.shape(height_m), float(self.pressure_hpa)) if np.ndim(height_m) \
                else float(self.pressure_hpa)
        return standard_pressure(height_m)


def standard_pressure(height_m):
    """hPa of the ICAO standard atmosphere at ``height_m`` (1013.25 at sea level); arrays too."""
    h = np.clip(np.asarray(height_m, np.float64), -500.0, 11000.0)
    p = STANDARD_PRESSURE_HPA * (1.0 - 2.25577e-5 * h) ** 5.25588
    return float(p) if p.ndim == 0 else p


def solar_position(times, lat, lon, height_m=0.0, atmosphere: Atmosphere = Atmosphere(),
                   delta_t: float | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(azimuth, elevation, zenith) in degrees of the sun at ``times`` (aware datetimes, or unix
    seconds) seen from (lat, lon, height_m); arrays broadcast together. Azimuth clockwise from
    true north; elevation and zenith apparent (SPA refraction) unless ``atmosphere.refraction`` is
    False. ``delta_t``: TT - UT1 in seconds (default: pvlib's estimate for the year)."""
    from pvlib import spa

    if not isinstance(times, np.ndarray) or times.dtype == object:
        times = np.array([t.timestamp() if isinstance(t, _dt.datetime) else float(t)
                          for t in np.ravel(np.asarray(times, dtype=object))], dtype=np.float64)
    unix, lat, lon, h = np.broadcast_arrays(np.asarray(times, np.float64),
                                            np.asarray(lat, np.float64),
                                            np.asarray(lon, np.float64),
                                            np.asarray(height_m, np.float64))
    shape = unix.shape
    unix, lat, lon, h = (np.ravel(a) for a in (unix, lat, lon, h))
    finite = unix[np.isfinite(unix)]
    if finite.size:
        span = np.floor(np.array([finite.min(), finite.max()])).astype("datetime64[s]")
        y0, y1 = (span.astype("datetime64[Y]").astype(np.int64) + 1970).tolist()
        lo, hi = SPA_YEARS
        if y0 < lo or y1 > hi:
            bad = y0 if y0 < lo else y1
            raise UsageProblem(f"year {bad} is outside the solar position algorithm's range "
                               f"(NREL SPA: years {lo} to {hi})")
    if delta_t is None:
        dt64 = np.floor(unix).astype("datetime64[s]")
        years = dt64.astype("datetime64[Y]").astype(np.int64) + 1970
        months = dt64.astype("datetime64[M]").astype(np.int64) % 12 + 1
        lo, hi = DELTA_T_YEARS
        outside = (years < lo) | (years > hi)
        if outside.any():
            import warnings
            with warnings.catch_warnings():         # pvlib's multi-line warning: ours instead
                warnings.simplefilter("ignore")
                delta_t = spa.calculate_deltat(years, months)
            far = years[outside]
            warnings.warn(HillshadeWarning(
                f"year {int(far.min()) if far.min() < lo else int(far.max())}: delta T (TT - UT) is "
                f"known for the years {lo} to {hi} only; pvlib's extrapolation is used, so the "
                "sun's position there is uncertain"), stacklevel=2)
        else:
            delta_t = spa.calculate_deltat(years, months)
    pressure = atmosphere.pressure_at(h)
    zen_app, zen, el_app, el, az, _ = spa.solar_position_numpy(
        unix, lat, lon, h, pressure, float(atmosphere.temperature_c), delta_t, ATMOS_REFRACT, 1)
    if atmosphere.refraction:
        el_out, zen_out = el_app, zen_app
    else:
        el_out, zen_out = el, zen
    return (np.asarray(az, np.float64).reshape(shape), np.asarray(el_out, np.float64).reshape(shape),
            np.asarray(zen_out, np.float64).reshape(shape))


# --------------------------------------------------------------------------------------------
# where a DEM is

EARTH_A_RANGE = (6.35e6, 6.40e6)   # semi-major axes of Earth ellipsoids (metres)


@dataclass
class Site:
    """Where a DEM's sun is computed: its centre (or the user's --lat/--lon) and the ground
    height there; ``to_lonlat`` maps pixel coordinates to longitude/latitude when the DEM has a
    CRS (None otherwise: one sun for the whole raster)."""

    lat: float
    lon: float
    height: float
    source: str
    to_lonlat: object = None     # callable(rows, cols) -> (lon, lat) arrays, or None
    convergence: object = None   # callable(rows, cols) -> grid azimuth of true north, degrees
    north_offset: float = 0.0    # without to_lonlat: grid azimuth of true north (DEM centre)
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"latitude": self.lat, "longitude": self.lon, "height_m": self.height,
                "source": self.source}


def centre_height_of(z: np.ndarray, r: int | None = None, c: int | None = None) -> tuple[float, str]:
    """The observer's height: the centre cell (``r``, ``c``; default the middle of ``z``), else the
    median of the valid cells nearest to it."""
    rows, cols = z.shape
    r = rows // 2 if r is None else r
    c = cols // 2 if c is None else c
    v = float(z[r, c])
    if math.isfinite(v):
        return v, "the DEM's centre cell"
    for half in (2, 8, 32, 128):
        win = z[max(0, r - half):r + half + 1, max(0, c - half):c + half + 1]
        if np.isfinite(win).any():
            return float(np.nanmedian(win)), f"median of valid cells within {half} of the centre"
    return float(np.nanmedian(z)), "median of the DEM (its centre is a void)"


OTHER_BODY_ADVICE = ("the solar position from --time is for the Earth: give "
                     "--azimuth/--elevation")


def dem_site(dem, lat: float | None = None, lon: float | None = None,
             other_body: str | None = None) -> Site:
    """The :class:`Site` of a :class:`~hillshade_rt.io.Dem` or an ``io.DemSource`` (anything with
    ``crs``, ``transform``, ``shape``, ``path`` and ``centre_height()``). ``other_body``: what the
    error says after "not the Earth; " for a DEM on another body (default: the lighting
    commands' advice, --azimuth/--elevation)."""
    height, hnote = dem.centre_height()
    if (lat is None) != (lon is None):
        raise HillshadeError("--lat and --lon go together")
    if lat is not None:
        if not (-90.0 <= lat <= 90.0) or not math.isfinite(lon):
            raise HillshadeError(f"--lat must be within [-90, 90] and --lon finite, got {lat}, {lon}")
        lon = (lon + 180.0) % 360.0 - 180.0
        site = Site(lat, lon, height, "--lat/--lon", notes=[f"observer height: {hnote}"])
        if dem.crs is not None and dem.transform is not None:
            # the sun at the given place, one vector; still turned to the DEM's grid north
            centre = dem_site(dem, other_body=other_body)
            rows, cols = dem.shape
            site.north_offset = float(centre.convergence(np.array([(rows - 1) / 2.0]),
                                                         np.array([(cols - 1) / 2.0]))[0])
        return site
    if dem.crs is None or dem.transform is None:
        raise HillshadeError(f"{dem.path}: has no CRS, so its place on Earth is unknown; "
                             "give --lat and --lon (degrees) for a sun from --time")
    from pyproj import CRS as PCRS, Transformer

    pcrs = PCRS.from_user_input(dem.crs.to_wkt())
    ell = pcrs.ellipsoid
    if ell is not None and not (EARTH_A_RANGE[0] <= ell.semi_major_metre <= EARTH_A_RANGE[1]):
        raise HillshadeError(
            f"{dem.path}: its CRS is on {ell.name} (a = {ell.semi_major_metre / 1000:.1f} km), not "
            "the Earth; " + (other_body or OTHER_BODY_ADVICE))
    geo = pcrs.geodetic_crs
    fwd = Transformer.from_crs(pcrs, geo, always_xy=True)
    back = Transformer.from_crs(geo, pcrs, always_xy=True)
    tr = dem.transform

    def to_lonlat(rows, cols):
        rows = np.asarray(rows, np.float64)
        cols = np.asarray(cols, np.float64)
        x = tr.c + tr.a * (cols + 0.5)
        y = tr.f + tr.e * (rows + 0.5)
        lo, la = fwd.transform(x, y)
        return np.asarray(lo, np.float64), np.asarray(la, np.float64)

    def convergence(rows, cols):
        """Grid azimuth (degrees clockwise from the raster's north) of true north."""
        if pcrs.is_geographic:
            return np.zeros(np.broadcast(np.asarray(rows), np.asarray(cols)).shape)
        lo, la = to_lonlat(rows, cols)
        dlat = 1e-4 * np.where(la > 89.0, -1.0, 1.0)
        x0, y0 = back.transform(lo, la)
        x1, y1 = back.transform(lo, la + dlat)
        dx = (np.asarray(x1) - np.asarray(x0)) * np.sign(dlat)
        dy = (np.asarray(y1) - np.asarray(y0)) * np.sign(dlat)
        return np.degrees(np.arctan2(dx, dy))

    rows, cols = dem.shape
    lo, la = to_lonlat(np.array([(rows - 1) / 2.0]), np.array([(cols - 1) / 2.0]))
    if not (np.isfinite(lo[0]) and np.isfinite(la[0])):
        raise HillshadeError(f"{dem.path}: its centre does not map to a longitude/latitude")
    return Site(float(la[0]), float((lo[0] + 180.0) % 360.0 - 180.0), height,
                "the DEM's centre", to_lonlat, convergence, notes=[f"observer height: {hnote}"])


# --------------------------------------------------------------------------------------------
# the sun over a raster

@dataclass
class Region:
    """Part of a raster (row and column slices) and the sun there (grid azimuth, elevation)."""

    rows: slice
    cols: slice
    azimuth: float
    elevation: float


@dataclass
class SunOver:
    """The sun over a raster at one time: one vector (``tiles`` None) or one per tile."""

    time: _dt.datetime | None
    azimuth: float            # grid azimuth at the centre, degrees
    elevation: float          # at the centre
    true_azimuth: float | None = None
    zenith: float | None = None
    deviation_deg: float = 0.0      # largest angle between the centre's sun and any other place's
    tiles: list[Region] | None = None
    tile_deviation_deg: float = 0.0  # estimated largest deviation inside one tile
    # the SPA's n x n lattice over the raster as unit vectors (east, north, up; grid azimuth and
    # apparent elevation): each cell's own sun, interpolated (algorithms.per_cell_sun)
    lattice: np.ndarray | None = None
    field_deviation_deg: float | None = None   # interpolated vs SPA at the tile centres

    @property
    def fieldwise(self) -> bool:
        """Whether each cell may take its own sun from the lattice (``algorithms.per_cell_sun``): the
        sun varies across the raster and is up at every node, so at every cell (the
        interpolated vector is a convex combination of the nodes': it stays above the lowest
        node's elevation and within the nodes' azimuths). Where it is down somewhere (the
        terminator crosses the raster) the tiles serve."""
        return (self.tiles is not None and self.lattice is not None
                and bool(np.all(self.lattice[..., 2] > 1e-9)))

    def lattice_span(self, shape, bounds, azimuth: float) -> tuple[float, float, float]:
        """(lowest, highest grid azimuth, lowest elevation), degrees, of the suns the lattice
        gives the cells of ``bounds`` (r0, r1, c0, c1 of a raster of ``shape``): over the nodes
        of the lattice cells it covers (``fieldwise`` says why that bounds them); azimuths as
        offsets from ``azimuth``, so that they do not wrap."""
        n = self.lattice.shape[0]
        rows, cols = shape
        r0, r1, c0, c1 = bounds

        def nodes(a, b, m):
            if m <= 1 or n <= 1:
                return 0, n
            sc = (n - 1.0) / (m - 1.0)
            return max(0, min(int(a * sc), n - 2)), min(n, min(int((b - 1) * sc), n - 2) + 2)
        i0, i1 = nodes(r0, r1, rows)
        j0, j1 = nodes(c0, c1, cols)
        v = self.lattice[i0:i1, j0:j1].reshape(-1, 3)
        az = np.degrees(np.arctan2(v[:, 0], v[:, 1]))
        d = (az - azimuth + 180.0) % 360.0 - 180.0
        el = np.degrees(np.arcsin(np.clip(v[:, 2] / np.linalg.norm(v, axis=1), -1.0, 1.0)))
        return azimuth + float(d.min()), azimuth + float(d.max()), float(el.min())

    def regions(self, shape) -> list[Region]:
        if self.tiles is not None:
            return self.tiles
        return [Region(slice(0, shape[0]), slice(0, shape[1]), self.azimuth, self.elevation)]

    @property
    def night(self) -> bool:
        return all(r.elevation <= 0 for r in self.tiles) if self.tiles else self.elevation <= 0

    def as_dict(self) -> dict:
        d = {"azimuth": self.azimuth, "elevation": self.elevation}
        if self.time is not None:
            d.update(time=iso(self.time), true_azimuth=self.true_azimuth, zenith=self.zenith)
        elif self.true_azimuth is not None:     # a given sun's azimuth from true north
            d["true_azimuth"] = self.true_azimuth
        d["night"] = self.night
        d["mode"] = "per tile" if self.tiles else "one vector"
        if self.field_deviation_deg is not None:
            d["field_deviation_deg"] = self.field_deviation_deg
        d["deviation_deg"] = self.deviation_deg
        if self.tiles:
            d["tiles"] = len(self.tiles)
            d["tile_deviation_deg"] = self.tile_deviation_deg
        return d


def _vectors(az, el):
    a, e = np.radians(az), np.radians(el)
    return np.stack([np.cos(e) * np.sin(a), np.cos(e) * np.cos(a), np.sin(e)], axis=-1)


def _angle(u, v):
    return np.degrees(np.arccos(np.clip(np.sum(u * v, axis=-1), -1.0, 1.0)))


def _field_deviation(lattice, rows, cols, r, c, spa_vectors) -> float:
    """Largest angle (deg) between the interpolated sun of ``algorithms.per_cell_sun`` and the SPA's at
    the places (r, c): how well the lattice stands for the SPA between its nodes."""
    worst = 0.0
    for k in range(len(r)):
        n = lattice.shape[0]
        fi = r[k] * (n - 1.0) / max(rows - 1.0, 1.0)
        fj = c[k] * (n - 1.0) / max(cols - 1.0, 1.0)
        i0, j0 = min(int(fi), n - 2), min(int(fj), n - 2)
        ti, tj = fi - i0, fj - j0
        v = ((1 - ti) * (1 - tj) * lattice[i0, j0] + (1 - ti) * tj * lattice[i0, j0 + 1]
             + ti * (1 - tj) * lattice[i0 + 1, j0] + ti * tj * lattice[i0 + 1, j0 + 1])
        v = v / np.linalg.norm(v)
        worst = max(worst, float(_angle(v, spa_vectors[k])))   # (field.cell_ray's weights)
    return worst


def sun_over(site: Site, shape, times, atmosphere: Atmosphere = Atmosphere(),
             tolerance: float = DEFAULT_TOLERANCE, delta_t: float | None = None) -> list[SunOver]:
    """The sun over a raster of ``shape`` at each of ``times`` (aware datetimes).

    The SPA runs at the centre and on a 9 x 9 lattice of places; where the sun's direction (grid
    azimuth and apparent elevation as a unit vector) differs from the centre's by more than
    ``tolerance`` degrees, the raster is cut into tiles small enough that the direction inside one
    varies by about the tolerance, and the SPA runs again at each tile's centre."""
    rows, cols = shape
    times = list(times)
    ts = np.array([t.timestamp() for t in times])
    if site.to_lonlat is None:
        az, el, zen = solar_position(ts, site.lat, site.lon, site.height, atmosphere, delta_t)
        return [SunOver(t, float((a + site.north_offset) % 360.0), float(e), float(a), float(z))
                for t, a, e, z in zip(times, az, el, zen)]
    n = 9
    lr = np.linspace(0.0, rows - 1.0, n)
    lc = np.linspace(0.0, cols - 1.0, n)
    gr, gc = np.meshgrid(lr, lc, indexing="ij")
    lo, la = site.to_lonlat(gr.ravel(), gc.ravel())
    conv = site.convergence(gr.ravel(), gc.ravel())
    az, el, zen = solar_position(ts[:, None], la[None, :], lo[None, :], site.height, atmosphere,
                                 delta_t)
    gaz = az + conv[None, :]
    vec = _vectors(gaz, el).reshape(len(times), n, n, 3)
    mid = n // 2
    out = []
    for i, t in enumerate(times):
        centre = vec[i, mid, mid]
        dev = float(_angle(vec[i], centre).max())
        s = SunOver(t, float(gaz[i, mid * n + mid] % 360.0), float(el[i, mid * n + mid]),
                    float(az[i, mid * n + mid]), float(zen[i, mid * n + mid]), dev)
        if dev > tolerance and not (el[i] <= -2.0).all():
            # angular change per pixel along rows and columns (largest between lattice neighbours)
            per_c = float(_angle(vec[i, :, 1:], vec[i, :, :-1]).max()) / max(lc[1] - lc[0], 1e-9)
            per_r = float(_angle(vec[i, 1:, :], vec[i, :-1, :]).max()) / max(lr[1] - lr[0], 1e-9)
            nc = max(1, math.ceil(cols * per_c / tolerance))
            nr = max(1, math.ceil(rows * per_r / tolerance))
            while nr * nc > MAX_TILES:
                nr, nc = max(1, (nr + 1) // 2), max(1, (nc + 1) // 2)
            re_ = np.linspace(0, rows, nr + 1).round().astype(int)
            ce = np.linspace(0, cols, nc + 1).round().astype(int)
            tr_, tc_ = np.meshgrid((re_[:-1] + re_[1:] - 1) / 2.0, (ce[:-1] + ce[1:] - 1) / 2.0,
                                   indexing="ij")
            tlo, tla = site.to_lonlat(tr_.ravel(), tc_.ravel())
            tconv = site.convergence(tr_.ravel(), tc_.ravel())
            taz, tel, _ = solar_position(np.full(tlo.shape, ts[i]), tla, tlo, site.height,
                                         atmosphere, delta_t)
            taz = (taz + tconv) % 360.0
            s.tiles = [Region(slice(int(re_[a]), int(re_[a + 1])), slice(int(ce[b]), int(ce[b + 1])),
                              float(taz[a * nc + b]), float(tel[a * nc + b]))
                       for a in range(nr) for b in range(nc)]
            s.tile_deviation_deg = 0.5 * (per_c * cols / nc + per_r * rows / nr)
            s.lattice = np.ascontiguousarray(vec[i])
            s.field_deviation_deg = _field_deviation(s.lattice, rows, cols, tr_.ravel(),
                                                     tc_.ravel(), _vectors(taz, tel))
        out.append(s)
    return out


def disk_fraction(horizon_deg, elevation_deg, radius_deg: float = SUN_RADIUS_DEG):
    """Visible fraction (0..1) of the solar disk of angular radius ``radius_deg`` centred at
    ``elevation_deg`` above a horizon at ``horizon_deg`` (flat horizon across the disk; the
    astronomical horizon, 0 degrees, hides what is below it): the area of the disk above the line,
    (acos(d) - d sqrt(1 - d^2)) / pi with d = (horizon - elevation) / radius."""
    h = np.maximum(np.asarray(horizon_deg, np.float64), 0.0)
    d = np.clip((h - elevation_deg) / radius_deg, -1.0, 1.0)
    return (np.arccos(d) - d * np.sqrt(1.0 - d * d)) / math.pi


def _times(time, start, end, step, tz) -> list[_dt.datetime]:
    """--time's instants, or the series --start..--end every --step, local times in ``tz``."""
    if time:
        return [parse_time(t, tz, "--time") for t in time]
    t0, t1 = parse_time(start, tz, "--start"), parse_time(end, tz, "--end")
    return time_range(t0, t1, parse_step(step))


@dataclass
class SunRequest:
    """The sun options of a command line, checked before anything is read."""

    azimuth: float | None = None
    elevation: float | None = None
    times: list[_dt.datetime] = field(default_factory=list)
    tz: object = None
    lat: float | None = None
    lon: float | None = None
    atmosphere: Atmosphere = Atmosphere()
    tolerance: float = DEFAULT_TOLERANCE
    auto_tz: bool = False          # --tz auto: ``tz`` is the DEM's zone once :meth:`site` ran
    pending: tuple | None = None   # --tz auto: (time, start, end, step) parsed again then
    # a given sun's azimuth from true north, when it was given so (a STAC item's): ``azimuth``
    # is then the grid azimuth it was turned to (run.stac.to_grid_north)
    true_azimuth: float | None = None

    @property
    def from_time(self) -> bool:
        return bool(self.times)

    @classmethod
    def from_options(cls, azimuth=None, elevation=None, time=(), start=None, end=None, step=None,
                     tz=None, lat=None, lon=None, pressure=None, temperature=None,
                     no_refraction=False, sun_tolerance=DEFAULT_TOLERANCE,
                     default_sun: tuple[float, float] | None = None) -> "SunRequest":
        from .geometry import check_elevation, normalize_azimuth
        zone_ = zone(tz)
        time = tuple(time or ())
        series = start is not None or end is not None or step is not None
        explicit = azimuth is not None or elevation is not None
        if sum([bool(time), series, explicit]) > 1:
            raise HillshadeError("give the sun one way: --azimuth/--elevation, --time, or "
                                 "--start/--end/--step")
        if series and (start is None or end is None or step is None):
            raise HillshadeError("--start, --end and --step go together")
        if not (time or series or explicit):
            if default_sun is None:
                raise HillshadeError("no sun given: use --azimuth and --elevation, --time, or "
                                     "--start/--end/--step")
            azimuth, elevation = default_sun
            explicit = True
        timed_only = {"--tz": tz, "--lat": lat, "--lon": lon, "--pressure": pressure,
                      "--temperature": temperature}
        if explicit:
            if azimuth is None or elevation is None:
                raise HillshadeError("--azimuth and --elevation go together")
            given = [k for k, v in timed_only.items() if v is not None]
            if no_refraction:
                given.append("--no-refraction")
            if given:
                raise HillshadeError(f"{', '.join(given)} apply to a sun from --time or --start, "
                                     "not to --azimuth/--elevation")
            return cls(normalize_azimuth(azimuth), check_elevation(elevation, "--elevation"))
        req = cls.at_place(_times(time, start, end, step, UTC if is_auto(tz) else zone_), tz,
                           lat, lon, pressure, temperature, no_refraction, sun_tolerance)
        if req.auto_tz:   # checked now with UTC standing in; read again in the DEM's zone
            req.pending = (time, start, end, step)
        return req

    @classmethod
    def at_place(cls, times, tz=None, lat=None, lon=None, pressure=None, temperature=None,
                 no_refraction=False, sun_tolerance=DEFAULT_TOLERANCE) -> "SunRequest":
        """Suns at ``times`` (aware datetimes; may be filled in later, as sun-hours does once
        it knows the place), with the place and atmosphere options checked."""
        zone_ = zone(tz)
        if (lat is None) != (lon is None):
            raise HillshadeError("--lat and --lon go together")
        if lat is not None and not (math.isfinite(lat) and -90.0 <= lat <= 90.0):
            raise HillshadeError(f"--lat must be a latitude within [-90, 90] degrees, got {lat}")
        if lon is not None and not math.isfinite(lon):
            raise HillshadeError(f"--lon must be a finite number of degrees, got {lon}")
        if pressure is not None and not (math.isfinite(pressure) and 0 < pressure < 1200):
            raise HillshadeError(f"--pressure must be in hPa (mbar), between 0 and 1200, got {pressure}")
        if temperature is not None and not (math.isfinite(temperature) and -100 < temperature < 100):
            raise HillshadeError(f"--temperature must be in degrees Celsius, got {temperature}")
        if not (math.isfinite(sun_tolerance) and sun_tolerance > 0):
            raise HillshadeError(f"--sun-tolerance must be a positive number of degrees, got {sun_tolerance}")
        atm = Atmosphere(not no_refraction, pressure,
                         12.0 if temperature is None else float(temperature))
        return cls(times=times, tz=zone_, lat=lat, lon=lon, atmosphere=atm,
                   tolerance=float(sun_tolerance), auto_tz=is_auto(tz))

    def site(self, dem, other_body: str | None = None):
        """Where this request's suns are computed for ``dem`` (``sun.dem_site``; ``other_body``:
        what to advise for a DEM on another body than the Earth). With ``--tz auto`` the zone
        is then that of the site (:func:`zone_at`) and the times given without an offset are
        read again as local times there."""
        site = dem_site(dem, self.lat, self.lon, other_body)
        if self.auto_tz and self.tz is None:
            self.tz, name = zone_at(site.lon, site.lat)
            site.notes.append(f"--tz auto: {name}, the zone at {site.lat:.4f}, {site.lon:.4f}")
            if self.pending is not None:
                self.times = _times(*self.pending, self.tz)
        return site

    def suns(self, dem, site=None) -> tuple[list[SunOver], dict | None]:
        """(suns, site report) for ``dem``: the given sun, or the SPA's at each time (at
        ``site`` when the caller already has it)."""
        if not self.from_time:
            return [SunOver(None, self.azimuth, self.elevation,
                            true_azimuth=self.true_azimuth)], None
        site = site or self.site(dem)
        suns = sun_over(site, dem.shape, self.times, self.atmosphere, self.tolerance)
        atm = self.atmosphere
        info = {"site": site.as_dict(), "site_notes": site.notes,
                "refraction": atm.refraction,
                "pressure_hpa": atm.pressure_at(site.height) if atm.refraction else None,
                "temperature_c": atm.temperature_c if atm.refraction else None,
                "pressure_source": ("--pressure" if atm.pressure_hpa is not None
                                    else "standard atmosphere at the observer's height"),
                "solar_position": "NREL SPA (pvlib.spa, numpy)",
                "tolerance_deg": self.tolerance}
        return suns, info
