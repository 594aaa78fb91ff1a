"""The ``hillshade --light-position`` / ``--light-lonlat`` run: shaded
relief lit by a point light, and lightmaps for terrain artists (``-f PNG``, 8 or 16 bits).

Per cell, as the directional hillshade: ambient + (1 - ambient) x max(0, N . L) x lit, written
1..255 (0 nodata), with N the Horn normal of the ground and L the unit vector from the cell's
point (its height plus ``--height-above-ground``) to the light, lit from the point light's
cast-shadow mask (``arrays.point_light_mask``, the same mask ``shadow --light-position``
writes). ``--bits 16``: 1..65535 in uint16 (the same formula with 65534 levels), for PNG
lightmaps or GeoTIFF. ``--falloff inverse-square`` scales the direct part by
min(1, (d_ref / d)^2): d the distance from the cell's point to the light, d_ref the light's
height above the ground beneath it (bilinear; beneath the nearest point of the raster when the
light is off it), so that the cell right under the light keeps its Lambert value and nothing is
brighter: a lightmap whose brightest cells stay in range however near the light is, and whose
brightness halves at 1.41 d_ref. The kernels: ``algorithms.lightmap``.

In memory, on the CPU, as the point light's shadow: what it does not take yet is a usage error
(``run.point_light.LightConfig``'s ``refused``)."""

from __future__ import annotations

import math
import os

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import FALLOFFS, LightmapConfig


def light_xy(d, position, lonlat) -> tuple[float, float, float]:
    """(x, y, z) of the light in the DEM's CRS: ``position`` as given, or ``lonlat`` (WGS84
    degrees) transformed into it."""
    if lonlat is None:
        return tuple(float(v) for v in position)
    if d.crs is None:
        raise HillshadeError("--light-lonlat needs a DEM with a CRS; give --light-position in "
                             "the DEM's coordinates")
    from pyproj import Transformer
    lon, lat, zl = lonlat
    x, y = Transformer.from_crs("EPSG:4326", d.crs.to_wkt(), always_xy=True).transform(lon, lat)
    return float(x), float(y), float(zl)


def light_cell(d, x: float, y: float) -> tuple[float, float]:
    """The light's fractional (row, col), cell centres at whole numbers."""
    if d.transform is None:
        raise HillshadeError("the DEM has no geotransform: a light position needs one")
    col, row = ~d.transform @ (x, y)
    return row - 0.5, col - 0.5


def reference_distance(z, row: float, col: float, height: float) -> float:
    """The light's height above the ground beneath it (bilinear at its place, or at the nearest
    point of the raster's cell centres when it is off them): inverse-square's distance of 1."""
    from ..engine.arrays import ground_height
    rows, cols = z.shape
    r = min(max(row, 0.0), rows - 1.0)
    c = min(max(col, 0.0), cols - 1.0)
    ground = ground_height(z, r, c)
    if not math.isfinite(ground):
        raise HillshadeError("--falloff inverse-square needs ground beneath the light (it is "
                             f"over nodata at row {row:.2f} col {col:.2f}); give --falloff none")
    if height <= ground:
        where = "beneath it" if (r, c) == (row, col) else "at the raster's edge nearest it"
        raise HillshadeError(f"--falloff inverse-square: the light ({height:g} m) is not above "
                             f"the ground {where} ({ground:g} m)")
    return height - ground


def point_light_relief(d, x: float, y: float, z: float, *, ambient: float = 0.2,
                       falloff: str = "none", bits: int = 8,
                       height_above_ground: float = 0.0, mask=None) -> dict:
    """Shaded relief of a ``Dem`` (``read_dem``; its ``grid`` the ground spacing) lit by a point
    light at (``x``, ``y``) in its CRS and ``z`` metres above the datum: a dict with ``direct``
    (float32 0..1, NaN voids: Lambert x lit x falloff), ``relief`` (the hillshade's integers:
    uint8 1..255 or uint16 1..65535 with ``bits`` 16, 0 nodata), ``mask`` (the cast shadows,
    ``arrays.point_light_mask``; given, it is used as is), ``row``, ``col`` (the light's cell),
    ``d_ref`` (inverse-square's distance of 1; None without falloff)."""
    from ..algorithms.lightmap import direct_light, encode
    from ..engine.arrays import point_light_mask
    if falloff not in FALLOFFS:
        raise UsageProblem(f"--falloff must be one of {', '.join(FALLOFFS)}, got {falloff!r}")
    if not (0.0 <= ambient <= 1.0):
        raise UsageProblem(f"--ambient must be within 0..1, got {ambient}")
    lift = float(height_above_ground)
    if not (math.isfinite(lift) and lift >= 0.0):
        raise HillshadeError(f"height_above_ground must be finite metres >= 0, got "
                             f"{height_above_ground}")
    row, col = light_cell(d, x, y)
    if mask is None:
        mask = point_light_mask(d, x, y, z, height_above_ground=lift)
    d_ref = reference_distance(d.heights, row, col, z) if falloff == "inverse-square" else None
    direct = direct_light(d.heights, d.grid, mask, row, col, z, lift, falloff, d_ref or 0.0)
    return {"direct": direct, "relief": encode(direct, ambient, bits), "mask": mask, "row": row,
            "col": col, "d_ref": d_ref}


