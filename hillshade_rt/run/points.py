"""Points on a DEM, for the commands that answer at places rather than over a raster (``profile``,
``query``): read from the command line (``--at LON,LAT``, ``--at-xy X,Y``) and from files (a CSV
with columns lon,lat or x,y, an id or name optional; a GeoJSON file of Point features), placed on
the DEM's grid (fractional row and column, cell centres at whole numbers; within 1e-6 cells of a
centre a point is that centre), their ground height interpolated bilinearly; and the text those
commands write (atomically, or to standard output).

A point outside the DEM's cell centres, or whose ground touches nodata, is an error (one line,
nothing written): there is no ground height to stand on.
"""

from __future__ import annotations

import csv
import io as _io
import json
import math

from ..errors import HillshadeError, UsageProblem


def parse_pair(text: str, what: str) -> tuple[float, float]:
    """'A,B' as two finite floats (a usage error otherwise)."""
    parts = str(text).replace(" ", "").split(",")
    try:
        a, b = (float(p) for p in parts)
    except ValueError:
        raise UsageProblem(f"{what} must be two numbers A,B, got {text!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)):
        raise UsageProblem(f"{what} must be finite numbers, got {text!r}")
    return a, b


def read_points(path: str) -> list[dict]:
    """Points of a CSV (columns lon,lat or x,y; an optional id or name) or a GeoJSON file
    (Point features, lon/lat as GeoJSON says): dicts with id and lon/lat or x/y."""
    try:
        with open(path, encoding="utf-8-sig") as fh:
            text = fh.read()
    except OSError as exc:
        raise HillshadeError(f"{path}: {exc.strerror or exc}") from None
    if path.lower().endswith((".geojson", ".json")):
        try:
            doc = json.loads(text)
            feats = doc["features"] if doc.get("type") == "FeatureCollection" else [doc]
            out = []
            for i, f in enumerate(feats):
                g = f.get("geometry") or {}
                if g.get("type") != "Point":
                    continue
                lon, lat = (float(v) for v in g["coordinates"][:2])
                pid = (f.get("properties") or {}).get("id", (f.get("properties") or {}).get(
                    "name", i))
                out.append({"id": str(pid), "lon": lon, "lat": lat})
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise HillshadeError(f"{path}: not a GeoJSON file of points ({exc})") from None
        if not out:
            raise HillshadeError(f"{path}: no Point feature")
        return out
    rows = list(csv.DictReader(_io.StringIO(text)))
    if not rows:
        raise HillshadeError(f"{path}: no points (a CSV with a header: lon,lat or x,y)")
    keys = {k.strip().lower(): k for k in rows[0] if k is not None}
    if {"lon", "lat"} <= set(keys):
        a, b, ka, kb = "lon", "lat", keys["lon"], keys["lat"]
    elif {"x", "y"} <= set(keys):
        a, b, ka, kb = "x", "y", keys["x"], keys["y"]
    else:
        raise HillshadeError(f"{path}: no coordinates: the CSV needs columns lon,lat (degrees) "
                             "or x,y (the DEM's CRS)")
    kid = keys.get("id", keys.get("name"))
    out = []
    for i, r in enumerate(rows):
        try:
            va, vb = float(r[ka]), float(r[kb])
        except (TypeError, ValueError):
            raise HillshadeError(f"{path}: row {i + 2}: {r[ka]!r}, {r[kb]!r} are not "
                                 "numbers") from None
        if not (math.isfinite(va) and math.isfinite(vb)):
            raise HillshadeError(f"{path}: row {i + 2}: {r[ka]!r}, {r[kb]!r} are not finite")
        out.append({"id": str(r[kid]) if kid else str(i), a: va, b: vb})
    return out


def gather(at, at_xy, path: str | None) -> list[dict]:
    """The points of ``--at`` ((lon, lat) pairs), ``--at-xy`` ((x, y) pairs in the DEM's CRS)
    and ``--points`` (a file, or None), in that order, ids numbered from 0 where none is given;
    none at all is a usage error."""
    points = ([{"id": str(i), "lon": a, "lat": b} for i, (a, b) in enumerate(at)]
              + [{"id": str(len(at) + i), "x": a, "y": b} for i, (a, b) in enumerate(at_xy)])
    if path is not None:
        points += read_points(path)
    if not points:
        raise UsageProblem("give a point: --at LON,LAT, --at-xy X,Y or --points FILE")
    return points


def locate(points, src):
    """(the points with their x, y (the DEM's CRS), lon, lat, and fractional row and column
    (cell centres at whole numbers); the transformer from the DEM's CRS to lon/lat, or None)."""
    from pyproj import CRS as PCRS, Transformer
    if src.transform is None:
        raise HillshadeError(f"{src.path}: the DEM has no georeferencing: points cannot be "
                             "placed on it")
    crs = PCRS.from_user_input(src.crs.to_wkt()) if src.crs is not None else None
    need_crs = any("lon" in p for p in points)
    if crs is None and need_crs:
        raise HillshadeError(f"{src.path}: the DEM has no CRS: give points in its coordinates "
                             "(--at-xy, or x,y columns)")
    to_xy = Transformer.from_crs("EPSG:4326", crs, always_xy=True) if crs is not None else None
    to_ll = Transformer.from_crs(crs, "EPSG:4326", always_xy=True) if crs is not None else None
    inv = ~src.transform
    for p in points:
        if "lon" in p:
            p["x"], p["y"] = (float(v) for v in to_xy.transform(p["lon"], p["lat"]))
        elif to_ll is not None:
            p["lon"], p["lat"] = (float(v) for v in to_ll.transform(p["x"], p["y"]))
        else:
            p["lon"] = p["lat"] = None
        if not (math.isfinite(p["x"]) and math.isfinite(p["y"])):
            raise HillshadeError(f"point {p['id']} has no place in the DEM's CRS")
        col, row = inv @ (p["x"], p["y"])
        # within rounding of a cell centre (a centre's coordinates through the transform and
        # back), the point is that centre: a crossing 1e-9 steps away would read the ground's
        # own slope there as the horizon
        p["col"], p["row"] = (snap(col - 0.5), snap(row - 0.5))
    return points, to_ll


def snap(v: float, eps: float = 1e-6) -> float:
    """``v``, or the whole number within ``eps`` of it."""
    w = round(v)
    return float(w) if abs(v - w) <= eps else float(v)


def on_ground(points, d, height_above_ground: float = 0.0) -> list[dict]:
    """Each point (``locate``d on the DEM ``d``) with ``ground`` (the terrain interpolated
    bilinearly at it: ``arrays.ground_height``) and ``observer`` (``height_above_ground`` above
    that); a point outside the DEM's cell centres, or whose ground needs a nodata cell, is an
    error."""
    from ..engine.arrays import ground_height
    rows, cols = d.shape
    for p in points:
        if not (-1e-9 <= p["row"] <= rows - 1 + 1e-9 and -1e-9 <= p["col"] <= cols - 1 + 1e-9):
            raise HillshadeError(f"point {p['id']} ({p['x']:.6g}, {p['y']:.6g}) is outside the "
                                 "DEM's cell centres")
        p["row"] = min(max(p["row"], 0.0), rows - 1.0)
        p["col"] = min(max(p["col"], 0.0), cols - 1.0)
        g = ground_height(d.heights, p["row"], p["col"])
        if not math.isfinite(g):
            raise HillshadeError(f"point {p['id']} lies on nodata: no ground height there")
        p["ground"] = g
        p["observer"] = g + float(height_above_ground)
    return points


def write_text(output: str | None, text: str, overwrite: bool = False) -> None:
    """``text`` to ``output`` (a temporary file beside it, then renamed: nothing half-written),
    or to standard output when ``output`` is None."""
    from ..io.write import atomic_path, os_error
    if output is None:
        import sys
        sys.stdout.write(text)
        return
    with atomic_path(output, overwrite=overwrite) as tmp:
        try:
            with open(tmp, "w", encoding="utf-8", newline="") as fh:
                fh.write(text)
        except OSError as exc:
            raise os_error(output, exc) from None
