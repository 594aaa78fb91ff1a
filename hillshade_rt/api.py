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

# keyword arguments passed on as the run's options of the same name
_PASSED = PLACE_KEYS + READ_KEYS + ("threads",)


# the command line's options that are other keywords here (the rest: --foo-bar -> foo_bar)
_KEYWORDS = {"--overwrite": "overwrite=True", "--earth-curvature": "curvature=True",
             "--no-earth-curvature": "curvature=False", "--refraction-coefficient": "refraction_k",
             "--time": "times", "--scheduler": "client", "--co": "creation_options",
             "--format": "fmt", "--soft": "soft=True", "--self-shadow": "self_shadow=True",
             "--no-self-shadow": "self_shadow=False", "--cog": "cog=True", "--each": "each=True",
             "--mean": "mean=True", "--perez": "perez=True", "--classes": "product='classes'",
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
          stac_item: str | None = None, context=None, each: bool = False, **more) -> dict:
    """Shade DEM file(s) into ``output`` (one band per sun) or ``output_pattern`` files.

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

    ``each``: many unrelated DEMs (any grid, CRS, size) in one call, each shaded on its own
    into ``output_pattern`` with ``{stem}`` (the input's file name without its extension), as
    ``--each``: the report lists each input's status (``ok``, ``empty``: every cell nodata,
    written all nodata; ``failed`` and its message) and its own run's report; when any failed,
    :class:`~hillshade_rt.run.batch.BatchFailed` (a ``HillshadeError``) is raised after the
    others are written, its ``report`` attribute the report.

    Returns the report (what ``--report`` writes; also written to ``report`` when given)."""
    from .run import ReadOptions, RunOptions, ShadeConfig
    from .run import shade as run_shade
    from .run.batch import check_pattern, shade_each
    from .algorithms import algorithm_for, options_for
    from .run.config import PRODUCTS
    from .model.sun import DEFAULT_TOLERANCE
    from .io.write import virtual_outputs
    if product not in PRODUCTS:
        raise HillshadeError(f"product must be one of {', '.join(PRODUCTS)}, got {product!r}")
    unknown = set(more) - set(_PASSED)
    if unknown:
        raise TypeError(f"shade() got unexpected keyword argument(s) {', '.join(sorted(unknown))}")
    files = [os.fspath(dems)] if isinstance(dems, (str, os.PathLike)) else [os.fspath(p)
                                                                            for p in dems]
    if not files:
        raise HillshadeError("no DEM given")
    if not each:
        check_pattern(output_pattern, False)     # {stem} without each
    if output is None and output_pattern is None and not each:
        raise HillshadeError("give output or output_pattern")
    if scale is not None and product != "hillshade":
        raise HillshadeError("scale applies to product='hillshade'")
    given = dict(algorithm_options or {})
    algorithm = algorithm_for(algorithm, given)
    options = options_for(algorithm, given)
    sun = dict(azimuth=azimuth, elevation=elevation,
               time=tuple(str(_iso(t)) for t in ([times] if isinstance(times, (str, _dt.datetime))
                                                 else times)),
               start=_iso(start), end=_iso(end), step=step,
               sun_from_stac=None if sun_from_stac is None else os.fspath(sun_from_stac),
               **{k: more.get(k, d) for k, d in zip(PLACE_KEYS, (None,) * 5 + (False, DEFAULT_TOLERANCE))})
    read = ReadOptions(**{k: more[k] for k in READ_KEYS if k in more},
                       context=None if context is None else os.fspath(context))
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, quiet=not progress, fmt=fmt, preview=preview,
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
                      stac_item=None if stac_item is None else os.fspath(stac_item))
    token = virtual_outputs.set(True)    # /vsimem/ outputs are fine from Python
    try:
        return shade_each(cfg) if each else run_shade(cfg)
    finally:
        virtual_outputs.reset(token)


