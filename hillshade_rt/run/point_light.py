"""The ``shadow --light-position`` / ``--light-lonlat`` run: a DEM lit by a point light
(``algorithms.point_light``): each cell's ray runs straight to the light and ends there.
Hard shadows, exact (the march over the maximum-height pyramid), on the CPU or the GPU
(``--backend``), in memory or in windows (``--window-size``, or a DEM larger than
``--max-memory`` allows: each window read with its halo toward the light, ``_windows``). The
combinations not built yet (a sun option, --soft, --classes, --self-shadow, --algorithm,
--earth-curvature, Dask, --output-pattern, --cog, --preview in windows) are usage errors that
say so."""

from __future__ import annotations

import math
import os

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import LightConfig


def light_shadow(cfg: LightConfig) -> dict:
    """Write the point light's cast-shadow mask of the DEM; returns the report. In memory, or
    in windows (``--window-size``, or a DEM larger than ``--max-memory`` allows; ``_windows``).
    The preamble and the tail every run shares: ``run.runner.RunContext`` (the paths claimed,
    the threads, the backend by the one rule; the report and the summary)."""
    import numpy as np

    from ..engine.arrays import point_light_mask
    from ..io import check_output_format, input_label, output_driver, write_png, write_raster
    from ..pictures.preview import relief_rgb
    from .config import parse_window_size
    from .local import needs_windows
    from ..engine.windows import bytes_per_cell, default_max_memory, parse_size
    from .runner import RunContext

    ro = cfg.run
    dem, output, position, lonlat = cfg.check()
    wshape = parse_window_size(cfg.window_size)
    try:
        limit = (parse_size(cfg.max_memory) if cfg.max_memory is not None
                 else default_max_memory())
    except HillshadeError as exc:
        raise UsageProblem(f"--max-memory: {exc}") from None
    per_cell = bytes_per_cell("brute")
    ctx = RunContext.start(ro, inputs=[dem], outputs=[(output, "OUTPUT")], note=False)
    timer = ctx.timer
    check_output_format(output, output_driver(output, ro.fmt), "uint8", 1, False,
                        ro.creation_options)
    with timer("read"):
        src = cfg.read.open(dem, windows=wshape is not None)
    with src:
        windowed = wshape is not None or needs_windows(src, limit, per_cell)
        if windowed and ro.preview is not None:
            raise UsageProblem("a point light in windows does not take --preview (yet)")
        if lonlat is not None:
            if src.crs is None:
                raise HillshadeError("--light-lonlat needs a DEM with a CRS; give "
                                     "--light-position in the DEM's coordinates")
            from pyproj import Transformer
            lon, lat, zl = lonlat
            x, y = Transformer.from_crs("EPSG:4326", src.crs.to_wkt(),
                                        always_xy=True).transform(lon, lat)
        else:
            x, y, zl = position
        if src.transform is None:
            raise HillshadeError("the DEM has no geotransform: a light position needs one")
        col, row = ~src.transform @ (x, y)
        row, col = row - 0.5, col - 0.5            # the transform's cell centres at +0.5
        tags = {"HILLSHADE_RT_VERSION": __version__, "VALUES": "1 shadow, 0 lit, 255 nodata",
                "LIGHT": f"point light at x={x:.6f} y={y:.6f} z={zl:g} m (the DEM's CRS)",
                "LIGHT_CELL": f"row {row:.3f} col {col:.3f}",
                "HEIGHT_ABOVE_GROUND_M": f"{float(cfg.height_above_ground):g}"}
        st: dict = {}
        if windowed:
            shadowed, valid, processing = _windows(ctx, src, row, col, zl,
                                                   cfg.height_above_ground, wshape, limit,
                                                   per_cell, output, tags)
        else:
            with timer("read"):
                d = src.read()
            with timer("compute"):
                mask = point_light_mask(d, x, y, zl, height_above_ground=cfg.height_above_ground,
                                        backend=ctx.backend, stats=st)
            with timer("write"):
                write_raster(output, mask, d, nodata=255, description="cast shadow (point light)",
                             tags=tags, overwrite=ro.overwrite, fmt=ro.fmt,
                             co=ro.creation_options)
                if ro.preview is not None:
                    write_png(ro.preview, relief_rgb(d.heights, d.grid,
                                                     shade=np.where(mask == 1, 1.0, 0.0)),
                              ro.overwrite)
            shadowed, valid = int((mask == 1).sum()), int((mask != 255).sum())
            processing = {"mode": "memory"}
        shape, path = src.shape, src.path
    share = shadowed / valid if valid else 0.0
    rep = {"input": input_label(path), "output": os.path.abspath(output),
           "shape": list(shape), "light": {"x": x, "y": y, "z": zl, "row": row, "col": col},
           "height_above_ground_m": float(cfg.height_above_ground),
           "shadow_fraction": share, "backend": ctx.backend,
           "algorithm": "point (pyramid march)", "processing": processing,
           "seconds": ctx.seconds(), "version": __version__}
    if "gpu" in st:
        rep["gpu"] = st["gpu"]
    return ctx.finish(rep, [("summary", f"hillshade-rt: {output}: {shape[1]}x{shape[0]}, point "
                                        f"light at row {row:.1f} col {col:.1f} z {zl:g} m: "
                                        f"{100 * share:.2f}% of valid cells in shadow; compute "
                                        f"{timer.seconds.get('compute', 0.0):.2f} s")])


