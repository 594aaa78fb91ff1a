"""Where a lighting run's products go: bands of one OUTPUT or the files of ``--output-pattern``
(one per time, per input tile of a mosaic), their type, nodata, tags and band descriptions; a
series into OUTPUT named ``*.nc`` or ``*.zarr``: one CF time cube (``io.cube``).
"""

from __future__ import annotations

import contextlib
import os
import string

from .. import __version__
from ..errors import HillshadeError
from ..model.sun import SunOver
from ..model.times import iso


def tile_name(path: str) -> str:
    """``{tile}`` of an input: its file name without the extension; for an archive member given
    the rasterio way (``zip://t.zip!n46/e007.tif``) the member's (``e007``)."""
    if "://" in path and "!" in path:
        path = path.rsplit("!", 1)[1]
    return os.path.splitext(os.path.basename(path.rstrip("/")))[0]


class OutputPattern:
    """``--output-pattern 'out_{time:%Y%m%dT%H%M}.tif'``: one file per time. Fields: ``time``
    (an aware datetime in the zone of the times, with each instant's own offset: ``%z`` tells
    apart the hour repeated when clocks go back), ``index`` (0-based), ``azimuth``,
    ``elevation``, and ``tile``: the input DEM's file name without its extension; with several
    input tiles shaded as one mosaic, a pattern with ``{tile}`` gives one output per input tile
    (cut from the mosaic, on the tile's grid)."""

    FIELDS = ("time", "index", "azimuth", "elevation", "tile")

    def __init__(self, pattern: str):
        self.pattern = pattern
        try:
            fields = {f for _, f, _, _ in string.Formatter().parse(pattern) if f is not None}
        except ValueError as exc:
            raise HillshadeError(f"--output-pattern {pattern!r}: {exc}") from None
        names = {f.split(".")[0].split("[")[0] for f in fields}
        bad = names - set(self.FIELDS)
        if bad:
            raise HillshadeError(f"--output-pattern {pattern!r}: unknown field(s) "
                                 f"{', '.join(sorted(bad))} (use {', '.join(self.FIELDS)})")
        self.per_tile = "tile" in names
        self.planned: list[str] = []    # the files of the last ``paths``, as the pattern names them

    def paths(self, suns: list[SunOver], tiles: list[str] | None = None) -> list[list[str]]:
        """The files of each sun: one per name in ``tiles`` (the inputs' file names) when the
        pattern has ``{tile}``, else one."""
        names = [tile_name(t) for t in (tiles or [""])]
        if not self.per_tile:
            names = names[:1]
        out = []
        for i, s in enumerate(suns):
            try:
                out.append([self.pattern.format(time=s.time, index=i, azimuth=s.azimuth,
                                                elevation=s.elevation, tile=n) for n in names])
            except (ValueError, KeyError, AttributeError, IndexError, TypeError) as exc:
                raise HillshadeError(f"--output-pattern {self.pattern!r}: {exc}") from None
        if len(set(names)) != len(names):
            twins = sorted({t for t, n in zip(tiles, names) if names.count(n) > 1})
            raise HillshadeError(f"--output-pattern {self.pattern!r}: input tiles {twins[0]} and "
                                 f"{twins[1]} have the same file name, so {{tile}} cannot tell "
                                 "their outputs apart: rename one")
        flat = [p for ps in out for p in ps]
        if len(set(flat)) != len(flat):
            seen: dict = {}
            for s, ps in zip(suns, out):
                for p in ps:
                    seen.setdefault(p, []).append(s.time)
            twice = next(ts for ts in seen.values() if len(ts) > 1)
            if all(t is not None for t in twice) and \
                    twice[0].replace(tzinfo=None) == twice[1].replace(tzinfo=None):
                # the same local clock time twice: the hour repeated when the clocks go back
                raise HillshadeError(
                    f"--output-pattern {self.pattern!r} gives {iso(twice[0])} and "
                    f"{iso(twice[1])} (the same clock time, before and after the clocks go back) "
                    "the same file name: add the offset (e.g. {time:%Y%m%dT%H%M%z}) or {index}")
            raise HillshadeError(f"--output-pattern {self.pattern!r} gives two times the same file "
                                 "name: add a finer time field (e.g. {time:%Y%m%dT%H%M%S%z}) or "
                                 "{index}")
        self.planned = flat
        return out


