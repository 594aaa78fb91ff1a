"""Whole runs from Python: DEM files in, georeferenced files out, as the command line does it.

:func:`shade` is ``hillshade-rt shadow`` / ``hillshade`` as a function: one DEM or a mosaic of
tiles, one sun or a series of times, in memory or in windows under a memory limit, on this
machine or on a Dask cluster given as a ``distributed.Client``. It builds the run's config and
calls ``run.shade``, as the command line does (one source of truth for checks, outputs and the
report), and returns the report as a dict.
Bad input raises :class:`~hillshade_rt.errors.HillshadeError` with the command line's one-line
message; nothing is left half-written.

    >>> import hillshade_rt as hr
    >>> from distributed import Client
    >>> rep = hr.shade(["n46e007.tif", "n46e008.tif"], "shadow.tif", azimuth=203.7,
    ...                elevation=12, max_memory="2GB", cog=True, client=Client("tcp://s:8786"))
    >>> rep["processing"]["windows"], rep["processing"]["bytes_read_beyond_output_fraction"]

For arrays already in memory use :func:`~hillshade_rt.shadow_mask` or
:class:`~hillshade_rt.engine.shader.Shader` instead.
"""

from __future__ import annotations

import datetime as _dt
import functools
import os
import re

from .errors import HillshadeError
from .run.config import DEFAULT_WORKER_TIMEOUT, PLACE_KEYS, READ_KEYS

# keyword arguments taken through ``**more``: the run's options of the same name (the
# command line's --tz, --lat, ..., the DEM's --band, --nodata, ..., --threads)
FORWARDED = PLACE_KEYS + READ_KEYS + ("threads",)


# the command line's options that are other keywords here (the rest: --foo-bar -> foo_bar)
_KEYWORDS = {"--overwrite": "overwrite=True", "--earth-curvature": "curvature=True",
             "--no-earth-curvature": "curvature=False", "--refraction-coefficient": "refraction_k",
             "--time": "times", "--scheduler": "client", "--co": "creation_options",
             "--format": "fmt", "--soft": "soft=True", "--self-shadow": "self_shadow=True",
             "--no-self-shadow": "self_shadow=False", "--cog": "cog=True", "--each": "each=True",
             "--mean": "mean=True", "--perez": "perez=True", "--classes": "product='classes'",
             "--instant": "instant=True",
             "--no-refraction": "no_refraction=True", "--output": "output",
             "--quiet": "progress=False", "--help": "help()"}
_OPTION = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")


def _algorithm_keywords() -> dict:
    """The algorithms' own flags as ``algorithm_options`` entries (from the registry)."""
    from .algorithms import REGISTRY
    out = {}
    for spec in REGISTRY.values():
        for opt in spec.options:
            out[opt.flag] = (f"algorithm_options={{'{opt.keyword}': {opt.flag_value!r}}}"
                             if opt.kind == "flag" else f"algorithm_options['{opt.keyword}']")
    return out


def in_keywords(message: str) -> str:
    """A message of the run's checks (written for the command line) as Python's: each option
    named by this API's keyword (``--overwrite`` -> ``overwrite=True``, ``--pixel-size`` ->
    ``pixel_size``, ``--nextv`` -> ``algorithm_options['nextv']``), OUTPUT as ``output``."""
    table = {**_algorithm_keywords(), **_KEYWORDS}

    def one(m):
        flag = m.group(0)
        return table.get(flag, flag[2:].replace("-", "_"))
    return re.sub(r"\bOUTPUT\b", "output", _OPTION.sub(one, message))


def _keyword_errors(f):
    """``f`` whose :class:`HillshadeError` says this API's keywords, not the command line's
    options (its class and attributes kept)."""
    @functools.wraps(f)
    def wrapper(*args, **kwargs):
        try:
            return f(*args, **kwargs)
        except HillshadeError as exc:
            if exc.args and isinstance(exc.args[0], str):
                exc.args = (in_keywords(exc.args[0]),) + exc.args[1:]
            raise
    return wrapper


def _iso(t):
    return t.isoformat() if isinstance(t, _dt.datetime) else t


