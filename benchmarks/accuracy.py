"""Disagreement of the approximate algorithms with brute on real DEMs.

For each DEM and sun: the share of valid cells whose mask differs from brute, and how far the
exact horizon angle of those cells is from the sun elevation (max |beta - alpha|, degrees).

    python benchmarks/accuracy.py DEM [DEM ...] [--out FILE]
"""

import argparse
import os
import sys

import numpy as np

from hillshade_rt.algorithms import brute, horizon, sweep
from hillshade_rt.model.geometry import sun_rays
from hillshade_rt.io import read_dem

SUNS = [(203.7, 3.0), (163.0, 10.0), (291.3, 5.0), (77.7, 20.0), (17.5, 1.5), (130.0, 30.0),
        (250.0, 8.0), (340.0, 45.0)]

VARIANTS = {
    "sweep K=1": lambda z, r: sweep.shadow_mask(z, r, exact_steps=1),
    "sweep K=4": lambda z, r: sweep.shadow_mask(z, r, exact_steps=4),
    "sweep K=8 (default)": lambda z, r: sweep.shadow_mask(z, r, exact_steps=8),
    "horizon hull": lambda z, r: horizon.shadow_mask(z, r, method="hull"),
    "horizon sp=2": lambda z, r: horizon.shadow_mask(z, r, sample_spacing=2),
    "horizon sp=4": lambda z, r: horizon.shadow_mask(z, r, sample_spacing=4),
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dems", nargs="+")
    ap.add_argument("--out", default=None)
    a = ap.parse_args(argv)
    lines = ["| DEM | algorithm | cells wrong: mean % | worst % | max abs(beta - alpha) deg |",
             "|---|---|---|---|---|"]
    for path in a.dems:
        d = read_dem(path)
        z = d.heights
        res = {k: ([], []) for k in VARIANTS}
        for az, el in SUNS:
            rays = sun_rays(d.grid, az, el)
            ref = brute.shadow_mask(z, rays)
            valid = max(1, int((ref != 255).sum()))
            beta = None
            for name, fn in VARIANTS.items():
                m = fn(z, rays)
                wrong = m != ref
                res[name][0].append(100.0 * wrong.sum() / valid)
                if wrong.any():
                    if beta is None:
                        beta = horizon.horizon_angles(z, rays)
                    res[name][1].append(float(np.abs(beta[wrong] - el).max()))
        for name, (fr, dev) in res.items():
            lines.append(f"| {os.path.basename(path)} | {name} | {np.mean(fr):.3f} | "
                         f"{np.max(fr):.3f} | {max(dev) if dev else 0.0:.2f} |")
        print("\n".join(lines[-len(VARIANTS):]), flush=True)
    text = "\n".join(lines) + "\n"
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
