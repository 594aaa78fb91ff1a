"""run/statscache.py: the context's block statistics kept between runs: where, the key (files,
sizes, times, read options), atomic store and checked load, hits, the survey and prune."""

import os
import time

import numpy as np
import pytest
from affine import Affine

from hillshade_rt.errors import AllNodata
from hillshade_rt.io.source import open_dem
from hillshade_rt.run import statscache
from hillshade_rt.testing import fractal_terrain, write_geotiff

TR = Affine(30.0, 0, 400000.0, 0, -30.0, 3800000.0)


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "stats"
    monkeypatch.setenv("HILLSHADE_RT_STATS_DIR", str(folder))
    return folder


def _dem(tmp_path, z=None, name="d.tif"):
    z = fractal_terrain(40, 50, seed=2, relief=90.0) + 10.0 if z is None else z
    path = write_geotiff(tmp_path / name, z.astype(np.float32), TR, "EPSG:32611", -9999.0)
    return open_dem(path, windows=True), z


def test_stats_root(monkeypatch, tmp_path):
    for off in ("off", "", "0", "None"):
        monkeypatch.setenv("HILLSHADE_RT_STATS_DIR", off)
        assert statscache.stats_root() is None
    monkeypatch.delenv("HILLSHADE_RT_STATS_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert statscache.stats_root() == os.path.join(str(tmp_path), "hillshade-rt", "stats")


def test_block_ranges_stored_then_hit(cache, tmp_path):
    """16 x 16 blocks of a 40 x 50 DEM: 3 x 4 ranges, each the block's own min and max."""
    src, z = _dem(tmp_path)
    bs, rep = statscache.cached_block_stats(src, 16)
    assert rep["cache"] == "stored" and rep["bytes_read"] == 40 * 50 * 4
    assert os.path.dirname(rep["file"]) == str(cache)
    assert bs.lo.shape == (3, 4) and bs.valid == 40 * 50
    for i in range(3):
        for j in range(4):
            block = z[16 * i:16 * i + 16, 16 * j:16 * j + 16]
            assert bs.lo[i, j] == pytest.approx(block.min())
            assert bs.hi[i, j] == pytest.approx(block.max())
    again, rep2 = statscache.cached_block_stats(src, 16)
    assert rep2 == {"cache": "hit", "bytes_read": 0, "file": rep["file"]}
    np.testing.assert_array_equal(again.lo, bs.lo)
    np.testing.assert_array_equal(again.hi, bs.hi)
    # another block size is another entry
    assert statscache.cached_block_stats(src, 32)[1]["cache"] == "stored"
    assert len(os.listdir(cache)) == 2


def test_key_follows_the_files_time_and_read_options(cache, tmp_path):
    src, _ = _dem(tmp_path)
    key = statscache.key_of(src, 16)
    assert key["files"][0][0] == str(tmp_path / "d.tif") and key["block"] == 16
    st = os.stat(tmp_path / "d.tif")
    os.utime(tmp_path / "d.tif", ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    assert statscache.digest(statscache.key_of(src, 16)) != statscache.digest(key)
    assert statscache.digest(dict(key)) == statscache.digest(key)


def test_load_refuses_another_key_or_shape(tmp_path):
    key = {"version": 1, "a": 1}
    lo = np.zeros((2, 3), np.float32)
    path = str(tmp_path / "e.npz")
    assert statscache.store(str(tmp_path), path, key, lo, lo + 1, 5)
    got = statscache.load(path, key, (2, 3))
    assert got is not None and got[2] == 5
    assert statscache.load(path, {"version": 1, "a": 2}, (2, 3)) is None
    assert statscache.load(path, key, (3, 2)) is None
    assert statscache.load(str(tmp_path / "absent.npz"), key, (2, 3)) is None
    assert [n for n in os.listdir(tmp_path) if n.startswith(".tmp-")] == []


def test_store_into_an_unwritable_place_is_false(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert not statscache.store(str(blocker / "sub"), str(blocker / "sub" / "e.npz"), {},
                                np.zeros((1, 1)), np.zeros((1, 1)), 1)


def test_off_and_all_nodata(monkeypatch, cache, tmp_path):
    monkeypatch.setenv("HILLSHADE_RT_STATS_DIR", "off")
    src, _ = _dem(tmp_path)
    assert statscache.cached_block_stats(src, 16)[1]["cache"] == "off"
    monkeypatch.setenv("HILLSHADE_RT_STATS_DIR", str(cache))
    # an entry that says every cell is nodata: the run stops as for such a DEM
    key = statscache.key_of(src, 16)
    path = os.path.join(str(cache), statscache.digest(key) + statscache.SUFFIX)
    inf = np.full((3, 4), np.inf, np.float32)
    assert statscache.store(str(cache), path, key, inf, -inf, 0)
    with pytest.raises(AllNodata, match="every cell is nodata"):
        statscache.cached_block_stats(src, 16)


def test_survey_finds_stale_entries_and_prunes_them(cache, tmp_path):
    src, _ = _dem(tmp_path)
    statscache.cached_block_stats(src, 16)
    found = statscache.survey()
    assert found["root"] == str(cache) and found["entries"] == 1 and found["stale"] == []
    old_tmp = cache / ".tmp-x.npz"
    old_tmp.write_bytes(b"partial")
    hour_ago = time.time() - 7200
    os.utime(old_tmp, (hour_ago, hour_ago))
    (cache / "junk.npz").write_bytes(b"not an npz")
    stale = {os.path.basename(p) for p, _ in statscache.survey()["stale"]}
    assert stale == {".tmp-x.npz", "junk.npz"}
    os.unlink(tmp_path / "d.tif")          # the entry's file gone: stale too
    found = statscache.survey(prune=True)
    assert len(found["stale"]) == 3 and os.listdir(cache) == []
