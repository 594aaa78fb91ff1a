"""``--context RASTER``: one tile of a larger raster lit as the whole raster lights it.

A Makefile runs one process per tile; each tile's rays must still see the terrain of its
neighbours. With ``--context`` (a VRT or mosaic of the tiles on the same grid) the output covers
the tile only (its shape, transform and CRS) while its heights, and those its rays cross, are
read from the context, in the windowed runs' windows: ``engine.windows`` (shadows, hillshade, sun
hours: the region and its halo toward the sun) and ``run.horizon_windows`` (horizons, sky view: the rays'
reach, ``--max-distance`` or the context's edge); irradiance uses both (its beam's shadows per
sun, its Dozier sky view). The regions of those runs are cut to the tile
(:meth:`Area.clip`) and written at the tile's coordinates (:meth:`Area.local`).

Everything the whole raster's run decides from the whole raster is decided from the context:
the height range and extent (Earth curvature "auto", the halos' bound: one streaming pass of
block statistics, ``engine.windows.block_stats``, kept between runs by ``run.statscache``), the body and its latitude, the place of the sun
and the suns per tile of the raster (``sun.sun_over`` over the context's shape), so that the
tile's cells get the bits the whole context's run gives them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AllNodata, UsageProblem


@dataclass(eq=False)
class Area:
    """A tile of a larger raster: ``source`` the context (an ``io.DemSource`` opened for
    windows: the heights read), ``tile`` the tile's own source (its grid: the outputs' shape,
    transform and CRS; its values are not read), ``bounds`` (r0, r1, c0, c1) the tile's cells in
    the context."""

    source: object
    tile: object
    bounds: tuple
    statistics: dict | None = None     # how the block statistics were had (block_stats)

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(self.tile.shape)

    def clip(self, region):
        """``region`` (r0, r1, c0, c1 of the context) cut to the tile; None when they do not
        meet."""
        a0, a1, b0, b1 = self.bounds
        r0, r1, c0, c1 = max(region[0], a0), min(region[1], a1), max(region[2], b0), \
            min(region[3], b1)
        return (r0, r1, c0, c1) if r0 < r1 and c0 < c1 else None

    def local(self, region):
        """``region`` (inside the tile, context coordinates) in the tile's rows and columns."""
        a0, _, b0, _ = self.bounds
        return region[0] - a0, region[1] - a0, region[2] - b0, region[3] - b0

    def regions(self, regs):
        """Regions of the tile (its rows and columns, e.g. ``run.horizon_windows.plan_regions`` of its
        shape) in the context's coordinates."""
        a0, _, b0, _ = self.bounds
        return [(r0 + a0, r1 + a0, c0 + b0, c1 + b0) for r0, r1, c0, c1 in regs]

    def block_stats(self):
        """The context's block statistics (``engine.windows.BlockStats``), from the cache of earlier
        runs when the context has not changed since (``run.statscache``), else one pass over
        it (then cached); how: ``statistics`` (the reports' ``statistics_pass``)."""
        from ..engine.windows import STAT_BLOCK
        from .statscache import cached_block_stats
        bs, self.statistics = cached_block_stats(self.source, STAT_BLOCK)
        return bs

    def report(self) -> dict:
        """The reports' ``context``: the path, shape, the tile's window, the statistics pass."""
        from ..io import input_label
        return {"path": input_label(self.source.path), "shape": list(self.source.shape),
                "window": list(self.bounds), "statistics_pass": self.statistics}

    def check_valid(self) -> None:
        """``AllNodata`` when every cell of the tile is nodata in the context (read in bands of
        rows, stopping at the first valid cell)."""
        r0, r1, c0, c1 = self.bounds
        step = max(1, (8 << 20) // max(1, 4 * (c1 - c0)))
        with self.source.reader() as rd:
            for a in range(r0, r1, step):
                b = min(r1, a + step)
                z = np.empty((b - a, c1 - c0), np.float32)
                rd.read((a, b, c0, c1), z)
                if np.isfinite(z).any():
                    return
        raise AllNodata(f"{self.tile.path}: every cell is nodata in --context "
                        f"{self.source.path}, nothing to shade")

    def close(self) -> None:
        self.source.close()
        self.tile.close()

    def __enter__(self) -> Area:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_area(read, paths) -> Area:
    """The tile at ``paths`` (one DEM) placed in ``read.context`` (``ReadOptions``): both opened
    with the same read options (band, nodata, z-factor), the context for windows; a usage error
    when the context is not on the tile's grid or does not contain it."""
    from ..io.paths import STDIN
    from ..io.source import open_dem, place_in
    paths = [paths] if isinstance(paths, str) else list(paths)
    if len(paths) != 1:
        raise UsageProblem("--context takes one DEM, the tile (the context is the mosaic)")
    if STDIN in paths or read.context == STDIN:
        raise UsageProblem("--context: the tile and the context are read from files, not from "
                           "standard input")
    opts = read.options()
    tile = open_dem(paths[0], opts)
    try:
        context = open_dem(read.context, opts, windows=True)
    except BaseException:
        tile.close()
        raise
    try:
        bounds = place_in(context, tile)
    except BaseException:
        tile.close()
        context.close()
        raise
    return Area(context, tile, bounds)


def nodata_note(path: str) -> str:
    """The note of a run whose DEM (or tile) is all nodata."""
    return f"{path}: every cell is nodata: the output is all nodata"
