"""The ``hillshade-rt`` command line.

Small click commands in the manner of rasterio's ``rio``; option names follow GDAL where GDAL has
one (``-b/--band``, ``-z/--z-factor``, ``--overwrite``). Every error is one line on stderr and a
non-zero exit status: 1 for bad input, 2 for a bad command line, 130 when interrupted.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import os
import sys

import click

from . import __version__
from .errors import HillshadeError, UsageProblem


def _signal_name(signum: int) -> str:
    import signal
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


def _complete_note() -> str:
    """What this run has written whole, for a message about a failed or interrupted run."""
    from .io.write import completed, is_virtual
    # what is still there: scratch files published and removed again (a mosaic cut into its
    # tiles, Dask's parts) are no outputs
    names = [p for p in completed if is_virtual(p) or os.path.lexists(p)]
    if not names:
        return ""
    shown = ", ".join(names) if len(names) <= 4 else f"{names[0]}, {names[1]} ... {names[-1]}"
    return f"; {len(names)} output(s) complete and kept: {shown}"


class _OneLineErrors(click.Group):
    """A group whose errors (usage errors included) print as a single line, never a traceback;
    SIGINT, SIGTERM and SIGHUP stop a run like Ctrl-C (exit 130, 143, 129)."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        import signal
        import threading

        from .io import write as writes
        writes.reset()
        previous = {}
        if threading.current_thread() is threading.main_thread():
            for s in writes._SIGNALS:
                with contextlib.suppress(OSError, ValueError):
                    previous[s] = signal.signal(s, writes.on_signal)
        try:
            rv = self._main(args, prog_name, complete_var, **extra)
        finally:
            for s, h in previous.items():
                with contextlib.suppress(OSError, ValueError, TypeError):
                    signal.signal(s, h)
        if not standalone_mode:
            return rv
        sys.exit(rv if isinstance(rv, int) else 0)

    def _main(self, args, prog_name, complete_var, **extra):
        try:
            return super().main(args=args, prog_name=prog_name, complete_var=complete_var,
                                standalone_mode=False, **extra)
        except SystemExit:
            raise
        except BaseException as exc:   # noqa: BLE001 -- every way out is one line
            from .io.write import caught
            if caught or isinstance(exc, (KeyboardInterrupt, click.exceptions.Abort)):
                signum = caught[0] if caught else 2
                done = _complete_note()
                click.echo(f"hillshade-rt: interrupted ({_signal_name(signum)}); "
                           + (done[2:] + ", the unfinished output removed" if done
                              else "no output written"), err=True)
                sys.exit(128 + signum)
            if isinstance(exc, click.exceptions.NoArgsIsHelpError):  # click >= 8.2: bare group
                click.echo(exc.ctx.get_help(), err=True)
                sys.exit(2)
            if isinstance(exc, click.ClickException):
                msg = exc.format_message()
                if isinstance(exc, click.UsageError) and exc.ctx is not None:
                    msg += f" (see '{exc.ctx.command_path} --help')"
                elif exc.exit_code == 1:
                    msg += _complete_note()
                click.echo(f"hillshade-rt: error: {msg}", err=True)
                sys.exit(exc.exit_code)
            if isinstance(exc, BrokenPipeError):
                sys.exit(1)
            if isinstance(exc, OSError):
                where = f"{exc.filename}: " if exc.filename else ""
                click.echo(f"hillshade-rt: error: {where}{exc.strerror or exc}"
                           f"{_complete_note()}", err=True)
                sys.exit(1)
            if os.environ.get("HILLSHADE_RT_DEBUG"):
                raise
            first = str(exc).splitlines()[0] if str(exc) else ""
            click.echo(f"hillshade-rt: error: internal error ({type(exc).__name__}"
                       f"{': ' + first if first else ''}); please report it, "
                       f"HILLSHADE_RT_DEBUG=1 shows the traceback{_complete_note()}", err=True)
            sys.exit(1)


def _fail(exc: HillshadeError) -> click.ClickException:
    return click.ClickException(str(exc))


def _stack(f, opts):
    """Apply click options in the order they are listed (the first shows first in --help)."""
    for opt in reversed(opts):
        f = opt(f)
    return f


def _checked(parse):
    """A click callback that checks an option's text with ``parse`` (a parser of ``io`` raising
    HillshadeError) while the command line is parsed: a bad value is a usage error (exit status
    2). The text itself is passed on (the command parses it again where it reads the DEM)."""
    def callback(ctx, param, value):
        if value is not None:
            try:
                parse(value)
            except HillshadeError as exc:
                raise click.UsageError(str(exc), ctx=ctx) from None
        return value
    return callback


def _check_pixel_size(ctx, param, value):
    from .io import parse_pixel_size
    return _checked(parse_pixel_size)(ctx, param, value)


def _check_raw_shape(ctx, param, value):
    from .io import parse_raw_shape
    return _checked(parse_raw_shape)(ctx, param, value)


def _finite(ctx, param, value):
    """A click callback: a float option must be a finite number (click's float takes nan, inf)."""
    if value is not None and not math.isfinite(value):
        raise click.BadParameter(f"must be a finite number, got {value}", ctx=ctx, param=param)
    return value


def _check_z_factor(ctx, param, value):
    from .io import check_z_factor
    return _checked(check_z_factor)(ctx, param, value)


def dem_options(f):
    """Options that say how to read a DEM (shared by every command that reads one)."""
    return _stack(f, [
        click.option("-b", "--band", type=click.IntRange(min=1), default=1, show_default=True,
                     help="Band of a multi-band raster."),
        click.option("--nodata", type=float, default=None,
                     help="Nodata value (overrides the file's). NaN is always nodata."),
        click.option("-z", "--z-factor", type=float, default=1.0, show_default=True,
                     callback=_check_z_factor,
                     help="Multiply heights by this (like gdaldem -z), e.g. 0.3048 for feet."),
        click.option("--pixel-size", metavar="DX[,DY]", default=None,
                     callback=_check_pixel_size, help="Ground spacing in metres; overrides the geotransform. "
                          "Required for input without georeferencing."),
        click.option("--raw-shape", metavar="ROWSxCOLS", default=None, callback=_check_raw_shape,
                     help="Read a raw binary grid of this shape."),
        click.option("--raw-dtype", type=click.Choice(
            ["int16", "uint16", "int32", "float32", "float64"]), default=None,
            help="Value type of a raw grid (.hgt: int16)."),
        click.option("--raw-byteorder", type=click.Choice(["little", "big"]), default=None,
                     help="Byte order of a raw grid (default little; .hgt: big)."),
    ])


def format_option(f):
    return click.option("-f", "--format", "--of", "fmt", metavar="DRIVER", default=None,
                     help="Output format, a GDAL driver name (GTiff, COG, PNG, JPEG, AAIGrid, "
                          "...); default: from the output's extension (.png PNG, .jpg JPEG, "
                          ".asc AAIGrid, ...), else GeoTIFF.")(f)


def backend_option(f):
    return click.option(
        "--backend", type=click.Choice(["auto", "cpu", "gpu"]), default="auto", show_default=True,
        help="cpu: numba on all cores; gpu: CUDA through numba-cuda (pip install "
             "'hillshade-rt[gpu]'); auto: the GPU when numba finds one, else the CPU.")(f)


def _read(dem_path, band, nodata, z_factor, pixel_size, raw_shape, raw_dtype, raw_byteorder):
    from .io import parse_pixel_size, parse_raw_shape, read_dem

    return read_dem(dem_path, band=band, nodata=nodata, z_factor=z_factor,
                    pixel_size=parse_pixel_size(pixel_size), raw_shape=parse_raw_shape(raw_shape),
                    raw_dtype=raw_dtype, raw_byteorder=raw_byteorder)


def _errors_to_click(f):
    @functools.wraps(f)
    def wrapper(*args, **kwargs):
        try:
            return f(*args, **kwargs)
        except UsageProblem as exc:
            raise click.UsageError(str(exc)) from None
        except HillshadeError as exc:
            raise _fail(exc) from None
        except MemoryError:
            raise click.ClickException("out of memory (the DEM is too large for this machine)") from None
    return wrapper


