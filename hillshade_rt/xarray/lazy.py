"""The lazy Dask graph of a Dask-backed input: the windows of the command line's windowed runs
(``engine.windows``) as Dask tasks. The statistics pass (block height ranges, the halos' source)
as one reduction; one task per window of ``WindowLighting.pieces`` (the region and its halo
toward the sun), mosaicked back into one array per sun; the horizon products' windows toward
each azimuth (within ``max_distance``, else to the edge); one task over the whole raster where
no window applies. The tasks share one lock: numba's parallel kernels run one at a time."""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from ..errors import HillshadeError
from ..model.geometry import Grid
from .dataarray import Input

# one numba computation at a time in this process (Dask's threads would otherwise call the
# parallel kernels concurrently, which numba's default threading layer does not allow)
LOCK = threading.Lock()


@dataclass(eq=False)
class LazySource:
    """A Dask-backed input as the windowed runs see a DEM (``engine.windows.WindowLighting``,
    ``model.site.dem_site``): its shape, grid, transform, CRS, and the centre height read from
    the centre only."""

    heights: object
    grid: Grid
    transform: object
    crs: object
    path: str

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.heights.shape)

    def centre_height(self) -> tuple[float, str]:
        from ..model.site import centre_height_of
        rows, cols = self.shape
        r, c = rows // 2, cols // 2
        r0, c0 = max(0, r - 128), max(0, c - 128)
        z = np.asarray(self.heights[r0:min(rows, r + 129), c0:min(cols, c + 129)].compute())
        if not np.isfinite(z).any():
            return 0.0, "sea level (no valid cell within 128 cells of the centre)"
        return centre_height_of(z, r - r0, c - c0)


@dataclass(frozen=True)
class Frame:
    """What ``engine.windows.WindowLighting`` reads of its DEM: the shape and the grid. Not the
    Dask array itself: Dask looks inside a task's dataclass arguments, and the whole input would
    become a dependency of every window's task."""

    shape: tuple[int, int]
    grid: Grid


