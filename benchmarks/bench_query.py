"""Observers above the ground and the sun at points: what ``--height-above-ground`` and
``hillshade-rt query`` cost.

All figures are measured within this one run, CPU backend, the median of --repeat runs after a
warm-up:

  * brute's mask (over the pyramid) at H = 0, 2 and 20 m on the bundled example DEM (Big
    Tujunga, SRTM 30 m, 1197 x 643, UTM 11N) at a low and a middle sun: a lift ends rays sooner;
  * ``arrays.sun_at_points`` for N random points x M suns, one sun for every point (one march
    call) and one sun per point (the per-cell sun of a time on a DEM the sun varies over: one
    call per point), as a query runs them;
  * the clear-sky irradiance of those points and times (``run.query.irradiance``).
"""

import argparse
import datetime as dt
import os

import numpy as np

from hillshade_rt.testing import median_seconds, real_dems

DEM = real_dems(["bigtujunga_srtm30m_utm11n_1197x643.tif"])[0][0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--points", type=int, default=2000)
    ap.add_argument("--suns", type=int, default=48)
    args = ap.parse_args()

    from hillshade_rt import read_dem, sun_at_points
    from hillshade_rt.algorithms import brute
    from hillshade_rt.model.geometry import sun_rays
    from hillshade_rt.run.query import irradiance

    d = read_dem(DEM)
    z, grid = d.heights, d.grid
    print(f"DEM {os.path.basename(DEM)} {d.shape[1]}x{d.shape[0]}, CPU, {os.cpu_count()} cores, "
          f"median of {args.repeat}\n")
    print("brute's mask with a lift (ms)")
    for el in (4.0, 25.0):
        rays = sun_rays(grid, 203.7, el)
        row = []
        for H in (0.0, 2.0, 20.0):
            s = median_seconds(lambda: brute.shadow_mask(z, rays, lift=H), args.repeat, True)
            row.append(f"H {H:g} m: {1e3 * s:.1f}")
        print(f"  elevation {el:g}: " + ", ".join(row))

    rng = np.random.default_rng(0)
    ok = np.flatnonzero(np.isfinite(z).ravel())
    pick = rng.choice(ok, args.points, replace=False)
    rows, cols = (pick // z.shape[1]).astype(float), (pick % z.shape[1]).astype(float)
    az = np.linspace(60.0, 300.0, args.suns)
    el = 5.0 + 40.0 * np.sin(np.linspace(0.1, np.pi - 0.1, args.suns))
    n, m = args.points, args.suns
    shared = median_seconds(lambda: sun_at_points(d, rows, cols, az, el, height_above_ground=1.7),
                            args.repeat, True)
    per_az = az[None, :] + np.linspace(-0.2, 0.2, n)[:, None]      # a sun per point
    per = median_seconds(lambda: sun_at_points(d, rows, cols, per_az, np.tile(el, (n, 1)),
                                               height_above_ground=1.7), args.repeat, True)
    print(f"\nsun_at_points, {n} points x {m} suns")
    print(f"  one sun for every point: {shared:.2f} s ({1e6 * shared / (n * m):.1f} us per "
          "point and sun)")
    print(f"  a sun per point:         {per:.2f} s ({1e6 * per / (n * m):.1f} us per point and "
          "sun)")

    res = sun_at_points(d, rows, cols, az, el, height_above_ground=1.7)
    pts = [{"lat": 34.3, "lon": -118.2 + 1e-3 * i} for i in range(n)]
    t0 = dt.datetime(2026, 6, 21, 13, tzinfo=dt.timezone.utc)
    times = [t0 + dt.timedelta(minutes=15 * k) for k in range(m)]
    s = median_seconds(lambda: irradiance(pts, None, times, res), args.repeat, True)
    print(f"\nclear-sky irradiance, {n} points x {m} times: {s:.2f} s")


if __name__ == "__main__":
    main()
