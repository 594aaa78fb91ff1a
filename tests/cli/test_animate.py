"""hillshade-rt animate: frame k's shadows are the shadow command's mask of time k (every n-th
cell), read back from the GIF itself; labels; MP4; errors as one line with nothing written."""

import json
import sys

import numpy as np
import pytest
from PIL import Image

from hillshade_rt.pictures.animation import shadowed_pixels
from hillshade_rt.cli import cli
from hillshade_rt.testing import data_path, read_band

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")      # 400 x 400, UTM 15N
# a winter morning to the afternoon, every 2 h 10 min (non-round azimuths), from before sunrise
SERIES = ["--start", "2026-01-15T06:30", "--end", "2026-01-15T15:30", "--step", "2h10min",
          "--tz", "America/Chicago"]


def gif_frames(path):
    with Image.open(path) as im:
        out = []
        for k in range(im.n_frames):
            im.seek(k)
            out.append(np.asarray(im.convert("RGB")))
        return out, im.info


def animate(runner, tmp_path, name, *args):
    out, rep = tmp_path / name, tmp_path / (name + ".json")
    r = runner.invoke(cli, ["animate", LIDAR, str(out), *args, "--report", str(rep)])
    assert r.exit_code == 0, r.output
    return out, json.loads(rep.read_text()), r


def test_frames_are_the_masks_of_their_times(tmp_path, runner):
    out, doc, r = animate(runner, tmp_path, "a.gif", *SERIES, "--size", "100", "--no-label",
                          "--fps", "5")
    times = [t["time"] for t in doc["times"]]
    assert len(times) == 5 and doc["frames"] == 5        # 06:30, 08:40, 10:50, 13:00, 15:10
    frames, info = gif_frames(out)
    assert len(frames) == 5 and info["loop"] == 0 and info["duration"] == 200
    n = doc["every_nth_cell"]
    assert n == 4 and frames[0].shape == (100, 100, 3) and doc["picture"] == [100, 100]
    assert doc["times"][0]["night"] and doc["night_frames"] == 1
    masks = tmp_path / "m.tif"
    r = runner.invoke(cli, ["shadow", LIDAR, str(masks), "--tz", "America/Chicago", "-q",
                            *[a for t in times for a in ("--time", t)]])
    assert r.exit_code == 0, r.output
    lit_and_shadow = 0
    for k, frame in enumerate(frames):
        mask = read_band(masks, k + 1)[::n, ::n]
        valid = mask != 255
        assert np.array_equal(shadowed_pixels(frame)[valid], mask[valid] == 1), times[k]
        lit_and_shadow += 0 < (mask[valid] == 1).mean() < 1
    assert lit_and_shadow >= 3          # the day's frames have both


def test_labels_change_only_the_top_left_corner(tmp_path, runner):
    args = ["--start", "2026-01-15T08:40", "--end", "2026-01-15T10:50", "--step", "30min",
            "--tz", "America/Chicago",
            "--size", "400"]
    plain, _, _ = animate(runner, tmp_path, "plain.gif", *args, "--no-label")
    labelled, doc, r = animate(runner, tmp_path, "label.gif", *args)
    assert doc["label"] is True and doc["frames"] == 5
    (a, _), (b, _) = gif_frames(plain), gif_frames(labelled)
    for fa, fb in zip(a, b):
        diff = np.any(fa != fb, axis=2)
        rows, cols = np.nonzero(diff)
        assert diff.sum() > 100                                  # text was drawn
        assert rows.max() < fa.shape[0] / 10 and cols.max() < fa.shape[1] / 2
    assert "5 frames" in r.output and "0 at night" in r.output


def test_a_day_has_a_frame_per_step(tmp_path, runner):
    out, doc, _ = animate(runner, tmp_path, "d.gif", "--date", "2026-06-21", "--step", "1h",
                          "--tz", "America/Chicago", "--size", "80", "-q")
    assert doc["frames"] == 24 and doc["times"][0]["time"] == "2026-06-21T00:00:00-05:00"
    assert doc["times"][-1]["time"] == "2026-06-21T23:00:00-05:00"
    assert 0 < doc["night_frames"] < 24
    assert gif_frames(out)[0][0].shape[:2] == (80, 80)
    # the day the clocks spring forward has 23 hours; without labels the night's frames are
    # alike, and the GIF keeps a run of equal frames as one shown as long (Pillow)
    out, doc, _ = animate(runner, tmp_path, "dst.gif", "--date", "2026-03-08", "--step", "1h",
                          "--tz", "America/Chicago", "--size", "32", "-q", "--no-label",
                          "--fps", "4")
    assert doc["frames"] == 23
    with Image.open(out) as im:
        durations = []
        for k in range(im.n_frames):
            im.seek(k)
            durations.append(im.info["duration"])
    assert len(durations) < 23 and sum(durations) == 23 * 250


def test_mp4(tmp_path, runner):
    ffmpeg = pytest.importorskip("imageio_ffmpeg")
    out, doc, _ = animate(runner, tmp_path, "a.mp4", *SERIES, "--size", "70", "-q")
    assert doc["format"] == "mp4" and doc["frames"] == 5
    reader = ffmpeg.read_frames(str(out))
    meta = reader.__next__()
    frames = list(reader)
    assert len(frames) == 5 and tuple(meta["size"]) == (68, 68)   # 67 padded to even
    assert meta["fps"] == pytest.approx(12.0)


def test_mp4_without_the_extra_is_one_line(tmp_path, runner, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)      # import fails
    out = tmp_path / "a.mp4"
    r = runner.invoke(cli, ["animate", LIDAR, str(out), *SERIES])
    assert r.exit_code == 1 and "hillshade-rt[video]" in r.output
    assert len(r.output.strip().splitlines()) == 1 and not out.exists()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("args, words", [
    (["a.png", "--date", "2026-06-21"], ".gif or .mp4"),
    (["a.gif"], "--date, or --start"),
    (["a.gif", "--date", "2026-06-21", *SERIES[:4]], "--date, or --start"),
    (["a.gif", "--start", "2026-06-21T10:00Z"], "go together"),
    (["a.gif", "--date", "2026-13-01"], "not a date"),
    (["a.gif", "--date", "2026-06-21", "--step", "often"], "not a duration"),
    (["a.gif", "--date", "2026-06-21", "--fps", "0"], "--fps"),
    (["a.gif", "--date", "2026-06-21", "--size", "8"], "--size"),
    (["a.gif", "--date", "2026-06-21", "--step", "10s"], "more than 2000"),
    (["a.gif", "--start", "2026-01-15T06:30Z", "--end", "2026-01-17T06:30Z", "--step", "1min"],
     "2881 frames: more than 2000"),
])
def test_usage_errors(tmp_path, runner, args, words):
    r = runner.invoke(cli, ["animate", LIDAR, str(tmp_path / args[0]), *args[1:]])
    assert r.exit_code == 2, r.output
    assert words in r.output and len(r.output.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_existing_output_is_kept(tmp_path, runner):
    out = tmp_path / "a.gif"
    out.write_bytes(b"mine")
    r = runner.invoke(cli, ["animate", LIDAR, str(out), "--date", "2026-06-21"])
    assert r.exit_code == 1 and "already exists" in r.output
    assert out.read_bytes() == b"mine" and len(list(tmp_path.iterdir())) == 1
