"""Whole runs from Python: DEM files in, georeferenced files out, as the command line does it.

:func:`shade` is ``hillshade-rt shadow`` / ``hillshade`` as a function: one DEM or a mosaic of
tiles, one sun or a series of times, in memory or in windows under a memory limit, on this
machine or on a Dask cluster given as a ``distributed.Client``. It runs the command line's own
code (one source of truth for checks, outputs and the report) and returns the report as a dict.
Bad input raises :class:`~hillshade_rt.errors.HillshadeError` with the command line's one-line
message; nothing is left half-written.

    >>> import hillshade_rt as hr
    >>> from distributed import Client
    >>> rep = hr.shade(["n46e007.tif", "n46e008.tif"], "shadow.tif", azimuth=203.7,
    ...                elevation=12, max_memory="2GB", cog=True, client=Client("tcp://s:8786"))
    >>> rep["processing"]["windows"], rep["processing"]["bytes_read_beyond_output_fraction"]

For arrays already in memory use :func:`~hillshade_rt.shadow_mask` or
:class:`~hillshade_rt.engine.Shader` instead.
"""

from __future__ import annotations

import datetime as _dt
import os

from .errors import HillshadeError

PRODUCTS = ("shadow", "classes", "hillshade")

# the command line's run options, set from shade()'s own arguments
_RUN_KEYS = ("output", "output_pattern", "preview", "backend", "report_path", "overwrite",
             "quiet", "max_memory", "window_size", "cog", "scheduler", "fmt")
# keyword arguments passed on as the command line's options of the same name
_PASSED = ("tz", "lat", "lon", "pressure", "temperature", "no_refraction", "sun_tolerance",
           "band", "nodata", "z_factor", "pixel_size", "raw_shape", "raw_dtype",
           "raw_byteorder", "threads")


def shade(dems, output: str | None = None, *, product: str = "shadow",
          output_pattern: str | None = None, azimuth: float | None = None,
          elevation: float | None = None, times=(), start=None, end=None, step: str | None = None,
          algorithm: str = "auto", algorithm_options: dict | None = None, soft: bool = False,
          self_shadow: bool = False, ambient: float = 0.2, scale: float | None = None,
          curvature: bool | None = None, refraction_k: float | None = None,
          backend: str = "auto", max_memory=None, window_size=None, cog: bool = False,
          fmt: str | None = None,
          client=None, overwrite: bool = False, report: str | None = None,
          preview: str | None = None, progress: bool = False, **more) -> dict:
    """Shade DEM file(s) into ``output`` (one band per sun) or ``output_pattern`` files.

    ``dems``: a path or a list of paths (tiles on one grid, shaded as one surface; with
    ``{tile}`` in ``output_pattern`` one file per tile). ``product``: "shadow" (1 shadow / 0 lit;
    visible fraction of the disk with ``soft``), "classes" or "hillshade". The sun:
    ``azimuth``/``elevation``, or ``times`` (datetimes or ISO strings), or ``start``/``end``/
    ``step`` at the DEM's place. ``algorithm_options``: e.g. ``{"nextv": "quad"}``.
    ``fmt``: a GDAL driver name (default from the extension, as ``--format``).
    ``max_memory`` (bytes or "2GB"), ``window_size`` ((rows, cols), an int, or "2048x2048"):
    windows as ``--max-memory``/``--window-size``. ``client``: a ``distributed.Client`` (or a
    scheduler address, or "local:N"): windows and times run as Dask tasks on it; the client is
    left open. Further keywords are the command line's options of the same name (``tz``,
    ``lat``, ``lon``, ``band``, ``nodata``, ``z_factor``, ``pixel_size``, ``raw_shape``, ...).

    Returns the report (what ``--report`` writes; also written to ``report`` when given)."""
    import click

    from . import cli as _cli
    if product not in PRODUCTS:
        raise HillshadeError(f"product must be one of {', '.join(PRODUCTS)}, got {product!r}")
    unknown = set(more) - set(_PASSED)
    if unknown:
        raise TypeError(f"shade() got unexpected keyword argument(s) {', '.join(sorted(unknown))}")
    files = [os.fspath(dems)] if isinstance(dems, (str, os.PathLike)) else [os.fspath(p)
                                                                            for p in dems]
    if not files:
        raise HillshadeError("no DEM given")
    cmd = _cli.cli.commands["hillshade" if product == "hillshade" else "shadow"]
    ctx = click.Context(cmd)
    kw = {p.name: p.get_default(ctx) for p in cmd.params if p.name not in ("files",)}
    kw = {k: v for k, v in kw.items() if k in _cli._SUN_KEYS or k in _RUN_KEYS or k in _PASSED}
    kw.update(more)
    if isinstance(window_size, int):
        window_size = f"{window_size}x{window_size}"
    elif isinstance(window_size, (tuple, list)):
        window_size = "x".join(str(int(v)) for v in window_size)
    kw.update(azimuth=azimuth, elevation=elevation,
              time=tuple(t.isoformat() if isinstance(t, _dt.datetime) else str(t)
                         for t in ([times] if isinstance(times, (str, _dt.datetime)) else times)),
              start=start.isoformat() if isinstance(start, _dt.datetime) else start,
              end=end.isoformat() if isinstance(end, _dt.datetime) else end, step=step,
              output=None if output is None else os.fspath(output),
              output_pattern=output_pattern, preview=preview, backend=backend,
              report_path=report, overwrite=overwrite, quiet=not progress,
              max_memory=max_memory, window_size=window_size, cog=cog, scheduler=client,
              fmt=fmt)
    if output is None and output_pattern is None:
        raise HillshadeError("give output or output_pattern")
    bad = set(algorithm_options or {}) - set(_cli._OPTION_OWNERS)
    if bad:
        raise HillshadeError(f"unknown algorithm option(s) {', '.join(sorted(bad))} (known: "
                             f"{', '.join(sorted(_cli._OPTION_OWNERS))})")
    algorithm = _cli._algorithm_for(algorithm, **(algorithm_options or {}))
    from .io.write import virtual_outputs
    token = virtual_outputs.set(True)    # /vsimem/ outputs are fine from Python
    try:
        if product == "hillshade":
            return _cli._light(files, "hillshade", algorithm,
                               _cli._algorithm_options(algorithm, **(algorithm_options or {})),
                               curvature, refraction_k, soft, True, ambient, scale, kw,
                               default_sun=(315.0, 45.0))
        if scale is not None:
            raise HillshadeError("scale applies to product='hillshade'")
        return _cli._light(files, product, algorithm,
                           _cli._algorithm_options(algorithm, **(algorithm_options or {})),
                           curvature, refraction_k, soft, self_shadow or product == "classes",
                           0.2, None, kw)
    except click.ClickException as exc:
        raise HillshadeError(exc.format_message()) from None
    finally:
        virtual_outputs.reset(token)

