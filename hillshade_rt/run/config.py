"""What a run is asked to do, as plain data: the DEM's read options, the sun, the algorithm and
its options, the product and where it goes. Every command's config is here, keyword-only
(``ShadeConfig``, ``SunHoursConfig``, ``HorizonConfig``, ``IrradianceConfig``, ``IllumConfig``,
``LightConfig``, ``LightmapConfig``, ``SubsolarConfig``, ``SkyviewConfig``, ``QueryConfig``,
``ProfileConfig``, ``ViewConfig``, ``AnimateConfig``); the command line, ``api``, xarray and
QGIS (through the command line) build them, and a lighting run turns its config into one
``engine.lighting.Lighting`` (``ShadeConfig.lighting``). The checks of the options'
combinations live here (one place for every front door), raising
:class:`~hillshade_rt.errors.UsageProblem` (exit status 2 on the command line) for a bad
combination and :class:`~hillshade_rt.errors.HillshadeError` for a bad value.

The messages name the command line's options (``--window-size``): the API takes the same names
as keywords, so a Python caller reads them as its own arguments.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field
from typing import Callable

from ..errors import HillshadeError, UsageProblem

# the option names the command line and the API share, each set once: the sun's place and
# atmosphere (``sun.SunRequest.at_place``), all the sun options of the lighting commands
# (``SunRequest.from_options``), the DEM's read options (``ReadOptions``)
PLACE_KEYS = ("tz", "lat", "lon", "pressure", "temperature", "no_refraction", "sun_tolerance")
SUN_KEYS = ("azimuth", "elevation", "time", "start", "end", "step", "sun_from_stac") + PLACE_KEYS
READ_KEYS = ("band", "nodata", "z_factor", "pixel_size", "raw_shape", "raw_dtype",
             "raw_byteorder")

# the smallest --window-size side: smaller windows make the run slow for nothing (each window has
# its halo and its own read; 1x1 windows of a 465x457 DEM are 212 k windows, minutes of work)
MIN_WINDOW_SIDE = 64

PRODUCTS = ("shadow", "classes", "hillshade")

# --worker-timeout: how long a Dask run waits without any worker (none at the start, or every
# one lost) before it fails; long enough for a worker to restart or an autoscaler to add one
DEFAULT_WORKER_TIMEOUT = 60.0


@dataclass(kw_only=True)
class ReadOptions:
    """How to read a DEM (the command line's ``dem_options``): band, nodata, z-factor, the
    spacing of an ungeoreferenced grid and the layout of a raw one (texts as given; parsed
    where the DEM is read)."""

    band: int = 1
    nodata: float | None = None
    z_factor: float = 1.0
    pixel_size: object = None
    raw_shape: object = None
    raw_dtype: str | None = None
    raw_byteorder: str | None = None
    # --context RASTER: the DEM is a tile of this raster (same grid), whose heights its rays
    # see (run.context)
    context: str | None = None

    def inputs(self) -> list:
        """The paths read besides the DEMs (no output may be one): the context."""
        return [] if self.context is None else [self.context]

    def check_context(self, dems, **given) -> None:
        """The options ``--context`` does not go with (``given``: flag -> whether given), and
        one DEM only: usage errors."""
        if self.context is None:
            return
        dems = [dems] if isinstance(dems, (str, os.PathLike)) else list(dems)
        if len(dems) != 1:
            raise UsageProblem("--context takes one DEM, the tile (the context is the mosaic "
                               "of the tiles)")
        for flag, on in given.items():
            if on:
                raise UsageProblem(f"--context does not go with {flag}")

    def open_area(self, dems):
        """The tile ``dems`` placed in the context (``run.context.Area``), both opened."""
        from .context import open_area
        return open_area(self, dems)

    def options(self):
        """As ``io.DemOptions`` (the texts parsed)."""
        from ..io.source import DemOptions
        return DemOptions.parse(band=self.band, nodata=self.nodata, z_factor=self.z_factor,
                                pixel_size=self.pixel_size, raw_shape=self.raw_shape,
                                raw_dtype=self.raw_dtype, raw_byteorder=self.raw_byteorder)

    def open(self, paths, windows: bool = False):
        """The DEM (or the mosaic of tiles) at ``paths`` opened and checked, not read
        (``io.open_dem``): ``.read()`` it whole or ``.reader()`` it in windows. ``windows``: it
        will be read in windows (standard input, read whole only, is refused before it is
        read)."""
        from ..io.source import open_dem
        return open_dem(paths, self.options(), windows=windows)

    def read(self, path):
        """The whole DEM at ``path`` (``io.read_dem``)."""
        with self.open(path) as src:
            return src.read()


def set_threads(ro: "RunOptions") -> int:
    """Set numba's thread count from ``ro.threads`` (``--threads``; None: all cores, numba's
    ``NUMBA_NUM_THREADS``), capped at what numba started with; returns the count in use. Every
    run calls this one function, so that no command accepts ``--threads`` and ignores it."""
    import numba

    if ro.threads is not None:
        numba.set_num_threads(min(ro.threads, numba.config.NUMBA_NUM_THREADS))
    return numba.get_num_threads()


def say_nothing(kind: str, message: str) -> None:
    """The default ``say`` of a run: silent."""


@dataclass(kw_only=True)
class RunOptions:
    """How a run goes, whatever it makes: backend, threads, report, overwrite, messages.
    ``say(kind, message)`` receives the run's messages for people: kind "compile" (numba is
    about to compile kernels), "summary" (the one-line summary) and "note"."""

    backend: str = "auto"
    threads: int | None = None
    report_path: str | None = None
    overwrite: bool = False
    quiet: bool = False
    progress: str = "bar"       # --progress: "bar" (tqdm's, on a terminal) or "json" lines
    fmt: str | None = None
    preview: str | None = None
    say: Callable[[str, str], None] = say_nothing
    # --co NAME=VALUE: GDAL creation options of the rasters written, over the tool's defaults
    # ({NAME: VALUE}, io.parse_creation_options)
    creation_options: dict = field(default_factory=dict)
    # --worker-timeout: seconds a Dask run (--scheduler) waits without any worker, at the start
    # or after every worker is lost, before it fails (run.dask.DaskSession)
    worker_timeout: float = DEFAULT_WORKER_TIMEOUT

    def __post_init__(self):
        import math
        from ..io.raster import parse_creation_options
        self.creation_options = parse_creation_options(self.creation_options)
        try:
            t = float(self.worker_timeout)
        except (TypeError, ValueError):
            t = math.nan
        if not (math.isfinite(t) and t > 0):
            raise UsageProblem(f"--worker-timeout must be a positive number of seconds, got "
                               f"{self.worker_timeout!r}")
        self.worker_timeout = t


@dataclass(kw_only=True)
class ShadeConfig:
    """A ``shadow`` / ``hillshade`` run: ``files`` (DEMs, and OUTPUT last when neither
    ``output`` nor ``output_pattern`` is given), the product ``kind`` ("shadow", "classes",
    "hillshade"), the sun options (``sun``: ``SUN_KEYS``; ``default_sun`` when none is given),
    the algorithm and its options, physics, windows and Dask."""

    files: list
    kind: str = "shadow"
    sun: dict = field(default_factory=dict)
    default_sun: tuple | None = None
    algorithm: str = "auto"
    options: dict = field(default_factory=dict)
    algorithm_explicit: bool = True     # named by the user (not the default)
    curvature: object = None            # None: "auto"
    refraction_k: float | None = None
    soft: bool = False
    self_shadow: bool = False
    ambient: float = 0.2
    scale: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    output: str | None = None
    output_pattern: str | None = None
    max_memory: object = None
    window_size: object = None
    cog: bool = False
    scheduler: object = None
    height_above_ground: float = 0.0    # metres: each cell's ray starts this far above it
    stac_item: str | None = None        # --stac-item: a STAC item describing OUTPUT
    command: str | None = None          # the command line, as the STAC item records it
    vector: str | None = None           # --vector: the shadow polygons (GPKG, GeoJSON, FGB)
    vector_connectivity: int = 4        # cells of a polygon joined by edges (4) or corners (8)

    def check(self) -> None:
        """The combinations no run can take (before the sun is looked at, as before). With a
        height above the ground, ``algorithm`` becomes the one that marches it
        (``algorithms.for_lift``: auto -> brute)."""
        import math
        from ..engine.products import product
        if self.kind not in PRODUCTS:
            raise HillshadeError(f"product must be one of {', '.join(PRODUCTS)}, got {self.kind!r}")
        product(self.kind, self.soft)     # classes are hard only
        if self.vector is not None:
            self.check_vector()
        self.algorithm = check_lift(self.height_above_ground, self.algorithm, self.soft)
        if self.scale is not None:
            if not (math.isfinite(self.scale) and self.scale > 0):
                raise UsageProblem(f"--scale must be a positive number, got {self.scale}")
            if self.read.pixel_size is not None:
                raise UsageProblem("--scale and --pixel-size do not go together")

    def check_vector(self) -> None:
        """--vector: a local file of a known format (usage errors), polygons of a mask (the
        shadow or classes product, hard shadows); --vector-connectivity 4 or 8."""
        from ..io.vector import check_connectivity, check_vector_path
        self.vector = check_vector_path(self.vector)
        self.vector_connectivity = check_connectivity(self.vector_connectivity)
        if self.kind == "hillshade":
            raise UsageProblem("--vector writes polygons of shadow: it goes with shadow, not "
                               "hillshade")
        if self.soft:
            raise UsageProblem("--vector writes polygons of the shadow mask: not with --soft "
                               "(fractions of the sun's disk)")

    def lighting(self, backend: str):
        """How the terrain is lit (``engine.lighting.Lighting``), on ``backend`` (chosen);
        after :meth:`check`."""
        from ..engine.lighting import Lighting
        return Lighting(algorithm=self.algorithm, options=self.options, backend=backend,
                        curvature=self.curvature, refraction_k=self.refraction_k,
                        soft=self.soft, self_shadow=self.self_shadow, ambient=self.ambient,
                        lift=self.height_above_ground)


@dataclass(kw_only=True)
class SunHoursConfig:
    """A ``sun-hours`` run: the hours of direct sun per cell over a day or a range of days."""

    dem: str
    output: str
    date: str
    end_date: str | None = None
    step: str = "10min"
    place: dict = field(default_factory=dict)     # tz, lat, lon, pressure, temperature,
    algorithm: str = "auto"                       # no_refraction, sun_tolerance
    curvature: object = None
    refraction_k: float | None = None
    soft: bool = False
    self_shadow: bool | None = True   # None: on with the observer on the ground, off above it
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    height_above_ground: float = 0.0  # metres: each cell's ray starts this far above it
    max_memory: object = None         # windows (run.sun_hours_windows) when the DEM needs more
    window_size: object = None        # windows of this many output cells, whatever the size
    scheduler: object = None          # the windows as Dask tasks
    monthly: bool = False             # and the hours of each month, a band each (in memory)
    command: str | None = None        # the command line (a CF dataset's history)

    def check(self) -> None:
        """The height above the ground (``check_lift``: ``algorithm`` becomes the one that
        marches it) and what --self-shadow means then: not given (None), the surface's
        orientation counts on the ground only (an observer above the ground does not stand on
        the facet)."""
        self.algorithm = check_lift(self.height_above_ground, self.algorithm, self.soft)
        if self.self_shadow is None:
            self.self_shadow = self.height_above_ground == 0.0

    def lighting(self, backend: str):
        """How the terrain is lit (``engine.lighting.Lighting``), on ``backend`` (chosen);
        after :meth:`check`."""
        from ..engine.lighting import Lighting
        return Lighting(algorithm=self.algorithm, backend=backend, curvature=self.curvature,
                        refraction_k=self.refraction_k, soft=self.soft,
                        self_shadow=self.self_shadow, lift=self.height_above_ground)


def check_lift(height: float, algorithm: str, soft: bool) -> str:
    """``--height-above-ground`` checked (metres, finite, >= 0) against the other options; the
    algorithm that marches it (``algorithms.for_lift``; ``algorithm`` itself at 0). ``soft``
    takes it too (the horizon scan's lift: ``Shader.visible_fraction``)."""
    import math
    from ..algorithms import for_lift
    try:
        h = float(height)
    except (TypeError, ValueError):
        raise UsageProblem(f"--height-above-ground must be a number of metres, got "
                           f"{height!r}") from None
    if not (math.isfinite(h) and h >= 0.0):
        raise UsageProblem(f"--height-above-ground must be a finite number of metres >= 0, "
                           f"got {height}")
    if h == 0.0:
        return algorithm
    return for_lift(algorithm)


@dataclass(kw_only=True)
class HorizonConfig:
    """A ``horizon`` run: the horizon angle toward one azimuth of every cell."""

    dem: str
    output: str
    azimuth: float | None = None
    method: str = "scan"
    sample_spacing: int = 1
    curvature: object = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    directions: int | None = None     # N azimuths clockwise from north, 0 first: N bands
    distance: str | None = None       # a second raster: metres to each cell's horizon point
    max_distance: float | None = None  # metres: terrain farther along a ray is ignored
    max_memory: object = None          # windows (run.horizon_windows) when the DEM needs more
    window_size: object = None         # windows of this many output cells, whatever the size
    scheduler: object = None           # the windows as Dask tasks
    height_above_ground: float = 0.0   # metres: the observer of every cell stands this high
    start: float | None = None         # r.horizon's start/end/step, clockwise from north:
    end: float | None = None           # the azimuths start, start + step, ... before end
    step: float | None = None
    angle_unit: str = "degrees"        # the angles written: "degrees" or "radians" (-d)

    def many(self) -> bool:
        """One band per direction (--directions or --step), not --azimuth's single band."""
        return self.azimuth is None

    def series(self) -> tuple[float, float, float] | None:
        """(start, end, step) of --start/--end/--step (start 0 and end start + 360 when not
        given), or None without --step."""
        if self.step is None:
            return None
        start = 0.0 if self.start is None else float(self.start)
        return start, start + 360.0 if self.end is None else float(self.end), float(self.step)

    def azimuths(self) -> list[float]:
        """The azimuths of the bands: ``azimuth``, the ``directions`` ones, or those of
        ``start``/``end``/``step``; exactly one of the three (a usage error otherwise)."""
        from ..model.geometry import equal_azimuths, normalize_azimuth
        if self.angle_unit not in ANGLE_UNITS:
            raise UsageProblem(f"--angle-unit must be one of {', '.join(ANGLE_UNITS)}, got "
                               f"{self.angle_unit!r}")
        if self.step is None and (self.start is not None or self.end is not None):
            raise UsageProblem("--start and --end go with --step (the angle between "
                               "directions)")
        given = [self.azimuth is not None, self.directions is not None, self.step is not None]
        if sum(given) != 1:
            raise UsageProblem("give --azimuth A (one direction), --directions N or --start/"
                               "--end/--step, one of them")
        if self.directions is not None:
            n = int(self.directions)
            if not 8 <= n <= 360:
                raise UsageProblem(f"--directions must be between 8 and 360, got {n}")
            return equal_azimuths(360.0 / n)
        if self.step is not None:
            return series_azimuths(*self.series())
        return [normalize_azimuth(self.azimuth)]


# the units horizon angles are written in (r.horizon's -d flag: degrees; its default radians)
ANGLE_UNITS = ("degrees", "radians")
# the most directions --start/--end/--step may ask for (every 0.1 degree)
MAX_DIRECTIONS = 3600


def series_azimuths(start: float, end: float, step: float) -> list[float]:
    """The azimuths of ``horizon --start --end --step`` (degrees clockwise from north, each in
    [0, 360)): start, start + step, ... as r.horizon counts them, floor((end - start) / step)
    of them, so the last one is before ``end``, and where the step does not divide the range
    the remainder gives no direction (r.horizon's ``(int)((end - start) / step)``). Where it
    divides, direction k is start + (end - start) * k / n: with start 0 and end 360 the
    azimuths of ``--directions n``, bit for bit. Usage errors: ``start`` outside [0, 360),
    ``end`` not in (start, start + 360], ``step`` not > 0, or more than ``MAX_DIRECTIONS``."""
    from ..model.geometry import normalize_azimuth
    for name, v in (("--start", start), ("--end", end), ("--step", step)):
        if not math.isfinite(v):
            raise UsageProblem(f"{name} must be a finite number of degrees, got {v}")
    if not 0.0 <= start < 360.0:
        raise UsageProblem(f"--start must be in [0, 360) degrees clockwise from north, got "
                           f"{start:g}")
    if not start < end <= start + 360.0:
        raise UsageProblem(f"--end must be after --start and at most one turn on (--start "
                           f"{start:g}: {start:g} < --end <= {start + 360.0:g}), got {end:g}")
    if not step > 0.0:
        raise UsageProblem(f"--step must be a positive number of degrees, got {step:g}")
    span = end - start
    n = int(math.floor(span / step + 1e-9))
    if n < 1:
        raise UsageProblem(f"--step {step:g} is larger than --end - --start ({span:g}): no "
                           "direction")
    if n > MAX_DIRECTIONS:
        raise UsageProblem(f"--start/--end/--step give {n} directions, more than "
                           f"{MAX_DIRECTIONS}: use a larger --step")
    if abs(n * step - span) <= 1e-9 * max(1.0, span):
        return [normalize_azimuth(start + span * k / n) for k in range(n)]
    return [normalize_azimuth(start + k * step) for k in range(n)]


def inputs_and_output(files, output, pattern, optional: bool = False):
    """rio-style paths: ``DEM... OUTPUT``, or every path a DEM with -o/--output or
    --output-pattern. ``optional`` (--vector, which may stand for the raster): one path alone
    is the DEM, no OUTPUT (two or more: the last is OUTPUT, as without it)."""
    from ..io import is_gdal_name    # a DEM the local disk cannot tell about (/vsizip/, URLs)
    files = list(files)
    if output is not None or pattern is not None:
        if output is not None and pattern is not None:
            raise UsageProblem("give -o/--output or --output-pattern, not both")
        given = "--output-pattern" if pattern is not None else "-o/--output"
        last = files[-1]
        if len(files) > 1 and not (os.path.exists(last) or is_gdal_name(last)):
            # `shadow dem.tif out.tif --output-pattern 'x_{index}.tif'`: out.tif is no DEM
            raise UsageProblem(f"{last} does not exist: give OUTPUT or {given}, not both "
                               f"(with {given} every path is a DEM)")
        return files, output
    if len(files) < 2:
        if optional and files:
            return files, None
        raise UsageProblem("give OUTPUT or --output-pattern (one of them)")
    return files[:-1], files[-1]


def parse_window_size(text):
    """--window-size ROWS[xCOLS] as (rows, cols) (also an int or a pair); a malformed or too
    small size is a usage error. (``engine.windows.plan`` itself takes any window shape.)"""
    if text is None:
        return None
    if isinstance(text, int):
        text = f"{text}x{text}"
    elif isinstance(text, (tuple, list)):
        text = "x".join(str(int(v)) for v in text)
    m = re.fullmatch(r"\s*(\d+)\s*(?:[xX,]\s*(\d+))?\s*", str(text))
    if not m:
        raise UsageProblem(f"--window-size must be ROWS or ROWSxCOLS (e.g. 2048x2048), got "
                           f"{text!r}")
    rows = int(m.group(1))
    cols = int(m.group(2)) if m.group(2) else rows
    if min(rows, cols) < MIN_WINDOW_SIDE:
        raise UsageProblem(f"--window-size {str(text).strip()}: "
                           f"windows must be at least {MIN_WINDOW_SIDE} cells on each side "
                           f"(e.g. {MIN_WINDOW_SIDE}x{MIN_WINDOW_SIDE}; 1024x1024 or more is "
                           "faster)")
    return rows, cols


def apply_scale(d, scale):
    """gdaldem's -s: ground spacing = the transform's pixel size times ``scale``."""
    from ..model.geometry import Grid, orientation
    if d.transform is None:
        raise UsageProblem("--scale needs a georeferenced DEM; use --pixel-size")
    cs, rs = orientation(d.transform)
    rows, cols = d.shape
    d.grid = Grid.uniform(rows, cols, abs(d.transform.a) * scale, abs(d.transform.e) * scale,
                          cs, rs, f"--scale {scale:g} x transform units")


@dataclass(kw_only=True)
class IrradianceConfig:
    """An ``irradiance`` run. The period: ``date`` (and ``end_date``), or ``start`` and
    ``end``; the open sky: ``clear_sky`` (None: ineichen) with ``linke_turbidity``, or the
    measured series of the CSV file ``ghi``."""

    dem: str
    output: str
    date: str | None = None
    end_date: str | None = None
    start: str | None = None
    end: str | None = None
    step: str = "15min"
    clear_sky: str | None = None          # None: "ineichen" (and not with ``ghi``)
    # a number, 12 monthly numbers ("a,b,..." or a sequence), a raster or a pattern with
    # {month} (run.sky_inputs); linke_turbidity None: pvlib's climatological lookup
    linke_turbidity: float | str | None = None
    albedo: float | str = 0.2
    # r.sun's real sky (coeff_bh, coeff_dh): the clear sky's beam and diffuse times these
    # (0..1), the same forms; None: 1 (the clear sky)
    beam_index: float | str | None = None
    diffuse_index: float | str | None = None
    ghi: str | None = None                # a CSV: time, ghi[, dni, dhi]
    mean: bool = False                    # mean W/m² over the period instead of Wh/m²
    daily_mean: bool = False              # Wh/m² per day: the energy over the period's days
    monthly: bool = False                 # and the global energy of each month, a band each
    soft: bool = False
    perez: bool = False
    skyview_directions: int = 32
    place: dict = field(default_factory=dict)    # PLACE_KEYS: tz, lat, lon, pressure, ...
    algorithm: str = "auto"
    curvature: object = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    height_above_ground: float = 0.0      # metres: the receiving surface stands this high
    sky_view: str | None = None           # Dozier's Vd read from this file (skyview's output)
    sky_view_out: str | None = None       # the Vd computed written to this file too
    max_memory: object = None   # windows (run.irradiance_windows) when the DEM needs more
    window_size: object = None  # windows of this many output cells, whatever the size
    scheduler: object = None    # the windows as Dask tasks
    # (check() parses linke_turbidity and albedo into run.sky_inputs.SkyValue)
    linke_input: object = field(default=None, init=False, repr=False, compare=False)
    albedo_input: object = field(default=None, init=False, repr=False, compare=False)
    beam_input: object = field(default=None, init=False, repr=False, compare=False)
    diffuse_input: object = field(default=None, init=False, repr=False, compare=False)

    def sky_inputs(self) -> list:
        """The files of --albedo, --linke-turbidity, --beam-index and --diffuse-index (after
        :meth:`check`)."""
        return [p for v in (self.albedo_input, self.linke_input, self.beam_input,
                            self.diffuse_input) if v is not None for p in v.inputs()]

    def sky_per_cell(self) -> bool:
        """Whether the open sky differs from cell to cell: --linke-turbidity, --beam-index or
        --diffuse-index as rasters (after :meth:`check`)."""
        return any(v is not None and v.rasters
                   for v in (self.linke_input, self.beam_input, self.diffuse_input))
    times: tuple = ()                     # --time: instants (W/m² at each, run.irradiance_instant)
    instant: bool = False                 # --instant: the period's times as instants, not sums
    command: str | None = None            # the command line (a time cube's history)

    def instants(self) -> bool:
        """Whether the run writes instants (``--time`` or ``--instant``: r.sun's mode 1) rather
        than the period's sums."""
        return bool(self.times) or bool(self.instant)

    def check(self):
        """The options' combinations and values (UsageProblem: exit status 2)."""
        from ..engine.irradiance import CLEAR_SKY_MODELS, check_options
        from .sky_inputs import SkyValue
        self.albedo_input = SkyValue.parse("--albedo", self.albedo, 0.0, 1.0)
        self.linke_input = SkyValue.parse("--linke-turbidity", self.linke_turbidity, 1.0, 10.0,
                                          " (clean, dry air ~2, hazy ~5)")
        self.beam_input = SkyValue.parse("--beam-index", self.beam_index, 0.0, 1.0)
        self.diffuse_input = SkyValue.parse("--diffuse-index", self.diffuse_index, 0.0, 1.0)
        if self.mean and self.daily_mean:
            raise UsageProblem("--mean (W/m2) and --daily-mean (Wh/m2 per day): give one")
        if self.sky_view is not None and self.sky_view_out is not None:
            raise UsageProblem("--sky-view-out writes the sky view the run computes; with "
                               "--sky-view it computes none: give one of them")
        by_date = self.date is not None or self.end_date is not None
        by_time = self.start is not None or self.end is not None
        if self.instants() and (self.monthly or self.daily_mean):
            raise UsageProblem("--monthly and --daily-mean are a period's sums: the instants of "
                               "--time or --instant have none")
        if self.instants() and self.mean:
            raise UsageProblem("--mean averages a period's sums: the instants of --time or "
                               "--instant are W/m2 already")
        if self.times and (by_date or by_time):
            raise UsageProblem("--time gives the instants: --date, --end-date, --start and --end "
                               "do not go with it")
        if not self.times and by_date == by_time:
            raise UsageProblem("give the period one way: --date [--end-date], or --start and "
                               "--end" + (" (or the instants: --time)" if not by_date else ""))
        if by_date and self.date is None:
            raise UsageProblem("--end-date goes with --date")
        if by_time and (self.start is None or self.end is None):
            raise UsageProblem("--start and --end go together")
        if self.clear_sky is not None and self.clear_sky not in CLEAR_SKY_MODELS:
            raise UsageProblem(f"--clear-sky must be one of {', '.join(CLEAR_SKY_MODELS)}, got "
                               f"{self.clear_sky!r}")
        if self.ghi is not None and (self.clear_sky is not None
                                     or self.linke_input is not None):
            raise UsageProblem("--ghi gives the sky measured: --clear-sky and "
                               "--linke-turbidity do not go with it")
        if self.ghi is not None and (self.beam_input is not None
                                     or self.diffuse_input is not None):
            raise UsageProblem("--ghi gives the sky measured: the clear-sky indices "
                               "--beam-index and --diffuse-index do not go with it")
        if self.linke_input is not None and self.clear_sky == "haurwitz":
            raise UsageProblem("--linke-turbidity is Ineichen's: Haurwitz takes none")
        self.algorithm = check_lift(self.height_above_ground, self.algorithm, self.soft)
        try:
            check_options(0.0, None, self.skyview_directions)
        except HillshadeError as exc:
            raise UsageProblem(str(exc)) from None

    def lighting(self, backend: str):
        """How the terrain is lit (``engine.lighting.Lighting``), on ``backend`` (chosen);
        after :meth:`check`. The cast shadows only: the incidence is the irradiance's own
        (``engine.irradiance``), no self-shadowing."""
        from ..engine.lighting import Lighting
        return Lighting(algorithm=self.algorithm, backend=backend, curvature=self.curvature,
                        refraction_k=self.refraction_k, soft=self.soft,
                        lift=self.height_above_ground)


@dataclass(kw_only=True)
class IllumConfig:
    """``files``: DEM and OUTPUT (or the DEM alone with ``output``); ``subsolar_file``: the
    series; ``body`` --body's text or None (the CRS's); ``sun_distance`` metres where the series
    gives none (None: the body's mean distance); ``curvature`` True/False or None (on);
    ``window_size`` (--window-size text or (rows, cols)), ``max_memory`` (text), ``scheduler``
    (Dask), ``chunks`` (time chunks per window on Dask; None: the workers)."""

    files: list
    output: str | None = None
    subsolar_file: str | None = None
    body: str | None = None
    sun_distance: float | None = None
    height_above_ground: float = 0.0
    soft: bool = False
    curvature: bool | None = None
    refraction_k: float | None = None
    window_size: object = None
    max_memory: object = None
    scheduler: object = None
    chunks: int | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)

    def check(self) -> tuple:
        """(dem, output) checked."""
        if self.subsolar_file is None:
            raise UsageProblem("illumination needs --subsolar-file F (a subsolar series)")
        inputs, output = inputs_and_output(self.files, self.output, None)
        if len(inputs) != 1:
            raise UsageProblem("illumination lights one DEM: give DEM OUTPUT")
        d = self.sun_distance
        if d is not None and not (math.isfinite(d) and d > 0):
            raise UsageProblem(f"--sun-distance must be positive metres, got {d:g}")
        h = float(self.height_above_ground)
        if not (math.isfinite(h) and h >= 0):
            raise UsageProblem(f"--height-above-ground must be >= 0 metres, got {h:g}")
        if self.chunks is not None and int(self.chunks) < 1:
            raise UsageProblem("chunks must be 1 or more")
        return inputs[0], output

    def lighting(self, backend: str):
        """How the terrain is lit (``engine.lighting.Lighting``), on ``backend`` (chosen):
        curvature on unless turned off (``None``: on; never "auto"), refraction, the lift, soft
        shadows. The algorithm is the per-cell sun's march (``algorithms.subsolar``), whatever
        ``algorithm`` says; after :meth:`check`."""
        from ..engine.lighting import Lighting
        return Lighting(backend=backend,
                        curvature=True if self.curvature is None else bool(self.curvature),
                        refraction_k=self.refraction_k, soft=bool(self.soft),
                        lift=self.height_above_ground)


