"""The ``shadow --subsolar LAT,LON`` run (``arrays.subsolar_mask``): the sun
given by its subsolar point on the DEM's body (``--body`` overrides the CRS's) and its distance
(``--sun-distance``, default the body's mean distance), every cell lit by its own sun; or a
series of them (``--subsolar-file F``, ``ephemeris.read_subsolar``): one band per time, the
cells' frames and the pyramid prepared once. In memory; hard shadows or --soft (the visible fraction of the solar disk, whose radius is
asin(R_sun / distance)); the CPU, or the GPU (``--backend gpu``, or ``auto`` on a real
device). What it does not take yet
(--azimuth/--time, a point light, --classes, --self-shadow, --algorithm, windows, Dask) is a
usage error that says so."""

from __future__ import annotations

import os

from .. import __version__
from ..errors import UsageProblem
from .config import SubsolarConfig


def subsolar_shadow(cfg: SubsolarConfig) -> dict:
    """Write the per-cell-sun cast-shadow mask of the DEM; returns the report. The preamble
    and the tail every run shares: ``run.runner.RunContext`` (the paths claimed, the threads,
    the backend by the one rule, ``auto`` the GPU on a real device; the report and the
    summary)."""
    import numpy as np

    from ..engine.arrays import subsolar_mask
    from ..engine.cell_suns import (
        CellFrames, body_from_option, cell_suns, mean_sun_distance, sun_radius_deg, sun_vector
    )
    from ..model.earth import dem_body
    from ..errors import HillshadeError
    from ..io import check_output_format, output_driver, write_png, write_raster
    from ..pictures.preview import relief_rgb
    from ..engine.products import product
    from .runner import RunContext

    ro = cfg.run
    dem, output, point = cfg.check()
    ctx = RunContext.start(ro, inputs=[dem], outputs=[(output, "OUTPUT")], note=False)
    timer = ctx.timer
    if cfg.body is not None:
        body_from_option(cfg.body)              # a bad --body: exit 2 before anything is read
    prod = product("shadow", bool(cfg.soft))
    if not (point is None and _is_cube(output, ro)):    # (a series' cube: io.cube checks)
        check_output_format(output, output_driver(output, ro.fmt), prod.dtype, 1,
                            prod.continuous, ro.creation_options)
    series = None
    if point is None:
        from ..model.ephemeris import read_subsolar
        if ro.preview is not None:
            raise UsageProblem("--preview shows one sun: not with --subsolar-file")
        series = read_subsolar(cfg.subsolar_file)  # a bad file: nothing read, nothing written
    with timer("read"):
        d = cfg.read.read(dem)
    if d.transform is None or d.crs is None:
        raise HillshadeError("--subsolar needs a DEM with a geotransform and a CRS (each "
                             "cell's place on the body)")
    body = body_from_option(cfg.body, dem_body(d))
    distance = mean_sun_distance(body) if cfg.sun_distance is None else float(cfg.sun_distance)
    if not distance > body.a:
        raise UsageProblem(f"--sun-distance must exceed the body's radius ({body.a:.0f} m, "
                           f"{body.source}), got {distance:g} m")
    curvature = True if cfg.curvature is None else bool(cfg.curvature)
    if series is not None:
        return _series(cfg, ctx, d, output, series, body, distance, curvature, prod)
    lat, lon = point
    s = sun_vector(body, lat, lon, distance)
    with timer("compute"):
        frames = CellFrames.of_dem(d)
        arr = subsolar_mask(d, lat, lon, body=body, height_above_ground=cfg.height_above_ground,
                            curvature=curvature, refraction_k=cfg.refraction_k, frames=frames,
                            sun_xyz=s, soft=bool(cfg.soft),
                            backend=ctx.backend)
        az, el = cell_suns(frames, body, s, d.heights, float(cfg.height_above_ground))
    arr, valid, share = _band(arr, bool(cfg.soft), prod)
    shade = np.where(valid, 1.0 - arr, 0.0) if cfg.soft else np.where(arr == 1, 1.0, 0.0)
    el_v = el[valid] if valid.any() else el.ravel()
    az_v = az[valid] if valid.any() else az.ravel()
    tags = {"HILLSHADE_RT_VERSION": __version__, "VALUES": prod.values,
            "SUBSOLAR": f"lat {lat:g} lon {lon:g} (degrees on {body.source})",
            "SUN_DISTANCE_M": f"{distance:.6g}",
            "HEIGHT_ABOVE_GROUND_M": f"{float(cfg.height_above_ground):g}"}
    with timer("write"):
        write_raster(output, arr, d, nodata=prod.nodata, description=f"{prod.what} (per-cell "
                     "suns)", tags=tags, overwrite=ro.overwrite, fmt=ro.fmt,
                     co=ro.creation_options)
        if ro.preview is not None:
            write_png(ro.preview, relief_rgb(d.heights, d.grid, shade=shade), ro.overwrite)
    rep = _report(cfg, ctx, d, output, body, curvature,
                  subsolar={"lat": lat, "lon": lon},
                  sun_distance_m=distance,
                  sun={"elevation_deg": [float(el_v.min()), float(el_v.max())],
                       "azimuth_deg": [float(az_v.min()), float(az_v.max())],
                       "azimuth": "true, clockwise from north"},
                  sun_radius_deg=sun_radius_deg(distance), shadow_fraction=share)
    half = " (less than half the disk)" if cfg.soft else ""
    return ctx.finish(rep, [("summary", f"hillshade-rt: {output}: {d.shape[1]}x{d.shape[0]}, "
                                        f"subsolar point {lat:g},{lon:g} on {body.source}: sun "
                                        f"elevation {el_v.min():.2f}..{el_v.max():.2f} deg; "
                                        f"{100 * share:.2f}% of valid cells in shadow{half}; "
                                        f"compute {timer.seconds['compute']:.2f} s")])


