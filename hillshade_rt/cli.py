"""The ``hillshade-rt`` command line.

Small click commands in the manner of rasterio's ``rio``; option names follow GDAL where GDAL has
one (``-b/--band``, ``-z/--z-factor``, ``--overwrite``). Every error is one line on stderr and a
non-zero exit status: 1 for bad input, 2 for a bad command line, 130 when interrupted.
"""

from __future__ import annotations

import functools
import json
import sys

import click

from . import __version__
from .errors import HillshadeError


class _OneLineErrors(click.Group):
    """A group whose errors (usage errors included) print as a single line, never a traceback."""

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        try:
            rv = super().main(args=args, prog_name=prog_name, complete_var=complete_var,
                              standalone_mode=False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:  # click >= 8.2: bare group prints help
            click.echo(exc.ctx.get_help(), err=True)
            sys.exit(2)
        except click.ClickException as exc:
            msg = exc.format_message()
            if isinstance(exc, click.UsageError) and exc.ctx is not None:
                msg += f" (see '{exc.ctx.command_path} --help')"
            click.echo(f"hillshade-rt: error: {msg}", err=True)
            sys.exit(exc.exit_code)
        except click.exceptions.Abort:
            click.echo("hillshade-rt: aborted", err=True)
            sys.exit(130)
        except KeyboardInterrupt:
            click.echo("hillshade-rt: interrupted; no output written", err=True)
            sys.exit(130)
        except BrokenPipeError:
            sys.exit(1)
        if not standalone_mode:
            return rv
        sys.exit(rv if isinstance(rv, int) else 0)


def _fail(exc: HillshadeError) -> click.ClickException:
    return click.ClickException(str(exc))


def dem_options(f):
    """Options that say how to read a DEM (shared by every command that reads one)."""
    opts = [
        click.option("-b", "--band", type=int, default=1, show_default=True,
                     help="Band of a multi-band raster."),
        click.option("--nodata", type=float, default=None,
                     help="Nodata value (overrides the file's). NaN is always nodata."),
        click.option("-z", "--z-factor", type=float, default=1.0, show_default=True,
                     help="Multiply heights by this (like gdaldem -z), e.g. 0.3048 for feet."),
        click.option("--pixel-size", metavar="DX[,DY]", default=None,
                     help="Ground spacing in metres; overrides the geotransform. "
                          "Required for input without georeferencing."),
        click.option("--raw-shape", metavar="ROWSxCOLS", default=None,
                     help="Read a raw binary grid of this shape."),
        click.option("--raw-dtype", type=click.Choice(
            ["int16", "uint16", "int32", "float32", "float64"]), default=None,
            help="Value type of a raw grid (.hgt: int16)."),
        click.option("--raw-byteorder", type=click.Choice(["little", "big"]), default=None,
                     help="Byte order of a raw grid (default little; .hgt: big)."),
    ]
    for opt in reversed(opts):
        f = opt(f)
    return f


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
        except HillshadeError as exc:
            raise _fail(exc) from None
        except MemoryError:
            raise click.ClickException("out of memory (the DEM is too large for this machine)") from None
    return wrapper


@click.group(cls=_OneLineErrors, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="hillshade-rt")
def cli():
    """Terrain cast-shadow masks from digital elevation models."""


@cli.command()
@click.argument("dem", type=click.Path(dir_okay=False))
@click.argument("output", type=click.Path(dir_okay=False))
@click.option("--azimuth", type=float, required=True,
              help="Sun azimuth, degrees clockwise from north (any value wraps).")
@click.option("--elevation", "--altitude", "elevation", type=float, required=True,
              help="Sun elevation above the horizon, degrees, > 0 and <= 90.")
@click.option("--algorithm", type=click.Choice(["brute", "smap", "horizon", "sweep"]),
              default="smap", show_default=True,
              help="brute: exact reference; smap: exact, fastest at low sun; horizon: exact "
                   "(horizon angles); sweep: approximate, fastest (see docs/algorithms.md).")
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
@backend_option
@click.option("--threads", type=click.IntRange(min=1), default=None,
              help="CPU threads (default: all cores).")
@click.option("--report", "report_path", type=click.Path(dir_okay=False), default=None,
              help="Write a JSON timing report here.")
@click.option("--overwrite", is_flag=True, help="Replace OUTPUT (and the report) if they exist.")
@click.option("-q", "--quiet", is_flag=True, help="No summary line on stderr.")
@dem_options
@_errors_to_click
def shadow(dem, output, azimuth, elevation, algorithm, nextv, better_nextv, horizon_method,
           sample_spacing, exact_steps, backend, threads, report_path, overwrite, quiet,
           **read_opts):
    """Write the cast-shadow mask of DEM to OUTPUT (GeoTIFF: 1 shadow, 0 lit, 255 nodata)."""
    import numba

    from .geometry import check_elevation, normalize_azimuth, sun_rays
    from .io import check_output_path, write_json, write_raster
    from .report import Timer, build_report, mask_stats, summary_line
    from .algorithms import ALGORITHMS
    from .shadow import choose_backend, warm_up

    timer = Timer()
    # validate everything cheap before reading or computing anything
    options = _algorithm_options(algorithm, nextv=nextv, better_nextv=better_nextv,
                                 method=horizon_method, sample_spacing=sample_spacing,
                                 exact_steps=exact_steps)
    az = normalize_azimuth(azimuth)
    el = check_elevation(elevation)
    check_output_path(output, overwrite)
    if report_path is not None:
        check_output_path(report_path, overwrite)
    if threads is not None:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    ran_on = choose_backend(backend, algorithm, options)

    with timer("read"):
        d = _read(dem, **read_opts)
    algo_stats: dict = {}
    gpu_dem = None
    with timer("prepare"):  # numba compilation on a first run; the DEM's upload to the GPU
        warm_up(algorithm, d.grid, az, el, backend=ran_on, **options)
        rays = sun_rays(d.grid, az, el)
        zmin, zmax = d.height_range()
        if ran_on == "gpu":
            from .gpu import GpuDem
            gpu_dem = GpuDem(d.heights, (zmin, zmax, d.valid_count() < d.heights.size))
    with timer("compute"):
        if gpu_dem is not None:
            mask = gpu_dem.shadow_mask(rays, algorithm, zmax, algo_stats, **options)
        else:
            mask = ALGORITHMS[algorithm](d.heights, rays, zmax, algo_stats, **options)
    tags = {"HILLSHADE_RT_VERSION": __version__, "SUN_AZIMUTH": az, "SUN_ELEVATION": el,
            "ALGORITHM": algorithm, "VALUES": "1=shadow 0=lit 255=nodata"}
    with timer("write"):
        write_raster(output, mask, d, nodata=255, description="cast shadow", tags=tags)
    stats = mask_stats(mask)
    seconds = dict(timer.seconds, total=timer.total())
    rep = build_report(dem=d, output=output, azimuth=az, elevation=el, algorithm=algorithm,
                       backend=ran_on, backend_requested=backend,
                       threads=numba.get_num_threads(), seconds=seconds,
                       stats=stats, height_range=(zmin, zmax), options=options,
                       algorithm_stats=algo_stats,
                       gpu=gpu_dem.report() if gpu_dem is not None else None)
    if report_path is not None:
        write_json(report_path, rep)
    if not quiet:
        click.echo(summary_line(rep), err=True)
        if algo_stats.get("note"):
            click.echo(f"hillshade-rt: note: {algo_stats['note']}", err=True)


_OPTION_OWNERS = {"nextv": "smap", "better_nextv": "smap", "method": "horizon",
                  "sample_spacing": "horizon", "exact_steps": "sweep"}
_OPTION_FLAGS = {"nextv": "--nextv", "better_nextv": "--better-nextv", "method": "--horizon-method",
                 "sample_spacing": "--sample-spacing", "exact_steps": "--exact-steps"}


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
@click.option("--azimuth", type=float, required=True,
              help="Azimuth along which to look, degrees clockwise from north.")
@click.option("--method", type=click.Choice(["scan", "hull"]), default="scan", show_default=True,
              help="scan: exact per-cell march; hull: convex-hull approximation, much faster.")
@click.option("--sample-spacing", type=click.IntRange(min=1), default=1, show_default=True,
              help="scan: use every N-th sample only (the paper's sp; faster, approximate).")
@backend_option
@click.option("--threads", type=click.IntRange(min=1), default=None,
              help="CPU threads (default: all cores).")
@click.option("--overwrite", is_flag=True, help="Replace OUTPUT if it exists.")
@click.option("-q", "--quiet", is_flag=True, help="No summary line on stderr.")
@dem_options
@_errors_to_click
def horizon(dem, output, azimuth, method, sample_spacing, backend, threads, overwrite, quiet,
            **read_opts):
    """Write the horizon angle toward AZIMUTH of every cell of DEM to OUTPUT.

    Float32 degrees above the horizontal (negative: the cell looks down on everything ahead;
    -90: no terrain ahead inside the raster); nodata -9999. A cell is lit by a sun at this
    azimuth iff its angle <= the sun's elevation."""
    import numba
    import numpy as np

    from .algorithms import horizon as hz
    from .geometry import Grid, normalize_azimuth, sun_rays
    from .shadow import choose_backend, warm_up
    from .io import check_output_path, write_raster
    from .report import Timer

    timer = Timer()
    az = normalize_azimuth(azimuth)
    check_output_path(output, overwrite)
    if method == "hull" and sample_spacing != 1:
        raise click.UsageError("--sample-spacing applies to --method scan only")
    if threads is not None:
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    ran_on = choose_backend(backend, "horizon", {"method": method})
    with timer("read"):
        d = _read(dem, **read_opts)
    stats: dict = {}
    with timer("prepare"):  # numba compilation on a first run
        rays = sun_rays(d.grid, az, 45.0)   # the elevation does not enter the angles
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
        beta[np.isnan(beta)] = -9999.0
    tags = {"HILLSHADE_RT_VERSION": __version__, "AZIMUTH": az, "METHOD": method,
            "SAMPLE_SPACING": sample_spacing, "UNITS": "degrees above the horizontal"}
    with timer("write"):
        write_raster(output, beta, d, nodata=-9999.0, description="horizon angle", tags=tags)
    if not quiet:
        rows, cols = d.shape
        click.echo(f"hillshade-rt: {output}: {cols}x{rows}, horizon toward az {az:g} ({method}, "
                   f"{ran_on}), compute {timer.seconds['compute']:.3f} s", err=True)
        if stats.get("note"):
            click.echo(f"hillshade-rt: note: {stats['note']}", err=True)


@cli.command()
@click.argument("dem", type=click.Path(dir_okay=False))
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@dem_options
@_errors_to_click
def info(dem, as_json, **read_opts):
    """Print what hillshade-rt understood of DEM: size, spacing, CRS, nodata, heights."""
    d = _read(dem, **read_opts)
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
    """Console-script entry point."""
    cli(prog_name="hillshade-rt")


if __name__ == "__main__":
    main()
