"""A DEM's CRS for people and reports: its EPSG code or WKT, and a name, made up from the
projection and the body it is on when the CRS has none."""

from __future__ import annotations

# bodies by their mean or equatorial radius (m), IAU / NASA figures; a sphere or ellipsoid within
# 0.2 % of one is named after it
_BODIES = {"the Moon": 1737400.0, "Mars": 3396190.0, "Mars (mean)": 3389500.0,
           "Mercury": 2439700.0, "Venus": 6051800.0, "Ceres": 469700.0, "Vesta": 262700.0,
           "Europa": 1560800.0, "Ganymede": 2631200.0, "Callisto": 2410300.0, "Titan": 2574730.0,
           "Io": 1821600.0, "Pluto": 1188300.0}


def body_name(a_m: float) -> str | None:
    """The body whose radius is ``a_m`` (within 0.2 %), the Earth for the semi-major axes of its
    ellipsoids (``sun.EARTH_A_RANGE``)."""
    from ..model.site import EARTH_A_RANGE
    if EARTH_A_RANGE[0] <= a_m <= EARTH_A_RANGE[1]:
        return "the Earth"
    for name, r in _BODIES.items():
        if abs(a_m - r) <= 0.002 * r:
            return name.replace(" (mean)", "")
    return None


def crs_string(crs) -> str | None:
    """``EPSG:n`` when the CRS has a code, else its WKT; None without a CRS."""
    if crs is None:
        return None
    epsg = crs.to_epsg()
    return f"EPSG:{epsg}" if epsg else crs.to_wkt()


def crs_name(crs) -> str | None:
    """A CRS's name for people: its own, or, for one without a name (``+proj=stere
    +R=1737400``), the projection and the body or ellipsoid it is on ("Polar Stereographic
    (variant A) on the Moon (sphere, R 1737400 m)")."""
    if crs is None:
        return None
    from pyproj import CRS as PCRS
    try:
        pcrs = PCRS.from_user_input(crs.to_wkt() if hasattr(crs, "to_wkt") else crs)
    except Exception:  # noqa: BLE001 -- a name is only for display
        return crs.to_string()
    if pcrs.name and pcrs.name.lower() not in ("unknown", "unnamed", ""):
        return pcrs.name
    op = pcrs.coordinate_operation
    what = (op.method_name if op is not None and op.method_name else
            "geographic (longitude, latitude)" if pcrs.is_geographic else "unnamed CRS")
    ell = pcrs.ellipsoid
    if ell is None:
        return what
    a = ell.semi_major_metre
    shape = (f"sphere, R {a:.0f} m" if not ell.inverse_flattening
             else f"ellipsoid a {a:.0f} m, 1/f {ell.inverse_flattening:g}")
    named = ell.name if ell.name and ell.name.lower() not in ("unknown", "unnamed") else None
    body = body_name(a)
    on = ", ".join(x for x in (named, shape) if x)
    return f"{what} on {body + ' (' + on + ')' if body else on}"
