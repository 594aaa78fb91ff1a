"""The ``illumination`` run: a DEM on a body lit by every position of a
subsolar series (``ephemeris.read_subsolar``: a plain CSV or a JPL Horizons table), every cell
with its own sun (``bodysun``, ``algorithms.subsolar``). One float32 GeoTIFF, NaN nodata:

1. the fraction of the time lit (each sample weighted by ``SubsolarSeries.durations_h``);
2. with ``--soft``: the mean visible fraction of the solar disk over the time;
3. (2 without --soft) the longest continuous shadow, hours (a run of consecutive shadowed
   samples lasts the sum of their intervals);
4. (3) permanently shadowed: 1.0 never lit in the series, 0.0 otherwise.

The DEM (or each window) is prepared once (frames, pyramid, highest height), then one kernel
call per position into reused buffers, folded into per-cell sums by
``algorithms.illumination`` (no Python loop over cells). A position whose sun is below the
horizon of every cell is dark everywhere without a march.

Windows (``--window-size``, or ``--max-memory`` smaller than the DEM needs): each window is lit
with a halo as wide as any ray that can still be blocked: with curvature a ray above its
horizon rises at least (1 - k) d^2 / 2R above the cell, so nothing farther than
sqrt(2 R (zmax - zmin) / (1 - k)) can block it (R the smallest radius of curvature of the
body, zmin the window's lowest height); without curvature the lowest positive tan(elevation)
of the sun over the window's cells and the series bounds it: (zmax - zmin) / tan. Dask
(``--scheduler``): the times cut into chunks (and the windows) as tasks, each returning its
sums; the chunks are combined in time order (``algorithms.illumination.combine``).

The run's steps, between the shared preamble and tail (``run.runner.RunContext``): the series
read, the DEM opened, the suns on its body, the light (``IllumConfig.lighting`` made into the
kernels' constants, :meth:`Physics.of`; each region's bands written as it comes), the report.
"""

from __future__ import annotations

import math
import os
import threading
from dataclasses import dataclass

import numpy as np

from .. import __version__
from ..errors import HillshadeError, UsageProblem
from .config import IllumConfig
from .runner import RunContext

BYTES_PER_CELL = 96     # heights 4, frames 24, pyramid ~6, mask 1, soft 4, sums 5 x 8 + 1
_LOCK = threading.Lock()   # one numba computation at a time per worker process
HALO_MARGIN = 2         # cells beyond the reach (interpolation between two cell centres)


@dataclass
class Physics:
    """What every window and task shares (picklable): the body's ellipsoid, the curvature's
    refraction k (-1: none), the lift, soft, the radius of the smallest curvature."""

    a: float
    e2: float
    curv_k: float
    lift: float
    soft: bool
    r_min: float
    backend: str = "cpu"

    @classmethod
    def of(cls, body, lighting) -> Physics:
        """The kernels' constants of ``body`` lit by ``lighting`` (``engine.lighting``): the
        refraction k of its curvature (-1: none), its lift, soft, backend."""
        from ..model.earth import refraction_for
        k = refraction_for(body, lighting.refraction_k) if lighting.curvature else -1.0
        return cls(float(body.a), 1.0 - (body.b * body.b) / (body.a * body.a), k,
                   float(lighting.lift), bool(lighting.soft),
                   float(body.b * body.b / body.a), lighting.backend)


@dataclass
class Counts:
    """The positions of a stretch of the series lit (``positions``) and those dark on every
    cell (``dark``: no march)."""

    positions: int = 0
    dark: int = 0

    def add(self, other: Counts) -> None:
        self.positions += other.positions
        self.dark += other.dark


def band_names(soft: bool) -> list[str]:
    return (["fraction_lit"] + (["soft_mean"] if soft else [])
            + ["longest_shadow_h", "permanent_shadow"])


DESCRIPTIONS = {"fraction_lit": "fraction of the time lit (time-weighted)",
                "soft_mean": "mean visible fraction of the solar disk (time-weighted)",
                "longest_shadow_h": "longest continuous shadow (hours)",
                "permanent_shadow": "permanently shadowed (1 never lit in the series, 0 lit)"}


