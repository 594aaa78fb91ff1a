"""STAC items (https://stacspec.org): the sun of a satellite scene read from its item
(``--sun-from-stac``), and an item written for an output raster (``--stac-item``).

Reading takes plain JSON (no pystac: a run that only reads an item imports nothing more). The
sun's angles are the view extension's ``view:sun_azimuth`` / ``view:sun_elevation`` (degrees,
azimuth clockwise from north, elevation above the horizon), which Landsat Collection 2 items
(USGS, Earth Search, Planetary Computer) and Sentinel-2 L2A items on Earth Search carry;
Sentinel-2 L2A items on Planetary Computer carry only ``s2:mean_solar_azimuth`` /
``s2:mean_solar_zenith`` (elevation = 90 - zenith), and items of the STAC 0.x ``eo`` extension
(sat-api's Landsat) ``eo:sun_azimuth`` / ``eo:sun_elevation``: those are read too, in that order.

Writing uses pystac (the ``stac`` extra), imported only then: the item's footprint in WGS84
(pyproj), the projection, view and file extensions, one asset (the raster, its href relative
to the item), written atomically (``write.write_json``).
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
from dataclasses import dataclass

from ..errors import HillshadeError

# (azimuth key, elevation-or-zenith key, whether the second is a zenith angle), first found wins
SUN_KEYS = (("view:sun_azimuth", "view:sun_elevation", False),
            ("s2:mean_solar_azimuth", "s2:mean_solar_zenith", True),
            ("eo:sun_azimuth", "eo:sun_elevation", False))

# an item's bytes at most (a STAC item is a few kB to a few hundred kB)
MAX_ITEM_BYTES = 64 << 20

GEOTIFF = "image/tiff; application=geotiff"
COG = "image/tiff; application=geotiff; profile=cloud-optimized"
MEDIA_TYPES = {"GTiff": GEOTIFF, "COG": COG, "PNG": "image/png", "JPEG": "image/jpeg",
               "netCDF": "application/netcdf", "JP2OpenJPEG": "image/jp2"}


@dataclass(frozen=True)
class ItemSun:
    """What an item says of its scene's sun: ``azimuth``/``elevation`` (degrees; None when the
    item has no angles), ``time`` (the item's ``datetime``, aware, or None), ``keys`` (the
    properties the angles came from), the item's ``id`` and the ``path`` it was read from."""

    path: str
    id: str
    azimuth: float | None
    elevation: float | None
    time: _dt.datetime | None
    keys: tuple[str, str] | None = None
    bbox: tuple[float, float, float, float] | None = None    # the scene's, WGS84 (2-D)

    @property
    def has_angles(self) -> bool:
        return self.azimuth is not None

    def as_dict(self) -> dict:
        return {"item": self.id, "path": self.path,
                "sun_from": "angles" if self.has_angles else "datetime",
                "properties": list(self.keys) if self.keys else None,
                "azimuth": self.azimuth, "elevation": self.elevation,
                "datetime": None if self.time is None else self.time.isoformat()}


def _read_bytes(path: str) -> bytes:
    """The bytes of ``path``: a local file (or ``file://``), an http(s) URL (``/vsicurl/``
    too), a member of a zip archive (``/vsizip/a.zip/item.json``, ``zip://a.zip!item.json``)
    or a gzip file (``/vsigzip/``, ``gzip://``)."""
    from .paths import gdal_path
    p = os.fspath(path)
    if p.startswith("file://"):
        p = p[len("file://"):]
    if p.startswith("/vsicurl/"):
        p = p[len("/vsicurl/"):]
    if p.startswith(("http://", "https://")):
        return _read_url(path, p)
    g = gdal_path(p)
    if g.startswith("/vsizip/"):
        return _read_zip(path, g[len("/vsizip/"):])
    if g.startswith("/vsigzip/"):
        import gzip
        return _read_local(path, g[len("/vsigzip/"):], gzip.open)
    if g.startswith("/vsi") or "://" in g:
        raise HillshadeError(f"{path}: --sun-from-stac reads local files, http(s) URLs and zip or "
                             "gzip archives; download the item first")
    return _read_local(path, p, open)


