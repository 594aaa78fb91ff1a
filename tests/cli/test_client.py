"""cli/client.py: the way to a warm server, without a server: the setting, the private folder
and socket checks (moved here from test_serve), the key (what a server shares with its callers),
the frames over a socket (lengths, split reads, descriptors, deadlines, a wake-up), what goes to a
server and what a missing one gives. (A real server: test_serve.)"""

import os
import socket

import pytest

from hillshade_rt.cli import client


def test_the_checks_of_folder_and_socket(tmp_path):
    uid = os.getuid()
    d = tmp_path / "d"
    d.mkdir(mode=0o700)
    os.chmod(d, 0o700)
    assert client.folder_problem(str(d)) is None
    assert "owned by uid" in client.folder_problem(str(d), uid=uid + 1)
    os.chmod(d, 0o750)
    assert "mode 750" in client.folder_problem(str(d))
    os.chmod(d, 0o700)
    (tmp_path / "l").symlink_to(d)
    assert "symbolic link" in client.folder_problem(str(tmp_path / "l"))
    assert "not a folder" in client.folder_problem(__file__)
    s = socket.socket(socket.AF_UNIX)
    path = str(d / "s")
    s.bind(path)
    s.close()
    os.chmod(path, 0o600)
    assert client.socket_problem(path) is None
    assert "owned by uid" in client.socket_problem(path, uid=uid + 1)
    os.chmod(path, 0o660)
    assert "mode 660" in client.socket_problem(path)
    assert "not a socket" in client.socket_problem(__file__)


def test_mode():
    for value, want in [(None, "running"), ("", "running"), ("default", "running"),
                        ("AUTO", "auto"), ("on", "auto"), ("1", "auto"), ("off", "off"),
                        ("no", "off"), ("maybe", "off")]:
        env = {} if value is None else {client.SETTING: value}
        assert client.mode(env) == want, value


def test_runtime_dir_and_paths():
    assert client.runtime_dir({"XDG_RUNTIME_DIR": "/run/user/7"}) == "/run/user/7/hillshade-rt"
    tmp = f"/tmp/hillshade-rt-{os.getuid()}"
    assert client.runtime_dir({"XDG_RUNTIME_DIR": "relative/dir"}) == tmp
    assert client.runtime_dir({}) == tmp
    p = client.paths({"XDG_RUNTIME_DIR": "/run/user/7"}, key="k")
    assert p == {"folder": "/run/user/7/hillshade-rt", "key": "k",
                 "socket": "/run/user/7/hillshade-rt/k.sock",
                 "lock": "/run/user/7/hillshade-rt/k.lock", "log": "/run/user/7/hillshade-rt/k.log"}


def test_make_folder(tmp_path):
    d = tmp_path / "priv"
    assert client.make_folder(str(d)) is None
    assert oct(d.stat().st_mode & 0o777) == "0o700"
    assert client.make_folder(str(d)) is None           # there already
    os.chmod(d, 0o755)
    assert "mode 755" in client.make_folder(str(d))
    assert "No such file" in client.make_folder(str(tmp_path / "no" / "such"))


def test_server_key_follows_the_settings_read_once():
    base = {"HOME": "/home/a", "PATH": "/bin"}
    k = client.server_key(base)
    assert len(k) == 24 and k == client.server_key(dict(base))
    assert client.server_key(dict(base, PATH="/usr/bin")) == k          # not read once
    assert client.server_key(dict(base, HILLSHADE_RT_SERVER="auto")) == k
    for name, value in [("NUMBA_NUM_THREADS", "1"), ("GDAL_CACHEMAX", "64"),
                        ("LC_ALL", "C"), ("HOME", "/home/b"), ("XDG_CACHE_HOME", "/c")]:
        assert client.server_key(dict(base, **{name: value})) != k, name


def test_frames_round_trip_split_and_with_descriptors():
    a, b = socket.socketpair()
    try:
        client.send_frame(a, {"type": "status", "x": [1, 2]})
        client.send_frame(a, {"text": "\udcff é"})           # surrogates survive
        frames = client.Frames(b)
        assert frames.read(2.0) == {"type": "status", "x": [1, 2]}
        assert frames.read(2.0) == {"text": "\udcff é"}
        # a frame arriving in pieces
        data = b'{"k": 1}'
        whole = len(data).to_bytes(4, "big") + data
        a.sendall(whole[:3])
        with pytest.raises(TimeoutError):
            frames.read(0.05)
        a.sendall(whole[3:])
        assert frames.read(2.0) == {"k": 1}
        # descriptors ride with the first frame
        r, w = os.pipe()
        try:
            client.send_frame(a, {"type": "go"}, fds=[r])
            got = client.Frames(b, want_fds=1)
            assert got.read(2.0) == {"type": "go"} and len(got.fds) == 1
            os.write(w, b"through")
            assert os.read(got.fds[0], 16) == b"through"
            assert not os.get_inheritable(got.fds[0])
            os.close(got.fds[0])
        finally:
            os.close(r)
            os.close(w)
        # a wake-up descriptor interrupts the wait; the end of the stream is None
        wr, ww = os.pipe()
        os.write(ww, b"!")
        with pytest.raises(InterruptedError):
            client.Frames(b).read(2.0, wake=wr)
        os.close(wr)
        os.close(ww)
        a.close()
        assert client.Frames(b).read(2.0) is None
    finally:
        a.close()
        b.close()


def test_what_goes_to_a_server():
    assert client.goes_to_server(["shadow", "a.tif", "b.tif"], {})
    assert not client.goes_to_server([], {})
    assert not client.goes_to_server(["--version"], {})
    assert not client.goes_to_server(["serve", "start"], {})
    assert not client.goes_to_server(["view", "a.tif"], {})
    assert not client.goes_to_server(["shadow"], {"_HILLSHADE_RT_COMPLETE": "bash_complete"})


def test_no_server_means_none(tmp_path):
    d = tmp_path / "d"
    d.mkdir(mode=0o700)
    os.chmod(d, 0o700)
    assert client.connect(str(d / "absent.sock")) is None
    assert client.request(str(d / "absent.sock"), {"type": "status"}) is None
    assert client.connect(str(d / ("x" * 120) / "s.sock")) is None      # past sun_path
    env = {"XDG_RUNTIME_DIR": str(tmp_path), client.SETTING: "off"}
    assert client.hand_over(["shadow", "a.tif", "b.tif"], env) is None
