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


@njit(cache=True, inline="always")
def _lit_cos(lit, cast, use_cast, ge, gn, length, suns, from_normals, tr, tc, r, c):
    """The direct beam's factor at cell (r, c) (float32): max(cos i, 0) (the incidence from the
    Horn normals and the tile's sun ``suns[tr, tc]``) times lit (``cast`` 0: lit, else the soft
    fraction ``lit``), or ``lit`` alone without normals."""
    zero = np.float32(0.0)
    if not from_normals:
        return lit[r, c]
    s = suns[tr, tc]
    cosi = np.float32((s[2] - ge[r, c] * s[0] - gn[r, c] * s[1]) / length[r, c])
    if not (cosi >= zero or math.isnan(cosi)):
        cosi = zero
    if use_cast:
        return cosi * (np.float32(1.0) if cast[r, c] == 0 else zero)
    return cosi * lit[r, c]


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
    for r in prange(n_r):
        tr = row_tile[r]
        for c in range(n_c):
            d = zero
            if beam_on or circ_on:
                d = _lit_cos(lit, cast, use_cast, ge, gn, length, suns, from_normals,
                             tr, col_tile[c], r, c)
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


@njit(cache=True)
def _perez_bin(eps, bins):
    i = 0
    while i < bins.shape[0] and bins[i] <= eps:
        i += 1
    return i


@njit(parallel=True, cache=True)
def add_sample_cells(lit, cast, use_cast, ge, gn, length, row_tile, col_tile, suns,
                     from_normals, has_lit, w, sky, tl_on, tl, corr, ine, kb_on, kb, kb0,
                     kd_on, kd, kd0, perez, pz, table, bins, vd, sin_s, share, beam, diffuse,
                     ghi_sum):
    """Add one sample whose open sky differs from cell to cell into the sums ``beam``,
    ``diffuse`` and ``ghi_sum`` (float64, in place).

    The open sky of a cell: with ``tl_on`` Ineichen & Perez's clear sky for the cell's Linke
    turbidity ``tl`` (pvlib's ``clearsky.ineichen``, its operations in its order: ``ine`` the
    sample's absolute air mass, extraterrestrial irradiance, max(cos Z, 0), then the
    altitude's fh1, fh2, cg1, cg2 and b = 0.664 + 0.163 / fh1; ``corr`` the cell's
    1 - (0.1 - 0.2 exp(-TL)) / (0.1 + 0.882 / fh1)), else ``sky`` (GHI, DNI, DHI) of the sample.
    Then the clear-sky indices (r.sun's coeff_bh, coeff_dh): the cell's ``kb``/``kd`` (with
    ``kb_on``/``kd_on``) or the numbers ``kb0``/``kd0``: DNI · kb, DHI · kd, and the global
    horizontal kb · GHI where kb = kd, else kb · (GHI - DHI) + kd · DHI.
    beam += w · (float32(DNI) · max(cos i, 0) · lit) (``lit`` and the cell's cos i as
    ``add_sample``'s, with ``has_lit``); ghi_sum += w · GHI; isotropic (not ``perez``):
    diffuse += w · DHI; ``perez``: the cell's F1, F2 from its DNI and DHI as
    ``engine.irradiance.with_perez`` computes them (``pz``: the zenith (radians), 1.041 Z³, the
    relative air mass, the extraterrestrial irradiance, max(cos Z, cos 85°), 1 where the air
    mass is defined; ``table`` and ``bins`` Perez's coefficients and clearness bins), and
    diffuse += w · max(DHI · ((1 - F1) vd + F2 sin_s share + F1 / b · max(cos i, 0) lit), 0)
    (the circumsolar term where lit and F1 > 0)."""
    n_r, n_c = beam.shape
    zero = np.float32(0.0)
    am, extra, cosz, fh1, fh2, cg1, cg2, bb = (ine[0], ine[1], ine[2], ine[3], ine[4], ine[5],
                                               ine[6], ine[7])
    for r in prange(n_r):
        tr = row_tile[r]
        for c in range(n_c):
            if tl_on:
                t = tl[r, c]
                g = math.exp(-cg2 * am * (fh1 + fh2 * (t - 1.0)))
                if not g >= 0.0:
                    g = 0.0
                ghi = cg1 * extra * cosz * t / t * g
                bn = bb * math.exp(-0.09 * am * (t - 1.0))
                if not bn >= 0.0:
                    bn = 0.0
                bn = extra * bn
                b2 = corr[r, c] / cosz
                if not b2 >= 0.0:
                    b2 = 0.0
                if b2 > 1e20:
                    b2 = 1e20
                b2 = ghi * b2
                dni = bn if bn < b2 else b2
                dhi = ghi - dni * cosz
            else:
                ghi, dni, dhi = sky[0], sky[1], sky[2]
            kbv = kb[r, c] if kb_on else kb0
            kdv = kd[r, c] if kd_on else kd0
            if kbv == kdv:
                ghi = kbv * ghi
            else:
                ghi = kbv * (ghi - dhi) + kdv * dhi
            dni = kbv * dni
            dhi = kdv * dhi
            d = zero
            if has_lit:
                d = _lit_cos(lit, cast, use_cast, ge, gn, length, suns, from_normals,
                             tr, col_tile[c], r, c)
                b = np.float32(dni) * d
                beam[r, c] += w * np.float64(b)
            ghi_sum[r, c] += w * ghi
            if not perez:
                diffuse[r, c] += w * dhi
            elif pz[5] > 0.0 and dhi > 0.0:
                z = pz[0]
                kz3 = pz[1]
                delta = dhi * pz[2] / pz[3]
                eps = ((dhi + dni) / dhi + kz3) / (1.0 + kz3)
                i = _perez_bin(eps, bins)
                f1 = table[i, 0] + table[i, 1] * delta + table[i, 2] * z
                if not (f1 >= 0.0 or math.isnan(f1)):
                    f1 = 0.0
                f2 = table[i, 3] + table[i, 4] * delta + table[i, 5] * z
                t = (1.0 - f1) * vd[r, c] + f2 * sin_s[r, c] * share[r, c]
                if has_lit and f1 > 0.0:
                    t += (f1 / pz[4]) * np.float64(d)
                t = dhi * t
                if not (t >= 0.0 or math.isnan(t)):
                    t = 0.0
                diffuse[r, c] += w * t