def _read_local(shown: str, path: str, opener) -> bytes:
    if not os.path.exists(path):
        raise HillshadeError(f"{shown}: no such file")
    if os.path.isdir(path):
        raise HillshadeError(f"{shown}: is a folder, not a STAC item")
    try:
        with opener(path, "rb") as fh:
            data = fh.read(MAX_ITEM_BYTES + 1)
    except OSError as exc:
        raise HillshadeError(f"{shown}: cannot read ({exc.strerror or exc})") from None
    if len(data) > MAX_ITEM_BYTES:
        raise HillshadeError(f"{shown}: larger than {MAX_ITEM_BYTES >> 20} MB: not a STAC item")
    return data


def _read_zip(shown: str, rest: str) -> bytes:
    """``rest``: ``archive.zip/member`` (the archive: the longest prefix that is a file)."""
    import zipfile
    parts = rest.split("/")
    for i in range(len(parts) - 1, 0, -1):
        archive = "/".join(parts[:i])
        if os.path.isfile(archive):
            member = "/".join(parts[i:])
            try:
                with zipfile.ZipFile(archive) as z:
                    with z.open(member) as fh:
                        return fh.read(MAX_ITEM_BYTES + 1)
            except KeyError:
                raise HillshadeError(f"{shown}: no {member} in {archive}") from None
            except (OSError, zipfile.BadZipFile) as exc:
                raise HillshadeError(f"{shown}: cannot read {archive} ({exc})") from None
    raise HillshadeError(f"{shown}: no such file")


def _read_url(shown: str, url: str) -> bytes:
    import urllib.error
    import urllib.request
    try:
        with urllib.request.urlopen(url, timeout=30) as r:      # noqa: S310 (http(s) only)
            return r.read(MAX_ITEM_BYTES + 1)
    except urllib.error.HTTPError as exc:
        raise HillshadeError(f"{shown}: HTTP {exc.code} {exc.reason}") from None
    except (urllib.error.URLError, OSError, ValueError) as exc:
        reason = getattr(exc, "reason", exc)
        raise HillshadeError(f"{shown}: cannot read ({reason})") from None


def _the_item(doc, path: str) -> dict:
    """The one item of ``doc``: an item (a GeoJSON Feature), or a FeatureCollection (a STAC
    API's ItemCollection) holding exactly one."""
    if not isinstance(doc, dict):
        raise HillshadeError(f"{path}: not a STAC item (a JSON {type(doc).__name__}, not an "
                             "object)")
    kind = doc.get("type")
    if kind == "FeatureCollection":
        feats = doc.get("features")
        if not isinstance(feats, list) or not feats:
            raise HillshadeError(f"{path}: the collection holds no item")
        if len(feats) > 1:
            ids = ", ".join(str(f.get("id")) for f in feats[:3] if isinstance(f, dict))
            raise HillshadeError(f"{path}: the collection holds {len(feats)} items ({ids}"
                                 f"{', ...' if len(feats) > 3 else ''}); give one scene's item")
        doc = feats[0]
        if not isinstance(doc, dict):
            raise HillshadeError(f"{path}: the collection's item is not a JSON object")
        kind = doc.get("type")
    if kind != "Feature":
        what = f"type {kind!r}" if kind is not None else "no type"
        raise HillshadeError(f"{path}: not a STAC item ({what}; an item is a GeoJSON Feature)")
    if not isinstance(doc.get("properties"), dict):
        raise HillshadeError(f"{path}: not a STAC item (no properties)")
    return doc