def _is_cube(output: str, ro) -> bool:
    """Whether a series goes into one CF time cube (``io.cube.cube_output``)."""
    from ..io.cube import cube_output
    return cube_output(output, ro.fmt, ro.creation_options) is not None


def _series_writer(cfg: SubsolarConfig, output: str, d, series, dist, prod, tags: dict):
    """The series' writer: a GeoTIFF's bands (``io.BandWriter``), or a time cube
    (``io.cube.CubeWriter``: the subsolar points and the distance per time)."""
    from ..io import BandWriter
    ro = cfg.run
    if not _is_cube(output, ro):
        return BandWriter(output, d, len(series), prod.dtype, prod.nodata, tags=tags,
                          overwrite=ro.overwrite, fmt=ro.fmt, co=ro.creation_options)
    from ..io.cube import CubeWriter
    from .outputs import cube_attrs, cube_globals, cube_name
    return CubeWriter(
        output, d, series.times(), name=cube_name(prod), dtype=prod.dtype, nodata=prod.nodata,
        attrs=cube_attrs(prod),
        time_variables={
            "subsolar_lat": (series.lat, {"long_name": "latitude of the subsolar point",
                                          "units": "degrees_north"}),
            "subsolar_lon": (series.lon, {"long_name": "longitude of the subsolar point",
                                          "units": "degrees_east"}),
            "sun_distance": (dist, {"long_name": "distance to the sun", "units": "m"})},
        global_attrs=cube_globals(f"hillshade-rt: {prod.what} of a subsolar series (every "
                                  "cell its own sun)", tags, cfg.command),
        overwrite=ro.overwrite)