@click.group(cls=_OneLineErrors, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="hillshade-rt")
def cli():
    """Terrain cast-shadow masks from digital elevation models."""


def place_options(f):
    """How the sun is computed from a time: zone, place, atmosphere, tolerance."""
    return _stack(f, [
        click.option("--tz", default=None, metavar="ZONE",
                     help="IANA zone, e.g. Europe/Zurich: times written without an offset are "
                          "local times there (daylight saving included) and outputs are labelled "
                          "in it; sun-hours: days run midnight to midnight there (default: local "
                          "mean solar time)."),
        click.option("--lat", type=float, default=None,
                     help="Latitude of the sun's observer, degrees (default: the DEM's centre; "
                          "required for input without a CRS)."),
        click.option("--lon", type=float, default=None, help="Longitude, degrees east (with --lat)."),
        click.option("--pressure", type=float, default=None,
                     help="Air pressure for refraction, hPa (default: standard atmosphere at "
                          "the DEM's centre height)."),
        click.option("--temperature", type=float, default=None,
                     help="Air temperature for refraction, degrees C (default 12)."),
        click.option("--no-refraction", is_flag=True,
                     help="True (geometric) sun elevation instead of the apparent one."),
        click.option("--sun-tolerance", type=float, default=0.05, show_default=True,
                     help="Degrees the sun's direction may vary across the raster before it is "
                          "computed per tile."),
    ])


def sun_options(f):
    """Where the sun is: given, or from times at the DEM's place (shared by the lighting commands)."""
    return _stack(place_options(f), [
        click.option("--azimuth", type=float, default=None,
                     help="Sun azimuth, degrees clockwise from the raster's north (any value wraps)."),
        click.option("--elevation", "--altitude", "elevation", type=float, default=None,
                     help="Sun elevation above the horizon, degrees, > 0 and <= 90."),
        click.option("--time", "time", multiple=True, metavar="ISO8601",
                     help="Sun from this instant (e.g. 2026-06-21T14:30:00+02:00) at the DEM's "
                          "centre; repeat for a series (one band per time)."),
        click.option("--start", default=None, metavar="ISO8601", help="Series: first time."),
        click.option("--end", default=None, metavar="ISO8601",
                     help="Series: last time (included when a step lands on it)."),
        click.option("--step", default=None, metavar="DURATION",
                     help="Series: interval, e.g. 30min, 1h, 1h30min, PT10M."),
    ])


def physics_options(f):
    return _stack(f, [
        click.option("--earth-curvature/--no-earth-curvature", "curvature", default=None,
                     help="Let the terrain fall away by d^2(1-k)/2R along each ray (default: on "
                          "when rays can be longer than 1 km)."),
        click.option("--refraction-coefficient", "refraction_k", type=float, default=None,
                     help="Terrestrial refraction k for --earth-curvature (default 0.13 on the "
                          "Earth, 0 on other bodies)."),
        click.option("--soft", is_flag=True,
                     help="The sun as a disk of 0.533 deg: the visible fraction of the disk "
                          "(0..1, from the exact horizon angle) instead of hard shadows."),
    ])


def algorithm_option(f):
    return click.option(
        "--algorithm", type=click.Choice(["auto", "bounds", "brute", "smap", "horizon", "sweep"]),
        default="auto", show_default=True,
        help="auto: the fastest exact method for this DEM, sun and backend (bounds or brute; "
             "the report says which ran and why); bounds: exact, guaranteed horizon bounds + "
             "pyramid march; brute: exact reference march (over a max-height pyramid unless "
             "--no-pyramid); smap, horizon: exact (the seeds' methods); sweep: approximate "
             "(see docs/algorithms.md).")(f)


def run_options(f):
    return _stack(f, [
        click.option("-o", "--output", default=None, type=click.Path(dir_okay=False),
                     help="The output (then every path given is a DEM)."),
        click.option("--output-pattern", default=None, metavar="PATTERN",
                     help="One file per time instead of one multi-band OUTPUT, e.g. "
                          "'out_{time:%Y%m%dT%H%M}.tif' (fields: time, index, azimuth, elevation, "
                          "tile: the input's file name; with several input tiles, one file per "
                          "tile)."),
        click.option("--preview", type=click.Path(dir_okay=False), default=None,
                     help="Also write a quick-look PNG (shaded relief, shadows tinted)."),
        backend_option,
        click.option("--threads", type=click.IntRange(min=1), default=None,
                     help="CPU threads (default: all cores)."),
        click.option("--report", "report_path", type=click.Path(dir_okay=False), default=None,
                     help="Write a JSON timing report here."),
        click.option("--overwrite", is_flag=True,
                     help="Replace outputs (and the report, the preview) if they exist."),
        click.option("-q", "--quiet", is_flag=True, help="No progress bar or summary on stderr."),
        click.option("--max-memory", metavar="SIZE", default=None,
                     help="Memory the run may use, e.g. 2GB or 512MiB; a DEM that needs more is "
                          "shaded in windows read and written through GDAL (default: half of "
                          "this machine's memory)."),
        click.option("--window-size", metavar="ROWS[xCOLS]", default=None,
                     help="Shade in windows of this many output cells (each read with its halo "
                          "toward the sun), whatever the DEM's size."),
        click.option("--cog", is_flag=True,
                     help="Write Cloud-Optimized GeoTIFF (512 px tiles, deflate, overviews)."),
        format_option,
        click.option("--scheduler", metavar="ADDRESS", default=None,
                     help="Run the windows as Dask tasks: a dask.distributed scheduler "
                          "(tcp://host:8786) or 'local[:N]' (N worker processes here). Needs "
                          "hillshade-rt[dask] and DEM paths the workers can read."),
    ])


_SUN_KEYS = ("azimuth", "elevation", "time", "start", "end", "step", "tz", "lat", "lon",
             "pressure", "temperature", "no_refraction", "sun_tolerance")


def _pop_sun(kw: dict, default_sun=None):
    """The sun options as a checked SunRequest; a bad one is a usage error (exit status 2)."""
    from .runner import SunRequest
    try:
        return SunRequest.from_options(**{k: kw.pop(k) for k in _SUN_KEYS},
                                       default_sun=default_sun)
    except HillshadeError as exc:
        raise click.UsageError(str(exc)) from None


@cli.command()
@click.argument("files", metavar="DEM... [OUTPUT]", nargs=-1, required=True,
                type=click.Path(dir_okay=False))
@sun_options
@algorithm_option
@click.option("--nextv", type=click.Choice(["scan", "binary", "quad"]), default=None,
              help="smap: how NextV is built (same result; default scan).")
@click.option("--better-nextv", is_flag=True, default=None,
              help="smap: skip silhouettes hidden by nearer ones (paper's section 9).")
@click.option("--horizon-method", type=click.Choice(["scan", "hull"]), default=None,
              help="horizon: exact per-cell scan (default) or the faster convex-hull "
                   "approximation.")
@click.option("--sample-spacing", type=click.IntRange(min=1), default=None,
              help="horizon scan: use every N-th sample only (faster, approximate; default 1).")
@click.option("--exact-steps", type=click.IntRange(min=1), default=None,
              help="sweep: samples marched exactly before stored values are reused (default 8).")
@click.option("--no-pyramid", "no_pyramid", is_flag=True, default=None,
              help="brute: the plain march, every sample taken (same mask; the benchmarks' "
                   "reference).")
@physics_options
@click.option("--self-shadow", is_flag=True,
              help="Also shadow cells whose surface faces away from the sun (Horn normals).")
@click.option("--classes", is_flag=True,
              help="Write classes: 0 lit, 1 self-shadow, 2 cast shadow, 255 nodata.")
