"""The pictures of docs/products.md, made by the tool's own ``--preview`` on a 400 x 300 crop of
the bundled example DEM (Big Tujunga, SRTM 1 arc-second, UTM 11N): ``make docs-pictures``.

Two are drawn here from the tool's outputs instead (Pillow and Fiona: the tool's own
dependencies): the shadow polygons of ``shadow --vector`` over the crop's shaded relief, and
the twelve monthly bands of ``irradiance --monthly`` side by side (on the crop at 60 m: a year
in about a minute).

Every command line below is printed as it runs; the pictures go to docs/img/ (replaced).
``python docs/pictures.py NAME ...`` makes only those (names of docs/img/NAME.png)."""

import argparse
import os
import shlex
import subprocess
import sys
import tempfile

import numpy as np
import rasterio
from rasterio.enums import Resampling
from rasterio.windows import Window

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLE = os.path.join(ROOT, "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif")
IMG = os.path.join(ROOT, "docs", "img")
TOOL = [sys.executable, "-m", "hillshade_rt"]
DAY = "2026-12-21"
TZ = "America/Los_Angeles"


def crop(path: str, every: int = 1) -> None:
    """Columns 500..900, rows 150..450 of the example (a ridge, valleys and a basin edge);
    ``every`` > 1: averaged over blocks of every x every cells (a coarser DEM of the same
    place)."""
    with rasterio.open(EXAMPLE) as src:
        win = Window(500, 150, 400, 300)
        rows, cols = 300 // every, 400 // every
        z = src.read(1, window=win, out_shape=(rows, cols), resampling=Resampling.average)
        prof = src.profile | {"width": cols, "height": rows,
                              "transform": src.window_transform(win)
                              * rasterio.Affine.scale(every)}
    with rasterio.open(path, "w", **prof) as dst:
        dst.write(z.astype(prof["dtype"]), 1)


def show(cmd, tmp: str) -> None:
    """Print ``cmd`` as hillshade-rt's command line (file names without their folders)."""
    print("hillshade-rt " + " ".join(shlex.quote(os.path.basename(a) if a.startswith(tmp)
                                                 or a.startswith(IMG)
                                                 or a.startswith(ROOT) else a)
                                     for a in cmd), flush=True)


def tool(cmd, tmp: str) -> None:
    show(cmd, tmp)
    subprocess.run(TOOL + list(cmd), check=True)


