"""The sun's position from a time and a place: NREL's SPA (through pvlib), the atmosphere's
refraction, the solar disk, and sun hours' samples (the part of each interval the sun is up).

* The solar position is NREL's Solar Position Algorithm (Reda & Andreas 2004 [1]_ [2]_) as
  implemented by ``pvlib.spa`` (its numpy version) [3]_: topocentric azimuth (clockwise from true
  north) and elevation, apparent (with the SPA's refraction) unless refraction is turned off.
* Where a DEM is (:mod:`.site`) and the sun over a raster, per tile where its direction varies
  (:mod:`.sun`), build on it.

References
----------
References
----------
.. [1] I. Reda, A. Andreas, "Solar position algorithm for solar radiation applications," Solar
       Energy, vol. 76, no. 5, pp. 577-589, 2004. :doi:`10.1016/j.solener.2003.12.003`
.. [2] I. Reda, A. Andreas, "Solar Position Algorithm for Solar Radiation Applications," National
       Renewable Energy Laboratory, Technical Report NREL/TP-560-34302.
.. [3] W. F. Holmgren, C. W. Hansen, M. A. Mikofski, "pvlib python: a python package for modeling
       solar energy systems," Journal of Open Source Software, vol. 3, no. 29, p. 884, 2018.
       :doi:`10.21105/joss.00884`"""

from __future__ import annotations

import datetime as _dt
import math
from dataclasses import dataclass

import numpy as np

from ..errors import HillshadeWarning, UsageProblem
from .times import SPA_YEARS, UTC, day_samples

STANDARD_PRESSURE_HPA = 1013.25
STANDARD_TEMPERATURE_C = 12.0      # the SPA's (and pvlib's) default
ATMOS_REFRACT = 0.5667             # the SPA's refraction at sunrise/sunset, degrees
SUN_RADIUS_DEG = 0.533 / 2         # the solar disk: 0.533 degrees across
# ΔT (TT - UT) is known for -1999..3000 only (pvlib.spa extrapolates it beyond, with a warning
# this module turns into one line); the SPA itself is valid for times.SPA_YEARS
DELTA_T_YEARS = (-1999, 3000)


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
    # the times as given (T, 1) against places (1, P): the SPA's part that depends on the time
    # only runs once per time, the rest per (time, place) broadcast (_spa)
    times = np.asarray(times, np.float64)
    unix, lat, lon, h = np.broadcast_arrays(times, np.asarray(lat, np.float64),
                                            np.asarray(lon, np.float64),
                                            np.asarray(height_m, np.float64))
    shape = unix.shape
    unix, lat, lon, h = (np.ravel(a) for a in (unix, lat, lon, h))
    if times.shape != shape:        # fewer times than positions: the time's own shape
        unix = np.ravel(times)
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
    if times.shape == shape:
        zen_app, zen, el_app, el, az, _ = spa.solar_position_numpy(
            unix, lat, lon, h, pressure, float(atmosphere.temperature_c), delta_t,
            ATMOS_REFRACT, 1)
    else:
        tshape = times.shape
        zen_app, zen, el_app, el, az = _spa(
            unix, np.broadcast_to(delta_t, unix.shape).astype(np.float64), tshape, shape,
            lat.reshape(shape), lon.reshape(shape), h.reshape(shape), np.reshape(
                np.broadcast_to(pressure, h.shape), shape), float(atmosphere.temperature_c))
    if atmosphere.refraction:
        el_out, zen_out = el_app, zen_app
    else:
        el_out, zen_out = el, zen
    return (np.asarray(az, np.float64).reshape(shape), np.asarray(el_out, np.float64).reshape(shape),
            np.asarray(zen_out, np.float64).reshape(shape))