def _progress(progress) -> dict:
    """``RunOptions``' ``quiet`` and ``progress`` of the ``progress`` keyword: False (as
    ``--quiet``: nothing on stderr), True or "bar" (the bar and the summary line), "json" (as
    ``--progress json``: only the ``{"progress": F}`` lines, for a program reading stderr)."""
    from .run.report import PROGRESS_MODES
    if progress in (False, None):
        return dict(quiet=True, progress="bar")
    if progress is True:
        return dict(quiet=False, progress="bar")
    if progress not in PROGRESS_MODES:
        raise HillshadeError(f"progress must be True, False or one of "
                             f"{', '.join(map(repr, PROGRESS_MODES))}, got {progress!r}")
    return dict(quiet=progress == "json", progress=progress)


def _no_other_keywords(function: str, more: dict, allowed=FORWARDED) -> None:
    """TypeError, as Python's own, for a keyword in ``**more`` that is not one of ``allowed``
    (FORWARDED: the read options, the place's, ``threads``)."""
    unknown = set(more) - set(allowed)
    if unknown:
        raise TypeError(f"{function}() got unexpected keyword argument(s) "
                        f"{', '.join(sorted(unknown))}")


def _read_options(more: dict, context=None):
    """The read options (``run.ReadOptions``) of ``**more`` (``READ_KEYS``) and ``context``
    (--context's path, or None)."""
    from .run import ReadOptions
    return ReadOptions(**{k: more[k] for k in READ_KEYS if k in more},
                       context=None if context is None else os.fspath(context))


def _place(more: dict) -> dict:
    """The place's options (``run.config.PLACE_KEYS``) from ``**more``, the command line's
    defaults for those not given."""
    from .model.sun import DEFAULT_TOLERANCE
    return {k: more.get(k, d) for k, d in zip(PLACE_KEYS, (None,) * 5 + (False,
                                                                         DEFAULT_TOLERANCE))}


def _times(times) -> tuple:
    """The ``times`` keyword (None, one time, or many; datetimes or ISO text) as the ISO texts
    of ``--time``."""
    if times is None:
        return ()
    if isinstance(times, (str, _dt.datetime)):
        times = [times]
    return tuple(_text(t) for t in times)


def _text(v):
    """A date or datetime as ISO text (None stays None; text as it is)."""
    return None if v is None else str(v.isoformat() if hasattr(v, "isoformat") else v)


def _stderr(kind: str, message: str) -> None:
    """``say`` with ``progress=True``: the command line's lines on stderr."""
    import sys
    if kind == "note":
        message = f"hillshade-rt: note: {message}"
    elif kind == "compile":
        return
    print(message, file=sys.stderr)