def _windows(ctx, src, row, col, zl, lift, wshape, limit, per_cell, output, tags):
    """The mask in windows of ``src`` (an open ``io.DemSource``), each read with its halo: the box
    of the window and the light's cell (``algorithms.point_light.halo``), lit with the raster's ray
    arithmetic (the same cells as in memory, bit for bit) and its region written by
    ``io.raster.BandWriter``. Windows of ``wshape``, else squares a quarter of what
    ``--max-memory`` allows (the halo reaches to the light: it may be larger); on the run's
    backend (``ctx.backend``), timed by its timer. Returns (shadowed cells, valid cells, the
    report's processing)."""
    import numpy as np

    from ..algorithms import point_light
    from ..algorithms.horizon import bilinear
    from ..engine.gpu import GpuDem
    from ..io.raster import BandWriter
    from ..engine.windows import window_budget

    lift = float(lift)
    if not (math.isfinite(lift) and lift >= 0.0):
        raise HillshadeError(f"height_above_ground must be finite metres >= 0, got {lift}")
    rows, cols = src.shape
    if wshape is None:
        side = max(64, int(math.sqrt(window_budget(limit, per_cell)[0] / 4)))
        wshape = (side, side)
    ro, timer, ran_on = ctx.ro, ctx.timer, ctx.backend
    shadowed = valid = windows = 0
    largest = 0
    with src.reader() as rd, BandWriter(output, src, 1, "uint8", 255, tags,
                                        overwrite=ro.overwrite, fmt=ro.fmt,
                                        co=ro.creation_options) as w:
        fr, fc = math.floor(row), math.floor(col)        # the light inside the terrain?
        a, b = max(0, fr - 1), min(rows, fr + 3)
        c, d = max(0, fc - 1), min(cols, fc + 3)
        if a < b and c < d:
            near = np.empty((b - a, d - c), np.float32)
            rd.read((a, b, c, d), near)
            ground = bilinear(near, row - a, col - c) if 0 <= row <= rows - 1 and \
                0 <= col <= cols - 1 else math.nan
            if np.isfinite(ground) and zl <= ground:
                raise HillshadeError(f"the light is inside the terrain ({zl:g} m at a ground "
                                     f"of {ground:g} m)")
        for r0 in range(0, rows, wshape[0]):
            for c0 in range(0, cols, wshape[1]):
                region = (r0, min(rows, r0 + wshape[0]), c0, min(cols, c0 + wshape[1]))
                h = point_light.halo(region, row, col, (rows, cols))
                with timer("read"):
                    z = np.empty((h[1] - h[0], h[3] - h[2]), np.float32)
                    rd.read(h, z)
                largest = max(largest, z.size)
                with timer("compute"):
                    if ran_on == "gpu":     # the window's heights only: a DEM on the device
                        m = point_light.shadow_mask_gpu(GpuDem(z), row, col, zl, lift,
                                                  origin=(h[0], h[2]), shape=(rows, cols))
                    else:
                        m = point_light.shadow_mask(z, row, col, zl, lift, origin=(h[0], h[2]),
                                              shape=(rows, cols))
                    part = np.ascontiguousarray(m[region[0] - h[0]:region[1] - h[0],
                                                  region[2] - h[2]:region[3] - h[2]])
                    shadowed += int((part == 1).sum())
                    valid += int((part != 255).sum())
                with timer("write"):
                    w.write(1, part, window=region)
                windows += 1
        w.describe(1, "cast shadow (point light)")
    return shadowed, valid, {"mode": "tiled", "windows": windows,
                             "window_shape": list(wshape), "largest_halo_cells": largest,
                             "bytes_read": rd.bytes_read}
