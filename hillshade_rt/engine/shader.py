"""One DEM prepared once, lit by any number of suns: cast shadows, soft shadows, self-shadow,
shaded relief and sun hours on top of the algorithms.

A :class:`Shader` holds the heights, their ground geometry and everything that does not depend on
the sun (height range, numba kernels compiled, the heights uploaded to the GPU, the Earth's radius
for curvature). Each sun is a :class:`~hillshade_rt.model.sun.SunOver`: one vector for the raster, or
one per tile when the sun's direction varies across a large raster; a tile is computed on its own
window plus the halo toward the sun that can shadow it (the rays of its cells rise above the
highest cell within that distance), so a tile's cells get exactly what a run of the whole raster
with that tile's sun gives them.

Night: a sun at or below the (apparent) horizon lights nothing; every valid cell is in shadow.

Earth curvature (docs/model.md): at ground distance d from its cell the ray stands
d^2 (1 - k) / (2 R) higher above the terrain than on a flat Earth. ``brute`` and the horizon scan
march the curved ray directly; the other algorithms compute the flat answer and their shadowed
cells are re-marched by brute with curvature (curvature can only light a cell, never shadow one),
so the result is exactly brute's.
"""

from __future__ import annotations

import contextlib
import math

import numpy as np

from ..algorithms import REGISTRY, lookup
from ..errors import HillshadeError
from ..model.earth import Body, curvature_coefficient, curvature_report, refraction_for
from ..model.geometry import Grid, SunRays, sun_rays
from ..model.solar import SUN_RADIUS_DEG, disk_fraction
from ..model.sun import Region, SunOver

# a tile whose window (tile + halo) holds more than this many times its own cells is marched by
# brute over its own cells only (exact), instead of running the algorithm over the whole window
# (bounds, auto's usual pick: by the cost model instead, algorithms.auto.tile_by_brute)
TILE_BRUTE_RATIO = 3.0
_TILE = 7   # scratch code: a cell of the tile, still to decide
# a sun's kernels run on at most one thread per this many cells (``threads_for``)
CELLS_PER_THREAD = 1 << 15
SOFT_NODATA = -9999.0

# output codes of --classes
LIT, SELF_SHADOW, CAST_SHADOW, NODATA = 0, 1, 2, 255


def reach_m(dz: float, elevation: float, curv_per_m2: float = 0.0) -> float:
    """Ground metres after which a ray leaving at ``elevation`` has risen ``dz`` above its start
    (with the Earth-curvature gain ``curv_per_m2`` * d^2 when that is > 0): terrain farther than
    this toward the sun, and no higher than start + ``dz``, cannot shadow the start. inf for a sun
    at or below the horizon, 0 at the zenith or when ``dz`` <= 0."""
    if elevation <= 0:
        return math.inf
    if elevation >= 90 or dz <= 0:
        return 0.0
    t = math.tan(math.radians(elevation))
    if curv_per_m2 > 0:
        return (-t + math.sqrt(t * t + 4.0 * curv_per_m2 * dz)) / (2.0 * curv_per_m2)
    return dz / t


def halo_bounds(bounds: tuple[int, int, int, int], shape: tuple[int, int], grid: Grid,
                azimuth: float, reach: float, margin: int = 0) -> tuple[int, int, int, int]:
    """(r0, r1, c0, c1) of ``bounds`` (rows r0:r1, columns c0:c1 of a raster of ``shape``) grown
    toward the sun at ``azimuth`` by ``reach`` ground metres plus 2 cells (on both sides of an
    axis the sun does not move along), and by ``margin`` cells on every side, within the raster.

    The rays of row r use row r's spacing, so the smallest spacing of the bounds' rows sets how
    many cells ``reach`` spans."""
    rows, cols = shape
    r0, r1, c0, c1 = bounds
    east = math.sin(math.radians(azimuth)) * grid.col_sign
    north = math.cos(math.radians(azimuth)) * grid.row_sign
    dxm = float(np.min(grid.dx[r0:r1]))
    dym = float(np.min(grid.dy[r0:r1]))

    def grow(lo, hi, comp, spacing, n):
        if abs(comp) < 1e-12:
            return max(0, lo - 2 - margin), min(n, hi + 2 + margin)
        more = n if not math.isfinite(reach) else int(math.ceil(reach * abs(comp) / spacing)) + 2
        if comp > 0:
            return max(0, lo - margin), min(n, hi + more + margin)
        return max(0, lo - more - margin), min(n, hi + margin)
    c0, c1 = grow(c0, c1, east, dxm, cols)
    r0, r1 = grow(r0, r1, north, dym, rows)
    return r0, r1, c0, c1


def _window_range(a: np.ndarray) -> tuple[int, float, float]:
    """(valid cells, lowest, highest) of a small window (numpy: a parallel kernel's start costs
    more than the pass); inf / -inf when nothing is valid."""
    ok = ~np.isnan(a)
    n = int(ok.sum())
    if not n:
        return 0, math.inf, -math.inf
    v = a[ok]
    return n, float(v.min()), float(v.max())


def warm_up(algorithm: str, grid: Grid | None = None, azimuth: float = 203.7,
            elevation: float = 10.0, backend: str = "cpu", **options) -> None:
    """Compile (or load from numba's cache) the kernels that a run of ``algorithm`` on ``grid``
    with this sun will use, on a 4x4 grid with the same orientation and spacing pattern (same
    array layouts and argument types), so that a timed run measures computing, not compiling.
    ``backend`` "gpu": the CUDA kernels (compiled for this process's device)."""
    z = np.zeros((4, 4), np.float32)
    if grid is None:
        small = Grid.uniform(4, 4, 1.0)
    else:
        idx = np.linspace(0, grid.rows - 1, 4).astype(int)
        small = Grid(4, 4, grid.dx[idx], grid.dy[idx], grid.col_sign, grid.row_sign, grid.method)
    rays = sun_rays(small, azimuth, elevation)
    if backend == "gpu":
        from .gpu import GpuDem
        z[0, 0] = 1.0    # a non-flat DEM, so that no kernel is skipped
        GpuDem(z).shadow_mask(rays, algorithm, None, None, **options)
    else:
        REGISTRY[algorithm].cpu(z, rays, 0.0, None, **options)


