"""``hillshade-rt view``: a local web viewer of a DEM's shadows: the DEM read once and prepared
(``run.viewer.Viewer``, the model), served on 127.0.0.1 (``run.view_server``: the page and the
API, docs/viewer.md) until interrupted.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

from ..errors import HillshadeError, UsageProblem
from .config import ReadOptions, say_nothing
from .view_server import make_server
from .viewer import Viewer


@dataclass
class ViewConfig:
    """``hillshade-rt view DEM``: where to listen and what to shade with."""

    dem: str
    read: ReadOptions = field(default_factory=ReadOptions)
    port: int = 0
    open_browser: bool = True
    algorithm: str = "auto"
    backend: str = "auto"
    tz: str | None = None
    say: object = say_nothing

    def check(self) -> None:
        from ..model.times import zone
        if not (0 <= int(self.port) <= 65535):
            raise UsageProblem(f"--port must be 0..65535, got {self.port}")
        try:
            zone(self.tz)
        except HillshadeError as exc:
            raise UsageProblem(str(exc)) from None


def view(cfg: ViewConfig) -> None:
    """Read the DEM, prepare it, serve the viewer until interrupted (Ctrl-C: the server is
    closed and the interruption goes on up: the command line exits 130)."""
    from ..engine.shader import choose_backend
    cfg.check()
    backend = choose_backend(cfg.backend, cfg.algorithm, {})
    dem = cfg.read.read(cfg.dem)
    viewer = Viewer(dem, cfg.algorithm, backend, cfg.tz)
    server = make_server(viewer, cfg.port)
    try:
        cfg.say("compile", "preparing the kernels (numba) ...")
        viewer.warm_up()
        rows, cols = dem.shape
        print(f"hillshade-rt: viewing {dem.path} ({cols} x {rows}) at {server.url} "
              "(Ctrl-C stops)", flush=True)
        if cfg.open_browser:
            import webbrowser
            threading.Thread(target=webbrowser.open, args=(server.url,), daemon=True).start()
        server.serve_forever(poll_interval=0.2)
    finally:
        server.server_close()
        viewer.close()
