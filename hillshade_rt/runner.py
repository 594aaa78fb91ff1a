"""What the ``shadow``, ``hillshade`` and ``sun-hours`` commands share: which suns a run asks for,
and the loop that lights one prepared DEM with each of them and writes the results.

Suns come from ``--azimuth/--elevation`` (one, given) or from times (``--time`` repeated, or
``--start/--end/--step``) at the DEM's place (``sun.dem_site``). Outputs: one GeoTIFF (one band per
time, band descriptions carrying the ISO times) or one file per time from ``--output-pattern``.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
import string
from dataclasses import dataclass, field

import numpy as np

from .errors import HillshadeError
from .sun import (DEFAULT_TOLERANCE, Atmosphere, SunOver, dem_site, iso, parse_step, parse_time,
                  sun_over, time_range, zone)


def tile_name(path: str) -> str:
    """``{tile}`` of an input: its file name without the extension; for an archive member given
    the rasterio way (``zip://t.zip!n46/e007.tif``) the member's (``e007``)."""
    if "://" in path and "!" in path:
        path = path.rsplit("!", 1)[1]
    return os.path.splitext(os.path.basename(path.rstrip("/")))[0]


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
        if time:
            times = [parse_time(t, zone_, "--time") for t in time]
        else:
            t0, t1 = parse_time(start, zone_, "--start"), parse_time(end, zone_, "--end")
            times = time_range(t0, t1, parse_step(step))
        return cls.at_place(times, tz, lat, lon, pressure, temperature, no_refraction,
                            sun_tolerance)

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
                   tolerance=float(sun_tolerance))

    def site(self, dem, other_body: str | None = None):
        """Where this request's suns are computed for ``dem`` (``sun.dem_site``; ``other_body``:
        what to advise for a DEM on another body than the Earth)."""
        return dem_site(dem, self.lat, self.lon, other_body)

    def suns(self, dem, site=None) -> tuple[list[SunOver], dict | None]:
        """(suns, site report) for ``dem``: the given sun, or the SPA's at each time (at
        ``site`` when the caller already has it)."""
        if not self.from_time:
            return [SunOver(None, self.azimuth, self.elevation)], None
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


class OutputPattern:
    """``--output-pattern 'out_{time:%Y%m%dT%H%M}.tif'``: one file per time. Fields: ``time``
    (an aware datetime in the zone of the times, with each instant's own offset: ``%z`` tells
    apart the hour repeated when clocks go back), ``index`` (0-based), ``azimuth``,
    ``elevation``, and ``tile``: the input DEM's file name without its extension; with several
    input tiles shaded as one mosaic, a pattern with ``{tile}`` gives one output per input tile
    (cut from the mosaic, on the tile's grid)."""

    FIELDS = ("time", "index", "azimuth", "elevation", "tile")

    def __init__(self, pattern: str):
        self.pattern = pattern
        try:
            fields = {f for _, f, _, _ in string.Formatter().parse(pattern) if f is not None}
        except ValueError as exc:
            raise HillshadeError(f"--output-pattern {pattern!r}: {exc}") from None
        names = {f.split(".")[0].split("[")[0] for f in fields}
        bad = names - set(self.FIELDS)
        if bad:
            raise HillshadeError(f"--output-pattern {pattern!r}: unknown field(s) "
                                 f"{', '.join(sorted(bad))} (use {', '.join(self.FIELDS)})")
        self.per_tile = "tile" in names
        self.planned: list[str] = []    # the files of the last ``paths``, as the pattern names them

    def paths(self, suns: list[SunOver], tiles: list[str] | None = None) -> list[list[str]]:
        """The files of each sun: one per name in ``tiles`` (the inputs' file names) when the
        pattern has ``{tile}``, else one."""
        import os
        names = [tile_name(t) for t in (tiles or [""])]
        if not self.per_tile:
            names = names[:1]
        out = []
        for i, s in enumerate(suns):
            try:
                out.append([self.pattern.format(time=s.time, index=i, azimuth=s.azimuth,
                                                elevation=s.elevation, tile=n) for n in names])
            except (ValueError, KeyError, AttributeError, IndexError, TypeError) as exc:
                raise HillshadeError(f"--output-pattern {self.pattern!r}: {exc}") from None
        if len(set(names)) != len(names):
            twins = sorted({t for t, n in zip(tiles, names) if names.count(n) > 1})
            raise HillshadeError(f"--output-pattern {self.pattern!r}: input tiles {twins[0]} and "
                                 f"{twins[1]} have the same file name, so {{tile}} cannot tell "
                                 "their outputs apart: rename one")
        flat = [p for ps in out for p in ps]
        if len(set(flat)) != len(flat):
            seen: dict = {}
            for s, ps in zip(suns, out):
                for p in ps:
                    seen.setdefault(p, []).append(s.time)
            twice = next(ts for ts in seen.values() if len(ts) > 1)
            if all(t is not None for t in twice) and \
                    twice[0].replace(tzinfo=None) == twice[1].replace(tzinfo=None):
                # the same local clock time twice: the hour repeated when the clocks go back
                raise HillshadeError(
                    f"--output-pattern {self.pattern!r} gives {iso(twice[0])} and "
                    f"{iso(twice[1])} (the same clock time, before and after the clocks go back) "
                    "the same file name: add the offset (e.g. {time:%Y%m%dT%H%M%z}) or {index}")
            raise HillshadeError(f"--output-pattern {self.pattern!r} gives two times the same file "
                                 "name: add a finer time field (e.g. {time:%Y%m%dT%H%M%S%z}) or "
                                 "{index}")
        self.planned = flat
        return out


def sun_tags(sun: SunOver) -> dict:
    tags = {"SUN_AZIMUTH": f"{sun.azimuth:.6f}", "SUN_ELEVATION": f"{sun.elevation:.6f}",
            "NIGHT": "yes" if sun.night else "no"}
    if sun.time is not None:
        tags["TIME"] = iso(sun.time)
    if sun.tiles:
        tags["SUN_MODE"] = f"per tile ({len(sun.tiles)} tiles)"
    return tags


def label(sun: SunOver) -> str:
    if sun.time is not None:
        return iso(sun.time)
    return f"sun az {sun.azimuth:g} el {sun.elevation:g}"


def progress(items, quiet: bool, desc: str, unit: str = "time"):
    """A tqdm bar on stderr over ``items`` (off with ``quiet``, and when stderr is no terminal)."""
    from tqdm import tqdm
    items = list(items)
    return tqdm(items, desc=desc, unit=unit, disable=True if quiet or len(items) < 2 else None,
                leave=False)