@run_options
@dem_options
@_errors_to_click
def shadow(files, algorithm, nextv, better_nextv, horizon_method, sample_spacing,
           exact_steps, no_pyramid, curvature, refraction_k, soft, self_shadow, classes, **kw):
    """Write the cast-shadow mask of DEM to OUTPUT (GeoTIFF: 1 shadow, 0 lit, 255 nodata).

    Several DEMs (tiles on one grid) are shaded as one mosaic, so that a mountain in one tile
    shadows the next; OUTPUT is the last path, or give it with -o. The sun:
    --azimuth/--elevation, or --time (repeatable) or --start/--end/--step at the DEM's
    place (one band per time). --soft writes the visible fraction of the sun's disk (float32,
    1 = fully lit, -9999 nodata); --classes writes 0 lit / 1 self-shadow / 2 cast / 255."""
    given = dict(nextv=nextv, better_nextv=better_nextv, method=horizon_method,
                 sample_spacing=sample_spacing, exact_steps=exact_steps,
                 pyramid=False if no_pyramid else None)
    algorithm = _algorithm_for(algorithm, **given)
    options = _algorithm_options(algorithm, **given)
    kind = "classes" if classes else "shadow"
    _light(files, kind, algorithm, options, curvature, refraction_k, soft,
           self_shadow or classes, 0.2, None, kw)


@cli.command()
@click.argument("files", metavar="DEM... [OUTPUT]", nargs=-1, required=True,
                type=click.Path(dir_okay=False))
@sun_options
@click.option("--ambient", type=click.FloatRange(0.0, 1.0), default=0.2, show_default=True,
              callback=_finite,
              help="Light in shadow and on faces turned away, 0..1.")
@click.option("-s", "--scale", type=float, default=None,
              help="Ratio of vertical units to horizontal (gdaldem -s), e.g. 111120 for a DEM "
                   "in degrees with heights in metres; default: ground metres from the CRS.")
@algorithm_option
@physics_options
@run_options
@dem_options
@_errors_to_click
def hillshade(files, ambient, scale, algorithm, curvature, refraction_k, soft, **kw):
    """Write 8-bit shaded relief with cast shadows of DEM to OUTPUT.

    Illumination = ambient + (1 - ambient) * max(0, L.N) in lit cells and ambient in shadow
    (normals by Horn's method, like gdaldem); written as 1..255, 0 nodata. Sun as for `shadow`
    (default --azimuth 315 --elevation 45, like gdaldem)."""
    _light(files, "hillshade", algorithm, {}, curvature, refraction_k, soft, True, ambient,
           scale, kw, default_sun=(315.0, 45.0))


def _inputs_and_output(files, output, pattern):
    """rio-style paths: ``DEM... OUTPUT``, or every path a DEM with -o/--output or
    --output-pattern."""
    from .io import is_gdal_name    # a DEM the local disk cannot tell about (/vsizip/, URLs)
    files = list(files)
    if output is not None or pattern is not None:
        if output is not None and pattern is not None:
            raise click.UsageError("give -o/--output or --output-pattern, not both")
        given = "--output-pattern" if pattern is not None else "-o/--output"
        last = files[-1]
        if len(files) > 1 and not (os.path.exists(last) or is_gdal_name(last)):
            # `shadow dem.tif out.tif --output-pattern 'x_{index}.tif'`: out.tif is no DEM
            raise click.UsageError(f"{last} does not exist: give OUTPUT or {given}, not both "
                                   f"(with {given} every path is a DEM)")
        return files, output
    if len(files) < 2:
        raise click.UsageError("give OUTPUT or --output-pattern (one of them)")
    return files[:-1], files[-1]


# the smallest --window-size side: smaller windows make the run slow for nothing (each window has
# its halo and its own read; 1x1 windows of a 465x457 DEM are 212 k windows, minutes of work)
MIN_WINDOW_SIDE = 64


def _window_size(text):
    """--window-size ROWS[xCOLS] as (rows, cols); a malformed or too small size is a usage
    error. (``tiling.plan`` itself takes any window shape.)"""
    if text is None:
        return None
    import re
    m = re.fullmatch(r"\s*(\d+)\s*(?:[xX,]\s*(\d+))?\s*", str(text))
    if not m:
        raise click.UsageError(f"--window-size must be ROWS or ROWSxCOLS (e.g. 2048x2048), got "
                               f"{text!r}")
    rows = int(m.group(1))
    cols = int(m.group(2)) if m.group(2) else rows
    if min(rows, cols) < MIN_WINDOW_SIDE:
        raise click.UsageError(f"--window-size {str(text).strip()}: "
                               f"windows must be at least {MIN_WINDOW_SIDE} cells on each side "
                               f"(e.g. {MIN_WINDOW_SIDE}x{MIN_WINDOW_SIDE}; 1024x1024 or more is "
                               "faster)")
    return rows, cols


def _light(files, kind, algorithm, options, curvature, refraction_k, soft, self_shadow,
           ambient, scale, kw, default_sun=None):
    """The body of ``shadow`` and ``hillshade``: one DEM (or a mosaic of several), one or more
    suns, one output per sun (bands of OUTPUT, or files of --output-pattern). In memory when the
    run fits --max-memory, else in windows (``tiling``), on Dask workers with --scheduler.
    Also the body of ``api.shade``: the checks of the options' combinations live here."""
    import numba

    from .io import write_json, write_png
    from .report import Timer, build_report, shown_paths, summary_line
    from .io.write import Claims, reset
    from .runner import OutputPattern
    from .shadow import choose_backend
    from .tiling import bytes_per_cell, default_max_memory, parse_size

    if kind == "classes" and soft:
        raise click.UsageError("--classes and --soft do not go together (classes are hard)")
    if scale is not None:
        if not (math.isfinite(scale) and scale > 0):
            raise click.UsageError(f"--scale must be a positive number, got {scale}")
        if kw.get("pixel_size") is not None:
            raise click.UsageError("--scale and --pixel-size do not go together")
    timer = Timer()
    pattern, preview, backend, threads = (kw.pop("output_pattern"), kw.pop("preview"),
                                          kw.pop("backend"), kw.pop("threads"))
    report_path, overwrite, quiet = kw.pop("report_path"), kw.pop("overwrite"), kw.pop("quiet")
    output, fmt = kw.pop("output"), kw.pop("fmt", None)
    max_memory, window_size, cog, scheduler = (kw.pop("max_memory"), kw.pop("window_size"),
                                               kw.pop("cog"), kw.pop("scheduler"))
    req = _pop_sun(kw, default_sun)
    inputs, output = _inputs_and_output(files, output, pattern)
    reset()
    wshape = _window_size(window_size)
    try:
        limit = parse_size(max_memory) if max_memory is not None else default_max_memory()
    except HillshadeError as exc:
        raise click.UsageError(f"--max-memory: {exc}") from None
    claims = Claims(inputs, overwrite)   # every path written: no input, no two the same
    if output is not None:
        claims.claim(output, "OUTPUT")
    for extra, what in ((report_path, "--report"), (preview, "--preview")):
        if extra is not None:
            claims.claim(extra, what)
    if pattern is not None:
        pattern = OutputPattern(pattern)
    if threads is not None:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    ran_on = choose_backend(backend, algorithm, options)
    per_cell = bytes_per_cell(algorithm, kind, soft, self_shadow)
    with timer("read"):     # (opens the DEM for its size: part of reading it)
        tiled = (scheduler is not None or wshape is not None or len(inputs) > 1
                 or _needs_windows(inputs[0], kw, limit, per_cell))
    dtype, nodata = {"shadow": ("float32", -9999.0) if soft else ("uint8", 255),
                     "classes": ("uint8", 255), "hillshade": ("uint8", 0)}[kind]
    out = _Outputs(kind, soft, algorithm, dtype, nodata, output, pattern, claims, cog,
                   preview is not None, ambient, fmt)
    # Dask's parts are put together by GDAL (no 16-bit encoding of soft shadows on the way)
    out.via_vrt = scheduler is not None
    if output is not None:   # the format can hold the product (before any work)
        from .io import check_output_format, output_driver
        check_output_format(output, output_driver(output, fmt, cog), dtype,
                            len(req.times) if req.from_time else 1,
                            out.continuous and not out.via_vrt)
    if not quiet:
        _compile_note(algorithm, ran_on, self_shadow or kind != "shadow")
    try:
        with (_bounded_gdal_cache() if tiled else contextlib.nullcontext()):
            run = (_light_tiled if tiled else _light_in_memory)(
                inputs, kw, scale, req, out, timer, algorithm, options, ran_on, curvature,
                refraction_k, soft, self_shadow, ambient, quiet, limit=limit, window_shape=wshape,
                scheduler=scheduler, per_cell=per_cell)
    finally:
        out.cleanup()
    d, suns, records = run["dem"], run["suns"], run["records"]
    if preview is not None:
        with timer("write"):
            day = [s for s in suns if not s.night]
            s0 = day[0] if day else suns[0]
            write_png(preview, run["relief"](s0.azimuth, s0.elevation), overwrite)
    seconds = dict(timer.seconds, total=timer.total())
    first = suns[0]
    rep = build_report(dem=d, output=output or pattern.pattern, azimuth=first.azimuth,
                       elevation=first.elevation, algorithm=algorithm, backend=ran_on,
                       backend_requested=backend, threads=numba.get_num_threads(),
                       seconds=seconds, stats=_mean_stats(records, run["stats"]),
                       height_range=run["zrange"], options=options,
                       algorithm_stats=run["algo_stats"], gpu=run.get("gpu"))
    rep["sun"] = records[0] if len(records) == 1 else None
    rep["sun_source"] = "time" if req.from_time else "given"
    if run["sun_info"] is not None:
        rep.update(run["sun_info"])
    if len(records) > 1 or req.from_time:
        rep["times"] = records
    rep["night_count"] = sum(1 for s in suns if s.night)
    rep["product"] = {"kind": kind, "soft": soft, "self_shadow": self_shadow,
                      "dtype": dtype, "nodata": nodata, "bands": len(suns) if output else 1,
                      "cog": cog}
    if kind == "hillshade":
        rep["product"].update(ambient=ambient, scale=scale)
    rep["curvature"] = run["curvature"]
    from .io import input_label
    rep["inputs"] = [input_label(p) for p in inputs]
    rep["processing"] = run["processing"]
    if preview is not None:
        rep["preview"] = os.path.abspath(preview)
    if report_path is not None:
        write_json(report_path, rep, overwrite)
    if not quiet:
        # the outputs named as the user gave them (as every command does), a pattern's files
        click.echo(summary_line(rep, output if output is not None
                                else shown_paths(pattern.planned) or pattern.pattern), err=True)
        note = _note_to_show(run["algo_stats"], algorithm, options)
        if note:
            click.echo(f"hillshade-rt: note: {note}", err=True)
        if rep["night_count"]:
            click.echo(f"hillshade-rt: note: the sun is below the horizon at "
                       f"{rep['night_count']} of {len(suns)} time(s): all shadow there", err=True)
    return rep


