"""The pictures of docs/products.md, made by the tool's own ``--preview`` on a 400 x 300 crop of
the bundled example DEM (Big Tujunga, SRTM 1 arc-second, UTM 11N): ``make docs-pictures``.

Every command line below is printed as it runs; the pictures go to docs/img/ (replaced)."""

import os
import shlex
import subprocess
import sys
import tempfile

import numpy as np
import rasterio
from rasterio.windows import Window

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLE = os.path.join(ROOT, "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif")
IMG = os.path.join(ROOT, "docs", "img")
TOOL = [sys.executable, "-m", "hillshade_rt"]
DAY = "2026-12-21"
TZ = "America/Los_Angeles"


def crop(path: str) -> None:
    """Columns 500..900, rows 150..450 of the example (a ridge, valleys and a basin edge)."""
    with rasterio.open(EXAMPLE) as src:
        win = Window(500, 150, 400, 300)
        z = src.read(1, window=win)
        prof = src.profile | {"width": 400, "height": 300,
                              "transform": src.window_transform(win)}
    with rasterio.open(path, "w", **prof) as dst:
        dst.write(z.astype(prof["dtype"]), 1)


def main() -> int:
    os.makedirs(IMG, exist_ok=True)
    tmp = tempfile.mkdtemp()
    dem = os.path.join(tmp, "dem.tif")
    crop(dem)

    def out(name):
        return os.path.join(tmp, name)

    def img(name):
        return os.path.join(IMG, name)

    q = ["-q", "--overwrite"]
    steps = [
        ["shadow", dem, out("shadow.tif"), "--azimuth", "203.7", "--elevation", "12",
         "--preview", img("shadow.png")],
        ["shadow", dem, out("soft.tif"), "--azimuth", "203.7", "--elevation", "12", "--soft",
         "--preview", img("soft.png")],
        ["hillshade", dem, out("hillshade.tif"), "--time", f"{DAY}T15:00", "--tz", TZ,
         "--preview", img("hillshade.png")],
        ["sun-hours", dem, out("hours.tif"), "--date", DAY, "--tz", TZ, "--step", "20min",
         "--preview", img("sun_hours.png")],
        ["horizon", dem, out("horizon.tif"), "--azimuth", "163", "--preview",
         img("horizon.png")],
        ["skyview", dem, out("svf.tif"), "--directions", "32", "--preview", img("skyview.png")],
        ["skyview", dem, out("open.tif"), "--openness", "positive", "--directions", "32",
         "--max-distance", "3000", "--preview", img("openness.png")],
        ["irradiance", dem, out("irr.tif"), "--date", DAY, "--tz", TZ, "--step", "30min",
         "--preview", img("irradiance.png")],
        ["profile", dem, "--at=-118.155,34.305", "--height-above-ground", "2", "-o",
         out("profile.csv"), "--preview", img("profile.png")],
    ]
    # the illumination of the Kepler crater (LOLA, its real place near 8 deg N) over a toy
    # lunation (testing.toy_lunar_subsolar: one synodic month in 6-hour steps)
    from hillshade_rt.testing import toy_lunar_subsolar, write_subsolar_csv
    kepler = os.path.join(ROOT, "benchmarks", "data", "moon_kepler_crater_lola_ortho_804x804.tif")
    lunation = write_subsolar_csv(out("lunation.csv"), toy_lunar_subsolar(119, 6.0))
    steps.append(["illumination", kepler, out("illum.tif"), "--subsolar-file", lunation,
                  "--preview", img("illumination.png")])
    for s in steps:
        cmd = [s[0], *s[1:], *q]
        print("hillshade-rt " + " ".join(shlex.quote(os.path.basename(a) if a.startswith(tmp)
                                                     or a.startswith(IMG)
                                                     or a.startswith(ROOT) else a)
                                         for a in cmd), flush=True)
        subprocess.run(TOOL + cmd, check=True)
    print(f"pictures in {IMG}")
    return 0


if __name__ == "__main__":
    np.seterr(all="ignore")
    sys.exit(main())
