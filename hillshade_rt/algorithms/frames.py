"""Octant mapping: views of a DEM in which the sun lies toward increasing line index.

The published algorithms fix the light's dominant axis and direction (Sakalauskas [1]_:
``L_v = 1``). Here every one of the eight octants is mapped onto that case with numpy *views* (a
transpose and reversed strides), never copies:

* canonical **lines** are the grid lines the rays cross one per step (rows or columns of the DEM),
  numbered so that the sun lies toward increasing line index;
* canonical **positions** run along a line, numbered so that a ray's position grows (``s >= 0``).

A ray from canonical cell ``(v0, p0)`` crosses line ``v0 + k`` at position ``p0 + k*s`` and rises
``k * rise``. ``Frame`` converts indices both ways; ``view(a)`` applies the same mapping to any
array of the DEM's shape (the heights, an output mask), so a kernel can write its result straight
into the caller's array.

References
----------
.. [1] T. Sakalauskas, "Hybrid Terrain Shadow Ray Casting," in WSCG 2008 Communication Papers, 16th
       Int. Conf. in Central Europe on Computer Graphics, Visualization and Computer Vision, Plzeň:
       UNION Agency, pp. 175-182, 2008.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.geometry import SunRays
from ._cuda import cuda, kernel
from ._jitcache import njit


@dataclass(frozen=True)
class Frame:
    dom_col: bool      # lines are columns of the DEM (rays step one column per step)
    flip_line: bool    # line index runs against the DEM index
    flip_pos: bool     # position index runs against the DEM index
    s: float           # position change per step, >= 0
    so: float          # the same in the DEM's own index direction (signed)
    sd: int            # dominant index change per step in the DEM (+1 / -1)
    rise: float        # height gained per step
    step_m: float      # ground metres per step

    def view(self, a: np.ndarray) -> np.ndarray:
        """``a`` (DEM-shaped) seen in canonical (line, position) order: a view, no copy."""
        v = a.T if self.dom_col else a
        if self.flip_line:
            v = v[::-1, :]
        if self.flip_pos:
            v = v[:, ::-1]
        return v


def uniform_rays(rays: SunRays) -> bool:
    """True when every row has the same ray (projected CRS, raw grids): the structures that the
    fast algorithms share between cells need one sun direction in pixel units."""
    return bool(np.all(rays.dom_col == rays.dom_col[0]) and np.all(rays.step_dom == rays.step_dom[0])
                and np.all(rays.step_other == rays.step_other[0])
                and np.all(rays.rise == rays.rise[0]))


def reach(shape: tuple[int, int], zrange: tuple[float, float], rays: SunRays) -> float:
    """The steps a ray takes to rise over the relief ``zrange`` (at most the raster's extent
    along the rays; inf for a sun at the zenith or below): what decides whether skipping over
    the maximum-height pyramid pays (``auto``, ``smap``)."""
    L = shape[1] if bool(rays.dom_col[len(rays.rise) // 2]) else shape[0]
    return steps_over(zrange[1] - zrange[0], float(np.min(rays.rise)), L)


def steps_over(span: float, rise: float, lines: int) -> float:
    """``reach`` of one ray rising ``rise`` per step over ``span`` of relief, across ``lines``
    lines of its dominant axis."""
    if not math.isfinite(rise) or rise <= 0:
        return math.inf
    return max(1.0, min(max(0.0, span) / rise, float(lines)))


def frame_of(rays: SunRays, row: int = 0) -> Frame:
    """The canonical frame of the rays of ``row`` (all rows when the rays are uniform)."""
    dom_col = bool(rays.dom_col[row])
    sd = int(rays.step_dom[row])
    so = float(rays.step_other[row])
    return Frame(dom_col=dom_col, flip_line=sd < 0, flip_pos=so < 0, s=abs(so), so=so, sd=sd,
                 rise=float(rays.rise[row]), step_m=float(rays.step_m[row]))


@njit(cache=True)
def dem_index(v, p, L, P, dom_col, flip_line, flip_pos):
    """(row, col) of the DEM cell at canonical (line v, position p) of an L x P canonical grid."""
    line = L - 1 - v if flip_line else v
    pos = P - 1 - p if flip_pos else p
    if dom_col:
        return pos, line
    return line, pos


@kernel
def canonical_copy_gpu(dem, can, dom_col, flip_line, flip_pos, to_canonical):
    """Copy between a DEM-shaped device array and its canonical-order twin ``can`` (L x P,
    contiguous): to_canonical ``can = Frame.view(dem)``, else the inverse."""
    p, v = cuda.grid(2)
    L, P = can.shape
    if v < L and p < P:
        r, c = dem_index(v, p, L, P, dom_col, flip_line, flip_pos)
        if to_canonical:
            can[v, p] = dem[r, c]
        else:
            dem[r, c] = can[v, p]


@kernel
def paste_gpu(dst, src, r0, c0):
    """``dst[r0:r0 + h, c0:c0 + w] = src`` on the device (``src`` h x w): a window of new
    heights uploaded on its own (``gpu.GpuDem.update``) put into place."""
    c, r = cuda.grid(2)
    if r < src.shape[0] and c < src.shape[1]:
        dst[r0 + r, c0 + c] = src[r, c]
