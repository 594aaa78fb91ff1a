"""Nothing lost, nothing half-written (issue 16): full disks, signals, links, races, formats.

Each test reproduces one way the old code lost or corrupted data: a full disk reported as success,
--report/--preview writing over the input, SIGTERM leaving temporary files, a symlink replaced
by a file, two runs both "winning" one output, picture formats silently written as GeoTIFF."""

import contextlib
import errno
import json
import os
import signal
import subprocess
import sys
import time
import uuid

import numpy as np
import pytest
import rasterio
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.io import write as writes
from hillshade_rt.cli import cli
from hillshade_rt.errors import HillshadeError
from hillshade_rt.testing import data_path, fractal_terrain, read_band, write_geotiff

LIDAR = data_path("lidar_dem_1m_utm15n_400x400.tif")
SUN = ["--azimuth", "203.7", "--elevation", "12"]
UTM = CRS.from_epsg(32611)
EXE = [sys.executable, "-m", "hillshade_rt"]


def one_line_error(r, code=1):
    assert r.exit_code == code, (r.exit_code, r.output)
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("hillshade-rt: error:"), r.stderr
    return lines[0]


def hidden(folder):
    return [f for f in os.listdir(folder) if f.startswith(".")]


# ---------------------------------------------------------------------------------------------
# 1. full disks

@contextlib.contextmanager
def _tmpfs(path, size="3m"):
    os.makedirs(path, exist_ok=True)
    p = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
                       capture_output=True, text=True)
    if p.returncode != 0:
        yield None
        return
    try:
        yield str(path)
    finally:
        subprocess.run(["umount", "-l", str(path)], capture_output=True)


def _fill(folder, leave=0):
    """Fill the file system of ``folder`` up to ``leave`` bytes."""
    with open(os.path.join(folder, "filler"), "wb", buffering=0) as fh:
        st = os.statvfs(folder)
        with contextlib.suppress(OSError):
            fh.write(b"x" * max(0, st.f_bavail * st.f_frsize - leave))
        with contextlib.suppress(OSError):
            while leave == 0:
                fh.write(b"x" * 4096)


@pytest.fixture
def full_disk(tmp_path):
    """A folder on a 3 MB tmpfs (root can mount one; CI runs as root)."""
    with _tmpfs(tmp_path / "small") as folder:
        if folder is None:
            pytest.skip("cannot mount a tmpfs here (not root): see the simulated ENOSPC tests")
        yield folder


@pytest.mark.parametrize("room", [0.0, 0.5, 0.9])
def test_full_disk_is_an_error_and_leaves_nothing(full_disk, runner, room):
    """No room, or room for part of the mask (GDAL then fails while flushing at close)."""
    z = fractal_terrain(700, 700, 4, relief=800) + np.random.default_rng(1).random((700, 700),
                                                                                   np.float32)
    here = os.path.dirname(full_disk)
    dem = write_geotiff(os.path.join(here, "dem.tif"), z, Affine(10, 0, 400000, 0, -10, 3800000),
                        UTM)
    args = ["--azimuth", "135", "--elevation", "15"]
    assert runner.invoke(cli, ["hillshade", dem, os.path.join(here, "fits.tif")] + args
                         ).exit_code == 0
    size = os.path.getsize(os.path.join(here, "fits.tif"))
    assert size > 100_000
    _fill(full_disk, int(room * size))
    out = os.path.join(full_disk, "out.tif")
    r = runner.invoke(cli, ["hillshade", dem, out] + args)
    line = one_line_error(r)
    assert out in line and "no space left on device" in line
    assert sorted(os.listdir(full_disk)) == ["filler"]


def test_full_disk_series_says_what_is_complete(full_disk, runner):
    z = fractal_terrain(300, 300, 5, relief=600)
    dem = write_geotiff(os.path.join(os.path.dirname(full_disk), "dem.tif"), z,
                        Affine(10, 0, 400000, 0, -10, 3800000), UTM)
    # room for a few masks only
    one = os.path.join(os.path.dirname(full_disk), "one.tif")
    assert runner.invoke(cli, ["shadow", dem, one, "-q"] + SUN).exit_code == 0
    _fill(full_disk, 3 * os.path.getsize(one) + 4096)
    pattern = os.path.join(full_disk, "m_{index:03d}.tif")
    r = runner.invoke(cli, ["shadow", dem, "--output-pattern", pattern,
                            "--report", os.path.join(full_disk, "r.json"),
                            "--start", "2026-06-21T06:00-07:00", "--end", "2026-06-21T18:00-07:00",
                            "--step", "30min", "--lat", "34.2", "--lon", "-118.1"])
    line = one_line_error(r)
    assert "no space left on device" in line
    done = sorted(f for f in os.listdir(full_disk) if f.startswith("m_"))
    assert done and "complete" in line and all(d in line for d in done[:2])
    assert not hidden(full_disk) and "r.json" not in os.listdir(full_disk)
    for f in done:       # every file left is whole
        assert read_band(os.path.join(full_disk, f)).shape == (300, 300)


