"""Suns from times: what a series, per-tile suns, curvature and soft shadows cost.

All ratios are measured within this one run, on the bundled example DEM (Big Tujunga, SRTM 30 m,
1197 x 643, UTM 11N), CPU backend, every figure the median of --repeat runs after a warm-up:

  * series: one ``shadow`` run with N times (one band each) vs N separate ``shadow`` runs (new
    processes, as a Makefile loop would do): seconds per time;
  * per cell (the default) and per tile vs one vector: the same instant with the default
    tolerance (the sun varies 0.18 deg across this DEM) and with the tolerance raised so one
    vector serves;
  * curvature on vs off, soft vs hard, self-shadow and hillshade vs the plain mask, at a 2 and a
    20 deg sun;
  * sun-hours of one day at 10 min.
"""

import argparse
import os
import subprocess
import sys
import tempfile

from hillshade_rt.testing import median_seconds, real_dems

DEM = real_dems(["bigtujunga_srtm30m_utm11n_1197x643.tif"])[0][0]


def median_time(fn, repeat):
    """The median of ``repeat`` runs, after one warm-up run."""
    return median_seconds(fn, repeat, warm_up=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--times", type=int, default=8, help="times in the series comparison")
    args = ap.parse_args()

    from hillshade_rt import read_dem
    from hillshade_rt.engine.shader import Shader, render
    from hillshade_rt.model.earth import dem_body
    from hillshade_rt.model.site import dem_site
    from hillshade_rt.model.sun import sun_over
    from hillshade_rt.model.times import parse_time

    d = read_dem(DEM)
    site = dem_site(d)
    lines = [f"DEM {os.path.basename(DEM)} {d.shape[1]}x{d.shape[0]}, CPU, "
             f"{os.cpu_count()} cores, median of {args.repeat}", ""]

    # -- series: one run with N bands vs N runs --------------------------------------------------
    exe = [sys.executable, "-m", "hillshade_rt"]
    times = [f"2026-06-21T{6 + i:02d}:15-07:00" for i in range(args.times)]
    with tempfile.TemporaryDirectory() as tmp:
        def one_run():
            cmd = exe + ["shadow", DEM, os.path.join(tmp, "s.tif"), "--overwrite", "-q"]
            for t in times:
                cmd += ["--time", t]
            subprocess.run(cmd, check=True)

        def separate_runs():
            for t in times:
                subprocess.run(exe + ["shadow", DEM, os.path.join(tmp, "x.tif"), "--overwrite",
                                      "-q", "--time", t], check=True)
        t_one = median_time(one_run, args.repeat)
        t_sep = median_time(separate_runs, args.repeat)
    lines += ["| series of %d times (the default, auto; 06:15..%02d:15 local) | s per time | ratio |" % (
        args.times, 6 + args.times - 1), "|---|---|---|",
        f"| one run, one band per time | {t_one / args.times:.3f} | 1 |",
        f"| {args.times} separate runs (new process each) | {t_sep / args.times:.3f} | "
        f"{t_sep / t_one:.2f} |", ""]

    # -- per tile vs one vector; physics options -----------------------------------------------
    rows = ["| sun | variant | compute s | vs plain mask (one vector, no curvature) |",
            "|---|---|---|---|"]
    for label, when in (("05:55 local", "2026-06-21T05:55-07:00"),
                        ("07:30 local", "2026-06-21T07:30-07:00")):
        t = parse_time(when)
        [tiled] = sun_over(site, d.shape, [t])
        [one] = sun_over(site, d.shape, [t], tolerance=10.0)
        zr = d.height_range()

        def sh(curv, alg="auto", options=None, per_cell=True):
            return Shader(d.heights, d.grid, alg, options or {}, "cpu", curv, None, dem_body(d),
                          zr, sun_field=per_cell)
        flat, curved = sh(False), sh(True)
        flat_t, curved_t = sh(False, per_cell=False), sh(True, per_cell=False)
        base = median_time(lambda: render(flat, one, "shadow"), args.repeat)
        variants = [
            ("one vector, curvature off (plain)", lambda: None, base),
            ("one vector, curvature on", None, lambda: render(curved, one, "shadow")),
            (f"per cell (dev {tiled.deviation_deg:.3f} deg across the DEM), curvature off", None,
             lambda: render(flat, tiled, "shadow")),
            ("per cell, curvature on (the default)", None, lambda: render(curved, tiled, "shadow")),
            (f"per tile ({len(tiled.tiles or [])} tiles), curvature on", None,
             lambda: render(curved_t, tiled, "shadow")),
            ("one vector, --soft", None, lambda: render(flat, one, "shadow", soft=True)),
            ("one vector, --self-shadow", None,
             lambda: render(flat, one, "shadow", self_shadow=True)),
            ("one vector, hillshade", None, lambda: render(flat, one, "hillshade")),
            ("one vector, brute (over the pyramid)", None,
             lambda: render(sh(False, "brute"), one, "shadow")),
            ("one vector, brute --no-pyramid (the plain march)", None,
             lambda: render(sh(False, "brute", {"pyramid": False}), one, "shadow")),
            ("one vector, smap", None, lambda: render(sh(False, "smap"), one, "shadow")),
        ]
        for name, _, fn in variants:
            s = fn if isinstance(fn, float) else median_time(fn, args.repeat)
            rows.append(f"| {label}, el {one.elevation:.1f} | {name} | {s:.3f} | {s / base:.2f} |")
    lines += rows + [""]

    # -- sun hours -----------------------------------------------------------------------------
    with tempfile.TemporaryDirectory() as tmp:
        def hours():
            subprocess.run(exe + ["sun-hours", DEM, os.path.join(tmp, "h.tif"), "--date",
                                  "2026-06-21", "--step", "10min", "--overwrite", "-q",
                                  "--report", os.path.join(tmp, "h.json")], check=True)
        t_h = median_time(hours, 1)
        import json
        with open(os.path.join(tmp, "h.json")) as fh:
            rep = json.load(fh)
    lines += [f"sun-hours 2026-06-21 at 10 min: {rep['samples_with_sun']} of {rep['samples']} "
              f"samples with the sun up, {t_h:.1f} s in all, compute "
              f"{rep['seconds']['compute']:.1f} s = "
              f"{rep['seconds']['compute'] / max(1, rep['samples_with_sun']):.3f} s per sun"]
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
