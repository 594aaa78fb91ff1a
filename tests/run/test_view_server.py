"""hillshade-rt view's HTTP server (run/view_server.py): the page and its static files, the
one-line 400s of malformed queries (the server goes on), bound to the loopback only, every page
file shipped as package data."""

from __future__ import annotations

import os
import socket

import pytest

from hillshade_rt.io import read_dem
from hillshade_rt.run.viewer import Viewer
from hillshade_rt.testing import data_path, http_get, serving

DEM = data_path("everest_srtm3_voids_crop200.tif")     # EPSG:4326, 19.5 % voids


@pytest.fixture(scope="module")
def server():
    with serving(Viewer(read_dem(DEM))) as srv:
        yield srv


def test_page_and_static(server):
    status, headers, body = http_get(server, "/")
    assert status == 200 and headers["Content-Type"].startswith("text/html")
    assert b"/static/leaflet/leaflet.js" in body and b"/static/viewer.js" in body
    for name in ("leaflet/leaflet.js", "leaflet/leaflet.css", "viewer.js", "viewer.css",
                 "leaflet/images/layers.png"):
        status, _, body = http_get(server, "/static/" + name)
        assert status == 200 and len(body) > 100, name
    # nothing outside the static folder
    assert http_get(server, "/static/../view.py")[0] == 404
    assert http_get(server, "/static/%2e%2e/view.py")[0] == 404
    assert http_get(server, "/nothing")[0] == 404


@pytest.mark.parametrize("query, words", [
    ("/api/render?az=abc&el=10", "az must be a number"),
    ("/api/render?az=10&el=95", "el must be"),
    # a given sun at or below the horizon: 400, as the command line's --elevation 0 (exit 2)
    ("/api/download?el=0", "el must be > 0"),
    ("/api/download?az=10&el=-5", "el must be > 0"),
    ("/api/render?az=10&el=0", "el must be > 0"),
    ("/api/point?x=5&y=5&az=10&el=0", "el must be > 0"),
    ("/api/point?x=5&y=5&el=-0.0", "el must be > 0"),
    ("/api/render?bbox=1,2", "bbox must be"),
    ("/api/render?bbox=5,5,1,1", "bbox must be"),
    ("/api/render?w=0&h=10", "w and h"),
    ("/api/render?w=100000&h=100000", "w and h"),
    ("/api/render?algorithm=nope", "unknown algorithm"),
    ("/api/render?soft=maybe", "soft must be"),
    ("/api/render?time=yesterday", "not an ISO 8601 time"),
    ("/api/render?sunhours=June", "date must be"),
    ("/api/point?x=nan&y=1", "x must be finite"),
    ("/api/point?y=1", "missing x"),
    ("/api/sunpath?date=", "date must be"),
    ("/api/render?time=9999-06-21T12:00Z", "outside the solar position algorithm's range"),
    ("/api/point?x=10&y=10&time=9999-06-21T12:00Z", "year 9999 is outside"),
    ("/api/sunpath?date=9999-06-21", "year 9999 is outside"),
    ("/api/render?sunhours=9999-06-21", "year 9999 is outside"),
])
def test_malformed_queries_400_and_the_server_goes_on(server, query, words):
    status, _, body = http_get(server, query)
    assert status == 400
    text = body.decode()
    assert words in text and "\n" not in text.strip() and "Traceback" not in text
    assert http_get(server, "/api/info")[0] == 200


def test_bound_to_loopback_only(server):
    host, port = server.server_address[:2]
    assert host == "127.0.0.1" and port > 0
    # this machine's other addresses: nothing listens there
    others = set()
    for name in (socket.gethostname(), socket.getfqdn()):
        try:
            others |= {a[4][0] for a in socket.getaddrinfo(name, None, socket.AF_INET)}
        except OSError:
            pass
    others = {a for a in others if not a.startswith("127.")}
    for addr in others:
        with socket.socket() as s:
            s.settimeout(2)
            assert s.connect_ex((addr, port)) != 0, addr


def test_every_page_file_is_package_data():
    """The wheel carries the page: pyproject's package-data globs cover every file of
    view_static (checked against a built wheel once: index.html, JS, CSS, Leaflet, images)."""
    import fnmatch

    from hillshade_rt.run.view_server import STATIC
    tomllib = pytest.importorskip("tomllib")         # Python >= 3.11
    from hillshade_rt.testing import repo_root
    with open(os.path.join(repo_root(), "pyproject.toml"), "rb") as f:
        globs = tomllib.load(f)["tool"]["setuptools"]["package-data"]["hillshade_rt.run"]
    base = os.path.dirname(STATIC)
    files = [os.path.relpath(os.path.join(d, n), base).replace(os.sep, "/")
             for d, _, names in os.walk(STATIC) for n in names]
    assert len(files) >= 10
    for f in files:
        assert any(fnmatch.fnmatch(f, g) and f.count("/") == g.count("/") for g in globs), f
