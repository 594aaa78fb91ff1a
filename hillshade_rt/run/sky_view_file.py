"""Dozier's sky view factor Vd kept in a file, made once per DEM and read by many ``irradiance``
runs (``irradiance --sky-view FILE``): what such a file says of how it was made (its tags, which
``skyview`` and ``irradiance --sky-view-out`` write alike), and its reading, checked against the
DEM and the run's settings.

A Vd depends on the heights, the grid, the directions, the Earth's curvature (on or off, the
body's radii and the terrestrial refraction coefficient k of the curved rays), the height of the
observer above each cell, the longest ray (``--max-distance``; irradiance takes none) and, for a
tile of a larger raster (``--context``), on the context's terrain. Each is a tag:

``DEFINITION``, ``PRODUCT``   dozier, "sky view factor (dozier)" (not the terrain configuration)
``DIRECTIONS``                the number of azimuths
``EARTH_CURVATURE``           on / off
``REFRACTION_K``, ``BODY``    k, and the body's axes and latitude (their radii of curvature)
``MAX_DISTANCE``              "none (to the raster's edge)" for irradiance
``HEIGHT_ABOVE_GROUND_M``     the observer above each cell, metres
``CONTEXT``                   "none", or the context raster and the tile's rows and columns in it
``HEIGHTS_DIGEST``            sha256 of the heights read (float32, NaN voids, z-factor applied),
                              when the DEM was read whole (not in windows)
``HILLSHADE_RT_VERSION``      the version that wrote it

The sun's atmospheric refraction (``--no-refraction``, ``--pressure``, ``--temperature``) does
not enter Vd. A file whose grid (shape, transform, CRS) is not the DEM's, or whose tags differ
from the run's, is refused with a one-line message naming the difference (exit status 1).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass

import numpy as np

from .. import __version__
from ..errors import HillshadeError

#: the tags a Vd file must carry, in the order they are compared
CHECKED = ("DEFINITION", "PRODUCT", "CONTEXT", "DIRECTIONS", "EARTH_CURVATURE", "REFRACTION_K",
           "BODY", "MAX_DISTANCE", "HEIGHT_ABOVE_GROUND_M")
#: the options that set each tag, for the messages
OPTION = {"DIRECTIONS": "--skyview-directions (skyview's --directions)",
          "EARTH_CURVATURE": "--earth-curvature / --no-earth-curvature",
          "REFRACTION_K": "--refraction-coefficient", "BODY": "the body and latitude (--lat)",
          "MAX_DISTANCE": "--max-distance (irradiance takes none)",
          "HEIGHT_ABOVE_GROUND_M": "--height-above-ground", "CONTEXT": "--context",
          "DEFINITION": "--definition dozier", "PRODUCT": "no --terrain-configuration"}
DOZIER_PRODUCT = "sky view factor (dozier)"


def heights_digest(z: np.ndarray) -> str:
    """``sha256:`` and the hex digest of the heights' bytes (float32, C order)."""
    return "sha256:" + hashlib.sha256(np.ascontiguousarray(z, np.float32).tobytes()).hexdigest()


def body_text(body) -> str:
    """The body's axes and latitude, exactly (``repr`` of the floats)."""
    return f"{body.source}: a {body.a!r} m, b {body.b!r} m, latitude {body.lat!r}"


def context_text(area) -> str:
    """The ``CONTEXT`` tag of a run on ``area`` (``run.context.Area``, or None)."""
    if area is None:
        return "none"
    from ..io import input_label
    r0, r1, c0, c1 = area.bounds
    return f"{input_label(area.source.path)}, rows {r0}..{r1}, columns {c0}..{c1}"


def provenance(*, k: float, body, area=None, heights=None) -> dict:
    """The tags of how a sky view was made, beyond skyview's own (``REFRACTION_K``, ``BODY``,
    ``CONTEXT``, ``HEIGHTS_DIGEST`` when ``heights`` are given)."""
    tags = {"REFRACTION_K": repr(float(k)), "BODY": body_text(body),
            "CONTEXT": context_text(area)}
    if heights is not None:
        tags["HEIGHTS_DIGEST"] = heights_digest(heights)
    return tags


def dozier_tags(directions: int, *, curved: bool, k: float, body, height_above_ground: float,
                area=None, heights=None) -> dict:
    """Every tag of a Dozier Vd made as ``irradiance`` makes it (no --max-distance), as
    ``skyview --definition dozier`` writes them."""
    from .horizon import distance_tag
    from ..algorithms.skyview import units
    return {"HILLSHADE_RT_VERSION": __version__, "DEFINITION": "dozier",
            "PRODUCT": DOZIER_PRODUCT, "DIRECTIONS": int(directions),
            "UNITS": units("dozier"), "MAX_DISTANCE": distance_tag(math.inf),
            "HEIGHT_ABOVE_GROUND_M": float(height_above_ground),
            "EDGE": "no terrain beyond the raster: border cells see open sky outward",
            "EARTH_CURVATURE": "on" if curved else "off",
            **provenance(k=k, body=body, area=area, heights=heights)}


def _same_grid(path: str, ds, geom) -> None:
    """Refuse a file whose shape, transform or CRS is not the DEM's (``geom``)."""
    from ..io import input_label
    name = input_label(geom.path)
    rows, cols = geom.shape
    if (ds.height, ds.width) != (rows, cols):
        raise HillshadeError(f"{path}: {ds.width}x{ds.height} cells, the DEM {name} has "
                             f"{cols}x{rows}: a sky view of another grid")
    tr = getattr(geom, "transform", None)
    if tr is not None and tuple(ds.transform)[:6] != tuple(tr)[:6]:
        raise HillshadeError(f"{path}: its transform {tuple(ds.transform)[:6]} is not the DEM "
                             f"{name}'s {tuple(tr)[:6]}: a sky view of another grid")
    crs = getattr(geom, "crs", None)
    if (ds.crs is None) != (crs is None) or (crs is not None and ds.crs != crs):
        def show(c):
            return "none" if c is None else (c.to_string() or "a custom CRS")
        raise HillshadeError(f"{path}: its CRS ({show(ds.crs)}) is not the DEM {name}'s "
                             f"({show(crs)})")