def lightmap(cfg: LightmapConfig) -> dict:
    """Write the point light's shaded relief of the DEM; returns the report. Bad input raises
    before anything is written. The preamble and the tail every run shares:
    ``run.runner.RunContext`` (the paths claimed, the threads; the CPU, the only backend of the
    lightmap kernels; the report and the summary)."""
    import numpy as np

    from ..io import check_output_format, input_label, output_driver, write_png, write_raster
    from ..pictures.preview import relief_rgb
    from .config import apply_scale
    from .runner import RunContext

    ro = cfg.run
    dem, output, position, lonlat = cfg.check()
    ctx = RunContext.start(ro, inputs=[dem], outputs=[(output, "OUTPUT")], backend=False,
                           note=False)
    timer = ctx.timer
    dtype = "uint8" if cfg.bits == 8 else "uint16"
    check_output_format(output, output_driver(output, ro.fmt), dtype, 1, True, ro.creation_options)
    with timer("read"):
        d = cfg.read.read(dem)
    if cfg.scale is not None:
        apply_scale(d, cfg.scale)
    x, y, zl = light_xy(d, position, lonlat)
    with timer("compute"):
        res = point_light_relief(d, x, y, zl, ambient=cfg.ambient, falloff=cfg.falloff,
                                 bits=cfg.bits, height_above_ground=cfg.height_above_ground)
    relief, mask, row, col = res["relief"], res["mask"], res["row"], res["col"]
    top = 255 if cfg.bits == 8 else 65535
    tags = {"HILLSHADE_RT_VERSION": __version__,
            "VALUES": f"1..{top} shaded relief lit by a point light: 1 + {top - 1} x (ambient + "
                      f"(1 - ambient) x direct), 0=nodata",
            "LIGHT": f"point light at x={x:.6f} y={y:.6f} z={zl:g} m (the DEM's CRS)",
            "LIGHT_CELL": f"row {row:.3f} col {col:.3f}",
            "AMBIENT": f"{cfg.ambient:g}", "FALLOFF": cfg.falloff,
            "HEIGHT_ABOVE_GROUND_M": f"{float(cfg.height_above_ground):g}"}
    if res["d_ref"] is not None:
        tags["FALLOFF_REFERENCE_M"] = f"{res['d_ref']:g}"
    with timer("write"):
        write_raster(output, relief, d, nodata=0,
                     description="shaded relief (point light)", tags=tags,
                     overview_resampling="average", overwrite=ro.overwrite, fmt=ro.fmt,
                     co=ro.creation_options)
        if ro.preview is not None:
            write_png(ro.preview, relief_rgb(d.heights, d.grid,
                                             shade=np.where(mask == 1, 1.0, 0.0)), ro.overwrite)
    valid = mask != 255
    share = float((mask[valid] == 1).mean()) if valid.any() else 0.0
    direct = res["direct"]
    rep = {"input": input_label(d.path), "output": os.path.abspath(output),
           "shape": list(d.shape), "product": {"kind": "hillshade", "light": "point",
                                               "ambient": cfg.ambient, "falloff": cfg.falloff,
                                               "falloff_reference_m": res["d_ref"],
                                               "bits": cfg.bits, "scale": cfg.scale},
           "light": {"x": x, "y": y, "z": zl, "row": row, "col": col},
           "height_above_ground_m": float(cfg.height_above_ground),
           "shadow_fraction": share,
           "direct_mean": float(np.nanmean(direct)) if valid.any() else None,
           "backend": ctx.backend, "algorithm": "point (plain march) + Lambert",
           "seconds": ctx.seconds(), "version": __version__}
    return ctx.finish(rep, [("summary", f"hillshade-rt: {output}: {d.shape[1]}x{d.shape[0]}, "
                                        f"{cfg.bits}-bit relief lit by a point light at row "
                                        f"{row:.1f} col {col:.1f} z {zl:g} m (falloff "
                                        f"{cfg.falloff}): {100 * share:.2f}% of valid cells in "
                                        f"cast shadow; compute {timer.seconds['compute']:.2f} s")])