@dataclass(kw_only=True)
class LightConfig:
    """``files``: DEM and OUTPUT (or the DEM alone with ``output``); ``position`` (x, y, z: the
    DEM's CRS, metres above the datum) or ``lonlat`` (lon, lat, z: WGS84 degrees), as numbers
    or the command line's 'A,B,C' texts; ``refused``: the options given with the light that it
    does not take yet (name -> given), a usage error naming them."""

    files: list
    output: str | None = None
    position: object = None
    lonlat: object = None
    height_above_ground: float = 0.0
    window_size: object = None
    max_memory: object = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    refused: dict = field(default_factory=dict)

    def check(self) -> tuple:
        """(dem, output, position, lonlat) checked: one light, one DEM, nothing refused."""
        taken = [name for name, on in self.refused.items() if on]
        if taken:
            raise UsageProblem(f"a point light does not take {', '.join(taken)} (yet: hard "
                               "shadows, in memory or in windows, CPU or GPU)")
        if (self.position is None) == (self.lonlat is None):
            raise UsageProblem("give --light-position X,Y,Z or --light-lonlat LON,LAT,Z, one "
                               "of them")
        inputs, output = inputs_and_output(self.files, self.output, None)
        if len(inputs) != 1:
            raise UsageProblem("a point light lights one DEM: give DEM OUTPUT")
        pos = None if self.position is None else parse_triple(self.position,
                                                               "--light-position")
        ll = None if self.lonlat is None else parse_triple(self.lonlat, "--light-lonlat")
        return inputs[0], output, pos, ll


