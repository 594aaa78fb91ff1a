"""The ``horizon`` run: the horizon angle toward one azimuth of every cell of a DEM (float32
degrees above the horizontal, -9999 nodata). Returns the report."""

from __future__ import annotations

import contextlib
import os

from .. import __version__
from ..errors import UsageProblem
from .config import HorizonConfig


def horizon(cfg: HorizonConfig) -> dict:
    import numba
    import numpy as np

    from ..algorithms import horizon as hz
    from ..shading import horizon_shader
    from ..earth import dem_body
    from ..geometry import Grid, sun_rays
    from ..io import (BandWriter, check_output_format, input_label, output_driver, write_png,
                      write_raster)
    from ..preview import relief_rgb
    from ..shading import choose_backend, warm_up
    from ..io.write import Claims
    from .notes import compile_note
    from .report import Timer

    ro, output, method, sample_spacing = cfg.run, cfg.output, cfg.method, cfg.sample_spacing
    timer = Timer()
    azimuths = cfg.azimuths()
    az = azimuths[0]
    many = cfg.directions is not None
    claims = Claims([cfg.dem], ro.overwrite)
    claims.claim(output, "OUTPUT")
    if ro.preview is not None:
        claims.claim(ro.preview, "--preview")
    if cfg.distance is not None:
        claims.claim(cfg.distance, "--distance")
    for path in [output] + ([cfg.distance] if cfg.distance is not None else []):
        check_output_format(path, output_driver(path, ro.fmt), "float32", len(azimuths), False)
    if method == "hull" and sample_spacing != 1:
        raise UsageProblem("--sample-spacing applies to --method scan only")
    if method == "hull" and cfg.distance is not None:
        raise UsageProblem("--distance comes from --method scan only (the hull keeps no "
                           "horizon point)")
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
        shader = horizon_shader(d.heights, d.grid, ran_on, cfg.curvature, cfg.refraction_k,
                                dem_body(d), method)
        small = sun_rays(Grid.uniform(4, 4, *d.grid.centre_spacing(), d.grid.col_sign,
                                      d.grid.row_sign), az, 45.0)
        gpu_dem = None
        if ran_on == "gpu":
            from ..gpu import GpuDem
            hz.horizon_angles_gpu(GpuDem(np.eye(4, dtype=np.float32)), small, method,
                                  sample_spacing)
            gpu_dem = GpuDem(d.heights)
        else:
            warm_up("horizon", d.grid, az, 45.0, method=method, sample_spacing=sample_spacing)
            hz.horizon_angles(np.zeros((4, 4), np.float32), small, method=method,
                              sample_spacing=sample_spacing)

    # one pyramid for every direction (built at the first march)
    pyramid = None if gpu_dem is not None else shader.pyramid(d.heights, True)

    def angles(a):
        """(the horizon angles toward azimuth ``a``: float32 degrees, NaN on voids; the
        distances to the horizon points, -9999 where there is none, or None)."""
        rays = shader.rays(d.grid, a, 45.0)
        dist = None if cfg.distance is None else np.empty(d.shape, np.float32)
        with timer("compute"):
            if gpu_dem is not None:
                beta = hz.horizon_angles_gpu(gpu_dem, rays, method, sample_spacing,
                                             distance=dist)
            else:
                beta = hz.horizon_angles(d.heights, rays, method=method,
                                         sample_spacing=sample_spacing, stats=stats,
                                         pyramid=pyramid, distance=dist)
            if dist is not None:
                dist[np.isnan(dist)] = -9999.0
        return beta, dist

    curved = shader.curvature_for(az, 45.0) > 0     # the same for every direction
    base = {"HILLSHADE_RT_VERSION": __version__, "METHOD": method,
            "SAMPLE_SPACING": sample_spacing, "UNITS": "degrees above the horizontal"}
    dist_tags = {"HILLSHADE_RT_VERSION": __version__, "UNITS": "metres (ground distance along "
                 "the ray to the horizon point)", "NODATA": "-9999 (a void, or nothing ahead)"}
    shade = None
    if not many:
        beta, dist = angles(az)
        shade = (np.clip(np.nan_to_num(beta, nan=0.0) / 30.0, 0.0, 1.0)
                 if ro.preview else None)
        beta[np.isnan(beta)] = -9999.0
        tags = {**base, "AZIMUTH": az,
                "EARTH_CURVATURE": (f"on, R {shader.body.radius(az):.0f} m, k {shader.k:g}"
                                    if curved else "off")}
        with timer("write"):
            write_raster(output, beta, d, nodata=-9999.0, description="horizon angle",
                         tags=tags, overwrite=ro.overwrite, fmt=ro.fmt)
            if dist is not None:
                write_raster(cfg.distance, dist, d, nodata=-9999.0,
                             description="distance to the horizon point",
                             tags={**dist_tags, "AZIMUTH": az}, overwrite=ro.overwrite,
                             fmt=ro.fmt)
    else:
        # one band per direction, written as it is made (N bands never all in memory)
        series = {"DIRECTIONS": len(azimuths), "AZIMUTHS": ",".join(f"{a:g}" for a in azimuths),
                  "AZIMUTH_CONVENTION": "degrees clockwise from north (grid north), band i at "
                                        "i * 360 / N"}
        tags = {**base, "NODATA": "-9999 (a void)", "NO_TERRAIN_AHEAD": "-90", **series,
                "EARTH_CURVATURE": f"on, k {shader.k:g}" if curved else "off"}
        dist_tags.update(series)
        with BandWriter(output, d, len(azimuths), "float32", -9999.0, tags,
                        overview_resampling="average", overwrite=ro.overwrite,
                        fmt=ro.fmt) as w, (
                contextlib.nullcontext() if cfg.distance is None else
                BandWriter(cfg.distance, d, len(azimuths), "float32", -9999.0, dist_tags,
                           overview_resampling="average", overwrite=ro.overwrite,
                           fmt=ro.fmt)) as wd:
            for i, a in enumerate(azimuths):
                beta, dist = angles(a)
                if ro.preview and i == 0:
                    shade = np.clip(np.nan_to_num(beta, nan=0.0) / 30.0, 0.0, 1.0)
                beta[np.isnan(beta)] = -9999.0
                with timer("write"):
                    w.write(i + 1, beta, description=f"horizon angle toward azimuth {a:g}",
                            tags={"AZIMUTH": f"{a:g}"})
                    if wd is not None:
                        wd.write(i + 1, dist, description=f"distance to the horizon point "
                                                          f"toward azimuth {a:g}",
                                 tags={"AZIMUTH": f"{a:g}"})
            with timer("write"):
                w.finish()
                if wd is not None:
                    wd.finish()
    if ro.preview is not None:
        with timer("write"):
            write_png(ro.preview, relief_rgb(d.heights, d.grid, az, 45.0, shade=shade),
                      ro.overwrite)
    rows, cols = d.shape
    rep = {"input": input_label(d.path), "output": os.path.abspath(output), "shape": [rows, cols],
           "distance": None if cfg.distance is None else os.path.abspath(cfg.distance),
           "azimuth": az if not many else None, "azimuths": azimuths, "method": method,
           "sample_spacing": sample_spacing, "backend": ran_on, "curvature": curved,
           "algorithm_stats": stats, "seconds": dict(timer.seconds, total=timer.total()),
           "version": __version__}
    if not ro.quiet:
        toward = (f"toward az {az:g}" if not many else
                  f"toward {len(azimuths)} directions ({360.0 / len(azimuths):g} deg apart)")
        ro.say("summary", f"hillshade-rt: {output}: {cols}x{rows}, horizon {toward} "
                          f"({method}, {ran_on}), compute {timer.seconds['compute']:.3f} s")
        if stats.get("note"):
            ro.say("note", stats["note"])
    return rep