@_keyword_errors
def irradiance(dem, output, *, date=None, end_date=None, start=None, end=None,
               step: str = "15min", clear_sky: str | None = None,
               linke_turbidity: float | None = None, albedo: float = 0.2, ghi=None,
               mean: bool = False, soft: bool = False, perez: bool = False,
               skyview_directions: int = 32, algorithm: str = "auto",
               curvature: bool | None = None, refraction_k: float | None = None,
               backend: str = "auto", fmt: str | None = None, creation_options=None,
               overwrite: bool = False, report: str | None = None,
               preview: str | None = None, progress: bool = False, context=None,
               height_above_ground: float = 0.0, **more) -> dict:
    """``hillshade-rt irradiance`` as a function: the beam, diffuse, reflected and global
    irradiance on every cell of the DEM at ``dem`` over a period, written to ``output`` (4
    float32 bands, Wh/m², or W/m² with ``mean``). The period: ``date`` (a date or
    "YYYY-MM-DD") and ``end_date``, or ``start`` and ``end`` (datetimes or ISO strings). The
    sky: ``clear_sky`` ("ineichen", the default, with ``linke_turbidity``; "haurwitz") or
    ``ghi``, the path of a measured series (CSV: time, ghi[, dni, dhi]). Further keywords are
    the command line's options of the same name (``tz``, ``lat``, ``lon``, ``band``,
    ``nodata``, ``threads``, ...); ``fmt`` and ``creation_options`` as for :func:`shade`;
    ``context`` as ``--context`` (the DEM a tile of that raster); ``height_above_ground`` as
    ``--height-above-ground`` (metres: the receiving surface stands this high). Returns the
    report. For
    heights in memory:
    :func:`hillshade_rt.engine.arrays.irradiance`."""
    from .run import ReadOptions, RunOptions
    from .run.irradiance import IrradianceConfig, irradiance as run_irradiance
    from .model.sun import DEFAULT_TOLERANCE
    from .io.write import virtual_outputs
    unknown = set(more) - set(_PASSED)
    if unknown:
        raise TypeError(f"irradiance() got unexpected keyword argument(s) "
                        f"{', '.join(sorted(unknown))}")

    def text(v):
        return None if v is None else str(v.isoformat() if hasattr(v, "isoformat") else v)
    place = {k: more.get(k, d) for k, d in zip(PLACE_KEYS, (None,) * 5 + (False,
                                                                          DEFAULT_TOLERANCE))}
    read = ReadOptions(**{k: more[k] for k in READ_KEYS if k in more},
                       context=None if context is None else os.fspath(context))
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, quiet=not progress, fmt=fmt, preview=preview,
                     say=_stderr, creation_options=creation_options)
    cfg = IrradianceConfig(os.fspath(dem), os.fspath(output), text(date), text(end_date),
                           text(start), text(end), step, clear_sky, linke_turbidity, albedo,
                           None if ghi is None else os.fspath(ghi), mean, soft, perez,
                           skyview_directions, place, algorithm, curvature, refraction_k,
                           read, run, height_above_ground=height_above_ground)
    token = virtual_outputs.set(True)    # /vsimem/ outputs are fine from Python
    try:
        return run_irradiance(cfg)
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
    from .run import ReadOptions, RunOptions
    from .run.animate import AnimateConfig, animate as run_animate
    from .model.sun import DEFAULT_TOLERANCE
    unknown = set(more) - set(_PASSED)
    if unknown:
        raise TypeError(f"animate() got unexpected keyword argument(s) "
                        f"{', '.join(sorted(unknown))}")

    def text(v):
        return None if v is None else str(v.isoformat() if hasattr(v, "isoformat") else v)
    place = {k: more.get(k, d) for k, d in zip(PLACE_KEYS, (None,) * 5 + (False,
                                                                          DEFAULT_TOLERANCE))}
    read = ReadOptions(**{k: more[k] for k in READ_KEYS if k in more})
    run = RunOptions(backend=backend, threads=more.get("threads"), report_path=report,
                     overwrite=overwrite, quiet=not progress, say=_stderr)
    return run_animate(AnimateConfig(os.fspath(dem), os.fspath(output), text(date), text(start),
                                     text(end), step, place, fps, size, label, algorithm,
                                     curvature, refraction_k, read, run))