# ---------------------------------------------------------------------------------------------
# one region, a stretch of times

def _sums(shape, soft: bool) -> dict:
    return {"lit": np.zeros(shape), "soft": np.zeros(shape) if soft else None,
            "start": np.zeros(shape), "end": np.zeros(shape), "longest": np.zeros(shape),
            "dark": np.ones(shape, np.uint8)}


def light_series(z, frames, grid, phys: Physics, suns, hours, tick=None) -> tuple[dict, Counts]:
    """The sums (``algorithms.illumination``) of heights ``z`` (float32, NaN voids) with its
    ``frames`` (``bodysun.CellFrames``) and ``grid`` lit by the suns ``suns`` ((n, 3) metres,
    body-fixed) of ``hours`` each, and the counts (positions marched, dark ones). The pyramid,
    the highest height and the buffers made once; ``tick()`` after each position. ``phys.backend``
    "gpu": the heights, the pyramid and the frames uploaded once, each position's mask made by
    the CUDA twins (``subsolar.shadow_mask_gpu``: bit for bit the CPU's) and folded into the
    sums on the host."""
    from ..algorithms import illumination as ill, subsolar
    from ..algorithms.pyramid import pyramid_args
    from ..engine.cell_suns import sun_radius_deg
    sums = _sums(z.shape, phys.soft)
    counts = Counts()
    if not np.isfinite(z).any():
        return sums, counts
    zmax = float(np.nanmax(z))
    fr = frames.args()
    if phys.backend == "gpu":
        from ..engine.gpu import GpuDem
        g = GpuDem(z)
        frd = tuple(g.upload(a) for a in fr)
    else:
        pyr = pyramid_args(z, True)
        mask = np.empty(z.shape, np.uint8)
        frac = np.empty(z.shape, np.float32) if phys.soft else None
    for s, dt in zip(suns, hours):
        sx, sy, sz = (float(v) for v in s)
        dt = float(dt)
        counts.positions += 1
        if ill.any_sun_up(z, *fr[:4], phys.a, phys.e2, sx, sy, sz, phys.lift) == 0:
            counts.dark += 1
            ill.accumulate_dark(z, dt, sums["start"], sums["end"], sums["longest"], sums["dark"])
        else:
            if phys.backend == "gpu":
                mask = subsolar.shadow_mask_gpu(g, frd, grid, phys.a, phys.e2, s, phys.curv_k,
                                                zmax, phys.lift)
            else:
                subsolar.shadow_mask(z, pyr, fr, grid, phys.a, phys.e2, s, phys.curv_k, zmax,
                                     phys.lift, out=mask)
            ill.accumulate(mask, dt, sums["lit"], sums["start"], sums["end"], sums["longest"],
                           sums["dark"])
            if phys.soft:
                radius = sun_radius_deg(float(np.linalg.norm(s)))
                if phys.backend == "gpu":
                    frac = subsolar.soft_fraction_gpu(g, frd, grid, phys.a, phys.e2, s, radius,
                                                      phys.curv_k, zmax, phys.lift)
                else:
                    subsolar.soft_fraction(z, pyr, fr, grid, phys.a, phys.e2, s, radius,
                                           phys.curv_k, zmax, phys.lift, out=frac)
                ill.accumulate_soft(frac, dt, sums["soft"])
        if tick is not None:
            tick()
    return sums, counts


def _crop(sums: dict, r: slice, c: slice) -> dict:
    return {k: (None if v is None else np.ascontiguousarray(v[r, c])) for k, v in sums.items()}


def bands_of(sums: dict, valid, total_h: float, soft: bool) -> list[np.ndarray]:
    """The output's bands (float32, NaN where not ``valid``)."""
    out = [sums["lit"] / total_h] + ([sums["soft"] / total_h] if soft else []) + \
          [sums["longest"], sums["dark"].astype(np.float64)]
    return [np.where(valid, b, np.nan).astype(np.float32) for b in out]


# ---------------------------------------------------------------------------------------------
# windows

