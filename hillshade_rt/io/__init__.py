"""The I/O layer: DEMs in, rasters and reports out. It imports only ``errors``, ``geometry``,
``sun``, ``_preload`` and ``algorithms`` (the heights' counts), never the layers above it.

=============  ===============================================================================
``source``     ``open_dem(paths, options) -> DemSource``: every DEM (GDAL, TIFF, raw, .hgt,
               standard input, mosaics) opened and checked once; ``.read()`` whole (a ``Dem``),
               ``.reader()`` in windows; ``read_dem(path)``
``dem``        ``Dem`` (heights in memory), the conversions every read shares
``paths``      where a DEM is (local paths, GDAL names, URLs, standard input), how reports
               name it
``gdal``       opening through rasterio, GDAL's errors as one line
``raw``        raw grids and SRTM .hgt tiles; ``tiff``: TIFFs through tifffile
``vrt``        VRT documents (mosaics in, parts put together out)
``crs``        a CRS for people
``raster``     ``BandWriter``, the one GeoTIFF profile, output formats, COGs, PNG pictures
``cube``       time cubes: a (time, y, x) series as one CF-1.8 NetCDF4 file or Zarr store
               (``CubeWriter``, ``write_cube``)
``write``      every file written whole or not at all: ``atomic_path``, ``Claims``,
               ``gdal_checked``, signals, ``write_json``
``vector``     shadow polygons: a mask's bands traced by GDAL, written by Fiona (GPKG,
               GeoJSON, FlatGeobuf) whole or not at all: ``write_polygons``
=============  ===============================================================================

The names below are imported when first used (PEP 562): ``hillshade_rt.io.write`` (what the
command line needs before it takes over the signals) loads without numpy or GDAL.
"""

from .._lazy import lazy_names

_EXPORTS = {
    # reading
    "open_dem": "source", "read_dem": "source", "open_windowed": "source", "place_in": "source",
    "DemSource": "source", "DemOptions": "source", "Reader": "source",
    "parse_pixel_size": "source", "check_z_factor": "source", "READ_CHUNK": "source",
    "Dem": "dem", "heights_into": "dem", "grid_of": "dem",
    "parse_raw_shape": "raw", "RAW_DTYPES": "raw", "RAW_EXTS": "raw",
    "STDIN": "paths", "STDIN_NAME": "paths", "is_gdal_name": "paths", "gdal_path": "paths",
    "dataset_name": "paths", "input_label": "paths",
    "crs_name": "crs", "crs_string": "crs",
    "VrtSource": "vrt", "vrt_xml": "vrt",
    # writing
    "BandWriter": "raster", "write_raster": "raster", "write_png": "raster",
    "read_decimated": "raster",
    "copy_vrt": "raster", "to_cog": "raster", "output_driver": "raster",
    "check_output_format": "raster", "gtiff_profile": "raster", "DEFLATE_LEVEL": "raster",
    "CubeWriter": "cube", "write_cube": "cube", "cube_format": "cube",
    "check_cube_support": "cube",
    "atomic_path": "write", "temp_beside": "write", "Claims": "write",
    "check_output_path": "write", "gdal_checked": "write", "write_json": "write",
}

__all__ = list(_EXPORTS)


__getattr__, __dir__ = lazy_names(__name__, _EXPORTS, globals())