@_keyword_errors
def shade(dems, output: str | None = None, *, product: str = "shadow",
          output_pattern: str | None = None, azimuth: float | None = None,
          elevation: float | None = None, times=(), start=None, end=None, step: str | None = None,
          algorithm: str = "auto", algorithm_options: dict | None = None, soft: bool = False,
          self_shadow: bool = False, ambient: float = 0.2, scale: float | None = None,
          curvature: bool | None = None, refraction_k: float | None = None,
          backend: str = "auto", max_memory=None, window_size=None, cog: bool = False,
          fmt: str | None = None, creation_options=None,
          client=None, worker_timeout: float = DEFAULT_WORKER_TIMEOUT,
          overwrite: bool = False, report: str | None = None,
          preview: str | None = None, progress: bool = False,
          height_above_ground: float = 0.0, sun_from_stac: str | None = None,
          stac_item: str | None = None, context=None, each: bool = False,
          light_position=None, light_lonlat=None, falloff: str | None = None,
          bits: int | None = None, subsolar=None, subsolar_file=None,
          sun_distance: float | None = None, body: str | None = None, vector=None,
          vector_connectivity: int = 4, **more) -> dict:
    """Shade DEM file(s) into ``output`` (one band per sun) or ``output_pattern`` files.
    A series of times into an ``output`` named ``*.nc`` or ``*.zarr`` is one CF-1.8 time cube
    (``io.cube``: dimensions time, y, x; the sun's azimuth and elevation per time).

    ``dems``: a path or a list of paths (tiles on one grid, shaded as one surface; with
    ``{tile}`` in ``output_pattern`` one file per tile). ``product``: "shadow" (1 shadow / 0 lit;
    visible fraction of the disk with ``soft``), "classes" or "hillshade". The sun:
    ``azimuth``/``elevation``, or ``times`` (datetimes or ISO strings), or ``start``/``end``/
    ``step`` at the DEM's place. ``algorithm_options``: e.g. ``{"nextv": "quad"}``.
    ``fmt``: a GDAL driver name (default from the extension, as ``--format``).
    ``creation_options``: GDAL creation options of the files written, as ``--co`` (a mapping
    such as ``{"COMPRESS": "ZSTD"}`` or ``["COMPRESS=ZSTD"]``), over the tool's defaults.
    ``height_above_ground``: metres above every cell its ray starts from, as
    ``--height-above-ground`` (brute marches it; ``algorithm="auto"`` runs brute).
    ``sun_from_stac``: a STAC item's path or URL, its scene's sun (``--sun-from-stac``);
    ``stac_item``: also write a STAC item describing ``output`` there (``--stac-item``).
    ``max_memory`` (bytes or "2GB"), ``window_size`` ((rows, cols), an int, or "2048x2048"):
    windows as ``--max-memory``/``--window-size``. ``client``: a ``distributed.Client`` (or a
    scheduler address, or "local:N"): windows and times run as Dask tasks on it; the client is
    left open. ``worker_timeout``: seconds the run waits while the scheduler has no worker (none
    at the start, or every one lost) before it fails, as ``--worker-timeout``. ``context``: a
    raster (VRT, mosaic) on the grid of ``dems`` (one tile) whose heights its rays see, as
    ``--context``: the output covers the tile and equals the same cells of the whole raster's
    output. Further keywords are the command line's options of the
    same name (``tz``,
    ``lat``, ``lon``, ``band``, ``nodata``, ``z_factor``, ``pixel_size``, ``raw_shape``, ...).

    A point light instead of the sun, as ``--light-position``/``--light-lonlat``:
    ``light_position`` (x, y, z: the DEM's CRS, metres above the datum) or ``light_lonlat``
    (lon, lat, z: WGS84 degrees), numbers or "A,B,C" texts; every cell's ray runs to the light
    (``run.point_light``); with ``product="hillshade"`` the light's shaded relief
    (``run.lightmap``), ``falloff`` ("none", "inverse-square") and ``bits`` (8, 16) as
    ``--falloff``/``--bits``. Every cell its own sun on the DEM's body, as ``--subsolar``:
    ``subsolar`` (lat, lon or "LAT,LON") or ``subsolar_file`` (a series, one band per time),
    ``sun_distance`` (metres) and ``body`` ("moon", "mars", "earth" or a radius in metres;
    default the CRS's) as ``--sun-distance``/``--body`` (``run.subsolar``; product "shadow").
    These runs take one DEM and refuse what they do not take yet, as the command line does.
    ``progress``: False (nothing on stderr, as ``--quiet``), True or "bar" (the progress bar
    and the summary line), "json" (only ``{"progress": F}`` lines, as ``--progress json``).

    ``vector``: also write the shadow as polygons to this file (GeoPackage ``.gpkg``, GeoJSON
    ``.geojson``, FlatGeobuf ``.fgb``), in the DEM's CRS, one layer with every sun's polygons
    (attributes ``azimuth``, ``elevation``; ``time`` and ``true_azimuth`` for suns from times;
    ``index`` in a series; ``shadow_class`` with ``product="classes"``), as ``--vector``;
    ``output`` may then be None (polygons only). ``vector_connectivity``: 4 (cells joined
    through their edges) or 8 (also their corners). The report's ``vector`` gives their count
    and area.

    ``each``: many unrelated DEMs (any grid, CRS, size) in one call, each shaded on its own
    into ``output_pattern`` with ``{stem}`` (the input's file name without its extension), as
    ``--each``: the report lists each input's status (``ok``, ``empty``: every cell nodata,
    written all nodata; ``failed`` and its message) and its own run's report; when any failed,
    :class:`~hillshade_rt.run.batch.BatchFailed` (a ``HillshadeError``) is raised after the
    others are written, its ``report`` attribute the report.

    Returns the report (what ``--report`` writes; also written to ``report`` when given)."""
    from .run import RunOptions, ShadeConfig
    from .run import shade as run_shade
    from .run.batch import check_pattern, shade_each
    from .algorithms import algorithm_for, options_for
    from .run.config import PRODUCTS
    from .io.write import virtual_outputs
    if product not in PRODUCTS:
        raise HillshadeError(f"product must be one of {', '.join(PRODUCTS)}, got {product!r}")
    _no_other_keywords("shade", more)
    files = [os.fspath(dems)] if isinstance(dems, (str, os.PathLike)) else [os.fspath(p)
                                                                            for p in dems]
    if not files:
        raise HillshadeError("no DEM given")
    if not each:
        check_pattern(output_pattern, False)     # {stem} without each
    if output is None and output_pattern is None and not each and vector is None:
        raise HillshadeError("give output or output_pattern (or vector)")
    if scale is not None and product != "hillshade":
        raise HillshadeError("scale applies to product='hillshade'")
    if any(v is not None for v in (subsolar, subsolar_file, sun_distance, body, light_position,
                                   light_lonlat, falloff, bits)):
        token = virtual_outputs.set(True)
        try:
            return _other_light(
                files, output, product, dict(
                    azimuth=azimuth, elevation=elevation, times=times, start=start, end=end,
                    step=step, sun_from_stac=sun_from_stac, soft=soft, self_shadow=self_shadow,
                    algorithm=algorithm, algorithm_options=algorithm_options,
                    curvature=curvature, refraction_k=refraction_k, ambient=ambient,
                    scale=scale, height_above_ground=height_above_ground,
                    max_memory=max_memory, window_size=window_size, client=client,
                    output_pattern=output_pattern, cog=cog, stac_item=stac_item,
                    context=context, each=each, light_position=light_position,
                    light_lonlat=light_lonlat, falloff=falloff, bits=bits, subsolar=subsolar,
                    subsolar_file=subsolar_file, sun_distance=sun_distance, body=body,
                    vector=vector),
                _read_options(more),
                RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                           overwrite=overwrite, **_progress(progress), fmt=fmt,
                           preview=preview, say=_stderr, creation_options=creation_options,
                           worker_timeout=worker_timeout))
        finally:
            virtual_outputs.reset(token)
    given = dict(algorithm_options or {})
    algorithm = algorithm_for(algorithm, given)
    options = options_for(algorithm, given)
    sun = dict(azimuth=azimuth, elevation=elevation,
               time=tuple(str(_iso(t)) for t in ([times] if isinstance(times, (str, _dt.datetime))
                                                 else times)),
               start=_iso(start), end=_iso(end), step=step,
               sun_from_stac=None if sun_from_stac is None else os.fspath(sun_from_stac),
               **_place(more))
    read = _read_options(more, context)
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, **_progress(progress), fmt=fmt, preview=preview,
                     say=_stderr, creation_options=creation_options,
                     worker_timeout=worker_timeout)
    hill = product == "hillshade"
    cfg = ShadeConfig(files=files, kind=product, sun=sun,
                      default_sun=(315.0, 45.0) if hill else None,
                      algorithm=algorithm, options=options, curvature=curvature,
                      refraction_k=refraction_k, soft=soft,
                      self_shadow=hill or self_shadow or product == "classes",
                      ambient=ambient if hill else 0.2, scale=scale if hill else None,
                      read=read, run=run, output=None if output is None else os.fspath(output),
                      output_pattern=output_pattern, max_memory=max_memory,
                      window_size=window_size, cog=cog, scheduler=client,
                      height_above_ground=height_above_ground,
                      stac_item=None if stac_item is None else os.fspath(stac_item),
                      vector=None if vector is None else os.fspath(vector),
                      vector_connectivity=vector_connectivity)
    token = virtual_outputs.set(True)    # /vsimem/ outputs are fine from Python
    try:
        return shade_each(cfg) if each else run_shade(cfg)
    finally:
        virtual_outputs.reset(token)