def halo_cells(phys: Physics, zmax: float, zmin_w: float, spacing_min: float,
               tan_min: float | None) -> int:
    """Cells of the halo around a window whose lowest height is ``zmin_w`` (module docstring):
    curvature: sqrt(2 R (zmax - zmin) / (1 - k)); none: (zmax - zmin) / ``tan_min`` (the
    lowest positive tan of the sun's elevation over the window; None: no sun up, no halo)."""
    relief = max(0.0, zmax - zmin_w)
    if relief == 0.0:
        return HALO_MARGIN
    if phys.curv_k >= 0.0 and phys.curv_k < 1.0:
        reach = math.sqrt(2.0 * phys.r_min * relief / (1.0 - phys.curv_k))
    else:
        reach = 0.0 if tan_min is None else relief / tan_min
    if phys.curv_k >= 0.0 and tan_min is not None and tan_min > 0:
        reach = min(reach, relief / tan_min)
    if not math.isfinite(reach) or reach > 1e12:
        return 1 << 40
    return int(math.ceil(reach / spacing_min)) + HALO_MARGIN


@dataclass
class Region:
    """A window (r0, r1, c0, c1) and what it reads: ``read`` the bounds with the halo."""

    core: tuple
    read: tuple


def _region_inputs(src, rd, region: Region):
    """(heights, frames, grid) of a region's read bounds through the reader ``rd``."""
    from affine import Affine

    from ..engine.cell_suns import CellFrames
    from ..model.geometry import grid_from_transform
    r0, r1, c0, c1 = region.read
    z = np.empty((r1 - r0, c1 - c0), np.float32)
    rd.read(region.read, z)
    tr = src.transform @ Affine.translation(c0, r0)
    return z, CellFrames.from_transform(tr, src.crs, z.shape), grid_from_transform(tr, src.crs,
                                                                                  z.shape)


def _core_slices(region: Region):
    r0, r1, c0, c1 = region.core
    R0, _, C0, _ = region.read
    return slice(r0 - R0, r1 - R0), slice(c0 - C0, c1 - C0)


def plan_windows(src, phys: Physics, suns, window_shape) -> tuple[list, float]:
    """The regions of a windowed run (each window's halo from the relief) and the DEM's
    highest height; the heights read once window by window for the figures."""
    from ..algorithms import illumination as ill
    from ..engine.cell_suns import CellFrames
    from ..model.geometry import grid_from_transform
    from .horizon_windows import regions
    rows, cols = src.shape
    cores = regions(src.shape, window_shape)
    lows, zmax = [], -math.inf
    tans = []
    with src.reader() as rd:
        for core in cores:
            r0, r1, c0, c1 = core
            z = np.empty((r1 - r0, c1 - c0), np.float32)
            rd.read(core, z)
            ok = np.isfinite(z)
            lows.append(float(z[ok].min()) if ok.any() else math.inf)
            if ok.any():
                zmax = max(zmax, float(z[ok].max()))
            t = None
            if phys.curv_k < 0.0 and ok.any():
                from affine import Affine
                fr = CellFrames.from_transform(src.transform @ Affine.translation(c0, r0),
                                               src.crs, z.shape).args()
                best = np.full(z.shape[0], np.inf)
                for s in suns:
                    ill.lowest_elevation_tan(z, *fr[:4], phys.a, phys.e2, float(s[0]),
                                             float(s[1]), float(s[2]), phys.lift, best)
                t = float(best.min()) if np.isfinite(best.min()) else None
            tans.append(t)
    grid = grid_from_transform(src.transform, src.crs, src.shape)
    spacing = float(min(np.min(grid.dx), np.min(grid.dy)))
    out = []
    for core, lo, t in zip(cores, lows, tans):
        h = 0 if not math.isfinite(lo) else halo_cells(phys, zmax, lo, spacing, t)
        r0, r1, c0, c1 = core
        out.append(Region(core, (max(0, r0 - h), min(rows, r1 + h), max(0, c0 - h),
                                 min(cols, c1 + h))))
    return out, zmax


def region_task(src, region: Region, phys: Physics, suns, hours) -> tuple[dict, Counts]:
    """A window (or the whole DEM) lit by a stretch of the series: its core's sums and counts
    (the Dask task; also the local windows' step)."""
    with src.reader() as rd:
        z, frames, grid = _region_inputs(src, rd, region)
    with _LOCK:
        sums, counts = light_series(z, frames, grid, phys, suns, hours)
    return _crop(sums, *_core_slices(region)), counts


