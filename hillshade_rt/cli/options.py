"""Every option of the command line, declared once (as rasterio's ``rio/options.py``): the
commands stack these groups, and ``to_read_options`` / ``to_run_options`` turn the parsed values
into the library's configs (``run.config``)."""

from __future__ import annotations

import math

import click

from ..errors import HillshadeError
from ..run.config import DEFAULT_WORKER_TIMEOUT, READ_KEYS


class InternalOption(click.Option):
    """An expert option (an algorithm's internals, tuning): listed by ``SectionedCommand``'s
    --help after the everyday options, under "Algorithm internals"."""

    internal = True


class SectionedCommand(click.Command):
    """A command whose --help lists its everyday options first ("Options"), then the expert
    ones (``InternalOption``: an algorithm's own flags, tuning) under "Algorithm internals"
    (click has no option groups of its own)."""

    INTERNALS = "Algorithm internals"

    def format_options(self, ctx, formatter):
        everyday, internal = [], []
        for param in self.get_params(ctx):
            rv = param.get_help_record(ctx)
            if rv is not None:
                (internal if getattr(param, "internal", False) else everyday).append(rv)
        if everyday:
            with formatter.section("Options"):
                formatter.write_dl(everyday)
        if internal:
            with formatter.section(self.INTERNALS):
                formatter.write_dl(internal)


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
    from ..io import parse_pixel_size
    return _checked(parse_pixel_size)(ctx, param, value)


def _check_raw_shape(ctx, param, value):
    from ..io import parse_raw_shape
    return _checked(parse_raw_shape)(ctx, param, value)


def finite(ctx, param, value):
    """A click callback: a float option must be a finite number (click's float takes nan, inf)."""
    if value is not None and not math.isfinite(value):
        raise click.BadParameter(f"must be a finite number, got {value}", ctx=ctx, param=param)
    return value


def _check_z_factor(ctx, param, value):
    from ..io import check_z_factor
    return _checked(check_z_factor)(ctx, param, value)


