"""Rasters larger than memory: windows read and written through rasterio, each with only the halo
toward the sun that can shadow it.

The DEM is an ``io.DemSource`` (``io.open_dem``) read through its windowed reader: one file GDAL
reads, several files (or a VRT) shaded as one mosaic, or a raw grid (memory-mapped). Nothing
reads it whole.

1. **Statistics pass.** One streaming pass over the DEM gives the lowest and highest height of
   every ``STAT_BLOCK`` x ``STAT_BLOCK`` block (and the raster's range).
2. **Plan** (:func:`plan`). A ray leaving a cell at height ``z0`` toward a sun at elevation E has
   risen above every height ``zhigh`` after ``reach = (zhigh - z0) / tan E`` ground metres (less
   with Earth curvature: ``d tan E + c d^2 = zhigh - z0``; with ``--height-above-ground H`` the
   ray starts at ``z0 + H``: less again), so no terrain farther than that toward the sun can
   shadow the cell. A window is its output region plus that halo, **on the sun's side
   only** (two cells either side of an axis the sun does not move along), plus one cell all round
   for the surface normals of self-shadow and relief. ``z0`` is the lowest height of the blocks
   under the region, ``zhigh`` the highest of the blocks under the region and its halo, tightened
   until it stops shrinking (the halo is found from the raster's highest cell first). Regions are
   as large as ``--max-memory`` allows, shaped to waste the fewest halo cells: strips along the
   sun's direction have no halo along their length.
3. **Order and carry.** Windows run from the sun's side, so that the halo of a window is part of
   the window before it; the heights two consecutive windows share are carried over in memory,
   not read again.
4. Each window is lit by the same code as an in-memory run (``engine.shader.Shader`` with the whole
   raster's height range and extent, so Earth curvature decides alike), and its region written
   into the output, a GeoTIFF written through a temporary file (``io.raster.BandWriter``).

Because a window holds every cell whose terrain can shadow its region, the exact algorithms give
the region exactly what a run on the whole raster gives it (tests compare them cell for cell).
"""

from __future__ import annotations

import contextlib
import math
import os
import re
from dataclasses import dataclass, field, replace

import numpy as np

from ..algorithms import REGISTRY
from ..algorithms.counts import block_range
from ..errors import AllNodata, HillshadeError
from .lighting import Lighting
from ..model.geometry import Grid
from ..io.source import READ_CHUNK, DemSource, Reader
from ..pictures.preview import every_nth

STAT_BLOCK = 256          # cells per side of the blocks whose height range bounds the halos
ALIGN = 256               # output regions are multiples of the output's block size
GDAL_CACHE_MB = 64        # GDAL's block cache during a tiled run (its default is 5 % of RAM)

# bytes per window cell while it is lit (heights, the carried previous window, the algorithm's
# tables, the mask, the region's copies): an upper bound measured by benchmarks/bigdem.py; the
# algorithm's share is its registry entry's (AlgorithmSpec.bytes_per_cell), the product's here
_BYTES_PRODUCT = {"shadow": 0, "classes": 6, "hillshade": 22, "sun": 9}
_BYTES_SOFT = 20


def bytes_per_cell(algorithm: str, kind: str = "shadow", soft: bool = False,
                   self_shadow: bool = False) -> int:
    """Working memory per window cell of one run (an upper bound)."""
    spec = REGISTRY.get(algorithm)
    n = (spec.bytes_per_cell if spec is not None else 20) + _BYTES_PRODUCT.get(kind, 22)
    if soft:
        n += _BYTES_SOFT
    if self_shadow and kind == "shadow":
        n += 6
    return n


# ---------------------------------------------------------------------------------------------
# memory

_SIZE = re.compile(r"^\s*(\d+(?:\.\d*)?|\.\d+)\s*([kmgtp]?)(i?)(b?)\s*$", re.IGNORECASE)


def parse_size(text) -> int:
    """'2GB' (2e9 bytes), '1.5GiB' (1.5 * 2**30), '800M', '1e9'-free plain integers -> bytes.
    Decimal units unless written with 'i' (as Dask's ``parse_bytes``)."""
    if isinstance(text, (int, np.integer)):
        return int(text)
    m = _SIZE.match(str(text))
    if not m:
        raise HillshadeError(f"memory size must be like 2GB, 512MB or 1.5GiB, got {text!r}")
    value, unit, binary = float(m.group(1)), m.group(2).lower(), m.group(3)
    power = "kmgtp".index(unit) + 1 if unit else 0
    n = int(value * (1024 if binary else 1000) ** power)
    if n <= 0:
        raise HillshadeError(f"memory size must be positive, got {text!r}")
    return n


