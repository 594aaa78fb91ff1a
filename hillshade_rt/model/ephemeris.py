"""Subsolar series: where the sun stands over a body at each time, read from a
file the user made with an ephemeris (no ephemeris is bundled; docs/subsolar.md says how to get a
table from JPL Horizons).

Two layouts are read:

- **a plain CSV**: a header row naming ``time``, ``lat`` and ``lon`` (or ``latitude``,
  ``longitude``; ``subsolar_lat`` ... too), optionally ``distance_m`` (the sun's distance from
  the body's centre in metres; ``distance`` alone means metres too) or ``distance_au``, then
  one row per time (ISO 8601 with a UTC offset or ``Z``), strictly increasing. Latitudes are
  planetocentric = planetographic on a sphere, longitudes east-positive in degrees (any range:
  they are wrapped). Lines starting with ``#`` are comments.
- **a JPL Horizons observer table saved as CSV** (``CSV_FORMAT=YES``) with the body as the
  target and quantity 15 (the sub-solar point: ``Sl-lon``/``Sl-lat`` columns, planetodetic,
  in the sense of the target's cartographic system) and optionally quantity 19 (``r``: the
  heliocentric range in au). Recognised by its ``$$SOE`` / ``$$EOE`` markers; the times are UT
  (``2026-Jan-01 00:00``); the longitude convention is taken from the header's
  ``Target pole/equ`` line (``{East-longitude positive}`` or ``West-...``).

Anything else is a one-line error naming the file, the line and what is wrong: missing columns,
times not increasing, a latitude outside +-90, a distance that is not positive."""

from __future__ import annotations

import csv
import datetime as _dt
import math
import os
import re
from dataclasses import dataclass

import numpy as np

from ..errors import HillshadeError

AU_M = 149597870700.0

_LAT = ("lat", "latitude", "subsolar_lat", "sub_lat", "sl-lat")
_LON = ("lon", "longitude", "subsolar_lon", "sub_lon", "sl-lon")


@dataclass(frozen=True)
class SubsolarSeries:
    """``unix`` (seconds, strictly increasing), ``lat``/``lon`` (degrees; lon east-positive,
    wrapped into [-180, 180)), ``distance`` (metres from the body's centre, or None when the
    file gave none: the body's mean distance applies), ``path``."""

    unix: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    distance: np.ndarray | None
    path: str

    def __len__(self) -> int:
        return int(self.unix.size)

    def times(self) -> list:
        """The times as aware UTC datetimes."""
        return [_dt.datetime.fromtimestamp(float(u), _dt.timezone.utc) for u in self.unix]

    def durations_h(self) -> np.ndarray:
        """Hours each sample stands for: the interval to the next sample (the last sample:
        the one before it; a single sample: 0)."""
        if self.unix.size < 2:
            return np.zeros(self.unix.size)
        d = np.diff(self.unix) / 3600.0
        return np.append(d, d[-1])


def subsolar_point(lat: float, lon: float, what: str = "--subsolar") -> tuple[float, float]:
    """(lat, lon) checked: finite, |lat| <= 90; lon wrapped into [-180, 180)."""
    lat, lon = float(lat), float(lon)
    if not (math.isfinite(lat) and math.isfinite(lon)):
        raise HillshadeError(f"{what}: latitude and longitude must be finite numbers")
    if abs(lat) > 90.0:
        raise HillshadeError(f"{what}: latitude {lat:g} is outside -90..90 degrees")
    return lat, ((lon + 180.0) % 360.0) - 180.0


def _read_lines(path: str) -> list[str]:
    try:
        with open(path, newline="", encoding="utf-8-sig") as fh:
            return fh.read().splitlines()
    except FileNotFoundError:
        raise HillshadeError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise HillshadeError(f"{path}: is a directory, not a CSV file") from None
    except UnicodeDecodeError:
        raise HillshadeError(f"{path}: not a text (CSV) file") from None
    except OSError as exc:
        raise HillshadeError(f"{path}: cannot be read ({exc.strerror or exc})") from None


def read_subsolar(path: str) -> SubsolarSeries:
    """The subsolar series of ``path`` (a plain CSV or a Horizons table, see the module)."""
    lines = _read_lines(path)
    if any(ln.strip() == "$$SOE" for ln in lines):
        return _horizons(path, lines)
    return _plain(path, lines)


def _column(cols: list[str], names: tuple) -> int | None:
    for i, c in enumerate(cols):
        if c in names:
            return i
    return None


def _finite(text: str, where: str, what: str) -> float:
    try:
        v = float(text.strip())
    except ValueError:
        v = math.nan
    if not math.isfinite(v):
        raise HillshadeError(f"{where}: {what} {text.strip()!r} is not a number")
    return v