def _other_light(files, output, product, kw, read, run) -> dict:
    """:func:`shade` with a point light (``run.point_light``; ``run.lightmap`` for
    ``product="hillshade"``) or every cell's own sun (``run.subsolar``), as the ``shadow`` and
    ``hillshade`` commands run them: ``kw`` the keywords given to :func:`shade`; what these runs
    do not take yet (a keyword away from its default) is refused, named as the command line's
    option (``in_keywords`` names it as the keyword)."""
    from .errors import UsageProblem
    output = None if output is None else os.fspath(output)
    hill, classes = product == "hillshade", product == "classes"
    subsolar = any(kw[k] is not None for k in ("subsolar", "subsolar_file", "sun_distance",
                                               "body"))
    light = kw["light_position"] is not None or kw["light_lonlat"] is not None
    sun_given = any(kw[k] not in (None, (), [], "") for k in ("azimuth", "elevation", "times",
                                                               "start", "end", "step",
                                                               "sun_from_stac"))
    refused = {"--azimuth/--elevation/--time/--start": sun_given,
               "--algorithm": kw["algorithm"] != "auto" or bool(kw["algorithm_options"]),
               "--context": kw["context"] is not None,
               "--scheduler": kw["client"] is not None,
               "--output-pattern": kw["output_pattern"] is not None, "--cog": kw["cog"],
               "--stac-item": kw["stac_item"] is not None, "--each": kw["each"],
               "--vector": kw["vector"] is not None}
    if subsolar:
        if hill:
            raise UsageProblem("--subsolar, --subsolar-file, --sun-distance and --body go with "
                               "the shadow product")
        from .run.config import SubsolarConfig
        from .run.subsolar import subsolar_shadow
        refused.update({"--light-position/--light-lonlat": light,
                        "--self-shadow": kw["self_shadow"], "--classes": classes,
                        "--window-size": kw["window_size"] is not None,
                        "--max-memory": kw["max_memory"] is not None})
        if kw["falloff"] is not None or kw["bits"] is not None:
            raise UsageProblem("--falloff and --bits go with the hillshade product")
        return subsolar_shadow(SubsolarConfig(
            files=files, output=output, subsolar=kw["subsolar"],
            sun_distance=kw["sun_distance"], body=kw["body"],
            height_above_ground=kw["height_above_ground"], soft=kw["soft"],
            curvature=kw["curvature"], refraction_k=kw["refraction_k"], read=read, run=run,
            refused=refused, subsolar_file=None if kw["subsolar_file"] is None
            else os.fspath(kw["subsolar_file"])))
    if not light:
        raise UsageProblem("--falloff and --bits go with a point light (--light-position or "
                           "--light-lonlat)")
    if hill:
        from .run.config import LightmapConfig
        from .run.lightmap import lightmap
        refused.update({"--soft": kw["soft"], "--earth-curvature": kw["curvature"] is True,
                        "--refraction-coefficient": kw["refraction_k"] is not None,
                        "--backend gpu": run.backend == "gpu",
                        "--window-size": kw["window_size"] is not None,
                        "--max-memory": kw["max_memory"] is not None})
        return lightmap(LightmapConfig(
            files=files, output=output, position=kw["light_position"],
            lonlat=kw["light_lonlat"], height_above_ground=kw["height_above_ground"],
            read=read, run=run, refused=refused, ambient=kw["ambient"], scale=kw["scale"],
            falloff=kw["falloff"] or "none", bits=int(kw["bits"] or 8)))
    if kw["falloff"] is not None or kw["bits"] is not None:
        raise UsageProblem("--falloff and --bits go with the hillshade product")
    from .run.config import LightConfig
    from .run.point_light import light_shadow
    refused.update({"--soft": kw["soft"], "--self-shadow": kw["self_shadow"],
                    "--classes": classes, "--earth-curvature": kw["curvature"] is True})
    return light_shadow(LightConfig(
        files=files, output=output, position=kw["light_position"], lonlat=kw["light_lonlat"],
        height_above_ground=kw["height_above_ground"], window_size=kw["window_size"],
        max_memory=kw["max_memory"], read=read, run=run, refused=refused))


