"""Where a DEM's sun is computed: its centre (or the user's ``--lat/--lon``), the ground height
there, its pixels' longitudes and latitudes, and the meridian convergence that turns a true
azimuth into the raster's grid azimuth (pyproj, imported when a DEM needs it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import HillshadeError

EARTH_A_RANGE = (6.35e6, 6.40e6)   # semi-major axes of Earth ellipsoids (metres)


@dataclass
class Site:
    """Where a DEM's sun is computed: its centre (or the user's --lat/--lon) and the ground
    height there; ``to_lonlat`` maps pixel coordinates to longitude/latitude when the DEM has a
    CRS (None otherwise: one sun for the whole raster)."""

    lat: float
    lon: float
    height: float
    source: str
    to_lonlat: object = None     # callable(rows, cols) -> (lon, lat) arrays, or None
    convergence: object = None   # callable(rows, cols) -> grid azimuth of true north, degrees
    north_offset: float = 0.0    # without to_lonlat: grid azimuth of true north (DEM centre)
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"latitude": self.lat, "longitude": self.lon, "height_m": self.height,
                "source": self.source}


def centre_height_of(z: np.ndarray, r: int | None = None, c: int | None = None) -> tuple[float, str]:
    """The observer's height: the centre cell (``r``, ``c``; default the middle of ``z``), else the
    median of the valid cells nearest to it."""
    rows, cols = z.shape
    r = rows // 2 if r is None else r
    c = cols // 2 if c is None else c
    v = float(z[r, c])
    if math.isfinite(v):
        return v, "the DEM's centre cell"
    for half in (2, 8, 32, 128):
        win = z[max(0, r - half):r + half + 1, max(0, c - half):c + half + 1]
        if np.isfinite(win).any():
            return float(np.nanmedian(win)), f"median of valid cells within {half} of the centre"
    return float(np.nanmedian(z)), "median of the DEM (its centre is a void)"


OTHER_BODY_ADVICE = ("the solar position from --time is for the Earth: give "
                     "--azimuth/--elevation")


def dem_site(dem, lat: float | None = None, lon: float | None = None,
             other_body: str | None = None) -> Site:
    """The :class:`Site` of a :class:`~hillshade_rt.io.Dem` or an ``io.DemSource`` (anything with
    ``crs``, ``transform``, ``shape``, ``path`` and ``centre_height()``). ``other_body``: what the
    error says after "not the Earth; " for a DEM on another body (default: the lighting
    commands' advice, --azimuth/--elevation)."""
    height, hnote = dem.centre_height()
    if (lat is None) != (lon is None):
        raise HillshadeError("--lat and --lon go together")
    if lat is not None:
        if not (-90.0 <= lat <= 90.0) or not math.isfinite(lon):
            raise HillshadeError(f"--lat must be within [-90, 90] and --lon finite, got {lat}, {lon}")
        lon = (lon + 180.0) % 360.0 - 180.0
        site = Site(lat, lon, height, "--lat/--lon", notes=[f"observer height: {hnote}"])
        if dem.crs is not None and dem.transform is not None:
            # the sun at the given place, one vector; still turned to the DEM's grid north
            centre = dem_site(dem, other_body=other_body)
            rows, cols = dem.shape
            site.north_offset = float(centre.convergence(np.array([(rows - 1) / 2.0]),
                                                         np.array([(cols - 1) / 2.0]))[0])
        return site
    if dem.crs is None or dem.transform is None:
        raise HillshadeError(f"{dem.path}: has no CRS, so its place on Earth is unknown; "
                             "give --lat and --lon (degrees) for a sun from --time")
    from pyproj import CRS as PCRS, Transformer

    pcrs = PCRS.from_user_input(dem.crs.to_wkt())
    ell = pcrs.ellipsoid
    if ell is not None and not (EARTH_A_RANGE[0] <= ell.semi_major_metre <= EARTH_A_RANGE[1]):
        raise HillshadeError(
            f"{dem.path}: its CRS is on {ell.name} (a = {ell.semi_major_metre / 1000:.1f} km), not "
            "the Earth; " + (other_body or OTHER_BODY_ADVICE))
    geo = pcrs.geodetic_crs
    fwd = Transformer.from_crs(pcrs, geo, always_xy=True)
    back = Transformer.from_crs(geo, pcrs, always_xy=True)
    tr = dem.transform

    def to_lonlat(rows, cols):
        rows = np.asarray(rows, np.float64)
        cols = np.asarray(cols, np.float64)
        x = tr.c + tr.a * (cols + 0.5)
        y = tr.f + tr.e * (rows + 0.5)
        lo, la = fwd.transform(x, y)
        return np.asarray(lo, np.float64), np.asarray(la, np.float64)

    def convergence(rows, cols):
        """Grid azimuth (degrees clockwise from the raster's north) of true north."""
        if pcrs.is_geographic:
            return np.zeros(np.broadcast(np.asarray(rows), np.asarray(cols)).shape)
        lo, la = to_lonlat(rows, cols)
        dlat = 1e-4 * np.where(la > 89.0, -1.0, 1.0)
        x0, y0 = back.transform(lo, la)
        x1, y1 = back.transform(lo, la + dlat)
        dx = (np.asarray(x1) - np.asarray(x0)) * np.sign(dlat)
        dy = (np.asarray(y1) - np.asarray(y0)) * np.sign(dlat)
        return np.degrees(np.arctan2(dx, dy))

    rows, cols = dem.shape
    lo, la = to_lonlat(np.array([(rows - 1) / 2.0]), np.array([(cols - 1) / 2.0]))
    if not (np.isfinite(lo[0]) and np.isfinite(la[0])):
        raise HillshadeError(f"{dem.path}: its centre does not map to a longitude/latitude")
    return Site(float(la[0]), float((lo[0] + 180.0) % 360.0 - 180.0), height,
                "the DEM's centre", to_lonlat, convergence, notes=[f"observer height: {hnote}"])