def _number(props: dict, key: str, path: str, item: str) -> float:
    v = props[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise HillshadeError(f"{path}: item {item}: {key} is {v!r}, not a number of degrees")
    return float(v)


def parse_time(text, path: str, item: str, key: str = "datetime") -> _dt.datetime:
    """An item's RFC 3339 time (``2023-07-14T10:27:39.024Z``) as an aware datetime (UTC when
    it has no offset, as STAC's times are)."""
    if not isinstance(text, str):
        raise HillshadeError(f"{path}: item {item}: {key} is {text!r}, not a time")
    try:
        t = _dt.datetime.fromisoformat(text.strip().replace("z", "Z"))
    except ValueError:
        raise HillshadeError(f"{path}: item {item}: {key} {text!r} is not an RFC 3339 "
                             "time") from None
    return t if t.tzinfo is not None else t.replace(tzinfo=_dt.timezone.utc)


def item_sun(doc, path: str) -> ItemSun:
    """The sun of the item ``doc`` (parsed JSON) read from ``path`` (see the module)."""
    item = _the_item(doc, path)
    ident = item.get("id")
    if not isinstance(ident, str) or not ident:
        raise HillshadeError(f"{path}: not a STAC item (no id)")
    props = item["properties"]
    az = el = keys = None
    for ka, ke, zenith in SUN_KEYS:
        has_a, has_e = props.get(ka) is not None, props.get(ke) is not None
        if has_a != has_e:
            there, missing = (ka, ke) if has_a else (ke, ka)
            raise HillshadeError(f"{path}: item {ident} has {there} but no {missing}")
        if has_a:
            az, el = _number(props, ka, path, ident), _number(props, ke, path, ident)
            if zenith:
                el = 90.0 - el
            keys = (ka, ke)
            break
    if el is not None and not 0.0 < el <= 90.0:
        raise HillshadeError(f"{path}: item {ident}: the sun's elevation is {el:g} degrees "
                             f"({keys[1]}): the scene was taken with the sun at or below the "
                             "horizon, there is no shadow to match")
    when = props.get("datetime")
    t = None if when is None else parse_time(when, path, ident)
    if az is None and t is None:
        span = (" (only start_datetime/end_datetime: a span, not an instant)"
                if props.get("start_datetime") is not None else "")
        raise HillshadeError(f"{path}: item {ident} gives no sun: no view:sun_azimuth/"
                             f"view:sun_elevation and no datetime{span}")
    return ItemSun(path, ident, az, el, t, keys, _bbox(item.get("bbox")))


def _bbox(b):
    """An item's 2-D WGS84 bbox (west, south, east, north), from 4 or 6 numbers; None when it
    has none (or something else)."""
    if not isinstance(b, list) or len(b) not in (4, 6) or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            for v in b):
        return None
    n = len(b) // 2
    return (float(b[0]), float(b[1]), float(b[n]), float(b[n + 1]))


def read_item_sun(path: str) -> ItemSun:
    """The sun of the STAC item at ``path`` (local, http(s), zip, gzip; see the module)."""
    data = _read_bytes(path)
    try:
        doc = json.loads(data)
    except UnicodeDecodeError:
        raise HillshadeError(f"{path}: not a STAC item (not JSON text)") from None
    except json.JSONDecodeError as exc:
        raise HillshadeError(f"{path}: not a STAC item (not JSON: {exc.msg} at line "
                             f"{exc.lineno} column {exc.colno})") from None
    return item_sun(doc, path)


# --------------------------------------------------------------------------------------------
# writing an item for an output raster

def sha256_multihash(path: str) -> str:
    """The file extension's ``file:checksum`` of ``path``: a multihash, sha2-256 (code 0x12,
    32 bytes) in hex."""
    import hashlib
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return "1220" + h.hexdigest()


def footprint(crs, transform, shape, points_per_side: int = 16):
    """(GeoJSON polygon, bbox) in WGS84 longitude/latitude of a raster's outline (each side
    sampled at ``points_per_side`` points, so that a projected raster's curved edges are
    followed), or (None, None) without a CRS."""
    if crs is None:
        return None, None
    from pyproj import CRS, Transformer
    rows, cols = shape
    n = points_per_side
    edge = [(c * cols / n, 0.0) for c in range(n)] + [(cols, r * rows / n) for r in range(n)] + \
           [(cols - c * cols / n, rows) for c in range(n)] + \
           [(0.0, rows - r * rows / n) for r in range(n)]
    a, b, c0, d, e, f = tuple(transform)[:6]
    xy = [(a * c + b * r + c0, d * c + e * r + f) for c, r in edge]
    src = CRS.from_user_input(crs.to_wkt() if hasattr(crs, "to_wkt") else crs)
    a = src.ellipsoid.semi_major_metre if src.ellipsoid is not None else None
    if a is not None and abs(a - 6378137.0) > 50_000.0:
        raise HillshadeError("--stac-item: the raster is not on the Earth (its CRS's ellipsoid "
                             f"is {src.ellipsoid.name}); a STAC item's footprint is in WGS84")
    t = Transformer.from_crs(src, CRS.from_epsg(4326), always_xy=True)
    lon, lat = t.transform([p[0] for p in xy], [p[1] for p in xy])
    ring = [[float(x), float(y)] for x, y in zip(lon, lat)]
    if not all(math.isfinite(v) for p in ring for v in p):
        raise HillshadeError("--stac-item: the raster's outline has no WGS84 longitude and "
                             "latitude (outside its CRS's area)")
    ring.append(ring[0])
    bbox = [min(p[0] for p in ring), min(p[1] for p in ring),
            max(p[0] for p in ring), max(p[1] for p in ring)]
    return {"type": "Polygon", "coordinates": [ring]}, bbox


