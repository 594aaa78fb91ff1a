"""The ``profile`` run: the horizon of points, every ``step`` degrees of azimuth, for PV siting and
for anyone who wants the skyline of a place, in the formats the tools around it read.

A point is given in lon/lat (``--at``, a CSV's ``lon``/``lat`` columns, GeoJSON) or in the DEM's
CRS (``--at-xy``, a CSV's ``x``/``y``); the observer stands ``height_above_ground`` metres above
the terrain interpolated bilinearly at the point (not snapped to a cell). Each direction's ray is
sampled as the model samples a cell's (where it crosses the grid lines of its dominant axis,
interpolated on the line; the rays of the point's nearest row): at a cell centre with no height
above the ground, the profile is the ``horizon`` raster's value there (a test checks it). A point
within 1e-6 cells of a centre is that centre. Between centres the first crossing can be close to
the observer: with no height above the ground, the ground's own slope there is part of the
horizon, as for a person standing on it.

Formats, each saying its convention in its header (``FORMATS``):

* ``csv``: one row per point and azimuth (point, x, y, lon, lat, azimuth, horizon, distance);
* ``json``: the same, one object per point, with the convention and the DEM;
* ``pvlib``: ``azimuth,horizon`` rows that ``pandas.read_csv(f, index_col=0, comment="#")
  .squeeze()`` turns into the Series pvlib's horizon functions take (azimuth clockwise from north
  in [0, 360), elevation degrees); one point;
* ``pvgis``: PVGIS's ``userhorizon``: the elevations, comma-separated, at equally spaced
  azimuths clockwise from north starting at north; one point;
* ``grass``: GRASS r.horizon's point output: ``azimuth,horizon_height`` with the azimuth
  counter-clockwise from east (r.horizon's default), degrees; one point;
* ``geojson``: one Point feature per point (the profile in its properties) and its horizon line
  as a 3-D LineString (lon, lat, height of each horizon point).
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
from ..errors import UsageProblem
from .config import ProfileConfig
from .points import gather, locate, on_ground, parse_pair, write_text
from .runner import RunContext

__all__ = ["ProfileConfig", "parse_pair", "profile", "render"]

FORMATS = ("csv", "json", "pvlib", "pvgis", "grass", "geojson")
ONE_POINT = ("pvlib", "pvgis", "grass")
CONVENTION = ("azimuth in degrees clockwise from north (grid north of the DEM), 0 = north; "
              "horizon elevation in degrees above the observer's horizontal (negative: the "
              "observer looks down); -90 and no distance: no terrain ahead inside the DEM; "
              "distance in metres along the ground to the horizon point")


@dataclass
class Profiles:
    """The horizons of the points (``engine.arrays.observer_profiles``): the azimuths (degrees
    clockwise from north, north first), per point the horizon elevation (degrees) and the
    ground distance to the horizon point (metres, inf: no terrain ahead) toward each, and
    whether the Earth's curvature was on."""

    azimuths: list
    angles: np.ndarray
    distances: np.ndarray
    curved: bool


def profile(cfg: ProfileConfig) -> dict:
    """Compute and write the profiles; returns the document (what ``json`` writes)."""
    _check(cfg)
    points = gather(cfg.at, cfg.at_xy, cfg.points)
    if cfg.fmt in ONE_POINT and len(points) != 1:
        raise UsageProblem(f"--format {cfg.fmt} holds one point's profile; {len(points)} given "
                           "(use csv, json or geojson for several)")
    ctx = RunContext.start(cfg.run, inputs=[cfg.dem] + ([cfg.points] if cfg.points else []),
                           outputs=[(cfg.output, "-o/--output")], backend=False)
    with ctx.timer("read"):
        d = cfg.read.read(cfg.dem)
    with ctx.timer("prepare"):
        points, to_ll = locate(points, d)
        on_ground(points, d, cfg.height_above_ground)
    with ctx.timer("compute"):
        prof = _profiles(cfg, d, points)
        doc = _document(cfg, d, points, prof, to_ll)
    with ctx.timer("write"):
        write_text(cfg.output, render(doc, cfg.fmt), cfg.run.overwrite)
        if cfg.run.preview is not None:     # the first point's horizon as its observer sees it
            from ..io import write_png
            from ..pictures.preview import panorama_rgb
            write_png(cfg.run.preview, panorama_rgb(prof.azimuths, prof.angles[0]),
                      cfg.run.overwrite)
    ctx.finish(_report(cfg, d, ctx, doc, prof),
               [("summary", None if cfg.output is None else
                 f"hillshade-rt: {cfg.output}: {len(points)} point(s) x "
                 f"{len(prof.azimuths)} azimuths ({cfg.fmt})")])
    return doc