def _spa(unix, delta_t, tshape, shape, lat, lon, elev, pressure, temp):
    """``pvlib.spa.solar_position_numpy``'s steps, split: those of the time alone (the
    heliocentric series, nutation, sidereal time, the geocentric sun: most of the work) on the
    ``unix`` times (flat, of ``tshape``), the rest on the (time, place) arrays of ``shape`` they
    broadcast to. The same elementwise operations in the same order: the same bits as a call on
    the broadcast arrays (tests/model/test_solar.py), for the cost of one call per time rather
    than per (time, place). Returns (apparent zenith, zenith, apparent elevation, elevation,
    azimuth), degrees, of ``shape``."""
    from pvlib import spa
    jd = spa.julian_day(unix)
    jde = spa.julian_ephemeris_day(jd, delta_t)
    jc = spa.julian_century(jd)
    jce = spa.julian_ephemeris_century(jde)
    jme = spa.julian_ephemeris_millennium(jce)
    R = spa.heliocentric_radius_vector(jme)
    L = spa.heliocentric_longitude(jme)
    B = spa.heliocentric_latitude(jme)
    Theta = spa.geocentric_longitude(L)
    beta = spa.geocentric_latitude(B)
    x0 = spa.mean_elongation(jce)
    x1 = spa.mean_anomaly_sun(jce)
    x2 = spa.mean_anomaly_moon(jce)
    x3 = spa.moon_argument_latitude(jce)
    x4 = spa.moon_ascending_longitude(jce)
    l_o_nutation = np.empty((2, len(x0)))
    spa.longitude_obliquity_nutation(jce, x0, x1, x2, x3, x4, l_o_nutation)
    delta_psi = l_o_nutation[0]
    delta_epsilon = l_o_nutation[1]
    epsilon0 = spa.mean_ecliptic_obliquity(jme)
    epsilon = spa.true_ecliptic_obliquity(epsilon0, delta_epsilon)
    delta_tau = spa.aberration_correction(R)
    lamd = spa.apparent_sun_longitude(Theta, delta_psi, delta_tau)
    v0 = spa.mean_sidereal_time(jd, jc)
    v = spa.apparent_sidereal_time(v0, delta_psi, epsilon)
    alpha = spa.geocentric_sun_right_ascension(lamd, epsilon, beta)
    delta = spa.geocentric_sun_declination(lamd, epsilon, beta)
    xi = spa.equatorial_horizontal_parallax(R)

    def each(a):
        return np.broadcast_to(np.reshape(a, tshape), shape)
    v, alpha, delta, xi = each(v), each(alpha), each(delta), each(xi)
    H = spa.local_hour_angle(v, lon, alpha)
    u = spa.uterm(lat)
    x = spa.xterm(u, lat, elev)
    y = spa.yterm(u, lat, elev)
    delta_alpha = spa.parallax_sun_right_ascension(x, xi, H, delta)
    delta_prime = spa.topocentric_sun_declination(delta, x, y, xi, delta_alpha, H)
    H_prime = spa.topocentric_local_hour_angle(H, delta_alpha)
    e0 = spa.topocentric_elevation_angle_without_atmosphere(lat, delta_prime, H_prime)
    delta_e = spa.atmospheric_refraction_correction(pressure, temp, e0, ATMOS_REFRACT)
    e = spa.topocentric_elevation_angle(e0, delta_e)
    theta = spa.topocentric_zenith_angle(e)
    theta0 = spa.topocentric_zenith_angle(e0)
    gamma = spa.topocentric_astronomers_azimuth(H_prime, delta_prime, lat)
    phi = spa.topocentric_azimuth_angle(gamma)
    return (np.ravel(theta), np.ravel(theta0), np.ravel(e), np.ravel(e0), np.ravel(phi))


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

def disk_fraction(horizon_deg, elevation_deg, radius_deg: float = SUN_RADIUS_DEG):
    """Visible fraction (0..1) of the solar disk of angular radius ``radius_deg`` centred at
    ``elevation_deg`` above a horizon at ``horizon_deg`` (flat horizon across the disk; the
    astronomical horizon, 0 degrees, hides what is below it): the area of the disk above the line,
    (acos(d) - d sqrt(1 - d^2)) / pi with d = (horizon - elevation) / radius."""
    h = np.maximum(np.asarray(horizon_deg, np.float64), 0.0)
    d = np.clip((h - elevation_deg) / radius_deg, -1.0, 1.0)
    return (np.arccos(d) - d * np.sqrt(1.0 - d * d)) / math.pi