def write_stac_item(path: str, raster: str, *, when: _dt.datetime | None = None,
                    start: _dt.datetime | None = None, end: _dt.datetime | None = None,
                    sun: tuple[float, float] | None = None, properties: dict | None = None,
                    title: str | None = None, overwrite: bool = False) -> dict:
    """Write at ``path`` a STAC item describing the finished raster ``raster`` (a local file):
    id from its name, geometry and bbox in WGS84, ``datetime`` ``when`` (or null with
    ``start``/``end`` for a series; now when neither), the projection extension (code, shape,
    transform, bbox in the raster's CRS), the view extension (``sun``: azimuth, elevation in
    degrees), ``properties`` (more properties, e.g. ``hillshade_rt:*``) and one asset "data"
    (href relative to the item, media type from the driver, the file extension's checksum
    and size). Returns the item as a dict."""
    import pystac
    import rasterio
    from pystac.extensions.file import FileExtension
    from pystac.extensions.projection import ProjectionExtension
    from pystac.extensions.view import ViewExtension

    import warnings
    from rasterio.errors import NotGeoreferencedWarning
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(raster) as ds:
            crs, transform, shape, driver = ds.crs, ds.transform, (ds.height, ds.width), ds.driver
            bounds = list(ds.bounds)
            tags = ds.tags(ns="IMAGE_STRUCTURE") if driver == "GTiff" else {}
    georeferenced = crs is not None or not transform.is_identity
    geometry, bbox = footprint(crs, transform, shape)
    ident = os.path.splitext(os.path.basename(raster))[0]
    if when is None and (start is None or end is None):
        when = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0)
        start = end = None
    item = pystac.Item(id=ident, geometry=geometry, bbox=bbox,
                       datetime=None if when is None else when.astimezone(_dt.timezone.utc),
                       start_datetime=None if start is None else start.astimezone(_dt.timezone.utc),
                       end_datetime=None if end is None else end.astimezone(_dt.timezone.utc),
                       properties=dict(properties or {}))
    if title:
        item.common_metadata.title = title
    item.common_metadata.created = _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0)
    proj = ProjectionExtension.ext(item, add_if_missing=True)
    if crs is not None:
        epsg = crs.to_epsg()
        if epsg is not None:
            proj.epsg = epsg                  # proj:code "EPSG:n" (projection v2), or proj:epsg
        else:
            proj.epsg = None
            proj.wkt2 = crs.to_wkt()
    else:
        proj.epsg = None
    proj.shape = list(shape)
    if georeferenced:     # a raster without a geotransform: no transform, no bbox
        proj.transform = [float(v) for v in tuple(transform)[:6]]
        proj.bbox = [float(v) for v in bounds]
    if sun is not None:
        view = ViewExtension.ext(item, add_if_missing=True)
        view.sun_azimuth, view.sun_elevation = float(sun[0]), float(sun[1])
    cog = driver == "GTiff" and tags.get("LAYOUT") == "COG"
    media = COG if cog else MEDIA_TYPES.get(driver)
    href = os.path.relpath(os.path.abspath(raster),
                           os.path.dirname(os.path.abspath(path))).replace(os.sep, "/")
    asset = pystac.Asset(href=href, media_type=media, roles=["data"], title=title)
    item.add_asset("data", asset)
    file_ = FileExtension.ext(asset, add_if_missing=True)
    file_.checksum = sha256_multihash(raster)
    file_.size = os.path.getsize(raster)
    doc = item.to_dict(include_self_link=False, transform_hrefs=False)
    from .write import write_json
    write_json(path, doc, overwrite)
    return doc
