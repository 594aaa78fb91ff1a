"""The viewer's HTTP server (``hillshade-rt view``).

A small HTTP server from the standard library (``http.server.ThreadingHTTPServer``: no
dependency; the viewer is local and single-user, so a thread per request is plenty), bound to
127.0.0.1 only, asking a :class:`~hillshade_rt.run.viewer.Viewer` (the DEM prepared once per
overview level; each request shades only what the page shows):

* ``/``, ``/static/...``: the page (``view_static/``: HTML, JS, CSS and Leaflet, vendored);
* ``/api/info``: the DEM's file name (not its folder), size, bounds, CRS, zone (``--tz``, else the IANA zone of the DEM's
  centre: ``times.zone_at``), the default date and time, the algorithms;
* ``/api/render?bbox=x0,y0,x1,y1&w=&h=&az=&el=|time=&algorithm=&soft=&sunhours=DATE``: a PNG
  (RGBA) of the window ``bbox`` (pixel coordinates of the DEM: x a column, y a row, cell (r, c)
  the square [c, c+1) x [r, r+1)) at ``w`` x ``h``: relief lit by the sun, cast shadows tinted
  blue (lit pixels have red > blue, shadowed ones blue > red), transparent outside the DEM and
  on voids. The window is shaded at the coarsest level that still has a cell per pixel, with
  its halo toward the sun (``Shader.cast`` of a region: the same cells as the whole raster at
  that level; level 1 is the command line's mask). Headers say the sun, level and algorithm;
* ``/api/point?x=&y=&az=&el=|time=``: JSON: the height there, lit or not, its horizon profile;
* ``/api/sunpath?date=``: the day's sun (grid azimuth, elevation) every 10 minutes;
* ``/api/download?...``: the whole DEM's mask at full resolution for the current sun, GeoTIFF
  (of the edited terrain after brush edits, which its TERRAIN and EDITS tags say);
* ``POST /api/edit`` (JSON ``{x, y, radius, delta, shape}``; or ``map_x``, ``map_y`` in the
  DEM's CRS, or ``lon``, ``lat``): the terrain brush: the cells within ``radius`` metres raised
  or lowered by ``delta`` metres (``disk``) or set to the centre's height + ``delta`` (``flat``), in memory
  (``Shader.update`` on every Shader, the overview levels' cells of that window taken again);
  ``POST /api/undo``, ``POST /api/reset``: the last edit, every edit taken back.

Malformed queries get a 400 with a one-line message; nothing a request does stops the server.
The requests' threads only parse and answer: the viewer shades and edits on its one worker
thread, one request at a time (``run.viewer``).
"""

from __future__ import annotations

import json
import os
import sys
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import parse_qs, urlsplit

from ..errors import HillshadeError
from ..pictures.png import png_bytes
from .viewer import BadRequest, NotFound, Viewer

STATIC = os.path.join(os.path.dirname(__file__), "view_static")
HOST = "127.0.0.1"
MAX_BODY = 1 << 16                # bytes of a POST's JSON
TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
         ".css": "text/css; charset=utf-8", ".png": "image/png", ".svg": "image/svg+xml",
         ".txt": "text/plain; charset=utf-8"}



# --------------------------------------------------------------------------------------------
# the server

