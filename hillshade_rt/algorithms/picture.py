"""Pictures of a window in one pass (``hillshade-rt view``): the relief's brightness from the
sun's incidence on surface gradients computed once (``gradients``, Horn's method [1]_ as
``relief.incidence``), a two-colour mix by a 0..1 value per cell (shadow, sun hours), voids and
pixels outside the raster transparent, each pixel taking its cell (nearest): the colour
arithmetic, the incidence and the resampling fused, parallel over the picture's rows (numpy's
temporaries and a separate incidence pass took 4-8x longer on a 1024² view).

References
----------
.. [1] B. K. P. Horn, "Hill shading and the reflectance map," Proc. IEEE, vol. 69, no. 1,
       pp. 14-47, 1981. :doi:`10.1109/PROC.1981.11918`
"""

import math

import numpy as np
from numba import prange

from ._jitcache import njit
from .relief import horn_gradient


@njit(cache=True, parallel=True)
def gradients(z, dx, dy, csign, rsign, r0, c0, ge, gn):
    """(dz/d(east), dz/d(north)) of the cells of ``z`` from row ``r0``, column ``c0`` into
    ``ge``, ``gn`` (float32, their shape; NaN on voids): ``relief.horn_gradient``."""
    for i in prange(ge.shape[0]):
        r = r0 + i
        for j in range(ge.shape[1]):
            c = c0 + j
            if math.isnan(z[r, c]):
                ge[i, j] = np.nan
                gn[i, j] = np.nan
                continue
            a, b = horn_gradient(z, r, c, dx[r], dy[r], csign, rsign)
            ge[i, j] = a
            gn[i, j] = b


@njit(cache=True, parallel=True)
def rgba(ge, gn, g_r0, g_c0, value, v_r0, v_c0, is_mask, ri, ci, lx, ly, lz, low, high, out):
    """Fill ``out`` (h, w, 4 uint8): pixel (i, j) shows cell (ri[i], ci[j]) of the raster (-1:
    outside it, transparent). ``ge``, ``gn`` hold the gradients of the cells from (g_r0, g_c0)
    (NaN: a void, transparent), ``value`` the 0..1 value of the cells from (v_r0, v_c0) (NaN as
    0; ``is_mask``: a uint8 mask, 1 -> 1, anything else 0). Brightness g = 0.25 + 0.75 *
    clamp(cos i, 0, 1) for the sun (lx, ly, lz); colour g * (low * (1 - v) + high * v)."""
    h, w = out.shape[0], out.shape[1]
    for i in prange(h):
        k = ri[i]
        for j in range(w):
            m = ci[j]
            a = np.nan
            if k >= 0 and m >= 0:
                a = ge[k - g_r0, m - g_c0]
            if math.isnan(a):
                out[i, j, 0] = 0
                out[i, j, 1] = 0
                out[i, j, 2] = 0
                out[i, j, 3] = 0
                continue
            b = gn[k - g_r0, m - g_c0]
            c = (lz - a * lx - b * ly) / math.sqrt(1.0 + a * a + b * b)
            c = min(max(c, 0.0), 1.0)
            g = 0.25 + 0.75 * c
            v = float(value[k - v_r0, m - v_c0])
            if is_mask:
                v = 1.0 if v == 1.0 else 0.0
            elif math.isnan(v):
                v = 0.0
            for ch in range(3):
                x = g * (low[ch] * (1.0 - v) + high[ch] * v)
                x = min(max(x, 0.0), 1.0)
                out[i, j, ch] = np.uint8(math.floor(255.0 * x + 0.5))
            out[i, j, 3] = 255