@_keyword_errors
def irradiance(dem, output=None, *, date=None, end_date=None, start=None, end=None,
               step: str = "15min", clear_sky: str | None = None,
               linke_turbidity=None, albedo=0.2, ghi=None, beam_index=None,
               diffuse_index=None,
               mean: bool = False, daily_mean: bool = False, monthly: bool = False,
               soft: bool = False, perez: bool = False,
               skyview_directions: int = 32, algorithm: str = "auto",
               curvature: bool | None = None, refraction_k: float | None = None,
               backend: str = "auto", fmt: str | None = None, creation_options=None,
               overwrite: bool = False, report: str | None = None,
               preview: str | None = None, progress: bool = False, context=None,
               height_above_ground: float = 0.0, each: bool = False,
               output_pattern: str | None = None, sky_view=None, sky_view_out=None,
               max_memory=None, window_size=None, client=None,
               worker_timeout: float = DEFAULT_WORKER_TIMEOUT, times=None,
               instant: bool = False, **more) -> dict:
    """``hillshade-rt irradiance`` as a function: the beam, diffuse, reflected and global
    irradiance on every cell of the DEM at ``dem`` over a period, written to ``output`` (4
    float32 bands, Wh/m², or W/m² with ``mean``). The period: ``date`` (a date or
    "YYYY-MM-DD") and ``end_date``, or ``start`` and ``end`` (datetimes or ISO strings). The
    sky: ``clear_sky`` ("ineichen", the default, with ``linke_turbidity``; "haurwitz") or
    ``ghi``, the path of a measured series (CSV: time, ghi[, dni, dhi]); ``linke_turbidity``
    and ``albedo`` a number, 12 monthly numbers (a sequence or "a,b,..."), a raster's path
    or a pattern with ``{month}``; ``beam_index`` and ``diffuse_index`` (the same forms, 0..1)
    as ``--beam-index``/``--diffuse-index``, GRASS r.sun's real-sky coeff_bh and coeff_dh;
    ``daily_mean`` as ``--daily-mean`` (Wh/m²
    a day), ``monthly`` as ``--monthly`` (a global band per month after the four). Further keywords are
    the command line's options of the same name (``tz``, ``lat``, ``lon``, ``band``,
    ``nodata``, ``threads``, ...); ``fmt`` and ``creation_options`` as for :func:`shade`;
    ``context`` as ``--context`` (the DEM a tile of that raster); ``height_above_ground`` as
    ``--height-above-ground`` (metres: the receiving surface stands this high); ``sky_view``
    as ``--sky-view`` (the path of Dozier's sky view factor made by ``skyview --definition
    dozier`` with the run's settings, read instead of computed), ``sky_view_out`` as
    ``--sky-view-out`` (the path the computed one is written to). In memory, or in windows as
    ``--max-memory``/``--window-size``; ``client`` a ``distributed.Client`` (or a scheduler
    address, or "local:N"): the windows run as Dask tasks on it (``worker_timeout`` as
    ``--worker-timeout``), as :func:`sun_hours`'s; the same bits in every mode. ``each``:
    ``dem`` a list of unrelated DEMs, each on its own into ``output_pattern``'s ``{stem}``, as
    ``--each`` (no ``output``; the report lists each input's status, as :func:`shade`'s).
    ``progress`` as for :func:`shade`. ``times`` (a datetime or ISO string, or a list of
    them) as ``--time``: instead of a period, the irradiance at each of those instants (W/m²)
    and the sun's elevation above each cell's surface, five bands per time (r.sun's mode 1);
    ``instant=True`` as ``--instant``: the same at the times ``start``..``end`` every
    ``step``, or at ``date``'s sample times. Returns the report. For heights in memory:
    :func:`hillshade_rt.engine.arrays.irradiance`."""
    from .run import RunOptions
    from .run.config import IrradianceConfig
    from .run.irradiance_instant import irradiance_or_instants as run_irradiance
    from .run.batch import irradiance_each, split_files
    from .io.write import virtual_outputs
    _no_other_keywords("irradiance", more)
    dems = [dem] if isinstance(dem, (str, os.PathLike)) else list(dem)
    dem, output = split_files(dems + ([] if output is None else [output]), each,
                              output_pattern, "irradiance")
    place = _place(more)
    read = _read_options(more, context)
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, **_progress(progress), fmt=fmt, preview=preview,
                     say=_stderr, creation_options=creation_options,
                     worker_timeout=worker_timeout)
    cfg = IrradianceConfig(dem=dem, output=output, date=_text(date),
                           end_date=_text(end_date), start=_text(start), end=_text(end),
                           step=step, clear_sky=clear_sky, linke_turbidity=linke_turbidity,
                           albedo=albedo, ghi=None if ghi is None else os.fspath(ghi),
                           beam_index=beam_index, diffuse_index=diffuse_index, mean=mean,
                           daily_mean=daily_mean, monthly=monthly, soft=soft,
                           perez=perez, skyview_directions=skyview_directions, place=place,
                           algorithm=algorithm, curvature=curvature, refraction_k=refraction_k,
                           read=read, run=run, height_above_ground=height_above_ground,
                           sky_view=None if sky_view is None else os.fspath(sky_view),
                           sky_view_out=None if sky_view_out is None else os.fspath(sky_view_out),
                           max_memory=max_memory, window_size=window_size, scheduler=client,
                           times=_times(times), instant=bool(instant))
    token = virtual_outputs.set(True)    # /vsimem/ outputs are fine from Python
    try:
        return irradiance_each(cfg, dem, output_pattern) if each else run_irradiance(cfg)
    finally:
        virtual_outputs.reset(token)


