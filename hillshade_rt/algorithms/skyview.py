"""What a cell's horizons in N directions add up to (the definitions: ``run.skyview``'s
docstring and docs/skyview.md): Zakšek's sky view factor 1 - mean sin γ [1]_, Dozier & Frew's
cosine-weighted view from the tilted surface [2]_ [3]_, and Yokoyama's positive and negative
openness [4]_.

One function per definition adds one direction's horizon angles to a running sum, cell by cell
(numba: the same scalar arithmetic whatever the array's shape, so a window of a raster gets the
bits a run in memory gives its cells); :class:`Sum` holds the sums of a raster or of one window
and says the result. One direction's angles are in memory at a time.

References
----------
.. [1] K. Zakšek, K. Oštir, Ž. Kokalj, "Sky-View Factor as a Relief Visualization Technique,"
       Remote Sensing, vol. 3, no. 2, pp. 398-415, 2011. :doi:`10.3390/rs3020398`
.. [2] J. Dozier, J. Frew, "Rapid calculation of terrain parameters for radiation modeling from
       digital elevation data," IEEE Trans. Geosci. Remote Sens., vol. 28, no. 5, pp. 963-969,
       1990. :doi:`10.1109/36.58986`
.. [3] J. Dozier, "Revisiting Topographic Horizons in the Era of Big Data and Parallel Computing,"
       IEEE Geosci. Remote Sens. Lett., vol. 19, art. 8024605, 2022.
       :doi:`10.1109/LGRS.2021.3125278`
.. [4] R. Yokoyama, M. Shirasawa, R. J. Pike, "Visualizing topography by openness: A new
       application of image processing to digital elevation models," Photogramm. Eng. Remote Sens.,
       vol. 68, no. 3, pp. 257-265, 2002.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ._jitcache import njit

DEFINITIONS = ("zaksek", "dozier")          # --definition: sky view factors (0..1)
OPENNESS = ("positive", "negative")         # --openness: degrees


def definition_of(definition: str = "zaksek", openness: str | None = None) -> str:
    """The definition's name: ``definition`` (a sky view factor) or, with ``openness``,
    "openness-positive" / "openness-negative"."""
    from ..errors import HillshadeError
    if openness is not None:
        if openness not in OPENNESS:
            raise HillshadeError(f"openness must be one of {', '.join(OPENNESS)}, got "
                                 f"{openness!r}")
        return f"openness-{openness}"
    if definition not in DEFINITIONS:
        raise HillshadeError(f"definition must be one of {', '.join(DEFINITIONS)}, got "
                             f"{definition!r}")
    return definition


def inverted(definition: str) -> bool:
    """Whether the definition wants the horizons of the inverted terrain (-z): negative
    openness looks down, at the lowest terrain."""
    return definition == "openness-negative"


def floor_deg(definition: str) -> float | None:
    """The floor of the horizon scan a definition can take (``horizon.horizon_angles``'
    ``floor_deg``): 0 for the sky view factors, which read the horizon clipped at the
    horizontal (a scan that starts its maximum at 0 skips every block below the cell from the
    first step, and returns the same angle bits wherever the horizon is above the horizontal:
    the sky view factors' bits unchanged, 1.1-1.4x faster on real DEMs and fractals); None
    for openness, which reads negative angles."""
    return 0.0 if definition in DEFINITIONS else None


def units(definition: str) -> str:
    return ("degrees (mean over the directions)" if definition.startswith("openness")
            else "fraction 0..1")


# -- one function per definition: one direction's angles (degrees, float32: NaN on voids, -90
#    with nothing ahead) added to the sums ------------------------------------------------------

@njit(parallel=True, cache=True)
def zaksek(beta, acc):
    """Zakšek et al. 2011 (RVT, HORAYZON's sky view factor): adds sin γ, γ the horizon clipped
    at the horizontal (terrain below it hides no sky); the result is 1 - mean."""
    rows, cols = beta.shape
    for i in prange(rows):
        for j in range(cols):
            b = float(beta[i, j])
            if math.isnan(b):
                acc[i, j] = np.nan
            elif b > 0.0:
                acc[i, j] += math.sin(math.radians(b))


@njit(parallel=True, cache=True)
def dozier(beta, cos_s, sc, acc):
    """Dozier & Frew 1990 (Dozier 2022's Vd): adds cos S sin² H + sin S cos(φ - A) (H - sin H
    cos H), H = 90° - γ the horizon's zenith angle (γ clipped at the horizontal), ``cos_s`` the
    cell's cos S, ``sc`` its sin S cos(φ - A) (the incidence of a sun on the horizon at the
    direction's azimuth φ); the result is the mean."""
    rows, cols = beta.shape
    for i in prange(rows):
        for j in range(cols):
            b = float(beta[i, j])
            if math.isnan(b):
                acc[i, j] = np.nan
                continue
            g = math.radians(b) if b > 0.0 else 0.0
            h = math.pi / 2.0 - g
            acc[i, j] += cos_s[i, j] * math.cos(g) ** 2 + float(sc[i, j]) * (
                h - math.sin(h) * math.cos(h))


@njit(parallel=True, cache=True)
def openness(beta, acc, count):
    """Yokoyama, Shirasawa & Pike 2002: adds the horizon's zenith angle 90° - β (β not clipped:
    a cell that looks down has a horizon below the horizontal) over the directions with terrain
    ahead (within the maximum distance); the result is the mean over those. Negative openness
    is the same sum over the horizons of the inverted terrain (90° - β(-z) = 90° + the angle
    down to the lowest terrain)."""
    rows, cols = beta.shape
    for i in prange(rows):
        for j in range(cols):
            b = float(beta[i, j])
            if b != -90.0 and not math.isnan(b):
                acc[i, j] += 90.0 - b
                count[i, j] += 1


@njit(parallel=True, cache=True)
def _mean(acc, count, out):
    rows, cols = acc.shape
    for i in prange(rows):
        for j in range(cols):
            out[i, j] = acc[i, j] / count[i, j] if count[i, j] > 0 else np.nan


class Sum:
    """The running sums of one definition over a raster or a window's region.

    ``z`` and ``grid``: heights (and their grid) around the cells, ``rows``/``cols`` the cells'
    place in ``z`` (the whole of it in memory; a window's region, with a cell of margin, in
    windows): Dozier's definition takes the cells' slope and aspect from Horn's normals there.
    :meth:`add` one direction's angles of the cells, then :meth:`result`. ``normals``: Horn's
    normals of the whole of ``z`` (``irradiance.normals``, computed once by the caller, which
    reuses them), read instead of the heights for the incidences (the same values)."""

    def __init__(self, definition: str, z: np.ndarray, grid, rows: slice = slice(None),
                 cols: slice = slice(None), normals=None):
        r0, r1, _ = rows.indices(z.shape[0])
        c0, c1, _ = cols.indices(z.shape[1])
        self.definition, self.z, self.grid, self.rows, self.cols = definition, z, grid, rows, cols
        whole = (r0, r1, c0, c1) == (0, z.shape[0], 0, z.shape[1])
        self.normals = normals if whole else None
        self.shape = (r1 - r0, c1 - c0)
        self.acc = np.zeros(self.shape, np.float64)
        self.count = np.zeros(self.shape, np.int32) if definition.startswith("openness") else None
        self.cos_s = None
        if definition == "dozier":
            self.cos_s = self._incidence(0.0, 90.0).astype(np.float64)
        self.n = 0

    def add(self, azimuth: float, beta: np.ndarray) -> None:
        """The cells' horizon angles toward ``azimuth`` (float32 degrees, NaN on voids, -90
        with nothing ahead; of -z for negative openness)."""
        d = self.definition
        if d == "zaksek":
            zaksek(beta, self.acc)
        elif d == "dozier":
            # sin S cos(φ - A): the normal's horizontal part along φ (incidence of a sun on
            # the horizon at azimuth φ)
            dozier(beta, self.cos_s, self._incidence(azimuth, 0.0), self.acc)
        else:
            openness(beta, self.acc, self.count)
        self.n += 1

    def _incidence(self, azimuth: float, elevation: float) -> np.ndarray:
        """``relief.incidence`` of the cells, from the normals when the caller gave them."""
        from .relief import incidence, sun_vector
        if self.normals is not None:
            from .irradiance import incidence_of
            return incidence_of(self.normals, *sun_vector(azimuth, elevation))
        return incidence(self.z, self.grid, azimuth, elevation, self.rows, self.cols)

    def result(self) -> np.ndarray:
        """float32: the sky view factor (0..1) or the openness (degrees); NaN on voids and,
        for openness, where no direction has terrain ahead."""
        if self.count is not None:
            out = np.empty(self.shape, np.float64)
            _mean(self.acc, self.count, out)
            return out.astype(np.float32)
        out = self.acc / self.n
        if self.definition == "zaksek":
            out = 1.0 - out
        return out.astype(np.float32)


def sky_view(z, grid, azimuths, angles_of, definition: str, normals=None) -> np.ndarray:
    """The definition's result over the whole raster ``z`` (float32, NaN on voids) from
    ``angles_of(azimuth)`` (horizon elevation in degrees per cell, NaN on voids, -90 with
    nothing ahead; of -z for negative openness) at each azimuth; ``normals`` as
    :class:`Sum`'s."""
    s = Sum(definition, z, grid, normals=normals)
    for a in azimuths:
        s.add(a, angles_of(a))
    return s.result()
