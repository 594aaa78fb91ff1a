"""The ``horizon`` run: the horizon angle toward one azimuth of every cell of a DEM (float32
degrees above the horizontal, -9999 nodata). Returns the report."""

from __future__ import annotations

import os

from .. import __version__
from ..errors import UsageProblem
from .config import HorizonConfig


def horizon(cfg: HorizonConfig) -> dict:
    import numba
    import numpy as np

    from ..algorithms import horizon as hz
    from ..shading import Shader
    from ..earth import dem_body
    from ..geometry import Grid, normalize_azimuth, sun_rays
    from ..io import check_output_format, input_label, output_driver, write_png, write_raster
    from ..preview import relief_rgb
    from ..shading import choose_backend, warm_up
    from ..io.write import Claims
    from .notes import compile_note
    from .report import Timer

    ro, output, method, sample_spacing = cfg.run, cfg.output, cfg.method, cfg.sample_spacing
    timer = Timer()
    az = normalize_azimuth(cfg.azimuth)
    claims = Claims([cfg.dem], ro.overwrite)
    claims.claim(output, "OUTPUT")
    if ro.preview is not None:
        claims.claim(ro.preview, "--preview")
    check_output_format(output, output_driver(output, ro.fmt), "float32", 1, False)
    if method == "hull" and sample_spacing != 1:
        raise UsageProblem("--sample-spacing applies to --method scan only")
    if ro.threads is not None:
        numba.set_num_threads(min(ro.threads, numba.config.NUMBA_NUM_THREADS))
    ran_on = choose_backend(ro.backend, "horizon", {"method": method})
    if not ro.quiet:
        note = compile_note("horizon", ran_on)
        if note:
            ro.say("compile", note)
    with timer("read"):
        d = cfg.read.read(cfg.dem)
    stats: dict = {}
    with timer("prepare"):  # numba compilation on a first run
        # the elevation does not enter the angles; curvature "auto" looks at the raster's size
        shader = Shader(d.heights, d.grid, "horizon", {}, ran_on,
                        "auto" if cfg.curvature is None else cfg.curvature, cfg.refraction_k,
                        dem_body(d))
        if shader.curvature == "auto":   # the hull has no curvature: off unless asked for
            shader.curvature = shader.extent_m > 1000.0 and method == "scan"
        rays = shader.rays(d.grid, az, 45.0)
        small = sun_rays(Grid.uniform(4, 4, *d.grid.centre_spacing(), d.grid.col_sign,
                                      d.grid.row_sign), az, 45.0)
        if ran_on == "gpu":
            from ..gpu import GpuDem
            hz.horizon_angles_gpu(GpuDem(np.eye(4, dtype=np.float32)), small, method,
                                  sample_spacing)
            gpu_dem = GpuDem(d.heights)
        else:
            warm_up("horizon", d.grid, az, 45.0, method=method, sample_spacing=sample_spacing)
            hz.horizon_angles(np.zeros((4, 4), np.float32), small, method=method,
                              sample_spacing=sample_spacing)
    with timer("compute"):
        if ran_on == "gpu":
            beta = hz.horizon_angles_gpu(gpu_dem, rays, method, sample_spacing)
        else:
            beta = hz.horizon_angles(d.heights, rays, method=method,
                                     sample_spacing=sample_spacing, stats=stats)
        shade = (np.clip(np.nan_to_num(beta, nan=0.0) / 30.0, 0.0, 1.0)
                 if ro.preview else None)
        beta[np.isnan(beta)] = -9999.0
    tags = {"HILLSHADE_RT_VERSION": __version__, "AZIMUTH": az, "METHOD": method,
            "SAMPLE_SPACING": sample_spacing, "UNITS": "degrees above the horizontal",
            "EARTH_CURVATURE": (f"on, R {shader.body.radius(az):.0f} m, k {shader.k:g}"
                                if rays.curved else "off")}
    with timer("write"):
        write_raster(output, beta, d, nodata=-9999.0, description="horizon angle", tags=tags,
                     overwrite=ro.overwrite, fmt=ro.fmt)
        if ro.preview is not None:
            write_png(ro.preview, relief_rgb(d.heights, d.grid, az, 45.0, shade=shade),
                      ro.overwrite)
    rows, cols = d.shape
    rep = {"input": input_label(d.path), "output": os.path.abspath(output), "shape": [rows, cols],
           "azimuth": az, "method": method, "sample_spacing": sample_spacing, "backend": ran_on,
           "curvature": bool(rays.curved), "algorithm_stats": stats,
           "seconds": dict(timer.seconds, total=timer.total()), "version": __version__}
    if not ro.quiet:
        ro.say("summary", f"hillshade-rt: {output}: {cols}x{rows}, horizon toward az {az:g} "
                          f"({method}, {ran_on}), compute {timer.seconds['compute']:.3f} s")
        if stats.get("note"):
            ro.say("note", stats["note"])
    return rep
