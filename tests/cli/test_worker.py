"""cli/worker.py, a worker of the server, without a master: a job runs in the caller's working
folder, environment, umask, command line and standard streams, all restored afterwards, and its
status goes back to the caller; a job that did not end cleanly leaves the worker unfit; the
watcher turns the caller's cancel (or its going away) into a signal; the loop's messages to the
master. (A real server with workers: tests/cli/test_serve.py.)"""

import json
import os
import signal
import socket
import subprocess
import sys
import time

import pytest

from hillshade_rt.cli import client, worker

# one job through worker.run_job in a fresh process, the command line's run replaced by one
# that records the conditions it runs in and writes a line to each stream
JOB = r"""
import json, os, socket, sys
from hillshade_rt.cli import client, group, worker
seen = {}
def run(argv):
    mask = os.umask(0)
    os.umask(mask)
    seen.update(argv=argv, cwd=os.getcwd(), env=dict(os.environ), umask=mask,
                sys_argv=sys.argv, stdin=sys.stdin.read())
    print("out: " + " ".join(argv))
    print("err line", file=sys.stderr)
    return int(argv[0])
group.run = run
work, code, cwd = sys.argv[1:]
def state():
    mask = os.umask(0o022)
    os.umask(mask)
    return [os.getcwd(), dict(os.environ), mask, sys.argv, [os.fstat(i).st_ino for i in (0, 1, 2)]]
before = state()
caller, conn = socket.socketpair()
with open(os.path.join(work, "in"), "w") as fh:
    fh.write("standard input\n")
fds = [os.open(cwd, os.O_RDONLY), os.open(os.path.join(work, "in"), os.O_RDONLY),
       os.open(os.path.join(work, "out"), os.O_WRONLY | os.O_CREAT, 0o600),
       os.open(os.path.join(work, "err"), os.O_WRONLY | os.O_CREAT, 0o600)]
client.send_frame(caller, {"type": "go"}, fds)
result = worker.run_job({"argv": [code, "x y"], "env": {"TZ": "UTC", "ONLY": "this"},
                         "umask": 0o027}, conn)
frames = client.Frames(caller)
answers = [frames.read(2.0), frames.read(2.0), frames.read(2.0)]
after = state()
print(json.dumps({"result": result, "answers": answers, "seen": seen, "before": before,
                  "after": after, "pid": os.getpid()}))
"""


def job(tmp_path, code, cwd=None):
    r = subprocess.run([sys.executable, "-c", JOB, str(tmp_path), str(code),
                        str(cwd or tmp_path)], capture_output=True, text=True, timeout=120,
                       cwd="/")
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.splitlines()[-1]), r.stderr


@pytest.mark.parametrize("code, fit", [(0, True), (2, True), (1, False), (3, False)])
def test_a_job_runs_in_the_callers_conditions_and_restores_them(tmp_path, code, fit):
    got, stderr = job(tmp_path, code)
    assert got["result"] == ["done", code, fit]
    assert got["answers"] == [{"type": "accepted", "pid": got["pid"]},
                              {"type": "status", "code": code}, None]
    seen = got["seen"]
    assert seen["argv"] == [str(code), "x y"]
    assert seen["sys_argv"] == ["hillshade-rt", str(code), "x y"]
    assert os.path.realpath(seen["cwd"]) == os.path.realpath(tmp_path)
    assert seen["env"] == {"TZ": "UTC", "ONLY": "this"} and seen["umask"] == 0o027
    assert seen["stdin"] == "standard input\n"
    assert (tmp_path / "out").read_text() == f"out: {code} x y\n"
    assert (tmp_path / "err").read_text() == "err line\n"
    before, after = got["before"], got["after"]
    assert after[0] == "/"                                  # a worker waits in /
    assert after[1:] == before[1:]           # environment, umask, argv, descriptors 0 1 2
    assert stderr == ""


def test_a_job_that_cannot_be_set_up_is_one_line_and_status_1(tmp_path):
    (tmp_path / "file").write_text("")
    got, stderr = job(tmp_path, 0, cwd=tmp_path / "file")    # fchdir to a file fails
    assert got["result"] == ["done", 1, False] and got["seen"] == {}
    assert got["answers"][1] == {"type": "status", "code": 1}
    assert stderr.startswith("hillshade-rt: error: the server could not run the command "
                             "(NotADirectoryError: ") and stderr.count("\n") == 1


def test_a_caller_gone_before_go_skips_the_job():
    caller, conn = socket.socketpair()
    try:
        caller.shutdown(socket.SHUT_WR)
        assert worker.run_job({"argv": ["info"]}, conn) == ("skipped", 0, True)
        assert client.Frames(caller).read(2.0) == {"type": "accepted", "pid": os.getpid()}
    finally:
        caller.close()
        conn.close()


@pytest.fixture
def handlers():
    """SIGHUP and SIGTERM recorded for the test (then restored)."""
    got = []
    saved = {s: signal.signal(s, lambda signum, frame: got.append(signum))
             for s in (signal.SIGHUP, signal.SIGTERM)}
    yield got
    for s, h in saved.items():
        signal.signal(s, h)


def wait_for(got, n=1):
    deadline = time.monotonic() + 5
    while len(got) < n and time.monotonic() < deadline:
        time.sleep(0.01)
    return got