def _report(cfg: ProfileConfig, d, ctx: RunContext, doc: dict, prof: Profiles) -> dict:
    """The run's report (``--report``): the document (its keys as they were) and the run's:
    input, output (absolute; None: standard output), shape, format, threads, the counts, the
    horizon elevations' min/mean/max over every point and azimuth, the phases' seconds."""
    from ..io import input_label
    ang = np.asarray(prof.angles, np.float64)
    return {**doc, "input": input_label(d.path),
            "output": None if cfg.output is None else os.path.abspath(cfg.output),
            "shape": list(d.shape), "format": cfg.fmt, "threads": ctx.threads,
            "point_count": int(ang.shape[0]), "azimuth_count": len(prof.azimuths),
            "horizon_deg_stats": {"min": float(ang.min()), "mean": float(ang.mean()),
                                  "max": float(ang.max())} if ang.size else None,
            "seconds": ctx.phase_seconds()}


def _check(cfg: ProfileConfig) -> None:
    """The format, the step and the height checked (usage errors)."""
    if cfg.fmt not in FORMATS:
        raise UsageProblem(f"--format must be one of {', '.join(FORMATS)}, got {cfg.fmt!r}")
    if not (math.isfinite(cfg.step) and 0.0 < cfg.step <= 90.0):
        raise UsageProblem(f"--step must be a number of degrees in (0, 90], got {cfg.step}")
    if not math.isfinite(cfg.height_above_ground):
        raise UsageProblem("--height-above-ground must be a finite number of metres")


def _profiles(cfg: ProfileConfig, d, points) -> Profiles:
    """The points' horizons every ``cfg.step`` degrees (the model's rays from each observer)."""
    from ..engine.arrays import observer_profiles
    from ..model.earth import dem_body
    azimuths, ang, dist, curved = observer_profiles(
        d.heights, d.grid, np.array([p["row"] for p in points]),
        np.array([p["col"] for p in points]), np.array([p["observer"] for p in points]),
        cfg.step, curvature=cfg.curvature, refraction_k=cfg.refraction_k, body=dem_body(d))
    return Profiles(azimuths, ang, dist, curved)


def _document(cfg: ProfileConfig, d, points, prof: Profiles, to_ll) -> dict:
    """The document (what ``json`` writes; the other formats render it)."""
    doc = {"dem": os.path.abspath(d.path) if os.path.exists(d.path) else d.path,
           "crs": d.crs_string(), "convention": CONVENTION, "azimuth_step": cfg.step,
           "height_above_ground_m": cfg.height_above_ground,
           "earth_curvature": prof.curved, "version": __version__, "points": []}
    for i, p in enumerate(points):
        line = (_horizon_line(d, p, prof.azimuths, prof.angles[i], prof.distances[i], to_ll)
                if cfg.fmt == "geojson" else [])
        doc["points"].append({"id": p["id"], "x": p["x"], "y": p["y"], "lon": p["lon"],
                              "lat": p["lat"], "ground_m": p["ground"],
                              "observer_m": p["observer"], "azimuth": prof.azimuths,
                              "horizon_deg": [round(float(v), 6) for v in prof.angles[i]],
                              "distance_m": [None if not math.isfinite(v) else round(float(v), 3)
                                             for v in prof.distances[i]],
                              "line": line})
    return doc


