"""Dask runs when the cluster fails (run/dask.py): every worker lost, no worker at all, the
scheduler lost, and each of Dask's failures as one true line. A real scheduler and workers
run as processes of their own (``python -m dask scheduler|worker``) on 127.0.0.1 and are
SIGKILLed mid-run; the run must end within its bound, exit 1 with one line naming the cause,
and leave nothing under the output's name and no parts."""

import contextlib
import json
import os
import signal
import subprocess
import sys
import time

import pytest
from affine import Affine
from rasterio.crs import CRS

from hillshade_rt.errors import HillshadeError
from hillshade_rt.testing import (LUNAR_SOUTH_POLAR_STEREO, fractal_terrain, repo_root,
                                  toy_lunar_subsolar, write_geotiff, write_subsolar_csv)

pytest.importorskip("distributed")

# a 1024 x 1024 DEM in 64 x 64 windows: 256 tasks, some seconds on one worker
SIDE = 1024
WINDOWS = (SIDE // 64) ** 2
START = 60.0          # the longest wait for the scheduler, a worker, the first part
BOUND = 3.0           # --worker-timeout of the runs here


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (repo_root(), env.get("PYTHONPATH")) if p)
    env["HILLSHADE_RT_SERVER"] = "off"       # this process runs it, not a warm server
    return env


def _wait_for(what: str, ready, timeout: float = START, procs=()):
    """Poll ``ready()`` until it is true (its value returned); fail after ``timeout`` s or when
    one of ``procs`` has ended."""
    deadline = time.monotonic() + timeout
    while True:
        got = ready()
        if got:
            return got
        for p in procs:
            if p.poll() is not None:
                pytest.fail(f"{what}: {p.args[1:4]} ended first (status {p.returncode})")
        if time.monotonic() > deadline:
            pytest.fail(f"{what}: not within {timeout} s")
        time.sleep(0.1)


class Cluster:
    """A scheduler and ``workers`` worker processes (each with its nanny), started in process
    groups of their own under ``folder``; ``close()`` SIGKILLs whatever is left of them."""

    def __init__(self, folder):
        self.folder = folder
        self.procs: dict = {}
        self.address = None

    def start(self, workers: int) -> None:
        folder = self.folder
        info = folder / "scheduler.json"
        self._start("scheduler", ["scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--no-dashboard", "--scheduler-file", str(info)])
        self.address = _wait_for("the scheduler's address",
                                 lambda: _address(info), procs=[self.procs["scheduler"]])
        for i in range(workers):
            self._start(f"worker{i}", ["worker", self.address, "--nthreads", "1",
                                       "--no-dashboard", "--host", "127.0.0.1",
                                       "--death-timeout", "30"])
        for i in range(workers):
            log = folder / f"worker{i}.log"
            _wait_for(f"worker {i} registered", lambda: "Registered to" in log.read_text(),
                      procs=[self.procs[f"worker{i}"]])

    def _start(self, name: str, args: list) -> None:
        with open(self.folder / f"{name}.log", "wb") as log:
            self.procs[name] = subprocess.Popen([sys.executable, "-m", "dask", *args],
                                                stdout=log, stderr=subprocess.STDOUT,
                                                env=_env(), start_new_session=True)

    def kill(self, name: str) -> None:
        """SIGKILL the process group of ``name`` (a worker: its nanny and the worker)."""
        p = self.procs[name]
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGKILL)
        p.wait(timeout=30)

    def close(self) -> None:
        for name in list(self.procs):
            self.kill(name)


def _address(info):
    try:
        return json.loads(info.read_text())["address"]
    except (OSError, ValueError, KeyError):
        return None


@contextlib.contextmanager
def cluster(tmp_path, workers: int = 1):
    logs = tmp_path / "logs"
    logs.mkdir()
    c = Cluster(logs)
    try:
        c.start(workers)
        yield c
    finally:
        c.close()