# ---------------------------------------------------------------------------------------------
# the run

def _chunks(n: int, k: int) -> list[tuple[int, int]]:
    k = max(1, min(n, k))
    edges = [round(i * n / k) for i in range(k + 1)]
    return [(edges[i], edges[i + 1]) for i in range(k) if edges[i + 1] > edges[i]]


@dataclass
class _Lit:
    """What the light of the series gave: the body, the lighting and the kernels' constants of
    it, the bands' names, the counts of positions, the sums and cells of each band (its mean),
    the cells never lit, the number of regions."""

    body: object
    lighting: object        # engine.lighting.Lighting
    phys: Physics
    names: list
    counts: Counts
    means: dict             # band -> [sum, cells]
    never_lit: int
    windows: int

    @property
    def valid(self) -> int:
        return self.means[self.names[0]][1]


def illumination(cfg: IllumConfig) -> dict:
    """Write the illumination bands of the DEM over the series; returns the report."""
    from ..engine.cell_suns import body_from_option
    from .config import parse_window_size
    from .horizon import memory_limit

    ro = cfg.run
    dem, output = cfg.check()
    window_shape = parse_window_size(cfg.window_size)
    limit = memory_limit(cfg.max_memory)      # default: half of this machine's memory
    if cfg.body is not None:
        body_from_option(cfg.body)              # a bad --body: exit 2 before anything is read
    ctx = RunContext.start(ro, inputs=[dem, cfg.subsolar_file], outputs=[(output, "OUTPUT")],
                           note=False)
    series, hours = _series(cfg)
    with ctx.timer("read"):
        src = cfg.read.open(dem, windows=window_shape is not None or cfg.scheduler is not None)
    with src:
        lit = _light(cfg, ctx, src, output, series, hours, window_shape, limit)
    if ro.preview is not None:
        with ctx.timer("write"):
            _preview(src, output, ro)
    rep = _report(cfg, ctx, src, output, series, hours, lit)
    m, n_psr = rep["mean"], lit.never_lit
    return ctx.finish(rep, [(
        "summary", f"hillshade-rt: {output}: {src.shape[1]}x{src.shape[0]}, {len(series)} "
                   f"subsolar positions over {rep['hours']:.1f} h on {lit.body.source}: mean "
                   f"fraction lit {100 * (m['fraction_lit'] or 0):.2f}%, "
                   f"{n_psr} cells never lit ({100 * n_psr / max(1, lit.valid):.2f}%); "
                   f"compute {ctx.timer.seconds['compute']:.2f} s "
                   f"({1000 * rep['seconds']['per_position']:.1f} ms a position)")])


def _series(cfg: IllumConfig) -> tuple:
    """The subsolar series (``ephemeris.read_subsolar``: at least 2 times) and the hours each
    sample stands for."""
    from ..model.ephemeris import read_subsolar
    series = read_subsolar(cfg.subsolar_file)
    if len(series) < 2:
        raise HillshadeError(f"{cfg.subsolar_file}: the series needs at least 2 times (each "
                             "sample stands for the interval to the next)")
    return series, series.durations_h()


def _suns(cfg: IllumConfig, src, series) -> tuple:
    """(body, suns): the DEM's body (``--body``, else its CRS's) and the sun of each position
    ((n, 3) metres, body-fixed; at the series' distance, else ``--sun-distance``, else the
    body's mean distance)."""
    from ..engine.cell_suns import body_from_option, mean_sun_distance, sun_vector
    from ..model.earth import dem_body
    if src.transform is None or src.crs is None:
        raise HillshadeError("illumination needs a DEM with a geotransform and a CRS (each "
                             "cell's place on the body)")
    body = body_from_option(cfg.body, dem_body(src))
    default_d = mean_sun_distance(body) if cfg.sun_distance is None else cfg.sun_distance
    if not default_d > body.a:
        raise UsageProblem(f"--sun-distance must exceed the body's radius ({body.a:.0f} m, "
                           f"{body.source}), got {default_d:g} m")
    dist = (np.full(len(series), float(default_d)) if series.distance is None
            else series.distance)
    return body, np.array([sun_vector(body, la, lo, d)
                           for la, lo, d in zip(series.lat, series.lon, dist)])


