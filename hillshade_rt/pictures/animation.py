"""The frames of ``hillshade-rt animate`` and their encoding (GIF through Pillow, MP4 through
imageio-ffmpeg): shaded relief with the cast shadows tinted, the local time written on each frame.

A frame is a palette picture of at most 256 colours (``PALETTE``), so that a GIF holds it
exactly: ``LEVELS`` grey levels of the relief lit by the frame's sun, the same levels tinted as
``preview`` tints shadows (``preview.TINT``), darker tinted levels for frames at night, white for
voids, and the label's box and text. Lit relief is grey (red = green = blue) and every shadowed
or night colour is not, so whether a pixel of a frame (or of the GIF read back) is in shadow can
be read from its colour alone (:func:`shadowed_pixels`).

The picture is the DEM's every ``n``-th cell, ``n = ceil(long side / size)`` (as
``preview.relief_rgb``): frame k's shadows are the full-resolution mask of time k at those
cells.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import HillshadeError, UsageProblem
from ..model.geometry import Grid
from .preview import TINT

LEVELS = 80                   # grey levels of the relief (0.25 .. 1 of white)
LIT, SHADOW, NIGHT = 0, LEVELS, 2 * LEVELS     # first palette index of each band of levels
VOID = 3 * LEVELS             # white
BOX, TEXT = VOID + 1, VOID + 2     # the label: dark grey box, white text
NIGHT_DIM = 0.45              # a night frame: the shadow tint, darker still
FORMATS = (".gif", ".mp4")
MAX_FPS = 50.0                # GIF delays are whole hundredths of a second; browsers slow < 2


def palette() -> np.ndarray:
    """(256, 3) uint8: the colours of the frames' indices."""
    grey = 0.25 + 0.75 * np.arange(LEVELS, dtype=np.float32) / (LEVELS - 1)
    pal = np.zeros((256, 3), np.float32)
    pal[LIT:LIT + LEVELS] = grey[:, None]
    pal[SHADOW:SHADOW + LEVELS] = grey[:, None] * TINT
    pal[NIGHT:NIGHT + LEVELS] = grey[:, None] * TINT * NIGHT_DIM
    pal[VOID] = 1.0
    pal[BOX] = 0.12
    pal[TEXT] = 1.0
    return np.rint(255.0 * pal).astype(np.uint8)


PALETTE = palette()


def step_of(shape, size: int) -> int:
    """Every how many cells the picture takes (its long side at most ``size``)."""
    return max(1, math.ceil(max(shape) / size))


def subsample(z: np.ndarray, grid: Grid, n: int) -> tuple[np.ndarray, Grid]:
    """Every ``n``-th cell of ``z`` and its grid (``preview.relief_rgb``'s subsampling)."""
    zs = np.ascontiguousarray(z[::n, ::n])
    g = Grid(zs.shape[0], zs.shape[1], grid.dx[::n] * n, grid.dy[::n] * n, grid.col_sign,
             grid.row_sign, grid.method)
    return zs, g


def relief_levels(zs: np.ndarray, grid: Grid, azimuth: float, elevation: float) -> np.ndarray:
    """uint8 grey level (0 .. LEVELS-1) per cell of ``zs``: 0.25 + 0.75 cos i, lit from
    ``azimuth``, ``elevation`` (at least 5 degrees: a low sun would make the picture black)."""
    from ..algorithms.relief import incidence
    cosi = np.clip(np.nan_to_num(incidence(zs, grid, azimuth, max(elevation, 5.0)), nan=0.0),
                   0.0, 1.0)
    return np.rint(cosi * (LEVELS - 1)).astype(np.uint8)


def frame_indices(levels: np.ndarray, shadow: np.ndarray | None, void: np.ndarray) -> np.ndarray:
    """uint8 palette indices of one frame: ``levels`` (:func:`relief_levels`) lit, or tinted
    where ``shadow`` is 1 (the subsampled mask: 1 shadow, 0 lit, 255 void); ``shadow`` None: a
    night frame (all dark). ``void``: cells without a height (white)."""
    if shadow is None:
        out = (NIGHT + levels).astype(np.uint8)
    else:
        out = np.where(shadow == 1, SHADOW + levels, LIT + levels).astype(np.uint8)
    out[void] = VOID
    return out


def shadowed_pixels(rgb: np.ndarray) -> np.ndarray:
    """bool per pixel of an (rows, cols, 3) frame in colour: in shadow (tinted: not grey)."""
    rgb = np.asarray(rgb)
    return (rgb[..., 0] != rgb[..., 2]) | (rgb[..., 1] != rgb[..., 2])


