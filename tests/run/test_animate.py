"""The animation's frames (hillshade_rt.pictures.animation) and the animate run's times."""

import datetime as dt
from zoneinfo import ZoneInfo

import numpy as np
import pytest
from affine import Affine
from PIL import Image
from rasterio.crs import CRS

import hillshade_rt as hr
from hillshade_rt.pictures.animation import (
    LEVELS, PALETTE, draw_label, frame_indices, label_text, shadowed_pixels, step_of, write_gif
)
from hillshade_rt.errors import UsageProblem
from hillshade_rt.run.config import AnimateConfig
from hillshade_rt.run.animate import animate, day_times
from hillshade_rt.testing import fractal_terrain, write_geotiff


def test_the_palette_tells_shadow_from_light():
    """Lit levels grey, shadowed and night levels not (the colour says which), all distinct."""
    lit = PALETTE[:LEVELS]
    dark = PALETTE[LEVELS:3 * LEVELS]
    assert not shadowed_pixels(lit).any() and shadowed_pixels(dark).all()
    assert len({tuple(c) for c in PALETTE[:2 * LEVELS]}) == 2 * LEVELS     # night: darker, fewer
    assert not shadowed_pixels(PALETTE[3 * LEVELS:3 * LEVELS + 3]).any()   # void, label


def test_frame_indices_keep_the_mask():
    rng = np.random.default_rng(7)
    levels = rng.integers(0, LEVELS, (37, 53)).astype(np.uint8)
    mask = rng.integers(0, 2, (37, 53)).astype(np.uint8)
    void = rng.random((37, 53)) < 0.1
    mask[void] = 255
    rgb = PALETTE[frame_indices(levels, mask, void)]
    assert np.array_equal(shadowed_pixels(rgb), mask == 1)
    assert (rgb[void] == 255).all()
    night = PALETTE[frame_indices(levels, None, void)]
    assert shadowed_pixels(night)[~void].all()
    assert night[~void].mean() < rgb[~void & (mask == 1)].mean()        # darker than shadow


def test_the_gif_holds_the_frames_exactly(tmp_path):
    rng = np.random.default_rng(3)
    frames = [rng.integers(0, 3 * LEVELS + 3, (21, 30)).astype(np.uint8) for _ in range(4)]
    write_gif(tmp_path / "a.gif", frames, 10.0)
    with Image.open(tmp_path / "a.gif") as im:
        assert im.n_frames == 4 and im.size == (30, 21)
        for k, f in enumerate(frames):
            im.seek(k)
            assert np.array_equal(np.asarray(im.convert("RGB")), PALETTE[f])


def test_labels():
    idx = np.zeros((90, 300), np.uint8)
    out = draw_label(idx, "2026-06-21 14:30 CEST")
    assert set(np.unique(out)) <= {0, 3 * LEVELS + 1, 3 * LEVELS + 2}
    assert (out == 3 * LEVELS + 2).sum() > 50           # text
    assert not out[45:].any()                           # the box stays at the top
    t = dt.datetime(2026, 6, 21, 12, 0, tzinfo=dt.timezone.utc)
    assert label_text(t.astimezone(ZoneInfo("Europe/Zurich")), False, None) == \
        "2026-06-21 14:00 CEST"
    assert label_text(t, True, -90.0) == "2026-06-21 06:00 LMT  night"    # 6 h west of UTC


def test_day_times():
    la = ZoneInfo("America/Los_Angeles")
    ts = day_times(dt.date(2026, 11, 1), "1h", la, 0.0)        # clocks go back: 25 hours
    assert len(ts) == 25 and ts[0].isoformat() == "2026-11-01T00:00:00-07:00"
    ts = day_times(dt.date(2026, 6, 21), "45min", None, 45.0)   # local mean solar time, 3 h east
    assert len(ts) == 32 and ts[0] == dt.datetime(2026, 6, 20, 21, 0, tzinfo=dt.timezone.utc)
    assert step_of((643, 1197), 480) == 3 and step_of((10, 10), 1024) == 1


