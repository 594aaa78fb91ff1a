"""The warm server (``hillshade-rt serve``, ``cli/client.py``, ``cli/server.py``,
``cli/worker.py``): a command through it gives what it gives in-process (files, stdout, stderr,
exit status), several at once; signals cancel a job; any server that cannot be trusted or
reached means the command runs in-process, silently; the idle timeout; ``HILLSHADE_RT_SERVER``.

Every server here lives in a temporary XDG_RUNTIME_DIR (short, under /tmp: a socket's path is
at most 107 bytes) and is stopped, its processes checked gone, before the test ends. (Each
module alone, without a server: test_client.py, test_server.py, test_worker.py.)
"""

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np
import pytest
from rasterio.transform import Affine

from hillshade_rt.cli import client
from hillshade_rt.testing import fractal_terrain, read_band, repo_root, write_geotiff

EXE = os.path.join(os.path.dirname(sys.executable), "hillshade-rt")
EXAMPLE = os.path.join(repo_root(), "examples", "bigtujunga_srtm30m_utm11n_1197x643.tif")
SUN = ["--azimuth", "203.7", "--elevation", "12"]


def hrt(args, env, cwd=None, timeout=300):
    return subprocess.run([EXE, *map(str, args)], env=env, cwd=cwd, capture_output=True,
                          text=True, timeout=timeout)


def untimed(text: str) -> str:
    """A run's messages without its timings (they differ from run to run)."""
    return re.sub(r"\d+(\.\d+)? (s|Mpix/s)\b", "T", text)


def status(env) -> dict | None:
    return client.request(client.paths(env)["socket"], {"type": "status"})


def jobs(env, expect: int | None = None) -> int:
    """Jobs the server has served. A worker reports a job to its master just after the job's
    status goes to the caller, so the count is read once it has settled: with ``expect``, once
    it has counted that many; without, once no worker is busy (each at most 10 s)."""
    deadline = time.monotonic() + 10
    while True:
        st = status(env)
        n = st["jobs"]
        settled = n >= expect if expect is not None else st["workers"]["busy"] == 0
        if settled or time.monotonic() > deadline:
            return n
        time.sleep(0.02)