@contextlib.contextmanager
def shadow_run(tmp_path, address: str, *extra, side: int = SIDE):
    """``hillshade-rt shadow`` of a ``side`` x ``side`` DEM in 64-cell windows on ``address``,
    as a process of its own: (the process, the output folder). Killed if still running
    after."""
    dem = tmp_path / "dem.tif"
    write_geotiff(dem, fractal_terrain(side, side, 7, relief=300.0),
                  Affine(5, 0, 400000, 0, -5, 3800000), CRS.from_epsg(32611))
    out = tmp_path / "out"
    out.mkdir(exist_ok=True)
    p = subprocess.Popen([sys.executable, "-m", "hillshade_rt", "shadow", str(dem),
                          str(out / "shadow.tif"), "--azimuth", "200", "--elevation", "20",
                          "--window-size", "64", "--scheduler", address, "-q", *extra],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env(),
                         start_new_session=True)
    try:
        yield p, out
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
        p.communicate(timeout=30)


def _first_part(out, p) -> None:
    """Wait until the run has written a part (it is under way)."""
    def written():
        return any(name.startswith(".shadow.tif.parts.") and os.listdir(out / name)
                   for name in os.listdir(out))
    _wait_for("the first part", written, procs=[p])


def _finished(p, within: float):
    """(exit status, stderr) of ``p``, which must end within ``within`` seconds."""
    try:
        _, err = p.communicate(timeout=within)
    except subprocess.TimeoutExpired:
        pytest.fail(f"the run did not end within {within} s")
    return p.returncode, err


def _done(line: str) -> int:
    """N of "...; N of WINDOWS windows done" (fewer than all: the run was under way)."""
    import re
    m = re.search(rf"; (\d+) of {WINDOWS} windows done$", line)
    assert m, line
    assert int(m.group(1)) < WINDOWS, line
    return int(m.group(1))


def _one_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]


@pytest.mark.slow
def test_every_worker_lost_fails_within_the_bound(tmp_path):
    """The only worker and its nanny SIGKILLed mid-run: the run stops --worker-timeout after,
    one line naming the scheduler and how far it got; no output, no parts."""
    with cluster(tmp_path) as c, shadow_run(tmp_path, c.address,
                                            "--worker-timeout", str(BOUND)) as (p, out):
        _first_part(out, p)
        c.kill("worker0")
        t0 = time.monotonic()
        status, err = _finished(p, BOUND + 30)
        took = time.monotonic() - t0
        line = _one_line(err)
        assert status == 1, err
        assert f"no Dask worker left at {c.address}" in line, line
        assert _done(line) < WINDOWS and "--worker-timeout" in line, line
        assert "internal error" not in line
        assert BOUND <= took < BOUND + 20, took
        assert os.listdir(out) == []        # no output, no parts, no temporary file


@pytest.mark.slow
def test_a_killed_runs_parts_are_removed_by_the_next_run(tmp_path):
    """The run's process SIGKILLed mid-run (no chance to clean up) leaves its parts' folder; the
    next run into that folder removes it (the folder carries the dead process's tag), and
    writes its output."""
    with cluster(tmp_path) as c:
        with shadow_run(tmp_path, c.address) as (p, out):
            _first_part(out, p)
            os.killpg(p.pid, signal.SIGKILL)
            p.wait(timeout=30)
        left = [n for n in os.listdir(out) if n.startswith(".shadow.tif.parts.")]
        assert left, os.listdir(out)
        with shadow_run(tmp_path, c.address) as (q, _):
            status, err = _finished(q, 120)
        assert status == 0, err
        assert os.listdir(out) == ["shadow.tif"], os.listdir(out)


@pytest.mark.slow
def test_workers_killed_and_restarted_by_their_nannies_the_run_goes_on(tmp_path, runner):
    """local:2, both worker processes SIGKILLed mid-run: their nannies (in the run's process)
    start new ones, which take the windows over, rewriting the parts the dead ones had
    written; the run ends well, says nothing, and its output is the one-process run's."""
    import psutil

    from hillshade_rt.cli import cli
    from hillshade_rt.testing import read_band
    with shadow_run(tmp_path, "local:2", "--worker-timeout", "30") as (p, out):
        _first_part(out, p)
        workers = [c for c in psutil.Process(p.pid).children()
                   if "spawn_main" in " ".join(c.cmdline())]
        assert len(workers) == 2
        for w in workers:
            w.send_signal(signal.SIGKILL)
        status, err = _finished(p, START)
        assert (status, err) == (0, ""), err
        assert os.listdir(out) == ["shadow.tif"]
    ref = tmp_path / "ref.tif"
    r = runner.invoke(cli, ["shadow", str(tmp_path / "dem.tif"), str(ref), "--azimuth", "200",
                            "--elevation", "20", "-q"])
    assert r.exit_code == 0, r.output
    assert (read_band(ref) == read_band(out / "shadow.tif")).all()