def _explicit(name: str) -> bool:
    """Whether the option ``name`` was given on the command line (True outside a command line:
    api.shade's arguments are the caller's choice)."""
    from click.core import ParameterSource
    ctx = click.get_current_context(silent=True)
    if ctx is None or name not in ctx.params:
        return True
    return ctx.get_parameter_source(name) not in (ParameterSource.DEFAULT,
                                                  ParameterSource.DEFAULT_MAP)


def _note_to_show(algo_stats: dict, algorithm: str, options: dict) -> str | None:
    """The algorithm's note, once per run, where it tells the user something they can act on: a
    method they asked for did not run (horizon's hull replaced by the scan). SMap marching every
    cell like brute on a DEM with per-row spacing (every geographic DEM, e.g. each SRTM tile) is
    said only when SMap was asked for by name or with its options: with the default algorithm
    the result is the same and the note would be noise. The report keeps the note always."""
    note = algo_stats.get("note")
    if not note:
        return None
    if algorithm == "smap" and not options and not _explicit("algorithm"):
        return None
    return note


def _stderr_is_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError, OSError):
        return False


def _compile_note(algorithm: str, backend: str, relief: bool = False) -> None:
    """One line on stderr before numba compiles kernels that are not in its cache yet (a first
    run, or the first use of an algorithm: seconds to a minute with nothing else on screen).
    On a terminal only, like the progress bar: logs and pipelines keep their one summary line."""
    if backend != "cpu" or not _stderr_is_terminal():
        return
    from .algorithms._jitcache import cache_dir, cached
    # what each algorithm runs: auto either exact method; both march over the pyramid
    names = {"auto": ["bounds", "brute", "pyramid"], "bounds": ["bounds", "brute", "pyramid"],
             "brute": ["brute", "pyramid"]}.get(algorithm, [algorithm])
    missing = [m for m in names + (["relief"] if relief else []) if not cached(m)]
    if missing:
        where = cache_dir().replace(os.path.expanduser("~"), "~", 1)
        click.echo(f"hillshade-rt: compiling the {' and '.join(missing)} kernels (first run "
                   f"only: cached in {where})", err=True)


def _bounded_gdal_cache():
    """GDAL's block cache held to ``tiling.GDAL_CACHE_MB`` (its default, 5 % of the machine's
    memory, would break --max-memory on its own)."""
    import rasterio
    from .tiling import GDAL_CACHE_MB
    return rasterio.Env(GDAL_CACHEMAX=GDAL_CACHE_MB)


def _source(paths, read_opts):
    """``tiling.open_source`` with the DEM options of the command line (as ``_read``). A DEM
    from standard input is read whole only: with windows or a mosaic, a usage error."""
    from .io import parse_pixel_size, parse_raw_shape
    from .io import open_windowed as open_source
    return open_source(paths, band=read_opts["band"], nodata=read_opts["nodata"],
                       pixel_size=parse_pixel_size(read_opts["pixel_size"]),
                       z_factor=read_opts["z_factor"],
                       raw_shape=parse_raw_shape(read_opts["raw_shape"]),
                       raw_dtype=read_opts["raw_dtype"], raw_byteorder=read_opts["raw_byteorder"])


def _needs_windows(path, read_opts, limit, per_cell) -> bool:
    """Whether shading ``path`` whole would need more than ``limit`` bytes (a DEM whose size
    cannot be told without reading it is read whole, as before)."""
    from .io import STDIN
    from .tiling import window_budget
    if path == STDIN:
        return False      # standard input is read whole (once)
    try:
        src = _source(path, read_opts)
    except HillshadeError:
        return False      # read whole: read_dem says what is wrong with it
    try:
        budget = window_budget(limit, per_cell)[0]
    except HillshadeError:
        return True   # too small even for a window: the windowed run says what would do
    rows, cols = src.shape
    return rows * cols > budget