def _plain(path: str, lines: list[str]) -> SubsolarSeries:
    from .times import parse_time
    name = os.path.basename(path)
    rows = [(i + 1, r) for i, r in enumerate(csv.reader(lines))
            if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
    if not rows:
        raise HillshadeError(f"{path}: empty (a header row naming time, lat, lon and optionally "
                             "distance_m, then one row per time)")
    head_line, head = rows[0]
    cols = [c.strip().lower() for c in head]
    at = {"time": _column(cols, ("time", "utc", "date")), "lat": _column(cols, _LAT),
          "lon": _column(cols, _LON)}
    missing = [k for k, v in at.items() if v is None]
    if missing:
        raise HillshadeError(f"{path}: no {', '.join(missing)} column in its header (line "
                             f"{head_line}: {', '.join(c.strip() for c in head)}); the columns "
                             "are time, lat, lon and optionally distance_m or distance_au")
    dist_m = _column(cols, ("distance_m", "distance"))
    dist_au = _column(cols, ("distance_au", "r_au"))
    if dist_m is not None and dist_au is not None:
        raise HillshadeError(f"{path}: give the distance once (distance_m or distance_au)")
    unix, lat, lon, dist = [], [], [], []
    for n, r in rows[1:]:
        where = f"{name} line {n}"
        if len(r) < len(cols):
            raise HillshadeError(f"{where}: {len(r)} fields, the header has {len(cols)}")
        try:
            t = parse_time(r[at["time"]], None, f"{where}: time", spa=False)
        except HillshadeError as exc:
            msg = str(exc)
            raise HillshadeError(msg if msg.startswith(where) else f"{where}: {msg}") from None
        unix.append(t.timestamp())
        la, lo = subsolar_point(_finite(r[at["lat"]], where, "lat"),
                                _finite(r[at["lon"]], where, "lon"), where)
        lat.append(la)
        lon.append(lo)
        if dist_m is not None or dist_au is not None:
            d = _finite(r[dist_m if dist_m is not None else dist_au], where, "distance")
            d = d if dist_m is not None else d * AU_M
            if d <= 0:
                raise HillshadeError(f"{where}: the distance must be positive")
            dist.append(d)
    return _series(path, unix, lat, lon, dist if dist else None)


def _series(path, unix, lat, lon, dist) -> SubsolarSeries:
    if not unix:
        raise HillshadeError(f"{path}: no rows after the header")
    u = np.array(unix, np.float64)
    steps = np.diff(u)
    if (steps <= 0).any():
        k = int(np.argmax(steps <= 0))
        raise HillshadeError(f"{path}: times must increase, but row {k + 2} is not after row "
                             f"{k + 1}")
    return SubsolarSeries(u, np.array(lat, np.float64), np.array(lon, np.float64),
                          None if dist is None else np.array(dist, np.float64), path)


_HORIZONS_TIME = ("%Y-%b-%d %H:%M:%S.%f", "%Y-%b-%d %H:%M:%S", "%Y-%b-%d %H:%M", "%Y-%b-%d %H",
                  "%Y-%m-%d %H:%M:%S.%f", "%Y-%m-%d %H:%M:%S", "%Y-%m-%d %H:%M")


def _horizons_time(text: str, where: str) -> float:
    s = text.strip()
    s = re.sub(r"^(A\.D\.|b\.c\.)\s*", "", s, flags=re.I)
    for fmt in _HORIZONS_TIME:
        try:
            return _dt.datetime.strptime(s, fmt).replace(tzinfo=_dt.timezone.utc).timestamp()
        except ValueError:
            pass
    raise HillshadeError(f"{where}: time {s!r} is not a Horizons calendar time (e.g. "
                         "2026-Jan-01 00:00; ask for TIME_TYPE=UT and CAL format)")


def _horizons(path: str, lines: list[str]) -> SubsolarSeries:
    name = os.path.basename(path)
    soe = next(i for i, ln in enumerate(lines) if ln.strip() == "$$SOE")
    try:
        eoe = next(i for i in range(soe + 1, len(lines)) if lines[i].strip() == "$$EOE")
    except StopIteration:
        raise HillshadeError(f"{path}: a Horizons table without its $$EOE line (cut short?)") \
            from None
    head_i = next((i for i in range(soe - 1, -1, -1)
                   if lines[i].strip() and not set(lines[i].strip()) <= {"*"}), None)
    if head_i is None:
        raise HillshadeError(f"{path}: no column header above $$SOE")
    cols = [c.strip().lower() for c in next(csv.reader([lines[head_i]]))]
    t_col = next((i for i, c in enumerate(cols) if c.startswith("date")), None)
    lon_col, lat_col = _column(cols, ("sl-lon",)), _column(cols, ("sl-lat",))
    if t_col is None or lon_col is None or lat_col is None:
        raise HillshadeError(f"{path}: a Horizons table needs the CSV format with the date and "
                             "the sub-solar point (quantity 15: Sl-lon, Sl-lat columns); its "
                             f"header has {', '.join(c for c in cols if c)}")
    r_col = _column(cols, ("r",))
    west = any("target pole/equ" in ln.lower() and "west-longitude" in ln.lower()
               for ln in lines[:soe])
    unix, lat, lon, dist = [], [], [], []
    for n in range(soe + 1, eoe):
        if not lines[n].strip():
            continue
        r = next(csv.reader([lines[n]]))
        where = f"{name} line {n + 1}"
        if len(r) <= max(t_col, lon_col, lat_col, r_col or 0):
            raise HillshadeError(f"{where}: {len(r)} fields, fewer than its header's")
        unix.append(_horizons_time(r[t_col], where))
        lo = _finite(r[lon_col], where, "Sl-lon")
        la, lo = subsolar_point(_finite(r[lat_col], where, "Sl-lat"), -lo if west else lo, where)
        lat.append(la)
        lon.append(lo)
        if r_col is not None:
            d = _finite(r[r_col], where, "r") * AU_M
            if d <= 0:
                raise HillshadeError(f"{where}: the distance must be positive")
            dist.append(d)
    return _series(path, unix, lat, lon, dist if dist else None)
