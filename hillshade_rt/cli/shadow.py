"""``hillshade-rt shadow`` and ``hillshade-rt hillshade``: options -> ``run.ShadeConfig`` ->
``run.shade``."""

from __future__ import annotations

import click

from .errors import errors_to_click, say
from ..run.config import SUN_KEYS
from .options import (SectionedCommand, algorithm_flags, algorithm_option, command_line, context_option,
                      dem_options, each_option, finite,
                      given, height_above_ground_option, light_options, lightmap_options,
                      physics_options, run_options, stac_item_option, subsolar_options,
                      sun_options, to_read_options, to_run_options)

VECTOR_HELP = ("Also write the shadow as polygons (GeoPackage, GeoJSON or FlatGeobuf by the "
               "extension; with one DEM and no OUTPUT, only them) in the DEM's CRS: each "
               "polygon's azimuth, elevation, time (a sun from --time) and index (a series: "
               "every time's polygons in one layer). Lit cells and nodata make no polygon; "
               "--classes: shadow_class 1 self, 2 cast.")

LIFT_HELP = ("Each cell's ray toward the sun starts this many metres above the cell (a person, "
             "a panel above every cell); brute marches it (auto runs brute), --soft the horizon "
             "scan.")


def _config(files, kind, algorithm, options, kw, **more):
    """The ShadeConfig of a lighting command's parsed options ``kw`` (``each`` popped by
    the caller: ``_shade``)."""
    from ..run.config import ShadeConfig
    sun = {k: kw.pop(k) for k in SUN_KEYS}
    read = to_read_options(kw)
    run = to_run_options(kw, say)
    return ShadeConfig(files=list(files), kind=kind, sun=sun, algorithm=algorithm,
                       options=options, algorithm_explicit=given("algorithm"), read=read, run=run,
                       output=kw.pop("output"), output_pattern=kw.pop("output_pattern"),
                       max_memory=kw.pop("max_memory"), window_size=kw.pop("window_size"),
                       cog=kw.pop("cog"), scheduler=kw.pop("scheduler"),
                       stac_item=kw.pop("stac_item"), command=command_line(), **more)


def _shade(cfg, each):
    """``run.shade`` (one DEM or one mosaic), or with ``--each`` ``run.batch.shade_each``
    (each DEM on its own)."""
    from ..run import shade
    from ..run.batch import check_pattern, shade_each
    if each:
        return shade_each(cfg)
    check_pattern(cfg.output_pattern, False)     # {stem} without --each
    return shade(cfg)


@click.command(cls=SectionedCommand)
@click.argument("files", metavar="DEM... [OUTPUT]", nargs=-1, required=True,
                type=click.Path())
@sun_options("shadow")
@algorithm_option
@algorithm_flags
@physics_options
@click.option("--self-shadow", is_flag=True,
              help="Also shadow cells whose surface faces away from the sun (Horn normals).")
@click.option("--classes", is_flag=True,
              help="Write classes: 0 lit, 1 self-shadow, 2 cast shadow, 255 nodata.")
@click.option("--vector", metavar="OUT.gpkg|.geojson|.fgb", default=None,
              type=click.Path(dir_okay=False), help=VECTOR_HELP)
@click.option("--vector-connectivity", type=click.Choice(["4", "8"]), default="4",
              show_default=True,
              help="--vector's cells joined into one polygon through their edges (4, GDAL's "
                   "default) or also through their corners (8).")
