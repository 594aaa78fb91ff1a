"""The sun over a DEM: one vector, or per tile where its direction differs across the raster by
more than a tolerance (:func:`sun_over`), and :class:`SunRequest`, the sun options checked.

A DEM's sun is computed by the SPA (:mod:`.solar`) at its centre (:mod:`.site`), converted from
true north to the raster's grid north (meridian convergence of its projection), and, where the
direction differs across the raster by more than a tolerance, per tile; the SPA's lattice over
the raster also gives each cell its own sun (``algorithms.per_cell_sun``).
"""

from __future__ import annotations

import datetime as _dt
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import HillshadeError
from .site import Site, dem_site
from .solar import Atmosphere, solar_position
from .times import UTC, is_auto, iso, parse_step, parse_time, time_range, zone, zone_at

DEFAULT_TOLERANCE = 0.05           # degrees: above this the sun is computed per tile
MAX_TILES = 4096


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
    # interpolated vs SPA at the tile centres (``field_deviation_deg``), worked out when first
    # asked (a report's): the arguments of ``_field_deviation`` until then
    _field_deviation: float | None = field(default=None, repr=False)
    _field_inputs: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def field_deviation_deg(self) -> float | None:
        """Largest angle (deg) between the lattice's interpolated sun and the SPA's at the
        tile centres (None: no lattice)."""
        if self._field_deviation is None and self._field_inputs is not None:
            lattice, rows, cols, r, c, taz, tel = self._field_inputs
            self._field_deviation = _field_deviation(lattice, rows, cols, r, c,
                                                     _vectors(taz, tel))
            self._field_inputs = None
        return self._field_deviation

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
    out, tiled = [], []
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
            tiled.append((i, s, per_c, per_r, nr, nc, re_, ce, tr_, tc_, tlo, tla, tconv))
        out.append(s)
    if not tiled:
        return out
    # the SPA at every tile centre of every time, in one call (elementwise: each value the
    # bits of a call per time)
    taz_all, tel_all, _ = solar_position(
        np.concatenate([np.full(x[10].shape, ts[x[0]]) for x in tiled]),
        np.concatenate([x[11] for x in tiled]), np.concatenate([x[10] for x in tiled]),
        site.height, atmosphere, delta_t)
    at = 0
    for i, s, per_c, per_r, nr, nc, re_, ce, tr_, tc_, tlo, tla, tconv in tiled:
        taz, tel = taz_all[at:at + tlo.size], tel_all[at:at + tlo.size]
        at += tlo.size
        taz = (taz + tconv) % 360.0
        rs = [slice(a, b) for a, b in zip(re_[:-1].tolist(), re_[1:].tolist())]
        cs = [slice(a, b) for a, b in zip(ce[:-1].tolist(), ce[1:].tolist())]
        az_l, el_l = taz.tolist(), tel.tolist()
        s.tiles = [Region(rs[a], cs[b], az_l[a * nc + b], el_l[a * nc + b])
                   for a in range(nr) for b in range(nc)]
        s.tile_deviation_deg = 0.5 * (per_c * cols / nc + per_r * rows / nr)
        s.lattice = np.ascontiguousarray(vec[i])
        s._field_inputs = (s.lattice, rows, cols, tr_.ravel(), tc_.ravel(), taz, tel)
    return out


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
        """Where this request's suns are computed for ``dem`` (``site.dem_site``; ``other_body``:
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
