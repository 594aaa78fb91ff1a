"""What the checked writes of issue 16 cost (``make bench-writes``).

Every output goes through ``io.write.atomic_path``: a temporary file, GDAL's errors collected
(``gdal_checked``: rasterio's log and GDAL's stderr read through a pipe), ``fsync``, a
no-clobber publish. This times ``io.raster.write_raster`` against a bare ``rasterio.open(...).write()``
of the same array with the same creation options, in one run, on the shadow masks and soft
shadows of the bundled real DEM (Big Tujunga, SRTM 30 m) and of a power-law fractal, and one
multi-band series written window by window (the tiled path's many small writes). Also PNG
(copied from a finished GeoTIFF) against GeoTIFF. Figures go to docs/benchmarks.md.
"""

from __future__ import annotations

import os
import statistics
import tempfile
import time

import numpy as np
import rasterio

from hillshade_rt import io as hio
from hillshade_rt.model.earth import dem_body
from hillshade_rt.engine.shader import Shader, render
from hillshade_rt.model.geometry import Grid
from hillshade_rt.model.sun import SunOver
from hillshade_rt.testing import real_dems, spectral_f64

EXAMPLE = real_dems(["bigtujunga_srtm30m_utm11n_1197x643.tif"])[0][0]
REPEAT = 5


def best(f) -> float:
    ts = []
    for _ in range(REPEAT):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return min(ts), statistics.median(ts)


def products(dem):
    lo, hi = dem.height_range()
    sh = Shader(dem.heights, dem.grid, "smap", {}, "cpu", False, None, dem_body(dem), (lo, hi))
    sh.warm_up(203.7, 12.0, soft=True)
    mask = render(sh, SunOver(None, 203.7, 12.0), "shadow")
    soft = render(sh, SunOver(None, 203.7, 12.0), "shadow", soft=True)
    soft = np.where(np.isnan(soft), np.float32(-9999), soft).astype(np.float32)
    return mask, soft


def main():
    d = hio.read_dem(EXAMPLE)
    n = 4000
    z = spectral_f64(n)   # power-law fractal
    f = hio.Dem(heights=z, grid=Grid.uniform(n, n, 30.0, 30.0, 1, -1, "bench"), path="fractal",
                kind="bench", transform=d.transform, crs=d.crs)
    folder = tempfile.mkdtemp(prefix="bench-writes-", dir=os.path.dirname(EXAMPLE))
    print("| data | product | plain rasterio (s) | checked write (s) | ratio | PNG (s) |")
    print("|---|---|---|---|---|---|")
    try:
        for name, dem in (("Big Tujunga 1197x643 (real)", d), (f"fractal {n}x{n}", f)):
            mask, soft = products(dem)
            for pname, arr, nodata, resampling in (("mask uint8", mask, 255, "nearest"),
                                                   ("soft float32", soft, -9999.0, "average")):
                out = os.path.join(folder, "o.tif")
                prof = hio.gtiff_profile(dem, str(arr.dtype), nodata)
                if arr.dtype == np.float32:
                    prof["predictor"] = 3

                def plain():
                    with rasterio.open(out, "w", **prof) as ds:
                        ds.write(arr, 1)

                def checked():
                    hio.write_raster(out, arr, dem, nodata, overview_resampling=resampling,
                                     overwrite=True)

                def png():
                    hio.write_raster(os.path.join(folder, "o.png"), arr, dem, nodata,
                                     overview_resampling=resampling, overwrite=True)
                a, b, c = best(plain), best(checked), best(png)
                print(f"| {name} | {pname} | {a[0]:.3f} | {b[0]:.3f} | {b[0] / a[0]:.2f} | "
                      f"{c[0]:.3f} |")
        # a series written window by window (the tiled path): 8 bands, 512 x 512 windows
        mask, _ = products(f)
        windows = [(r, min(r + 512, n), c, min(c + 512, n)) for r in range(0, n, 512)
                   for c in range(0, n, 512)]
        out = os.path.join(folder, "s.tif")
        prof = hio.gtiff_profile(f, "uint8", 255)
        prof.update(count=8, interleave="band")

        def plain_series():
            from rasterio.windows import Window
            with rasterio.open(out, "w", **prof) as ds:
                for b in range(1, 9):
                    for r0, r1, c0, c1 in windows:
                        ds.write(mask[r0:r1, c0:c1], b, window=Window(c0, r0, c1 - c0, r1 - r0))

        def checked_series():
            with hio.BandWriter(out, f, 8, "uint8", 255, overwrite=True) as w:
                for b in range(1, 9):
                    for win in windows:
                        w.write(b, mask[win[0]:win[1], win[2]:win[3]], window=win)
        a, b = best(plain_series), best(checked_series)
        print(f"| fractal {n}x{n}, 8 bands in {len(windows)} windows each | mask uint8 | "
              f"{a[0]:.3f} | {b[0]:.3f} | {b[0] / a[0]:.2f} | |")
    finally:
        for p in os.listdir(folder):
            os.remove(os.path.join(folder, p))
        os.rmdir(folder)
    print(f"\nbest of {REPEAT}; ratio = checked / plain, measured in this run")


if __name__ == "__main__":
    main()