@pytest.mark.slow
def test_no_worker_at_the_start(tmp_path):
    """A scheduler without any worker: the run fails after --worker-timeout, one line."""
    with cluster(tmp_path, workers=0) as c, shadow_run(tmp_path, c.address,
                                                       "--worker-timeout", "2") as (p, out):
        status, err = _finished(p, START)
        line = _one_line(err)
        assert status == 1, err
        assert f"no Dask worker at {c.address} (none joined in 2 s" in line, line
        assert _done(line) == 0, line
        assert os.listdir(out) == []


@pytest.mark.slow
def test_no_worker_in_the_horizon_skyview_and_illumination_runs(tmp_path, runner):
    """Their windows (and times) as tasks go through the same watch: a scheduler without a
    worker fails each after --worker-timeout, one line, nothing written."""
    from hillshade_rt.cli import cli
    z = fractal_terrain(128, 128, 3, relief=300.0)
    dem = write_geotiff(tmp_path / "dem.tif", z, Affine(5, 0, 400000, 0, -5, 3800000),
                        CRS.from_epsg(32611))
    polar = write_geotiff(tmp_path / "polar.tif", z, Affine(20, 0, -1280, 0, -20, 1280),
                          LUNAR_SOUTH_POLAR_STEREO)
    csv = write_subsolar_csv(tmp_path / "sun.csv",
                             toy_lunar_subsolar(6, 20.0, phase_deg=270.0))
    out = tmp_path / "out"
    out.mkdir()
    with cluster(tmp_path, workers=0) as c:
        dask = ["--window-size", "64", "--scheduler", c.address, "--worker-timeout", "1"]
        for args, what in ((["horizon", dem, str(out / "h.tif"), "--azimuth", "200"], "windows"),
                           (["skyview", dem, str(out / "s.tif"), "--directions", "8"],
                            "windows"),
                           (["illumination", polar, str(out / "i.tif"), "--subsolar-file", csv],
                            "tasks")):
            r = runner.invoke(cli, args + dask + ["-q"])
            assert r.exit_code == 1, (args[0], r.output)
            line = _one_line(r.stderr)
            assert f"no Dask worker at {c.address} (none joined in 1 s" in line, line
            assert f"0 of " in line and f" {what} done" in line, line
            assert os.listdir(out) == [], args[0]


@pytest.mark.slow
def test_a_run_on_an_outside_cluster_says_nothing_else(tmp_path):
    """All well on a scheduler and worker of their own: exit 0, nothing on stderr (the client
    closed quietly), the output and no parts."""
    with cluster(tmp_path) as c, shadow_run(tmp_path, c.address, side=256) as (p, out):
        status, err = _finished(p, START)
        assert (status, err) == (0, ""), err
        assert os.listdir(out) == ["shadow.tif"]


@pytest.mark.slow
def test_scheduler_lost(tmp_path):
    """The scheduler SIGKILLed mid-run: exit 1 at once, one line naming it (not an internal
    error); no output, no parts."""
    with cluster(tmp_path) as c, shadow_run(tmp_path, c.address) as (p, out):
        _first_part(out, p)
        c.kill("scheduler")
        status, err = _finished(p, 30)
        line = _one_line(err)
        assert status == 1, err
        assert f"lost the Dask scheduler at {c.address}" in line, line
        assert _done(line) < WINDOWS, line
        assert os.listdir(out) == []