def _window_shape(src, window_shape, limit):
    """The windows' shape: ``--window-size``'s, else the one ``--max-memory`` needs (None: the
    DEM in memory)."""
    if window_shape is not None:
        return window_shape
    from .local import needs_windows
    from ..engine.windows import window_budget
    if needs_windows(src, limit, BYTES_PER_CELL):
        from .horizon_windows import region_shape
        return region_shape(src.shape, window_budget(limit, BYTES_PER_CELL)[0])
    return None


def _light(cfg: IllumConfig, ctx: RunContext, src, output, series, hours, window_shape,
           limit) -> _Lit:
    """The series lit on the DEM (in memory, in windows or on Dask) and each region's bands
    written as it comes."""
    from ..engine.cell_suns import CellFrames
    from ..io import BandWriter
    from .report import progress
    ro = ctx.ro
    body, suns = _suns(cfg, src, series)
    lighting = cfg.lighting(ctx.backend)
    phys = Physics.of(body, lighting)
    window_shape = _window_shape(src, window_shape, limit)
    total_h = float(hours.sum())
    names = band_names(cfg.soft)
    counts = Counts()
    tags = {"HILLSHADE_RT_VERSION": __version__,
            "SUBSOLAR_FILE": os.path.basename(cfg.subsolar_file),
            "TIMES": f"{len(series)} from {series.times()[0].isoformat()} to "
                     f"{series.times()[-1].isoformat()}",
            "HOURS": f"{total_h:.6g}", "BODY": body.source,
            "HEIGHT_ABOVE_GROUND_M": f"{phys.lift:g}", "BANDS": ",".join(names)}
    means = {n: [0.0, 0] for n in names}
    n_psr = 0
    with ctx.timer("compute"), BandWriter(output, src, len(names), "float32", float("nan"),
                                          tags, overwrite=ro.overwrite, fmt=ro.fmt,
                                          co=ro.creation_options) as w:
        if window_shape is not None or cfg.scheduler is not None:
            if window_shape is not None:
                regs, _ = plan_windows(src, phys, suns, window_shape)
            else:
                rows, cols = src.shape
                regs = [Region((0, rows, 0, cols), (0, rows, 0, cols))]
            results = _run_regions(src, regs, phys, suns, hours, cfg, ro.quiet)
        else:
            d = src.read()
            frames = CellFrames.of_dem(d)
            rows, cols = d.shape
            regs = [Region((0, rows, 0, cols), (0, rows, 0, cols))]
            bar = progress(range(len(series)), ro.quiet, "illumination", "position",
                           mode=ro.progress)
            with bar:
                sums, c = light_series(d.heights, frames, d.grid, phys, suns, hours,
                                       tick=lambda: bar.update(1))
            results = iter([(regs[0], sums, c, np.isfinite(d.heights))])
        for reg, sums, c, valid in results:
            counts.add(c)
            bands = bands_of(sums, valid, total_h, cfg.soft)
            r0, r1, c0, c1 = reg.core
            for i, (name, b) in enumerate(zip(names, bands)):
                w.write(i + 1, b, DESCRIPTIONS[name], window=(r0, r1, c0, c1))
                v = b[valid]
                means[name][0] += float(v.sum(dtype=np.float64))
                means[name][1] += int(v.size)
            n_psr += int((sums["dark"][valid] == 1).sum())
    return _Lit(body, lighting, phys, names, counts, means, n_psr, len(regs))