def test_the_watcher_raises_the_callers_signal_once(handlers):
    caller, conn = socket.socketpair()
    w = worker.Watcher(client.Frames(conn))
    w.start()
    client.send_frame(caller, {"type": "cancel", "signal": int(signal.SIGKILL)})   # not ours
    client.send_frame(caller, {"type": "something else"})
    client.send_frame(caller, {"type": "cancel", "signal": int(signal.SIGHUP)})
    assert wait_for(handlers) == [signal.SIGHUP] and w.raised == [signal.SIGHUP]
    client.send_frame(caller, {"type": "cancel", "signal": int(signal.SIGTERM)})
    caller.close()                                   # and the caller gone: nothing more
    w.join(5)
    time.sleep(0.05)
    assert handlers == [signal.SIGHUP] and not w.is_alive()
    conn.close()


def test_the_caller_gone_is_sigterm_but_not_after_the_job(handlers):
    caller, conn = socket.socketpair()
    w = worker.Watcher(client.Frames(conn))
    w.start()
    caller.close()
    assert wait_for(handlers) == [signal.SIGTERM] and w.raised == [signal.SIGTERM]
    w.join(5)
    conn.close()
    caller, conn = socket.socketpair()
    w = worker.Watcher(client.Frames(conn))
    w.start()
    w.finish()                                       # the job is over
    caller.close()
    w.join(5)
    time.sleep(0.05)
    assert handlers == [signal.SIGTERM] and w.raised == []
    conn.close()


@pytest.fixture
def channel(monkeypatch):
    """(the master's end, the worker's end) of a worker's channel; the worker's signal
    handlers restored after the test."""
    saved = {s: signal.getsignal(s) for s in worker.SIGNALS}
    ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    monkeypatch.setattr(worker, "log", lambda message: None)
    yield ours, theirs
    for s, h in saved.items():
        signal.signal(s, h)
    ours.close()
    theirs.close()


def run_worker(theirs, *args):
    """``worker.main`` on a duplicate of the worker's end (its closing then leaves the messages
    it sent readable); the end closed for writing afterwards, as when the worker ends."""
    code = worker.main([str(os.dup(theirs.fileno())), *args])
    theirs.shutdown(socket.SHUT_WR)
    return code


def messages(sock):
    sock.settimeout(2.0)
    got = []
    while True:
        msg = sock.recv(256)
        if not msg:
            return got
        got.append(msg.decode())


def test_the_loop_says_ready_then_each_job_and_ends_with_the_master(channel, monkeypatch):
    ours, theirs = channel
    warmed, jobs = [], []
    monkeypatch.setattr(worker, "warm_up", lambda check: warmed.append(check))

    def run_job(req, conn):
        jobs.append(req)
        conn.close()
        return ("done", 2, True) if req["n"] == 1 else ("skipped", 0, True)
    monkeypatch.setattr(worker, "run_job", run_job)
    for n in (1, 2):
        a, b = socket.socketpair()
        client.send_frame(ours, {"n": n, "argv": ["info"]}, fds=[b.fileno()])
        a.close()
        b.close()
    ours.send(b"\0\0\0\2{}")                            # no connection with it: ignored
    ours.shutdown(socket.SHUT_WR)                       # the master is gone
    assert run_worker(theirs, "--check-kernels") == 0
    assert warmed == [True] and [j["n"] for j in jobs] == [1, 2]
    assert messages(ours) == ["ready", "done 2 1", "skipped 0 1"]
    assert all(signal.getsignal(s) is worker._late for s in worker.SIGNALS)


def test_the_loop_ends_after_a_job_that_leaves_it_unfit(channel, monkeypatch):
    ours, theirs = channel
    monkeypatch.setattr(worker, "warm_up", lambda check: None)
    jobs = []
    monkeypatch.setattr(worker, "run_job", lambda req, conn: jobs.append(req["n"])
                        or ("done", 1, False))
    for n in (1, 2):
        a, b = socket.socketpair()
        client.send_frame(ours, {"n": n}, fds=[b.fileno()])
        a.close()
        b.close()
    assert run_worker(theirs) == 0
    assert messages(ours) == ["ready", "done 1 0"] and jobs == [1]   # the second never taken


def test_a_failed_warm_up_ends_the_worker_before_ready(channel, monkeypatch):
    ours, theirs = channel
    logged = []
    monkeypatch.setattr(worker, "log", logged.append)

    def warm_up(check):
        raise RuntimeError("the warm-up shadow run ended with status 1")
    monkeypatch.setattr(worker, "warm_up", warm_up)
    assert run_worker(theirs) == 1
    assert logged == ["warm-up failed: RuntimeError: the warm-up shadow run ended with status 1"]
    assert messages(ours) == []                                # no "ready"


def test_a_stream_is_buffered_as_pythons_own(tmp_path):
    like = sys.__stderr__ or sys.stderr
    fd = os.open(tmp_path / "f", os.O_WRONLY | os.O_CREAT, 0o600)
    try:
        out = worker._stream(fd, "w", like)
        err_like = worker._stream(2, "w", like)
        assert out.line_buffering is False and err_like.line_buffering is True
        assert out.encoding == like.encoding and out.errors == like.errors
        out.write("kept")
        out.flush()
        assert (tmp_path / "f").read_text() == "kept"
        out.close()
        os.fstat(fd)                                         # closefd=False: still open
    finally:
        os.close(fd)
