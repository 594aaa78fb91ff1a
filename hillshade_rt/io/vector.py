"""Shadow polygons: the cells of given values of raster bands as polygons in a vector file
(GeoPackage, GeoJSON, FlatGeobuf, by the file's extension).

The polygons are GDAL's (``GDALPolygonize`` through ``rasterio.features.shapes``), made from a
band of a dataset opened on disk, so that GDAL reads the raster block by block: a raster larger
than memory is polygonized as well as a small one (GDAL keeps the polygons, not the cells). The
band is its own mask, so lit cells (value 0) are never traced; the other values (nodata, 255)
are traced and dropped. Each region of equal value is one polygon (with its holes), its cells
joined through their edges (4-connected, GDAL's default) or also through their corners
(8-connected). The records are GeoJSON-like dicts written by Fiona (one layer, the CRS of the
raster as WKT with its authority code), to a temporary file in the destination's folder,
published whole (``write.atomic_path``) or not at all.

Fiona and rasterio each bundle a GDAL: each reads and writes its own files (the raster through
rasterio, the vector through Fiona); nothing is handed between them but Python objects.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass, field

from ..errors import HillshadeError, UsageProblem

# the vector formats by extension: (Fiona's driver, its name for people)
VECTOR_FORMATS = {".gpkg": "GPKG", ".geojson": "GeoJSON", ".fgb": "FlatGeobuf"}
CONNECTIVITIES = (4, 8)


def vector_driver(path) -> str:
    """The OGR driver of the vector file ``path`` from its extension (``VECTOR_FORMATS``); an
    unknown one is a usage error."""
    ext = os.path.splitext(os.fspath(path))[1].lower()
    try:
        return VECTOR_FORMATS[ext]
    except KeyError:
        raise UsageProblem(f"--vector {path}: unknown vector format {ext or '(no extension)'!r}; "
                           f"give a file ending in {', '.join(VECTOR_FORMATS)}") from None


def check_connectivity(n) -> int:
    """--vector-connectivity: 4 (cells joined through their edges) or 8 (also their corners)."""
    try:
        k = int(n)
    except (TypeError, ValueError):
        k = None
    if k not in CONNECTIVITIES or (isinstance(n, float) and n != k):
        raise UsageProblem(f"--vector-connectivity must be 4 or 8, got {n!r}")
    return k


def check_vector_path(path) -> str:
    """A local file of a known format (the vector library writes with its own GDAL: a
    ``/vsimem/`` file of it would not be rasterio's)."""
    from .write import is_virtual
    path = os.fspath(path)
    vector_driver(path)
    if is_virtual(path):
        raise UsageProblem(f"--vector {path}: polygons go to a local file")
    return path


def vector_library():
    """Fiona, imported (its absence said as what to install)."""
    try:
        import fiona
    except ImportError as exc:       # a broken install: fiona is a dependency
        raise HillshadeError(f"--vector needs fiona ({exc}): pip install fiona") from None
    return fiona


@dataclass(kw_only=True)
class PolygonSource:
    """One set of polygons: band ``band`` of the raster at ``path``, the cells of ``values``
    (value -> the attributes its polygons get besides ``attributes``)."""

    path: str
    band: int
    attributes: dict
    values: dict = field(default_factory=lambda: {1: {}})


@dataclass
class LayerStats:
    """What a layer got: polygons and area per source, in order.

    Attributes
    ----------
    polygons : list of int
        Polygons of each source.
    area : list of float
        Their planar area in the CRS's units squared (pixels without a transform).
    area_m2 : list of float or None
        Their area in square metres: the planar area times the linear unit's metres squared
        (projected CRSs), the area on the CRS's ellipsoid (geographic CRSs: pyproj's
        ``Geod.polygon_area_perimeter``); None without a CRS.
    """

    polygons: list = field(default_factory=list)
    area: list = field(default_factory=list)
    area_m2: list = field(default_factory=list)

    @property
    def total_polygons(self) -> int:
        return int(sum(self.polygons))

    @property
    def total_area_m2(self):
        return None if any(a is None for a in self.area_m2) else float(sum(self.area_m2))


def _ring_area(ring) -> float:
    """The planar area of a closed ring of (x, y) points (shoelace), positive; from the
    ring's first point (map coordinates of millions of units would cancel)."""
    import numpy as np
    xy = np.asarray(ring, dtype=np.float64)
    xy = xy - xy[0]
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * abs(float(np.dot(x[:-1], y[1:]) - np.dot(x[1:], y[:-1])))


class PolygonArea:
    """A polygon's areas: planar (shoelace, CRS units squared) and in square metres as the CRS
    allows (the linear unit's factor squared when projected; on the CRS's ellipsoid, pyproj's
    ``Geod.polygon_area_perimeter``, when geographic; None without a CRS). Called with a
    GeoJSON-like polygon: ``(area, area_m2)``."""

    def __init__(self, crs):
        self.factor = self.geod = None
        if crs is None:
            return
        if crs.is_geographic:
            from pyproj import CRS as ProjCRS
            self.geod = ProjCRS.from_wkt(crs.to_wkt()).get_geod()
        else:
            try:
                self.factor = float(crs.linear_units_factor[1])
            except Exception:          # a CRS without a linear unit: no metres
                self.factor = None

    def __call__(self, geom) -> tuple[float, float | None]:
        rings = geom["coordinates"]
        planar = _ring_area(rings[0]) - sum(_ring_area(r) for r in rings[1:])
        if self.geod is not None:
            import numpy as np

            def geodesic(ring):
                xy = np.asarray(ring, dtype=np.float64)
                return abs(self.geod.polygon_area_perimeter(xy[:, 0], xy[:, 1])[0])
            return planar, geodesic(rings[0]) - sum(geodesic(r) for r in rings[1:])
        if self.factor is not None:
            return planar, planar * self.factor ** 2
        return planar, None


def _schema(fields: dict) -> dict:
    return {"geometry": "Polygon", "properties": dict(fields)}


def write_polygons(path, sources, fields: dict, *, overwrite: bool = False,
                   connectivity: int = 4, layer: str | None = None) -> LayerStats:
    """Write the polygons of every ``PolygonSource`` of ``sources`` to the vector file ``path``
    (its format by extension: ``vector_driver``), one layer named ``layer`` (default: the
    file's name without extension), its fields ``fields`` (name -> Fiona type: "float",
    "int", "str"; each record's attributes are the source's and its value's). The CRS is the
    first raster's (all share it). The file appears whole or not at all; without
    ``overwrite`` an existing file is kept. Returns the polygons' count and areas per source.
    """
    import rasterio
    from rasterio.features import shapes

    from .write import atomic_path, os_error

    path = os.fspath(path)
    driver = vector_driver(path)
    fiona = vector_library()
    sources = list(sources)
    layer = layer or os.path.splitext(os.path.basename(path))[0] or "shadow"
    stats = LayerStats()
    crs = None
    if sources:
        with rasterio.open(sources[0].path) as ds:
            crs = ds.crs
    measure = PolygonArea(crs)
    opts = {"crs_wkt": crs.to_wkt()} if crs is not None else {}

    def records(src, ds):
        """The source's features, its count and areas added to ``stats`` as they go."""
        n, area, metres = 0, 0.0, 0.0
        band = rasterio.band(ds, src.band)
        for geom, value in shapes(band, mask=band, connectivity=connectivity):
            extra = src.values.get(int(value))
            if extra is None:           # nodata, or a value not asked for
                continue
            a, m = measure(geom)
            n, area = n + 1, area + a
            metres = None if m is None or metres is None else metres + m
            yield fiona.Feature(geometry=fiona.Geometry.from_dict(geom),
                                properties=fiona.Properties(**src.attributes, **extra))
        stats.polygons.append(n)
        stats.area.append(area)
        stats.area_m2.append(metres)

    ext = os.path.splitext(path)[1]
    with atomic_path(path, suffix=ext, overwrite=overwrite) as tmp:
        os.remove(tmp)        # the drivers create their file (GeoJSON's refuses to overwrite)
        try:
            with fiona.open(tmp, "w", driver=driver, schema=_schema(fields), layer=layer,
                            **opts) as sink:
                for src in sources:
                    with rasterio.open(src.path) as ds:
                        # in one call: the driver's transactions span many records (GPKG
                        # commits per call otherwise)
                        sink.writerecords(records(src, ds))
        except BaseException as exc:
            for extra in ("-journal", "-wal", "-shm"):      # SQLite's, beside a GeoPackage
                with contextlib.suppress(OSError):
                    os.remove(tmp + extra)
            if isinstance(exc, HillshadeError) or not isinstance(exc, Exception):
                raise       # ours, or an interruption: as it is
            if isinstance(exc, OSError):
                raise os_error(path, exc) from None
            text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise HillshadeError(f"{path}: cannot write ({text})") from None
    return stats
