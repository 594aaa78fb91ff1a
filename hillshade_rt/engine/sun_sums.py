"""Sums over many suns of rasters larger than memory: each cell's weighted sum of what each sun
makes of it (``sun-hours``: the lit mask of every sample times its hours), window by window, with
the bits of a run in memory.

A run in memory adds the suns one after the other over the whole raster (``hours += w * lit``,
float32). Here the output is cut into *regions*, and each region makes the same sums in the same
order of the suns, so every cell gets the same float32 additions in the same order: the same
bits. Each sun's piece of a region is lit by the windowed shadow machinery
(``windows.WindowLighting.pieces``: the region and its halo toward that sun, from the statistics
pass's block ranges; ``WindowLighting.light``).

**Reading the DEM once.** The suns of a region are lit in *groups*: contiguous runs of suns (in
their order) whose windows together fit in memory. A group's windows are read once, as their
union, and every sun of the group is lit in it; consecutive unions share cells, which the
``windows.WindowCache`` copies instead of reading again. When the whole day's windows of a region
fit, the region is read once for every sun, and the DEM about once for the run (plus the halos
around the regions): a pass per sun would read it once per sun, and would need the sum of the
whole raster (as large as the DEM) kept between passes. Only where the halos of low suns are
too long for one window do the suns of a region split into several groups (at worst one per
sun, what a pass per sun reads).

The regions' shape (:func:`region_shape`) is the one whose groups read the fewest cells by the
halo bounds every window plan uses (the raster's height range), within the memory given;
``--window-size`` gives it instead.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .windows import MIN_WINDOW_CELLS, MemoryTooSmall, PlannedWindow

# bytes per cell of a group's window beyond what lighting a window needs
# (``windows.bytes_per_cell``): the group's heights held while each sun's piece is lit, that
# piece's own copy of them, the region's float32 sum
BYTES_PER_GROUP_CELL = 12
SMALLEST_SIDE = 64      # the smallest region side tried (then 128, 256, ...: aligned writes)


@dataclass(frozen=True)
class SunGroup:
    """Suns lit from one read: ``window`` (r0, r1, c0, c1), the union of their pieces'
    windows, and the pieces ``((i, piece), ...)``, ``i`` the sun's index, in the suns' order."""

    window: tuple
    pieces: tuple

    @property
    def cells(self) -> int:
        r0, r1, c0, c1 = self.window
        return (r1 - r0) * (c1 - c0)


@dataclass(frozen=True)
class RegionSuns:
    """One region of the output (r0, r1, c0, c1) and its groups of suns, in order (picklable:
    a Dask task gets one)."""

    region: tuple
    groups: tuple

    @property
    def pieces(self) -> int:
        return sum(len(g.pieces) for g in self.groups)


def _union(a, b):
    if a is None:
        return b
    return min(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), max(a[3], b[3])


def _cells(w) -> int:
    return (w[1] - w[0]) * (w[3] - w[2])


# ---------------------------------------------------------------------------------------------
# the regions' shape

def _sides(grid, azimuth: float, reach: float, rows: tuple, margin: int = 1) -> tuple:
    """(up, down, left, right): cells a window adds to its region on each side for a sun at
    ``azimuth`` whose halo reaches ``reach`` metres (as ``shader.halo_bounds`` grows it, before
    clipping to the raster; the smallest spacing of ``rows``)."""
    east = math.sin(math.radians(azimuth)) * grid.col_sign
    north = math.cos(math.radians(azimuth)) * grid.row_sign

    def grow(comp, spacing):
        if abs(comp) < 1e-12:
            return 2 + margin, 2 + margin
        more = (1 << 62) if not math.isfinite(reach) else int(math.ceil(reach * abs(comp)
                                                                        / spacing)) + 2
        return (margin, more + margin) if comp > 0 else (more + margin, margin)
    up, down = grow(north, float(np.min(grid.dy[rows[0]:rows[1]])))
    left, right = grow(east, float(np.min(grid.dx[rows[0]:rows[1]])))
    return up, down, left, right


def sun_sides(job, sun, stats, bounds) -> tuple:
    """The largest (up, down, left, right) halo of ``sun``'s windows over ``bounds``, from the
    raster's height range (the bound ``windows.plan`` sizes windows by), as
    ``WindowLighting.pieces`` makes them (the disk's lower edge when soft, the lowest and
    outermost suns of a sun per cell, the lift)."""
    from .shader import reach_m
    from ..model.solar import SUN_RADIUS_DEG
    shape = job.source.shape
    out = [0, 0, 0, 0]
    for reg in sun.regions(shape):
        el = reg.elevation
        night, hel = (el + SUN_RADIUS_DEG <= 0, el - SUN_RADIUS_DEG) if job.soft else \
            (el <= 0, el)
        azimuths = [reg.azimuth]
        if sun.fieldwise:
            lo, hi, el_lo = sun.lattice_span(shape, bounds, reg.azimuth)
            night, hel, azimuths = False, min(hel, el_lo), [reg.azimuth, lo, hi]
        if night:
            reach = 0.0
        else:
            curv = job.curv(reg.azimuth, max(min(el, 90.0), 1e-6))
            reach = reach_m(stats.zmax - (stats.zmin + job.lift), hel, curv)
        for az in azimuths:
            s = _sides(job.source.grid, az, reach, (bounds[0], bounds[1]), 2)
            out = [max(a, b) for a, b in zip(out, s)]
    return tuple(out)


def _sizes(n: int) -> list[int]:
    """Region sides tried along an axis of ``n`` cells: all of it, or 64, 128, 256, ..."""
    out, s = {n}, SMALLEST_SIDE
    while s < n:
        out.add(s)
        s *= 2
    return sorted(out)


def _cost(tr, tc, sides, shape, budget):
    """(cells read, windows read) of regions of ``tr`` x ``tc`` cells by the halo bounds
    ``sides`` (one per sun, in order), the suns grouped as :func:`plan_regions` groups them;
    None when one sun's window alone would not fit ``budget`` cells."""
    rows, cols = shape
    total, reads, cur = 0, 0, None

    def cells(u):
        return min(rows, tr + u[0] + u[1]) * min(cols, tc + u[2] + u[3])
    for s in sides:
        if cells(s) > budget:
            return None
        nxt = s if cur is None else tuple(max(a, b) for a, b in zip(cur, s))
        if cells(nxt) > budget:
            total, reads, nxt = total + cells(cur), reads + 1, s
        cur = nxt
    if cur is not None:
        total, reads = total + cells(cur), reads + 1
    return total, reads


