"""The ``skyview`` run: the sky view factor of every cell from its horizon in N directions.

* ``zaksek`` (Zakšek, Oštir & Kokalj 2011; HORAYZON's "visible sky fraction"): 1 - mean over the
  directions of sin(γ), γ the horizon elevation clipped at the horizontal (the sky is the upper
  hemisphere: terrain below the horizontal hides none of it). A flat plane: 1; a plane of slope
  S: 1 - S/π (S in radians, continuous directions).
* ``dozier`` (Dozier & Frew 1990; Dozier 2022, eq. for Vd): the cosine-weighted view of the sky
  from the tilted surface, (1/2π) ∫ [cos S sin² H + sin S cos(φ - A) (H - sin H cos H)] dφ, H the
  horizon's zenith angle (π/2 - γ), S and A the cell's slope and aspect (Horn's normals, as the
  hillshade's): a plane of slope S gives (1 + cos S)/2, the rest, (1 - cos S)/2, being the
  terrain it faces: ``terrain_configuration`` writes that share, 1 - Vd (the view factor of
  the terrain, for reflected light). (Issue 20's ``--openness`` and ``--max-distance`` are not
  built yet.)

Each direction is the ``horizon`` scan (exact on the model, curvature as for ``horizon``),
accumulated as it is made (one direction's angles in memory at a time). At the raster's edge
there is no terrain beyond it: a border cell sees open sky toward the outside (a larger DEM
around the area of interest fixes that). Distances are ground metres throughout (per row on
geographic DEMs).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from .. import __version__
from ..errors import UsageProblem
from .config import ReadOptions, RunOptions

from ..algorithms.skyview import DEFINITIONS  # (the definitions, once)


@dataclass
class SkyviewConfig:
    dem: str
    output: str
    directions: int = 32
    definition: str = "zaksek"
    terrain_configuration: bool = False   # 1 - Vd (Dozier's): the terrain a tilted cell sees
    curvature: object = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)


def skyview(cfg: SkyviewConfig) -> dict:
    import numba

    from ..algorithms import horizon as hz
    from ..earth import dem_body
    from ..geometry import equal_azimuths
    from ..io import check_output_format, input_label, output_driver, write_raster
    from ..io.write import Claims
    from ..shading import choose_backend, horizon_shader
    from .report import Timer

    ro = cfg.run
    if cfg.definition not in DEFINITIONS:
        raise UsageProblem(f"--definition must be one of {', '.join(DEFINITIONS)}, got "
                           f"{cfg.definition!r}")
    if cfg.terrain_configuration and cfg.definition != "dozier":
        raise UsageProblem("--terrain-configuration is 1 - Dozier's view factor: give "
                           "--definition dozier")
    if not 4 <= int(cfg.directions) <= 360:
        raise UsageProblem(f"--directions must be between 4 and 360, got {cfg.directions}")
    timer = Timer()
    Claims([cfg.dem], ro.overwrite).claim(cfg.output, "OUTPUT")
    check_output_format(cfg.output, output_driver(cfg.output, ro.fmt), "float32", 1, True)
    if ro.threads is not None:
        numba.set_num_threads(min(ro.threads, numba.config.NUMBA_NUM_THREADS))
    ran_on = choose_backend(ro.backend, "horizon", {"method": "scan"})
    with timer("read"):
        d = cfg.read.read(cfg.dem)
    shader = horizon_shader(d.heights, d.grid, ran_on, cfg.curvature, cfg.refraction_k,
                            dem_body(d))
    gpu_dem = None
    if ran_on == "gpu":
        from ..gpu import GpuDem
        gpu_dem = GpuDem(d.heights)
    n = int(cfg.directions)
    azimuths = equal_azimuths(360.0 / n)

    pyramid = None if gpu_dem is not None else shader.pyramid(d.heights, True)  # one for all

    def angles_of(a):
        rays = shader.rays(d.grid, a, 45.0)
        if gpu_dem is not None:
            return hz.horizon_angles_gpu(gpu_dem, rays)
        return hz.horizon_angles(d.heights, rays, pyramid=pyramid)

    from ..algorithms.skyview import sky_view
    with timer("compute"):
        svf = sky_view(d.heights, d.grid, azimuths, angles_of, cfg.definition)
        if cfg.terrain_configuration:     # the rest of the surface's hemisphere: terrain
            svf = (1.0 - svf).astype(np.float32)
    what = ("terrain configuration factor (1 - Vd, dozier)" if cfg.terrain_configuration
            else f"sky view factor ({cfg.definition})")
    tags = {"HILLSHADE_RT_VERSION": __version__, "DEFINITION": cfg.definition,
            "PRODUCT": what,
            "DIRECTIONS": n, "UNITS": "fraction 0..1",
            "EDGE": "no terrain beyond the raster: border cells see open sky outward",
            "EARTH_CURVATURE": "on" if shader.curvature else "off"}
    with timer("write"):
        write_raster(cfg.output, np.where(np.isnan(svf), np.float32(-9999.0), svf), d,
                     nodata=-9999.0, description=what,
                     tags=tags, overview_resampling="average", overwrite=ro.overwrite,
                     fmt=ro.fmt)
    rows, cols = d.shape
    valid = svf[~np.isnan(svf)]
    rep = {"input": input_label(d.path), "output": os.path.abspath(cfg.output),
           "shape": [rows, cols], "definition": cfg.definition, "directions": n,
           "backend": ran_on, "curvature": bool(shader.curvature),
           "svf": {"min": float(valid.min()) if valid.size else None,
                   "mean": float(valid.mean()) if valid.size else None},
           "seconds": dict(timer.seconds, total=timer.total()), "version": __version__}
    if not ro.quiet:
        ro.say("summary", f"hillshade-rt: {cfg.output}: {cols}x{rows}, {what}, "
                          f"{n} directions, mean "
                          f"{rep['svf']['mean'] if valid.size else math.nan:.3f}; compute "
                          f"{timer.seconds['compute']:.2f} s")
    return rep