class _Outputs:
    """Where a lighting run's products go: bands of OUTPUT or files of a pattern; their type,
    nodata, tags and descriptions."""

    def __init__(self, kind, soft, algorithm, dtype, nodata, output, pattern, claims, cog,
                 preview, ambient, fmt=None):
        self.kind, self.soft, self.dtype, self.nodata = kind, soft, dtype, nodata
        self.output, self.pattern, self.cog = output, pattern, cog
        self.claims, self.overwrite, self.fmt = claims, claims.overwrite, fmt
        self.preview, self.ambient = preview, ambient
        self.base_tags = {"HILLSHADE_RT_VERSION": __version__, "ALGORITHM": algorithm,
                          "VALUES": _VALUES[kind, soft]}
        self.what = {"shadow": "visible fraction of the sun" if soft else "cast shadow",
                     "classes": "shadow classes", "hillshade": "shaded relief"}[kind]
        self.resampling = "average" if (soft or kind == "hillshade") else "nearest"
        self.continuous = self.resampling == "average"   # lossy formats and 16-bit PNG allowed
        self.via_vrt = False    # outputs assembled by GDAL from parts (Dask)
        self.paths = None
        self.tiles = self.tile_paths = None
        self._scratch: list[str] = []

    def plan(self, suns, inputs, tiles=None):
        """The files of each sun. ``tiles``: a mosaic's input tiles (``Source.tiles``); with a
        pattern naming ``{tile}`` each sun's mosaic is written to a scratch file beside the
        outputs and cut into one file per tile (``finish``)."""
        from .io import check_output_format, output_driver
        if self.pattern is None:
            return
        per_tile = bool(self.pattern.per_tile and tiles)
        paths = self.pattern.paths(suns, [t["path"] for t in tiles] if per_tile else inputs[:1])
        if tiles:   # a mosaic's tiles are inputs too
            self.claims.inputs += [t["path"] for t in tiles]
        for ps in paths:
            for p in ps:
                self.claims.claim(p, "--output-pattern")
                check_output_format(p, output_driver(p, self.fmt, self.cog and not per_tile),
                                    self.dtype, 1,
                                    self.continuous and not (per_tile or self.via_vrt))
        if per_tile:
            self.tiles, self.tile_paths = tiles, paths
            self.paths = [None] * len(suns)
        else:
            self.paths = [ps[0] for ps in paths]

    @property
    def file_cog(self) -> bool:
        """Whether the per-sun files are written as COGs (not the scratch mosaics of tiles)."""
        return self.cog and self.tile_paths is None

    def target(self, i) -> str:
        """Where sun ``i``'s file is written: its output, or a scratch mosaic to be cut."""
        if self.paths[i] is None:
            from .io.write import temp_beside
            self.paths[i] = temp_beside(self.tile_paths[i][0], ".scratch.tif")
            self._scratch.append(self.paths[i])
        return self.paths[i]

    def finish(self, i, sun, src):
        """Cut sun ``i``'s scratch mosaic into its tiles' files (on each tile's own grid), then
        remove it."""
        if self.tile_paths is None:
            return
        from .io import copy_vrt, input_label
        from .runner import sun_tags
        from .io.vrt import VrtSource, vrt_xml
        scratch = self.paths[i]
        dtype = {"uint8": "Byte", "float32": "Float32"}[self.dtype]
        for t, path in zip(self.tiles, self.tile_paths[i]):
            r0, r1, c0, c1 = t["window"]
            shape = (r1 - r0, c1 - c0)
            doc = vrt_xml(shape, t["transform"], src.crs,
                          [[VrtSource(scratch, 1, (0, 0), shape, src_offset=(r0, c0))]], dtype,
                          self.nodata, [self.description(sun)],
                          {**self.base_tags, **sun_tags(sun),
                           "TILE_SOURCE": input_label(t["path"])})
            copy_vrt(doc, path, self.dtype, self.cog, self.resampling, self.overwrite, self.fmt)
        self._remove(scratch)

    def _remove(self, path):
        for p in (path, path + ".aux.xml", path + ".ovr"):
            with contextlib.suppress(OSError):
                os.remove(p)

    def cleanup(self):
        """Remove scratch mosaics left by a failed or interrupted run."""
        for p in self._scratch:
            self._remove(p)

    def description(self, sun) -> str:
        from .runner import label
        return label(sun) if sun.time is not None else self.what

    def writer(self, dem, count):
        """The multi-band writer of OUTPUT (None with a pattern)."""
        from .io import BandWriter
        if self.output is None:
            return contextlib.nullcontext()
        return BandWriter(self.output, dem, count, self.dtype, self.nodata, self.base_tags,
                          self.cog, self.resampling, overwrite=self.overwrite, fmt=self.fmt)

    def file_writer(self, dem, i, sun):
        from .io import BandWriter
        from .runner import sun_tags
        scratch = self.tile_paths is not None   # a mosaic to be cut into tiles: a GeoTIFF
        return BandWriter(self.target(i), dem, 1, self.dtype, self.nodata,
                          {**self.base_tags, **sun_tags(sun)}, self.file_cog, self.resampling,
                          overwrite=self.overwrite or scratch, fmt=None if scratch else self.fmt)

    def record(self, sun, i, st, seconds, per_cell=False):
        rec = dict(sun.as_dict(), shadow_fraction=st["shadow_fraction"], compute_s=seconds)
        if per_cell:          # each cell marched with its own sun (the tiles: incidence only)
            rec["mode"] = "per cell"
        if self.tile_paths:
            rec["outputs"] = [os.path.abspath(p) for p in self.tile_paths[i]]
        elif self.paths:
            rec["output"] = os.path.abspath(self.paths[i])
        return rec


def _light_in_memory(inputs, read_opts, scale, req, out, timer, algorithm, options, ran_on,
                     curvature, refraction_k, soft, self_shadow, ambient, quiet, **_):
    import numpy as np

    from .engine import Shader, dem_body, render
    from .preview import relief_rgb, shade_of
    from .report import product_stats
    from .runner import progress, sun_tags

    kind = out.kind
    with timer("read"):
        d = _read(inputs[0], **read_opts)
        if scale is not None:
            _apply_scale(d, scale)
    with timer("prepare"):   # solar positions; numba compilation on a first run; GPU upload
        suns, sun_info = req.suns(d)
        out.plan(suns, inputs)
        zmin, zmax = d.height_range()
        shader = Shader(d.heights, d.grid, algorithm, options, ran_on,
                        "auto" if curvature is None else curvature, refraction_k,
                        dem_body(d, req.lat), (zmin, zmax), survey=d.survey())
        day = [s for s in suns if not s.night]
        if day:
            shader.warm_up(day[0].azimuth, day[0].elevation, soft=soft,
                           incidence=self_shadow or kind != "shadow",
                           field=any(s.fieldwise for s in day))
    records, algo_stats = [], {}
    share, st = None, None
    with out.writer(d, len(suns)) as writer:
        for i, sun in enumerate(progress(suns, quiet, "hillshade-rt")):
            t0 = timer.seconds.get("compute", 0.0)
            with timer("compute"):
                arr = render(shader, sun, kind, soft=soft, self_shadow=self_shadow,
                             ambient=ambient, stats=algo_stats)
            seconds = timer.seconds["compute"] - t0
            with timer("compute"):      # the product's statistics (counts over the raster)
                st = product_stats(kind, soft, arr)
            if out.preview:
                sh = shade_of(kind, soft, arr, ambient)
                share = sh / len(suns) if share is None else share + sh / len(suns)
            if soft:
                arr = np.where(np.isnan(arr), np.float32(out.nodata), arr).astype(np.float32)
            with timer("write"):
                if writer is not None:
                    writer.write(i + 1, arr, description=out.description(sun), tags=sun_tags(sun))
                else:
                    with out.file_writer(d, i, sun) as w:
                        w.write(1, arr, description=out.description(sun))
            records.append(out.record(sun, i, st, seconds, shader.field_ok(sun, soft)))
        if writer is not None:
            with timer("write"):     # the close compresses the last blocks
                writer.finish()
    return {"dem": d, "suns": suns, "sun_info": sun_info, "records": records, "stats": st,
            "algo_stats": algo_stats, "zrange": (zmin, zmax), "curvature": shader.report(),
            "gpu": shader.gpu_report(),
            "relief": lambda az, el: relief_rgb(d.heights, d.grid, az, el, shade=share),
            "processing": {"mode": "in memory", "cells": int(d.heights.size)}}


