"""make bench-view: hillshade-rt view's round trip -- a 1024 x 1024 view recomputed and delivered
(HTTP request to the server in this process, shading of the window with its halo, the RGBA PNG
encoded and read back by the client) at several suns, algorithm auto, on real DEMs and a spectral
fractal. Target (issue 22): <= 100 ms per update on the CPU.

Per case: the median of 3 round trips per sun, and the split of one of them into shading
(Viewer.render: cast shadows, relief, colours), PNG encoding (run.view.png_bytes) and the rest
(HTTP, transfer). Figures for docs/benchmarks.md ("The viewer")."""

from __future__ import annotations

import os
import statistics
import sys
import threading
import time
import urllib.request

import numpy as np

from hillshade_rt.io import read_dem
from hillshade_rt.run.view import Viewer, make_server, png_bytes
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
          f"round trips, {os.cpu_count()} CPUs", flush=True)
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
            per_sun = []
            for az, el in SUNS:
                url = f"{srv.url}api/render?az={az}&el={el}&bbox={b}&w={SIDE}&h={SIDE}"
                fetch(url)                    # the first of a sun: the pyramid, the survey
                times = [fetch(url)[0] for _ in range(REPEAT)]
                per_sun.append(statistics.median(times))
            # the split of one update
            q = {"az": "203.7", "el": "25", "bbox": b, "w": str(SIDE), "h": str(SIDE)}
            t0 = time.perf_counter()
            pic, meta = viewer.render(q)
            t1 = time.perf_counter()
            png = png_bytes(pic)
            t2 = time.perf_counter()
            total, _ = fetch(f"{srv.url}api/render?az=203.7&el=25&bbox={b}&w={SIDE}&h={SIDE}")
        finally:
            srv.shutdown()
            srv.server_close()
        ms = [1000 * t for t in per_sun]
        rows_out.append((label, meta["X-Level"], meta["X-Algorithm"], ms,
                         1000 * (t1 - t0), 1000 * (t2 - t1), 1000 * total, len(png)))
        print(f"{label}\n  level {meta['X-Level']}, {meta['X-Algorithm']}; per sun (ms): "
              + ", ".join(f"{az:g}/{el:g}: {m:.0f}" for (az, el), m in zip(SUNS, ms))
              + f"\n  median {statistics.median(ms):.0f} ms, worst {max(ms):.0f} ms; one update: "
                f"shading {1000 * (t1 - t0):.0f} ms, PNG {1000 * (t2 - t1):.0f} ms "
                f"({len(png) / 1e6:.2f} MB), round trip {1000 * total:.0f} ms", flush=True)
    print("\n| view | level | median ms | worst ms | shading ms | PNG ms | round trip ms |")
    print("|---|---|---|---|---|---|---|")
    for label, level, alg, ms, sh, pn, tot, _ in rows_out:
        print(f"| {label} | {level} | {statistics.median(ms):.0f} | {max(ms):.0f} | {sh:.0f} | "
              f"{pn:.0f} | {tot:.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