class Handler(BaseHTTPRequestHandler):
    server_version = "hillshade-rt-view"
    viewer: Viewer = None       # set on the subclass made by make_server
    protocol_version = "HTTP/1.1"

    def log_message(self, fmt, *args):   # quiet: the terminal shows the URL and errors only
        pass

    def send(self, status: int, body: bytes, ctype: str, headers: dict | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        for k, v in (headers or {}).items():
            self.send_header(k, v)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def send_json(self, obj: dict) -> None:
        self.send(200, json.dumps(obj).encode(), "application/json")

    def do_HEAD(self):
        self.do_GET()

    def do_GET(self):
        url = urlsplit(self.path)
        try:
            q = {k: v[-1] for k, v in parse_qs(url.query, keep_blank_values=True).items()}
        except ValueError:
            q = None
        v = self.viewer
        try:
            if q is None:
                raise BadRequest("malformed query string")
            path = url.path
            if path in ("/", "/index.html"):
                self.static("index.html")
            elif path.startswith("/static/"):
                self.static(path[len("/static/"):])
            elif path == "/api/info":
                self.send_json(v.info())
            elif path == "/api/render":
                pic, meta = v.render(q)
                meta["Access-Control-Expose-Headers"] = ", ".join(meta)
                self.send(200, png_bytes(pic), "image/png", meta)
            elif path == "/api/point":
                self.send_json(v.point(q))
            elif path == "/api/sunpath":
                self.send_json(v.sunpath(q))
            elif path == "/api/download":
                data, name = v.download(q)
                self.send(200, data, "image/tiff",
                          {"Content-Disposition": f'attachment; filename="{name}"'})
            else:
                raise NotFound(f"no such page: {url.path}")
        except (BrokenPipeError, ConnectionResetError):
            return
        except Exception as exc:   # noqa: BLE001 -- a request never stops the server
            self.fail(exc)

    def fail(self, exc: BaseException) -> None:
        """The answer to a request that failed: 404 for no such page, 400 for a bad request
        (``BadRequest``, any ``HillshadeError``), else 500 with the error on one line, also
        printed on stderr."""
        if isinstance(exc, NotFound):
            self.send(404, one_line(exc), "text/plain; charset=utf-8")
        elif isinstance(exc, HillshadeError):
            self.send(400, one_line(exc), "text/plain; charset=utf-8")
        else:
            msg = f"internal error ({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''})"
            print(f"hillshade-rt: view: {self.path}: {msg}", file=sys.stderr)
            self.send(500, msg.encode(), "text/plain; charset=utf-8")

    def do_POST(self):
        url = urlsplit(self.path)
        v = self.viewer
        try:
            try:
                size = int(self.headers.get("Content-Length") or 0)
            except ValueError:
                size = -1
            if not 0 <= size <= MAX_BODY:
                self.close_connection = True
                raise BadRequest(f"the body must be JSON of at most {MAX_BODY} bytes")
            body = self.rfile.read(size) if size else b""
            if url.path == "/api/edit":
                try:
                    q = json.loads(body.decode("utf-8") or "null")
                except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                    raise BadRequest(f"the edit is not JSON ({exc})") from None
                self.send_json(v.edit(q))
            elif url.path == "/api/undo":
                self.send_json(v.undo())
            elif url.path == "/api/reset":
                self.send_json(v.reset())
            else:
                raise NotFound(f"no such page: {url.path}")
        except (BrokenPipeError, ConnectionResetError):
            return
        except Exception as exc:   # noqa: BLE001 -- a request never stops the server
            self.fail(exc)

    def static(self, name: str) -> None:
        root = os.path.realpath(STATIC)
        path = os.path.realpath(os.path.join(root, name))
        if not path.startswith(root + os.sep) or not os.path.isfile(path):
            raise NotFound(f"no such file: {name}")
        with open(path, "rb") as f:
            body = f.read()
        self.send(200, body, TYPES.get(os.path.splitext(path)[1], "application/octet-stream"))


def one_line(exc: BaseException) -> bytes:
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return text.encode()


class Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = False

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        return f"http://{host}:{port}/"


def make_server(viewer: Viewer, port: int = 0) -> Server:
    """An HTTP server for ``viewer`` on 127.0.0.1:``port`` (0: a free port), not yet serving."""
    handler = type("ViewHandler", (Handler,), {"viewer": viewer})
    try:
        return Server((HOST, int(port)), handler)
    except OSError as exc:
        raise HillshadeError(f"cannot listen on {HOST}:{port} ({exc.strerror or exc})") from None
