"""The ``shadow --light-position`` / ``--light-lonlat`` run: a DEM lit by a point light (issue
21, item 1; ``algorithms.point``): each cell's ray runs straight to the light and ends there.
In memory, on the CPU, hard shadows: the combinations not built yet (windows, Dask, the GPU,
--soft, --classes, --self-shadow, series) are usage errors that say so."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import ReadOptions, RunOptions


@dataclass
class LightConfig:
    """``files``: DEM and OUTPUT (or the DEM alone with ``output``); ``position`` (x, y, z: the
    DEM's CRS, metres above the datum) or ``lonlat`` (lon, lat, z: WGS84 degrees), as numbers
    or the command line's 'A,B,C' texts; ``refused``: the options given with the light that it
    does not take yet (name -> given), a usage error naming them."""

    files: list
    output: str | None = None
    position: object = None
    lonlat: object = None
    height_above_ground: float = 0.0
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    refused: dict = field(default_factory=dict)

    def check(self) -> tuple:
        """(dem, output, position, lonlat) checked: one light, one DEM, nothing refused."""
        from .config import inputs_and_output
        taken = [name for name, on in self.refused.items() if on]
        if taken:
            raise UsageProblem(f"a point light does not take {', '.join(taken)} (yet: in "
                               "memory, on the CPU, hard shadows)")
        if (self.position is None) == (self.lonlat is None):
            raise UsageProblem("give --light-position X,Y,Z or --light-lonlat LON,LAT,Z, one "
                               "of them")
        inputs, output = inputs_and_output(self.files, self.output, None)
        if len(inputs) != 1:
            raise UsageProblem("a point light lights one DEM: give DEM OUTPUT")
        pos = None if self.position is None else parse_triple(self.position,
                                                               "--light-position")
        ll = None if self.lonlat is None else parse_triple(self.lonlat, "--light-lonlat")
        return inputs[0], output, pos, ll


def parse_triple(text, what: str) -> tuple[float, float, float]:
    """'A,B,C' as three finite floats (a usage error otherwise)."""
    if isinstance(text, (tuple, list)):
        parts = list(text)
    else:
        parts = str(text).split(",")
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        vals = ()
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise UsageProblem(f"{what} takes three numbers A,B,C, got {text!r}")
    return vals


def light_shadow(cfg: LightConfig) -> dict:
    """Write the point light's cast-shadow mask of the DEM; returns the report."""
    import numpy as np

    from ..arrays import point_light_mask
    from ..io import check_output_format, input_label, output_driver, write_json, write_png, \
        write_raster
    from ..io.write import Claims
    from ..preview import relief_rgb
    from .report import Timer

    ro = cfg.run
    dem, output, position, lonlat = cfg.check()
    timer = Timer()
    claims = Claims([dem], ro.overwrite)
    claims.claim(output, "OUTPUT")
    for extra, what in ((ro.report_path, "--report"), (ro.preview, "--preview")):
        if extra is not None:
            claims.claim(extra, what)
    check_output_format(output, output_driver(output, ro.fmt), "uint8", 1, False)
    with timer("read"):
        d = cfg.read.read(dem)
    if lonlat is not None:
        if d.crs is None:
            raise HillshadeError("--light-lonlat needs a DEM with a CRS; give --light-position "
                                 "in the DEM's coordinates")
        from pyproj import Transformer
        lon, lat, zl = lonlat
        x, y = Transformer.from_crs("EPSG:4326", d.crs.to_wkt(), always_xy=True).transform(lon,
                                                                                           lat)
    else:
        x, y, zl = position
    if d.transform is None:
        raise HillshadeError("the DEM has no geotransform: a light position needs one")
    st: dict = {}
    with timer("compute"):
        mask = point_light_mask(d, x, y, zl, height_above_ground=cfg.height_above_ground,
                                backend=ro.backend, stats=st)
    col, row = ~d.transform @ (x, y)
    tags = {"HILLSHADE_RT_VERSION": __version__, "VALUES": "1 shadow, 0 lit, 255 nodata",
            "LIGHT": f"point light at x={x:.6f} y={y:.6f} z={zl:g} m (the DEM's CRS)",
            "LIGHT_CELL": f"row {row - 0.5:.3f} col {col - 0.5:.3f}",
            "HEIGHT_ABOVE_GROUND_M": f"{float(cfg.height_above_ground):g}"}
    with timer("write"):
        write_raster(output, mask, d, nodata=255, description="cast shadow (point light)",
                     tags=tags, overwrite=ro.overwrite, fmt=ro.fmt)
        if ro.preview is not None:
            write_png(ro.preview, relief_rgb(d.heights, d.grid,
                                             shade=np.where(mask == 1, 1.0, 0.0)), ro.overwrite)
    valid = mask != 255
    share = float((mask[valid] == 1).mean()) if valid.any() else 0.0
    rep = {"input": input_label(d.path), "output": os.path.abspath(output),
           "shape": list(d.shape), "light": {"x": x, "y": y, "z": zl, "row": row - 0.5,
                                             "col": col - 0.5},
           "height_above_ground_m": float(cfg.height_above_ground),
           "shadow_fraction": share, "backend": st["backend"],
           "algorithm": "point (pyramid march)",
           "seconds": dict(timer.seconds, total=timer.total()), "version": __version__}
    if "gpu" in st:
        rep["gpu"] = st["gpu"]
    if ro.report_path is not None:
        write_json(ro.report_path, rep, ro.overwrite)
    if not ro.quiet:
        ro.say("summary", f"hillshade-rt: {output}: {d.shape[1]}x{d.shape[0]}, point light "
                          f"at row {row - 0.5:.1f} col {col - 0.5:.1f} z {zl:g} m: "
                          f"{100 * share:.2f}% of valid cells in shadow; compute "
                          f"{timer.seconds['compute']:.2f} s")
    return rep
