"""The maximum-height pyramid and the exact march that skips over it ("maximum mipmaps", Tevs,
Ihrke & Seidel 2008 [1]_, adapted to the terrain model of docs/model.md).

**The pyramid.** Level l (1 <= l <= ``nlev``) cuts the raster into blocks of 2^l x 2^l cells;
block (i, j) stores the highest valid height among the cells of rows ``[i*2^l, (i+1)*2^l]`` and
columns ``[j*2^l, (j+1)*2^l]`` (both ends included: one cell more than the block on the far
side of each axis). The extra cell covers the model's interpolation: a sample on a grid line at a
position whose lower neighbour ``floor(pos)`` lies in the block interpolates between that cell
and the next, which is either in the block or in its padding. So every sample whose grid line and
``floor(pos)`` lie in a block is at most the block's value. The values are rounded up by one
float32 step, which covers the float64 rounding of the interpolation. Voids are ignored (a void
never blocks a ray); a block of voids holds -inf. Built once per DEM in O(N), 4/3 bytes per cell
(level 0 is the DEM itself), in parallel.

**The march.** The ray's height grows with every step (``h0 + k*rise + k*k*curv``, rise > 0,
curv >= 0, and float rounding keeps that order). At its current sample the march climbs to the
coarsest level whose block there is lower than the ray: no sample inside that block can block the
ray, so it jumps to the first sample outside the block (the count of samples left in the block is
taken one short where rounding could matter). When even the finest block is not lower, it
samples the terrain exactly as the plain march (``raymath.ray_is_blocked``) does, with the same
arithmetic. Every sample it does not take is one that could not block, so the answer is the plain
march's, cell for cell (tests); it only skips work. The march handles per-row rays unchanged (the
pyramid is in raster coordinates, the ray's own geometry is used throughout).

The level to try first follows the last one that worked (one level up after a skip, down while a
block is not lower): along a clear ray the skips grow geometrically, near the terrain it is the
plain march plus one pyramid read per step.

References
----------
.. [1] A. Tevs, I. Ihrke, H.-P. Seidel, "Maximum mipmaps for fast, accurate, and scalable dynamic
       height field rendering," in Proc. 2008 Symp. on Interactive 3D Graphics and Games (I3D '08),
       pp. 183-190, 2008. :doi:`10.1145/1342250.1342279`
"""

import math

import numpy as np
from numba import prange

from ._jitcache import njit
from .raymath import line_position, madd, ray_origin, terrain_on_line

MAX_LEVELS = 15


class MaxPyramid:
    """The pyramid of one DEM, built at its first use (``args``): ``data`` (float32, all levels,
    flat), ``offsets`` (int64, start of level l at ``offsets[l]``), ``widths`` (int64, blocks per
    row of level l), ``nlev``. A caller can hand one to every method that might march
    (``engine.shader.Shader`` keeps one per raster); only a march pays for it, once."""

    __slots__ = ("_z", "_built", "shape")

    def __init__(self, z: np.ndarray):
        self._z, self._built, self.shape = z, None, z.shape

    @property
    def args(self):
        if self._built is None:
            data, off, widths, nlev = _build(self._z)
            self._built, self._z = (data, off, widths, np.int64(nlev)), None
        return self._built

    @property
    def nbytes(self) -> int:
        return int(self.args[0].nbytes)

    @property
    def built(self) -> bool:
        return self._built is not None

    def update(self, z: np.ndarray, bounds: tuple[int, int, int, int]):
        """Bring the pyramid up to date after the cells of ``bounds`` (r0, r1, c0, c1) of ``z``
        (the array it was made of, edited in place) changed: only the blocks over them are
        rebuilt, to the values a new build would give. Returns, per level, the flat range
        ``[start, stop)`` of ``data`` rewritten (an (nlev + 1) x 2 int64 array; row 0 unused), or
        None when the pyramid was not built yet (it will be built from the edited ``z``)."""
        if self._built is None:
            self._z = z
            return None
        data, off, widths, nlev = self._built
        r0, r1, c0, c1 = (int(v) for v in bounds)
        if r1 <= r0 or c1 <= c0:
            return np.zeros((int(nlev) + 1, 2), np.int64)
        return _patch(z, data, off, widths, nlev, r0, r1, c0, c1)


# what a few marches cost (ns on 2 cores, measured: docs/benchmarks.md): the pyramid's build
# per cell of the raster, and per cell whose ray grazes the terrain (the cells the bounds leave
# open march their whole reach) a plain step, or a march over the pyramid (about brute's longest)
BUILD_NS = 2.8
PLAIN_NS_PER_STEP = 0.4
PYRAMID_MARCH_NS = 68.0


