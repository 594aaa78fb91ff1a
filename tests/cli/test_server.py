"""cli/server.py, the server's master, in this process with no worker started: what it answers
each request (status, stop, a job of another key or protocol, a job while stopping), how a job
waits for an idle worker and goes to it with the caller's connection, what the workers' messages
do, the idle timeout, the replacement of workers and when it gives up, the socket it binds and
removes, and ``main``'s refusals. (A real server with workers: tests/cli/test_serve.py.)"""

import fcntl
import json
import os
import shutil
import socket
import tempfile
import time
import types

import pytest

from hillshade_rt.cli import client, server


@pytest.fixture
def where():
    d = tempfile.mkdtemp(prefix="hrt", dir="/tmp")          # a socket's path: short
    yield {"folder": d, "key": "k" * 24, "socket": os.path.join(d, "k.sock"),
           "lock": os.path.join(d, "k.lock"), "log": os.path.join(d, "k.log")}
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture
def master(where, monkeypatch):
    monkeypatch.setattr(server, "log", lambda message: None)
    m = server.Master(where, idle_timeout=60.0, workers=2, queue_wait=5.0, environ={})
    yield m
    m.unbind()


class FakeWorker:
    """A worker as the master sees one (its channel, its process), no process behind it; the
    other end of its channel is ``peer``."""

    def __init__(self, master, state="idle", code=0):
        self.channel, self.peer = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        self.proc = types.SimpleNamespace(pid=4242, wait=lambda timeout=None: code,
                                          kill=lambda: None)
        self.state, self.jobs, self.since = state, 0, time.monotonic()
        master.workers.append(self)
        master.sel.register(self.channel, 1, ("worker", self))


def ask(master, req, wait=2.0):
    """``req`` sent to ``master.handle`` over a fresh connection: (its answer, the caller's
    end)."""
    caller, conn = socket.socketpair()
    client.send_frame(caller, req)
    master.handle(conn)
    try:
        answer = client.Frames(caller).read(wait)
    except TimeoutError:
        answer = "no answer"
    return answer, caller


def test_status_counts_the_workers_and_stop_stops(master, where):
    FakeWorker(master, "idle")
    FakeWorker(master, "busy")
    st, _ = ask(master, {"proto": client.PROTOCOL, "type": "status"})
    assert st["type"] == "status" and st["pid"] == os.getpid()
    assert st["workers"] == {"idle": 1, "busy": 1, "starting": 0, "ending": 0}
    assert (st["socket"], st["idle_timeout"], st["size"], st["jobs"]) == (
        where["socket"], 60.0, 2, 0)
    assert st["worker_pids"] == [4242, 4242] and master.seen      # a caller saw one ready
    answer, _ = ask(master, {"proto": client.PROTOCOL, "type": "stop"})
    assert answer["type"] == "stopping" and master.stopping == "asked to stop"
    answer, _ = ask(master, {"proto": client.PROTOCOL, "type": "job", "key": where["key"]})
    assert answer == {"type": "busy"}                             # stopping: run it yourself


def test_a_request_of_another_protocol_or_key_is_refused(master, where):
    answer, _ = ask(master, {"proto": client.PROTOCOL + 1, "type": "status"})
    assert answer == {"type": "refused", "why": "protocol"}
    answer, _ = ask(master, {"proto": client.PROTOCOL, "type": "job", "key": "another"})
    assert answer == {"type": "refused", "why": "another version or setting"}
    answer, _ = ask(master, {"proto": client.PROTOCOL, "type": "status"})
    assert answer["type"] == "status" and not master.seen         # no worker ready yet
    answer, _ = ask(master, [1, 2])                               # not a request: closed
    assert answer is None and master.pending == [] and master.stopping is None


def test_a_job_goes_to_an_idle_worker_with_the_callers_connection(master, where):
    """A job waits (no worker idle) until one is ready; then the worker receives the request
    with the caller's connection (the caller's descriptors go to the worker itself, with its
    "go"), and is busy."""
    job = {"proto": client.PROTOCOL, "type": "job", "key": where["key"], "argv": ["info"]}
    answer, caller = ask(master, job, wait=0.1)
    assert answer == "no answer" and len(master.pending) == 1
    worker = FakeWorker(master, "starting")
    worker.peer.send(b"ready")
    master.from_worker(worker)
    assert worker.state == "busy" and master.pending == []
    msg, fds, _, _ = socket.recv_fds(worker.peer, 1 << 16, 4)
    assert json.loads(msg[4:]) == job and len(fds) == 1
    conn = socket.socket(fileno=fds[0])
    conn.sendall(b"to the caller")
    assert caller.recv(64) == b"to the caller"
    conn.close()


def test_a_job_no_worker_takes_in_time_is_answered_busy(master, where):
    master.queue_wait = 0.0
    answer, _ = ask(master, {"proto": client.PROTOCOL, "type": "job", "key": where["key"]})
    assert answer == {"type": "busy"} and master.pending == []