def _series(cfg: SubsolarConfig, ctx, d, output: str, series, body, default_distance: float,
            curvature: bool, prod) -> dict:
    """``shadow --subsolar-file F``: one band per position of the series (description: its UTC
    time; tags: the subsolar point and the distance), the frames and the pyramid made once,
    the masks computed into one reused buffer; a progress bar. Returns the report."""
    import numpy as np

    from ..engine.arrays import subsolar_mask
    from ..engine.cell_suns import CellFrames, sun_vector
    from ..errors import HillshadeError
    from ..model.times import iso
    from .report import progress

    ro, timer, backend = cfg.run, ctx.timer, ctx.backend
    dist = (np.full(len(series), default_distance) if series.distance is None
            else np.asarray(series.distance, np.float64))
    if not (dist > body.a).all():
        i = int(np.argmin(dist > body.a))
        raise HillshadeError(f"{series.path}: the sun's distance at {iso(series.times()[i])} "
                             f"({dist[i]:g} m) is inside the body ({body.source}, radius "
                             f"{body.a:.0f} m)")
    times = series.times()
    tags = {"HILLSHADE_RT_VERSION": __version__, "VALUES": prod.values,
            "SUBSOLAR_FILE": os.path.basename(series.path),
            "BODY": body.source,
            "HEIGHT_ABOVE_GROUND_M": f"{float(cfg.height_above_ground):g}"}
    shares = []
    with timer("compute"):
        frames = CellFrames.of_dem(d)
        pyramid = None
        if backend == "cpu" and np.isfinite(d.heights).any():
            from ..algorithms.pyramid import MaxPyramid
            z = d.heights if d.heights.dtype == np.float32 else d.heights.astype(np.float32)
            pyramid = MaxPyramid(z)
    with _series_writer(cfg, output, d, series, dist, prod, tags) as w:
        for i in progress(range(len(series)), ro.quiet, "subsolar positions", "position",
                             mode=ro.progress):
            lat, lon = float(series.lat[i]), float(series.lon[i])
            with timer("compute"):
                s = sun_vector(body, lat, lon, float(dist[i]))
                buf = subsolar_mask(d, lat, lon, body=body,
                                    height_above_ground=cfg.height_above_ground,
                                    curvature=curvature, refraction_k=cfg.refraction_k,
                                    frames=frames, pyramid=pyramid, sun_xyz=s,
                                    soft=bool(cfg.soft), backend=backend)
                band, _, share = _band(buf, bool(cfg.soft), prod)
                shares.append(share)
            with timer("write"):
                w.write(i + 1, band, description=iso(times[i]),
                        tags={"TIME": iso(times[i]), "SUBSOLAR": f"lat {lat:g} lon {lon:g}",
                              "SUN_DISTANCE_M": f"{dist[i]:.6g}"})
    rep = _report(cfg, ctx, d, output, body, curvature,
                  subsolar_file=os.path.abspath(series.path), times=[iso(t) for t in times],
                  subsolar=[{"lat": float(a), "lon": float(b)}
                            for a, b in zip(series.lat, series.lon)],
                  sun_distance_m=[float(x) for x in dist], shadow_fraction=shares)
    return ctx.finish(rep, [("summary", f"hillshade-rt: {output}: {d.shape[1]}x{d.shape[0]}, "
                                        f"{len(series)} subsolar positions on {body.source} (one "
                                        f"band each): {100 * min(shares):.2f}.."
                                        f"{100 * max(shares):.2f}% of valid cells in shadow; "
                                        f"compute {timer.seconds['compute']:.2f} s")])


def _band(arr, soft: bool, prod):
    """(the band as written, valid cells, share of the valid cells in shadow) of a mask (1
    shadow, 0 lit, 255 void) or a visible fraction (NaN void: ``prod.nodata`` written)."""
    import numpy as np
    if soft:
        valid = np.isfinite(arr)
        share = float((arr[valid] < 0.5).mean()) if valid.any() else 0.0
        return np.where(valid, arr, np.float32(prod.nodata)).astype(np.float32), valid, share
    valid = arr != 255
    return arr, valid, float((arr[valid] == 1).mean()) if valid.any() else 0.0


def _report(cfg: SubsolarConfig, ctx, d, output: str, body, curvature: bool, **sun) -> dict:
    """The report of a ``--subsolar`` or ``--subsolar-file`` run (``sun``: the keys of the
    sun(s)); ``RunContext.finish`` writes it (--report)."""
    from ..model.earth import refraction_for
    from ..io import input_label
    rep = {"input": input_label(d.path), "output": os.path.abspath(output),
           "shape": list(d.shape), **sun,
           "body": {"source": body.source, "a_m": body.a, "b_m": body.b},
           "curvature": {"applied": curvature,
                         "refraction_k": refraction_for(body, cfg.refraction_k)
                         if curvature else None},
           "soft": bool(cfg.soft), "height_above_ground_m": float(cfg.height_above_ground),
           "backend": ctx.backend,
           "algorithm": "subsolar (pyramid march, a sun per cell)",
           "seconds": ctx.seconds(), "version": __version__}
    return rep