def _horizon_line(d, p, azimuths, ang, dist, to_ll):
    """The horizon points of ``p`` (lon, lat, height; x, y where lon/lat are unknown), one per
    azimuth with terrain ahead: ``dist`` ground metres from the point toward each azimuth, in
    pixels by the spacing of the point's nearest row (as its rays: ``geometry.sun_rays``), then
    through the transform (vectorised: one transform per point)."""
    ok = np.isfinite(dist)
    if not ok.any():
        return []
    r = int(min(max(round(p["row"]), 0), d.shape[0] - 1))
    g = d.grid
    az = np.radians(np.asarray(azimuths, np.float64)[ok])
    col = p["col"] + dist[ok] * np.sin(az) * g.col_sign / g.dx[r]
    row = p["row"] + dist[ok] * np.cos(az) * g.row_sign / g.dy[r]
    tr = d.transform
    x = tr.c + tr.a * (col + 0.5) + tr.b * (row + 0.5)
    y = tr.f + tr.d * (col + 0.5) + tr.e * (row + 0.5)
    h = p["observer"] + np.tan(np.radians(ang[ok])) * dist[ok]
    if to_ll is not None:
        x, y = to_ll.transform(x, y)
    return [[round(float(a), 9), round(float(b), 9), round(float(c), 3)]
            for a, b, c in zip(x, y, h)]


def render(doc: dict, fmt: str) -> str:
    """The document in ``fmt`` (``FORMATS``)."""
    pts = doc["points"]
    if fmt == "json":
        return json.dumps({**doc, "points": [{k: v for k, v in p.items() if k != "line"}
                                             for p in pts]}, indent=1) + "\n"
    if fmt == "geojson":
        feats = []
        for p in pts:
            props = {k: p[k] for k in ("id", "x", "y", "ground_m", "observer_m", "azimuth",
                                       "horizon_deg", "distance_m")}
            props["convention"] = doc["convention"]
            feats.append({"type": "Feature", "properties": props,
                          "geometry": {"type": "Point", "coordinates": [p["lon"], p["lat"]]}})
            feats.append({"type": "Feature",
                          "properties": {"id": p["id"], "kind": "horizon line",
                                         "coordinates": "lon, lat, height of the horizon point "
                                                        "(m, the DEM's vertical datum)"},
                          "geometry": {"type": "LineString", "coordinates": p["line"]}})
        return json.dumps({"type": "FeatureCollection", "features": feats}, indent=1) + "\n"
    head = (f"# hillshade-rt {doc['version']} horizon profile of {doc['dem']}; "
            f"height above ground {doc['height_above_ground_m']:g} m; earth curvature "
            f"{'on' if doc['earth_curvature'] else 'off'}\n")
    if fmt == "csv":
        buf = _io.StringIO()
        buf.write(head + f"# {doc['convention']}\n")
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["point", "x", "y", "lon", "lat", "azimuth_deg", "horizon_deg",
                    "distance_m"])
        for p in pts:
            for a, h, dd in zip(p["azimuth"], p["horizon_deg"], p["distance_m"]):
                w.writerow([p["id"], p["x"], p["y"], p["lon"], p["lat"], f"{a:g}", h,
                            "" if dd is None else dd])
        return buf.getvalue()
    p = pts[0]
    if fmt == "pvlib":
        lines = [head.rstrip("\n"), "# pvlib: azimuth degrees clockwise from north in [0, 360), "
                 "horizon elevation degrees; pandas.read_csv(f, index_col=0, comment='#')"
                 ".squeeze()", "azimuth,horizon_elevation"]
        lines += [f"{a:g},{h}" for a, h in zip(p["azimuth"], p["horizon_deg"])]
        return "\n".join(lines) + "\n"
    if fmt == "pvgis":
        return (head + "# PVGIS userhorizon: horizon elevations in degrees at equally spaced "
                "azimuths clockwise from north, starting at north\n"
                + ",".join(str(h) for h in p["horizon_deg"]) + "\n")
    # grass: r.horizon's convention, azimuth counter-clockwise from east, from east
    pairs = sorted(((90.0 - a) % 360.0, h) for a, h in zip(p["azimuth"], p["horizon_deg"]))
    lines = [head.rstrip("\n"), "# GRASS r.horizon: azimuth degrees counter-clockwise from east "
             "(0 = east, 90 = north), horizon height degrees", "azimuth,horizon_height"]
    lines += [f"{a:g},{h}" for a, h in pairs]
    return "\n".join(lines) + "\n"