def test_full_disk_report_and_preview(full_disk, runner, tmp_path):
    _fill(full_disk)
    out = tmp_path / "m.tif"
    for opt, name in (("--report", "r.json"), ("--preview", "p.png")):
        r = runner.invoke(cli, ["shadow", LIDAR, str(out), opt, os.path.join(full_disk, name),
                                "--overwrite"] + SUN)
        line = one_line_error(r)
        assert name in line and "no space left on device" in line and "complete" in line
        assert sorted(os.listdir(full_disk)) == ["filler"]


def test_enospc_simulated_at_sync_and_in_json(tmp_path, monkeypatch, runner):
    """Where no file system can be mounted: the checked close (fsync) and the JSON write fail
    with ENOSPC; the same one line, nothing under the final name."""
    real = writes._fsync

    def full(path):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)
    monkeypatch.setattr(writes, "_fsync", full)
    out = tmp_path / "m.tif"
    line = one_line_error(runner.invoke(cli, ["shadow", LIDAR, str(out)] + SUN))
    assert "no space left on device" in line and os.listdir(tmp_path) == []
    monkeypatch.setattr(writes, "_fsync", real)
    import builtins
    real_open = builtins.open

    def failing_open(path, mode="r", *a, **k):
        fh = real_open(path, mode, *a, **k)
        if "w" in mode and str(path).endswith(".part"):
            def write(_):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            fh.write = write
        return fh
    monkeypatch.setattr(builtins, "open", failing_open)
    line = one_line_error(runner.invoke(cli, ["shadow", LIDAR, str(out), "--report",
                                              str(tmp_path / "r.json")] + SUN))
    assert "r.json" in line and "no space left on device" in line
    assert os.listdir(tmp_path) == ["m.tif"] and "1 output(s) complete" in line


def test_gdal_failure_only_logged_is_an_error():
    """GDAL signals some failures only through its error handler (blocks flushed at close, as
    on the full tmpfs above), which rasterio logs: gdal_checked turns them into one error."""
    import logging
    with pytest.raises(HillshadeError, match=r"x\.tif: cannot write \(TIFFAppendToStrip"):
        with writes.gdal_checked("x.tif"):
            logging.getLogger("rasterio._env").info(
                "GDAL signalled an error: err_no=1, msg='TIFFAppendToStrip:Write error'")
    with writes.gdal_checked("x.tif"):     # a warning is not a failure
        logging.getLogger("rasterio._env").warning("a GDAL warning")


# ---------------------------------------------------------------------------------------------
# 2. no path written is an input or another output

def test_report_or_preview_never_overwrite_the_input_or_the_mask(tmp_path, runner):
    dem = tmp_path / "z.tif"
    dem.write_bytes(open(LIDAR, "rb").read())
    before = dem.read_bytes()
    os.mkdir(tmp_path / "o")
    link = tmp_path / "hard.tif"
    os.link(dem, link)
    sym = tmp_path / "sym.tif"
    sym.symlink_to(dem)
    mask = tmp_path / "o" / "q.tif"
    cases = [
        ["--report", str(dem), "--overwrite"],
        ["--preview", str(dem), "--overwrite"],
        ["--report", str(link), "--overwrite"],
        ["--preview", str(sym), "--overwrite"],
        ["--report", str(mask)],
        ["--report", str(tmp_path / "x.json"), "--preview", str(tmp_path / "x.json")],
    ]
    for extra in cases:
        r = runner.invoke(cli, ["shadow", str(dem), str(mask)] + SUN + extra)
        line = one_line_error(r, 2)
        assert "input" in line or "same file" in line, line
        assert dem.read_bytes() == before
        assert not mask.exists() and not (tmp_path / "x.json").exists()
    # the output itself through a hard link of the input
    r = runner.invoke(cli, ["shadow", str(dem), str(link), "--overwrite"] + SUN)
    assert "is also an input" in one_line_error(r, 2) and dem.read_bytes() == before
    # a pattern naming the input
    r = runner.invoke(cli, ["shadow", str(dem), "--output-pattern", str(tmp_path / "z.tif"),
                            "--overwrite"] + SUN)
    assert "is also an input" in one_line_error(r, 2) and dem.read_bytes() == before