def _block_range(block):
    """(lowest, highest valid height, valid cells) of each STAT_BLOCK² block of ``block``."""
    from ..engine.windows import STAT_BLOCK as B
    rows, cols = block.shape
    nr, nc = -(-rows // B), -(-cols // B)
    z = np.full((nr * B, nc * B), np.nan, np.float32)
    z[:rows, :cols] = block
    z = z.reshape(nr, B, nc, B)
    ok = np.isfinite(z)
    out = np.empty((nr, nc, 3), np.float32)
    out[..., 0] = np.where(ok, z, np.inf).min(axis=(1, 3))
    out[..., 1] = np.where(ok, z, -np.inf).max(axis=(1, 3))
    out[..., 2] = ok.sum(axis=(1, 3))
    return out


def block_stats(z):
    """``engine.windows.BlockStats`` of a Dask array of heights: the statistics pass of a windowed
    run, as one Dask reduction (computed now: the windows depend on it)."""
    from ..engine.windows import STAT_BLOCK as B, BlockStats
    size = 8 * B
    zz = z.rechunk((size, size))
    parts = zz.map_blocks(_block_range, dtype=np.float32, new_axis=2,
                          chunks=(tuple(-(-c // B) for c in zz.chunks[0]),
                                  tuple(-(-c // B) for c in zz.chunks[1]), (3,)))
    st = np.asarray(parts.compute())
    valid = int(st[..., 2].astype(np.int64).sum())
    return BlockStats(B, st[..., 0].copy(), st[..., 1].copy(), valid)



def light_piece(job, piece, z):
    """One task: the product over ``piece.region`` from its window's heights ``z``."""
    z = np.array(z, dtype=np.float32, copy=True)
    with LOCK:
        return job.light(z, piece)


def mosaic(blocks):
    """``blocks`` [(bounds (r0, r1, c0, c1), dask array)] tiling a rectangle as a grid -> one
    dask array."""
    import dask.array as dka
    rows = sorted({b[0] for b, _ in blocks})
    cols = sorted({b[2] for b, _ in blocks})
    at = {(b[0], b[2]): a for b, a in blocks}
    if len(at) != len(rows) * len(cols):
        raise HillshadeError("internal: the windows do not form a grid")
    return dka.block([[at[(r, c)] for c in cols] for r in rows])


def lazy_render(job, sun, stats, z, dtype):
    """One sun's product over the raster as a lazy Dask array: one task per window of the
    planner (``WindowLighting.pieces``: regions of about the input's chunk size, each window
    with its halo toward the sun), each reading its window from ``z`` (slices of the input's
    chunks)."""
    import dask
    import dask.array as dka
    rows, cols = z.shape
    shape = (int(max(z.chunks[0])), int(max(z.chunks[1])))
    pieces = job.pieces(sun, stats, rows * cols, window_shape=shape, in_order=False)
    task = dask.delayed(light_piece, pure=True)
    blocks = []
    for p in pieces:
        r0, r1, c0, c1 = p.region
        w0, w1, v0, v1 = p.window
        part = dka.from_delayed(task(job, p, z[w0:w1, v0:v1]), shape=(r1 - r0, c1 - c0),
                                dtype=dtype)
        blocks.append((p.region, part))
    tiles = []
    for reg in sun.regions((rows, cols)):
        r0, r1, _ = reg.rows.indices(rows)
        c0, c1, _ = reg.cols.indices(cols)
        inside = [(b, a) for b, a in blocks
                  if r0 <= b[0] and b[1] <= r1 and c0 <= b[2] and b[3] <= c1]
        tiles.append(((r0, r1, c0, c1), mosaic(inside)))
    return mosaic(tiles).rechunk(z.chunks)


def lazy_job(inp: Input, req, lighting, kind):
    """(job, block statistics, suns, sun info) of a Dask-backed input lit so (``lighting``,
    an ``engine.lighting.Lighting``) into product ``kind``."""
    from ..model.earth import dem_body
    from ..engine.windows import WindowLighting
    src = LazySource(inp.heights, inp.grid, inp.transform, inp.crs, inp.path)
    stats = block_stats(inp.heights)
    if stats.valid == 0:
        raise HillshadeError(f"{inp.path}: every cell is nodata, nothing to shade")
    suns, info = req.suns(src)
    rows, cols = inp.shape
    dx, dy = inp.grid.centre_spacing()
    job = WindowLighting(Frame(inp.shape, inp.grid), lighting, dem_body(src, req.lat),
                         (stats.zmin, stats.zmax), math.hypot(cols * dx, rows * dy), kind)
    return job, stats, suns, info


def horizon_settings(inp: Input, curvature, method: str):
    """(curvature, body) of the horizon products over the whole raster, decided once for its
    windows as ``engine.shader.horizon_shader`` decides them for the whole (curvature "auto":
    on for the scan of a raster more than 1 km across; the body at the DEM's centre)."""
    from ..model.earth import dem_body
    if curvature in ("auto", None):
        rows, cols = inp.shape
        dx, dy = inp.grid.centre_spacing()
        curvature = math.hypot(cols * dx, rows * dy) > 1000.0 and method == "scan"
    src = LazySource(inp.heights, inp.grid, inp.transform, inp.crs, inp.path)
    return curvature, dem_body(src)


def horizon_window(z, window, *, grid, azimuth, method, sample_spacing, backend, curvature,
                   refraction_k, body, max_distance, lift):
    from ..engine.arrays import horizon_angles
    from ..engine.windows import window_grid
    return horizon_angles(z, azimuth, window_grid(grid, window), method, sample_spacing,
                          backend, curvature=curvature, refraction_k=refraction_k, body=body,
                          max_distance=max_distance, height_above_ground=lift)


def skyview_window(z, window, *, grid, directions, definition, curvature, refraction_k, body,
                   openness, max_distance, lift):
    from ..engine.arrays import sky_view
    from ..engine.windows import window_grid
    return sky_view(z, window_grid(grid, window), directions, definition, curvature=curvature,
                    refraction_k=refraction_k, body=body, openness=openness,
                    max_distance=max_distance, height_above_ground=lift)


def reach_part(part, z, window, region):
    """One task of :func:`lazy_reach`: ``part`` over the window, cut to the region."""
    r0, r1, c0, c1 = region
    w0, _, v0, _ = window
    z = np.array(z, dtype=np.float32, copy=True)
    inner = (slice(r0 - w0, r1 - w0), slice(c0 - v0, c1 - v0))
    if not np.isfinite(z[inner]).any():
        return np.full((r1 - r0, c1 - c0), np.nan, np.float32)
    with LOCK:
        return np.asarray(part(z, window)[inner], np.float32)


def lazy_reach(inp: Input, azimuths, max_distance, part):
    """A lazy float32 product of a Dask-backed input (horizon angles, sky view), one task per
    chunk of the input: the chunk's window holds, toward each of ``azimuths``, every cell
    within ``max_distance`` metres (to the raster's edge without one;
    ``engine.shader.halo_bounds``, as the planner's halos) and a cell all round;
    ``part(heights, window)`` makes the product over the window, of which the task keeps the
    chunk."""
    import dask
    import dask.array as dka

    from ..engine.shader import halo_bounds
    z = inp.heights
    reach = math.inf if max_distance is None else float(max_distance)
    task = dask.delayed(reach_part, pure=True)
    redges = np.cumsum((0,) + tuple(z.chunks[0]))
    cedges = np.cumsum((0,) + tuple(z.chunks[1]))
    blocks = []
    for r0, r1 in zip(redges[:-1], redges[1:]):
        row = []
        for c0, c1 in zip(cedges[:-1], cedges[1:]):
            region = (int(r0), int(r1), int(c0), int(c1))
            wins = [halo_bounds(region, inp.shape, inp.grid, a, reach, 1) for a in azimuths]
            w = (min(x[0] for x in wins), max(x[1] for x in wins), min(x[2] for x in wins),
                 max(x[3] for x in wins))
            row.append(dka.from_delayed(task(part, z[w[0]:w[1], w[2]:w[3]], w, region),
                                        shape=(region[1] - region[0], region[3] - region[2]),
                                        dtype=np.float32))
        blocks.append(row)
    return dka.block(blocks)


def whole(compute, inp: Input, shape):
    """``compute(heights)`` now, or as one Dask task over the whole input (rechunked to the
    input's chunks) for a Dask-backed one."""
    if not inp.lazy:
        return compute(inp.heights)
    import dask
    import dask.array as dka

    def task(z):
        with LOCK:
            return compute(np.array(z, np.float32, copy=True))
    arr = dka.from_delayed(dask.delayed(task, pure=True)(inp.heights), shape=shape,
                           dtype=np.float32)
    return arr.rechunk(((shape[0],),) * (len(shape) - 2) + inp.heights.chunks
                       if len(shape) == 3 else inp.heights.chunks)
