"""make bench-view: hillshade-rt view's round trip -- a 1024 x 1024 view recomputed and delivered
(HTTP request to the server in this process, shading of the window with its halo, the RGBA PNG
encoded and read back by the client) at several suns, algorithm auto, on real DEMs and a spectral
fractal. Target (issue 22): <= 100 ms per update on the CPU.

Per case and sun: the median of 3 round trips, alternated in one process with the shadow mask
alone (the Shader.cast the server makes for that view: what the command line's shadow run
computes), so that the ratio round trip / mask says what the viewer adds whatever the machine's
load; and one update split into the picture (Viewer.render) and the PNG. Figures for
docs/benchmarks.md ("The viewer")."""

from __future__ import annotations

import os
import statistics
import sys
import threading
import time
import urllib.request

import numpy as np

from hillshade_rt.io import read_dem
from hillshade_rt.pictures.png import png_bytes
from hillshade_rt.run.view_server import make_server
from hillshade_rt.run.viewer import Viewer
from hillshade_rt.testing import memory_dem, real_dems, spectral

SUNS = [(163.0, 10.0), (203.7, 25.0), (290.0, 45.0), (40.0, 5.0), (120.0, 60.0), (250.0, 15.0)]
SIDE = 1024
REPEAT = 3


def fractal_dem(n: int):
    from affine import Affine
    z = spectral(n, 2.4, seed=7, relief=2000.0)
    return memory_dem(z, Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0), "EPSG:32611")


def cases():
    """(label, dem, bbox): 1024 x 1024 pixels of each."""
    out = []
    paths = dict((os.path.basename(p), (p, lab)) for p, lab in real_dems())
    for name in ("everest_srtm3_N27E086_voids_1201.tif", "nz_elev_1km_nztm_sea_nodata_1115x1450.tif"):
        path, label = paths[name]
        dem = read_dem(path)
        rows, cols = dem.shape
        r0, c0 = (rows - SIDE) // 2, (cols - SIDE) // 2
        out.append((f"{label}: central 1024² at full resolution", dem,
                    (c0, r0, c0 + SIDE, r0 + SIDE)))
    path, label = paths["bigtujunga_srtm30m_utm11n_1197x643.tif"]
    dem = read_dem(path)
    out.append((f"{label}: whole DEM in the view (1.17 cells per pixel)", dem,
                (0, -277, 1197, 920)))
    f = fractal_dem(2048)
    out.append(("spectral fractal 2048², beta 2.4, 30 m: central 1024² at full resolution", f,
                (512, 512, 1536, 1536)))
    f4 = fractal_dem(4096)
    out.append(("spectral fractal 4096²: whole DEM in the view (overview level 4)", f4,
                (0, 0, 4096, 4096)))
    return out


def fetch(url: str) -> tuple[float, bytes]:
    t = time.perf_counter()
    with urllib.request.urlopen(url, timeout=120) as r:
        body = r.read()
    return time.perf_counter() - t, body


def main() -> int:
    print(f"bench-view: {SIDE} x {SIDE} views, algorithm auto, {len(SUNS)} suns x {REPEAT} "
          f"round trips, {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}", flush=True)
    rows_out = []
    for label, dem, bbox in cases():
        viewer = Viewer(dem, "auto", "cpu")
        viewer.warm_up()
        srv = make_server(viewer, 0)
        th = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05},
                              daemon=True)
        th.start()
        try:
            b = ",".join(str(v) for v in bbox)
            trips, masks = [], []
            for az, el in SUNS:
                url = f"{srv.url}api/render?az={az}&el={el}&bbox={b}&w={SIDE}&h={SIDE}"
                _, body = fetch(url)          # the first of a sun (and of a level: gradients)
                pic, meta = viewer.render({"az": str(az), "el": str(el), "bbox": b,
                                           "w": str(SIDE), "h": str(SIDE)})
                n = int(meta["X-Level"])
                rows, cols = viewer.level(n)[0].shape
                ri = np.floor(bbox[1] + (np.arange(SIDE) + 0.5) * (bbox[3] - bbox[1]) / SIDE)
                ci = np.floor(bbox[0] + (np.arange(SIDE) + 0.5) * (bbox[2] - bbox[0]) / SIDE)
                ri, ci = ri[(ri >= 0) & (ri < dem.shape[0])] // n, ci[(ci >= 0) & (ci < dem.shape[1])] // n
                rs = slice(int(ri.min()), int(ri.max()) + 1)
                cs = slice(int(ci.min()), int(ci.max()) + 1)
                sh = viewer.shader(n, "auto")
                t_trip, t_mask = [], []
                for _ in range(REPEAT):       # A/B alternated: the round trip, the mask alone
                    t_trip.append(fetch(url)[0])
                    t = time.perf_counter()
                    viewer.call(viewer.part, sh, rs, cs, az, el)   # on the worker, as served
                    t_mask.append(time.perf_counter() - t)
                trips.append(statistics.median(t_trip))
                masks.append(statistics.median(t_mask))
            # the split of one update
            q = {"az": "203.7", "el": "25", "bbox": b, "w": str(SIDE), "h": str(SIDE)}
            t0 = time.perf_counter()
            pic, meta = viewer.render(q)
            t1 = time.perf_counter()
            png = png_bytes(pic)
            t2 = time.perf_counter()
        finally:
            srv.shutdown()
            srv.server_close()
        ms = [1000 * t for t in trips]
        mm = [1000 * t for t in masks]
        rows_out.append((label, meta["X-Level"], ms, mm, 1000 * (t1 - t0), 1000 * (t2 - t1)))
        print(f"{label}\n  level {meta['X-Level']}, {meta['X-Algorithm']}; round trip / the "
              "mask alone per sun (ms): "
              + ", ".join(f"{az:g}/{el:g}: {m:.0f}/{k:.0f}" for (az, el), m, k in zip(SUNS, ms, mm))
              + f"\n  round trip median {statistics.median(ms):.0f} ms, worst {max(ms):.0f} ms; "
                f"mask alone median {statistics.median(mm):.0f} ms; one update in process "
                f"{1000 * (t1 - t0):.0f} ms + PNG {1000 * (t2 - t1):.0f} ms "
                f"({len(png) / 1e6:.1f} MB)", flush=True)
    print("\n| view | level | round trip ms, median (worst) | mask alone ms, median | "
          "round trip / mask (median of suns) | PNG ms |")
    print("|---|---|---|---|---|---|")
    for label, level, ms, mm, _, pn in rows_out:
        ratio = statistics.median(m / k for m, k in zip(ms, mm))
        print(f"| {label} | {level} | {statistics.median(ms):.0f} ({max(ms):.0f}) | "
              f"{statistics.median(mm):.0f} | {ratio:.2f} | {pn:.0f} |")
    print(f"load average at the end {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