def _light_tiled(inputs, read_opts, scale, req, out, timer, algorithm, options, ran_on,
                 curvature, refraction_k, soft, self_shadow, ambient, quiet, *, limit,
                 window_shape, scheduler, per_cell):
    import math

    import numpy as np

    from .engine import dem_body
    from .geometry import Grid
    from .engine import curvature_report
    from .preview import every_nth, relief_rgb, shade_of
    from .report import merge_stats, product_stats
    from .runner import sun_tags
    from .tiling import (MIN_WINDOW_CELLS, Job, MemoryTooSmall, Tally, WindowCache, block_stats,
                         format_size, marched_per_cell, memory_needed, window_budget)

    kind = out.kind
    with timer("read"):
        src = _source(inputs, read_opts)
        if scale is not None:
            _apply_scale(src, scale)
    rows, cols = src.shape
    tally = Tally()
    with timer("prepare"):   # one pass for the height ranges; solar positions; compilation
        bstats = block_stats(src, preview_side=2048 if out.preview else None)
        tally.stats_pass_bytes = rows * cols * src.itemsize
        zrange = (bstats.zmin, bstats.zmax)
        suns, sun_info = req.suns(src)
        out.plan(suns, inputs, src.tiles)
        dx, dy = src.grid.centre_spacing()
        job = Job(src, algorithm, options, ran_on, "auto" if curvature is None else curvature,
                  refraction_k, dem_body(src, req.lat), zrange, math.hypot(cols * dx, rows * dy),
                  kind, soft, self_shadow, ambient)
        # a limit too small: measured now, after the preparation (the process has grown), the
        # error says the smallest --max-memory that would do: room for the largest window the
        # plan needs, or for the whole DEM where it could be shaded in memory
        try:
            budget, mem = window_budget(limit, per_cell)
            small = None
        except HillshadeError as exc:
            budget, mem, small = 0, None, exc
        try:
            plans = [job.pieces(s, bstats, budget, window_shape, in_order=scheduler is None)
                     for s in suns]
        except MemoryTooSmall as exc:
            small, cells = small or exc, exc.cells
        else:
            cells = max((p.cells for ps in plans for p in ps), default=0)
        if small is not None:
            least = memory_needed(per_cell, max(cells, MIN_WINDOW_CELLS))
            if len(inputs) == 1 and window_shape is None and scheduler is None:
                least = min(least, memory_needed(per_cell, rows * cols))
            said = str(small).split("; give")[0].replace(": raise --max-memory", "")
            raise HillshadeError(f"{said}; give at least --max-memory {format_size(least, up=True)}")
        day = [s for s in suns if not s.night]
        if day:
            job.warm_up(day[0])
    n = bstats.stride
    share = (np.zeros(bstats.preview.shape, np.float32) if out.preview else None)
    records, algo_stats, used = [], {}, set()
    st = None
    if scheduler is not None:
        from .distributed import run_on_dask
        with timer("compute"):
            records, st, extra = run_on_dask(scheduler, job, suns, plans, out, share, n, quiet,
                                             algo_stats, used, tally)
    else:
        from tqdm import tqdm
        total = sum(len(p) for p in plans)
        bar = tqdm(total=total, desc="hillshade-rt", unit="window", leave=False,
                   disable=True if quiet or total < 2 else None)
        with out.writer(src, len(suns)) as writer, src.reader() as rd, bar:
            cache = WindowCache(rd)
            carry = job.carrier(plans)
            for i, (sun, pieces) in enumerate(zip(suns, plans)):
                t0 = timer.seconds.get("compute", 0.0)
                with (out.file_writer(src, i, sun) if writer is None
                      else contextlib.nullcontext(writer)) as w:
                    band = 1 if writer is None else i + 1
                    st = None
                    for p in pieces:
                        with timer("compute"):
                            z = cache.get(p.window)
                            arr = job.light(z, p, algo_stats, used, carry)
                        tally.add(p)
                        with timer("compute"):      # the window's statistics
                            st = merge_stats(st, product_stats(kind, soft, arr))
                        if share is not None:
                            sub, (a, b) = every_nth(shade_of(kind, soft, arr, ambient),
                                                    p.region[0], p.region[2], n)
                            share[a:a + sub.shape[0], b:b + sub.shape[1]] += sub / len(suns)
                        if soft:
                            arr = np.where(np.isnan(arr), np.float32(out.nodata), arr).astype(
                                np.float32)
                        with timer("write"):
                            w.write(band, arr, window=p.region)
                        bar.update(1)
                    w.describe(band, out.description(sun),
                               sun_tags(sun) if writer is not None else None)
                    if writer is None:      # this sun's file: closed and published now
                        with timer("write"):
                            w.finish()
                out.finish(i, sun, src)
                records.append(out.record(sun, i, st, timer.seconds.get("compute", 0.0) - t0,
                                          marched_per_cell(plans[i])))
            tally.bytes_read = rd.bytes_read
            tally.bytes_carried = cache.carried_bytes
            tally.carry = carry
            if writer is not None:
                with timer("write"):     # the close compresses the last blocks
                    writer.finish()
        extra = {}
    curv = curvature_report(job.curvature, used, job.body, job.k)
    processing = {"mode": "tiled" if scheduler is None else "dask", "cells": rows * cols,
                  "memory": mem, "window_shape_requested": list(window_shape) if window_shape
                  else None, **tally.as_dict(src.itemsize), **extra}
    if src.tiles:
        from .io import input_label
        processing["mosaic"] = [{"path": input_label(t["path"]), "window": list(t["window"])}
                                for t in src.tiles]

    def relief(az, el):
        pv = bstats.preview
        g = Grid(pv.shape[0], pv.shape[1], src.grid.dx[::n] * n, src.grid.dy[::n] * n,
                 src.grid.col_sign, src.grid.row_sign, src.grid.method)
        return relief_rgb(pv, g, az, el, shade=share)
    return {"dem": src, "suns": suns, "sun_info": sun_info, "records": records, "stats": st,
            "algo_stats": algo_stats, "zrange": zrange, "curvature": curv, "gpu": None,
            "relief": relief, "processing": processing}


@cli.command("sun-hours")
@click.argument("dem", type=click.Path(dir_okay=False))
@click.argument("output", type=click.Path(dir_okay=False))
@click.option("--date", "date_", required=True, metavar="YYYY-MM-DD", help="The day (or first day).")
@click.option("--end-date", default=None, metavar="YYYY-MM-DD",
              help="Last day of a range (included); the hours are the total over the range.")
@click.option("--step", default="10min", show_default=True, metavar="DURATION",
              help="Sampling interval; each sample stands for the interval around it.")
@place_options
@algorithm_option
@physics_options
@click.option("--self-shadow/--no-self-shadow", default=True, show_default=True,
              help="Count no direct sun on surfaces facing away from the sun.")
@click.option("--preview", type=click.Path(dir_okay=False), default=None,
              help="Also write a quick-look PNG (relief tinted by sun hours).")
@backend_option
@click.option("--threads", type=click.IntRange(min=1), default=None,
              help="CPU threads (default: all cores).")
@click.option("--report", "report_path", type=click.Path(dir_okay=False), default=None,
              help="Write a JSON report here.")