@pytest.mark.slow
def test_a_scheduler_that_stops_answering_is_lost_within_the_bound(tmp_path):
    """The scheduler stopped (SIGSTOP: its connections stay open, nothing answers): the run
    ends within a few --worker-timeout, one line naming it; no output, no parts."""
    with cluster(tmp_path) as c, shadow_run(tmp_path, c.address,
                                            "--worker-timeout", str(BOUND)) as (p, out):
        _first_part(out, p)
        os.killpg(c.procs["scheduler"].pid, signal.SIGSTOP)
        t0 = time.monotonic()
        status, err = _finished(p, 4 * BOUND + 30)
        took = time.monotonic() - t0
        line = _one_line(err)
        assert status == 1, err
        assert f"lost the Dask scheduler at {c.address} (no answer for" in line, line
        assert _done(line) < WINDOWS, line
        assert took < 4 * BOUND + 10, took
        assert os.listdir(out) == []


# -- each of Dask's failures as the line it makes (run.dask.DaskSession._failure) ---------------

class _Client:
    def __init__(self, status="running"):
        self.status = status


class _Future:
    def __init__(self, status):
        self.status = status

    def cancelled(self):
        return self.status == "cancelled"


def _session(status="running"):
    from hillshade_rt.run.dask import DaskSession
    s = object.__new__(DaskSession)       # no cluster: only what _failure reads
    s.client, s.address = _Client(status), "tcp://127.0.0.1:8786"
    return s


def _line(exc, status="error", client="running"):
    err = _session(client)._failure(_Future(status), exc, 3, 10, "windows")
    return err, str(err)


def test_failures_of_the_cluster_are_one_true_line_each():
    from distributed import KilledWorker
    from distributed.client import FutureCancelledError
    from distributed.comm import CommClosedError

    err, line = _line(FutureCancelledError("k", "scheduler-connection-lost"), "cancelled",
                      "connecting")
    assert isinstance(err, HillshadeError)
    assert line == "lost the Dask scheduler at tcp://127.0.0.1:8786; 3 of 10 windows done"
    err, line = _line(FutureCancelledError("k", "cancelled by another client"), "cancelled")
    assert isinstance(err, HillshadeError) and "cancelled on the scheduler" in line
    assert "(cancelled by another client)" in line and "\n" not in line

    class Worker:
        address = "tcp://127.0.0.1:40001"
    err, line = _line(KilledWorker("shade_piece-1", Worker(), 3))
    assert isinstance(err, HillshadeError) and "\n" not in line
    assert "died 4 times (last tcp://127.0.0.1:40001)" in line and "3 of 10" in line

    err, line = _line(ModuleNotFoundError("No module named 'hillshade_rt'",
                                          name="hillshade_rt"))
    assert isinstance(err, HillshadeError) and "cannot import" in line
    assert "No module named 'hillshade_rt'" in line
    missing = ModuleNotFoundError("No module named 'hillshade_rt.nothere'",
                                  name="hillshade_rt.nothere")
    assert _line(missing)[0] is not missing      # the package is here: the workers lack it
    bug = ModuleNotFoundError("No module named 'no_such_package'", name="no_such_package")
    assert _line(bug)[0] is bug                  # missing here too: a bug
    err, line = _line(MemoryError())
    assert isinstance(err, HillshadeError) and "out of memory" in line

    # fetching a result when the scheduler's connection broke, or a worker's
    err, line = _line(CommClosedError("in <TCP ...>: Stream is closed"), "finished",
                      "connecting")
    assert line.startswith("lost the Dask scheduler at tcp://127.0.0.1:8786")
    err, line = _line(OSError("Timed out trying to connect"), "finished")
    assert isinstance(err, HillshadeError)
    assert "lost the connection to the Dask cluster" in line and "\n" not in line

    # a task's own failure stays what it is: its HillshadeError, or a bug (internal error)
    for exc in (HillshadeError("x.tif: cannot read"), ValueError("a bug"),
                OSError(28, "No space left on device"), TimeoutError("the task's own")):
        assert _line(exc)[0] is exc


