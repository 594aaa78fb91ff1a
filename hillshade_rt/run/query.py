"""The ``query`` run: is the sun up and unblocked at these points, at these times? For each point
and each sun, whether it is lit, the sun's azimuth and elevation, the horizon toward the sun's
azimuth, the margin between them, the observer's height; with ``irradiance`` the clear-sky direct
beam there.

* **Points**: as ``profile`` takes them (``run.points``): ``--at LON,LAT``, ``--at-xy X,Y``,
  ``--points`` CSV or GeoJSON; the observer stands ``height_above_ground`` metres above the
  terrain interpolated bilinearly at the point. A point outside the DEM's cell centres or on
  nodata is an error (one line, nothing written).
* **Suns**: given (``--azimuth/--elevation``: the same for every point), or from times
  (``--time``, ``--start/--end/--step``) at the DEM's place exactly as ``shadow --time`` computes
  them: the SPA at the DEM's centre, or where the direction varies across the DEM, on its 9 x 9
  lattice interpolated at the point (the sun the shadow mask gives that cell) or its tile's.
* **Lit**: the exact horizon of the point toward the sun's azimuth (the model's march from the
  point: ``arrays.sun_at_points``, with Earth curvature decided as the shadow mask decides it)
  against the sun's elevation: lit iff the sun is up and horizon <= elevation (margin >= 0: a ray
  that grazes the terrain is lit, as in the mask). At a cell centre with no height above the
  ground this is the shadow mask's value of that cell (tests).
* **Irradiance** (``--irradiance``, suns from times): pvlib's clear-sky model of Ineichen and
  Perez (Linke turbidity from pvlib's monthly climatology, at the point's place and the
  observer's altitude): ``dni_w_m2`` the direct normal irradiance, ``beam_horizontal_w_m2`` =
  DNI x sin(elevation) x lit, the direct beam on a horizontal surface at the observer (no
  diffuse part).

Formats (``FORMATS``): ``csv`` (one row per point and sun, the conventions in ``#`` lines
above the header), ``json`` (the same rows, with the conventions and the DEM), ``geojson`` (one
Point feature per point, its series as properties).
"""

from __future__ import annotations

import csv
import io as _io
import json
import math
import os
from dataclasses import dataclass

import numpy as np

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import QueryConfig
from .points import gather, locate, on_ground, write_text
from .runner import RunContext

FORMATS = ("csv", "json", "geojson")
CONVENTION = ("sun_azimuth_deg: degrees clockwise from the DEM's grid north (sun_true_azimuth_deg: "
              "from true north, suns from times); sun_elevation_deg: degrees above the "
              "horizontal (apparent, refracted, for suns from times unless --no-refraction); "
              "horizon_deg: elevation of the terrain toward the sun's azimuth seen from the "
              "observer, degrees (-90: no terrain ahead inside the DEM; negative: the observer "
              "looks down), horizon_distance_m: ground metres to it; margin_deg = sun elevation - "
              "horizon; lit (1/0; true/false in JSON) iff the sun is up and margin_deg >= 0 (a ray "
              "that grazes the terrain is lit, as in the shadow mask); observer_m = ground_m "
              "(bilinear between the cell centres) + height above ground; times in the zone of "
              "--tz, else as given")
IRRADIANCE = ("dni_w_m2: clear-sky direct normal irradiance (W/m2; pvlib ineichen, Linke "
              "turbidity from pvlib's monthly climatology, at the point and the observer's "
              "altitude); beam_horizontal_w_m2 = dni_w_m2 x sin(sun elevation) x lit: the direct "
              "beam on a horizontal surface at the observer (no diffuse part)")
COLUMNS = ("point", "x", "y", "lon", "lat", "time", "sun_azimuth_deg", "sun_true_azimuth_deg",
           "sun_elevation_deg", "horizon_deg", "horizon_distance_m", "margin_deg", "lit",
           "ground_m", "observer_m")