def font_size(width: int) -> int:
    return max(10, round(width / 30))


def draw_label(indices: np.ndarray, text: str) -> np.ndarray:
    """``indices`` with ``text`` written in its top-left corner, white on a dark box (Pillow's
    default font, sized to the picture, smaller where the text would not fit; glyphs drawn
    without anti-aliasing: the palette has no blends). Returns a new array."""
    from PIL import Image, ImageDraw, ImageFont
    img = Image.fromarray(indices, "L")      # indices as plain values: no blending below
    draw = ImageDraw.Draw(img)
    draw.fontmode = "1"
    width = indices.shape[1]
    size = font_size(width)
    font = ImageFont.load_default(size)
    while size > 6 and draw.textlength(text, font=font) > width - 2 * max(2, size // 4):
        size -= 1           # a narrow picture: a smaller font, so that the label fits
        font = ImageFont.load_default(size)
    pad = max(2, size // 4)
    left, top, right, bottom = draw.textbbox((pad, pad), text, font=font)
    draw.rectangle((0, 0, right + pad, bottom + pad), fill=BOX)
    draw.text((pad, pad), text, fill=TEXT, font=font)
    return np.asarray(img).copy()


def label_text(t, night: bool, lon: float | None) -> str:
    """The date and local time of ``t`` (aware): in its own zone with the zone's abbreviation
    (or UTC offset), or, ``lon`` given (no --tz), in local mean solar time there ("LMT")."""
    import datetime as dt
    if lon is not None:
        local = t.astimezone(dt.timezone.utc).replace(tzinfo=None) + dt.timedelta(hours=lon / 15)
        text = local.strftime("%Y-%m-%d %H:%M") + " LMT"
    else:
        name = t.tzname() or ""
        text = t.strftime("%Y-%m-%d %H:%M") + (f" {name}" if name else "")
    return text + ("  night" if night else "")


def check_output(path: str, fps: float, size: int) -> str:
    """The encoding of ``path`` (".gif" or ".mp4", from its extension), ``fps`` and ``size``
    checked before any work; ".mp4" needs the ``video`` extra (imageio-ffmpeg and its ffmpeg)."""
    ext = "." + path.rsplit(".", 1)[-1].lower() if "." in path else ""
    if ext not in FORMATS:
        raise UsageProblem(f"{path}: OUTPUT must end in .gif or .mp4 (the animation's format)")
    if not (math.isfinite(fps) and 0 < fps <= MAX_FPS):
        raise UsageProblem(f"--fps must be a number of frames per second in (0, {MAX_FPS:g}], "
                           f"got {fps}")
    if size < 16:
        raise UsageProblem(f"--size must be at least 16 pixels, got {size}")
    if ext == ".mp4":
        ffmpeg_exe()
    return ext


def ffmpeg_exe() -> str:
    """imageio-ffmpeg's ffmpeg, or a one-line error naming the extra."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise HillshadeError("writing .mp4 needs imageio-ffmpeg: pip install "
                             "'hillshade-rt[video]' (or write a .gif)") from None
    try:
        return imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError as exc:
        raise HillshadeError(f"writing .mp4 needs ffmpeg: {str(exc).splitlines()[0]}") from None


def write_gif(path: str, frames: list[np.ndarray], fps: float) -> None:
    """The frames (palette indices) as a looping GIF at ``path``, exactly (one palette, no
    dithering): each shown 1000 / fps ms (GIF keeps hundredths of a second)."""
    from PIL import Image
    pal = PALETTE.reshape(-1).tolist()
    images = []
    for f in frames:
        im = Image.fromarray(f, "P")
        im.putpalette(pal)
        images.append(im)
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:],
                   duration=round(1000.0 / fps), loop=0, optimize=False)


def write_mp4(path: str, frames: list[np.ndarray], fps: float) -> None:
    """The frames as H.264 MP4 (yuv420p, what players take) through imageio-ffmpeg; an odd
    width or height is padded with one white line (yuv420p halves the colour resolution)."""
    import imageio_ffmpeg
    rows, cols = frames[0].shape
    h, w = rows + rows % 2, cols + cols % 2
    gen = imageio_ffmpeg.write_frames(path, (w, h), fps=fps, codec="libx264",
                                      pix_fmt_out="yuv420p", macro_block_size=2, quality=8,
                                      ffmpeg_log_level="error")
    gen.send(None)
    try:
        for f in frames:
            padded = np.full((h, w), VOID, np.uint8)
            padded[:rows, :cols] = f
            gen.send(np.ascontiguousarray(PALETTE[padded]))
    finally:
        gen.close()