def parse_triple(text, what: str) -> tuple[float, float, float]:
    """'A,B,C' as three finite floats (a usage error otherwise)."""
    if isinstance(text, (tuple, list)):
        parts = list(text)
    else:
        parts = str(text).split(",")
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        vals = ()
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise UsageProblem(f"{what} takes three numbers A,B,C, got {text!r}")
    return vals


FALLOFFS = ("none", "inverse-square")


BITS = (8, 16)


@dataclass(kw_only=True)
class LightmapConfig(LightConfig):
    """``LightConfig`` (the DEM, OUTPUT, the light, what is refused) and the hillshade's own:
    ``ambient`` 0..1, ``scale`` (gdaldem's -s), ``falloff`` (``FALLOFFS``), ``bits`` (8: uint8
    1..255, 16: uint16 1..65535)."""

    ambient: float = 0.2
    scale: float | None = None
    falloff: str = "none"
    bits: int = 8

    def check(self) -> tuple:
        if self.falloff not in FALLOFFS:
            raise UsageProblem(f"--falloff must be one of {', '.join(FALLOFFS)}, got "
                               f"{self.falloff!r}")
        if self.bits not in BITS:
            raise UsageProblem(f"--bits must be 8 or 16, got {self.bits!r}")
        if not (math.isfinite(self.ambient) and 0.0 <= self.ambient <= 1.0):
            raise UsageProblem(f"--ambient must be within 0..1, got {self.ambient}")
        if self.scale is not None:
            if not (math.isfinite(self.scale) and self.scale > 0):
                raise UsageProblem(f"--scale must be a positive number, got {self.scale}")
            if self.read.pixel_size is not None:
                raise UsageProblem("--scale and --pixel-size do not go together")
        return super().check()