def gone(pids, timeout=15.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        alive = []
        for pid in pids:
            try:
                os.kill(pid, 0)
            except ProcessLookupError:
                continue
            # a zombie of ours counts as gone (its parent reaps it)
            try:
                with open(f"/proc/{pid}/stat") as fh:
                    if fh.read().split(") ")[-1].startswith("Z"):
                        continue
            except OSError:
                continue
            alive.append(pid)
        if not alive:
            return True
        time.sleep(0.05)
    return False


def make_env(rundir, **extra) -> dict:
    env = dict(os.environ, XDG_RUNTIME_DIR=rundir)
    env.pop("HILLSHADE_RT_SERVER", None)
    env.update(extra)
    return env


@pytest.fixture
def rundir():
    d = tempfile.mkdtemp(prefix="hrt", dir="/tmp")
    yield d
    shutil.rmtree(d, ignore_errors=True)


class Server:
    """A server started in a temporary runtime folder; ``stop`` stops it and checks that its
    master and workers are gone (killing what is left, then failing)."""

    def __init__(self, rundir, *options):
        self.env = make_env(rundir)
        r = hrt(["serve", "start", *options], self.env, timeout=600)
        assert r.returncode == 0, r.stderr
        st = status(self.env)
        assert st is not None
        self.pids = {st["pid"], *st["worker_pids"]}

    def all_pids(self):
        st = status(self.env)
        if st is not None:
            self.pids |= {st["pid"], *st["worker_pids"]}
        return self.pids

    def stop(self):
        pids = self.all_pids()
        r = hrt(["serve", "stop"], self.env, timeout=60)
        ok = gone(pids)
        with open(client.paths(self.env)["log"]) as fh:
            self.log = fh.read()
        if not ok:
            for pid in pids:
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
        assert r.returncode == 0 and ok, (r.stdout, r.stderr)
        assert "Traceback" not in self.log, self.log
        if r.stdout.startswith("stopped"):          # (not stopped already: idle)
            assert "stopping: asked to stop" in self.log
        assert re.search(r"stopped after \d+ job\(s\)", self.log), self.log


@pytest.fixture(scope="module")
def served():
    d = tempfile.mkdtemp(prefix="hrt", dir="/tmp")
    srv = Server(d, "--idle-timeout", "1200", "--workers", "2", "--queue-wait", "60")
    try:
        yield srv
    finally:
        try:
            srv.stop()
        finally:
            shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module")
def dem():
    d = tempfile.mkdtemp(prefix="hrt-dem")
    z = fractal_terrain(160, 200, seed=7, relief=900.0)
    path = write_geotiff(os.path.join(d, "dem.tif"), z, transform=Affine(30, 0, 380000, 0, -30, 3800000),
                         crs="EPSG:32611")
    yield path
    shutil.rmtree(d, ignore_errors=True)


def in_process(args, env, cwd=None):
    return hrt(args, dict(env, HILLSHADE_RT_SERVER="off"), cwd=cwd)


def same_run(a, b):
    assert (a.returncode, a.stdout, untimed(a.stderr)) == (b.returncode, b.stdout,
                                                           untimed(b.stderr))


# ------------------------------------------------------------------------------------------
# through the server: the same as in-process

@pytest.mark.slow
def test_a_shadow_run_through_the_server_is_the_in_process_run(served, dem, tmp_path):
    env = served.env
    here = in_process(["shadow", dem, tmp_path / "here.tif", *SUN], env)
    before = jobs(env)
    there = hrt(["shadow", dem, tmp_path / "there.tif", *SUN], env)
    assert jobs(env, before + 1) == before + 1                       # the server ran it
    assert here.returncode == 0, here.stderr
    assert (here.returncode, here.stdout, untimed(here.stderr)) == (
        there.returncode, there.stdout, untimed(there.stderr).replace("there.tif", "here.tif"))
    assert np.array_equal(read_band(tmp_path / "here.tif"), read_band(tmp_path / "there.tif"))
    assert (tmp_path / "here.tif").read_bytes() == (tmp_path / "there.tif").read_bytes()
    assert sorted(os.listdir(tmp_path)) == ["here.tif", "there.tif"]


@pytest.mark.slow
def test_failing_and_malformed_command_lines(served, dem, tmp_path):
    env = served.env
    before = jobs(env)
    for args, code in ((["shadow", tmp_path / "missing.tif", tmp_path / "o.tif", *SUN], 1),
                       (["shadow", dem, tmp_path / "o.tif", "--azimuth", "abc"], 2),
                       (["shadwo", dem], 2),
                       (["hillshade", dem, tmp_path / "h.tif", *SUN, "--overwrite"], 0)):
        here = in_process(args, env)
        there = hrt(args, env)
        assert there.returncode == code, there.stderr
        same_run(here, there)
        if code:
            assert len(there.stderr.splitlines()) == 1 and "Traceback" not in there.stderr
    assert jobs(env, before + 4) == before + 4
    assert not (tmp_path / "o.tif").exists()


def test_relative_paths_and_the_environment_are_the_callers(served, dem, tmp_path):
    env = served.env
    shutil.copy(dem, tmp_path / "dem.tif")
    (tmp_path / "sub").mkdir()
    before = jobs(env)
    r = hrt(["shadow", "dem.tif", "sub/out.tif", *SUN, "-q"], env, cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert np.array_equal(read_band(tmp_path / "sub" / "out.tif"),
                          read_band(in_process_out(dem, tmp_path, env)))
    # click wraps --help to $COLUMNS: the job's environment is the caller's
    narrow = hrt(["shadow", "--help"], dict(env, COLUMNS="50"))
    wide = hrt(["shadow", "--help"], dict(env, COLUMNS="150"))
    assert narrow.stdout != wide.stdout
    assert narrow.stdout == in_process(["shadow", "--help"], dict(env, COLUMNS="50")).stdout
    assert wide.stdout == in_process(["shadow", "--help"], dict(env, COLUMNS="150")).stdout
    assert len(narrow.stdout.splitlines()) > len(wide.stdout.splitlines())
    assert jobs(env, before + 3) == before + 3


def in_process_out(dem, tmp_path, env):
    out = tmp_path / "reference.tif"
    r = in_process(["shadow", dem, out, *SUN, "-q"], env)
    assert r.returncode == 0, r.stderr
    return out


def test_several_clients_at_once(served, dem, tmp_path):
    env = served.env
    ref = in_process_out(dem, tmp_path, env)
    before = jobs(env)
    procs = [subprocess.Popen([EXE, "shadow", dem, str(tmp_path / f"c{i}.tif"), *SUN],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for i in range(4)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0] * 4, outs
    for i, (out, err) in enumerate(outs):
        assert f"c{i}.tif: 200x160" in err
        assert np.array_equal(read_band(tmp_path / f"c{i}.tif"), read_band(ref))
    assert jobs(env, before + 4) == before + 4


def test_the_client_imports_no_numpy_click_numba_or_rasterio(served, dem, tmp_path):
    code = ("import sys\n"
            "from hillshade_rt.cli.client import hand_over\n"
            f"code = hand_over({['shadow', dem, str(tmp_path / 'o.tif'), *SUN, '-q']!r})\n"
            "heavy = sorted({m.split('.')[0] for m in sys.modules} & "
            "{'numpy', 'click', 'numba', 'rasterio'})\n"
            "print(code, heavy)\n")
    r = subprocess.run([sys.executable, "-c", code], env=served.env, capture_output=True,
                       text=True, timeout=120)
    assert r.stdout.strip() == "0 []", (r.stdout, r.stderr)
    assert (tmp_path / "o.tif").exists()


# ------------------------------------------------------------------------------------------
# signals and a lost worker

def long_job(out):
    """~10 s or more on two cores: 29 suns over the example DEM, the plain brute march."""
    return ["shadow", EXAMPLE, out, "--start", "2026-06-21T05:00-07:00",
            "--end", "2026-06-21T19:00-07:00", "--step", "30min", "--algorithm", "brute",
            "--no-pyramid"]


def start_and_wait_for_part(args, env, folder):
    """The client of a long job, once the job has begun writing (its hidden temporary file)."""
    p = subprocess.Popen([EXE, *map(str, args)], env=env, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not os.listdir(folder):
        assert p.poll() is None and time.monotonic() < deadline, p.communicate()
        time.sleep(0.05)
    return p


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_to_the_client_cancels_its_job(served, tmp_path, sig):
    env = served.env
    folder = tmp_path / "out"
    folder.mkdir()
    before = jobs(env)
    p = start_and_wait_for_part(long_job(folder / "m.tif"), env, folder)
    p.send_signal(sig)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 128 + sig, err
    # (the leading newline ends a progress line: in-process too)
    assert err.lstrip("\n") == (f"hillshade-rt: interrupted ({signal.Signals(sig).name}); "
                                "no output written\n")
    assert os.listdir(folder) == []                 # no output, no temporary file
    # the server serves the next job (its interrupted worker replaced)
    r = hrt(["shadow", EXAMPLE, folder / "next.tif", *SUN, "-q"], env)
    assert r.returncode == 0, r.stderr
    assert jobs(env, before + 2) == before + 2
    assert os.listdir(folder) == ["next.tif"]


def test_a_worker_lost_during_a_job_is_one_line_and_status_1(served, tmp_path):
    env = served.env
    folder = tmp_path / "out"
    folder.mkdir()
    p = start_and_wait_for_part(long_job(folder / "m.tif"), env, folder)
    st = status(env)
    busy = [pid for pid in st["worker_pids"] if _job_of(pid)]
    assert len(busy) == 1, st
    os.kill(busy[0], signal.SIGKILL)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 1
    assert err.startswith(f"hillshade-rt: error: the server's worker (pid {busy[0]}) ended "
                          "during the run") and err.count("\n") == 1
    assert not (folder / "m.tif").exists()
    for name in os.listdir(folder):       # the killed worker could not remove its part
        os.unlink(folder / name)
    r = hrt(["shadow", EXAMPLE, folder / "next.tif", *SUN, "-q"], env)
    assert r.returncode == 0, r.stderr
    served.all_pids()


def _job_of(pid) -> bool:
    """Whether the worker ``pid`` runs a job (its working folder is not /)."""
    try:
        return os.readlink(f"/proc/{pid}/cwd") != "/"
    except OSError:
        return False


# ------------------------------------------------------------------------------------------
# fallbacks: any server that cannot be trusted or reached means in-process, silently

def fallback_run(env, dem, tmp_path, name):
    here = in_process(["shadow", dem, tmp_path / f"{name}-ref.tif", *SUN, "-q"], env)
    t0 = time.monotonic()
    there = hrt(["shadow", dem, tmp_path / f"{name}.tif", *SUN, "-q"], env)
    took = time.monotonic() - t0
    assert there.returncode == 0 and there.stdout == "" and there.stderr == "", there.stderr
    same_run(here, there)
    assert np.array_equal(read_band(tmp_path / f"{name}.tif"),
                          read_band(tmp_path / f"{name}-ref.tif"))
    return took


@pytest.mark.slow
def test_an_unsafe_folder_or_socket_is_not_used(served, dem, tmp_path):
    env = served.env
    where = client.paths(env)
    before = jobs(env)
    try:                                        # the folder readable by others
        os.chmod(where["folder"], 0o755)
        fallback_run(env, dem, tmp_path, "mode")
    finally:
        os.chmod(where["folder"], 0o700)
    other = tempfile.mkdtemp(prefix="hrt", dir="/tmp")
    try:                                        # the folder a symbolic link to the real one
        os.symlink(where["folder"], os.path.join(other, "hillshade-rt"))
        fallback_run(make_env(other), dem, tmp_path, "link")
    finally:
        shutil.rmtree(other)
    try:                                        # the socket readable by others
        os.chmod(where["socket"], 0o666)
        fallback_run(env, dem, tmp_path, "sockmode")
    finally:
        os.chmod(where["socket"], 0o600)
    if os.getuid() == 0:                        # the socket owned by another user
        try:
            os.lchown(where["socket"], 65534, 65534)
            fallback_run(env, dem, tmp_path, "owner")
        finally:
            os.lchown(where["socket"], 0, 0)
    assert jobs(env) == before                  # none of those went to the server
    r = hrt(["shadow", dem, tmp_path / "ok.tif", *SUN, "-q"], env)
    assert r.returncode == 0 and jobs(env, before + 1) == before + 1


@pytest.mark.slow
def test_a_stale_socket_or_a_missing_folder_means_in_process(rundir, dem, tmp_path):
    env = make_env(rundir)
    fallback_run(env, dem, tmp_path, "nofolder")        # no folder at all
    assert not os.path.exists(os.path.join(rundir, "hillshade-rt"))   # and none made
    where = client.paths(env)
    os.mkdir(where["folder"], 0o700)
    s = socket.socket(socket.AF_UNIX)
    s.bind(where["socket"])                      # bound, never listening: refused
    s.close()
    os.chmod(where["socket"], 0o600)
    fallback_run(env, dem, tmp_path, "stale")


@pytest.mark.parametrize("behaviour", ["refuses", "closes",
                                       pytest.param("wedged", marks=pytest.mark.slow),
                                       pytest.param("garbage", marks=pytest.mark.slow)])
def test_a_server_of_another_kind_means_in_process(rundir, dem, tmp_path, behaviour):
    """A server at the socket that answers 'refused' (another version), closes the
    connection, never answers, or answers nonsense: the command runs in-process, silently,
    within a bounded wait."""
    env = make_env(rundir)
    where = client.paths(env)
    os.mkdir(where["folder"], 0o700)
    lst = socket.socket(socket.AF_UNIX)
    lst.bind(where["socket"])
    os.chmod(where["socket"], 0o600)
    lst.listen(8)
    lst.settimeout(0.2)
    done = threading.Event()
    held = []

    def fake():
        while not done.is_set():
            try:
                conn, _ = lst.accept()
            except OSError:
                continue
            if behaviour == "refuses":
                client.send_frame(conn, {"type": "refused", "why": "another version"})
                conn.close()
            elif behaviour == "closes":
                conn.close()
            elif behaviour == "wedged":
                held.append(conn)
            else:
                conn.sendall(b"\x00\x00\x00\x05hello")
                conn.close()

    t = threading.Thread(target=fake, daemon=True)
    t.start()
    try:
        took = fallback_run(env, dem, tmp_path, behaviour)
        assert took < client.REPLY_TIMEOUT + 60
    finally:
        done.set()
        t.join(5)
        lst.close()
        for c in held:
            c.close()


# ------------------------------------------------------------------------------------------
# the server's life: idle timeout, HILLSHADE_RT_SERVER

@pytest.mark.slow
def test_the_idle_timeout_stops_the_server(rundir):
    srv = Server(rundir, "--idle-timeout", "2", "--workers", "1")
    try:
        assert status(srv.env)["idle_timeout"] == 2
        deadline = time.monotonic() + 60
        while status(srv.env) is not None and time.monotonic() < deadline:
            time.sleep(0.2)
        assert status(srv.env) is None
        assert gone(srv.pids)
        assert not os.path.exists(client.paths(srv.env)["socket"])
        with open(client.paths(srv.env)["log"]) as fh:
            log = fh.read()
        assert "stopping: idle for 2 s" in log and "stopped after 0 job(s)" in log, log
    finally:
        srv.stop()


def test_off_never_uses_the_server(served, dem, tmp_path):
    before = jobs(served.env)
    r = hrt(["shadow", dem, tmp_path / "o.tif", *SUN, "-q"],
            dict(served.env, HILLSHADE_RT_SERVER="off"))
    assert r.returncode == 0 and jobs(served.env) == before


@pytest.mark.slow
def test_auto_starts_a_server_in_the_background(rundir, dem, tmp_path):
    env = make_env(rundir, HILLSHADE_RT_SERVER="auto", HILLSHADE_RT_SERVER_IDLE="120")
    pids = set()
    try:
        fallback_run(env, dem, tmp_path, "first")        # runs here, starts the server
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline:
            st = status(env)
            if st is not None:
                pids |= {st["pid"], *st["worker_pids"]}
                if st["workers"]["idle"]:
                    break
            time.sleep(0.2)
        assert st is not None and st["workers"]["idle"] and st["idle_timeout"] == 120
        r = hrt(["shadow", dem, tmp_path / "second.tif", *SUN, "-q"], env)
        assert r.returncode == 0 and r.stderr == ""
        assert jobs(env, 1) == 1
        assert np.array_equal(read_band(tmp_path / "second.tif"),
                              read_band(tmp_path / "first.tif"))
        s = hrt(["serve", "status"], env)
        assert s.returncode == 0 and f"socket: {client.paths(env)['socket']}" in s.stdout
        assert "jobs served: 1" in s.stdout
    finally:
        st = status(env)
        if st is not None:
            pids |= {st["pid"], *st["worker_pids"]}
        hrt(["serve", "stop"], env, timeout=60)
        ok = gone(pids)
        for pid in pids if not ok else ():
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        assert ok
    r = hrt(["serve", "status"], env)
    assert r.returncode == 3 and "no hillshade-rt server running" in r.stdout
