"""skyview (and horizon) in memory vs in windows, with and without --max-distance, on the
repository's real DEMs: seconds (the run's compute, the median of --repeat runs after a
warm-up) and the cells the windows read (the first windows and the continuation windows; the
ones the block maxima showed useless are skipped unread). docs/skyview.md has the figures.

    python benchmarks/bench_skyview.py [--directions 16] [--windows 512,256]
                                       [--max-distance 5000] [--repeat 1] [--threads N]
"""

import argparse
import os
import statistics
import tempfile


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--directions", type=int, default=16)
    ap.add_argument("--windows", default="512,256")
    ap.add_argument("--max-distance", type=float, default=5000.0)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--threads", type=int, default=None)
    ap.add_argument("--command", choices=["skyview", "horizon"], default="skyview")
    args = ap.parse_args()
    from hillshade_rt.run import HorizonConfig, horizon
    from hillshade_rt.run.config import RunOptions
    from hillshade_rt.run.config import SkyviewConfig
    from hillshade_rt.run.skyview import skyview
    from hillshade_rt.testing import real_dems

    out = os.path.join(tempfile.mkdtemp(prefix="hillshade-bench-skyview-"), "o.tif")
    ro = RunOptions(overwrite=True, quiet=True, threads=args.threads)

    def run(dem, ws, md):
        if args.command == "skyview":
            return skyview(SkyviewConfig(dem=dem, output=out, directions=args.directions,
                                         window_size=ws, max_distance=md, run=ro))
        return horizon(HorizonConfig(dem=dem, output=out, directions=args.directions,
                                     window_size=ws, max_distance=md, run=ro))
    print(f"{args.command} --directions {args.directions}; compute seconds, median of "
          f"{args.repeat} after a warm-up")
    print("| DEM | --max-distance | mode | seconds | vs in memory | cells read / cells | "
          "continuation windows (skipped) |")
    print("|---|---|---|---|---|---|---|")
    for dem, label in real_dems():
        for md in (None, args.max_distance):
            ref = None
            for ws in [None] + args.windows.split(","):
                run(dem, ws, md)
                reps = [run(dem, ws, md) for _ in range(args.repeat)]
                sec = statistics.median(r["seconds"]["compute"] for r in reps)
                ref = sec if ref is None else ref
                p = reps[-1]["processing"]
                read = p.get("cells_read", p["cells"]) / p["cells"]
                cont = (f"{p['continuation_windows']} ({p['skipped_windows']})"
                        if "continuation_windows" in p else "–")
                print(f"| {label} | {'–' if md is None else f'{md:g} m'} | "
                      f"{'in memory' if ws is None else f'windows of {ws}'} | {sec:.2f} | "
                      f"{sec / ref:.2f} | {read:.1f} | {cont} |")


if __name__ == "__main__":
    main()