@click.option("--overwrite", is_flag=True, help="Replace outputs if they exist.")
@click.option("-q", "--quiet", is_flag=True, help="No progress bar or summary on stderr.")
@format_option
@dem_options
@_errors_to_click
def sun_hours(dem, output, date_, end_date, step, tz, lat, lon, pressure, temperature,
              no_refraction, sun_tolerance, algorithm, curvature, refraction_k, soft, self_shadow,
              preview, backend, threads, report_path, overwrite, quiet, fmt, **read_opts):
    """Write the hours of direct sun per cell of DEM over a day (or a range of days) to OUTPUT
    (float32 hours, -9999 nodata), like WhiteboxTools' TimeInDaylight or GRASS r.sun's insolation
    time: the sun every --step, each lit sample counting for its interval."""
    import numba
    import numpy as np

    from .engine import Shader, dem_body, render
    from .io import write_json, write_png, write_raster
    from .preview import relief_rgb
    from .report import Timer
    from .runner import SunRequest, progress
    from .io.write import Claims
    from .shadow import choose_backend
    from .sun import SUN_RADIUS_DEG, day_samples, parse_date, parse_step

    timer = Timer()
    claims = Claims([dem], overwrite)
    for path, what in ((output, "OUTPUT"), (report_path, "--report"), (preview, "--preview")):
        if path is not None:
            claims.claim(path, what)
    from .io import check_output_format, output_driver
    check_output_format(output, output_driver(output, fmt), "float32", 1, False)
    try:    # the command line alone decides these: a bad one is a usage error (exit 2)
        first = parse_date(date_, "--date")
        last = parse_date(end_date, "--end-date") if end_date is not None else first
        parse_step(step)
        req = SunRequest.at_place([], tz, lat, lon, pressure, temperature, no_refraction,
                                  sun_tolerance)
    except HillshadeError as exc:
        raise click.UsageError(str(exc)) from None
    if last < first:
        raise click.UsageError("--end-date is before --date")
    if threads is not None:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    ran_on = choose_backend(backend, algorithm, {})
    if not quiet:
        _compile_note(algorithm, ran_on, self_shadow)
    with timer("read"):
        d = _read(dem, **read_opts)
    with timer("prepare"):
        site = req.site(d, "sun-hours computes the Earth's sun only (light a DEM of another "
                           "body with shadow or hillshade, which take the sun's direction)")
        try:
            req.times, weights = day_samples(first, last, step, req.tz, site.lon)
        except HillshadeError as exc:   # too many samples for the dates and the step
            raise click.UsageError(str(exc)) from None
        suns, sun_info = req.suns(d, site)
        zmin, zmax = d.height_range()
        shader = Shader(d.heights, d.grid, algorithm, {}, ran_on,
                        "auto" if curvature is None else curvature, refraction_k,
                        dem_body(d, lat), (zmin, zmax), survey=d.survey())

        def dark(s):
            top = max([r.elevation for r in s.tiles] if s.tiles else [s.elevation])
            return top + (SUN_RADIUS_DEG if soft else 0.0) <= 0.0
        work = [(s, w) for s, w in zip(suns, weights) if not dark(s)]
        if work:
            shader.warm_up(work[0][0].azimuth, max(work[0][0].elevation, 1.0), soft=soft,
                           incidence=self_shadow, field=any(s.fieldwise for s, _ in work))
        hours = np.where(np.isnan(d.heights), np.float32(np.nan), np.float32(0.0))
    algo_stats: dict = {}
    with timer("compute"):
        for s, w in progress(work, quiet, "hillshade-rt sun-hours", unit="sun"):
            hours += np.float32(w) * render(shader, s, "sun", soft=soft, self_shadow=self_shadow,
                                            stats=algo_stats)
    days = (last - first).days + 1
    tags = {"HILLSHADE_RT_VERSION": __version__, "UNITS": "hours of direct sun",
            "DATE_FIRST": first.isoformat(), "DATE_LAST": last.isoformat(), "DAYS": days,
            "STEP": step, "ALGORITHM": algorithm, "SOFT": soft, "SELF_SHADOW": self_shadow,
            "DAY": f"midnight to midnight, {req.tz.key}" if req.tz is not None
            else f"local mean solar time at longitude {site.lon:.4f}"}
    with timer("write"):
        write_raster(output, np.where(np.isnan(hours), np.float32(-9999.0), hours), d,
                     nodata=-9999.0, description="hours of direct sun", tags=tags,
                     overwrite=overwrite, fmt=fmt)
        if preview is not None:
            top = float(np.nanmax(hours)) if np.isfinite(hours).any() else 0.0
            write_png(preview, relief_rgb(d.heights, d.grid,
                                          warm=hours / top if top > 0 else np.zeros_like(hours)),
                      overwrite)
    valid = hours[~np.isnan(hours)]
    from .io import input_label
    rep = {"input": input_label(d.path), "output": os.path.abspath(output),
           "shape": list(d.shape), "algorithm": algorithm, "backend": ran_on,
           "dates": [first.isoformat(), last.isoformat()], "days": days, "step": step,
           "samples": len(suns), "samples_with_sun": len(work), "day_definition": tags["DAY"],
           "soft": soft, "self_shadow": self_shadow,
           "hours": {"min": float(valid.min()) if valid.size else None,
                     "mean": float(valid.mean()) if valid.size else None,
                     "max": float(valid.max()) if valid.size else None},
           "curvature": shader.report(), "algorithm_stats": algo_stats,
           "seconds": dict(timer.seconds, total=timer.total()), "version": __version__}
    rep.update(sun_info or {})
    if report_path is not None:
        write_json(report_path, rep, overwrite)
    if not quiet:
        h = rep["hours"]
        click.echo(f"hillshade-rt: {output}: {d.shape[1]}x{d.shape[0]}, {days} day(s) from "
                   f"{first.isoformat()}, {len(work)} of {len(suns)} samples with the sun up; "
                   f"sun hours {h['min']:.2f} .. {h['max']:.2f} (mean {h['mean']:.2f}); "
                   f"compute {timer.seconds['compute']:.2f} s", err=True)


_VALUES = {("shadow", False): "1=shadow 0=lit 255=nodata",
           ("shadow", True): "visible fraction of the solar disk 0..1, -9999=nodata",
           ("classes", False): "0=lit 1=self-shadow 2=cast shadow 255=nodata",
           ("hillshade", False): "1..255 shaded relief with cast shadows, 0=nodata",
           ("hillshade", True): "1..255 shaded relief with soft shadows, 0=nodata"}


def _mean_stats(records, last):
    fr = [r["shadow_fraction"] for r in records if r["shadow_fraction"] is not None]
    out = dict(last)
    out["shadow_fraction"] = (sum(fr) / len(fr)) if fr else None
    return out


def _apply_scale(d, scale):
    """gdaldem's -s: ground spacing = the transform's pixel size times ``scale``."""
    from .geometry import Grid, orientation
    if d.transform is None:
        raise click.UsageError("--scale needs a georeferenced DEM; use --pixel-size")
    cs, rs = orientation(d.transform)
    rows, cols = d.shape
    d.grid = Grid.uniform(rows, cols, abs(d.transform.a) * scale, abs(d.transform.e) * scale,
                          cs, rs, f"--scale {scale:g} x transform units")


_OPTION_OWNERS = {"nextv": "smap", "better_nextv": "smap", "method": "horizon",
                  "sample_spacing": "horizon", "exact_steps": "sweep", "pyramid": "brute"}
_OPTION_FLAGS = {"nextv": "--nextv", "better_nextv": "--better-nextv", "method": "--horizon-method",
                 "sample_spacing": "--sample-spacing", "exact_steps": "--exact-steps",
                 "pyramid": "--no-pyramid"}


def _algorithm_for(algorithm: str, **given) -> str:
    """``algorithm``, or for ``auto`` given options of one exact algorithm that has no
    approximate mode (smap's ``--nextv``, brute's ``--no-pyramid``), that algorithm: auto has no
    options of its own, and while SMap was the default ``--nextv quad`` alone ran it. Options of
    the approximate methods (sweep, the horizon's hull or sample spacing) still need their
    algorithm named: an approximate mask is never chosen for the user."""
    owners = {_OPTION_OWNERS[k] for k, v in given.items() if v is not None}
    if algorithm == "auto" and len(owners) == 1 and owners <= {"smap", "brute"}:
        return owners.pop()
    return algorithm


def _algorithm_options(algorithm: str, **given) -> dict:
    """The options given for ``algorithm``; an option of another algorithm is a usage error
    (``--sample-spacing 4 --algorithm brute`` would otherwise be silently ignored)."""
    out = {}
    for name, value in given.items():
        if value is None:
            continue
        if _OPTION_OWNERS[name] != algorithm:
            raise click.UsageError(f"{_OPTION_FLAGS[name]} applies to --algorithm "
                                   f"{_OPTION_OWNERS[name]}, not {algorithm}")
        out[name] = value
    return out


@cli.command()
@click.argument("dem", type=click.Path(dir_okay=False))
@click.argument("output", type=click.Path(dir_okay=False))
@click.option("--azimuth", type=float, required=True, callback=_finite,
              help="Azimuth along which to look, degrees clockwise from north.")
@click.option("--method", type=click.Choice(["scan", "hull"]), default="scan", show_default=True,
              help="scan: exact per-cell march; hull: convex-hull approximation, much faster.")
@click.option("--sample-spacing", type=click.IntRange(min=1), default=1, show_default=True,
              help="scan: use every N-th sample only (the paper's sp; faster, approximate).")
@click.option("--earth-curvature/--no-earth-curvature", "curvature", default=None,
              help="Let the terrain fall away by d^2(1-k)/2R along each ray (default: on when "
                   "the raster is more than 1 km across).")
@click.option("--refraction-coefficient", "refraction_k", type=float, default=None,
              help="Terrestrial refraction k (default 0.13 on the Earth, 0 on other bodies).")
@click.option("--preview", type=click.Path(dir_okay=False), default=None,
              help="Also write a quick-look PNG (relief, high horizons tinted).")
@backend_option
@click.option("--threads", type=click.IntRange(min=1), default=None,
              help="CPU threads (default: all cores).")
