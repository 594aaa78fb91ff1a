"""Compile, once, the kernels a first run needs: ``python -m hillshade_rt.warm`` (``make install``
runs it), so that the first shading after an install does not wait for numba.

What it compiles is what ``hillshade-rt shadow`` and ``hillshade`` use by default on the common
DEMs: auto's two methods, bounds and brute over the pyramid (with curvature), on a grid of one spacing (projected DEMs) and on a
grid whose spacing varies per row (geographic DEMs), the Horn normals of the relief and the
read's nodata pass. Each
kernel lands in numba's cache (``~/.cache/hillshade-rt/numba/<digest>``); what is already there
is only loaded.
"""

from __future__ import annotations

import sys
import time


def missing() -> list[str]:
    """The kernel modules of the defaults whose compiled kernels numba's cache lacks: auto's,
    the Horn normals and the read's nodata pass."""
    from .algorithms import REGISTRY
    from .algorithms._jitcache import cached
    return [m for m in REGISTRY["auto"].kernel_modules + ("relief", "counts") if not cached(m)]


def main() -> int:
    import numpy as np

    from .algorithms._jitcache import cache_dir
    from .shading import Shader
    from .earth import Body
    from .geometry import Grid

    todo = missing()
    if not todo:
        return 0
    print(f"hillshade-rt: compiling the {', '.join(todo)} kernels once (cached in "
          f"{cache_dir()})", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    z = np.zeros((4, 4), np.float32)
    grids = [Grid.uniform(4, 4, 30.0),
             Grid(4, 4, np.linspace(92.0, 60.0, 4), np.full(4, 92.5), 1, -1, "per row")]
    for grid in grids:
        sh = Shader(z, grid, "auto", {}, "cpu", True, None, Body(), (0.0, 1.0))
        sh.warm_up(203.7, 10.0, soft=False, incidence=True)
    from .algorithms.counts import clean_heights
    clean_heights(np.zeros((4, 4), np.float32), 0.0, True)   # the read's nodata pass
    print(f"hillshade-rt: kernels ready ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    _stale_hint()
    return 0


def _stale_hint() -> None:
    """After compiling a new version's kernels, the older versions' folders are what a user
    may want gone: say so, with their size (removing them is ``hillshade-rt cache --prune``'s
    to do: another environment may still use one)."""
    from .algorithms._jitcache import survey
    others = survey()["other_versions"]
    if others:
        size = sum(s for _, s in others) / 1e6
        print(f"hillshade-rt: {len(others)} other versions' compiled kernels ({size:.0f} MB) "
              f"are cached too; 'hillshade-rt cache --prune' removes them", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