@height_above_ground_option(LIFT_HELP)
@light_options
@subsolar_options
@run_options
@each_option
@stac_item_option
@dem_options
@context_option
@errors_to_click
def shadow(files, algorithm, curvature, refraction_k, soft, self_shadow, classes,
           height_above_ground, light_position, light_lonlat, subsolar, subsolar_file,
           sun_distance, body, **kw):
    """Write the cast-shadow mask of DEM to OUTPUT (GeoTIFF: 1 shadow, 0 lit, 255 nodata).

    Several DEMs (tiles on one grid) are shaded as one mosaic, so that a mountain in one tile
    shadows the next; OUTPUT is the last path, or give it with -o (with --vector and one DEM,
    OUTPUT may be left out: polygons only). Unrelated DEMs (any grid,
    CRS, size): --each with --output-pattern 'out/{stem}_shadow.tif', each on its own. The sun:
    --azimuth/--elevation, or --time (repeatable) or --start/--end/--step at the DEM's
    place (one band per time; OUTPUT.nc or OUTPUT.zarr: one CF time cube), or --subsolar
    LAT,LON / --subsolar-file F on the DEM's body (every cell its own sun). --soft writes the visible fraction of the sun's disk (float32,
    1 = fully lit, -9999 nodata); --classes writes 0 lit / 1 self-shadow / 2 cast / 255."""
    from ..algorithms import algorithm_for, options_for, options_from_cli
    if subsolar is not None or subsolar_file is not None or sun_distance is not None or \
            body is not None:
        return _subsolar(files, subsolar, subsolar_file, sun_distance, body, light_position,
                         light_lonlat,
                         height_above_ground, soft, self_shadow, classes, curvature,
                         refraction_k, kw)
    if light_position is not None or light_lonlat is not None:
        return _point_light(files, light_position, light_lonlat, height_above_ground, soft,
                            self_shadow, classes, algorithm, curvature, kw)
    flags = options_from_cli(kw)
    algorithm = algorithm_for(algorithm, flags)
    options = options_for(algorithm, flags)
    each = kw.pop("each")
    _shade(_config(files, "classes" if classes else "shadow", algorithm, options, kw,
                   curvature=curvature, refraction_k=refraction_k, soft=soft,
                   self_shadow=self_shadow or classes, height_above_ground=height_above_ground,
                   vector=kw.pop("vector"),
                   vector_connectivity=int(kw.pop("vector_connectivity"))),
           each)


def _point_light(files, position, lonlat, lift, soft, self_shadow, classes, algorithm, curvature,
                 kw):
    """``shadow --light-position/--light-lonlat``: -> ``run.point_light.LightConfig`` ->
    ``run.point_light`` (which refuses what a point light does not take yet)."""
    from ..algorithms import options_from_cli
    from ..run.config import PLACE_KEYS
    from ..run.config import LightConfig
    from ..run.point_light import light_shadow
    options_from_cli(kw)                       # the algorithms' own flags: none applies here
    sun = {k: kw.pop(k) for k in SUN_KEYS}
    refused = {"--azimuth/--elevation/--time/--start": any(
                   sun[k] for k in SUN_KEYS if k not in PLACE_KEYS),
               "--soft": soft, "--self-shadow": self_shadow, "--classes": classes,
               "--algorithm": given("algorithm"), "--earth-curvature": curvature is True,
               "--context": kw.get("context") is not None}
    kw.pop("vector_connectivity")
    for k, flag in (("scheduler", "--scheduler"), ("output_pattern", "--output-pattern"),
                    ("cog", "--cog"), ("stac_item", "--stac-item"), ("each", "--each"),
                    ("vector", "--vector")):
        refused[flag] = bool(kw.pop(k))
    window_size, max_memory = kw.pop("window_size"), kw.pop("max_memory")
    light_shadow(LightConfig(files=list(files), output=kw.pop("output"), position=position,
                             lonlat=lonlat, height_above_ground=lift, window_size=window_size,
                             max_memory=max_memory, read=to_read_options(kw),
                             run=to_run_options(kw, say), refused=refused))


def _lightmap_refused(kw, soft, curvature, refraction_k) -> dict:
    """What ``hillshade`` with a point light does not take yet (name -> given), as
    ``_point_light`` refuses them for ``shadow``; the sun's and the run's options popped from
    ``kw``."""
    from ..run.config import PLACE_KEYS
    sun = {k: kw.pop(k) for k in SUN_KEYS}
    refused = {"--azimuth/--elevation/--time/--start": any(
                   sun[k] for k in SUN_KEYS if k not in PLACE_KEYS),
               "--soft": soft, "--algorithm": given("algorithm"),
               "--earth-curvature": curvature is True,
               "--refraction-coefficient": refraction_k is not None,
               "--backend gpu": kw.get("backend") == "gpu",
               "--context": kw.get("context") is not None}
    for k, flag in (("window_size", "--window-size"), ("max_memory", "--max-memory"),
                    ("scheduler", "--scheduler"), ("output_pattern", "--output-pattern"),
                    ("cog", "--cog"), ("stac_item", "--stac-item"), ("each", "--each")):
        refused[flag] = bool(kw.pop(k))
    return refused