@_keyword_errors
def sun_hours(dem, output=None, *, date=None, end_date=None, monthly: bool = False,
              step: str = "10min",
              algorithm: str = "auto", curvature: bool | None = None,
              refraction_k: float | None = None, soft: bool = False,
              self_shadow: bool | None = None, height_above_ground: float = 0.0,
              backend: str = "auto", max_memory=None, window_size=None, client=None,
              worker_timeout: float = DEFAULT_WORKER_TIMEOUT, fmt: str | None = None,
              creation_options=None, overwrite: bool = False, report: str | None = None,
              preview: str | None = None, progress: bool = False, context=None,
              each: bool = False, output_pattern: str | None = None, **more) -> dict:
    """``hillshade-rt sun-hours`` as a function: the hours of direct sun per cell of the DEM
    at ``dem`` over the day ``date`` (a date or "YYYY-MM-DD"; to ``end_date``, included), the
    sun every ``step``, written to ``output`` (float32 hours, -9999 nodata). In memory, or in
    windows as ``--max-memory``/``--window-size``; ``client`` a ``distributed.Client`` (or a
    scheduler address, or "local:N"): the windows run as Dask tasks on it, as :func:`shade`'s.
    The same bits in every mode. Further keywords are the command line's options of the same
    name (``tz``, ``lat``, ``lon``, ``band``, ``nodata``, ``threads``, ...); ``self_shadow``
    None: on with the observer on the ground, off above it; ``each``, ``output_pattern``,
    ``context``, ``fmt``, ``creation_options`` and ``progress`` as for :func:`irradiance`.
    Returns the report."""
    from .run import RunOptions
    from .run.config import SunHoursConfig
    from .run.sun_hours import sun_hours as run_sun_hours
    from .run.batch import split_files, sun_hours_each
    from .io.write import virtual_outputs
    _no_other_keywords("sun_hours", more)
    if date is None:
        raise HillshadeError("sun_hours needs date (the day, or the first day with end_date)")
    dems = [dem] if isinstance(dem, (str, os.PathLike)) else list(dem)
    dem, output = split_files(dems + ([] if output is None else [output]), each,
                              output_pattern, "sun-hours")
    place = _place(more)
    read = _read_options(more, context)
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, **_progress(progress), fmt=fmt, preview=preview,
                     say=_stderr, creation_options=creation_options,
                     worker_timeout=worker_timeout)
    cfg = SunHoursConfig(dem=dem, output=output, date=_text(date), end_date=_text(end_date),
                         step=step, place=place, algorithm=algorithm, curvature=curvature,
                         refraction_k=refraction_k, soft=soft, self_shadow=self_shadow,
                         read=read, run=run, height_above_ground=height_above_ground,
                         max_memory=max_memory, window_size=window_size, scheduler=client,
                         monthly=monthly)
    token = virtual_outputs.set(True)    # /vsimem/ outputs are fine from Python
    try:
        return sun_hours_each(cfg, dem, output_pattern) if each else run_sun_hours(cfg)
    finally:
        virtual_outputs.reset(token)