def test_sun_hours_horizon_info_check_their_paths(tmp_path, runner):
    dem = tmp_path / "z.tif"
    dem.write_bytes(open(LIDAR, "rb").read())
    before = dem.read_bytes()
    for args in (["sun-hours", str(dem), str(tmp_path / "h.tif"), "--date", "2026-06-21",
                  "--report", str(dem), "--overwrite"],
                 ["horizon", str(dem), str(tmp_path / "h.tif"), "--azimuth", "163",
                  "--preview", str(tmp_path / "h.tif")],
                 ["info", str(dem), "--preview", str(dem), "--overwrite"]):
        one_line_error(runner.invoke(cli, args), 2)
        assert dem.read_bytes() == before and not (tmp_path / "h.tif").exists()


# ---------------------------------------------------------------------------------------------
# 3, 4, 5. signals

def _slow_dem(tmp_path):
    z = fractal_terrain(900, 900, 7, relief=1500)
    return write_geotiff(tmp_path / "big.tif", z, Affine(10, 0, 400000, 0, -10, 3800000), UTM)


def _series(dem, folder):
    return EXE + ["shadow", dem, "--output-pattern", os.path.join(folder, "s_{index:03d}.tif"),
                  "--algorithm", "brute", "--start", "2026-06-21T06:00-07:00",
                  "--end", "2026-06-21T19:00-07:00", "--step", "10min", "-q", "--threads", "1"]


def _wait_for(folder, pred, timeout=120):
    t0 = time.time()
    while time.time() - t0 < timeout:
        names = os.listdir(folder)
        if pred(names):
            return names
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting in {folder}: {os.listdir(folder)}")


@pytest.mark.slow
@pytest.mark.parametrize("sig,code", [(signal.SIGTERM, 143), (signal.SIGINT, 130),
                                      (signal.SIGHUP, 129)])