def _subsolar(files, subsolar, subsolar_file, distance, body, light_position, light_lonlat, lift,
              soft, self_shadow, classes, curvature, refraction_k, kw):
    """``shadow --subsolar LAT,LON`` or ``--subsolar-file F``: -> ``run.subsolar.SubsolarConfig``
    -> ``run.subsolar``
    (which refuses what it does not take yet)."""
    from ..algorithms import options_from_cli
    from ..run.config import PLACE_KEYS
    from ..run.config import SubsolarConfig
    from ..run.subsolar import subsolar_shadow
    options_from_cli(kw)
    sun = {k: kw.pop(k) for k in SUN_KEYS}
    refused = {"--azimuth/--elevation/--time/--start": any(
                   sun[k] for k in SUN_KEYS if k not in PLACE_KEYS),
               "--light-position/--light-lonlat": light_position is not None
               or light_lonlat is not None,
               "--self-shadow": self_shadow, "--classes": classes,
               "--algorithm": given("algorithm"), "--context": kw.get("context") is not None}
    kw.pop("vector_connectivity")
    for k, flag in (("window_size", "--window-size"), ("max_memory", "--max-memory"),
                    ("scheduler", "--scheduler"), ("output_pattern", "--output-pattern"),
                    ("cog", "--cog"), ("stac_item", "--stac-item"), ("each", "--each"),
                    ("vector", "--vector")):
        refused[flag] = bool(kw.pop(k))
    subsolar_shadow(SubsolarConfig(files=list(files), output=kw.pop("output"),
                                   subsolar=subsolar, sun_distance=distance, body=body,
                                   height_above_ground=lift, soft=soft, curvature=curvature,
                                   refraction_k=refraction_k, read=to_read_options(kw),
                                   run=to_run_options(kw, say), refused=refused,
                                   subsolar_file=subsolar_file, command=command_line()))


@click.command(cls=SectionedCommand)
@click.argument("files", metavar="DEM... [OUTPUT]", nargs=-1, required=True,
                type=click.Path())
@sun_options("hillshade")
@click.option("--ambient", type=click.FloatRange(0.0, 1.0), default=0.2, show_default=True,
              callback=finite,
              help="Light in shadow and on faces turned away, 0..1.")
@click.option("-s", "--scale", type=float, default=None,
              help="Ratio of vertical units to horizontal (gdaldem -s), e.g. 111120 for a DEM "
                   "in degrees with heights in metres; default: ground metres from the CRS.")
@algorithm_option
@physics_options
@height_above_ground_option(LIFT_HELP + " The relief's shading stays the ground's.")
@light_options
@lightmap_options
@run_options
@each_option
@stac_item_option
@dem_options
@context_option
@errors_to_click
def hillshade(files, ambient, scale, algorithm, curvature, refraction_k, soft,
              height_above_ground, light_position, light_lonlat, falloff, bits, **kw):
    """Write 8-bit shaded relief with cast shadows of DEM to OUTPUT.

    Illumination = ambient + (1 - ambient) * max(0, L.N) in lit cells and ambient in shadow
    (normals by Horn's method, like gdaldem); written as 1..255, 0 nodata. Sun as for `shadow`
    (default --azimuth 315 --elevation 45, like gdaldem). With a point light
    (--light-position/--light-lonlat) L points from each cell to the light; --falloff,
    --bits 16 and -f PNG make lightmaps."""
    from ..errors import UsageProblem
    if light_position is not None or light_lonlat is not None:
        from ..run.config import LightmapConfig
        from ..run.lightmap import lightmap
        refused = _lightmap_refused(kw, soft, curvature, refraction_k)
        lightmap(LightmapConfig(files=list(files), output=kw.pop("output"),
                                position=light_position, lonlat=light_lonlat,
                                height_above_ground=height_above_ground, read=to_read_options(kw),
                                run=to_run_options(kw, say), refused=refused, ambient=ambient,
                                scale=scale,
                                falloff=falloff or "none", bits=int(bits or 8)))
        return
    if falloff is not None or bits is not None:
        raise UsageProblem("--falloff and --bits go with a point light (--light-position or "
                           "--light-lonlat)")
    each = kw.pop("each")
    _shade(_config(files, "hillshade", algorithm, {}, kw, default_sun=(315.0, 45.0),
                   curvature=curvature, refraction_k=refraction_k, soft=soft, self_shadow=True,
                   ambient=ambient, scale=scale, height_above_ground=height_above_ground), each)
