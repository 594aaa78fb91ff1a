"""Times, zones and series of times: what ``--time``, ``--start/--end/--step``, ``--date`` and
``--tz`` mean.

* Times are ISO 8601 instants. A time without a UTC offset is refused unless an IANA zone is
  named (``tz``), which then also decides daylight saving; ambiguous and non-existent local times
  (the hour that repeats or is skipped when clocks change) are refused, naming the gap or the
  repeated span and, for a repeated one, the two offsets to choose from.
* Series (:func:`time_range`) and sun-hours days (:func:`day_samples`) step in elapsed time,
  computed in UTC; their times are shown in the zone with each instant's own offset.
* ``--tz auto``: the zone of a place (:func:`zone_at`, timezonefinder's polygons, imported
  lazily).
"""

from __future__ import annotations

import datetime as _dt
import math
import re

from ..errors import HillshadeError, UsageProblem

UTC = _dt.timezone.utc
# the years NREL's SPA is valid for (Reda & Andreas 2004, NREL/TP-560-34302: "for the period
# from the year -2000 to 6000"): a time the sun is computed for must lie within them
SPA_YEARS = (-2000, 6000)

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


def iso(t: _dt.datetime) -> str:
    """ISO 8601 with the offset, seconds only when needed."""
    return t.isoformat(timespec="seconds" if t.second or t.microsecond else "minutes")