@dataclass(kw_only=True)
class SubsolarConfig:
    """``files``: DEM and OUTPUT (or the DEM alone with ``output``); ``subsolar``: (lat, lon)
    or the command line's 'LAT,LON'; ``sun_distance`` metres or None; ``body``: --body's text
    or None (the CRS's); ``curvature`` True/False or None (on); ``refused``: the options given
    that this run does not take (name -> given)."""

    files: list
    output: str | None = None
    subsolar: object = None
    sun_distance: float | None = None
    body: str | None = None
    height_above_ground: float = 0.0
    soft: bool = False
    curvature: bool | None = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    refused: dict = field(default_factory=dict)
    subsolar_file: str | None = None
    command: str | None = None          # the command line (a time cube's history)

    def check(self) -> tuple:
        """(dem, output, (lat, lon) or None for a series) checked: one DEM, one of --subsolar
        and --subsolar-file, nothing refused."""
        if self.subsolar is None and self.subsolar_file is None:
            raise UsageProblem("--sun-distance and --body go with --subsolar LAT,LON or "
                               "--subsolar-file F")
        if self.subsolar is not None and self.subsolar_file is not None:
            raise UsageProblem("give --subsolar LAT,LON or --subsolar-file F, not both")
        taken = [name for name, on in self.refused.items() if on]
        if taken:
            raise UsageProblem(f"--subsolar does not take {', '.join(taken)} (yet: in memory, "
                               "the shadow or --soft)")
        inputs, output = inputs_and_output(self.files, self.output, None)
        if len(inputs) != 1:
            raise UsageProblem("--subsolar lights one DEM: give DEM OUTPUT")
        d = self.sun_distance
        if d is not None and not (math.isfinite(d) and d > 0):
            raise UsageProblem(f"--sun-distance must be positive metres, got {d:g}")
        return inputs[0], output, (None if self.subsolar is None
                                   else parse_latlon(self.subsolar))


