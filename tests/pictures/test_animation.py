"""pictures/animation.py: the frames' palette (grey lit, tinted shadow and night: shadow told
by colour alone), subsampling, relief levels, labels, the output checks and the GIF read back
exactly."""

import datetime as dt
import zoneinfo

import numpy as np
import pytest
from PIL import Image

from hillshade_rt.errors import UsageProblem
from hillshade_rt.model.geometry import Grid
from hillshade_rt.pictures import animation as an


def test_palette_tells_shadow_from_light_by_colour():
    pal = an.PALETTE
    assert pal.shape == (256, 3) and pal.dtype == np.uint8
    lit = pal[an.LIT:an.LIT + an.LEVELS]
    assert (lit[:, 0] == lit[:, 1]).all() and (lit[:, 1] == lit[:, 2]).all()
    assert lit[0, 0] == round(0.25 * 255) and lit[-1, 0] == 255
    assert not an.shadowed_pixels(lit[None]).any()
    assert an.shadowed_pixels(pal[an.SHADOW:an.SHADOW + an.LEVELS][None]).all()
    night = pal[an.NIGHT:an.NIGHT + an.LEVELS].astype(int)
    assert an.shadowed_pixels(night[None, 1:]).all()      # (the darkest may round to black)
    assert (night <= pal[an.SHADOW:an.SHADOW + an.LEVELS]).all()
    assert tuple(pal[an.VOID]) == (255, 255, 255) and an.BOX < 256 and an.TEXT < 256


def test_step_and_subsample():
    assert an.step_of((100, 640), 320) == 2 and an.step_of((100, 641), 320) == 3
    assert an.step_of((10, 10), 320) == 1
    z = np.arange(35, dtype=np.float32).reshape(5, 7)
    grid = Grid(5, 7, np.linspace(10, 14, 5), np.full(5, 20.0), -1, 1, "per row")
    zs, g = an.subsample(z, grid, 3)
    np.testing.assert_array_equal(zs, z[::3, ::3])
    assert (g.rows, g.cols, g.col_sign, g.row_sign) == (2, 3, -1, 1)
    np.testing.assert_allclose(g.dx, [30.0, 39.0])     # rows 0 and 3, three cells a step
    np.testing.assert_allclose(g.dy, 60.0)


def test_relief_levels_of_flat_ground_and_a_slope():
    grid = Grid.uniform(4, 4, 1.0)
    flat = an.relief_levels(np.zeros((4, 4), np.float32), grid, 203.7, 30.0)
    assert (flat == round(0.5 * (an.LEVELS - 1))).all()         # cos i = sin 30 deg
    low = an.relief_levels(np.zeros((4, 4), np.float32), grid, 203.7, 1.0)
    assert (low == round(np.sin(np.radians(5.0)) * (an.LEVELS - 1))).all()  # at least 5 deg
    c = np.mgrid[0:4, 0:4][1]
    away = an.relief_levels((10.0 * c).astype(np.float32), grid, 90.0, 20.0)
    assert (away == 0).all()        # a steep slope facing west, lit from the east: black


def test_frame_indices():
    levels = np.array([[0, 5], [10, 79]], np.uint8)
    shadow = np.array([[0, 1], [255, 1]], np.uint8)
    void = shadow == 255
    out = an.frame_indices(levels, shadow, void)
    np.testing.assert_array_equal(out, [[an.LIT, an.SHADOW + 5], [an.VOID, an.SHADOW + 79]])
    night = an.frame_indices(levels, None, void)
    np.testing.assert_array_equal(night, [[an.NIGHT, an.NIGHT + 5], [an.VOID, an.NIGHT + 79]])


def test_label_text():
    t = dt.datetime(2026, 12, 21, 15, 30, tzinfo=zoneinfo.ZoneInfo("America/Los_Angeles"))
    assert an.label_text(t, False, None) == "2026-12-21 15:30 PST"
    assert an.label_text(t, True, None) == "2026-12-21 15:30 PST  night"
    # local mean solar time at 120 deg W: UTC - 8 h exactly
    assert an.label_text(t, False, -120.0) == "2026-12-21 15:30 LMT"
    assert an.label_text(t, False, -118.25) == "2026-12-21 15:37 LMT"


def test_draw_label_uses_only_box_and_text_colours():
    base = np.full((60, 200), an.LIT + 40, np.uint8)
    out = an.draw_label(base, "2026-12-21 15:30 PST")
    assert out is not base and (base == an.LIT + 40).all()
    changed = out != base
    assert changed.any() and set(np.unique(out[changed])) <= {an.BOX, an.TEXT}
    assert out[0, 0] == an.BOX and (out[-1] == an.LIT + 40).all()
    assert (out == an.TEXT).any()


def test_check_output():
    assert an.check_output("a.GIF", 3.0, 100) == ".gif"
    for path, fps, size, why in [("a.png", 3.0, 100, "must end in .gif or .mp4"),
                                 ("a", 3.0, 100, "must end in .gif or .mp4"),
                                 ("a.gif", 0.0, 100, "--fps must be"),
                                 ("a.gif", 51.0, 100, "--fps must be"),
                                 ("a.gif", float("nan"), 100, "--fps must be"),
                                 ("a.gif", 3.0, 15, "--size must be at least 16")]:
        with pytest.raises(UsageProblem, match=why):
            an.check_output(path, fps, size)


def test_gif_reads_back_exactly(tmp_path):
    rng = np.random.default_rng(0)
    frames = [rng.integers(0, an.VOID + 1, (9, 13)).astype(np.uint8) for _ in range(3)]
    frames[1][:] = an.NIGHT + 3          # one frame of one colour: still its own frame
    path = tmp_path / "a.gif"
    an.write_gif(str(path), frames, 4.0)
    with Image.open(path) as im:
        assert im.n_frames == 3 and im.info["loop"] == 0
        for k, f in enumerate(frames):
            im.seek(k)
            assert im.info["duration"] == 250
            rgb = np.asarray(im.convert("RGB"))
            np.testing.assert_array_equal(rgb, an.PALETTE[f])