@_keyword_errors
def horizon(dem, output=None, *, azimuth: float | None = None, directions: int | None = None,
            start: float | None = None, end: float | None = None, step: float | None = None,
            angle_unit: str = "degrees", distance=None, method: str = "scan",
            sample_spacing: int = 1, max_distance: float | None = None,
            curvature: bool | None = None, refraction_k: float | None = None,
            height_above_ground: float = 0.0, backend: str = "auto", max_memory=None,
            window_size=None, client=None, worker_timeout: float = DEFAULT_WORKER_TIMEOUT,
            fmt: str | None = None, creation_options=None, overwrite: bool = False,
            report: str | None = None, preview: str | None = None, progress: bool = False,
            context=None, each: bool = False, output_pattern: str | None = None,
            **more) -> dict:
    """``hillshade-rt horizon`` as a function: the horizon angle of every cell of the DEM at
    ``dem`` toward ``azimuth`` (one band), or toward each of ``directions`` equally spaced
    azimuths, or toward ``start``, ``start + step``, ... before ``end`` (r.horizon's
    start/end/step in degrees clockwise from north: floor((end - start) / step) bands; start
    0 and end start + 360 by default), written to ``output`` (float32, ``angle_unit``
    "degrees" or "radians", -9999 nodata; each band's description its azimuth).
    ``distance``: the path of a second raster, the metres to each cell's horizon point. In
    memory, or in windows as ``max_memory``/``window_size``; ``client`` as for
    :func:`sun_hours`. Further keywords are the command line's options of the same name
    (``band``, ``nodata``, ``threads``, ...); ``each``, ``output_pattern``, ``context``,
    ``fmt``, ``creation_options`` and ``progress`` as for :func:`irradiance`. Returns the
    report. For heights in memory: :func:`hillshade_rt.engine.arrays.horizon_angles`."""
    from .run import HorizonConfig, RunOptions
    from .run.horizon import horizon as run_horizon
    from .run.batch import horizon_each, split_files
    from .io.write import virtual_outputs
    _no_other_keywords("horizon", more, READ_KEYS + ("threads",))
    dems = [dem] if isinstance(dem, (str, os.PathLike)) else list(dem)
    dem, output = split_files(dems + ([] if output is None else [output]), each,
                              output_pattern, "horizon")
    read = _read_options(more, context)
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, **_progress(progress), fmt=fmt, preview=preview,
                     say=_stderr, creation_options=creation_options,
                     worker_timeout=worker_timeout)
    cfg = HorizonConfig(dem=dem, output=output, azimuth=azimuth, method=method,
                        sample_spacing=sample_spacing, curvature=curvature,
                        refraction_k=refraction_k, read=read, run=run, directions=directions,
                        distance=None if distance is None else os.fspath(distance),
                        max_distance=max_distance, max_memory=max_memory,
                        window_size=window_size, scheduler=client,
                        height_above_ground=height_above_ground, start=start, end=end,
                        step=step, angle_unit=angle_unit)
    token = virtual_outputs.set(True)    # /vsimem/ outputs are fine from Python
    try:
        return horizon_each(cfg, dem, output_pattern) if each else run_horizon(cfg)
    finally:
        virtual_outputs.reset(token)


