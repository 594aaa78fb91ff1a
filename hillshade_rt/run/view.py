"""``hillshade-rt view``: a local web viewer of a DEM's shadows: the DEM read once and prepared
(``run.viewer.Viewer``, the model), served on 127.0.0.1 (``run.view_server``: the page and the
API, docs/viewer.md) until interrupted.
"""

from __future__ import annotations

import threading

from .config import RunOptions
from .config import ViewConfig
from .runner import RunContext
from .view_server import make_server
from .viewer import Viewer


def view(cfg: ViewConfig) -> None:
    """Read the DEM, prepare it, serve the viewer until interrupted (Ctrl-C: the server is
    closed and the interruption goes on up: the command line exits 130)."""
    cfg.check()
    ctx = RunContext.start(RunOptions(backend=cfg.backend, say=cfg.say), inputs=[cfg.dem],
                           algorithm=cfg.algorithm, note=False)
    dem = cfg.read.read(cfg.dem)
    viewer = Viewer(dem, cfg.algorithm, ctx.backend, cfg.tz)
    server = make_server(viewer, cfg.port)
    try:
        _prepare(ctx, viewer)
        _announce(cfg, dem, server.url)
        server.serve_forever(poll_interval=0.2)
    finally:
        server.server_close()
        viewer.close()


def _prepare(ctx: RunContext, viewer: Viewer) -> None:
    """The viewer's kernels compiled (or loaded) before the first request, said first."""
    ctx.say("compile", "preparing the kernels (numba) ...")
    viewer.warm_up()


def _announce(cfg: ViewConfig, dem, url: str) -> None:
    """The viewer's address on standard output, and the browser opened on it (unless
    --no-browser)."""
    rows, cols = dem.shape
    print(f"hillshade-rt: viewing {dem.path} ({cols} x {rows}) at {url} (Ctrl-C stops)",
          flush=True)
    if cfg.open_browser:
        import webbrowser
        threading.Thread(target=webbrowser.open, args=(url,), daemon=True).start()