@click.option("--overwrite", is_flag=True, help="Replace OUTPUT if it exists.")
@click.option("-q", "--quiet", is_flag=True, help="No summary line on stderr.")
@format_option
@dem_options
@_errors_to_click
def horizon(dem, output, azimuth, method, sample_spacing, curvature, refraction_k, preview,
            backend, threads, overwrite, quiet, fmt, **read_opts):
    """Write the horizon angle toward AZIMUTH of every cell of DEM to OUTPUT.

    Float32 degrees above the horizontal (negative: the cell looks down on everything ahead;
    -90: no terrain ahead inside the raster); nodata -9999. A cell is lit by a sun at this
    azimuth iff its angle <= the sun's elevation."""
    import numba
    import numpy as np

    from .algorithms import horizon as hz
    from .engine import Shader, dem_body
    from .geometry import Grid, normalize_azimuth, sun_rays
    from .shadow import choose_backend, warm_up
    from .io import check_output_format, output_driver, write_png, write_raster
    from .preview import relief_rgb
    from .report import Timer
    from .io.write import Claims

    timer = Timer()
    az = normalize_azimuth(azimuth)
    claims = Claims([dem], overwrite)
    claims.claim(output, "OUTPUT")
    if preview is not None:
        claims.claim(preview, "--preview")
    check_output_format(output, output_driver(output, fmt), "float32", 1, False)
    if method == "hull" and sample_spacing != 1:
        raise click.UsageError("--sample-spacing applies to --method scan only")
    if threads is not None:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    ran_on = choose_backend(backend, "horizon", {"method": method})
    if not quiet:
        _compile_note("horizon", ran_on)
    with timer("read"):
        d = _read(dem, **read_opts)
    stats: dict = {}
    with timer("prepare"):  # numba compilation on a first run
        # the elevation does not enter the angles; curvature "auto" looks at the raster's size
        shader = Shader(d.heights, d.grid, "horizon", {}, ran_on,
                        "auto" if curvature is None else curvature, refraction_k, dem_body(d))
        if shader.curvature == "auto":   # the hull has no curvature: off unless asked for
            shader.curvature = shader.extent_m > 1000.0 and method == "scan"
        rays = shader.rays(d.grid, az, 45.0)
        small = sun_rays(Grid.uniform(4, 4, *d.grid.centre_spacing(), d.grid.col_sign,
                                      d.grid.row_sign), az, 45.0)
        if ran_on == "gpu":
            from .gpu import GpuDem
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
        shade = np.clip(np.nan_to_num(beta, nan=0.0) / 30.0, 0.0, 1.0) if preview else None
        beta[np.isnan(beta)] = -9999.0
    tags = {"HILLSHADE_RT_VERSION": __version__, "AZIMUTH": az, "METHOD": method,
            "SAMPLE_SPACING": sample_spacing, "UNITS": "degrees above the horizontal",
            "EARTH_CURVATURE": (f"on, R {shader.body.radius(az):.0f} m, k {shader.k:g}"
                                if rays.curved else "off")}
    with timer("write"):
        write_raster(output, beta, d, nodata=-9999.0, description="horizon angle", tags=tags,
                     overwrite=overwrite, fmt=fmt)
        if preview is not None:
            write_png(preview, relief_rgb(d.heights, d.grid, az, 45.0, shade=shade), overwrite)
    if not quiet:
        rows, cols = d.shape
        click.echo(f"hillshade-rt: {output}: {cols}x{rows}, horizon toward az {az:g} ({method}, "
                   f"{ran_on}), compute {timer.seconds['compute']:.3f} s", err=True)
        if stats.get("note"):
            click.echo(f"hillshade-rt: note: {stats['note']}", err=True)


@cli.command()
@click.argument("dem", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@click.option("--preview", type=click.Path(dir_okay=False), default=None,
              help="Also write a quick-look PNG of the DEM (shaded relief, lit from the NW).")
@click.option("--overwrite", is_flag=True, help="Replace the preview if it exists.")
@dem_options
@_errors_to_click
def info(dem, as_json, preview, overwrite, **read_opts):
    """Print what hillshade-rt understood of DEM: size, spacing, CRS, nodata, heights."""
    if preview is not None:
        from .io.write import Claims
        Claims([dem], overwrite).claim(preview, "--preview")
    d = _read(dem, **read_opts)
    if preview is not None:
        from .io import write_png
        from .preview import relief_rgb
        write_png(preview, relief_rgb(d.heights, d.grid), overwrite)
    rows, cols = d.shape
    dx, dy = d.grid.centre_spacing()
    zmin, zmax = d.height_range()
    valid = d.valid_count()
    doc = {
        "path": d.path,
        "reader": d.kind,
        "driver": d.driver,
        "band": d.band,
        "dtype": d.source_dtype,
        "shape": [rows, cols],
        "crs": d.crs_string(),
        "crs_name": d.crs_name(),
        "transform": list(d.transform)[:6] if d.transform is not None else None,
        "orientation": ("north-up" if d.grid.row_sign < 0 else "south-up")
                       + ("" if d.grid.col_sign > 0 else ", columns run west"),
        "spacing_m": {"centre": [dx, dy],
                      "first_row": [float(d.grid.dx[0]), float(d.grid.dy[0])],
                      "last_row": [float(d.grid.dx[-1]), float(d.grid.dy[-1])],
                      "method": d.grid.method},
        "nodata": d.nodata,
        "valid_cells": valid,
        "nodata_fraction": 1.0 - valid / (rows * cols),
        "height_range_m": [zmin, zmax],
    }
    if as_json:
        click.echo(json.dumps(doc, indent=2))
        return
    click.echo(f"{d.path}")
    click.echo(f"  reader        {d.kind} ({d.driver}), band {d.band}, {d.source_dtype}")
    click.echo(f"  size          {cols} x {rows} (cols x rows), {d.heights.size:,} cells")
    click.echo(f"  crs           {doc['crs_name'] or 'none'}"
               + (f" ({doc['crs']})" if doc['crs'] and doc['crs'].startswith('EPSG') else ""))
    click.echo(f"  orientation   {doc['orientation']}")
    click.echo(f"  spacing (m)   dx {dx:.4f}  dy {dy:.4f} at the centre row")
    if d.grid.dx[0] != d.grid.dx[-1] or d.grid.dy[0] != d.grid.dy[-1]:
        click.echo(f"                dx {d.grid.dx[0]:.4f} .. {d.grid.dx[-1]:.4f}, "
                   f"dy {d.grid.dy[0]:.4f} .. {d.grid.dy[-1]:.4f} from first to last row")
    click.echo(f"                ({d.grid.method})")
    click.echo(f"  nodata        {d.nodata if d.nodata is not None else 'none'}"
               f"; {100 * doc['nodata_fraction']:.2f}% of cells are nodata")
    click.echo(f"  heights (m)   {zmin:.2f} .. {zmax:.2f}")


def main():
    """Console-script entry point (and ``python -m hillshade_rt``).

    The process ends with ``os._exit`` once the command is done and stdout and stderr are
    flushed: the interpreter's teardown of numba's and LLVM's objects took 0.2-0.3 s of every
    run (a fifth of a 10000² shadow run end to end) and has nothing left to do, every output
    being closed and in place by then. Where another thread or a child process is still alive
    (nothing of ours leaves one), the ordinary exit, which waits for them."""
    try:
        cli(prog_name="hillshade-rt")
        code = 0
    except SystemExit as exc:
        code = exc.code
    if code is None:
        code = 0
    elif not isinstance(code, int):
        print(code, file=sys.stderr)
        code = 1
    if _nothing_left_running():
        if "logging" in sys.modules:
            import logging
            logging.shutdown()
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(Exception):
                stream.flush()
        os._exit(code)
    sys.exit(code)


def _nothing_left_running() -> bool:
    """No other live non-daemon thread and no child process (``main``'s fast exit)."""
    import threading
    if any(t.is_alive() and not t.daemon and t is not threading.main_thread()
           for t in threading.enumerate()):
        return False
    if "multiprocessing" in sys.modules:
        import multiprocessing
        if multiprocessing.active_children():
            return False
    return True


if __name__ == "__main__":
    main()