def test_a_result_waits_in_bounded_steps_and_a_tasks_timeout_is_its_error(monkeypatch):
    """Fetching a result: each wait of the client's times out after a poll and the cluster is
    looked at again (a result whose worker died is computed again); a TimeoutError the task
    raised itself is its error, not a wait to repeat forever."""
    class Future(_Future):
        def __init__(self, status, outcomes):
            super().__init__(status)
            self.outcomes = list(outcomes)

        def result(self, timeout=None):
            assert timeout is not None          # never an unbounded wait
            got = self.outcomes.pop(0)
            if isinstance(got, BaseException):
                raise got
            return got

    s, looks = _session(), []
    s._check = lambda *args: looks.append(args)
    f = Future("finished", [TimeoutError(), TimeoutError(), {"stats": 1}])
    assert s._result(f, 3, 10, "windows", 0.1) == {"stats": 1}
    assert looks == [(3, 10, "windows")] * 2
    own = TimeoutError("the task's own")
    with pytest.raises(TimeoutError) as got:
        s._result(Future("error", [own]), 3, 10, "windows", 0.1)
    assert got.value is own

    # a connection closed while fetching: tried again (a worker's), named after the retries;
    # the scheduler's (the client no longer running): named at once
    from distributed.comm import CommClosedError
    import hillshade_rt.run.dask as rd
    monkeypatch.setattr(rd, "SETTLE_SECONDS", 0.0)
    closed = CommClosedError("in <TCP (closed) ConnectionPool.gather>: Stream is closed")
    f = Future("finished", [closed, {"stats": 2}])
    assert s._result(f, 3, 10, "windows", 0.1) == {"stats": 2}
    f = Future("finished", [closed] * rd.COMM_RETRIES)
    with pytest.raises(HillshadeError, match="lost the connection to the Dask cluster at "
                                             "tcp://127.0.0.1:8786 .*Stream is closed"):
        s._result(f, 3, 10, "windows", 0.1)
    s.client.status = "connecting"
    with pytest.raises(HillshadeError, match="^lost the Dask scheduler at tcp://127.0.0.1:8786; "
                                             "3 of 10 windows done$"):
        s._result(Future("finished", [closed]), 3, 10, "windows", 0.1)


@pytest.mark.slow
def test_a_task_whose_workers_keep_dying_is_named_when_dask_gives_up(tmp_path):
    """A real KilledWorker (the task kills its worker; allowed-failures 0): one line naming
    it, the parts' folder removed, the caller's client left open."""
    import logging

    import dask
    from distributed import Client, LocalCluster

    from hillshade_rt.run.dask import DaskSession
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
            LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                         dashboard_address=None, silence_logs=logging.CRITICAL) as lc, \
            Client(lc) as client:
        with pytest.raises(HillshadeError) as got:
            with DaskSession(client, str(tmp_path / "out.tif"), 30.0) as s:
                s.futures.append(client.submit(os._exit, 3, pure=False))
                list(s.completed(s.futures))
        line = str(got.value)
        assert line.startswith("Dask gave up on a task: the worker running it died once")
        assert "killed or out of memory" in line and line.endswith("; 0 of 1 windows done")
        assert "\n" not in line
        assert client.status == "running"
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
def test_a_series_on_dask_into_a_cube_equals_the_geotiff(tmp_path, runner):
    """A time series on Dask into OUTPUT.nc: the parts written into the cube window by window,
    the same values as the GeoTIFF the parts make, no part left."""
    import numpy as np
    import rasterio
    xr = pytest.importorskip("xarray")
    from hillshade_rt.cli import cli
    from hillshade_rt.testing import data_path
    dem = data_path("lidar_dem_1m_utm15n_400x400.tif")
    series = ["--time", "2026-06-21T09:20-05:00", "--time", "2026-06-21T16:50-05:00",
              "--window-size", "150", "-q"]
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "s.tif"), *series])
    assert r.exit_code == 0, r.output
    r = runner.invoke(cli, ["shadow", dem, str(tmp_path / "d.nc"), "--scheduler", "local:1",
                            *series])
    assert r.exit_code == 0, r.output
    with rasterio.open(tmp_path / "s.tif") as ds:
        bands = ds.read()
    with xr.open_dataset(tmp_path / "d.nc", mask_and_scale=False) as ds:
        np.testing.assert_array_equal(ds["shadow"].values, bands)
        assert ds["time"].values.astype("datetime64[m]").astype(str).tolist() == [
            "2026-06-21T14:20", "2026-06-21T21:50"]
    assert sorted(os.listdir(tmp_path)) == ["d.nc", "s.tif"]
