"""GDAL VRT documents: rasters placed side by side in one virtual raster, written as XML in
memory (never to disk). A mosaic of DEM tiles is read through one (``source.open_dem``); Dask's
parts and a mosaic's per-tile outputs are put together or cut out through one."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class VrtSource:
    """One raster placed in a VRT band: ``path`` (what GDAL opens), its ``band``, where it goes
    (``offset``, ``shape``) and the part of it taken (``src_offset``)."""

    path: str
    band: int
    offset: tuple[int, int]      # (row, col) in the VRT
    shape: tuple[int, int]
    nodata: float | None = None
    src_offset: tuple[int, int] = (0, 0)   # (row, col) of the part taken from the source


def _metadata_xml(md: dict | None) -> str:
    from xml.sax.saxutils import escape, quoteattr
    if not md:
        return ""
    return ("<Metadata>" + "".join(f"<MDI key={quoteattr(str(k))}>{escape(str(v))}</MDI>"
                                   for k, v in md.items()) + "</Metadata>")


def vrt_xml(shape, transform, crs, bands: list[list[VrtSource]], dtype: str = "Float32",
            nodata: float | None = None, descriptions: list[str] | None = None,
            metadata: dict | None = None, band_metadata: list[dict] | None = None) -> str:
    """A GDAL VRT document: ``bands`` lists, per VRT band, the rasters placed in it (a source's
    nodata cells are left to the band's nodata); descriptions and metadata (tags) per band and
    for the dataset, which a copy of the VRT carries over."""
    from xml.sax.saxutils import escape
    rows, cols = shape
    out = [f'<VRTDataset rasterXSize="{cols}" rasterYSize="{rows}">', _metadata_xml(metadata)]
    if crs is not None:
        out.append(f"<SRS>{escape(crs.to_wkt())}</SRS>")
    if transform is not None:
        gt = transform.to_gdal()
        out.append("<GeoTransform>" + ", ".join(repr(float(v)) for v in gt) + "</GeoTransform>")
    for i, sources in enumerate(bands, start=1):
        out.append(f'<VRTRasterBand dataType="{dtype}" band="{i}">')
        if nodata is not None:
            out.append(f"<NoDataValue>{'nan' if math.isnan(nodata) else repr(nodata)}</NoDataValue>")
        if descriptions and descriptions[i - 1]:
            out.append(f"<Description>{escape(descriptions[i - 1])}</Description>")
        if band_metadata:
            out.append(_metadata_xml(band_metadata[i - 1]))
        for s in sources:
            r, c = s.offset
            h, w = s.shape
            out.append("<ComplexSource>")
            out.append(f'<SourceFilename relativeToVRT="0">{escape(s.path)}</SourceFilename>')
            out.append(f"<SourceBand>{s.band}</SourceBand>")
            sr, sc = s.src_offset
            out.append(f'<SrcRect xOff="{sc}" yOff="{sr}" xSize="{w}" ySize="{h}"/>')
            out.append(f'<DstRect xOff="{c}" yOff="{r}" xSize="{w}" ySize="{h}"/>')
            if s.nodata is not None:
                out.append(f"<NODATA>{'nan' if math.isnan(s.nodata) else repr(s.nodata)}</NODATA>")
            out.append("</ComplexSource>")
        out.append("</VRTRasterBand>")
    out.append("</VRTDataset>")
    return "".join(out)