def parse_latlon(text) -> tuple[float, float]:
    """'LAT,LON' as two finite floats, the latitude in [-90, 90] (a usage error otherwise)."""
    parts = list(text) if isinstance(text, (tuple, list)) else str(text).split(",")
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        vals = ()
    if len(vals) != 2 or not all(math.isfinite(v) for v in vals):
        raise UsageProblem(f"--subsolar takes two numbers LAT,LON, got {text!r}")
    if not -90.0 <= vals[0] <= 90.0:
        raise UsageProblem(f"--subsolar latitude must be in [-90, 90] degrees, got {vals[0]:g}")
    return vals


@dataclass(kw_only=True)
class SkyviewConfig:
    dem: str
    output: str
    directions: int = 32
    definition: str = "zaksek"
    terrain_configuration: bool = False   # 1 - Vd (Dozier's): the terrain a tilted cell sees
    curvature: object = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    openness: str | None = None           # "positive" / "negative": Yokoyama's, in degrees
    max_distance: float | None = None     # metres (Yokoyama's L, RVT's radius)
    max_memory: object = None
    window_size: object = None
    scheduler: object = None              # the windows as Dask tasks
    height_above_ground: float = 0.0      # metres: the observer of every cell stands this high


@dataclass(kw_only=True)
class QueryConfig:
    dem: str
    at: list = field(default_factory=list)        # (lon, lat) pairs
    at_xy: list = field(default_factory=list)     # (x, y) pairs in the DEM's CRS
    points: str | None = None                     # a CSV or GeoJSON file of points
    sun: dict = field(default_factory=dict)       # run.config.SUN_KEYS
    height_above_ground: float = 0.0
    irradiance: bool = False
    fmt: str | None = None                        # None: from the output's extension, else csv
    output: str | None = None                     # None: standard output
    curvature: object = None                      # None: "auto", as shadow
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)
    light_position: object = None                 # a point light: X,Y,Z in the DEM's CRS
    light_lonlat: object = None                   # or LON,LAT,Z (WGS84 degrees)