def format_size(n: float, up: bool = False) -> str:
    """``n`` bytes for people (2.50 GB, 512.00 MB). ``up``: rounded up to a whole number of the
    unit and written as an option value that ``parse_size`` reads back (e.g. ``391MB``), for
    an amount that must not be undershot."""
    for unit, f in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if abs(n) >= f:
            if up:
                return f"{math.ceil(n / f)}{unit}"
            return f"{n / f:.2f} {unit}"
    return f"{math.ceil(n)}B" if up else f"{int(n)} B"


class MemoryTooSmall(HillshadeError):
    """--max-memory leaves no room for a window of ``cells`` cells (``plan``): the caller
    knows the bytes per cell and says the smallest memory that would do (``memory_needed``)."""

    def __init__(self, message: str, cells: int):
        super().__init__(message)
        self.cells = cells


MIN_WINDOW_CELLS = 64 * 64   # the smallest window --max-memory must leave room for


def _overhead() -> tuple[int, int, int]:
    """(what the process holds now, GDAL's block cache, a margin): bytes a run's windows do
    not get."""
    return process_rss(), GDAL_CACHE_MB << 20, 32 << 20


def memory_needed(per_cell: int, cells: int) -> int:
    """The smallest --max-memory that leaves room for a window of ``cells`` cells now (with 2 %
    headroom: the process grows a little while a run is prepared)."""
    return int(math.ceil((sum(_overhead()) + per_cell * cells) * 1.02))


def _meminfo() -> dict:
    out = {}
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                k, v = line.split(":", 1)
                out[k] = int(v.split()[0]) * 1024
    return out


def default_max_memory() -> int:
    """Half of the machine's memory, and no more than 80 % of what is available now."""
    info = _meminfo()
    total = info.get("MemTotal")
    if total is None:
        try:
            total = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (ValueError, OSError, AttributeError):
            total = 8 << 30
    limit = total // 2
    if "MemAvailable" in info:
        limit = min(limit, int(info["MemAvailable"] * 0.8))
    return max(limit, 256 << 20)


def process_rss() -> int:
    """Resident memory of this process now, bytes (0 where /proc is missing)."""
    with contextlib.suppress(OSError, ValueError, IndexError):
        with open("/proc/self/statm", encoding="ascii") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    return 0


def window_budget(max_memory: int, per_cell: int) -> tuple[int, dict]:
    """Cells a window may hold under ``max_memory`` for the whole process: what the process
    already holds (interpreter, numba, GDAL) and GDAL's block cache are taken off first."""
    base, cache, margin = _overhead()
    free = max_memory - base - cache - margin
    info = {"max_memory": max_memory, "process_before": base, "gdal_cache": cache,
            "bytes_per_cell": per_cell}
    if free < per_cell * MIN_WINDOW_CELLS:
        least = memory_needed(per_cell, MIN_WINDOW_CELLS)
        raise HillshadeError(
            f"--max-memory {format_size(max_memory)} leaves no room for a window: the process "
            f"already uses {format_size(base)} and GDAL's cache {format_size(cache)}; give at "
            f"least --max-memory {format_size(least, up=True)}")
    info["window_bytes"] = free
    return free // per_cell, info


# ---------------------------------------------------------------------------------------------
# statistics pass