def _same_settings(path: str, tags: dict, want: dict) -> None:
    """Refuse a file made with other settings than the run's: the first differing tag."""
    if tags.get("DEFINITION") != "dozier":
        what = (f"a sky view of definition {tags['DEFINITION']}" if "DEFINITION" in tags
                else "no sky view written by hillshade-rt")
        raise HillshadeError(f"{path}: {what}; make it with hillshade-rt skyview DEM FILE "
                             "--definition dozier")
    for key in CHECKED:
        if key not in tags:
            raise HillshadeError(f"{path}: has no {key} tag (written by hillshade-rt "
                                 f"{tags.get('HILLSHADE_RT_VERSION', 'before 0.1')}): make it "
                                 "again with this version's skyview --definition dozier")
        got, exp = str(tags[key]), str(want[key])
        if got != exp:
            raise HillshadeError(f"{path}: made with {key} {got!r}, this run has {exp!r} "
                                 f"({OPTION[key]}): make it again with the run's settings, or "
                                 "drop --sky-view")
    have, exp = tags.get("HEIGHTS_DIGEST"), want.get("HEIGHTS_DIGEST")
    if have is not None and exp is not None and have != exp:
        raise HillshadeError(f"{path}: made from other heights than this DEM's (HEIGHTS_DIGEST "
                             "differs: another DEM, --band, --nodata or --z-factor)")


def _checked(path: str, geom, want: dict, stack):
    """The sky view file ``path`` opened in ``stack`` (its dataset, its tags), checked: one
    float32 band, the grid of ``geom``, the settings of ``want``."""
    from ..io.gdal import open_raster
    from ..io.paths import check_input_path
    check_input_path(path)
    ds = open_raster(path, stack)
    if ds.count != 1 or ds.dtypes[0] != "float32":
        raise HillshadeError(f"{path}: {ds.count} band(s) of {ds.dtypes[0]}: a sky view "
                             "file is one float32 band (hillshade-rt skyview --definition "
                             "dozier)")
    _same_grid(path, ds, geom)
    tags = dict(ds.tags())
    _same_settings(path, tags, want)
    return ds, tags


def _read(path: str, ds, window=None) -> np.ndarray:
    """Vd of ``ds`` (whole, or its ``window`` (r0, r1, c0, c1)): float32, NaN where nodata."""
    from ..io.gdal import read_error
    try:
        if window is None:
            vd = ds.read(1)
        else:
            from rasterio.windows import Window
            r0, r1, c0, c1 = window
            vd = ds.read(1, window=Window(c0, r0, c1 - c0, r1 - r0))
    except Exception as exc:      # noqa: BLE001 -- GDAL's read errors, one line
        raise read_error(path, exc) from None
    if ds.nodata is not None:
        vd[vd == np.float32(ds.nodata)] = np.nan
    return np.ascontiguousarray(vd, np.float32)


def read_vd(path: str, geom, want: dict) -> tuple[np.ndarray, dict]:
    """(Vd: float32, NaN where the file has nodata; the file's tags) of the sky view file
    ``path``, checked against the DEM's grid (``geom``: a Dem, DemSource or tile) and the run's
    tags ``want`` (:func:`dozier_tags`)."""
    import contextlib
    with contextlib.ExitStack() as stack:
        ds, tags = _checked(path, geom, want, stack)
        return _read(path, ds), tags


@dataclass(frozen=True)
class VdFile:
    """A sky view file checked once (:func:`open_vd`) and read window by window (picklable: a
    Dask task reads its region)."""

    path: str
    tags: dict

    def read(self, window) -> np.ndarray:
        """Vd of ``window`` (r0, r1, c0, c1): float32, NaN where the file has nodata."""
        import contextlib

        from ..io.gdal import open_raster
        with contextlib.ExitStack() as stack:
            return _read(self.path, open_raster(self.path, stack), window)


def open_vd(path: str, geom, want: dict) -> VdFile:
    """The sky view file ``path`` checked as :func:`read_vd` checks it (its values not read)."""
    import contextlib
    with contextlib.ExitStack() as stack:
        return VdFile(path, _checked(path, geom, want, stack)[1])


def vd_writer(path: str, geom, tags: dict, ro):
    """The ``io.BandWriter`` of a Vd file on the grid of ``geom`` as skyview writes it: one
    float32 band, -9999 nodata, averaged overviews, ``tags``; atomic, in the format of its
    extension with the default creation options (not OUTPUT's --format and --co). Write it
    with :func:`write_vd_window`."""
    from ..io import BandWriter
    return BandWriter(path, geom, 1, "float32", -9999.0, tags, overview_resampling="average",
                      overwrite=ro.overwrite)


def write_vd_window(w, vd: np.ndarray, window=None) -> None:
    """``vd`` (float32, NaN voids) into the writer ``w`` of :func:`vd_writer`, whole or its
    ``window`` (r0, r1, c0, c1)."""
    w.write(1, np.where(np.isnan(vd), np.float32(-9999.0), vd), description=DOZIER_PRODUCT,
            window=window)


def write_vd(path: str, geom, vd: np.ndarray, tags: dict, ro) -> None:
    """``vd`` (float32, NaN voids) written to ``path`` as skyview writes it (:func:`vd_writer`)."""
    with vd_writer(path, geom, tags, ro) as w:
        write_vd_window(w, vd)