def dem_options(f):
    """Options that say how to read a DEM (shared by every command that reads one)."""
    return _stack(f, [
        click.option("-b", "--band", "--bidx", "band", type=click.IntRange(min=1), default=1,
                     show_default=True, help="Band of a multi-band raster."),
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


def _check_creation_options(ctx, param, value):
    """``--co NAME=VALUE`` (repeatable) -> {NAME: VALUE}; a malformed one: exit status 2."""
    if not value:
        return {}
    from ..io.raster import parse_creation_options
    try:
        return parse_creation_options(value)
    except HillshadeError as exc:
        raise click.UsageError(str(exc), ctx=ctx) from None


def format_option(f):
    """``-f/--format DRIVER`` and ``--co NAME=VALUE``: the rasters' GDAL driver and creation
    options (rasterio's ``rio`` spellings)."""
    return _stack(f, [
        click.option("-f", "--format", "--of", "fmt", metavar="DRIVER", default=None,
                     help="Output format, a GDAL driver name that can write (GTiff, COG, PNG, "
                          "JPEG, HFA, ENVI, AAIGrid, ...); default: from the output's extension "
                          "(.png PNG, .jpg JPEG, .asc AAIGrid, ...), else GeoTIFF."),
        click.option("--co", "creation_options", metavar="NAME=VALUE", multiple=True,
                     callback=_check_creation_options,
                     help="A GDAL creation option of the output's driver, e.g. COMPRESS=ZSTD, "
                          "PREDICTOR=2, BLOCKXSIZE=512, BIGTIFF=YES (with --cog or -f COG: the "
                          "COG driver's, e.g. BLOCKSIZE=1024, LEVEL=9); repeatable; overrides "
                          "the defaults (tiled, deflated). GDAL checks them before the run."),
    ])


def backend_option(f):
    return click.option(
        "--backend", type=click.Choice(["auto", "cpu", "gpu"]), default="auto", show_default=True,
        help="cpu: numba on all cores; gpu: CUDA through numba-cuda (pip install "
             "'hillshade-rt[gpu]'); auto: the GPU when numba finds one, else the CPU.")(f)


_ZONE = ("IANA zone, e.g. Europe/Zurich, or 'auto' (the zone of the DEM's centre, daylight "
         "saving included)")
TZ_HELP = {   # --tz's help, per command: what the zone does there
    "shadow": _ZONE + ": --time, --start and --end written without an offset are local times "
              "there, and the bands' descriptions and --output-pattern's {time} are in it "
              "(default: times need an offset, e.g. +02:00 or Z).",
    "hillshade": _ZONE + ": --time, --start and --end written without an offset are local "
                 "times there, and the bands' descriptions and --output-pattern's {time} are "
                 "in it (default: times need an offset, e.g. +02:00 or Z).",
    "query": _ZONE + ": --time, --start and --end written without an offset are local times "
             "there, and the rows' times are written in it (default: times need an offset, "
             "e.g. +02:00 or Z, and are written as given).",
    "sun-hours": _ZONE + ": --date's day runs midnight to midnight there (default: local mean "
                 "solar time at the DEM's longitude).",
    "irradiance": _ZONE + ": --date's days run midnight to midnight there and --start/--end "
                  "without an offset are local times there (default: local mean solar time "
                  "at the DEM's longitude).",
    "animate": _ZONE + ": --date's frames run from midnight to midnight there, --start/--end "
               "without an offset are local times there, and each frame's label shows its "
               "local time (default: 'auto').",
}


def place_options(command: str):
    """How the sun is computed from a time: zone, place, atmosphere, tolerance; ``command``
    (a key of ``TZ_HELP``) says what --tz does there."""
    def deco(f):
        return _stack(f, [
            click.option("--tz", default=None, metavar="ZONE", help=TZ_HELP[command]),
            click.option("--lat", type=float, default=None,
                         help="Latitude of the sun's observer, degrees (default: the DEM's "
                              "centre; required for input without a CRS)."),
            click.option("--lon", type=float, default=None,
                         help="Longitude, degrees east (with --lat)."),
            click.option("--pressure", type=float, default=None,
                         help="Air pressure for refraction, hPa (default: standard atmosphere "
                              "at the DEM's centre height)."),
            click.option("--temperature", type=float, default=None,
                         help="Air temperature for refraction, degrees C (default 12)."),
            click.option("--no-refraction", is_flag=True,
                         help="True (geometric) sun elevation instead of the apparent one."),
            click.option("--sun-tolerance", type=float, default=0.05, show_default=True,
                         cls=InternalOption,
                         help="Degrees the sun's direction may vary across the raster before "
                              "it is computed per tile."),
        ])
    return deco


TIME_HELP = {   # --time's help, per command: what each time gives there
    "shadow": "one band per time",
    "hillshade": "one band per time",
    "query": "one row per point and time",
}


def sun_options(command: str):
    """Where the sun is: given, or from times at the DEM's place (shared by the lighting
    commands and ``query``; ``command`` names the one, for the help texts)."""
    def deco(f):
        return _stack(place_options(command)(f), [
            click.option("--azimuth", type=float, default=None,
                         help="Sun azimuth, degrees clockwise from the raster's north (any "
                              "value wraps)."),
            click.option("--elevation", "--altitude", "elevation", type=float, default=None,
                         help="Sun elevation above the horizon, degrees, > 0 and <= 90."),
            click.option("--time", "time", multiple=True, metavar="ISO8601",
                         help="Sun from this instant (e.g. 2026-06-21T14:30:00+02:00) at the "
                              f"DEM's centre; repeat for a series ({TIME_HELP[command]})."),
        ] + _series_options("e.g. 30min, 1h, 1h30min, PT10M") + [
            click.option("--sun-from-stac", "sun_from_stac", default=None, metavar="ITEM.json",
                         help="The sun of a satellite scene: its STAC item's view:sun_azimuth "
                              "and view:sun_elevation (else the sun at the DEM at its "
                              "datetime); a file, URL or zip member, an item or a collection "
                              "of one."),
        ])
    return deco


def stac_item_option(f):
    """``--stac-item OUT.json``: a STAC item describing OUTPUT (pystac, the ``stac`` extra)."""
    return click.option("--stac-item", "stac_item", default=None, metavar="OUT.json",
                        type=click.Path(dir_okay=False),
                        help="Also write a STAC item describing OUTPUT (footprint, projection, "
                             "the sun, checksum; needs pip install 'hillshade-rt[stac]').")(f)


def command_line() -> str | None:
    """The current command as given on the command line (what a STAC item records): the
    command's path and the parameters given there, in click's order; None outside click."""
    import shlex
    from click.core import ParameterSource
    ctx = click.get_current_context(silent=True)
    if ctx is None:
        return None
    def long(opts):
        return next((o for o in opts if o.startswith("--")), opts[0])
    words = ctx.command_path.split()
    for p in ctx.command.params:
        if ctx.get_parameter_source(p.name) != ParameterSource.COMMANDLINE:
            continue
        value = ctx.params.get(p.name)
        values = list(value) if isinstance(value, (list, tuple)) else [value]
        if isinstance(p, click.Argument):
            words += [str(v) for v in values]
        elif getattr(p, "is_flag", False):
            on = value if getattr(p, "is_bool_flag", False) else True
            words.append(long(p.opts) if on or not p.secondary_opts else long(p.secondary_opts))
        else:
            for v in values:
                words += [long(p.opts), str(v)]
    return shlex.join(words)


def _series_options(step_help: str):
    """--start, --end and --step: a series of times."""
    return [
        click.option("--start", default=None, metavar="ISO8601", help="Series: first time."),
        click.option("--end", default=None, metavar="ISO8601",
                     help="Series: last time (included when a step lands on it)."),
        click.option("--step", default=None, metavar="DURATION",
                     help=f"Series: interval, {step_help}."),
    ]


def animation_options(f):
    """``animate``: the times (a day or a series), the frame rate, the picture's size, the
    label."""
    return _stack(f, [
        click.option("--date", "date_", default=None, metavar="YYYY-MM-DD",
                     help="A day: frames from local midnight (in --tz, else in the zone of "
                          "the DEM's centre) every --step until the next midnight."),
    ] + _series_options("e.g. 10min, 1h, PT15M (default 30min)") + [
        click.option("--fps", type=click.FloatRange(min=0.0, min_open=True, max=50.0),
                     default=12.0, show_default=True, help="Frames per second."),
        click.option("--size", type=click.IntRange(min=16), default=1024, show_default=True,
                     help="Pixels on the picture's long side at most (every n-th cell of the "
                          "DEM; the shadows are computed at full resolution)."),
        click.option("--label/--no-label", default=True, show_default=True,
                     help="Write the date and local time on each frame (top left)."),
    ])


def _curvature_options(when: str):
    """--earth-curvature and --refraction-coefficient, on by default ``when``."""
    return [
        click.option("--earth-curvature/--no-earth-curvature", "curvature", default=None,
                     help="Let the terrain fall away by d^2(1-k)/2R along each ray (default: on "
                          f"when {when})."),
        click.option("--refraction-coefficient", "refraction_k", type=float, default=None,
                     help="Terrestrial refraction k for --earth-curvature (default 0.13 on the "
                          "Earth, 0 on other bodies)."),
    ]


def curvature_options(f):
    """Earth curvature and refraction as the lighting commands decide them (on by default when
    rays can be longer than 1 km), without --soft (``query``: the same rays as ``shadow``)."""
    return _stack(f, _curvature_options("rays can be longer than 1 km"))


def horizon_physics_options(f):
    """Earth curvature and refraction of the horizon products (horizon, profile, skyview):
    curvature on by default when the raster is more than 1 km across."""
    return _stack(f, _curvature_options("the raster is more than 1 km across"))


def height_above_ground_option(what: str):
    """``--height-above-ground H``: metres (finite, >= 0) above the ground the observer stands
    (``what``: where, for this command)."""
    def deco(f):
        return click.option("--height-above-ground", type=click.FloatRange(min=0.0),
                            default=0.0, show_default=True, metavar="H", callback=finite,
                            help=what)(f)
    return deco


def preview_option(what: str = "Also write a quick-look PNG."):
    def deco(f):
        return click.option("--preview", type=click.Path(dir_okay=False), default=None,
                            help=what)(f)
    return deco


def light_options(f):
    """A point light instead of the sun (``shadow``): where it is."""
    return _stack(f, [
        click.option("--light-position", metavar="X,Y,Z", default=None,
                     help="A point light at X,Y in the DEM's CRS and Z metres above the datum "
                          "instead of the sun: every cell's ray runs to it and ends there."),
        click.option("--light-lonlat", metavar="LON,LAT,Z", default=None,
                     help="The same with the light's place in WGS84 degrees."),
    ])


def lightmap_options(f):
    """``hillshade`` with a point light: its falloff and the lightmap's bits."""
    return _stack(f, [
        click.option("--falloff", type=click.Choice(["none", "inverse-square"]), default=None,
                     help="With a point light: none (default), or inverse-square: the direct "
                          "light times min(1, (d_ref / d)^2), d the distance to the light, "
                          "d_ref its height above the ground beneath it."),
        click.option("--bits", type=click.Choice(["8", "16"]), default=None,
                     help="With a point light: 8 (default, 1..255) or 16 (1..65535) bits per "
                          "cell, e.g. 16-bit PNG lightmaps (-f PNG); 0 nodata."),
    ])


def subsolar_options(f):
    """The sun by its subsolar point on a body (``shadow``): every cell its own sun."""
    return _stack(f, [
        click.option("--subsolar", metavar="LAT,LON", default=None,
                     help="The sun straight above LAT,LON (degrees on the DEM's body) instead of "
                          "--azimuth/--time: every cell's sun from its own place on the body; "
                          "cells beyond the terminator are in shadow."),
        _subsolar_file_option(False),
        _sun_distance_option("--subsolar or the series' times without a distance"),
        _body_option("--subsolar"),
    ])


def _subsolar_file_option(required: bool):
    what = ("The subsolar series" if required else
            "A subsolar series instead of --subsolar: one band per time (the band's "
            "description its UTC time)")
    return click.option("--subsolar-file", metavar="F", required=required, default=None,
                        type=click.Path(dir_okay=False),
                        help=what + ": a CSV (time,lat,lon[,distance_m]; times increasing) or "
                                    "a JPL Horizons table saved as CSV (docs/subsolar.md).")


def _sun_distance_option(what: str):
    return click.option("--sun-distance", metavar="M", type=float, default=None,
                        help="The sun's distance from the body's centre in metres, for "
                             f"{what} (default the body's mean distance: 1 AU, Mars 1.5237 AU).")


def _body_option(what: str):
    return click.option("--body", metavar="moon|mars|earth|RADIUS", default=None,
                        help=f"The body for {what} instead of the CRS's: the Moon's or Mars' "
                             "sphere, WGS84, or a sphere of RADIUS metres.")


def subsolar_series_options(f):
    """A subsolar series (``illumination``): the file, the body, the sun's distance."""
    return _stack(f, [
        _subsolar_file_option(True),
        _sun_distance_option("the series' times without a distance"),
        _body_option("the series"),
    ])


def point_options(f):
    """Where the points of ``profile`` and ``query`` are: --at, --at-xy, --points."""
    return _stack(f, [
        click.option("--at", "at", multiple=True, metavar="LON,LAT",
                     help="A point in degrees (WGS84 longitude, latitude); repeatable."),
        click.option("--at-xy", "at_xy", multiple=True, metavar="X,Y",
                     help="A point in the DEM's CRS; repeatable."),
        click.option("--points", type=click.Path(dir_okay=False), default=None,
                     metavar="FILE",
                     help="Points from a CSV (columns lon,lat or x,y; id or name optional) or "
                          "a GeoJSON file of Point features."),
    ])


def monthly_option(what: str):
    """--monthly: one band per month of the period after the totals (``what``: of what)."""
    return click.option("--monthly", is_flag=True,
                        help=f"Also {what} of each month of the period: one band per month "
                             "after the total (description YYYY-MM; months in --tz, else "
                             "local mean solar time).")


def clear_sky_index_options(f):
    """--beam-index, --diffuse-index: GRASS r.sun's real sky (its coeff_bh, coeff_dh), the
    clear sky's beam and diffuse times these (0..1): a number, 12 monthly numbers, a raster or
    12 monthly rasters (``run.sky_inputs``)."""
    for name, what, rsun in (("--diffuse-index", "diffuse", "coeff_dh"),
                             ("--beam-index", "beam", "coeff_bh")):
        f = click.option(
            name, default=None, metavar="K|K1,...,K12|FILE|PATTERN",
            help=f"Clear-sky index of the {what} (0..1, r.sun's {rsun}): the real sky's "
                 f"{what} is the clear sky's times it; a number, 12 monthly numbers, a raster "
                 "or 12 monthly rasters, as --albedo. Not with --ghi.")(f)
    return f


def report_option(f):
    return click.option("--report", "report_path", type=click.Path(dir_okay=False),
                        default=None, help="Write a JSON report here.")(f)


def threads_option(f):
    return click.option("--threads", type=click.IntRange(min=1), default=None,
                        help="CPU threads (default: all cores).")(f)


def overwrite_option(what: str = "Replace OUTPUT if it exists."):
    def deco(f):
        return click.option("--overwrite", is_flag=True, help=what)(f)
    return deco


def quiet_option(what: str = "No summary line on stderr."):
    def deco(f):
        return click.option("-q", "--quiet", is_flag=True, help=what)(f)
    return deco


# run.report.PROGRESS_MODES (not imported here: the command line starts without the run layer)
PROGRESS_MODES = ("bar", "json")

progress_option = click.option(
    "--progress", type=click.Choice(PROGRESS_MODES), default="bar", show_default=True,
    help='bar: a progress bar on stderr (on a terminal, not with -q); json: instead a line '
         '{"progress": F} on stderr after each step (F the fraction done, increasing to 1.0; '
         'flushed; also with -q), for a program that shows the progress (the QGIS plugin).')


def physics_options(f):
    """Curvature, refraction and soft shadows of the lighting commands."""
    return _stack(f, _curvature_options("rays can be longer than 1 km") + [
        click.option("--soft", is_flag=True,
                     help="The sun as a disk of 0.533 deg: the visible fraction of the disk "
                          "(0..1, from the exact horizon angle) instead of hard shadows."),
    ])


def algorithm_option(f):
    """``--algorithm``: the registry's algorithms and their one-line summaries."""
    from ..algorithms import REGISTRY, algorithm_help
    return click.option("--algorithm", type=click.Choice(list(REGISTRY)), default="auto",
                        show_default=True, help=algorithm_help())(f)


def max_memory_option(f):
    return click.option("--max-memory", metavar="SIZE", default=None, cls=InternalOption,
                        help="Memory the run may use, e.g. 2GB or 512MiB; a DEM that needs more "
                             "is computed in windows read and written through GDAL (default: "
                             "half of this machine's memory).")(f)


def window_size_option(f):
    return click.option("--window-size", metavar="ROWS[xCOLS]", default=None,
                        cls=InternalOption,
                        help="Compute in windows of this many output cells, whatever the DEM's "
                             "size (each read with the halo it needs: toward the sun for "
                             "shadows, the rays' reach for horizons).")(f)


def max_distance_option(f):
    """--max-distance of the horizon products (horizon, skyview)."""
    return click.option("--max-distance", type=click.FloatRange(min=0.0, min_open=True),
                        default=None, metavar="METRES", callback=finite,
                        help="Ignore terrain farther than this ground distance along each ray "
                             "(RVT's and xarray-spatial's radius, Yokoyama's L; default: the "
                             "whole raster). Also bounds what windows read.")(f)


def scheduler_option(f):
    """--scheduler and its --worker-timeout (``run.config.RunOptions.worker_timeout``)."""
    return _stack(f, [
        click.option("--scheduler", metavar="ADDRESS", default=None,
                     help="Run the windows as Dask tasks: a dask.distributed scheduler "
                          "(tcp://host:8786) or 'local[:N]' (N worker processes here). Needs "
                          "hillshade-rt[dask] and DEM paths the workers can read."),
        click.option("--worker-timeout", type=click.FloatRange(min=0.0, min_open=True),
                     default=DEFAULT_WORKER_TIMEOUT, show_default=True, metavar="SECONDS",
                     callback=finite,
                     help="With --scheduler: fail when the scheduler has had no worker for "
                          "this long (none at the start, or every one lost during the run)."),
    ])


EACH_HELP = ("Each DEM on its own (different grids, CRSs, sizes welcome), into its own file "
             "named by --output-pattern's {stem} (the input's file name without extension), "
             "e.g. 'out/{stem}_shadow.tif'; a DEM that fails is named and the others go on "
             "(exit 1 at the end). Without it several DEMs are one mosaic.")


def each_option(f):
    """``--each``: many unrelated DEMs in one call (``run.batch``)."""
    return click.option("--each", is_flag=True, help=EACH_HELP)(f)


def each_pattern_options(f):
    """``--each`` and its ``--output-pattern`` for a command that takes ``DEM OUTPUT``."""
    return _stack(f, [
        click.option("--each", is_flag=True,
                     help="Several DEMs, each on its own into its own file named by "
                          "--output-pattern's {stem} (the input's file name without "
                          "extension); then every path given is a DEM. A DEM that fails is "
                          "named and the others go on (exit 1 at the end)."),
        click.option("--output-pattern", default=None, metavar="PATTERN",
                     help="With --each: each DEM's output, e.g. 'out/{stem}_hours.tif'."),
    ])


def run_options(f):
    return _stack(f, [
        click.option("-o", "--output", default=None, type=click.Path(dir_okay=False),
                     help="The output (then every path given is a DEM)."),
        click.option("--output-pattern", default=None, metavar="PATTERN",
                     help="One file per time instead of one multi-band OUTPUT, e.g. "
                          "'out_{time:%Y%m%dT%H%M}.tif' (fields: time, index, azimuth, elevation, "
                          "tile: the input's file name; with several input tiles, one file per "
                          "tile; with --each, stem: each DEM's own output)."),
        preview_option("Also write a quick-look PNG (shaded relief, shadows tinted)."),
        backend_option,
        threads_option,
        report_option,
        overwrite_option("Replace outputs (and the report, the preview) if they exist."),
        quiet_option("No progress bar or summary on stderr."),
        progress_option,
        max_memory_option,
        window_size_option,
        click.option("--cog", is_flag=True,
                     help="Write Cloud-Optimized GeoTIFF (512 px tiles, deflate, overviews)."),
        format_option,
        scheduler_option,
    ])


# the algorithms' own options, generated from the registry (each belongs to one algorithm)
def context_option(f):
    """--context RASTER: the DEM is a tile of a larger raster whose heights its rays see (the
    lighting and horizon commands; ``run.config.ReadOptions.context``)."""
    return click.option(
        "--context", metavar="RASTER", default=None, type=click.Path(dir_okay=False),
        help="The DEM is a tile of RASTER (a VRT or mosaic of the tiles, on the same grid): "
             "the output covers the tile only, but its rays see RASTER's heights (only the "
             "windows they need are read), so that each tile equals the same cells of the "
             "whole mosaic's output. For one process per tile, e.g. from a Makefile.")(f)


def algorithm_flags(f):
    from ..algorithms import OPTIONS
    for _, opt in reversed(list(OPTIONS.values())):      # the first listed shows first
        kind = {"choice": dict(type=click.Choice(opt.choices)),
                "int": dict(type=click.IntRange(min=opt.min)),
                "flag": dict(is_flag=True)}[opt.kind]
        f = click.option(opt.flag, opt.param, default=None, help=opt.help, cls=InternalOption,
                         **kind)(f)
    return f


def to_read_options(kw: dict):
    """The DEM options of ``dem_options``, popped from ``kw``, as ``run.ReadOptions``."""
    from ..run.config import ReadOptions
    return ReadOptions(**{k: kw.pop(k) for k in READ_KEYS}, context=kw.pop("context", None))


def to_run_options(kw: dict, say):
    """The options every run takes (backend, threads, report, overwrite, quiet, format,
    preview, --scheduler's --worker-timeout), popped from ``kw`` where given, as
    ``run.RunOptions``."""
    from ..run.config import RunOptions
    keys = ("backend", "threads", "report_path", "overwrite", "quiet", "progress", "fmt",
            "preview", "creation_options", "worker_timeout")
    return RunOptions(say=say, **{k: kw.pop(k) for k in keys if k in kw})


def given(name: str) -> bool:
    """Whether the option ``name`` was given on the command line (not its default)."""
    from click.core import ParameterSource
    ctx = click.get_current_context(silent=True)
    if ctx is None or name not in ctx.params:
        return True
    return ctx.get_parameter_source(name) not in (ParameterSource.DEFAULT,
                                                  ParameterSource.DEFAULT_MAP)


def view_options(f):
    """``hillshade-rt view``: where the viewer listens and whether it opens a browser."""
    return _stack(f, [
        click.option("--port", type=click.IntRange(0, 65535), default=0, show_default=True,
                     help="Port on 127.0.0.1 to listen on (0: a free one)."),
        click.option("--no-browser", is_flag=True,
                     help="Do not open the default browser (the URL is printed)."),
        click.option("--tz", default=None, metavar="ZONE",
                     help="IANA zone of the page's times (the clock, the date, the sun path), "
                          "e.g. Europe/Zurich; default: 'auto', the zone of the DEM's centre "
                          "(daylight saving included; a DEM without a CRS has no times)."),
    ])