@dataclass
class BlockStats:
    """Height range per ``block`` x ``block`` cells (``lo``/``hi``: +inf/-inf for void blocks)."""

    block: int
    lo: np.ndarray
    hi: np.ndarray
    valid: int
    preview: np.ndarray | None = None    # every ``stride``-th height, for --preview
    stride: int = 1

    @property
    def zmin(self) -> float:
        return float(np.min(self.lo))

    @property
    def zmax(self) -> float:
        return float(np.max(self.hi))

    def range_over(self, bounds) -> tuple[float, float]:
        r0, r1, c0, c1 = bounds
        B = self.block
        lo = self.lo[r0 // B:(r1 - 1) // B + 1, c0 // B:(c1 - 1) // B + 1]
        hi = self.hi[r0 // B:(r1 - 1) // B + 1, c0 // B:(c1 - 1) // B + 1]
        return float(lo.min()), float(hi.max())


def block_stats(source: DemSource, block: int = STAT_BLOCK,
                preview_side: int | None = None) -> BlockStats:
    """One pass over ``source`` in bands of ``block`` rows (bounded memory)."""
    rows, cols = source.shape
    nbr, nbc = -(-rows // block), -(-cols // block)
    lo = np.empty((nbr, nbc), np.float32)
    hi = np.empty((nbr, nbc), np.float32)
    stride = max(1, math.ceil(max(rows, cols) / preview_side)) if preview_side else 1
    pv = (np.empty((-(-rows // stride), -(-cols // stride)), np.float32) if preview_side
          else None)
    valid = 0
    cw = max(block, (READ_CHUNK // (4 * block)) // block * block)   # columns per read
    buf = np.empty((block, min(cols, cw)), np.float32)
    with source.reader() as rd:
        for i in range(nbr):
            r0, r1 = i * block, min(rows, (i + 1) * block)
            for c0 in range(0, cols, cw):
                c1 = min(cols, c0 + cw)
                z = buf[:r1 - r0, :c1 - c0]
                rd.read((r0, r1, c0, c1), z)
                valid += int(block_range(z, block, lo[i:i + 1, c0 // block:-(-c1 // block)],
                                          hi[i:i + 1, c0 // block:-(-c1 // block)]))
                if pv is not None:
                    sub, (a, b) = every_nth(z, r0, c0, stride)
                    pv[a:a + sub.shape[0], b:b + sub.shape[1]] = sub
    if valid == 0:
        raise AllNodata(f"{source.path}: every cell is nodata, nothing to shade")
    return BlockStats(block, lo, hi, valid, pv, stride)


# ---------------------------------------------------------------------------------------------
# plan

@dataclass(frozen=True)
class PlannedWindow:
    """One unit of work: output ``region`` and the ``window`` read for it (r0, r1, c0, c1), lit
    by the sun at ``azimuth``/``elevation``."""

    region: tuple[int, int, int, int]
    window: tuple[int, int, int, int]
    azimuth: float
    elevation: float
    zrange: tuple[float, float] | None = None    # bounds of the window's heights (block ranges)
    # a sun per cell (``SunOver.fieldwise``): the whole sun (its lattice, centre azimuth and
    # elevation), whose halo the window holds for every cell's ray
    sun: object = field(default=None, compare=False)

    @property
    def cells(self) -> int:
        r0, r1, c0, c1 = self.window
        return (r1 - r0) * (c1 - c0)

    @property
    def region_cells(self) -> int:
        r0, r1, c0, c1 = self.region
        return (r1 - r0) * (c1 - c0)

    def inner(self) -> tuple[slice, slice]:
        """The region's place inside the window."""
        r0, r1, c0, c1 = self.region
        w0, _, v0, _ = self.window
        return slice(r0 - w0, r1 - w0), slice(c0 - v0, c1 - v0)


def _cuts(lo: int, hi: int, size: int, align: int) -> list[tuple[int, int]]:
    """[lo, hi) cut into parts of ``size`` (a multiple of ``align`` when it is at least that),
    counted from ``lo``."""
    if size >= hi - lo:
        return [(lo, hi)]
    if size >= align:
        size = size // align * align
    return [(a, min(hi, a + size)) for a in range(lo, hi, size)]


def window_for(bounds, shape, grid: Grid, azimuth: float, elevation: float, curv: float,
               stats: BlockStats, margin: int = 1,
               lift: float = 0.0) -> tuple[int, int, int, int]:
    """The window of region ``bounds``: the region, its halo toward the sun (from the block
    ranges, tightened until it stops shrinking) and ``margin`` cells all round. ``lift``: the
    rays start that many metres above their cells (``--height-above-ground``): they clear the
    terrain sooner, the halo is shorter."""
    from .shader import halo_bounds, reach_m
    low, _ = stats.range_over(bounds)
    if not math.isfinite(low):          # voids only: nothing to shade, nothing to read around
        return halo_bounds(bounds, shape, grid, azimuth, 0.0, margin)
    zhigh = stats.zmax
    win = None
    for _ in range(8):
        reach = reach_m(zhigh - (low + lift), elevation, curv)
        new = halo_bounds(bounds, shape, grid, azimuth, reach, margin)
        if new == win:
            break
        win = new
        zhigh2 = stats.range_over(win)[1]
        if zhigh2 >= zhigh:
            break
        zhigh = zhigh2
    return win


def halo_cells(grid: Grid, azimuth: float, reach: float, rows: tuple[int, int],
               margin: int = 1) -> tuple[int, int]:
    """(rows, columns) a window adds to a region of these rows (as ``engine.shader.halo_bounds``, before
    clipping to the raster)."""
    east = math.sin(math.radians(azimuth)) * grid.col_sign
    north = math.cos(math.radians(azimuth)) * grid.row_sign

    def extra(comp, spacing):
        if abs(comp) < 1e-12:
            return 2 * (2 + margin)
        if not math.isfinite(reach):
            return 1 << 62
        return int(math.ceil(reach * abs(comp) / spacing)) + 2 + 2 * margin
    return (extra(north, float(np.min(grid.dy[rows[0]:rows[1]]))),
            extra(east, float(np.min(grid.dx[rows[0]:rows[1]]))))


def plan(shape, grid: Grid, azimuth: float, elevation: float, curv: float, stats: BlockStats,
         budget_cells: int, window_shape: tuple[int, int] | None = None,
         bounds: tuple[int, int, int, int] | None = None, align: int = ALIGN,
         halo_elevation: float | None = None, night: bool = False,
         carry: bool = False, azimuths: tuple[float, float] | None = None,
         lift: float = 0.0) -> list[PlannedWindow]:
    """Cut ``bounds`` (default: the raster) into regions whose windows hold at most
    ``budget_cells`` cells (or regions of ``window_shape``), ordered from the sun's side so that
    each window's halo was read by the window before.

    The regions form strips along the axis the sun moves along more (cells per step); within a
    strip the inner loop walks away from the sun. ``carry``: the algorithm carries its tables
    along a strip (SMap, ``BandCarry``): the windows of a strip then span the same cells
    across it and each reaches at least as far toward the sun as the next, and the sizes are
    chosen for the fewest cells coloured (each strip's halo once) rather than the fewest read.

    ``halo_elevation``: the elevation the halo is made for (default ``elevation``; soft shadows
    need the lower edge of the sun's disk). ``night``: nothing casts; windows have no halo.
    ``azimuths``: the lowest and highest azimuth of the cells' rays (a sun per cell): each
    window then holds the halos of both and of ``azimuth``, so every ray in between.
    ``lift``: the rays start that many metres above their cells (``window_for``)."""
    from .shader import halo_bounds, reach_m
    rows, cols = shape
    b = bounds or (0, rows, 0, cols)
    br, bc = b[1] - b[0], b[3] - b[2]
    hel = elevation if halo_elevation is None else halo_elevation
    east = math.sin(math.radians(azimuth)) * grid.col_sign
    north = math.cos(math.radians(azimuth)) * grid.row_sign
    # the inner loop runs along the axis whose halo is larger, so that it is carried
    cols_inner = abs(east) / grid.dx[0] >= abs(north) / grid.dy[0]
    if window_shape is not None:
        tr, tc = min(br, window_shape[0]), min(bc, window_shape[1])
    else:
        # halo sizes from the raster's whole range: an upper bound of every window's
        reach = 0.0 if night else reach_m(stats.zmax - (stats.zmin + lift), hel, curv)
        hr, hc = halo_cells(grid, azimuth, reach, (b[0], b[1]))
        for az in azimuths or ():
            hr_, hc_ = halo_cells(grid, az, reach, (b[0], b[1]), 2)
            hr, hc = max(hr, hr_), max(hc, hc_)
        best = None
        for tr_ in sorted({br} | set(range(align, br, align))):
            wr = min(rows, tr_ + hr)
            tc_ = budget_cells // wr - hc
            if tc_ >= bc:
                tc_ = bc
            elif tc_ >= align:
                tc_ = tc_ // align * align
            if tc_ < 16 or (tc_ < min(bc, align) and tr_ < br):
                continue       # too narrow (or narrow and not full height: unaligned writes)
            nr, nc = -(-br // tr_), -(-bc // tc_)
            n = nr * nc
            wc = min(cols, tc_ + hc)
            if carry:   # cells coloured (a strip's halo once), then a sixteenth for the copies
                strips = (nr * min(cols, bc + hc) * wr if cols_inner
                          else nc * min(rows, br + hr) * wc)
                key = (strips + n * wr * wc // 16, n)
            else:
                key = (n * wr * wc, n)      # cells read and lit, then windows
            if best is None or key < best[0]:
                best = (key, tr_, tc_)
        if best is None:
            # the fewest cells any candidate above would have accepted
            need = min(min(rows, t + hr) * ((16 if t >= br else min(bc, align)) + hc)
                       for t in sorted({br} | set(range(align, br, align))))
            raise MemoryTooSmall(
                f"the memory limit allows windows of {budget_cells:,} cells, but a window with "
                f"the sun's halo needs at least {need:,} here (sun elevation {hel:.2f} deg): "
                "raise --max-memory", need)
        _, tr, tc = best
    row_cuts = _cuts(b[0], b[1], tr, align)
    col_cuts = _cuts(b[2], b[3], tc, align)
    if north > 1e-12:        # the sun lies toward higher rows: start there
        row_cuts.reverse()
    if east > 1e-12:
        col_cuts.reverse()
    order = ([(r, c) for r in row_cuts for c in col_cuts] if cols_inner
             else [(r, c) for c in col_cuts for r in row_cuts])
    regions = [(r0, r1, c0, c1) for (r0, r1), (c0, c1) in order]
    wins = [halo_bounds(reg, shape, grid, azimuth, 0.0, 1) if night
            else window_for(reg, shape, grid, azimuth, hel, curv, stats, lift=lift)
            for reg in regions]
    if azimuths and not night:
        wins = [_union([w] + [window_for(reg, shape, grid, az, hel, curv, stats, 2, lift)
                              for az in azimuths]) for reg, w in zip(regions, wins)]
    if carry:
        inner = len(col_cuts) if cols_inner else len(row_cuts)
        for s0 in range(0, len(wins), inner):
            wins[s0:s0 + inner] = _strip_windows(wins[s0:s0 + inner], cols_inner,
                                                 (east if cols_inner else north) > 1e-12)
    return [PlannedWindow(reg, win, azimuth, elevation, _finite(stats.range_over(win)))
            for reg, win in zip(regions, wins)]


def marched_per_cell(pieces) -> bool:
    """Whether the pieces of one sun march each cell with its own sun (``WindowLighting.pieces``): the
    report's ``sun.mode`` "per cell"."""
    return any(p.sun is not None for p in pieces)


def _union(wins):
    """The smallest window holding all of ``wins``."""
    return (min(w[0] for w in wins), max(w[1] for w in wins), min(w[2] for w in wins),
            max(w[3] for w in wins))


def _finite(zr):
    return zr if all(math.isfinite(v) for v in zr) else None


def _strip_windows(wins, lines_are_cols: bool, sun_high: bool):
    """The windows of one strip (in the order they are lit) made to span the same cells across
    the strip and to reach, each, at least as far toward the sun as the next: the shape
    ``BandCarry`` needs. They stay within the planner's bound (same region width, halo on
    the same side)."""
    w = [list(x) for x in wins]
    a, b = (0, 1) if lines_are_cols else (2, 3)        # the positions' axis
    lo, hi = min(x[a] for x in w), max(x[b] for x in w)
    for x in w:
        x[a], x[b] = lo, hi
    i = (3 if sun_high else 2) if lines_are_cols else (1 if sun_high else 0)
    for k in range(len(w) - 2, -1, -1):
        w[k][i] = max(w[k][i], w[k + 1][i]) if sun_high else min(w[k][i], w[k + 1][i])
    return [tuple(x) for x in w]


# ---------------------------------------------------------------------------------------------
# reading windows, carrying what consecutive windows share

def _minus(outer, inner):
    """``outer`` minus ``inner`` (a rectangle inside it) as up to four rectangles."""
    r0, r1, c0, c1 = outer
    i0, i1, j0, j1 = inner
    parts = [(r0, i0, c0, c1), (i1, r1, c0, c1), (i0, i1, c0, j0), (i0, i1, j1, c1)]
    return [p for p in parts if p[1] > p[0] and p[3] > p[2]]


class WindowCache:
    """Reads windows through a :class:`Reader`, copying the part a window shares with the
    previous one instead of reading it again."""

    def __init__(self, reader: Reader):
        self.reader = reader
        self.prev: tuple | None = None
        self.carried_bytes = 0

    def get(self, window) -> np.ndarray:
        r0, r1, c0, c1 = window
        if self.prev is not None and self.prev[0] == window:
            return self.prev[1]
        z = np.empty((r1 - r0, c1 - c0), np.float32)
        todo = [window]
        if self.prev is not None:
            (p0, p1, q0, q1), pz = self.prev
            i0, i1, j0, j1 = max(r0, p0), min(r1, p1), max(c0, q0), min(c1, q1)
            if i1 > i0 and j1 > j0:
                z[i0 - r0:i1 - r0, j0 - c0:j1 - c0] = pz[i0 - p0:i1 - p0, j0 - q0:j1 - q0]
                self.carried_bytes += (i1 - i0) * (j1 - j0) * self.reader.source.itemsize
                todo = _minus(window, (i0, i1, j0, j1))
            self.prev = None          # let the previous window go before reading
            del pz
        for a0, a1, b0, b1 in todo:
            self.reader.read((a0, a1, b0, b1), z[a0 - r0:a1 - r0, b0 - c0:b1 - c0])
        self.prev = (window, z)
        return z

    def drop(self):
        self.prev = None


def window_grid(grid: Grid, window) -> Grid:
    r0, r1, c0, c1 = window
    return Grid(r1 - r0, c1 - c0, grid.dx[r0:r1], grid.dy[r0:r1], grid.col_sign, grid.row_sign,
                grid.method)


class BandCarry:
    """SMap's tables carried from window to window of a tiled run, so that the lines two
    windows share are coloured and scanned once (``algorithms.smap.carried_mask``: the planner's
    order makes a window's lines toward the sun the window before's): one buffer, the table it
    holds (``key``, ``base``, ``L``) and the run's figures."""

    def __init__(self, capacity: int = 0):
        # flat int32 buffer; the current J is its first L * (P + 2) items. ``capacity``: the
        # largest table to come (the planner knows it), so that it is never grown while the
        # carried lines are held (which would hold two tables at once)
        self.buf = np.empty(capacity, np.int32) if capacity else None
        self.key = None
        self.base = 0
        self.L = 0
        self.lines_carried = 0
        self.lines_coloured = 0
        self.cells_coloured = 0

    def figures(self, cells_output: int) -> dict:
        """For a report: SMap elements coloured (each line of a strip about once) against the
        output's cells, and lines coloured vs reused."""
        return {"smap_cells_coloured": self.cells_coloured,
                "smap_coloured_beyond_output_fraction":
                    self.cells_coloured / cells_output - 1.0 if cells_output else 0.0,
                "smap_lines_coloured": self.lines_coloured,
                "smap_lines_carried": self.lines_carried}

    def table(self, rows: int, E: int) -> np.ndarray:
        """The buffer as a ``rows`` x ``E`` table (grown when too small, the carried lines
        kept)."""
        if self.buf is None or self.buf.size < rows * E:
            old, self.buf = self.buf, np.empty(rows * E, np.int32)
            if old is not None and self.key is not None:     # keep the carried lines
                self.buf[:self.L * E] = old[:self.L * E]
        return self.buf[:rows * E].reshape(rows, E)

    def mask(self, z: np.ndarray, rays, zmax: float, zabs: float, window,
             shape, inner: tuple[slice, slice]) -> np.ndarray:
        """uint8 mask of the window ``z`` (DEM order; ``window`` (r0, r1, c0, c1) of a raster of
        ``shape``) with the cells of ``inner`` decided (1 shadow, 0 lit, 255 void) and the others
        0, by SMap with the tables carried. ``zabs``: the largest height magnitude of the whole
        raster (one tolerance for every window)."""
        from ..algorithms.smap import carried_mask
        out, fresh = carried_mask(z, rays, zmax, zabs, window, shape, inner, self)
        L = self.L                    # the window's lines (positions: the rest of its cells)
        self.lines_coloured += fresh
        self.cells_coloured += fresh * (z.size // L if L else 0)
        self.lines_carried += L - fresh
        return out


# ---------------------------------------------------------------------------------------------
# lighting windows

@dataclass
class WindowLighting:
    """What lights a window, the same for every window of a run (picklable: Dask tasks get it).

    ``zrange`` and ``extent_m`` are the whole raster's, so that every window decides Earth
    curvature as a run on the whole raster would."""

    source: DemSource
    lighting: Lighting = field(default_factory=Lighting)   # how the terrain is lit
    body: object = None
    zrange: tuple[float, float] = (0.0, 0.0)
    extent_m: float = 0.0
    kind: str = "shadow"

    # the lighting's settings, read through (the job passes ``lighting`` whole to its Shaders)
    algorithm = property(lambda self: self.lighting.algorithm)
    options = property(lambda self: self.lighting.options)
    backend = property(lambda self: self.lighting.backend)
    curvature = property(lambda self: self.lighting.curvature)
    refraction_k = property(lambda self: self.lighting.refraction_k)
    soft = property(lambda self: self.lighting.soft)
    self_shadow = property(lambda self: self.lighting.self_shadow)
    ambient = property(lambda self: self.lighting.ambient)
    lift = property(lambda self: self.lighting.lift)

    @property
    def k(self) -> float:
        from ..model.earth import refraction_for
        return refraction_for(self.body, self.refraction_k)

    def curv(self, azimuth: float, elevation: float) -> float:
        from ..model.earth import curvature_coefficient
        return curvature_coefficient(self.curvature, self.body, self.k, self.extent_m,
                                     self.zrange, azimuth, elevation)

    @property
    def carries(self) -> bool:
        """Whether the algorithm carries tables from window to window (SMap on the CPU)."""
        return (self.algorithm == "smap" and self.backend == "cpu"
                and not self.options.get("better_nextv"))

    def carrier(self, plans=()):
        """A fresh carrier of tables for a run of windows (None when nothing is carried), its
        buffer sized for the largest window of ``plans`` (lists of pieces)."""
        if not self.carries:
            return None
        most = max(((p.window[1] - p.window[0] + 2) * (p.window[3] - p.window[2] + 2)
                    for ps in plans for p in ps), default=0)
        return BandCarry(most)

    def shader(self, z: np.ndarray, window, local_range=None, carry=None):
        return self.lighting.shader(z, window_grid(self.source.grid, window), body=self.body,
                                    zrange=self.zrange, extent_m=self.extent_m,
                                    halo_ready=True, local_range=local_range, carry=carry,
                                    place=(window, self.source.shape))

    def light(self, z: np.ndarray, piece: PlannedWindow, stats: dict | None = None,
              curvature_used: set | None = None, carry=None) -> np.ndarray:
        """The product over ``piece.region`` from its window's heights ``z``. ``carry``: the
        run's ``carrier()``, for windows lit in plan order (a fresh one otherwise: SMap then
        still masks the region only)."""
        return self._light(z, piece, stats, curvature_used, carry)[0]

    def light_incidence(self, z: np.ndarray, piece: PlannedWindow, stats: dict | None = None,
                        curvature_used: set | None = None,
                        carry=None) -> tuple[np.ndarray, np.ndarray]:
        """(``light``'s product, the cos of the incidence of the piece's sun on the region's
        cells: float32, NaN voids), both from the window's heights ``z`` (the region's
        neighbours for the normals are in it): what irradiance's beam takes."""
        arr, sh, region = self._light(z, piece, stats, curvature_used, carry)
        return arr, sh.incidence(region)

    def _light(self, z, piece, stats, curvature_used, carry):
        from .shader import render_region
        from ..model.sun import Region
        sh = self.shader(z, piece.window, piece.zrange,
                         carry if carry is not None else self.carrier())
        rows, cols = piece.inner()
        region = Region(rows, cols, piece.azimuth, piece.elevation)
        # a sun per cell: the window's cells each with their own (as a run in memory does)
        cast = None if piece.sun is None else sh.cast_field(piece.sun, stats)[rows, cols]
        arr = render_region(sh, region, self.kind, self.soft, self.self_shadow, self.ambient,
                            stats, cast)
        if curvature_used is not None:
            curvature_used |= sh.curvature_used
        return arr, sh, region

    def pieces(self, sun, stats: BlockStats, budget_cells: int,
               window_shape: tuple[int, int] | None = None, in_order: bool = True,
               area: tuple[int, int, int, int] | None = None) -> list[PlannedWindow]:
        """The pieces of one sun (per-tile suns: each tile's, cut further to fit).
        ``in_order``: the windows are lit one after the other in this order (SMap tables are
        carried along strips); False for independent tasks (Dask), which carry nothing.
        ``area`` (r0, r1, c0, c1): only the cells there (a tile of the raster, ``--context``):
        the sun's regions cut to it, their windows read from the whole raster."""
        from .shader import field_method
        from ..model.solar import SUN_RADIUS_DEG
        out = []
        shape = self.source.shape
        # a sun per cell, as ``Shader.field_ok`` decides in memory
        fieldwise = sun.fieldwise and field_method(self.algorithm, self.options, self.soft)
        for reg in sun.regions(shape):
            r0, r1, _ = reg.rows.indices(shape[0])
            c0, c1, _ = reg.cols.indices(shape[1])
            if area is not None:
                r0, r1, c0, c1 = max(r0, area[0]), min(r1, area[1]), max(c0, area[2]), \
                    min(c1, area[3])
                if r0 >= r1 or c0 >= c1:
                    continue
            el = reg.elevation
            if self.soft:
                night, hel = el + SUN_RADIUS_DEG <= 0, el - SUN_RADIUS_DEG
            else:
                night, hel = el <= 0, el
            azimuths = None
            if fieldwise:        # halos for every cell's ray: its lowest sun, both azimuths
                az_lo, az_hi, el_lo = sun.lattice_span(shape, (r0, r1, c0, c1), reg.azimuth)
                night, hel, azimuths = False, min(hel, el_lo), (az_lo, az_hi)
            # the curvature the rays will have (decided at the sun's elevation, as the Shader
            # does; the raster's centre sun's for a sun per cell), applied to the halo's lower ray
            curv = (self.curv(sun.azimuth, max(min(sun.elevation, 90.0), 1e-6)) if fieldwise
                    else 0.0 if night else self.curv(reg.azimuth, max(min(el, 90.0), 1e-6)))
            got = plan(shape, self.source.grid, reg.azimuth, el, curv, stats, budget_cells,
                       window_shape, (r0, r1, c0, c1), halo_elevation=hel, night=night,
                       carry=in_order and self.carries and not self.soft, azimuths=azimuths,
                       lift=self.lift)
            out += [replace(p, sun=sun) for p in got] if fieldwise else got
        return out

    def warm_up(self, sun) -> None:
        """Compile (or load from numba's cache) what the windows will run."""
        z = np.zeros((4, 4), np.float32)     # the kernels' argument types; the grid's spacing
        sh = self.lighting.shader(z, self.source.grid, body=self.body, zrange=self.zrange,
                                  extent_m=self.extent_m)
        sh.warm_up(sun.azimuth, max(sun.elevation, 1.0), soft=self.soft, field=sun.fieldwise,
                   incidence=self.self_shadow or self.kind != "shadow")


@dataclass
class WindowedRunStats:
    """What a tiled run did: windows, cells lit, bytes read and carried."""

    windows: int = 0
    region_cells: int = 0
    window_cells: int = 0
    bytes_read: int = 0
    bytes_carried: int = 0
    stats_pass_bytes: int = 0
    largest_window: tuple[int, int] = (0, 0)
    carry: object = None                  # the run's BandCarry, if any

    def add(self, piece: PlannedWindow):
        self.windows += 1
        self.region_cells += piece.region_cells
        self.window_cells += piece.cells
        r0, r1, c0, c1 = piece.window
        if (r1 - r0) * (c1 - c0) > self.largest_window[0] * self.largest_window[1]:
            self.largest_window = (r1 - r0, c1 - c0)

    def as_dict(self, itemsize: int) -> dict:
        beyond = max(0, self.bytes_read - self.region_cells * itemsize)
        return {"windows": self.windows, "largest_window": list(self.largest_window),
                "cells_output": self.region_cells, "cells_lit": self.window_cells,
                "halo_cells_fraction": (self.window_cells / self.region_cells - 1.0)
                if self.region_cells else 0.0,
                "bytes_read": self.bytes_read,
                "bytes_read_beyond_output": beyond,
                "bytes_read_beyond_output_fraction": beyond / max(1, self.region_cells * itemsize),
                "bytes_carried": self.bytes_carried,
                "statistics_pass_bytes": self.stats_pass_bytes,
                **(self.carry.figures(self.region_cells) if self.carry is not None else {})}
