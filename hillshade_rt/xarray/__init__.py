"""hillshade-rt on xarray DataArrays (rioxarray's CRS and transform): ``import hillshade_rt.xarray``
registers the ``da.hrt`` accessor, with :func:`shadow`, :func:`horizon`, :func:`skyview`,
:func:`sun_hours`, :func:`irradiance` and :func:`shadow_polygons` as its methods
(``da.hrt.shadow(azimuth=203.7, elevation=12)``).

The input is a 2-D DataArray (or one with a ``band`` dimension of size 1) whose x/y coordinates
are regularly spaced. Its CRS is ``crs=``, else rioxarray's ``da.rio.crs``, else
``da.attrs["crs"]``; its transform rioxarray's ``da.rio.transform()`` (from the coordinates
where the stored one disagrees with them). Without a CRS the ground
spacing must be given (``spacing=``: metres per cell, ``d`` or ``(dx, dy)``), as the array API
(``hillshade_rt.engine.arrays``) requires. Nodata (``da.rio.nodata``, ``_FillValue``, or
``nodata=``), NaN and infinities are voids.

Every result is a DataArray on the input's x/y coordinates with its CRS and transform written by
rioxarray, a ``time`` dimension for a series of times, and attributes naming the product and the
sun (the GeoTIFF tags of the command line). The computation is the command line's: the same
``engine.shader.Shader`` and ``render``, the sun from ``--time`` through
``model.sun.SunRequest`` (the SPA on a lattice, per tile where it varies across the raster).

A **Dask-backed** DataArray gives a lazy, Dask-backed result, computed window by window as the
command line's windowed runs do (``engine.windows``): each output region's window holds the region
and the halo **toward the sun** that can shadow it (from the heights' block ranges), so the
windows are exactly what the planner reads, whatever the input's chunks (a chunk smaller than
the halo is fine: a task reads the slices of every chunk its window covers). One pass over the
input (the block height ranges the halos come from, and the centre height for a sun from a
time) runs when the function is called; the shadows when the result is computed. Horizons
take windows toward their azimuth (to the edge, or within ``max_distance``), sky views within
``max_distance`` all round (without it: one task over the whole raster).

The package: ``accessor`` (the functions and ``da.hrt``), ``dataarray`` (a DataArray in and
out), ``lazy`` (the Dask graph of the windows).
"""

from .accessor import (HrtAccessor, horizon, irradiance, shadow, shadow_polygons, skyview,
                       sun_hours)

__all__ = ["HrtAccessor", "shadow", "horizon", "skyview", "sun_hours", "irradiance",
           "shadow_polygons"]