def test_voids_are_white_and_the_run_checks_first(tmp_path):
    z = fractal_terrain(60, 90, seed=5, relief=400.0).astype(np.float32)
    z[20:30, 40:55] = -9999.0
    dem = write_geotiff(tmp_path / "z.tif", z, Affine(30.0, 0, 400000.0, 0, -30.0, 5200000.0),
                        CRS.from_epsg(32632), nodata=-9999.0)
    out = str(tmp_path / "a.gif")
    rep = animate(AnimateConfig(dem=dem, output=out, start="2026-09-01T07:30",
                                end="2026-09-01T17:30", step="163min",
                                place={"tz": "Europe/Rome"}, size=90,
                                label=False))
    assert rep["frames"] == 4 and rep["night_frames"] == 0 and rep["every_nth_cell"] == 1
    with Image.open(out) as im:
        im.seek(2)
        rgb = np.asarray(im.convert("RGB"))
    assert (rgb[20:30, 40:55] == 255).all() and (rgb[:20] != 255).any()
    with pytest.raises(UsageProblem, match="one way"):
        animate(AnimateConfig(dem=dem, output=str(tmp_path / "b.gif"), date="2026-09-01",
                              start="2026-09-01T07:30", end="2026-09-01T08:30"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "z.tif"]


def test_the_api(tmp_path):
    z = fractal_terrain(50, 40, seed=2, relief=300.0).astype(np.float32)
    dem = write_geotiff(tmp_path / "z.tif", z, Affine(25.0, 0, 500000.0, 0, -25.0, 4100000.0),
                        CRS.from_epsg(32611))
    first = dt.datetime(2026, 6, 21, 16, tzinfo=dt.timezone.utc)
    rep = hr.animate(dem, tmp_path / "a.gif", start=first, end="2026-06-21T20:00Z", step="1h",
                     size=25, tz="America/Los_Angeles")
    assert rep["frames"] == 5 and rep["every_nth_cell"] == 2 and rep["picture"] == [25, 20]
    with Image.open(tmp_path / "a.gif") as im:
        assert im.n_frames == 5 and im.size == (20, 25)
    with pytest.raises(TypeError, match="colour"):
        hr.animate(dem, tmp_path / "b.gif", date="2026-06-21", colour="red")


def test_without_tz_the_day_and_labels_are_in_the_dem_zone(tmp_path):
    """No --tz: the day runs from midnight to midnight in the zone of the DEM's centre (UTM 32N
    at 47 N, 8.5 E: Europe/Zurich), the labels in it (CEST in July), the report says so;
    a series' local times are read there too."""
    z = fractal_terrain(40, 40, seed=4, relief=300.0).astype(np.float32)
    dem = write_geotiff(tmp_path / "z.tif", z, Affine(30.0, 0, 465000.0, 0, -30.0, 5248000.0),
                        CRS.from_epsg(32632))
    rep = animate(AnimateConfig(dem=dem, output=str(tmp_path / "a.gif"), date="2026-07-15",
                                step="6h", size=40))
    assert rep["label_time"] == "Europe/Zurich (the DEM's zone)"
    assert [t["time"] for t in rep["times"]] == [f"2026-07-15T{h:02d}:00:00+02:00"
                                                 for h in (0, 6, 12, 18)]
    rep = animate(AnimateConfig(dem=dem, output=str(tmp_path / "b.gif"),
                                start="2026-01-15T10:00", end="2026-01-15T12:00", step="1h",
                                size=40))
    assert rep["times"][0]["time"] == "2026-01-15T10:00:00+01:00" and rep["frames"] == 3
    assert label_text(dt.datetime(2026, 7, 15, 10, tzinfo=ZoneInfo("Europe/Zurich")), False,
                      None) == "2026-07-15 10:00 CEST"