@dataclass(kw_only=True)
class ProfileConfig:
    dem: str
    at: list = field(default_factory=list)        # (lon, lat) pairs
    at_xy: list = field(default_factory=list)     # (x, y) pairs in the DEM's CRS
    points: str | None = None                     # a CSV or GeoJSON file of points
    height_above_ground: float = 0.0
    step: float = 1.0
    fmt: str = "csv"
    output: str | None = None                     # None: standard output
    curvature: object = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)


@dataclass(kw_only=True)
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


@dataclass(kw_only=True)
class AnimateConfig:
    """An ``animate`` run: ``dem`` to ``output`` (.gif or .mp4), the times as a day (``date``:
    local midnight to midnight every ``step``, in ``--tz`` or else the zone of the DEM's
    centre) or a series (``start``, ``end``, ``step``), the place of the sun (``place``:
    ``run.config.PLACE_KEYS``), frames per second, the picture's long side, the label."""

    dem: str
    output: str
    date: str | None = None
    start: str | None = None
    end: str | None = None
    step: str | None = None           # None: DEFAULT_STEP
    place: dict = field(default_factory=dict)
    fps: float = 12.0
    size: int = 1024
    label: bool = True
    algorithm: str = "auto"
    curvature: object = None
    refraction_k: float | None = None
    read: ReadOptions = field(default_factory=ReadOptions)
    run: RunOptions = field(default_factory=RunOptions)

    def check(self) -> str:
        """The options' combinations (UsageProblem) and the output's format (".gif"/".mp4")."""
        from ..pictures.animation import check_output
        series = self.start is not None or self.end is not None
        if (self.date is not None) == series:
            raise UsageProblem("give the times one way: --date, or --start and --end "
                               "(with --step)")
        if series and (self.start is None or self.end is None):
            raise UsageProblem("--start and --end go together")
        return check_output(self.output, self.fps, self.size)

    def lighting(self, backend: str):
        """How the terrain is lit (``engine.lighting.Lighting``): the ``shadow`` command's
        hard cast shadows, on ``backend`` (chosen)."""
        from ..engine.lighting import Lighting
        return Lighting(algorithm=self.algorithm, backend=backend, curvature=self.curvature,
                        refraction_k=self.refraction_k)
