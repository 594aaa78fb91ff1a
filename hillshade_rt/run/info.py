"""The ``info`` run: what hillshade-rt understood of a DEM (size, spacing, CRS, nodata, heights),
as a dict; with a preview PNG of its shaded relief."""

from __future__ import annotations

from .config import ReadOptions, RunOptions
from .runner import RunContext


def describe(dem: str, read: ReadOptions, preview: str | None = None,
             overwrite: bool = False) -> tuple[dict, object]:
    """(the description, the DEM read)."""
    RunContext.start(RunOptions(preview=preview, overwrite=overwrite), inputs=[dem],
                     backend=False)     # --preview claimed (no numba threads: none set)
    d = read.read(dem)
    if preview is not None:
        _write_preview(d, preview, overwrite)
    return _document(d), d


def _write_preview(d, preview: str, overwrite: bool) -> None:
    """--preview: the DEM's shaded relief, lit from the north-west."""
    from ..io import write_png
    from ..pictures.preview import relief_rgb
    write_png(preview, relief_rgb(d.heights, d.grid), overwrite)


def _document(d) -> dict:
    """What was understood of the DEM ``d``, as the JSON of ``info --json``."""
    rows, cols = d.shape
    dx, dy = d.grid.centre_spacing()
    zmin, zmax = d.height_range()
    valid = d.valid_count()
    return {
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