def save_png(img, path: str, colours: int = 256) -> None:
    """``img`` (Pillow, RGB) as a palette PNG of at most ``colours`` colours: a few hundred KB
    at most."""
    from PIL import Image
    img.quantize(colours, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(
        path, optimize=True)


def relief(path: str):
    """The shaded relief written by ``hillshade-rt hillshade`` (uint8 1..255, 0 nodata) as
    grey 0..1 (voids white) and its transform."""
    with rasterio.open(path) as src:
        v = src.read(1).astype(np.float32)
        transform = src.transform
    grey = v / 255.0
    grey[v == 0] = 1.0
    return grey, transform


def draw_shadow_polygons(relief_tif: str, vector: str, png: str, scale: int = 2) -> int:
    """The polygons of ``vector`` (``shadow --vector``) over the shaded relief, ``scale``
    pixels per cell: shadow translucent blue, each ring outlined. Returns how many polygons."""
    import fiona
    from PIL import Image, ImageDraw
    grey, transform = relief(relief_tif)
    rows, cols = grey.shape
    base = Image.fromarray(np.rint(255 * grey).astype(np.uint8), "L").resize(
        (cols * scale, rows * scale), Image.Resampling.BILINEAR)
    inverse = ~transform

    def pixels(ring):
        out = []
        for x, y in ring:
            col, row = inverse * (x, y)
            out.append((col * scale, row * scale))
        return out

    polygons = []
    with fiona.open(vector) as layer:
        for feature in layer:
            rings = [pixels(r) for r in feature["geometry"]["coordinates"]]
            xs = [p[0] for p in rings[0]]
            ys = [p[1] for p in rings[0]]
            polygons.append(((max(xs) - min(xs)) * (max(ys) - min(ys)), rings))
    # the largest first: a shadow inside another one's hole (a lit hollow in a shadowed
    # slope) is drawn after the hole was cleared
    polygons.sort(key=lambda p: -p[0])
    mask = Image.new("L", base.size, 0)
    fill = ImageDraw.Draw(mask)
    for _, rings in polygons:
        fill.polygon(rings[0], fill=255)
        for hole in rings[1:]:
            fill.polygon(hole, fill=0)
    a = 0.55 * np.asarray(mask, np.float32)[..., None] / 255.0
    g = np.asarray(base, np.float32)[..., None] / 255.0
    tint = np.array([0.12, 0.27, 0.90], np.float32)
    rgb = g * (1.0 - a) + g * tint * a
    img = Image.fromarray(np.rint(255 * rgb).astype(np.uint8), "RGB")
    outline = ImageDraw.Draw(img)
    for _, rings in polygons:
        for ring in rings:
            outline.line(ring + ring[:1], fill=(10, 25, 120), width=1)
    save_png(img, png, 96)
    return len(polygons)


MONTHS = "Jan Feb Mar Apr May Jun Jul Aug Sep Oct Nov Dec".split()


def draw_monthly(irradiance_tif: str, relief_tif: str, png: str, columns: int = 6) -> None:
    """The monthly bands of ``irradiance --monthly --daily-mean`` (bands 5..16, Wh/m2 per
    day) side by side, ``columns`` a row, one colour scale for all (the tool's preview ramp
    over the relief), each month's name in its corner, the scale below in kWh/m2 per day."""
    from PIL import Image, ImageDraw, ImageFont

    from hillshade_rt.pictures.preview import ramp_colours
    grey, _ = relief(relief_tif)
    with rasterio.open(irradiance_tif) as src:
        months = src.read(list(range(5, src.count + 1))).astype(np.float32) / 1000.0
        nodata = src.nodata
        names = src.descriptions[4:]
    months[months == nodata / 1000.0] = np.nan
    lo, hi = np.nanpercentile(months, [1.0, 99.0])
    rows, cols = grey.shape
    gap, bar, text = 4, 12, 18
    lines = -(-len(names) // columns)
    width = columns * cols + (columns - 1) * gap
    height = lines * rows + (lines - 1) * gap + gap + bar + text
    img = Image.new("RGB", (width, height), (255, 255, 255))
    font = ImageFont.load_default(13)
    draw = ImageDraw.Draw(img)
    for k, (name, v) in enumerate(zip(names, months)):
        colour = ramp_colours((v - lo) / (hi - lo))
        rgb = colour * (0.55 + 0.45 * grey[..., None])    # the relief under the colour
        rgb[np.isnan(v)] = 1.0
        x0 = (k % columns) * (cols + gap)
        y0 = (k // columns) * (rows + gap)
        img.paste(Image.fromarray(np.rint(255 * rgb).astype(np.uint8), "RGB"), (x0, y0))
        label = f"{MONTHS[int(name[5:7]) - 1]} {name[:4]}"
        box = draw.textbbox((x0 + 4, y0 + 3), label, font=font)
        draw.rectangle((box[0] - 3, box[1] - 2, box[2] + 3, box[3] + 2), fill=(30, 30, 30))
        draw.text((x0 + 4, y0 + 3), label, fill=(255, 255, 255), font=font)
    # the scale: the ramp from lo to hi, whole kWh/m2 marked under it, the unit beside it
    y0 = lines * rows + (lines - 1) * gap + gap
    right = "kWh/m2 per day (global, clear sky)"
    span = width - 16 - round(draw.textlength(right, font=font))
    ramp = ramp_colours(np.linspace(0.0, 1.0, span, dtype=np.float32))
    img.paste(Image.fromarray(np.rint(255 * np.repeat(ramp[None], bar, 0)).astype(np.uint8),
                              "RGB"), (0, y0))
    draw.text((span + 8, y0 - 1), right, fill=(0, 0, 0), font=font)
    for tick in range(int(np.ceil(lo)), int(np.floor(hi)) + 1):
        x = round((tick - lo) / (hi - lo) * (span - 1))
        draw.line((x, y0, x, y0 + bar + 2), fill=(0, 0, 0))
        draw.text((x + 3, y0 + bar + 2), str(tick), fill=(0, 0, 0), font=font)
    save_png(img, png)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help="only these pictures (docs/img/NAME.png)")
    names = set(parser.parse_args(argv).names)
    os.makedirs(IMG, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        make(tmp, names)
    print(f"pictures in {IMG}")
    return 0


def make(tmp: str, names: set) -> None:
    """The pictures named in ``names`` (all when empty), the commands' outputs in ``tmp``."""
    dem = os.path.join(tmp, "dem.tif")
    crop(dem)

    def wanted(name):
        return not names or name in names

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
        if wanted(os.path.splitext(os.path.basename(s[s.index("--preview") + 1]))[0]):
            tool([s[0], *s[1:], *q], tmp)

    # shadow polygons at a low winter sun (08:30 on the solstice) over the relief lit from
    # the north-west
    if wanted("shadow_polygons"):
        tool(["hillshade", dem, out("relief.tif"), "--azimuth", "315", "--elevation", "45",
              *q], tmp)
        tool(["shadow", dem, "--time", f"{DAY}T08:30", "--tz", TZ, "--vector",
              out("shadow.gpkg"), *q], tmp)
        n = draw_shadow_polygons(out("relief.tif"), out("shadow.gpkg"),
                                 img("shadow_polygons.png"))
        print(f"{n} polygons drawn over relief.tif: shadow_polygons.png", flush=True)

    # a year's twelve monthly bands, Wh/m2 per day, on the crop averaged to 60 m (2 x 2
    # cells), the sun every 2 hours, one sun for the whole crop per time (its direction
    # varies by about 0.07 degrees across the crop, over the default 0.05 that computes it
    # per tile: --sun-tolerance 1); about a minute on 2 cores
    if wanted("irradiance_monthly"):
        small = os.path.join(tmp, "dem60.tif")
        crop(small, every=2)
        tool(["hillshade", small, out("relief60.tif"), "--azimuth", "315", "--elevation",
              "45", *q], tmp)
        tool(["irradiance", small, out("year.tif"), "--date", "2026-01-01", "--end-date",
              "2026-12-31", "--step", "2h", "--tz", TZ, "--monthly", "--daily-mean",
              "--sun-tolerance", "1", *q], tmp)
        draw_monthly(out("year.tif"), out("relief60.tif"), img("irradiance_monthly.png"))


if __name__ == "__main__":
    np.seterr(all="ignore")
    sys.exit(main())