def sun_tags(sun: SunOver) -> dict:
    tags = {"SUN_AZIMUTH": f"{sun.azimuth:.6f}", "SUN_ELEVATION": f"{sun.elevation:.6f}",
            "NIGHT": "yes" if sun.night else "no"}
    if sun.time is not None:
        tags["TIME"] = iso(sun.time)
    if sun.tiles:
        tags["SUN_MODE"] = f"per tile ({len(sun.tiles)} tiles)"
    return tags


def cube_attrs(product) -> dict:
    """The CF attributes of a product's variable in a time cube: its long name, what its
    values mean (flags, a dimensionless range)."""
    import numpy as np
    a = {"long_name": product.what, "comment": f"values: {product.values}"}
    if product.kind in ("shadow", "classes") and not product.soft:
        flags = ([0, 1], "lit shadow") if product.kind == "shadow" else \
            ([0, 1, 2], "lit self_shadow cast_shadow")
        a.update(flag_values=np.array(flags[0], np.uint8), flag_meanings=flags[1])
    elif product.soft and product.kind == "shadow":
        a.update(units="1", valid_range=np.array([0.0, 1.0], np.float32))
    else:       # a shaded relief: 1..255
        a.update(units="1", valid_range=np.array([1, 255], np.uint8))
    return a


def cube_name(product) -> str:
    """The data variable of a product in a time cube."""
    return "visible_fraction" if product.kind == "shadow" and product.soft else product.kind


def sun_variables(suns) -> dict:
    """The per-time variables of a lighting series' cube: the sun's azimuth (from grid north,
    as the run used it) and elevation at the raster's centre, degrees; the true azimuth where
    every time has one."""
    out = {"azimuth": ([s.azimuth for s in suns],
                       {"long_name": "sun azimuth at the raster's centre, clockwise from grid "
                                     "north", "units": "degree"}),
           "elevation": ([s.elevation for s in suns],
                         {"standard_name": "solar_elevation_angle",
                          "long_name": "sun elevation at the raster's centre (apparent)",
                          "units": "degree"})}
    if all(s.true_azimuth is not None for s in suns):
        out["true_azimuth"] = ([s.true_azimuth for s in suns],
                               {"standard_name": "solar_azimuth_angle",
                                "long_name": "sun azimuth at the raster's centre, clockwise "
                                             "from true north", "units": "degree"})
    return out


def cube_globals(title: str, tags: dict, command: str | None) -> dict:
    """A cube's global attributes: ``title``, ``history`` (when and the command; the Python
    API's call otherwise), ``source`` (this version), ``tags`` (the GeoTIFF's dataset tags)
    lower-cased."""
    import datetime as dt
    now = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    out = {"title": title, "history": f"{now}: {command or 'hillshade_rt (Python API)'}",
           "source": f"hillshade-rt {__version__}"}
    out.update({k.lower(): str(v) for k, v in tags.items() if k != "HILLSHADE_RT_VERSION"})
    return out


def label(sun: SunOver) -> str:
    if sun.time is not None:
        return iso(sun.time)
    return f"sun az {sun.azimuth:g} el {sun.elevation:g}"