@_keyword_errors
def animate(dem, output, *, date=None, start=None, end=None, step: str | None = None,
            fps: float = 12.0, size: int = 1024, label: bool = True, algorithm: str = "auto",
            curvature: bool | None = None, refraction_k: float | None = None,
            backend: str = "auto", overwrite: bool = False, report: str | None = None,
            progress: bool = False, **more) -> dict:
    """``hillshade-rt animate`` as a function: the shadows on the DEM at ``dem`` over a day
    (``date``: a date or "YYYY-MM-DD") or a series (``start``, ``end``: datetimes or ISO
    strings), every ``step`` (default "30min"), as a GIF or an MP4 at ``output`` (its
    extension decides). Further keywords are the command line's options of the same name
    (``tz``, ``lat``, ``lon``, ``band``, ``nodata``, ``threads``, ...). Returns the report."""
    from .run import RunOptions
    from .run.config import AnimateConfig
    from .run.animate import animate as run_animate
    _no_other_keywords("animate", more)
    place = _place(more)
    read = _read_options(more)
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, **_progress(progress), say=_stderr)
    return run_animate(AnimateConfig(dem=os.fspath(dem), output=os.fspath(output),
                                     date=_text(date), start=_text(start), end=_text(end),
                                     step=step, place=place, fps=fps, size=size, label=label,
                                     algorithm=algorithm, curvature=curvature,
                                     refraction_k=refraction_k, read=read, run=run))