def for_few(pyramid, count, cells: int, steps: float):
    """The pyramid to march ``count()`` grazing rays of ``steps`` steps over a raster of
    ``cells`` with: ``pyramid`` when it is built already (or False; ``count`` is then not
    called), else False where the plain march of those rays costs less than building it and
    marching over it (the bounds leave 0.3 % of New Zealand's 1 km DEM open at 3 deg: its
    pyramid took 4.5 ms, their plain march 0.2)."""
    if pyramid is False or pyramid is None or (isinstance(pyramid, MaxPyramid) and pyramid.built):
        return pyramid
    n = count()
    plain = n * steps * PLAIN_NS_PER_STEP
    return pyramid if plain > cells * BUILD_NS + n * PYRAMID_MARCH_NS else False


# the kernels' pyramid arguments for the plain march (nlev 0: no level to skip over)
NO_PYRAMID = (np.zeros(1, np.float32), np.zeros(2, np.int64), np.zeros(1, np.int64), np.int64(0))


def pyramid_args(z: np.ndarray, pyramid) -> tuple:
    """The kernels' pyramid arguments: ``pyramid`` False (or None) for the plain march, True for
    a new pyramid of ``z``, or a ``MaxPyramid`` to reuse (when it is of an array of z's shape;
    else a new one)."""
    if pyramid is False or pyramid is None:
        return NO_PYRAMID
    if isinstance(pyramid, MaxPyramid) and pyramid.shape == z.shape:
        return pyramid.args
    return MaxPyramid(z).args


@njit(cache=True)
def _levels(rows, cols):
    n = max(rows, cols)
    nlev = 0
    while (1 << (nlev + 1)) < n and nlev < MAX_LEVELS:
        nlev += 1
    return max(nlev, 1)


@njit(parallel=True, cache=True)
def _build(z):
    rows, cols = z.shape
    nlev = _levels(rows, cols)
    nr = np.zeros(nlev + 1, np.int64)
    nc = np.zeros(nlev + 1, np.int64)
    off = np.zeros(nlev + 2, np.int64)
    nr[0] = rows
    nc[0] = cols
    for lev in range(1, nlev + 1):
        nr[lev] = (rows - 1) // (1 << lev) + 1
        nc[lev] = (cols - 1) // (1 << lev) + 1
        off[lev + 1] = off[lev] + nr[lev] * nc[lev]
    data = np.empty(max(1, off[nlev + 1]), np.float32)
    w1 = nc[1]
    for i in prange(nr[1]):                  # level 1 from the heights: 3 x 3 cells per block
        for j in range(w1):
            m = np.float32(-np.inf)
            for a in range(2 * i, min(rows, 2 * i + 3)):
                for b in range(2 * j, min(cols, 2 * j + 3)):
                    v = z[a, b]
                    if v > m:                # NaN (void) compares false
                        m = v
            data[off[1] + i * w1 + j] = m
    for lev in range(2, nlev + 1):           # each level from the one below: 2 x 2 blocks
        o, p, pw, ph, w = off[lev], off[lev - 1], nc[lev - 1], nr[lev - 1], nc[lev]
        for i in prange(nr[lev]):
            for j in range(w):
                m = np.float32(-np.inf)
                for a in range(2 * i, min(ph, 2 * i + 2)):
                    for b in range(2 * j, min(pw, 2 * j + 2)):
                        v = data[p + a * pw + b]
                        if v > m:
                            m = v
                data[o + i * w + j] = m
    inf32 = np.float32(np.inf)
    for q in prange(data.size):   # up by one float32 step: covers float64 interpolation rounding
        data[q] = np.nextafter(data[q], inf32)
    return data, off, nc, nlev