class Outputs:
    """Where a lighting run's products go: bands of OUTPUT or files of a pattern; their type,
    nodata, tags and descriptions."""

    def __init__(self, product, algorithm, output, pattern, claims, cog, preview, ambient,
                 fmt=None, co=None):
        self.product = product          # a products.Product
        self.kind, self.soft = product.kind, product.soft
        self.dtype, self.nodata = product.dtype, product.nodata
        self.output, self.pattern, self.cog = output, pattern, cog
        self.claims, self.overwrite, self.fmt = claims, claims.overwrite, fmt
        self.co = dict(co or {})     # --co: creation options of the files published
        self.preview, self.ambient = preview, ambient
        self.base_tags = {"HILLSHADE_RT_VERSION": __version__, "ALGORITHM": algorithm,
                          "VALUES": product.values}
        self.what = product.what
        self.resampling = product.resampling
        self.continuous = product.continuous   # lossy formats and 16-bit PNG allowed
        self.via_vrt = False    # outputs assembled by GDAL from parts (Dask)
        self.paths = None
        self.tiles = self.tile_paths = None
        self._scratch: list[str] = []
        self.cube = None        # "netcdf" or "zarr": OUTPUT is a time cube (use_cube)
        self.command = None     # the command line, a cube's history
        self.suns = None

    def use_cube(self, from_time: bool, cog: bool = False, stac_item=None) -> bool:
        """Whether OUTPUT is a time cube: named ``*.nc`` or ``*.zarr``, the suns from times,
        no --format (which names GDAL's driver). The options a cube cannot take are refused
        then (usage errors, before any work): --co (GDAL's creation options), --cog,
        --stac-item; a missing library is named (``io.cube.check_cube_support``)."""
        from ..io.cube import cube_format, cube_output
        if (self.output is None or self.fmt is not None or not from_time
                or cube_format(self.output) is None):
            return False
        self.cube = cube_output(self.output, self.fmt, self.co, refused=(
            cog and f"{self.output}: --cog writes a GeoTIFF, not a time cube (.nc, .zarr)",
            stac_item is not None and f"--stac-item describes a GeoTIFF OUTPUT, not the time "
            f"cube {self.output}"))
        return True

    def plan(self, suns, inputs, tiles=None):
        """The files of each sun. ``tiles``: a mosaic's input tiles (``DemSource.tiles``); with a
        pattern naming ``{tile}`` each sun's mosaic is written to a scratch file beside the
        outputs and cut into one file per tile (``finish``)."""
        from ..io import check_output_format, output_driver
        self.suns = suns
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
                                    self.continuous and not (per_tile or self.via_vrt), self.co,
                                    self.resampling)
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
            from ..io.write import temp_beside
            self.paths[i] = temp_beside(self.tile_paths[i][0], ".scratch.tif")
            self._scratch.append(self.paths[i])
        return self.paths[i]

    def finish(self, i, sun, src):
        """Cut sun ``i``'s scratch mosaic into its tiles' files (on each tile's own grid), then
        remove it."""
        if self.tile_paths is None:
            return
        from ..io import copy_vrt, input_label
        from ..io.vrt import VrtSource, vrt_xml
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
            copy_vrt(doc, path, self.dtype, self.cog, self.resampling, self.overwrite, self.fmt,
                     self.co)
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
        return label(sun) if sun.time is not None else self.what

    def writer(self, dem, count):
        """The multi-band writer of OUTPUT (None with a pattern)."""
        from ..io import BandWriter
        if self.output is None:
            return contextlib.nullcontext()
        if self.cube is not None:
            from ..io.cube import CubeWriter
            return CubeWriter(self.output, dem, [s.time for s in self.suns],
                              name=cube_name(self.product), dtype=self.dtype,
                              nodata=self.nodata, attrs=cube_attrs(self.product),
                              time_variables=sun_variables(self.suns),
                              global_attrs=cube_globals(f"hillshade-rt: {self.what} series",
                                                        self.base_tags, self.command),
                              overwrite=self.overwrite)
        return BandWriter(self.output, dem, count, self.dtype, self.nodata, self.base_tags,
                          self.cog, self.resampling, overwrite=self.overwrite, fmt=self.fmt,
                          co=self.co)

    def file_writer(self, dem, i, sun):
        from ..io import BandWriter
        scratch = self.tile_paths is not None   # a mosaic to be cut into tiles: a GeoTIFF
        return BandWriter(self.target(i), dem, 1, self.dtype, self.nodata,
                          {**self.base_tags, **sun_tags(sun)}, self.file_cog, self.resampling,
                          overwrite=self.overwrite or scratch, fmt=None if scratch else self.fmt,
                          co=None if scratch else self.co)

    def record(self, sun, i, st, seconds, per_cell=False):
        rec = dict(sun.as_dict(), shadow_fraction=st["shadow_fraction"], compute_s=seconds)
        if per_cell:          # each cell marched with its own sun (the tiles: incidence only)
            rec["mode"] = "per cell"
        if self.tile_paths:
            rec["outputs"] = [os.path.abspath(p) for p in self.tile_paths[i]]
        elif self.paths:
            rec["output"] = os.path.abspath(self.paths[i])
        return rec