def choose_backend(backend: str, algorithm: str, options: dict) -> str:
    """'cpu' or 'gpu' for a request (:func:`.gpu.resolve_backend`, the one rule)."""
    from .gpu import resolve_backend
    return resolve_backend(backend, algorithm, options)


_WARMED: set = set()     # Shader.warm_up: the kinds of calls warmed in this process


@contextlib.contextmanager
def threads_for(cells: int):
    """numba's threads in this thread capped at one per ``CELLS_PER_THREAD`` cells (at least
    one) while the block runs, then as they were. A sun's work is a few parallel kernels, the
    bounds sweep's wavefront a parallel region per block of lines, and every region wakes all
    the threads and waits for the last: on a small raster that wait, not the cells, was the
    cost. A 200 x 150 DEM's sun on 2 threads of a loaded 2-core machine: 67 ms in the sweep's
    regions, 3.6 ms on one thread; on an idle machine a region costs some microseconds a
    thread, which 2^15 cells (a few ms of work) repay. The masks do not depend on the threads
    (exact methods, cell by cell)."""
    import numba
    n = numba.get_num_threads()
    want = max(1, min(n, int(cells) // CELLS_PER_THREAD))
    if want == n:
        yield n
        return
    numba.set_num_threads(want)
    try:
        yield want
    finally:
        numba.set_num_threads(n)

class Shader:
    """A DEM ready to be lit by any number of suns (:func:`render`).

    A window of a larger raster (``engine.windows``): ``zrange`` and ``extent_m`` are the whole
    raster's (so that curvature "auto" decides as for the whole), and ``halo_ready`` says that
    ``z`` already holds the halo of every region asked for: each region is computed on all of
    ``z``. With a lift the cast shadows are marched by an algorithm that takes one
    (``algorithms.for_lift``: ``auto`` runs brute, an algorithm that cannot is an error); the
    halos toward the sun are shortened by it (a ray that starts higher clears the terrain
    sooner); soft shadows take it through the horizon scan's own lift
    (:meth:`visible_fraction`).

    Parameters
    ----------
    z : numpy.ndarray
        2-D float32 heights in metres, NaN voids, used in place (:meth:`update` edits it).
    grid : Grid
        Their ground geometry (metres per cell, per row).
    algorithm : str, default "auto"
        One of ``algorithms.REGISTRY``.
    options : dict, optional
        The algorithm's options (as :func:`hillshade_rt.engine.arrays.shadow_mask`'s ``**options``).
    backend : {"cpu", "gpu"}, default "cpu"
        Already resolved (:func:`choose_backend`).
    curvature : bool or "auto", default "auto"
        Earth curvature of the rays; ``auto``: on when a ray can run longer than 1 km before it
        rises above the highest cell or leaves the raster.
    refraction_k : float, optional
        Terrestrial refraction coefficient (dimensionless); default 0.13 on the Earth, 0
        elsewhere.
    body : earth.Body, optional
        The body (its ellipsoid axes in metres, the DEM's latitude in degrees); default WGS84
        at 45 degrees latitude.
    zrange : (float, float), optional
        Lowest and highest valid height of the whole raster, metres (default ``z``'s).
    extent_m : float, optional
        The whole raster's diagonal, ground metres (default ``z``'s).
    halo_ready : bool, default False
        ``z`` already holds the halo toward the sun of every region asked for.
    local_range : (float, float), optional
        Lowest and highest height of this window, metres (known from the statistics pass; else
        computed).
    carry : engine.windows.BandCarry, optional
        For ``smap`` on the CPU: the tables of the window before, reused.
    place : optional
        The window and the raster's shape, with ``carry``: SMap masks only the region.
    sun_field : bool, default True
        Suns that vary across the raster: every cell's own sun direction
        (``algorithms.per_cell_sun``) instead of one per tile.
    survey : (int, float, float), optional
        The read's (valid cells, lowest, highest height in metres) of ``z``, when the caller has
        it (saves a pass).
    lift : float, default 0.0
        Metres (>= 0) above every cell that its ray starts from (an observer, a panel above each
        cell: ``--height-above-ground``; 0 the ground itself).

    Raises
    ------
    HillshadeError
        An unknown algorithm, a lift that is not a finite number >= 0 or that the algorithm
        cannot take, a bad ``curvature`` or refraction coefficient.
    """

    def __init__(self, z: np.ndarray, grid: Grid, algorithm: str = "auto",
                 options: dict | None = None, backend: str = "cpu", curvature="auto",
                 refraction_k: float | None = None, body: Body | None = None,
                 zrange: tuple[float, float] | None = None, extent_m: float | None = None,
                 halo_ready: bool = False, local_range: tuple[float, float] | None = None,
                 carry=None, place=None, sun_field: bool = True,
                 survey: tuple[int, float, float] | None = None, lift: float = 0.0):
        from ..algorithms import for_lift
        lookup(algorithm)       # an unknown name: a HillshadeError listing the known ones
        lift = float(lift)
        if not (math.isfinite(lift) and lift >= 0.0):
            raise HillshadeError(f"the height above the ground must be a number of metres >= 0, "
                                 f"got {lift}")
        self.lift = lift
        if lift > 0.0:
            algorithm = for_lift(algorithm)
        self.z, self.grid = z, grid
        self.algorithm, self.options, self.backend = algorithm, dict(options or {}), backend
        if zrange is None:
            zrange = (float(np.nanmin(z)), float(np.nanmax(z)))
        self.zmin, self.zmax = zrange
        self.body = body or Body()
        self.k = refraction_for(self.body, refraction_k)
        if curvature not in (True, False, "auto"):
            raise HillshadeError(f"curvature must be True, False or 'auto', got {curvature!r}")
        self.curvature = curvature
        rows, cols = z.shape
        dx, dy = grid.centre_spacing()
        self.extent_m = math.hypot(cols * dx, rows * dy) if extent_m is None else float(extent_m)
        self.halo_ready = halo_ready
        # the heights of this array (a window's own range is tighter than the raster's)
        if local_range is None:
            local_range = ((float(np.nanmin(z)), float(np.nanmax(z))) if halo_ready
                           and np.isfinite(z).any() else (self.zmin, self.zmax))
        self.local_range = local_range
        self.carry, self.place = carry, place
        # suns that vary across the raster: every cell's own sun (algorithms.per_cell_sun) instead of
        # one per tile, in memory and in windows alike (``engine.windows.WindowLighting.pieces``); False: tiles
        self.sun_field = sun_field
        self._gpu = None
        self._pyramid = None     # the maximum-height pyramid of the whole raster, built once
        # (valid fraction, lowest, highest) of z for --algorithm auto; ``survey``: the read's
        # (valid cells, lowest, highest) of z, when the caller has it (saves a pass)
        self._survey = (None if survey is None else
                        (survey[0] / max(1, z.size), float(survey[1]), float(survey[2])))
        self.stats: dict = {}
        self.curvature_used: set = set()   # True/False seen, and the radii used (m)
        # dynamic terrain (``update``): the DEM's version, and each edit since the first:
        # (version after it, (r0, r1, c0, c1), highest height the window held before or after
        # it, the raster's (zmin, zmax) before it)
        self.version = 0
        self._edits: list = []
        self._valid = None      # valid cells of z, once an update needed them

    # -- dynamic terrain ---------------------------------------------------------------------
    def update(self, window, heights: np.ndarray) -> int:
        """Replace part of the DEM: ``heights`` (2-D, float32 or cast to it; NaN voids) go into
        ``self.z`` at ``window``, the (row, col) of its top-left cell, or a rasterio-like
        ``Window`` (``row_off``, ``col_off``; its height and width must be heights' shape).

        ``self.z`` is edited in place: the array the Shader was made with is the caller's, so the
        caller's array changes too (the Shader never copied the DEM; copy before if you need the
        original). Everything derived from the heights follows: the height range (exact: a full
        pass only when the window held the lowest or highest cell and lost it), auto's survey,
        the pyramid's blocks over the window (patched, the values a new build gives), the GPU's
        copy (``gpu.GpuDem.update``: only the window is uploaded).

        Returns the new ``version`` (the number of updates so far). A product rendered at
        version v can be brought up to date with ``render(..., previous=(product, v))``, which
        re-shades only the cells the edits since v can have changed."""
        from ..algorithms.counts import valid_range
        if self.halo_ready or self.place is not None or self.carry is not None:
            raise HillshadeError("update: this Shader lights a window of a larger raster; "
                                 "make a Shader of the whole DEM to edit it")
        heights = np.asarray(heights)
        if heights.ndim != 2:
            raise HillshadeError(f"update: the heights must be a 2-D array, got {heights.ndim}-D")
        if hasattr(window, "row_off") and hasattr(window, "col_off"):
            r0, c0 = int(window.row_off), int(window.col_off)
            if (int(window.height), int(window.width)) != heights.shape:
                raise HillshadeError(f"update: the window is {int(window.height)} x "
                                     f"{int(window.width)} but the heights are "
                                     f"{heights.shape[0]} x {heights.shape[1]}")
        else:
            try:
                r0, c0 = (int(v) for v in window)
            except (TypeError, ValueError):
                raise HillshadeError("update: the window must be (row, col) of its top-left "
                                     f"cell or a rasterio Window, got {window!r}") from None
        h, w = heights.shape
        rows, cols = self.z.shape
        if not (0 <= r0 and 0 <= c0 and r0 + h <= rows and c0 + w <= cols):
            raise HillshadeError(f"update: {h} x {w} heights at row {r0}, column {c0} do not "
                                 f"fit in the {rows} x {cols} DEM")
        r1, c1 = r0 + h, c0 + w
        heights = np.ascontiguousarray(heights, dtype=np.float32)
        if self._valid is None:
            self._valid = int(valid_range(self.z)[0])
        n_old, lo_old, hi_old = _window_range(self.z[r0:r1, c0:c1])
        n_new, lo_new, hi_new = _window_range(heights)
        before = (self.zmin, self.zmax)
        self.z[r0:r1, c0:c1] = heights
        self._valid += int(n_new) - int(n_old)
        if not (math.isfinite(self.zmin) and math.isfinite(self.zmax)) or (
                n_old and (lo_old <= self.zmin or hi_old >= self.zmax)):
            _, lo, hi = valid_range(self.z)       # an extreme may have gone: look again
            self.zmin, self.zmax = float(lo), float(hi)
        else:
            self.zmin, self.zmax = min(self.zmin, float(lo_new)), max(self.zmax, float(hi_new))
        self.local_range = (self.zmin, self.zmax)
        if self._survey is not None:
            self._survey = (self._valid / max(1, self.z.size), self.zmin, self.zmax)
        if self._pyramid is not None:
            self._pyramid.update(self.z, (r0, r1, c0, c1))
        if self._gpu is not None:
            self._gpu.update(r0, c0, self.z[r0:r1, c0:c1],
                             (self.zmin, self.zmax, self._valid < self.z.size))
        self.version += 1
        self._edits.append((self.version, (r0, r1, c0, c1),
                            max(float(hi_old), float(hi_new)), before))
        return self.version

    def edits_since(self, version: int) -> list:
        """The edits made after ``version`` (see ``update``), oldest first."""
        if not (isinstance(version, (int, np.integer)) and 0 <= version <= self.version):
            raise HillshadeError(f"previous: version {version!r} is not one of this Shader's "
                                 f"(0 .. {self.version})")
        return [e for e in self._edits if e[0] > version]

    def affected_bounds(self, bounds: tuple[int, int, int, int], top: float, azimuth: float,
                        elevation: float) -> tuple[int, int, int, int]:
        """(r0, r1, c0, c1): the cells whose shadow toward the sun at (``azimuth``,
        ``elevation``) an edit of ``bounds`` can change: the window and its anti-sun halo, the
        cells whose ray can pass below ``top`` (the highest the window held before or after
        the edit) over it, grown by one cell on every side (the interpolated samples next to
        the window, the normals of the relief). The halo's length in cells takes the smallest
        spacing of the raster (the rays of a row use its own spacing) and the flat ray
        (curvature and a lift only raise rays)."""
        box = self._anti_sun(bounds, top, azimuth, elevation, self.zmin)
        if not math.isfinite(top):
            return box
        # the cells of that box are no lower than its own lowest: a shorter halo serves
        r0, r1, c0, c1 = box
        lo = _window_range(self.z[r0:r1, c0:c1])[1]
        return self._anti_sun(bounds, top, azimuth, elevation, lo) if lo > self.zmin else box

    def _anti_sun(self, bounds, top, azimuth, elevation, low):
        """``affected_bounds`` for cells no lower than ``low``."""
        rows, cols = self.z.shape
        r0, r1, c0, c1 = bounds
        m = 1
        reach = (reach_m(top - low, elevation, 0.0) if math.isfinite(top) else 0.0)
        away = azimuth + 180.0
        east = math.sin(math.radians(away)) * self.grid.col_sign
        north = math.cos(math.radians(away)) * self.grid.row_sign
        dxm, dym = float(np.min(self.grid.dx)), float(np.min(self.grid.dy))

        def grow(lo, hi, comp, spacing, n):
            if abs(comp) < 1e-12:
                return max(0, lo - 2 - m), min(n, hi + 2 + m)
            more = (n if not math.isfinite(reach) else
                    int(math.ceil(reach * abs(comp) / spacing)) + 2)
            if comp > 0:
                return max(0, lo - m), min(n, hi + more + m)
            return max(0, lo - more - m), min(n, hi + m)
        c0, c1 = grow(c0, c1, east, dxm, cols)
        r0, r1 = grow(r0, r1, north, dym, rows)
        return r0, r1, c0, c1

    def warm_up(self, azimuth: float, elevation: float, soft: bool = False,
                incidence: bool = False, field: bool = False) -> None:
        """Compile (or load from numba's cache) what the suns to come will run, so that timings
        measure computing. On the CPU by lighting a small rough terrain through this very path
        (the same calls and argument types: the algorithm, or both methods of ``auto`` and its
        survey; the pyramid, refinements, soft horizons, the report's counts), on a grid with
        the same pattern of spacing; on the GPU through ``engine.shader.warm_up``. Once per process
        for each kind of call (a batch of DEMs, a warm server's worker: many runs)."""
        # what decides the kernels and their argument types, the sun's octant included (the
        # frames' views)
        key = (self.backend, self.algorithm, repr(sorted(self.options.items())),
               self.grid.method, self.grid.col_sign, self.grid.row_sign, repr(self.curvature),
               self.k, repr(self.lift), soft, incidence, field, int(azimuth % 360.0 // 45.0),
               azimuth % 45.0 == 0.0, elevation >= 89.0)
        if key in _WARMED:
            return
        self._warm_up(azimuth, elevation, soft, incidence, field)
        _WARMED.add(key)

    def _warm_up(self, azimuth: float, elevation: float, soft: bool, incidence: bool,
                 field: bool) -> None:
        from ..algorithms.counts import code_counts
        el = min(max(elevation, 1.0), 89.0)
        if self.backend != "cpu":
            for name in (("brute",) if self.algorithm == "auto" else (self.algorithm,)):
                warm_up(name, self.grid, azimuth, el, backend=self.backend, **self.options)
        else:
            n = 40
            i = np.arange(n)
            z = (60.0 * np.add.outer(np.sin(0.7 * i), np.cos(1.3 * i)) + 100.0).astype(np.float32)
            z[5, 7] = np.nan
            idx = np.linspace(0, self.grid.rows - 1, n).astype(int)
            small = Grid(n, n, self.grid.dx[idx], self.grid.dy[idx], self.grid.col_sign,
                         self.grid.row_sign, self.grid.method)
            names = (("auto", "bounds", "brute") if self.algorithm == "auto"
                     else (self.algorithm,))
            region = Region(slice(0, n), slice(0, n), azimuth, el)
            lattice = None
            if field and field_method(self.algorithm, self.options, soft):
                from types import SimpleNamespace
                from ..algorithms.per_cell_sun import lattice_vectors
                gi, gj = np.meshgrid(np.linspace(-0.2, 0.2, 3), np.linspace(-0.2, 0.2, 3),
                                     indexing="ij")
                lattice = SimpleNamespace(azimuth=azimuth, elevation=el,
                                          lattice=lattice_vectors(azimuth + gj, el + gi))
            for name in names:
                sh = Shader(z, small, name, self.options, "cpu", self.curvature, self.k,
                            self.body, (self.zmin, self.zmax), self.extent_m, lift=self.lift)
                sh.cast(region, {})
                if soft:
                    sh.visible_fraction(region)
                if lattice is not None:      # a sun per cell (``cast_field``)
                    sh.cast_field(lattice, {})
            code_counts(np.zeros((64, 64), np.uint8))    # the report's counts (>= 64 rows)
        if incidence:
            from ..algorithms.relief import incidence as inc
            small4 = Grid.uniform(4, 4, *self.grid.centre_spacing(), self.grid.col_sign,
                                  self.grid.row_sign)
            inc(np.zeros((4, 4), np.float32), small4, azimuth, elevation)

    # -- per sun -------------------------------------------------------------------------------
    def curvature_for(self, azimuth: float, elevation: float) -> float:
        """(1 - k) / 2R for this sun, or 0 when curvature is off."""
        return curvature_coefficient(self.curvature, self.body, self.k, self.extent_m,
                                     (self.zmin, self.zmax), azimuth, elevation)

    def curvature_used_for(self, azimuth: float, elevation: float) -> float:
        """``curvature_for``, noted for the report (whether rays were curved, and the radius they
        used: rounded, one per direction)."""
        c = self.curvature_for(azimuth, elevation)
        self.curvature_used.add(c > 0)
        if c > 0:
            self.curvature_used.add(round(float(self.body.radius(azimuth)), 1))
        return c

    def rays(self, grid: Grid, azimuth: float, elevation: float) -> SunRays:
        return sun_rays(grid, azimuth, elevation, self.curvature_used_for(azimuth, elevation))

    def window(self, region: Region, elevation: float) -> tuple[slice, slice]:
        """Rows and columns to read for ``region``: the region plus the halo toward the sun
        within which terrain can still rise above a ray leaving the region at ``elevation``."""
        rows, cols = self.z.shape
        r0, r1, _ = region.rows.indices(rows)
        c0, c1, _ = region.cols.indices(cols)
        if (r0, r1, c0, c1) == (0, rows, 0, cols):
            return region.rows, region.cols
        sub = self.z[r0:r1, c0:c1]
        low = float(np.nanmin(sub)) if np.isfinite(sub).any() else self.zmax
        # the rays start at least ``lift`` above the region's lowest cell
        reach = reach_m(self.zmax - (low + self.lift), elevation, 0.0)
        r0, r1, c0, c1 = halo_bounds((r0, r1, c0, c1), (rows, cols), self.grid, region.azimuth,
                                     reach)
        return slice(r0, r1), slice(c0, c1)

    def _piece(self, region: Region, elevation_for_halo: float):
        """(z, grid, inner) of the window of ``region``: heights (a view for the whole raster, a
        contiguous copy for a tile), its grid, and the region's place inside the window."""
        rows, cols = self.z.shape
        if self.halo_ready:
            return self.z, self.grid, (region.rows, region.cols), True
        wr, wc = self.window(region, elevation_for_halo)
        if (wr.indices(rows)[:2], wc.indices(cols)[:2]) == ((0, rows), (0, cols)):
            return self.z, self.grid, (region.rows, region.cols), True
        z = np.ascontiguousarray(self.z[wr, wc])
        g = Grid(z.shape[0], z.shape[1], self.grid.dx[wr], self.grid.dy[wr], self.grid.col_sign,
                 self.grid.row_sign, self.grid.method)
        r0 = region.rows.indices(rows)[0] - wr.start
        c0 = region.cols.indices(cols)[0] - wc.start
        inner = (slice(r0, r0 + len(range(*region.rows.indices(rows)))),
                 slice(c0, c0 + len(range(*region.cols.indices(cols)))))
        return z, g, inner, False

    def _gpu_dem(self, z, whole):
        from .gpu import GpuDem
        if whole:
            if self._gpu is None:
                self._gpu = GpuDem(z, (*self.local_range, bool(np.isnan(z).any())))
            return self._gpu
        return GpuDem(z)

    def pyramid(self, z: np.ndarray, whole: bool):
        """The maximum-height pyramid of ``z`` (kept for the next suns when ``z`` is the whole
        raster; built only when a march first uses it), or False when the options ask for the
        plain march."""
        from ..algorithms.pyramid import MaxPyramid
        if self.options.get("pyramid", True) is False:
            return False
        if not whole:
            return MaxPyramid(z)
        if self._pyramid is None:
            self._pyramid = MaxPyramid(z)
        return self._pyramid

    def choose(self, z: np.ndarray, whole: bool, rays, stats: dict | None = None) -> str:
        """The algorithm this sun runs: ``self.algorithm``, or for ``auto`` the one
        ``algorithms.auto.choose`` picks (counted in ``stats``, else ``self.stats``)."""
        if self.algorithm != "auto":
            return self.algorithm
        from ..algorithms import auto
        if whole:
            if self._survey is None:
                self._survey = auto.survey(z)
            frac, lo, hi = self._survey
        else:
            frac, lo, hi = auto.survey(z)
        name, why = auto.choose(z.shape, frac, (lo, hi), rays, self.backend)
        auto.record(self.stats if stats is None else stats, name, why)
        return name

    def cast(self, region: Region, stats: dict | None = None) -> np.ndarray:
        """uint8 cast-shadow mask of ``region`` (1 shadow, 0 lit, 255 void)."""
        from ..algorithms import auto, brute
        from ..algorithms.frames import uniform_rays
        sub = self.z[region.rows, region.cols]
        if region.elevation <= 0:     # night
            return np.where(np.isnan(sub), np.uint8(255), np.uint8(1)).astype(np.uint8)
        el = min(region.elevation, 90.0)
        z, g, inner, whole = self._piece(region, el)
        rays = self.rays(g, region.azimuth, el)
        zmax = self.local_range[1] if whole else float(np.nanmax(z))
        algorithm = self.choose(z, whole, rays, stats)
        options = dict(self.options)
        # a carrier is only given for smap on the CPU (engine.windows.WindowLighting.carrier); it needs one ray
        carried = self.carry is not None and whole and uniform_rays(rays)
        by_brute = (not carried and self.backend == "cpu" and z.size > sub.size
                    and (auto.tile_by_brute(z.size, sub.size, (self.zmin, zmax), rays)
                         if algorithm == "bounds" else z.size > TILE_BRUTE_RATIO * sub.size))
        pyr = self.pyramid(z, whole) if self.backend == "cpu" else False
        if algorithm == "brute" and pyr is not False and not auto.pyramid_pays(
                z.shape, self.local_range if whole else (self.zmin, zmax), rays):
            pyr = False     # rays of a few steps: the plain march, no pyramid to build
        if self.backend == "cpu":   # every method marches some rays (refinements, fallbacks)
            options["pyramid"] = pyr
        if self.lift > 0.0:         # brute (for_lift), which starts each ray that much higher
            options["lift"] = self.lift
        if algorithm == "bounds" and whole and self.backend == "cpu":
            options["zrange"] = self.local_range     # known: saves bounds a pass
        if carried:
            out = self.carry.mask(z, rays, zmax, max(abs(self.zmin), abs(self.zmax)),
                                  *self.place, inner)
        elif by_brute:
            # a tile whose halo is much larger than itself: march only the tile's own cells
            # (brute, exact) rather than run the algorithm over the whole window
            out = np.zeros(z.shape, np.uint8)
            out[inner] = _TILE
            brute.refine(z, rays, out, _TILE, zmax, pyr, self.lift)
            if stats is not None:
                stats["tiles_marched_by_brute"] = stats.get("tiles_marched_by_brute", 0) + 1
        elif self.backend == "gpu":
            out = self._gpu_dem(z, whole).shadow_mask(rays, algorithm, zmax, stats, **options)
        else:
            out = REGISTRY[algorithm].cpu(z, rays, zmax, stats, **options)
        curved_natively = by_brute or algorithm in ("brute", "bounds") or (
            algorithm == "horizon" and options.get("method", "scan") == "scan")
        if rays.curved and not curved_natively:
            n = brute.refine(z, rays, out, 1, zmax, pyr if pyr is not False else True,
                             self.lift)
            if stats is not None:
                stats["curvature_refined_fraction"] = n / max(1, out.size)
        return out if out.shape == sub.shape else np.ascontiguousarray(out[inner])

    def field_ok(self, sun: SunOver, soft: bool) -> bool:
        """Whether a sun that varies across the raster is marched with every cell's own
        direction (``algorithms.per_cell_sun``) instead of tile by tile: hard shadows of an exact
        march-based method (soft shadows, smap, the horizon scan, sweep and the plain march,
        ``--no-pyramid``, keep the tiles)."""
        return self.sun_field and sun.fieldwise and field_method(self.algorithm, self.options,
                                                                 soft)

    def field_place(self):
        """(r0, c0, rows, cols): where ``z`` lies in the raster the sun's lattice spans (a
        window of a larger raster, ``engine.windows``), for ``algorithms.per_cell_sun``."""
        if self.place is None:
            return (0, 0, *self.z.shape)
        (r0, _, c0, _), shape = self.place
        return (r0, c0, *shape)

    def cast_field(self, sun: SunOver, stats: dict | None = None) -> np.ndarray:
        """uint8 cast-shadow mask of all of ``z``, each cell with its own sun interpolated
        on ``sun.lattice`` (1 shadow, 0 lit, 255 void; a cell whose sun is below the horizon
        is in shadow). The method and the curvature are the raster's centre sun's
        (``sun.azimuth``, ``sun.elevation``), in a window as on the whole raster."""
        from ..algorithms import per_cell_sun
        c = self.curvature_used_for(sun.azimuth, max(sun.elevation, 1e-6))
        zmax = self.local_range[1]
        place = self.field_place()
        if self.backend == "gpu":
            out = per_cell_sun.shadow_mask_gpu(self._gpu_dem(self.z, True), self.grid, sun.lattice, c,
                                        zmax, place, self.lift)
        else:
            from ..algorithms import bounds
            # the method for the centre's sun (auto: its estimate), with every cell's own ray
            name = self.choose(self.z, True, sun_rays(self.grid, sun.azimuth,
                                                      min(max(sun.elevation, 1e-6), 90.0)),
                               stats)
            if name == "bounds":
                out = bounds.shadow_mask_field(self.z, self.grid, sun.lattice, c, zmax, stats,
                                               self.pyramid(self.z, True), self.local_range,
                                               place)
            else:
                out = per_cell_sun.shadow_mask(self.z, self.grid, sun.lattice, c, zmax,
                                        self.pyramid(self.z, True), place, self.lift)
        if stats is not None:
            stats["sun_field"] = stats.get("sun_field", 0) + 1
        return out

    def visible_fraction(self, region: Region) -> np.ndarray:
        """float32 visible fraction (0..1) of the solar disk over ``region`` (NaN on voids),
        from the exact horizon angle toward the sun against its elevation +- its radius."""
        from ..algorithms import horizon as hz
        sub = self.z[region.rows, region.cols]
        if region.elevation + SUN_RADIUS_DEG <= 0:
            return np.where(np.isnan(sub), np.float32(np.nan), np.float32(0.0)).astype(np.float32)
        z, g, inner, whole = self._piece(region, region.elevation - SUN_RADIUS_DEG)
        rays = self.rays(g, region.azimuth, max(min(region.elevation, 90.0), 1e-6))
        # only horizons across the disk matter: below its lower edge the disk is whole, above
        # its upper edge hidden (the scan starts at the one and stops at the other)
        lo, hi = region.elevation - SUN_RADIUS_DEG, region.elevation + SUN_RADIUS_DEG
        if self.backend == "gpu":
            beta = hz.horizon_angles_gpu(self._gpu_dem(z, whole), rays, floor_deg=lo, cap_deg=hi,
                                         lift=self.lift)
        else:
            beta = hz.horizon_angles(z, rays, pyramid=self.pyramid(z, whole) or True,
                                     floor_deg=lo, cap_deg=hi, lift=self.lift)
        if beta.shape != sub.shape:
            beta = beta[inner]
        frac = disk_fraction(beta, region.elevation).astype(np.float32)
        frac[np.isnan(sub)] = np.nan
        return frac

    def incidence(self, region: Region) -> np.ndarray:
        """cos of the incidence angle of the sun of ``region`` on its cells (float32, NaN voids)."""
        from ..algorithms.relief import incidence
        return incidence(self.z, self.grid, region.azimuth, region.elevation, region.rows,
                         region.cols)

    def gpu_report(self) -> dict | None:
        """The GPU figures of the whole-raster GpuDem (None when nothing ran on the GPU)."""
        return self._gpu.report() if self._gpu is not None else None

    def report(self) -> dict:
        return curvature_report(self.curvature, self.curvature_used, self.body, self.k)


KINDS = ("shadow", "classes", "hillshade", "sun")


def field_method(algorithm: str, options: dict, soft: bool) -> bool:
    """Whether this method marches each cell with its own sun when the sun varies across the
    raster (``Shader.field_ok``; ``engine.windows.WindowLighting.pieces`` plans such windows)."""
    spec = REGISTRY.get(algorithm)
    return (not soft and spec is not None and spec.field_march
            and options.get("pyramid", True) is not False)


def render(shader: Shader, sun: SunOver, kind: str = "shadow", *, soft: bool = False,
           self_shadow: bool = False, ambient: float = 0.2, stats: dict | None = None,
           previous: tuple[np.ndarray, int] | None = None) -> np.ndarray:
    """What one sun makes of the DEM, over the whole raster.

    Tile by tile when the sun is per tile. With ``previous`` after :meth:`Shader.update`, only
    the cells the edits since then can have changed are made again (``rerender``), the rest
    copied from it (it is not modified); the result is the product a new Shader of the edited
    DEM gives. On at most one of numba's threads per ``CELLS_PER_THREAD`` cells of the DEM
    (:func:`threads_for`).

    Parameters
    ----------
    shader : Shader
        The prepared DEM.
    sun : sun.SunOver
        The sun: one direction (azimuth and elevation in degrees) for the raster, or one per
        tile.
    kind : {"shadow", "classes", "hillshade", "sun"}, default "shadow"
        The product (see Returns).
    soft : bool, default False
        The visible fraction of the solar disk instead of hard shadows (not with ``classes``).
    self_shadow : bool, default False
        Surfaces facing away from the sun count as shadow (``shadow``), or get no sun (``sun``,
        soft ``shadow``).
    ambient : float, default 0.2
        The hillshade's ambient light (dimensionless, 0..1).
    stats : dict, optional
        Receives the algorithm's figures.
    previous : (numpy.ndarray, int), optional
        ``(product, version)``: what this call made for the same sun, kind and options when
        ``shader.version`` was ``version``.

    Returns
    -------
    numpy.ndarray
        The raster's shape:

        * ``shadow``: uint8 1 shadow / 0 lit / 255 void; with ``soft`` float32 visible fraction
          of the solar disk (0..1, NaN on voids);
        * ``classes``: uint8 0 lit, 1 self-shadow (facing away), 2 cast shadow, 255 void;
        * ``hillshade``: uint8 shaded relief 1..255 (0 void): 1 + 254 * (ambient + (1 - ambient)
          * max(0, cos i) * lit), i the sun's incidence angle, lit 1/0 (or the visible fraction
          with ``soft``);
        * ``sun``: float32 direct sun 0..1 (lit, or the visible fraction with ``soft``), NaN on
          voids: what sun hours add up (times the hours of each sample).

    Raises
    ------
    HillshadeError
        An unknown ``kind``, ``classes`` with ``soft``, a ``previous`` version this Shader never
        had.
    """
    if kind not in KINDS:
        raise HillshadeError(f"unknown product {kind!r}")
    if kind == "classes" and soft:
        raise HillshadeError("classes are for hard shadows: --classes and --soft do not go together")
    with threads_for(shader.z.size):
        return _render(shader, sun, kind, soft, self_shadow, ambient, stats, previous)


def _render(shader, sun, kind, soft, self_shadow, ambient, stats, previous):
    if previous is not None:
        out = rerender(shader, sun, kind, soft, self_shadow, ambient, stats, previous)
        if out is not None:
            return out
    shape = shader.z.shape
    regions = sun.regions(shape)
    # a sun that varies across the raster: every cell's own direction in one march when the
    # method allows (the tiles then only serve the incidence of the relief)
    whole = shader.cast_field(sun, stats) if shader.field_ok(sun, soft) else None
    if len(regions) == 1:
        return render_region(shader, regions[0], kind, soft, self_shadow, ambient, stats, whole)
    out = None
    for r in regions:   # each tile into place as it is made: no list of all tiles' arrays
        part = render_region(shader, r, kind, soft, self_shadow, ambient, stats,
                              None if whole is None else whole[r.rows, r.cols])
        if out is None:
            out = np.empty(shape, part.dtype)
        out[r.rows, r.cols] = part
    return out


def exact_options(algorithm: str, options: dict) -> bool:
    """Whether ``algorithm`` with ``options`` is exact (equals brute cell for cell)."""
    spec = REGISTRY[algorithm]
    return spec.exact and not any(
        opt.approximate and options.get(opt.keyword) not in (None, opt.default)
        for opt in spec.options)


def rerender(shader: Shader, sun: SunOver, kind: str, soft: bool, self_shadow: bool,
             ambient: float, stats: dict | None, previous) -> np.ndarray | None:
    """``render``'s product brought up to date from ``previous`` = (product, version): for
    each edit since ``version`` the cells of ``Shader.affected_bounds`` are made again (cast
    shadows by brute's march of those cells over the whole edited DEM: an exact method's mask;
    soft shadows and the relief by ``render_region``), the rest copied. None where a full
    render is needed: a sun per tile or per cell, the sun (its lowest edge for ``soft``) at or
    below the horizon, an approximate method (its errors depend on the whole raster: its own
    full render, not a patch), or Earth curvature "auto" turned on or off by the edits.

    The number of cells made again is added to ``stats["rerendered_cells"]`` (full renders
    count in ``stats["rerender_full"]``); ``stats`` None: ``shader.stats``."""
    from ..algorithms import brute
    counts = shader.stats if stats is None else stats
    prev, since = previous
    edits = shader.edits_since(since)
    if np.shape(prev) != shader.z.shape:
        raise HillshadeError(f"previous: a product of shape {np.shape(prev)} for a DEM of "
                             f"{shader.z.shape}")
    az, el = sun.azimuth, min(sun.elevation, 90.0)
    low = sun.elevation - SUN_RADIUS_DEG if soft else sun.elevation
    full = (sun.tiles is not None or low <= 0.0
            or not (soft or exact_options(shader.algorithm, shader.options)))
    if not full and edits and shader.curvature == "auto":
        el_c = max(el, 1e-6) if soft else el
        then = curvature_coefficient("auto", shader.body, shader.k, shader.extent_m,
                                     edits[0][3], az, el_c)
        full = then != shader.curvature_for(az, el_c)
    if full:
        counts["rerender_full"] = counts.get("rerender_full", 0) + 1
        return None
    out = np.array(prev, copy=True)
    cells = 0
    rays = None
    for _, bounds, top, _ in edits:
        r0, r1, c0, c1 = shader.affected_bounds(bounds, top, az, low)
        region = Region(slice(r0, r1), slice(c0, c1), sun.azimuth, sun.elevation)
        cast = None
        if not soft:
            if rays is None:
                rays = shader.rays(shader.grid, az, el)
                # the pyramid kept up to date by ``update`` (the GPU's host copy when it has
                # one; --no-pyramid: the plain march, the same mask)
                pyr = getattr(shader._gpu, "_host_pyramid", None)
                if pyr is None or shader.options.get("pyramid", True) is False:
                    pyr = shader.pyramid(shader.z, True)
            cast = brute.march_box(shader.z, rays, (r0, r1, c0, c1), shader.local_range[1],
                                   pyr, shader.lift)
        out[r0:r1, c0:c1] = render_region(shader, region, kind, soft, self_shadow, ambient,
                                          stats, cast)
        cells += (r1 - r0) * (c1 - c0)
    counts["rerendered_cells"] = counts.get("rerendered_cells", 0) + cells
    return out


def render_region(shader, region, kind, soft, self_shadow, ambient, stats, cast=None):
    sub = shader.z[region.rows, region.cols]
    need_cos = kind in ("classes", "hillshade") or self_shadow
    # the voids, where a product needs them (a hard mask has them: 0.1 s of a 10000² run)
    void = np.isnan(sub) if need_cos or kind != "shadow" or soft else None
    cosi = shader.incidence(region) if need_cos and region.elevation > -SUN_RADIUS_DEG else None
    if soft:
        lit = shader.visible_fraction(region)          # float32, NaN voids
    elif cast is None:
        cast = shader.cast(region, stats)              # uint8 1/0/255
    elif self_shadow:
        cast = cast.copy()                             # (self-shadow marks it below)
    # valid cells whose surface faces away from the sun (all of them with the sun far below)
    away = (~void if cosi is None else (cosi <= 0) & ~void) if need_cos else None
    if kind == "classes":
        out = np.where(cast == 1, np.uint8(CAST_SHADOW), np.uint8(LIT)).astype(np.uint8)
        out[away] = SELF_SHADOW
        out[void] = NODATA
        return out
    if kind == "hillshade":
        light = (lit if soft else (cast == 0).astype(np.float32))
        direct = np.maximum(cosi, 0.0) * light if cosi is not None else np.zeros_like(light)
        illum = ambient + (1.0 - ambient) * np.nan_to_num(direct)
        out = (1.0 + np.rint(254.0 * illum)).astype(np.uint8)
        out[void] = 0
        return out
    if kind == "shadow" and not soft:
        if self_shadow:
            cast[away] = 1
        return cast
    # float products: soft shadow, or direct sun for sun hours
    light = lit if soft else np.where(void, np.float32(np.nan),
                                      (cast == 0).astype(np.float32)).astype(np.float32)
    if self_shadow:
        light[away] = 0.0
    return light


def horizon_shader(z: np.ndarray, grid: Grid, backend: str = "cpu", curvature="auto",
                   refraction_k: float | None = None, body: Body | None = None,
                   method: str = "scan") -> Shader:
    """A :class:`Shader` for the horizon products (horizon, profile, skyview), curvature
    "auto" (or None) resolved as they do: on for a raster more than 1 km across (their rays run
    to its edge whatever the sun), off for the hull, which has none."""
    sh = Shader(z, grid, "horizon", {}, backend, "auto" if curvature is None else curvature,
                refraction_k, body, (0.0, 0.0))
    if sh.curvature == "auto":
        sh.curvature = sh.extent_m > 1000.0 and method == "scan"
    return sh