@njit(cache=True)
def _patch(z, data, off, widths, nlev, r0, r1, c0, c1):
    """Rebuild the blocks of every level over cells [r0, r1) x [c0, c1) of ``z`` as ``_build``
    would: level 1 from the heights (3 x 3 cells, up one float32 step), the levels above from
    the rounded level below (max commutes with the monotone step up: the same values). Returns
    the flat ranges rewritten per level (see ``MaxPyramid.update``)."""
    rows, cols = z.shape
    inf32 = np.float32(np.inf)
    ranges = np.zeros((nlev + 1, 2), np.int64)
    # level-1 block i spans rows 2i .. 2i + 2: the blocks holding rows r0 .. r1 - 1
    i0, i1 = max(0, (r0 - 1) // 2), min((rows - 1) // 2, (r1 - 1) // 2)
    j0, j1 = max(0, (c0 - 1) // 2), min((cols - 1) // 2, (c1 - 1) // 2)
    w = widths[1]
    for i in range(i0, i1 + 1):
        for j in range(j0, j1 + 1):
            m = np.float32(-np.inf)
            for a in range(2 * i, min(rows, 2 * i + 3)):
                for b in range(2 * j, min(cols, 2 * j + 3)):
                    v = z[a, b]
                    if v > m:
                        m = v
            data[off[1] + i * w + j] = np.nextafter(m, inf32)
    ranges[1, 0] = off[1] + i0 * w
    ranges[1, 1] = off[1] + (i1 + 1) * w
    for lev in range(2, nlev + 1):
        o, p, pw, w = off[lev], off[lev - 1], widths[lev - 1], widths[lev]
        ph = (off[lev] - off[lev - 1]) // pw
        i0, i1, j0, j1 = i0 // 2, i1 // 2, j0 // 2, j1 // 2
        for i in range(i0, i1 + 1):
            for j in range(j0, j1 + 1):
                m = np.float32(-np.inf)
                for a in range(2 * i, min(ph, 2 * i + 2)):
                    for b in range(2 * j, min(pw, 2 * j + 2)):
                        v = data[p + a * pw + b]
                        if v > m:
                            m = v
                data[o + i * w + j] = m
        ranges[lev, 0] = o + i0 * w
        ranges[lev, 1] = o + (i1 + 1) * w
    return ranges


@njit(cache=True, inline="always")
def climb(pyr, off, widths, nlev, lev, rr, cc, hr):
    """The coarsest level, from one above ``lev``, whose block holding cell (rr, cc) is lower
    than ``hr`` (0: none is; take the sample)."""
    up = lev + 1 if lev < nlev else lev
    while up > 0 and not pyr[off[up] + (rr >> up) * widths[up] + (cc >> up)] < hr:
        up -= 1
    return up


@njit(cache=True, inline="always")
def samples_left(lev, line, i0, pos, step_dom, step_other):
    """How many more samples of the ray stay in the level-``lev`` block of its current sample
    (grid line ``line``, position ``pos``, ``i0`` = floor(pos)): exactly along the dominant axis,
    one short along the other where the position is within rounding of the block's edge."""
    size = np.int64(1) << lev
    within = line & (size - 1)
    left = (size - 1 - within) if step_dom > 0 else within
    start = (i0 >> lev) * size
    if step_other > 0.0:
        q = (float(start + size) - pos - 1e-7) / step_other
        if q < left:
            left = np.int64(q) if q > 0.0 else np.int64(0)
    elif step_other < 0.0:
        q = (pos - float(start) - 1e-7) / (-step_other)
        if q < left:
            left = np.int64(q) if q > 0.0 else np.int64(0)
    return left


@njit(cache=True)
def ray_is_blocked_pyramid(z, pyr, off, widths, nlev, r, c, dom_col, step_dom, step_other, rise,
                           curv, zmax, lift):
    """``raymath.ray_is_blocked`` with the pyramid ``(pyr, off, widths, nlev)`` of ``z``: the same
    answer (the ray starting ``lift`` metres above the cell), skipping every block lower than the
    ray (see the module's docstring)."""
    line0, other0, n_dom, n_oth = ray_origin(z, r, c, dom_col)
    h0 = float(z[np.int64(r), np.int64(c)]) + lift
    k = 1
    lev = 0
    while True:
        hr = madd(h0, float(k), rise)
        if curv != 0.0:
            hr = madd(hr, float(k * k), curv)
        if hr >= zmax:
            return False
        line = line0 + k * step_dom
        if line < 0 or line >= n_dom:
            return False
        pos = line_position(madd(float(other0), float(k), step_other), n_oth)
        if pos < 0.0:
            return False
        i0 = np.int64(math.floor(pos))
        lev = climb(pyr, off, widths, nlev, lev, i0 if dom_col else line,
                    line if dom_col else i0, hr)
        if lev == 0:
            if terrain_on_line(z, dom_col, line, pos) > hr:
                return True
            k += 1
        else:   # no sample in the block can block the ray: past it
            k += samples_left(lev, line, i0, pos, step_dom, step_other) + 1