IRRADIANCE_COLUMNS = ("dni_w_m2", "beam_horizontal_w_m2")
LIGHT_CONVENTION = ("a point light (--light-position/--light-lonlat) instead of the sun: "
                    "light_azimuth_deg: degrees clockwise from the DEM's grid north toward the "
                    "light; light_elevation_deg: degrees above the horizontal seen from the "
                    "observer; light_distance_m: straight-line metres from the observer to the "
                    "light (the ground spacing of the point's row); incidence_cos: cos of the "
                    "light's incidence on the surface of the point's nearest cell (its Horn "
                    "normal, as hillshade's; <= 0: the surface faces away); lit (1/0; "
                    "true/false in JSON) iff no terrain is strictly above the straight line "
                    "from the observer to the light (as in shadow --light-position's mask; at a "
                    "cell centre that mask's value); observer_m = ground_m (bilinear between "
                    "the cell centres) + height above ground")
LIGHT_COLUMNS = ("point", "x", "y", "lon", "lat", "light_azimuth_deg", "light_elevation_deg",
                 "light_distance_m", "incidence_cos", "lit", "ground_m", "observer_m")


def output_format(fmt: str | None, output: str | None) -> str:
    """``fmt``, or the format of ``output``'s extension (.json, .geojson), else csv."""
    if fmt is None:
        ext = os.path.splitext(output or "")[1].lower()
        fmt = {".json": "json", ".geojson": "geojson"}.get(ext, "csv")
    if fmt not in FORMATS:
        raise UsageProblem(f"--format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    return fmt


def sun_at(sun, shape, row: float, col: float) -> tuple[float, float]:
    """(grid azimuth, elevation) in degrees of ``sun`` (a ``sun.SunOver``) at (row, col) of a
    raster of ``shape``: what the shadow mask gives that cell. Per cell (``fieldwise``): the
    lattice's unit vectors interpolated there as ``algorithms.per_cell_sun`` interpolates them; per
    tile: the tile's; else the one vector."""
    if sun.fieldwise:
        from ..algorithms.per_cell_sun import lattice_at, lattice_scale
        n = sun.lattice.shape[0]
        e, no, up = lattice_at(float(row), float(col), lattice_scale(n, shape[0]),
                               lattice_scale(n, shape[1]), sun.lattice)
        return (math.degrees(math.atan2(e, no)) % 360.0,
                math.degrees(math.atan2(up, math.hypot(e, no))))
    if sun.tiles:
        r, c = int(round(row)), int(round(col))
        for t in sun.tiles:
            if t.rows.start <= r < t.rows.stop and t.cols.start <= c < t.cols.stop:
                return t.azimuth, t.elevation
    return sun.azimuth, sun.elevation


@dataclass
class SunsAt:
    """The suns of a query at its points: the suns (``sun.SunOver``), what the report says of
    them (site, refraction; None for suns given), the site (None for suns given), and each
    point's (grid azimuth, elevation) of each sun (points x suns, degrees: what the shadow
    mask gives the point's cell)."""

    suns: list
    info: dict | None
    site: object
    azimuth: np.ndarray
    elevation: np.ndarray


def query(cfg: QueryConfig) -> dict:
    """Answer ``cfg`` and write it; returns the document (what ``json`` writes). Bad input
    raises ``HillshadeError`` (``UsageProblem`` for a bad command line) before anything is
    written."""
    if cfg.light_position is not None or cfg.light_lonlat is not None:
        return light_query(cfg)
    from .config import check_lift
    fmt = output_format(cfg.fmt, cfg.output)
    check_lift(cfg.height_above_ground, "brute", False)
    lift = float(cfg.height_above_ground)
    req, scene = _sun_request(cfg)
    points = gather(cfg.at, cfg.at_xy, cfg.points)
    ctx = _start(cfg, [cfg.sun["sun_from_stac"]] if cfg.sun.get("sun_from_stac") else [])
    with ctx.timer("read"):
        d = cfg.read.read(cfg.dem)
    with ctx.timer("prepare"):
        if scene is not None:
            from .stac import to_grid_north
            req = to_grid_north(req, scene, d)      # an item's azimuth is from true north
        points = _place(points, d, lift, fmt)
        at = _suns_at(req, d, points)
    with ctx.timer("compute"):
        res = _march(cfg, req, d, points, at, lift)
        irr = (irradiance(points, at.site, [s.time for s in at.suns], res) if cfg.irradiance
               else None)
        out_rows = _rows(points, at, res, _true_azimuth(at, points, res), irr)
    doc = {"dem": os.path.abspath(d.path) if os.path.exists(d.path) else d.path,
           "crs": d.crs_string(), "convention": CONVENTION,
           "height_above_ground_m": lift, "earth_curvature": bool(res["curved"].any()),
           "sun_source": "time" if req.from_time else "given",
           "sun_from_stac": scene.as_dict() if scene is not None else None,
           "irradiance": IRRADIANCE if irr is not None else None,
           "points": len(points), "suns": len(at.suns), "version": __version__,
           "rows": out_rows}
    if at.info is not None:
        doc["site"] = at.info["site"]
        doc["refraction"] = at.info["refraction"]
    with ctx.timer("write"):
        write_text(cfg.output, render(doc, fmt), cfg.run.overwrite)
    n, m = len(points), len(at.suns)
    lit = sum(r["lit"] for r in out_rows)
    ctx.finish(_report(cfg, d, ctx, doc, fmt, lit, [s.time for s in at.suns]),
               [("summary", None if cfg.output is None else
                 f"hillshade-rt: {cfg.output}: {n} point(s) x {m} sun(s), "
                 f"{lit} of {n * m} lit ({fmt})")])
    return doc


def _report(cfg: QueryConfig, d, ctx: RunContext, doc: dict, fmt: str, lit: int,
            times=()) -> dict:
    """The run's report (``--report``): the document (its keys as they were) and the run's:
    input, output (absolute; None: standard output), shape, format, threads, the lit rows,
    the suns' times (ISO 8601; none for given suns or a point light), the phases' seconds."""
    from ..io import input_label
    return {**doc, "input": input_label(d.path),
            "output": None if cfg.output is None else os.path.abspath(cfg.output),
            "shape": list(d.shape), "format": fmt, "threads": ctx.threads, "lit_rows": int(lit),
            "sun_times": [t.isoformat() for t in times if t is not None],
            "seconds": ctx.phase_seconds()}


def _start(cfg: QueryConfig, more_inputs=()) -> RunContext:
    """The run begun (``RunContext.start``): -o/--output claimed against the DEM, the points'
    file and ``more_inputs``; the threads set (the marches are numba's); no GPU kernels."""
    return RunContext.start(cfg.run, inputs=[cfg.dem] + ([cfg.points] if cfg.points else [])
                            + list(more_inputs), outputs=[(cfg.output, "-o/--output")],
                            backend=False)


def _sun_request(cfg: QueryConfig):
    """(the ``sun.SunRequest`` of the sun options, the STAC scene of --sun-from-stac or None);
    a bad sun is the command line's fault (exit status 2), so is --irradiance without suns
    from times."""
    from ..model.sun import SunRequest
    from .stac import sun_from_item
    sun, scene = sun_from_item(cfg.sun, cfg.run.quiet, cfg.run.say)   # --sun-from-stac
    try:
        req = SunRequest.from_options(**sun)
    except UsageProblem:
        raise
    except HillshadeError as exc:
        raise UsageProblem(str(exc)) from None
    if cfg.irradiance and not req.from_time:
        raise UsageProblem("--irradiance needs suns from times (--time or --start/--end/--step): "
                           "the clear-sky irradiance depends on the date and the place")
    return req, scene


def _place(points, d, lift: float, fmt: str) -> list:
    """The points placed on the DEM ``d`` (row, column, ground, observer ``lift`` above it);
    GeoJSON needs their longitude and latitude."""
    points, _ = locate(points, d)
    on_ground(points, d, lift)
    if fmt == "geojson" and any(p["lon"] is None for p in points):
        raise HillshadeError(f"{d.path}: the DEM has no CRS, so the points have no longitude "
                             "and latitude for GeoJSON: use --format csv or json")
    return points


def _suns_at(req, d, points) -> SunsAt:
    """The suns of ``req`` over ``d`` and their direction at each point (``sun_at``)."""
    site = req.site(d) if req.from_time else None
    suns, info = req.suns(d, site)
    n, m = len(points), len(suns)
    rows = np.array([p["row"] for p in points])
    cols = np.array([p["col"] for p in points])
    az = np.empty((n, m))
    el = np.empty((n, m))
    for j, s in enumerate(suns):
        for i in range(n):
            az[i, j], el[i, j] = sun_at(s, d.shape, rows[i], cols[i])
    return SunsAt(suns, info, site, az, el)


def _march(cfg: QueryConfig, req, d, points, at: SunsAt, lift: float) -> dict:
    """Each point's horizon toward each sun (``engine.arrays.sun_at_points``)."""
    from ..engine.arrays import sun_at_points
    from ..model.earth import dem_body
    rows = np.array([p["row"] for p in points])
    cols = np.array([p["col"] for p in points])
    return sun_at_points(d.heights, rows, cols, at.azimuth, at.elevation, d.grid, lift,
                         curvature="auto" if cfg.curvature is None else cfg.curvature,
                         refraction_k=cfg.refraction_k, body=dem_body(d, req.lat))


def _true_azimuth(at: SunsAt, points, res):
    """The suns' azimuths from true north at each point (from the grid's north, by the
    site's convergence there), or None for suns given."""
    site = at.site
    if site is None:
        return None
    rows = np.array([p["row"] for p in points])
    cols = np.array([p["col"] for p in points])
    conv = (site.convergence(rows, cols) if site.convergence is not None
            else np.full(len(points), site.north_offset))
    return np.mod(res["azimuth"] - np.asarray(conv, np.float64)[:, None], 360.0)


def _rows(points, at: SunsAt, res, true_az, irr) -> list:
    """One row per point and sun (``COLUMNS``, ``IRRADIANCE_COLUMNS`` with ``irr``)."""
    from ..model.times import iso
    out_rows = []
    for i, p in enumerate(points):
        for j, s in enumerate(at.suns):
            row = {"point": p["id"], "x": p["x"], "y": p["y"], "lon": p["lon"], "lat": p["lat"],
                   "time": iso(s.time) if s.time is not None else None,
                   "sun_azimuth_deg": float(res["azimuth"][i, j]),
                   "sun_true_azimuth_deg": None if true_az is None else float(true_az[i, j]),
                   "sun_elevation_deg": float(res["elevation"][i, j]),
                   "horizon_deg": float(res["horizon_deg"][i, j]),
                   "horizon_distance_m": _finite(res["distance_m"][i, j]),
                   "margin_deg": float(res["margin_deg"][i, j]),
                   "lit": bool(res["lit"][i, j]),
                   "ground_m": float(res["ground_m"][i]),
                   "observer_m": float(res["observer_m"][i])}
            if irr is not None:
                row["dni_w_m2"] = float(irr[0][i, j])
                row["beam_horizontal_w_m2"] = float(irr[1][i, j])
            out_rows.append(row)
    return out_rows


def light_query(cfg: QueryConfig) -> dict:
    """``query --light-position/--light-lonlat``: for each point, the point light's direction,
    distance, incidence on the surface and whether it reaches the observer
    (``algorithms.lightmap.light_at_points``; the same line as the point light's mask). The
    sun's options, --irradiance and the curvature options are usage errors; a light inside the
    terrain is an error. Nothing is written on failure."""
    from ..algorithms.lightmap import light_at_points
    from ..engine.arrays import ground_height
    from .config import PLACE_KEYS, SUN_KEYS, check_lift
    from .config import parse_triple
    from .lightmap import light_cell, light_xy

    fmt = output_format(cfg.fmt, cfg.output)
    if cfg.light_position is not None and cfg.light_lonlat is not None:
        raise UsageProblem("give --light-position X,Y,Z or --light-lonlat LON,LAT,Z, one of them")
    refused = (["--azimuth/--elevation/--time/--start"]
               if any(cfg.sun.get(k) for k in SUN_KEYS if k not in PLACE_KEYS) else [])
    refused += [flag for flag, on in (("--irradiance", cfg.irradiance),
                                      ("--earth-curvature", cfg.curvature is True),
                                      ("--refraction-coefficient", cfg.refraction_k is not None)) if on]
    if refused:
        raise UsageProblem(f"a point light does not take {', '.join(refused)}")
    pos = (None if cfg.light_position is None
           else parse_triple(cfg.light_position, "--light-position"))
    ll = None if cfg.light_lonlat is None else parse_triple(cfg.light_lonlat, "--light-lonlat")
    check_lift(cfg.height_above_ground, "brute", False)
    lift = float(cfg.height_above_ground)
    points = gather(cfg.at, cfg.at_xy, cfg.points)
    ctx = _start(cfg)
    with ctx.timer("read"):
        d = cfg.read.read(cfg.dem)
    points = _place(points, d, lift, fmt)
    x, y, zl = light_xy(d, pos, ll)
    row_l, col_l = light_cell(d, x, y)
    ground = ground_height(d.heights, row_l, col_l)
    if math.isfinite(ground) and zl <= ground:
        raise HillshadeError(f"the light is inside the terrain ({zl:g} m at a ground of "
                             f"{ground:g} m)")
    with ctx.timer("compute"):
        res = light_at_points(d.heights, d.grid, [p["row"] for p in points],
                              [p["col"] for p in points], [p["observer"] for p in points],
                              row_l, col_l, zl)
    out_rows = [{"point": p["id"], "x": p["x"], "y": p["y"], "lon": p["lon"], "lat": p["lat"],
                 "light_azimuth_deg": float(res["azimuth"][i]),
                 "light_elevation_deg": float(res["elevation"][i]),
                 "light_distance_m": float(res["distance"][i]),
                 "incidence_cos": _finite(res["incidence"][i]),
                 "lit": bool(res["lit"][i]), "ground_m": float(p["ground"]),
                 "observer_m": float(p["observer"])} for i, p in enumerate(points)]
    n = len(points)
    doc = {"dem": os.path.abspath(d.path) if os.path.exists(d.path) else d.path,
           "crs": d.crs_string(), "convention": LIGHT_CONVENTION, "columns": LIGHT_COLUMNS,
           "light": {"x": x, "y": y, "z": zl, "row": row_l, "col": col_l},
           "height_above_ground_m": lift, "earth_curvature": False, "sun_source": None,
           "irradiance": None, "points": n, "suns": 1, "version": __version__,
           "rows": out_rows}
    with ctx.timer("write"):
        write_text(cfg.output, render(doc, fmt), cfg.run.overwrite)
    lit = sum(r["lit"] for r in out_rows)
    ctx.finish(_report(cfg, d, ctx, doc, fmt, lit), [("summary", None if cfg.output is None else
                             f"hillshade-rt: {cfg.output}: {n} point(s), point light at x "
                             f"{x:.6g} y {y:.6g} z {zl:g} m, {lit} of {n} lit ({fmt})")])
    return doc


def _finite(v) -> float | None:
    v = float(v)
    return v if math.isfinite(v) else None


def irradiance(points, site, times, res) -> tuple[np.ndarray, np.ndarray]:
    """(DNI, beam on a horizontal surface), points x times, W/m2: pvlib's Ineichen-Perez clear
    sky at each point (its longitude and latitude, else the site's; the observer's altitude)
    for the query's suns (apparent elevation ``res["elevation"]``), the beam counted where the
    point is lit; 0 with the sun down. The steps of ``pvlib.location.Location.get_clearsky(...,
    model="ineichen")`` given that solar position (Kasten-Young airmass from the apparent
    zenith, pressure from the altitude, Linke turbidity from pvlib's monthly climatology),
    over every point at once."""
    import warnings

    import pandas as pd
    from pvlib import atmosphere, clearsky, irradiance as pvirr

    from ..model.times import UTC
    index = pd.DatetimeIndex([t.astimezone(UTC) for t in times])
    el = res["elevation"]
    alt = np.asarray(res["observer_m"], np.float64)[:, None]
    with warnings.catch_warnings():    # pvlib's own use of pandas' deprecated names
        warnings.filterwarnings("ignore", message=".*is deprecated.*")
        dni_extra = np.asarray(pvirr.get_extra_radiation(index), np.float64)[None, :]
        turbidity = np.array([np.asarray(clearsky.lookup_linke_turbidity(
            index, p["lat"] if p["lat"] is not None else site.lat,
            p["lon"] if p["lon"] is not None else site.lon), np.float64) for p in points])
    zen = 90.0 - el
    with np.errstate(all="ignore"):    # no airmass with the sun down (NaN: 0 below)
        airmass = atmosphere.get_absolute_airmass(atmosphere.get_relative_airmass(zen),
                                                  atmosphere.alt2pres(alt))
        cs = clearsky.ineichen(zen, airmass, turbidity, altitude=alt, dni_extra=dni_extra)
    dni = np.where(el > 0.0, np.nan_to_num(np.asarray(cs["dni"], np.float64)), 0.0)
    beam = dni * np.sin(np.radians(np.maximum(el, 0.0))) * res["lit"]
    return dni, beam


def render(doc: dict, fmt: str) -> str:
    """The document in ``fmt`` (``FORMATS``)."""
    rows = doc["rows"]
    cols = doc.get("columns") or COLUMNS + (IRRADIANCE_COLUMNS if doc["irradiance"] else ())
    if fmt == "json":
        return json.dumps(doc, indent=1) + "\n"
    if fmt == "geojson":
        feats = []
        series = [c for c in cols if c not in ("point", "x", "y", "lon", "lat", "ground_m",
                                                "observer_m")]
        for i in range(doc["points"]):
            part = rows[i * doc["suns"]:(i + 1) * doc["suns"]]
            p = part[0]
            props = {"id": p["point"], "x": p["x"], "y": p["y"], "ground_m": p["ground_m"],
                     "observer_m": p["observer_m"],
                     "height_above_ground_m": doc["height_above_ground_m"]}
            props.update({c: [r[c] for r in part] for c in series})
            props["convention"] = doc["convention"]
            if doc["irradiance"]:
                props["irradiance"] = doc["irradiance"]
            feats.append({"type": "Feature", "properties": props,
                          "geometry": {"type": "Point", "coordinates": [p["lon"], p["lat"]]}})
        return json.dumps({"type": "FeatureCollection", "features": feats}, indent=1) + "\n"
    buf = _io.StringIO()
    light = doc.get("light")
    source = (f"point light at x {light['x']:.6f} y {light['y']:.6f} z {light['z']:g} m"
              if light else "sun from times (NREL SPA)" if doc["sun_source"] == "time"
              else "sun given")
    buf.write(f"# hillshade-rt {doc['version']} query of {doc['dem']}; height above ground "
              f"{doc['height_above_ground_m']:g} m; earth curvature "
              f"{'on' if doc['earth_curvature'] else 'off'}; {source}\n")
    buf.write(f"# {doc['convention']}\n")
    if doc["irradiance"]:
        buf.write(f"# {doc['irradiance']}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in rows:
        w.writerow(["" if r[c] is None else int(r[c]) if c == "lit" else r[c] for c in cols])
    return buf.getvalue()