def test_signal_removes_unfinished_and_says_what_is_complete(tmp_path, sig, code):
    dem = _slow_dem(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    p = subprocess.Popen(_series(dem, str(out)), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    try:
        _wait_for(out, lambda ns: any(n.startswith("s_") for n in ns))
        p.send_signal(sig)
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == code, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "interrupted" in lines[0] and "Traceback" not in err, err
    assert signal.Signals(sig).name in lines[0]
    done = sorted(os.listdir(out))
    assert done and not hidden(out), done
    assert "complete" in lines[0] and done[0] in lines[0]
    for f in done:
        assert read_band(out / f).shape == (900, 900)


def test_sigterm_of_a_single_output_leaves_nothing(tmp_path):
    dem = _slow_dem(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    p = subprocess.Popen(EXE + ["shadow", dem, str(out / "m.tif"), "--algorithm", "brute",
                                "--time", "2026-06-21T07:00-07:00", "--time",
                                "2026-06-21T07:10-07:00", "--time", "2026-06-21T07:20-07:00",
                                "--threads", "1", "-q"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(out, lambda ns: any(".part" in n for n in ns))   # writing has begun
        p.terminate()
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            p.kill()
    assert p.returncode == 143, err
    assert err.strip().count("\n") == 0 and "Traceback" not in err
    # stopped while computing (the usual case) or, on a loaded machine, after the rename:
    # what it says is what is there
    if "no output written" in err:
        assert os.listdir(out) == []
    else:
        assert os.listdir(out) == ["m.tif"] and "m.tif" in err and read_band(out / "m.tif").shape



def test_interrupt_surfacing_as_systemerror_is_still_an_interrupt(tmp_path, runner, monkeypatch):
    """A signal handler's exception raised while numba's dispatcher runs comes out as
    SystemError ('returned a result with an exception set'): still exit 130, one line."""
    from hillshade_rt.engine import shader

    def render(*a, **k):
        try:
            writes.on_signal(signal.SIGINT, None)
        except KeyboardInterrupt as exc:
            raise SystemError("CPUDispatcher(<function _pieces_table>) returned a result with "
                              "an exception set") from exc
    monkeypatch.setattr(shader, "render", render)
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.tif")] + SUN)
    assert r.exit_code == 130 and r.stderr.strip().count("\n") == 0
    assert "interrupted (SIGINT)" in r.stderr and os.listdir(tmp_path) == []


def test_internal_errors_are_one_line(tmp_path, runner, monkeypatch):
    from hillshade_rt.engine import shader

    def render(*a, **k):
        raise ZeroDivisionError("boom")
    monkeypatch.setattr(shader, "render", render)
    line = one_line_error(runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.tif")] + SUN))
    assert "internal error" in line and "ZeroDivisionError" in line
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------------------------------------
# 6. links and special files

def test_symlinked_output_is_written_through_to_its_target(tmp_path, runner):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    target = elsewhere / "real.tif"
    target.write_bytes(b"old")
    link = tmp_path / "link.tif"
    link.symlink_to(target)
    r = runner.invoke(cli, ["shadow", LIDAR, str(link), "--overwrite", "-q"] + SUN)
    assert r.exit_code == 0, r.output
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert read_band(target).shape == (400, 400)
    assert os.listdir(elsewhere) == ["real.tif"] and sorted(os.listdir(tmp_path)) == [
        "elsewhere", "link.tif"]
    # a dangling link: its target is created
    dangling = tmp_path / "d.tif"
    dangling.symlink_to(elsewhere / "new.tif")
    assert runner.invoke(cli, ["shadow", LIDAR, str(dangling), "-q"] + SUN).exit_code == 0
    assert dangling.is_symlink() and read_band(elsewhere / "new.tif").shape == (400, 400)


def test_devices_and_pipes_are_refused(tmp_path, runner):
    fifo = tmp_path / "pipe.tif"
    os.mkfifo(fifo)
    for path in ("/dev/stdout", "/dev/null", str(fifo)):
        r = runner.invoke(cli, ["shadow", LIDAR, path, "--overwrite"] + SUN)
        line = one_line_error(r)
        assert "not a regular file" in line or "device" in line
    assert os.path.islink("/dev/stdout") or not os.path.isfile("/dev/stdout")
    r = runner.invoke(cli, ["shadow", LIDAR, "-"] + SUN)
    assert "standard output" in one_line_error(r, 2) and not os.path.exists("-")


# ---------------------------------------------------------------------------------------------
# 7. races

def test_publish_never_replaces_a_file_that_appeared(tmp_path):
    final = tmp_path / "m.tif"
    with pytest.raises(HillshadeError, match="appeared while this run was writing"):
        with writes.atomic_path(str(final)) as tmp:
            open(tmp, "w").write("mine")
            final.write_text("theirs")        # another run got there first
    assert final.read_text() == "theirs" and os.listdir(tmp_path) == ["m.tif"]
    with writes.atomic_path(str(final), overwrite=True) as tmp:
        open(tmp, "w").write("mine")
    assert final.read_text() == "mine" and os.listdir(tmp_path) == ["m.tif"]


def test_publish_without_hard_links_still_does_not_clobber(tmp_path, monkeypatch):
    def no_links(*a):
        raise OSError(errno.EPERM, "links not supported")
    monkeypatch.setattr(os, "link", no_links)
    final = tmp_path / "m.tif"
    with writes.atomic_path(str(final)) as tmp:
        open(tmp, "w").write("first")
    assert final.read_text() == "first"
    with pytest.raises(HillshadeError, match="appeared"):
        with writes.atomic_path(str(final)) as tmp:
            open(tmp, "w").write("second")
    assert final.read_text() == "first" and os.listdir(tmp_path) == ["m.tif"]


def test_output_appearing_during_the_run_is_kept(tmp_path, runner, monkeypatch):
    from hillshade_rt.engine import shader
    out = tmp_path / "m.tif"
    real = shader.render

    def render(*a, **k):
        out.write_bytes(b"another run's result")
        return real(*a, **k)
    monkeypatch.setattr(shader, "render", render)
    line = one_line_error(runner.invoke(cli, ["shadow", LIDAR, str(out)] + SUN))
    assert "appeared" in line and out.read_bytes() == b"another run's result"
    assert os.listdir(tmp_path) == ["m.tif"]


def test_two_concurrent_runs_on_one_output_exactly_one_wins(tmp_path):
    dem = _slow_dem(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    cmd = EXE + ["shadow", dem, str(out / "m.tif"), "--azimuth", "163", "--elevation", "4",
                 "--algorithm", "brute", "--threads", "1", "-q"]
    ps = [subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
          for _ in range(2)]
    res = [(p.wait(timeout=300), p.stderr.read()) for p in ps]
    codes = sorted(c for c, _ in res)
    assert codes == [0, 1], res
    err = next(e for c, e in res if c == 1)
    assert "appeared" in err or "already exists" in err
    assert os.listdir(out) == ["m.tif"] and read_band(out / "m.tif").shape == (900, 900)


# ---------------------------------------------------------------------------------------------
# 10. formats by extension, -f/--format

def test_png_output_is_png_with_the_mask_values(tmp_path, runner):
    ref, png = tmp_path / "m.tif", tmp_path / "m.png"
    assert runner.invoke(cli, ["shadow", LIDAR, str(ref), "-q"] + SUN).exit_code == 0
    r = runner.invoke(cli, ["shadow", LIDAR, str(png), "-q"] + SUN)
    assert r.exit_code == 0, r.output
    with rasterio.open(png) as ds:
        assert ds.driver == "PNG" and ds.dtypes[0] == "uint8"
        assert np.array_equal(ds.read(1), read_band(ref))
        assert ds.crs == CRS.from_epsg(26915)          # kept in the .aux.xml side-car
    assert sorted(os.listdir(tmp_path)) == ["m.png", "m.png.aux.xml", "m.tif"]


def test_soft_shadows_in_png_are_16_bit(tmp_path, runner):
    ref, png = tmp_path / "s.tif", tmp_path / "s.png"
    args = ["shadow", LIDAR, "--soft", "-q"] + SUN
    assert runner.invoke(cli, args[:2] + [str(ref)] + args[2:]).exit_code == 0
    assert runner.invoke(cli, args[:2] + [str(png)] + args[2:]).exit_code == 0
    f = read_band(ref)
    with rasterio.open(png) as ds:
        assert ds.driver == "PNG" and ds.dtypes[0] == "uint16"
        v = ds.read(1)
    valid = f != -9999
    assert np.all(v[~valid] == 0) and np.all(v[valid] >= 1)
    assert np.abs((v[valid] - 1) / 65534.0 - f[valid]).max() <= 0.5 / 65534 + 1e-7


def test_formats_that_cannot_hold_the_product_are_refused(tmp_path, runner):
    cases = [(["shadow", LIDAR, str(tmp_path / "m.jpg")] + SUN, "lossy"),
             (["horizon", LIDAR, str(tmp_path / "h.png"), "--azimuth", "163"], "float32"),
             (["shadow", LIDAR, str(tmp_path / "s.png"), "--time", "2026-06-21T10:00Z",
               "--time", "2026-06-21T11:00Z"], "one band"),
             (["shadow", LIDAR, str(tmp_path / "m.vrt")] + SUN, "VRT"),
             (["shadow", LIDAR, str(tmp_path / "m.png"), "--cog"] + SUN, "GeoTIFF"),
             (["shadow", LIDAR, str(tmp_path / "m.tif"), "-f", "NoSuchDriver"] + SUN, "driver")]
    for args, text in cases:
        line = one_line_error(runner.invoke(cli, args), 1)
        assert text in line, line
    assert os.listdir(tmp_path) == []


def test_format_option_and_other_drivers(tmp_path, runner):
    # hillshade as JPEG (lossy is fine for a picture), a mask as AAIGrid by extension, and -f
    r = runner.invoke(cli, ["hillshade", LIDAR, str(tmp_path / "h.jpg"), "-q"])
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.asc"), "-q"] + SUN)
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, ["shadow", LIDAR, str(tmp_path / "m.dat"), "-f", "png", "-q"] + SUN)
    assert r.exit_code == 0, r.output
    drivers = {}
    for name in ("h.jpg", "m.asc", "m.dat"):
        with rasterio.open(tmp_path / name) as ds:
            drivers[name] = ds.driver
    assert drivers == {"h.jpg": "JPEG", "m.asc": "AAIGrid", "m.dat": "PNG"}
    assert np.array_equal(read_band(tmp_path / "m.asc"), read_band(tmp_path / "m.dat"))
    assert not hidden(tmp_path)


def test_pattern_outputs_by_extension(tmp_path, runner):
    r = runner.invoke(cli, ["shadow", LIDAR, "--output-pattern", str(tmp_path / "m_{index}.png"),
                            "--time", "2026-06-21T17:00Z", "--time", "2026-06-21T18:00Z", "-q"])
    assert r.exit_code == 0, r.output
    for i in (0, 1):
        with rasterio.open(tmp_path / f"m_{i}.png") as ds:
            assert ds.driver == "PNG"


def test_vsimem_output_from_the_api():
    import hillshade_rt as hr
    path = f"/vsimem/{uuid.uuid4().hex}/m.tif"
    rep = hr.shade(LIDAR, path, azimuth=203.7, elevation=12)
    with rasterio.open(path) as ds:
        m = ds.read(1)
    assert m.shape == (400, 400) and rep["shadow_fraction"] == pytest.approx(
        (m == 1).sum() / (m != 255).sum())
    from hillshade_rt.run.config import inputs_and_output  # noqa: F401
    from click.testing import CliRunner
    r = CliRunner().invoke(cli, ["shadow", LIDAR, "/vsimem/x.tif"] + SUN)
    assert r.exit_code == 1 and "local files" in r.stderr


def test_report_is_valid_json_and_written_last(tmp_path, runner):
    out, rep = tmp_path / "m.tif", tmp_path / "r.json"
    assert runner.invoke(cli, ["shadow", LIDAR, str(out), "--report", str(rep), "-q"]
                         + SUN).exit_code == 0
    assert json.loads(rep.read_text())["output"] == str(out)
    assert sorted(os.listdir(tmp_path)) == ["m.tif", "r.json"]


def test_formats_of_mosaic_tiles_and_their_limits(tmp_path, runner):
    """One PNG per input tile (the mosaic cut through GDAL); soft shadows, whose 16-bit PNG
    encoding needs the writer, are refused there before any work."""
    z = fractal_terrain(128, 128, 3, relief=300)
    a = write_geotiff(tmp_path / "a.tif", z[:, :64], Affine(5, 0, 400000, 0, -5, 3800000), UTM)
    b = write_geotiff(tmp_path / "b.tif", z[:, 64:], Affine(5, 0, 400320, 0, -5, 3800000), UTM)
    out = tmp_path / "out"
    out.mkdir()
    r = runner.invoke(cli, ["shadow", a, b, "--output-pattern", str(out / "{tile}_m.png"),
                            "-q"] + SUN)
    assert r.exit_code == 0, r.output
    for t in ("a", "b"):
        with rasterio.open(out / f"{t}_m.png") as ds:
            assert ds.driver == "PNG" and ds.shape == (128, 64)
    r = runner.invoke(cli, ["shadow", a, b, "--output-pattern", str(out / "{tile}_s.png"),
                            "--soft"] + SUN)
    assert "float32" in one_line_error(r)
    assert not any("_s" in f for f in os.listdir(out)) and not hidden(out)


def test_dev_stdout_and_the_like_are_refused(runner):
    for path in ("/dev/stderr", "/proc/self/fd/1", "/dev/fd/2"):
        assert "device or system" in one_line_error(runner.invoke(cli, ["shadow", LIDAR, path,
                                                                        "--overwrite"] + SUN))


def test_dev_shm_is_a_place_to_write(runner):
    if not os.path.isdir("/dev/shm") or not os.access("/dev/shm", os.W_OK):
        pytest.skip("no writable /dev/shm on this machine")
    out = f"/dev/shm/hillshade-rt-test-{uuid.uuid4().hex}.tif"
    try:
        assert runner.invoke(cli, ["shadow", LIDAR, out, "-q"] + SUN).exit_code == 0
        assert read_band(out).shape == (400, 400)
    finally:
        with contextlib.suppress(OSError):
            os.remove(out)


def test_gdal_errors_of_another_thread_are_not_ours():
    """A GDAL error logged by another thread while our block runs does not fail our write; the
    same message logged by this thread does (so the first half is not passing by accident)."""
    import logging
    import threading
    log = logging.getLogger("rasterio._env")
    msg = "GDAL signalled an error: err_no=1, msg='theirs'"
    logged = []
    with writes.gdal_checked("mine.tif"):
        t = threading.Thread(target=lambda: (log.info(msg), logged.append(True)))
        t.start()
        t.join()
    assert logged == [True]                  # the other thread did log while the block ran
    with pytest.raises(HillshadeError) as exc:
        with writes.gdal_checked("mine.tif"):
            log.info(msg)
    assert "mine.tif" in str(exc.value) and "theirs" in str(exc.value)


@pytest.mark.slow      # six runs of the program, each interrupted after its first file
def test_interrupts_at_random_moments_of_a_per_tile_series_are_always_one_line(tmp_path):
    """The issue's case: Ctrl-C during --start/--end/--step runs on a UTM DEM with per-tile suns
    printed a SystemError traceback in 4 of 9 runs. Here 6 runs, each signalled at a random
    moment after its first file is written (in numba's dispatch, a kernel, a write, a rename)."""
    import random
    z = fractal_terrain(500, 500, 9, relief=2500)
    dem = write_geotiff(tmp_path / "wide.tif", z, Affine(200, 0, 300000, 0, -200, 3900000), UTM)
    rng = random.Random(16)
    for k in range(6):
        out = tmp_path / f"out{k}"
        out.mkdir()
        sig = (signal.SIGINT, signal.SIGTERM)[k % 2]
        cmd = EXE + ["shadow", dem, "--output-pattern", str(out / "t_{index:03d}.tif"),
                     "--start", "2026-06-21T05:30-07:00", "--end", "2026-06-21T20:00-07:00",
                     "--step", "15min", "--sun-tolerance", "0.01", "-q"]
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            _wait_for(out, lambda ns: any(n.startswith("t_") for n in ns))
            time.sleep(rng.uniform(0.0, 0.8))
            p.send_signal(sig)
            _, err = p.communicate(timeout=120)
        finally:
            if p.poll() is None:
                p.kill()
        if p.returncode == 0:      # finished before the signal: nothing to judge
            continue
        assert p.returncode == 128 + sig, (k, p.returncode, err)
        lines = err.strip().splitlines()
        assert len(lines) == 1 and "interrupted" in lines[0], (k, err)
        assert not hidden(out)
        done = sorted(os.listdir(out))
        assert all(d in lines[0] for d in done[:2]) and f"{len(done)} output(s)" in lines[0]


@pytest.mark.parametrize("where", ["open", "tags"])
def test_interrupt_while_the_writer_opens_publishes_nothing(tmp_path, monkeypatch, where):
    """A signal while BandWriter opens its dataset (found by SIGTERM on a cold numba cache: an
    empty m.tif was published as complete): the temporary file goes, nothing under the name."""
    import rasterio
    from hillshade_rt import io as hio
    from hillshade_rt.errors import Interrupted
    d = hio.read_dem(LIDAR)
    real_open = rasterio.open

    def interrupted_open(*a, **k):
        if where == "open":
            raise Interrupted(signal.SIGTERM)
        ds = real_open(*a, **k)
        ds.update_tags = lambda *a, **k: (_ for _ in ()).throw(Interrupted(signal.SIGTERM))
        return ds
    monkeypatch.setattr(rasterio, "open", interrupted_open)
    writes.reset()
    with pytest.raises(Interrupted):
        hio.write_raster(str(tmp_path / "m.tif"), np.zeros(d.shape, np.uint8), d, 255,
                         tags={"A": 1})
    assert os.listdir(tmp_path) == [] and writes.completed == []


def test_signal_held_back_while_stderr_is_redirected_restores_stderr(monkeypatch):
    """A signal deferred while gdal_checked redirects stderr stops the run as the redirection
    ends; stderr must be the process's again before the interrupt propagates, or the run's
    one-line message goes into the pipe (found in issue 18: exit 130 with stderr empty)."""
    from hillshade_rt.io import write as writes
    from hillshade_rt.errors import Interrupted
    before = os.readlink("/proc/self/fd/2") if os.path.exists("/proc/self/fd/2") else None
    real = writes._StderrCapture._start

    def start_then_signal(self):
        out = real(self)
        writes._deferral["pending"] = 2      # as on_signal does inside signals_deferred
        return out
    monkeypatch.setattr(writes._StderrCapture, "_start", start_then_signal)
    writes.reset()
    try:
        with pytest.raises(Interrupted):
            with writes._StderrCapture():
                pytest.fail("the block must not run")
        if before is not None:
            assert os.readlink("/proc/self/fd/2") == before
    finally:
        writes.reset()


# ---------------------------------------------------------------------------------------------
# the temporaries of runs killed with SIGKILL (or a power loss)

_KILLED_WRITER = """
import sys, time
from hillshade_rt.io.write import atomic_path
with atomic_path(sys.argv[1], ".tif") as tmp:
    with open(tmp, "wb") as fh:
        fh.write(b"half a raster")
    print(tmp, flush=True)
    time.sleep(300)
"""


def _writer(out):
    """A process that has begun writing ``out`` (its temporary exists) and waits."""
    import hillshade_rt
    # this checkout's package (a worktree's, where the venv's editable install points elsewhere)
    env = dict(os.environ, PYTHONPATH=os.path.dirname(os.path.dirname(hillshade_rt.__file__)))
    p = subprocess.Popen([sys.executable, "-c", _KILLED_WRITER, str(out)], env=env,
                         stdout=subprocess.PIPE, text=True)
    return p, p.stdout.readline().strip()


def test_temporaries_of_dead_runs_are_removed_by_the_next_run(tmp_path, runner):
    out = tmp_path / "out"
    out.mkdir()
    killed, dead_tmp = _writer(out / "a.tif")
    live, live_tmp = _writer(out / "b.tif")
    try:
        assert os.path.basename(dead_tmp).startswith(".a.tif.") and ".part.tif" in dead_tmp
        killed.kill()                                   # SIGKILL: no clean-up of its own
        killed.wait(30)
        assert os.path.exists(dead_tmp)
        # a .part of this very process, one of another host, one whose pid was reused
        tag = writes.owner_tag()
        pid, rest = tag.split("-", 1)
        start = rest.split("-", 1)[0]
        mine = out / f".c.tif.abcdefgh~{tag}.part.tif"
        other_host = out / f".d.tif.abcdefgh~{killed.pid}-{rest.split('@')[0]}@elsewhere.part.tif"
        reused = out / (f".e.tif.abcdefgh~{pid}-{int(start) + 1}-"
                        f"{rest.split('-', 1)[1]}.part.tif")
        untagged = out / ".f.tif.abcdefgh.part.tif"     # written by an older version
        for f in (mine, other_host, reused, untagged):
            f.write_bytes(b"x")
        dem = write_geotiff(tmp_path / "dem.tif", fractal_terrain(64, 64, 3, relief=200),
                            Affine(10, 0, 400000, 0, -10, 3800000), UTM)
        r = runner.invoke(cli, ["shadow", dem, str(out / "m.tif"), "-q"] + SUN)
        assert r.exit_code == 0, r.output
        left = sorted(os.listdir(out))
        assert os.path.basename(dead_tmp) not in left              # its writer is dead
        assert not reused.exists()                                 # pid alive, another start
        for kept in (live_tmp, mine, other_host, untagged):        # not provably dead
            assert os.path.exists(kept), left
        assert "m.tif" in left
    finally:
        for p in (killed, live):
            if p.poll() is None:
                p.kill()
            p.wait(30)


def test_temporary_names_say_their_writer(tmp_path):
    tmp = writes.temp_beside(str(tmp_path / "x.tif"), ".part.tif")
    name = os.path.basename(tmp)
    assert name.startswith(".x.tif.") and name.endswith(".part.tif")
    assert f"~{os.getpid()}-" in name and "@" in name
    assert not writes.writer_dead(name)
    long = writes.temp_beside(str(tmp_path / ("y" * 250)), ".part.tif")
    assert len(os.path.basename(long)) <= 255 and os.path.basename(long).startswith(".yyy")


def test_scratch_folders_say_their_writer_and_dead_ones_are_swept(tmp_path):
    """``scratch_folder``: a hidden folder beside the output named after it, its kind and
    this process (not dead); the sweep removes a scratch folder of a dead process (files in
    it), keeps one of this process and a plain folder with a dead tag but no scratch ending."""
    import subprocess
    import sys
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait(30)
    rest = writes.owner_tag().split("-", 1)[1]
    dead = tmp_path / f".x.tif.grids.abcdefgh~{child.pid}-{rest}.scratch.dir"
    other = tmp_path / f".x.tif.other.abcdefgh~{child.pid}-{rest}.scratch"   # not ours to rm
    for d in (dead, other):
        d.mkdir()
        (d / "a.npy").write_bytes(b"x")
    writes.reset()
    mine = writes.scratch_folder(str(tmp_path / "x.tif"), "grids")
    name = os.path.basename(mine)
    assert os.path.isdir(mine) and os.path.dirname(mine) == str(tmp_path)
    assert name.startswith(".x.tif.grids.") and name.endswith(".scratch.dir")
    assert f"~{os.getpid()}-" in name and not writes.writer_dead(name)
    assert writes.writer_dead(dead.name)
    assert not dead.exists() and other.exists()
    writes.reset()
    assert writes.sweep_dead(str(tmp_path)) == []       # its own: kept
    assert os.path.isdir(mine)