def _report(cfg: IllumConfig, ctx: RunContext, src, output, series, hours, lit: _Lit) -> dict:
    """The run's report (``--report``)."""
    from ..io import input_label
    phys, body, means = lit.phys, lit.body, lit.means
    curvature = lit.lighting.curvature
    timer = ctx.timer
    return {"input": input_label(src.path), "output": os.path.abspath(output),
            "subsolar_file": os.path.abspath(cfg.subsolar_file), "shape": list(src.shape),
            "times": len(series), "hours": float(hours.sum()),
            "first": series.times()[0].isoformat(), "last": series.times()[-1].isoformat(),
            "body": {"source": body.source, "a_m": body.a, "b_m": body.b},
            "curvature": {"applied": curvature,
                          "refraction_k": phys.curv_k if curvature else None},
            "height_above_ground_m": phys.lift, "soft": bool(cfg.soft), "bands": lit.names,
            "positions": {"marched": lit.counts.positions - lit.counts.dark,
                          "dark_everywhere": lit.counts.dark},
            "windows": lit.windows, "valid_cells": lit.valid,
            "mean": {n: (means[n][0] / means[n][1] if means[n][1] else None)
                     for n in lit.names},
            "permanently_shadowed_cells": lit.never_lit,
            "scheduler": None if cfg.scheduler is None else str(cfg.scheduler),
            "backend": phys.backend,
            "seconds": dict(ctx.seconds(),
                            per_position=timer.seconds.get("compute", 0.0) / len(series)),
            "version": __version__}


def _preview(src, output, ro) -> None:
    """--preview: the relief coloured by the fraction of the time lit (purple the least, yellow
    the most: stretched between the 2nd and 98th percentiles), both read back at most 2048
    cells a side."""
    from ..model.geometry import Grid
    from ..io import read_decimated, write_png
    from ..pictures.preview import relief_rgb, scaled
    rows, cols = src.shape
    n = max(1, math.ceil(max(rows, cols) / 2048))
    shape = ((rows + n - 1) // n, (cols + n - 1) // n)
    z = read_decimated(src.name, shape, src.band) * np.float32(src.z_factor)
    g = src.grid
    grid = Grid(shape[0], shape[1], g.dx[::n][:shape[0]] * n, g.dy[::n][:shape[0]] * n,
                g.col_sign, g.row_sign, g.method)
    frac = read_decimated(output, shape, 1)
    write_png(ro.preview, relief_rgb(z, grid, ramp=scaled(frac)), ro.overwrite)


def _run_regions(src, regs, phys, suns, hours, cfg, quiet):
    """(region, sums, counts, valid) of every region: locally window after window, or on Dask
    with the times cut into chunks (combined in time order)."""
    from ..algorithms.illumination import combine
    from .report import progress
    if cfg.scheduler is None:
        bar = progress(range(len(regs) * len(suns)), quiet, "illumination", "position",
                       mode=cfg.run.progress)
        with bar, src.reader() as rd:
            for reg in regs:
                z, frames, grid = _region_inputs(src, rd, reg)
                sums, c = light_series(z, frames, grid, phys, suns, hours,
                                       tick=lambda: bar.update(1))
                rs, cs = _core_slices(reg)
                yield reg, _crop(sums, rs, cs), c, np.isfinite(z[rs, cs])
        return
    from .dask import DaskSession
    output = cfg.output if cfg.output is not None else cfg.files[-1]
    with DaskSession(cfg.scheduler, output, cfg.run.worker_timeout) as session:
        n_chunks = cfg.chunks or max(1, session.workers())
        chunks = _chunks(len(suns), n_chunks)
        futs = {}
        for ri, reg in enumerate(regs):
            for ci, (a, b) in enumerate(chunks):
                f = session.client.submit(region_task, src, reg, phys, suns[a:b], hours[a:b],
                                          pure=False)
                session.futures.append(f)
                futs[(ri, ci)] = f
        bar = progress(range(len(futs)), quiet, "illumination", "task",
                       mode=cfg.run.progress)
        with bar:
            done = {}
            for f, res in session.completed(list(futs.values()), "tasks"):
                done[f.key] = res
                bar.update(1)
        for ri, reg in enumerate(regs):
            acc, counts = None, Counts()
            for ci in range(len(chunks)):
                sums, c = done[futs[(ri, ci)].key]
                acc = sums if acc is None else combine(acc, sums)
                counts.add(c)
            with src.reader() as rd:
                r0, r1, c0, c1 = reg.core
                z = np.empty((r1 - r0, c1 - c0), np.float32)
                rd.read(reg.core, z)
            yield reg, acc, counts, np.isfinite(z)