def region_shape(job, suns, stats, budget_cells: int, bounds) -> tuple[int, int]:
    """The regions' (rows, columns) that read the fewest cells (then the fewest windows) with
    every group's windows within ``budget_cells`` (:func:`_cost`). Raises
    ``windows.MemoryTooSmall`` (with the fewest cells that would do) when no shape fits one
    sun's window."""
    b = bounds
    br, bc = b[1] - b[0], b[3] - b[2]
    # no sun with light: each region is read once for its voids (a window without a halo)
    sides = [sun_sides(job, s, stats, b) for s in suns] or [(0, 0, 0, 0)]
    best, need = None, None
    for tr in _sizes(br):
        for tc in _sizes(bc):
            c = _cost(tr, tc, sides, job.source.shape, budget_cells)
            if c is None:
                rows, cols = job.source.shape
                one = max((min(rows, tr + s[0] + s[1]) * min(cols, tc + s[2] + s[3])
                           for s in sides), default=0)
                need = one if need is None else min(need, one)
                continue
            n = -(-br // tr) * -(-bc // tc)
            key = (n * c[0], n * c[1])
            if best is None or key < best[0]:
                best = (key, tr, tc)
    if best is None:
        raise MemoryTooSmall(
            f"the memory limit allows windows of {budget_cells:,} cells, but a window with the "
            f"halo of the lowest sun needs at least {need:,} here: raise --max-memory",
            max(need, MIN_WINDOW_CELLS))
    return best[1], best[2]


# ---------------------------------------------------------------------------------------------
# the plan: regions, their suns in groups

def plan_regions(job, suns, stats, budget_cells: int, window_shape=None,
                 bounds=None) -> list[RegionSuns]:
    """The regions of ``bounds`` (default: the raster), row by row, each with its suns' pieces
    (``WindowLighting.pieces`` of the region: per-tile suns cut to their tiles) in groups of
    contiguous suns whose windows' union holds at most ``budget_cells`` cells (a sun whose
    windows alone hold more, with ``window_shape``, is a group of its own). The regions are
    ``window_shape`` (--window-size) or :func:`region_shape`'s. A region without suns has one
    group without pieces: its window is the region (its voids make the sum's NaN)."""
    shape = job.source.shape
    b = bounds or (0, shape[0], 0, shape[1])
    tr, tc = (window_shape if window_shape is not None
              else region_shape(job, suns, stats, budget_cells, b))
    out = []
    for r0 in range(b[0], b[1], tr):
        for c0 in range(b[2], b[3], tc):
            reg = (r0, min(b[1], r0 + tr), c0, min(b[3], c0 + tc))
            rs = (reg[1] - reg[0], reg[3] - reg[2])
            groups, win, pcs = [], None, []
            for i, s in enumerate(suns):
                ps = job.pieces(s, stats, budget_cells, rs, in_order=False, area=reg)
                w = None
                for p in ps:
                    w = _union(w, p.window)
                if w is None:
                    continue
                both = _union(win, w)
                if pcs and _cells(both) > budget_cells:
                    groups.append(SunGroup(win, tuple(pcs)))
                    both, pcs = w, []
                win = both
                pcs += [(i, p) for p in ps]
            if pcs:
                groups.append(SunGroup(win, tuple(pcs)))
            if not groups:
                groups.append(SunGroup(reg, ()))
            out.append(RegionSuns(reg, tuple(groups)))
    return out


# ---------------------------------------------------------------------------------------------
# the sums

def weighted_light(job, weights, stats: dict | None = None, used: set | None = None):
    """The term of sun-hours: ``np.float32(weights[i])`` times the sun's product over the
    piece's region (``job.light``; "sun": 1 lit, 0 not, NaN voids), as a run in memory adds it."""
    def term(i: int, piece: PlannedWindow, z: np.ndarray) -> np.ndarray:
        return np.float32(weights[i]) * job.light(z, piece, stats, used)
    return term


def sun_pieces(get, rs: RegionSuns):
    """Each sun of ``rs`` in order with its pieces' heights: ``(i, pieces)``, ``i`` the sun's
    index, ``pieces`` an iterator of ``(piece, z)``, ``z`` the heights of the piece's window
    (a C-contiguous copy, made as it is reached: use it before the next sun); each group's
    window read once, when its first sun is reached (``get`` as :func:`region_sum`'s). For a
    caller that takes the suns one at a time (irradiance's sums: ``run.irradiance_windows``)."""
    def heights(zg, w0, v0, pieces):
        for _, p in pieces:
            a0, a1, b0, b1 = p.window
            yield p, np.ascontiguousarray(zg[a0 - w0:a1 - w0, b0 - v0:b1 - v0])
    for g in rs.groups:
        w0, _, v0, _ = g.window
        zg = get(g.window)
        k = 0
        while k < len(g.pieces):
            j = k
            while j < len(g.pieces) and g.pieces[j][0] == g.pieces[k][0]:
                j += 1
            yield g.pieces[k][0], heights(zg, w0, v0, g.pieces[k:j])
            k = j
        del zg


def region_sum(get, rs: RegionSuns, term, on_piece=None) -> np.ndarray:
    """The sum over the suns of ``rs`` of ``term(i, piece, z)`` (float32, the piece's region's
    shape; ``z`` the heights of the piece's window, C-contiguous), over the region: float32,
    NaN on voids, 0 elsewhere before the first sun, the terms added in the suns' order.
    ``get(window)`` reads a window's heights (``windows.WindowCache.get``: what consecutive
    windows share is copied, not read again); ``on_piece(piece)`` after each piece (figures,
    progress)."""
    return region_sums(get, rs, term, on_piece)[0]


def region_sums(get, rs: RegionSuns, term, on_piece=None, group_of=None,
                groups: int = 0) -> tuple[np.ndarray, list]:
    """(:func:`region_sum`'s sum, and with ``group_of`` (each sun's group, 0..``groups`` - 1:
    e.g. its month) each group's own sum of the same terms, float32, NaN on voids, in the
    suns' order): every term added to the total and to its group's sum, as a run in memory
    adds each sun's term to both (``sun-hours --monthly``)."""
    r0, r1, c0, c1 = rs.region
    acc, per = None, []
    for g in rs.groups:
        w0, _, v0, _ = g.window
        zg = get(g.window)
        if acc is None:
            acc = np.where(np.isnan(zg[r0 - w0:r1 - w0, c0 - v0:c1 - v0]), np.float32(np.nan),
                           np.float32(0.0))
            per = [acc.copy() for _ in range(groups if group_of is not None else 0)]
        for i, p in g.pieces:
            a0, a1, b0, b1 = p.window
            z = np.ascontiguousarray(zg[a0 - w0:a1 - w0, b0 - v0:b1 - v0])
            g0, g1, h0, h1 = p.region
            t = term(i, p, z)
            at = (slice(g0 - r0, g1 - r0), slice(h0 - c0, h1 - c0))
            acc[at] += t
            if per:
                per[group_of[i]][at] += t
            del z, t
            if on_piece is not None:
                on_piece(p)
    return acc, per
