"""The irradiance run's per-cell arithmetic (``engine.irradiance``) in place: Horn's normals of
the DEM once, the incidence of any sun on them, and one sample's beam and Perez diffuse light
added into the float64 sums, without numpy's temporaries.

Every value is the one the numpy expressions of ``engine.irradiance.sums`` and
``relief.incidence`` give, bit for bit: the same operations on the same types in the same order
(no fastmath: numba keeps IEEE order, no contraction into fused multiply-adds). The normals keep
Horn's gradients (float64) and the length of (-ge, -gn, 1), so that cos i = (lz - ge lx -
gn ly) / length is ``relief.incidence``'s expression; max(cos i, 0) propagates NaN (voids) as
``numpy.maximum`` does.

References
----------
.. [1] B. K. P. Horn, "Hill shading and the reflectance map," Proc. IEEE, vol. 69, no. 1,
       pp. 14-47, 1981. :doi:`10.1109/PROC.1981.11918`
.. [2] R. Perez, P. Ineichen, R. Seals, J. Michalsky, R. Stewart, "Modeling daylight availability
       and irradiance components from direct and global irradiance," Solar Energy, vol. 44, no. 5,
       pp. 271-289, 1990. :doi:`10.1016/0038-092X(90)90055-H`
"""

import math

import numpy as np
from numba import prange

from ._jitcache import njit
from .relief import horn_gradient


@njit(parallel=True, cache=True)
def _normals(z, dx, dy, csign, rsign, ge, gn, length):
    n_r, n_c = z.shape
    for r in prange(n_r):
        for c in range(n_c):
            if math.isnan(z[r, c]):
                ge[r, c] = np.nan
                gn[r, c] = np.nan
                length[r, c] = np.nan
                continue
            a, b = horn_gradient(z, r, c, dx[r], dy[r], csign, rsign)
            ge[r, c] = a
            gn[r, c] = b
            length[r, c] = math.sqrt(1.0 + a * a + b * b)


def normals(z: np.ndarray, grid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ge, gn, length): Horn's dz/d(east), dz/d(north) of every cell of ``z`` and the length
    of (-ge, -gn, 1), float64, NaN on voids (``relief.horn_gradient``: edges and voids as
    there)."""
    ge = np.empty(z.shape, np.float64)
    gn = np.empty(z.shape, np.float64)
    length = np.empty(z.shape, np.float64)
    _normals(z, grid.dx, grid.dy, float(grid.col_sign), float(grid.row_sign), ge, gn, length)
    return ge, gn, length


@njit(parallel=True, cache=True)
def _incidence_of(ge, gn, length, lx, ly, lz, out):
    n_r, n_c = out.shape
    for r in prange(n_r):
        for c in range(n_c):
            out[r, c] = (lz - ge[r, c] * lx - gn[r, c] * ly) / length[r, c]


def incidence_of(nrm: tuple, lx: float, ly: float, lz: float) -> np.ndarray:
    """cos i (float32, NaN voids) of the sun (``relief.sun_vector``'s lx, ly, lz) on the
    normals ``nrm`` (:func:`normals`): ``relief.incidence``'s values."""
    out = np.empty(nrm[0].shape, np.float32)
    _incidence_of(nrm[0], nrm[1], nrm[2], lx, ly, lz, out)
    return out


@njit(parallel=True, cache=True)
def add_sample(lit, cast, use_cast, ge, gn, length, row_tile, col_tile, suns, from_normals,
               beam_on, dni, w, beam, diffuse_on, circ_on, f1, circ, f2, dhi, vd, sin_s, share,
               diffuse):
    """Add one sample into the sums ``beam`` and ``diffuse`` (float64, in place).

    ``lit`` (float32): with ``from_normals`` the cast-shadow light (the disk's fraction, or
    with ``use_cast`` 1 where the hard mask ``cast`` (uint8) is 0, else 0: ``render``'s "sun"
    light, the voids NaN through cos i), each cell's cos i from the normals (``ge``, ``gn``,
    ``length``) and the sun of its tile (``suns[row_tile[r], col_tile[c]]``: lx, ly, lz); else
    max(cos i, 0) · lit itself. ``beam_on``: beam += w · (dni · max(cos i, 0) · lit), ``dni``
    float32.
    ``diffuse_on`` (Perez): d = (1 - f1) · vd + f2 · sin_s · share, plus ``circ`` ·
    max(cos i, 0) · lit with ``circ_on`` (circ = f1 / b); diffuse += w · max(dhi · d, 0)."""
    n_r, n_c = beam.shape
    zero = np.float32(0.0)
    one = np.float32(1.0)
    for r in prange(n_r):
        tr = row_tile[r]
        for c in range(n_c):
            d = zero
            if beam_on or circ_on:
                if from_normals:
                    s = suns[tr, col_tile[c]]
                    cosi = np.float32((s[2] - ge[r, c] * s[0] - gn[r, c] * s[1])
                                      / length[r, c])
                    if not (cosi >= zero or math.isnan(cosi)):
                        cosi = zero
                    if use_cast:
                        d = cosi * (one if cast[r, c] == 0 else zero)
                    else:
                        d = cosi * lit[r, c]
                else:
                    d = lit[r, c]
            if beam_on:
                b = dni * d
                beam[r, c] += w * np.float64(b)
            if diffuse_on:
                t = (1.0 - f1) * vd[r, c] + f2 * sin_s[r, c] * share[r, c]
                if circ_on:
                    t += circ * np.float64(d)
                t = dhi * t
                if not (t >= 0.0 or math.isnan(t)):
                    t = 0.0
                diffuse[r, c] += w * t
