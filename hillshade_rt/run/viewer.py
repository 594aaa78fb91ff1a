"""The viewer's model (``hillshade-rt view``): a DEM read once, a
:class:`~hillshade_rt.engine.shader.Shader` prepared once per overview level (every n-th cell, n a
power of two) and algorithm, each request shading only what the page shows; the terrain brush's
edits (``Shader.update`` on every Shader), undo and reset; the queries' checks
(:class:`BadRequest`, :class:`NotFound`). The HTTP server that asks it is ``run.view_server``.

Shading and edits run on one worker thread, one request at a time (the Shaders keep state;
numba's kernels use every core anyway, and its OpenMP pool belongs to the calling thread): the
worker is the lock that keeps an edit from changing the heights under a render.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import tempfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import HillshadeError

MAX_PIXELS = 4096 * 4096          # largest picture a request may ask for
GRADIENT_CELLS = 50_000_000       # levels up to this size keep their surface gradients
MAX_EDIT_CELLS = 16_000_000       # cells one brush edit may cover (its bounding box)
LIT_RGB = np.array([1.0, 0.97, 0.88], np.float32)      # lit relief: red > blue
SHADOW_RGB = np.array([0.30, 0.42, 0.85], np.float32)  # shadow (preview.TINT): blue > red
SUN_RGB = np.array([1.0, 0.86, 0.45], np.float32)      # sun hours (preview.SUN)



class BadRequest(HillshadeError):
    """A malformed query: answered 400 with this one line."""


class NotFound(HillshadeError):
    """Nothing there: answered 404."""


# --------------------------------------------------------------------------------------------
# overview levels

def level_for(scale: float, shape: tuple[int, int]) -> int:
    """The overview level (every n-th cell, n a power of two) for ``scale`` DEM cells per
    pixel: the largest n <= scale, so that each pixel still has a cell; 1 when zoomed in."""
    n = 1
    while n * 2 <= scale and min(shape) // (n * 2) >= 2:
        n *= 2
    return n


def pixel_cells(lo: float, hi: float, n_px: int, n_cells: int, level: int):
    """For ``n_px`` pixels spanning [lo, hi) of one axis: each pixel's cell at ``level`` (index
    into every ``level``-th cell) and whether it falls inside the raster's ``n_cells``."""
    centre = lo + (np.arange(n_px) + 0.5) * ((hi - lo) / n_px)
    cell = np.floor(centre).astype(np.int64)
    inside = (cell >= 0) & (cell < n_cells)
    idx = np.where(inside, cell // level, 0)
    return idx, inside


# --------------------------------------------------------------------------------------------
# the viewer: a DEM prepared once, shaded per request

@dataclass(frozen=True)
class ViewSun:
    """The sun of a query (``Viewer.sun``): grid azimuth and elevation in degrees, the time
    (ISO 8601 in the viewer's zone; None for a sun given by ``az`` and ``el``)."""

    azimuth: float
    elevation: float
    time: str | None = None

    def as_dict(self) -> dict:
        """As the API's JSON says it (``/api/point``'s ``sun``)."""
        return asdict(self)


class Viewer:
    """A DEM in memory (``io.Dem``) ready to be shaded window by window (thread-safe). The
    brush's edits change ``dem.heights`` in place (copy the Dem first to keep it)."""

    def __init__(self, dem, algorithm: str = "auto", backend: str = "cpu",
                 tz: str | None = None, options: dict | None = None):
        from ..algorithms import lookup
        from ..model.earth import dem_body
        from ..model.site import dem_site
        from ..model.times import is_auto, zone, zone_at
        lookup(algorithm)
        self.dem = dem
        self.z = dem.heights
        self.grid = dem.grid
        self.body = dem_body(dem)
        self.algorithm, self.backend, self.options = algorithm, backend, dict(options or {})
        # every computation on one worker thread, one at a time: the Shaders keep state, and
        # numba's OpenMP pool belongs to the thread that calls a kernel (a pool per request
        # thread would be made for each and compete for the cores with the last one's)
        self._worker = ThreadPoolExecutor(1, thread_name_prefix="hillshade-rt-view")
        self._levels: dict = {}
        self._shaders: dict = {}
        self._gradients: dict = {}
        self._undo_stack: list = []     # (row, col, the heights an edit replaced)
        self.zrange = tuple(float(v) for v in dem.height_range())
        if not all(math.isfinite(v) for v in self.zrange):
            raise HillshadeError(f"{dem.path}: every cell is nodata: nothing to view")
        dx, dy = self.grid.centre_spacing()
        rows, cols = self.z.shape
        self.extent_m = math.hypot(cols * dx, rows * dy)
        try:
            self.site = dem_site(dem)
        except HillshadeError:
            self.site = None          # no CRS or not the Earth: azimuth and elevation only
        self.zone_source = None
        if tz is not None and not is_auto(tz):
            self.tz, self.zone_name, self.zone_source = zone(tz), tz, "--tz"
        elif self.site is not None:     # the zone of the DEM's centre (daylight saving too)
            self.tz, self.zone_name = zone_at(self.site.lon, self.site.lat)
            self.zone_source = "the DEM's centre"
        else:
            self.tz, self.zone_name = None, None

    def call(self, fn, *args):
        """``fn(*args)`` on the worker thread (its exceptions raised here)."""
        return self._worker.submit(fn, *args).result()

    def render(self, q: dict) -> tuple[np.ndarray, dict]:
        """The picture a render query asks for: ((h, w, 4) uint8, headers)."""
        return self.call(self._render, q)

    def point(self, q: dict) -> dict:
        """Height, lit or not and the horizon profile at (x, y) (pixel coordinates)."""
        return self.call(self._point, q)

    def download(self, q: dict) -> tuple[bytes, str]:
        """The whole DEM's mask for the query's sun at full resolution as GeoTIFF bytes."""
        return self.call(self._download, q)

    def sunpath(self, q: dict) -> dict:
        """The sun of the query's date every 10 minutes of the local day."""
        return self.call(self._sunpath, q)

    def edit(self, q: dict) -> dict:
        """Raise or lower the terrain under a brush (see :meth:`_edit`)."""
        return self.call(self._edit, q)

    def undo(self) -> dict:
        """Take the last edit back."""
        return self.call(self._undo)

    def reset(self) -> dict:
        """Take every edit back: the DEM as read."""
        return self.call(self._reset)

    def warm_up(self) -> None:
        self.call(self._warm_up)

    def close(self) -> None:
        self._worker.shutdown(wait=False, cancel_futures=True)

    # -- levels and shaders --------------------------------------------------------------------
    def level(self, n: int):
        """(heights, grid) of every ``n``-th cell (kept)."""
        from ..model.geometry import Grid
        if n == 1:
            return self.z, self.grid
        if n not in self._levels:
            z = np.ascontiguousarray(self.z[::n, ::n])
            g = self.grid
            self._levels[n] = (z, Grid(z.shape[0], z.shape[1], g.dx[::n] * n, g.dy[::n] * n,
                                       g.col_sign, g.row_sign, g.method))
        return self._levels[n]

    def shader(self, n: int, algorithm: str):
        from ..engine.shader import Shader
        key = (n, algorithm)
        if key not in self._shaders:
            z, g = self.level(n)
            self._shaders[key] = Shader(z, g, algorithm, self.options, self.backend,
                                        body=self.body, zrange=self.zrange,
                                        extent_m=self.extent_m)
        return self._shaders[key]

    def _warm_up(self) -> None:
        self.shader(1, self.algorithm).warm_up(203.7, 20.0, soft=False, incidence=True)

    # -- the sun -------------------------------------------------------------------------------
    def sun(self, q: dict) -> ViewSun:
        """The sun a query asks for: ``az`` and ``el`` (degrees), or ``time`` (ISO 8601; without
        an offset a local time in the viewer's zone) -> its ``ViewSun``. A given ``el``
        is the command line's ``--elevation``: > 0 and <= 90 (a time may put the sun below the
        horizon: night)."""
        from ..model.geometry import normalize_azimuth
        if "time" in q:
            t = self.parse_time(q["time"])
            s = self.suns([t])[0]
            return ViewSun(s.azimuth, s.elevation, t.isoformat())
        from ..model.geometry import check_elevation
        az, el = number(q, "az", 203.7), number(q, "el", 30.0)
        try:            # as the command line's --elevation: > 0 and <= 90
            el = check_elevation(el, "el")
        except HillshadeError as exc:
            raise BadRequest(str(exc)) from None
        return ViewSun(normalize_azimuth(az), el)

    def parse_time(self, text: str) -> _dt.datetime:
        from ..model.times import parse_time
        if self.site is None:
            raise BadRequest("this DEM has no place on Earth (no CRS): give az and el")
        try:
            return parse_time(text, self.tz, "time")
        except BadRequest:
            raise
        except HillshadeError as exc:
            raise BadRequest(str(exc)) from None

    def suns(self, times):
        from ..model.sun import sun_over
        return sun_over(self.site, self.z.shape, times)

    def day_times(self, day: _dt.date, step_min: int = 10):
        """Instants every ``step_min`` minutes of ``day`` in the viewer's zone."""
        t0 = _dt.datetime.combine(day, _dt.time(0), self.tz)
        return [t0 + _dt.timedelta(minutes=m) for m in range(0, 24 * 60, step_min)]

    def _sunpath(self, q: dict) -> dict:
        if self.site is None:
            raise BadRequest("this DEM has no place on Earth (no CRS): no sun path")
        day = parse_day(q.get("date", ""))
        times = self.day_times(day)
        suns = self.suns(times)
        return {"date": day.isoformat(), "zone": self.zone_name,
                "zone_label": self.zone_label(day),
                "points": [{"minutes": i * 10, "time": t.isoformat(), "azimuth": s.azimuth,
                            "elevation": s.elevation} for i, (t, s) in enumerate(zip(times, suns))]}

    def zone_label(self, day: _dt.date | None = None) -> str | None:
        """The viewer's zone with its offset at noon of ``day`` (default today), e.g.
        ``Europe/Zurich (UTC+02:00, CEST)``."""
        from ..model.times import zone_label
        if self.tz is None:
            return None
        when = (_dt.datetime.combine(day, _dt.time(12), self.tz) if day is not None else None)
        return zone_label(self.tz, self.zone_name, when)

    # -- what the page asks ----------------------------------------------------------------------
    def info(self) -> dict:
        from ..algorithms import REGISTRY
        rows, cols = self.z.shape
        tr = self.dem.transform
        now = _dt.datetime.now(self.tz) if self.tz is not None else None
        # the file's name only: the page needs no more, and a page is no place for the
        # machine's folders
        return {"name": os.path.basename(str(self.dem.path)), "rows": rows, "cols": cols,
                "crs": self.dem.crs_string() if self.dem.crs is not None else None,
                "transform": list(tr)[:6] if tr is not None else None,
                "height_range": list(self.zrange),
                "spacing_m": list(self.grid.centre_spacing()),
                "zone": self.zone_name, "zone_source": self.zone_source,
                "zone_label": self.zone_label(now.date()) if now else None,
                "has_time": self.site is not None,
                "date": now.date().isoformat() if now else None, "minutes": 10 * 60,
                "algorithm": self.algorithm, "algorithms": list(REGISTRY),
                "lat": self.site.lat if self.site else None,
                "lon": self.site.lon if self.site else None}

    def algorithm_of(self, q: dict) -> str:
        from ..algorithms import REGISTRY
        name = q.get("algorithm", self.algorithm) or self.algorithm
        if name not in REGISTRY:
            raise BadRequest(f"unknown algorithm {name!r}; known: {', '.join(REGISTRY)}")
        return name

    def _render(self, q: dict) -> tuple[np.ndarray, dict]:
        """The picture a render query asks for: ((h, w, 4) uint8, headers)."""
        rows, cols = self.z.shape
        x0, y0, x1, y1 = bbox_of(q, (0.0, 0.0, float(cols), float(rows)))
        w, h = int(number(q, "w", 512)), int(number(q, "h", 512))
        if w < 1 or h < 1 or w * h > MAX_PIXELS:
            raise BadRequest(f"w and h must be >= 1 and w*h <= {MAX_PIXELS}, got {w} x {h}")
        algorithm = self.algorithm_of(q)
        soft = flag(q, "soft")
        hours_day = parse_day(q["sunhours"]) if q.get("sunhours") else None
        sun = self.sun(q)
        n = level_for(max((x1 - x0) / w, (y1 - y0) / h), (rows, cols))
        ci, cin = pixel_cells(x0, x1, w, cols, n)
        ri, rin = pixel_cells(y0, y1, h, rows, n)
        out = np.zeros((h, w, 4), np.uint8)
        meta = {"X-Level": str(n), "X-Sun-Azimuth": repr(sun.azimuth),
                "X-Sun-Elevation": repr(sun.elevation), "X-Algorithm": algorithm,
                "X-Time": sun.time or ""}
        if not cin.any() or not rin.any():
            return out, meta                 # the window lies outside the DEM: transparent
        from ..algorithms.picture import rgba
        from ..algorithms.relief import sun_vector
        r0, r1 = int(ri[rin].min()), int(ri[rin].max()) + 1
        c0, c1 = int(ci[cin].min()), int(ci[cin].max()) + 1
        rs, cs = slice(r0, r1), slice(c0, c1)
        az, el = sun.azimuth, sun.elevation
        sh = self.shader(n, algorithm)
        stats: dict = {}
        ge, gn, g0 = self.gradients(n, rs, cs)
        is_mask = False
        if hours_day is not None:
            hours, most = self.sun_hours(sh, rs, cs, hours_day)
            meta["X-Sun-Hours-Max"] = f"{most:.2f}"
            value, v0 = (hours / most if most > 0 else np.zeros_like(hours)), (r0, c0)
            low, high = 0.25 * SUN_RGB, SUN_RGB
        else:
            value, v0 = self.part(sh, rs, cs, az, el, soft=soft, stats=stats)
            if soft:
                value = 1.0 - value
            is_mask = not soft
            low, high = LIT_RGB, SHADOW_RGB
        if algorithm == "auto" and stats.get("auto"):
            meta["X-Algorithm"] = f"auto ({','.join(stats['auto']['chose'])})"
        rgba(ge, gn, g0[0], g0[1], value, v0[0], v0[1], is_mask, np.where(rin, ri, -1),
             np.where(cin, ci, -1), *sun_vector(az, max(el, 5.0)), low.astype(np.float64),
             high.astype(np.float64), out)
        return out, meta

    def gradients(self, n: int, rs: slice, cs: slice):
        """(ge, gn, (row, col) of their first cell): the surface gradients of level ``n`` for
        rows ``rs``, columns ``cs``: the whole level's, computed once and kept when it has at
        most ``GRADIENT_CELLS`` cells (8 bytes each), else the window's."""
        from ..algorithms.picture import gradients
        z, g = self.level(n)
        whole = z.size <= GRADIENT_CELLS
        if whole and n in self._gradients:
            return self._gradients[n]
        r0, r1, c0, c1 = ((0, z.shape[0], 0, z.shape[1]) if whole
                          else (rs.start, rs.stop, cs.start, cs.stop))
        ge = np.empty((r1 - r0, c1 - c0), np.float32)
        gn = np.empty_like(ge)
        gradients(z, g.dx, g.dy, float(g.col_sign), float(g.row_sign), r0, c0, ge, gn)
        out = (ge, gn, (r0, c0))
        if whole:
            self._gradients[n] = out
        return out

    def part(self, sh, rs, cs, az: float, el: float, soft: bool = False, stats=None):
        """(the cast-shadow mask, or with ``soft`` the visible fraction of the disk, (row, col)
        of its first cell) covering rows ``rs``, columns ``cs`` of the shader's raster: the
        window alone with its halo toward the sun, or, when that halo window holds more than
        half the raster, the whole raster (its pyramid and survey kept from sun to sun) -- the
        same cells either way."""
        from ..model.solar import SUN_RADIUS_DEG
        from ..model.sun import Region
        rows, cols = sh.z.shape
        region = Region(rs, cs, az, el)
        low = el - SUN_RADIUS_DEG if soft else el      # the lowest ray the product marches
        if el > 0:
            big = low <= 0
            if not big:
                wr, wc = sh.window(region, min(low, 90.0))
                big = (wr.indices(rows)[1] - wr.indices(rows)[0]) * \
                    (wc.indices(cols)[1] - wc.indices(cols)[0]) > 0.5 * rows * cols
            if big:
                region = Region(slice(0, rows), slice(0, cols), az, el)
        out = sh.visible_fraction(region) if soft else sh.cast(region, stats)
        return out, (region.rows.start or 0, region.cols.start or 0)

    def sun_hours(self, sh, rs, cs, day: _dt.date):
        """Hours of direct sun of ``day`` (every 30 minutes) over rows ``rs``, columns ``cs``
        of the shader's level, and the most any cell could get (the sun above the horizon)."""
        if self.site is None:
            raise BadRequest("this DEM has no place on Earth (no CRS): no sun hours")
        times = self.day_times(day, 30)
        suns = self.suns([t + _dt.timedelta(minutes=15) for t in times])
        hours = np.zeros((rs.stop - rs.start, cs.stop - cs.start), np.float32)
        most = 0.0
        for s in suns:
            if s.elevation <= 0:
                continue
            most += 0.5
            m, (a, b) = self.part(sh, rs, cs, s.azimuth, s.elevation)
            hours += 0.5 * (m[rs.start - a:rs.stop - a, cs.start - b:cs.stop - b] == 0)
        return hours, most

    def _point(self, q: dict) -> dict:
        """Height, lit or not and the horizon profile at (x, y) (pixel coordinates)."""
        from ..engine.arrays import ground_height, horizon_profile
        from ..model.sun import Region
        rows, cols = self.z.shape
        x, y = number(q, "x"), number(q, "y")
        r, c = int(math.floor(y)), int(math.floor(x))
        if not (0 <= r < rows and 0 <= c < cols):
            raise NotFound(f"({x}, {y}) lies outside the DEM ({cols} x {rows} cells)")
        sun = self.sun(q)
        height = float(self.z[r, c])
        out = {"x": x, "y": y, "row": r, "col": c, "sun": sun.as_dict(),
               "height": height if math.isfinite(height) else None,
               "height_bilinear": None, "lit": None, "horizon": None}
        if not math.isfinite(height):
            return out
        hb = ground_height(self.z, min(max(y - 0.5, 0.0), rows - 1.0),
                           min(max(x - 0.5, 0.0), cols - 1.0))
        out["height_bilinear"] = hb if math.isfinite(hb) else None
        sh = self.shader(1, self.algorithm_of(q))
        m = sh.cast(Region(slice(r, r + 1), slice(c, c + 1), sun.azimuth, sun.elevation))
        out["lit"] = bool(m[0, 0] == 0)
        az, ang, _ = horizon_profile(self.dem, [float(r)], [float(c)], step=2.0)
        ang = np.asarray(ang[0], np.float64)
        toward = float(np.interp(sun.azimuth, np.append(az, 360.0),
                                 np.append(ang, ang[0])))
        out["horizon"] = {"azimuths": [float(a) for a in az],
                          "angles": [float(a) for a in ang], "toward_sun": toward}
        if self.dem.transform is not None:
            tr = self.dem.transform
            out["map_x"], out["map_y"] = tr.c + tr.a * x, tr.f + tr.e * y
        if self.site is not None and self.site.to_lonlat is not None:
            lo, la = self.site.to_lonlat(np.array([float(r)]), np.array([float(c)]))
            out["lon"], out["lat"] = float(lo[0]), float(la[0])
        return out

    # -- the terrain brush ---------------------------------------------------------------------
    def _edit(self, q: dict) -> dict:
        """Raise (``delta`` > 0) or lower the cells within ``radius`` metres of (``x``, ``y``)
        (pixel coordinates, as /api/point; or ``map_x``, ``map_y`` in the DEM's CRS; or ``lon``,
        ``lat``, WGS84 degrees): ``disk``
        adds ``delta`` to each (the ground's shape kept: an embankment), ``flat`` (flat-top) sets
        each to the centre cell's height + ``delta`` (a level roof or platform). Voids stay
        voids. The heights change in memory only (every Shader through ``Shader.update``, the
        overview levels' cells of that window recomputed), never in the DEM's file."""
        if not isinstance(q, dict):
            raise BadRequest("an edit is a JSON object: {x, y, radius, delta, shape}")
        qs = {k: str(v) for k, v in q.items() if v is not None and not isinstance(v, (dict, list))}
        rows, cols = self.z.shape
        if "map_x" in qs or "map_y" in qs or "lon" in qs or "lat" in qs:
            tr = self.dem.transform
            if tr is None or self.dem.crs is None:
                raise BadRequest("this DEM has no georeferencing: give x and y (pixels)")
            if "lon" in qs or "lat" in qs:
                mx, my = self.from_lonlat(number(qs, "lon"), number(qs, "lat"))
            else:
                mx, my = number(qs, "map_x"), number(qs, "map_y")
            x, y = ~tr @ (mx, my)
            if not (math.isfinite(x) and math.isfinite(y)):
                raise BadRequest("the point does not map to the DEM's grid")
        else:
            x, y = number(qs, "x"), number(qs, "y")
        radius, delta = number(qs, "radius"), number(qs, "delta")
        shape = qs.get("shape", "disk").strip().lower()
        if shape not in ("disk", "flat", "flat-top"):
            raise BadRequest(f"shape must be disk or flat (flat-top), got {shape!r}")
        if not 0 <= radius <= 1e6:
            raise BadRequest(f"radius must be >= 0 metres, got {radius}")
        if abs(delta) > 1e5:
            raise BadRequest(f"delta must be within +-100 km, got {delta}")
        r, c = int(math.floor(y)), int(math.floor(x))
        if not (0 <= r < rows and 0 <= c < cols):
            raise BadRequest(f"({x:g}, {y:g}) lies outside the DEM ({cols} x {rows} cells)")
        dxs, dys = float(self.grid.dx[r]), float(self.grid.dy[r])
        hr, hc = int(radius // dys), int(radius // dxs)
        r0, r1 = max(0, r - hr), min(rows, r + hr + 1)
        c0, c1 = max(0, c - hc), min(cols, c + hc + 1)
        if (r1 - r0) * (c1 - c0) > MAX_EDIT_CELLS:
            raise BadRequest(f"radius {radius:g} m covers {(r1 - r0) * (c1 - c0)} cells: at "
                             f"most {MAX_EDIT_CELLS} per edit")
        ii, jj = np.ogrid[r0 - r:r1 - r, c0 - c:c1 - c]
        inside = (ii * dys) ** 2 + (jj * dxs) ** 2 <= radius * radius
        old = self.z[r0:r1, c0:c1].copy()
        if shape == "disk":
            new = np.where(inside, old + np.float32(delta), old)
        else:
            top = self.z[r, c]
            if not math.isfinite(top):
                raise BadRequest(f"the centre cell (row {r}, col {c}) is a void: a flat top "
                                 "needs its height")
            new = np.where(inside & np.isfinite(old), np.float32(top + delta), old)
        self._apply(r0, c0, new.astype(np.float32))
        self._undo_stack.append((r0, c0, old))
        return self._edit_state({"window": [r0, r1, c0, c1], "cells": int(inside.sum()),
                                 "shape": "flat" if shape != "disk" else "disk",
                                 "delta": delta, "radius": radius})

    def from_lonlat(self, lon: float, lat: float) -> tuple[float, float]:
        """(x, y) in the DEM's CRS of a WGS84 longitude and latitude."""
        from pyproj import CRS as PCRS, Transformer
        if self.site is None:
            raise BadRequest("this DEM has no place on Earth: give x and y (pixels) or map_x "
                             "and map_y")
        t = Transformer.from_crs("EPSG:4326", PCRS.from_user_input(self.dem.crs.to_wkt()),
                                 always_xy=True)
        mx, my = t.transform(lon, lat)
        return float(mx), float(my)

    def _undo(self) -> dict:
        if not self._undo_stack:
            raise BadRequest("nothing to undo")
        r0, c0, old = self._undo_stack.pop()
        self._apply(r0, c0, old)
        h, w = old.shape
        return self._edit_state({"window": [r0, r0 + h, c0, c0 + w]})

    def _reset(self) -> dict:
        while self._undo_stack:
            r0, c0, old = self._undo_stack.pop()
            self._apply(r0, c0, old)
        return self._edit_state({})

    def _edit_state(self, extra: dict) -> dict:
        return dict(extra, edits=len(self._undo_stack), height_range=list(self.zrange))

    def _apply(self, r0: int, c0: int, heights: np.ndarray) -> None:
        """``heights`` into the DEM at (r0, c0): every full-resolution Shader updated (each sees
        the old heights go: they share the array), then every overview level's cells in that
        window taken again from the full resolution, their Shaders and gradients with them."""
        h, w = heights.shape
        r1, c1 = r0 + h, c0 + w
        old = self.z[r0:r1, c0:c1].copy()
        if not any(key[0] == 1 for key in self._shaders):
            self.shader(1, self.algorithm)
        for (n, _), sh in self._shaders.items():
            if n == 1:
                self.z[r0:r1, c0:c1] = old
                sh.update((r0, c0), heights)
        self.z[r0:r1, c0:c1] = heights
        self._regradient(1, r0, r1, c0, c1)
        for n, (zn, _) in self._levels.items():
            a0, a1 = -(-r0 // n), -(-r1 // n)          # level-n rows whose cell is in [r0, r1)
            b0, b1 = -(-c0 // n), -(-c1 // n)
            if a0 >= a1 or b0 >= b1:
                continue
            fresh = np.ascontiguousarray(self.z[a0 * n:a1 * n:n, b0 * n:b1 * n:n])
            before = zn[a0:a1, b0:b1].copy()
            shaders = [sh for (m, _), sh in self._shaders.items() if m == n]
            for sh in shaders:
                zn[a0:a1, b0:b1] = before
                sh.update((a0, b0), fresh)
            zn[a0:a1, b0:b1] = fresh
            self._regradient(n, a0, a1, b0, b1)
        sh = next(sh for (n, _), sh in self._shaders.items() if n == 1)
        self.zrange = (float(sh.zmin), float(sh.zmax))

    def _regradient(self, n: int, r0: int, r1: int, c0: int, c1: int) -> None:
        """The kept gradients of level ``n`` over rows r0..r1, columns c0..c1 (and the cells
        next to them, whose Horn normals use these heights) computed again."""
        from ..algorithms.picture import gradients
        if n not in self._gradients:
            return
        ge, gn, _ = self._gradients[n]
        z, g = self.level(n)
        r0, r1 = max(0, r0 - 1), min(z.shape[0], r1 + 1)
        c0, c1 = max(0, c0 - 1), min(z.shape[1], c1 + 1)
        a = np.empty((r1 - r0, c1 - c0), np.float32)
        b = np.empty_like(a)
        gradients(z, g.dx, g.dy, float(g.col_sign), float(g.row_sign), r0, c0, a, b)
        ge[r0:r1, c0:c1] = a
        gn[r0:r1, c0:c1] = b

    def _download(self, q: dict) -> tuple[bytes, str]:
        """The whole DEM's mask for the query's sun at full resolution as GeoTIFF bytes."""
        from ..io.raster import write_raster
        from ..engine.products import product
        from ..engine.shader import render
        from ..model.sun import SunOver
        algorithm, soft, sun = self.algorithm_of(q), flag(q, "soft"), self.sun(q)
        data = render(self.shader(1, algorithm),
                      SunOver(None, sun.azimuth, sun.elevation), "shadow", soft=soft)
        p = product("shadow", soft)
        if soft:
            data = np.where(np.isnan(data), np.float32(p.nodata), data).astype(np.float32)
        edits = len(self._undo_stack)
        name = "shadow_{}{}_az{:.1f}_el{:.1f}.tif".format(
            os.path.splitext(os.path.basename(self.dem.path))[0] or "dem",
            "_edited" if edits else "", sun.azimuth, sun.elevation)
        with tempfile.TemporaryDirectory(prefix="hillshade-rt-view-") as tmp:
            path = os.path.join(tmp, name)
            tags = {"VALUES": p.values, "AZIMUTH": f"{sun.azimuth:.4f}",
                    "ELEVATION": f"{sun.elevation:.4f}"}
            if sun.time:
                tags["TIME"] = sun.time
            if edits:     # the mask is of the terrain as edited in the viewer, not the file's
                tags["TERRAIN"] = (f"edited: {edits} brush edit(s) in hillshade-rt view "
                                   "(in memory; the DEM's file is unchanged)")
                tags["EDITS"] = json.dumps([[int(r0), int(c0), int(o.shape[0]), int(o.shape[1])]
                                            for r0, c0, o in self._undo_stack])
            write_raster(path, data, self.dem, p.nodata, p.what, tags)
            with open(path, "rb") as f:
                return f.read(), name


# --------------------------------------------------------------------------------------------
# queries

def number(q: dict, key: str, default: float | None = None) -> float:
    if key not in q:
        if default is None:
            raise BadRequest(f"missing {key}")
        return default
    try:
        v = float(q[key])
    except ValueError:
        raise BadRequest(f"{key} must be a number, got {q[key]!r}") from None
    if not math.isfinite(v):
        raise BadRequest(f"{key} must be finite, got {q[key]!r}")
    return v


def flag(q: dict, key: str) -> bool:
    v = q.get(key, "0").lower()
    if v in ("1", "true", "yes", "on"):
        return True
    if v in ("0", "false", "no", "off", ""):
        return False
    raise BadRequest(f"{key} must be 0 or 1, got {q[key]!r}")


def bbox_of(q: dict, default) -> tuple[float, float, float, float]:
    if "bbox" not in q:
        return default
    parts = q["bbox"].split(",")
    try:
        x0, y0, x1, y1 = (float(p) for p in parts)
    except ValueError:
        raise BadRequest(f"bbox must be x0,y0,x1,y1 (pixel coordinates), got {q['bbox']!r}") \
            from None
    if not all(math.isfinite(v) for v in (x0, y0, x1, y1)) or x1 <= x0 or y1 <= y0:
        raise BadRequest(f"bbox must be finite with x0 < x1 and y0 < y1, got {q['bbox']!r}")
    return x0, y0, x1, y1


def parse_day(text: str) -> _dt.date:
    try:
        return _dt.date.fromisoformat(text.strip())
    except ValueError:
        raise BadRequest(f"date must be YYYY-MM-DD, got {text!r}") from None