def test_what_the_workers_say(master):
    worker = FakeWorker(master, "busy")
    master.failures = 2
    for said, state, jobs in ((b"done 0 1", "idle", 1), (b"skipped 0 1", "idle", 1),
                              (b"done 1 0", "ending", 2), (b"ready", "idle", 2)):
        worker.peer.send(said)
        master.from_worker(worker)
        assert (worker.state, worker.jobs, master.jobs) == (state, jobs, jobs), said
    assert master.failures == 0                                   # a worker got ready


def test_a_worker_that_ends_is_replaced_until_three_fail_to_start(master, monkeypatch):
    spawned = []
    monkeypatch.setattr(master, "spawn", lambda: spawned.append(1))
    w = FakeWorker(master, "idle")
    w.peer.close()
    master.from_worker(w)                                         # its channel ended
    assert master.workers == [] and spawned == [1] and master.failures == 0
    for n in range(server.STARTUP_FAILURES):
        w = FakeWorker(master, "starting", code=1)
        master.ended(w)
    assert master.failures == server.STARTUP_FAILURES
    assert len(spawned) == server.STARTUP_FAILURES                # the third is not replaced
    assert master.stopping == "workers fail to start"


def test_idle_waits_for_jobs_busy_workers_and_the_grace(master):
    now = time.monotonic()
    master.idle_timeout = 2.0
    master.last = now - 3.0
    assert not master.idle()                  # no caller has seen a worker: SEEN_GRACE at least
    master.last = now - server.SEEN_GRACE - 1
    assert master.idle()
    master.seen, master.last = True, now - 3.0
    assert master.idle()
    worker = FakeWorker(master, "busy")
    assert not master.idle()
    worker.state = "idle"
    master.pending.append((now + 60, None, [], {}))
    assert not master.idle()
    master.pending.clear()
    master.idle_timeout = 0                                       # never
    assert not master.idle()


def test_changed_sources_refuse_jobs_and_stop(master, where, monkeypatch):
    monkeypatch.setattr(server, "_sources_stamp", lambda: ("edited",))
    master.stamp_checked = time.monotonic() - 2.0
    answer, _ = ask(master, {"proto": client.PROTOCOL, "type": "job", "key": where["key"]})
    assert answer == {"type": "refused", "why": "sources changed"}
    assert master.stopping == "the package's sources changed"


def test_sources_stamp_sees_an_edit(tmp_path, monkeypatch):
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "data.txt").write_text("not a source")
    monkeypatch.setattr(client, "package_dir", lambda: str(tmp_path))
    before = server._sources_stamp()
    assert [f for _, f, _, _ in before] == ["a.py"]
    (tmp_path / "data.txt").write_text("still not a source")
    assert server._sources_stamp() == before
    (tmp_path / "a.py").write_text("x = 22\n")
    assert server._sources_stamp() != before


def test_bind_makes_a_private_socket_and_unbind_removes_only_its_own(master, where):
    master.bind()
    st = os.lstat(where["socket"])
    assert oct(st.st_mode & 0o777) == "0o600" and client.socket_problem(where["socket"]) is None
    assert client.request(where["socket"], {"type": "status"}, timeout=0.2) is None  # no loop
    master.unbind()
    assert not os.path.exists(where["socket"])
    master.bind()
    os.unlink(where["socket"])
    with open(where["socket"], "w") as fh:                        # another's file there now
        fh.write("someone else's")
    master.unbind()
    assert os.path.exists(where["socket"])


def test_number_and_default_workers(monkeypatch):
    env = {"A": "2.5", "B": "-1", "C": "x", "N": "3"}
    assert server._number(env, "A", 9.0) == 2.5
    assert server._number(env, "B", 9.0) == 9.0 and server._number(env, "C", 9.0) == 9.0
    assert server._number(env, "missing", 9.0) == 9.0
    assert server._number(env, "N", 1, int) == 3 and server._number(env, "A", 1, int) == 1
    for cpus, want in ((1, 1), (3, 3), (16, 4)):
        monkeypatch.setattr(os, "sched_getaffinity", lambda pid, n=cpus: set(range(n)))
        assert server.default_workers() == want


def test_main_refuses_without_serving(where, monkeypatch, capsys):
    """Another key's settings: status 3; an unsafe folder: 1, said; a master of this key
    running (its lock held): 0. None of them binds the socket."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", where["folder"])
    mine = client.paths(os.environ)
    assert server.main(["--key", "not-" + mine["key"]]) == 3
    os.mkdir(mine["folder"], 0o755)
    os.chmod(mine["folder"], 0o755)
    assert server.main([]) == 1
    assert "mode 755" in capsys.readouterr().err
    os.chmod(mine["folder"], 0o700)
    lock = os.open(mine["lock"], os.O_RDWR | os.O_CREAT, 0o600)
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        assert server.main(["--key", mine["key"]]) == 0
    finally:
        os.close(lock)
    assert not os.path.exists(mine["socket"]) and not os.path.exists(mine["log"])
