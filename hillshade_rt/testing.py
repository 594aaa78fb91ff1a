"""Helpers shared by hillshade-rt's tests and benchmarks (like ``numpy.testing``).

Tests and benchmarks import what they share from here, and from nowhere else: no ``sys.path``
edits, no test importing another test file or ``conftest`` (pytest fixtures stay in
``tests/conftest.py``; they may call these helpers). A test in ``tests/test_testing.py`` scans
``tests/`` and ``benchmarks/`` and fails where that rule is broken.

* **Terrains** (the same arrays, bit for bit, for the same arguments, whatever the machine):
  :func:`fractal_terrain`, the facet fractal of the tests (a few noise octaves upsampled
  bilinearly: planar facets tens of cells wide, far smoother than any real DEM; label it
  "smooth (facets)" wherever it is timed) and :func:`smooth_facets`, its benchmark setting;
  :func:`spectral`, power-law (spectral) fractals that look like Earth, :func:`tiled` to repeat
  them seamlessly, and :func:`spectral_f64`, ``bench_writes``' older power-law fractal;
  :func:`ridges` and :func:`write_ridges_dem`, the synthetic DEM of ``bigdem`` and
  ``bench_tiling``, written in bands; :func:`box_terrain`, one block on a plain;
  :func:`roughness`, figures that tell smooth from rough terrain.
* **Real DEMs shipped in the repository**: :func:`real_dems` (paths and labels), :func:`data_path`
  (``tests/data``), :func:`repo_root`. These files are only in a source checkout, not in an
  installed package: the functions say so when the files are absent.
* **References**: :func:`reference_mask`, the terrain model written out plainly in Python,
  independently of the package's kernels; the tests compare every algorithm against it.
* **Files**: :func:`write_geotiff`, :func:`read_band`, :func:`split_geotiff` (one DEM cut into
  tiles).
* **Timing and peers** (benchmarks): :func:`median_seconds`; :func:`peer_doshade`,
  :func:`peer_whitebox`, :func:`peer_topocalc`, other tools' shadow masks where installed;
  :func:`peer_svf_rvt`, :func:`peer_svf_whitebox`, their sky view factors.

Only numpy is imported here; rasterio and the peers are imported by the functions that use them.
"""

from __future__ import annotations

import contextlib
import math
import os
import statistics
import tempfile
import time
import warnings

import numpy as np

__all__ = [
    "BENCH_REAL_DEMS", "SMALL_REAL_DEMS", "box_terrain", "data_path", "fractal_terrain",
    "median_seconds", "peer_doshade", "peer_svf_rvt", "peer_svf_whitebox", "peer_topocalc",
    "peer_whitebox", "read_band", "real_dems",
    "reference_mask", "repo_root", "ridges", "roughness", "serving", "smooth_facets",
    "spectral", "spectral_f64", "split_geotiff", "tiled", "write_geotiff", "write_ridges_dem",
]


# --- the repository's data ------------------------------------------------------------------

# Every real DEM shipped in the repository: file name -> (folder from the repository root,
# label). Origins and licences: examples/SOURCES.md, tests/data/SOURCES.md,
# benchmarks/data/SOURCES.md.
_REAL = {
    "bigtujunga_srtm30m_utm11n_1197x643.tif": ("examples", "Big Tujunga SRTM 1″, UTM 30 m"),
    "everest_srtm3_N27E086_voids_1201.tif": ("benchmarks/data",
                                             "Everest SRTM 3″ tile, geographic, 9 % voids"),
    "nz_elev_1km_nztm_sea_nodata_1115x1450.tif": ("benchmarks/data",
                                                  "New Zealand 1 km, NZTM, 83 % sea"),
    "moon_kepler_crater_lola_ortho_804x804.tif": ("benchmarks/data",
                                                  "Moon Kepler crater LOLA, 47.7 m"),
    "jacksboro_fault_srtm3_mpl_403x344.tif": ("tests/data", "Jacksboro SRTM 3″, geographic"),
    "everest_srtm3_voids_crop200.tif": ("tests/data",
                                        "Everest SRTM 3″ 200² crop, geographic, 19.5 % voids"),
    "lidar_dem_1m_utm15n_400x400.tif": ("tests/data", "Minnesota lidar 1 m, UTM 15N"),
}

#: The real DEMs of ``bench_real`` and ``bench_fast``, in their order (the geographic SRTM tile
#: second, Jacksboro last).
BENCH_REAL_DEMS = ("bigtujunga_srtm30m_utm11n_1197x643.tif", "everest_srtm3_N27E086_voids_1201.tif",
                   "nz_elev_1km_nztm_sea_nodata_1115x1450.tif",
                   "moon_kepler_crater_lola_ortho_804x804.tif",
                   "jacksboro_fault_srtm3_mpl_403x344.tif")

#: The small real DEMs of ``bench_cpu`` and ``bench_gpu``.
SMALL_REAL_DEMS = ("bigtujunga_srtm30m_utm11n_1197x643.tif", "everest_srtm3_voids_crop200.tif",
                   "jacksboro_fault_srtm3_mpl_403x344.tif")

_CHECKOUT_ONLY = ("the tests' and benchmarks' data ship only with a source checkout of "
                  "hillshade-rt (git clone; pip install -e .), not with an installed package")


def repo_root(root: str | os.PathLike | None = None) -> str:
    """The source checkout's root folder: ``root`` if given, else the folder above this package
    (right for an editable install or a run from the checkout). FileNotFoundError when that
    folder holds no ``tests/data`` (an installed package: the data are not shipped)."""
    if root is None:
        root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    root = os.fspath(root)
    if not os.path.isdir(os.path.join(root, "tests", "data")):
        raise FileNotFoundError(f"{root} is not a source checkout of hillshade-rt (it has no "
                                f"tests/data): {_CHECKOUT_ONLY}; pass root=<the checkout>")
    return root


def data_path(name: str, root: str | os.PathLike | None = None) -> str:
    """Path of ``tests/data/<name>`` in the checkout (the file itself may not exist: tests ask
    for missing names on purpose)."""
    return os.path.join(repo_root(root), "tests", "data", name)


def real_dems(names=BENCH_REAL_DEMS, root: str | os.PathLike | None = None
              ) -> list[tuple[str, str]]:
    """``[(path, label)]`` of the real DEMs ``names`` (file names, default
    :data:`BENCH_REAL_DEMS`; see also :data:`SMALL_REAL_DEMS`), in that order.

    FileNotFoundError, naming every missing file, when the checkout lacks any of them."""
    base = repo_root(root)
    out, missing = [], []
    for name in names:
        if name not in _REAL:
            raise KeyError(f"{name!r} is not a real DEM of the repository "
                           f"(known: {', '.join(sorted(_REAL))})")
        folder, label = _REAL[name]
        path = os.path.join(base, *folder.split("/"), name)
        if not os.path.isfile(path):
            missing.append(os.path.join(folder, name))
        out.append((path, label))
    if missing:
        raise FileNotFoundError(f"real DEMs missing under {base}: {', '.join(missing)} "
                                f"({_CHECKOUT_ONLY})")
    return out


# --- terrains ---------------------------------------------------------------------------------

def box_terrain(rows=80, cols=80, h=10.0, r0=38, r1=42, c0=38, c1=42) -> np.ndarray:
    """A plain at 0 with one block of height ``h`` over rows r0:r1, columns c0:c1 (float32)."""
    z = np.zeros((rows, cols), np.float32)
    z[r0:r1, c0:c1] = h
    return z


def fractal_terrain(rows, cols, seed, relief=100.0, octaves=4) -> np.ndarray:
    """Smooth-ish random terrain: a sum of bilinearly upsampled noise octaves (float32,
    0..relief). Planar facets tens of cells wide: the "smooth (facets)" fractal."""
    rng = np.random.default_rng(seed)
    z = np.zeros((rows, cols))
    for o in range(octaves):
        n = 2 ** (o + 1) + 1
        coarse = rng.standard_normal((n, n)) / (2 ** o)
        ri = np.linspace(0, n - 1, rows)
        ci = np.linspace(0, n - 1, cols)
        r0 = np.minimum(np.floor(ri).astype(int), n - 2)
        c0 = np.minimum(np.floor(ci).astype(int), n - 2)
        fr = (ri - r0)[:, None]
        fc = (ci - c0)[None, :]
        z += ((1 - fr) * (1 - fc) * coarse[r0][:, c0] + (1 - fr) * fc * coarse[r0][:, c0 + 1]
              + fr * (1 - fc) * coarse[r0 + 1][:, c0] + fr * fc * coarse[r0 + 1][:, c0 + 1])
    z = (z - z.min()) / (z.max() - z.min()) * relief
    return z.astype(np.float32)


def smooth_facets(n: int, seed: int | None = None, relief: float = 1500.0) -> np.ndarray:
    """The smooth facet fractal of the benchmarks: :func:`fractal_terrain` n x n, six octaves,
    seed ``n`` unless given, 1.5 km of relief. No real DEM is that smooth; label it
    "smooth (facets)" wherever it is timed."""
    return fractal_terrain(n, n, seed=n if seed is None else seed, relief=relief,
                           octaves=6).astype(np.float32)


def spectral(n: int, beta: float, seed: int = 0, relief: float = 2000.0,
             cols: int | None = None) -> np.ndarray:
    """Power-law fractal, ``n`` rows x ``cols`` (default n) columns, float32 metres 0..relief.

    White Gaussian noise shaped in the Fourier domain so that its 2-D power spectrum falls as
    ``|k|^-beta`` (amplitude ``|k|^-beta/2``), i.e. fractional Brownian surfaces with Hurst
    exponent ``H = (beta - 2) / 2``: beta 2.4 is rough (H 0.2), 3.2 is smoother (H 0.6); real
    landscapes measure about 2-4 (Perron et al. 2008). The result is periodic (it tiles
    seamlessly, see :func:`tiled`). Built with a real FFT in float32 (numpy >= 2 keeps the
    precision), so an 8192² surface takes about 4 s and 1.1 GB at its peak."""
    cols = n if cols is None else cols
    rng = np.random.default_rng(seed)
    ky = np.fft.fftfreq(n).astype(np.float32)
    kx = np.fft.rfftfreq(cols).astype(np.float32)
    k2 = ky[:, None] ** 2 + kx[None, :] ** 2
    k2[0, 0] = 1.0
    amp = k2 ** np.float32(-beta / 4.0)        # |k|^-beta/2
    del k2
    amp[0, 0] = 0.0                            # no mean
    spec = rng.standard_normal(amp.shape, dtype=np.float32) * amp \
        + 1j * (rng.standard_normal(amp.shape, dtype=np.float32) * amp)
    del amp
    z = np.fft.irfft2(spec.astype(np.complex64), s=(n, cols))
    del spec
    z = z.astype(np.float32, copy=False)
    lo, hi = float(z.min()), float(z.max())
    z -= np.float32(lo)
    z *= np.float32(relief / (hi - lo))
    return z


def tiled(z: np.ndarray, n: int) -> np.ndarray:
    """``z`` (periodic, e.g. :func:`spectral`) repeated to n x n: the same terrain at a larger
    size, for cost-versus-size comparisons (seamless, since the spectral surface is periodic)."""
    r, c = z.shape
    return np.ascontiguousarray(np.tile(z, (-(-n // r), -(-n // c)))[:n, :n])


def spectral_f64(n: int, beta: float = 2.2, seed: int = 3) -> np.ndarray:
    """``bench_writes``' power-law fractal, n x n, float32 0..2000 m (a complex FFT in float64).

    Its ``beta`` is the exponent of a 1-D profile: the 2-D power spectrum falls as
    ``|k|^-(beta + 1)``, so ``spectral_f64(n, b)`` has the statistics of ``spectral(n, b + 1)``."""
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(n)
    kk = np.sqrt(k[:, None] ** 2 + k[None, :] ** 2)
    kk[0, 0] = 1.0
    spec = (rng.standard_normal((n, n)) + 1j * rng.standard_normal((n, n))) / kk ** (beta / 2 + 0.5)
    z = np.fft.ifft2(spec).real
    return ((z - z.min()) / (z.max() - z.min()) * 2000).astype(np.float32)


def ridges(r0: int, r1: int, cols: int) -> np.ndarray:
    """Rows r0:r1 of the synthetic ridge DEM of ``bigdem`` and ``bench_tiling`` (1 m cells, a few
    wavelengths, ~520 m of relief): any band of rows on its own, for DEMs larger than memory."""
    y = np.arange(r0, r1, dtype=np.float64)[:, None]
    x = np.arange(cols, dtype=np.float64)[None, :]
    z = (400.0 + 150.0 * np.sin(x / 900.0) * np.cos(y / 1300.0)
         + 80.0 * np.sin((x + 0.7 * y) / 430.0) + 30.0 * np.sin(x / 97.0) * np.sin(y / 131.0)
         + 12.0 * np.sin(x / 23.0 + y / 37.0))
    return z.astype(np.float32)


def write_ridges_dem(path, n: int) -> None:
    """Write the :func:`ridges` DEM, n x n float32, as a tiled BigTIFF in UTM 11N (1 m cells),
    512 rows at a time (never whole in memory)."""
    import rasterio
    from affine import Affine
    from rasterio.windows import Window

    prof = dict(driver="GTiff", width=n, height=n, count=1, dtype="float32", crs="EPSG:32611",
                transform=Affine(1, 0, 300000, 0, -1, 3900000), tiled=True, blockxsize=512,
                blockysize=512, BIGTIFF="YES")
    with rasterio.open(path, "w", **prof) as dst:
        for r0 in range(0, n, 512):
            r1 = min(n, r0 + 512)
            dst.write(ridges(r0, r1, n), 1, window=Window(0, r0, n, r1 - r0))


def roughness(z: np.ndarray, cell: float) -> dict:
    """A few figures that tell smooth from rough terrain: mean slope (degrees) and the share of
    cells whose slope differs from their east neighbour's by more than 5 degrees."""
    gy, gx = np.gradient(z.astype(np.float64), cell)
    s = np.degrees(np.arctan(np.hypot(gx, gy)))
    ds = np.abs(np.diff(s, axis=1))
    return {"mean_slope": float(np.nanmean(s)),
            "kinks": float(np.nanmean(ds > 5.0))}


# --- the reference ----------------------------------------------------------------------------

def _samples(z, r, c, vc, vr):
    """The model's samples of the ray from the centre of cell (r, c) of float64 heights ``z``,
    moving ``vc`` columns and ``vr`` rows per metre, written out plainly: (t, terrain) at every
    ground distance t where it crosses a grid line of its dominant pixel axis, the terrain
    interpolated between the two nearest cell centres on that line (NaN on a void), until it
    leaves the raster. Shared by the plain references below."""
    rows, cols = z.shape
    dom = max(abs(vc), abs(vr))

    def near_int(x):
        return abs(x - round(x)) < 1e-9

    k = 1
    while True:
        t = k / dom
        pc, pr = c + vc * t, r + vr * t
        if near_int(pc):
            pc = round(pc)
        if near_int(pr):
            pr = round(pr)
        if not (0 <= pc <= cols - 1 and 0 <= pr <= rows - 1):
            return
        if pc == int(pc) and pr == int(pr):
            terrain = z[int(pr), int(pc)]
        elif pc == int(pc):          # on a column line: interpolate along rows
            i = int(math.floor(pr)); f = pr - i
            terrain = (1 - f) * z[i, int(pc)] + f * z[i + 1, int(pc)]
        else:                        # on a row line: interpolate along columns
            i = int(math.floor(pc)); f = pc - i
            terrain = (1 - f) * z[int(pr), i] + f * z[int(pr), i + 1]
        yield t, terrain
        k += 1


def reference_mask(z, dx, dy, azimuth, elevation, col_sign=1, row_sign=-1,
                   lift=0.0) -> np.ndarray:
    """The terrain model written out plainly, independently of hillshade_rt's kernels.

    dx, dy: scalars or one value per row. The ray from the centre of cell (r, c) travels a ground
    distance t toward the sun; it is sampled at every t where it crosses a grid line of its
    dominant pixel axis; the terrain there is interpolated between the two nearest cell centres
    on that line; strictly-below means shadow; outside the raster there is no terrain; NaN cells
    are voids (never shadowed or lit: 255; a ray skips them). ``lift``: the ray starts that many
    metres above the cell's centre (an observer above the ground; 0: on it).
    """
    z = np.asarray(z, dtype=np.float64)
    rows, cols = z.shape
    dxs = np.broadcast_to(np.asarray(dx, dtype=np.float64), (rows,))
    dys = np.broadcast_to(np.asarray(dy, dtype=np.float64), (rows,))
    a = math.radians(azimuth % 360.0)
    east, north = math.sin(a), math.cos(a)
    tan_e = math.tan(math.radians(elevation))
    out = np.zeros((rows, cols), np.uint8)
    for r in range(rows):
        vc = col_sign * east / dxs[r]    # columns per metre
        vr = row_sign * north / dys[r]   # rows per metre
        for c in range(cols):
            if math.isnan(z[r, c]):
                out[r, c] = 255
                continue
            for t, terrain in _samples(z, r, c, vc, vr):
                if terrain > (z[r, c] + lift) + t * tan_e:
                    out[r, c] = 1
                    break
    return out


def wall_terrain(az: float, h: float = 30.0, s0: float = 70.0, thick: float = 10.0,
                 rows: int = 150, cols: int = 170):
    """(float32 heights, bool wall) of a long wall of height ``h`` perpendicular to azimuth
    ``az`` on flat ground at 0 (north-up cells): the cells whose distance along the azimuth
    (x east = column, y north = -row, in cells) lies in [s0, s0 + thick]."""
    a = math.radians(az)
    r, c = np.mgrid[0:rows, 0:cols].astype(np.float64)
    s = c * math.sin(a) - r * math.cos(a)
    wall = (s >= s0) & (s <= s0 + thick)
    return np.where(wall, np.float32(h), np.float32(0.0)), wall


def wall_contacts(wall, rays, rows_of, cols_of) -> dict:
    """{(row, col): d} for the ground cells (of ``rows_of`` x ``cols_of``) before a wall
    (``wall_terrain``) whose ray (``rays``: rows dominant, southward, one ray for the raster)
    meets it cleanly: its first sample whose two neighbouring centres are both wall cells lies
    ``d`` ground metres away, and the sample before it touches no wall cell (a sample between
    a wall cell and the ground would be part of the wall's face, lower and nearer). There the
    model's horizon from H above the cell is atan((h - H) / d)."""
    rows, cols = wall.shape
    assert not rays.dom_col[0] and rays.step_dom[0] == 1       # along rows, southward
    so, step_m = float(rays.step_other[0]), float(rays.step_m[0])
    out = {}
    for r in rows_of:
        for c in cols_of:
            if wall[r, c]:
                continue
            prev_out = True
            for k in range(1, rows):
                rr, p = r + k, c + k * so
                if rr >= rows or not (0.0 <= p <= cols - 1):
                    break                  # leaves the raster before the wall: no answer
                i0 = int(math.floor(p))
                both = [wall[rr, i0], wall[rr, min(i0 + 1, cols - 1)] if p > i0 else wall[rr, i0]]
                if all(both):
                    if prev_out:
                        out[(r, c)] = k * step_m
                    break
                prev_out = not any(both)
    return out


def reference_horizon(z, dx, dy, azimuth, col_sign=1, row_sign=-1, max_distance=None,
                      lift=0.0):
    """The horizon scan written out plainly (as :func:`reference_mask`, independently of the
    kernels): (β in degrees, the ground distance in metres to the horizon point), float64 per
    cell: the highest angle atan((terrain - h0) / t) over the ray's samples at ground distances
    t <= ``max_distance`` (the whole raster when None), the nearest of equal ones; -90 and NaN
    where no valid terrain lies ahead; NaN and NaN on voids. No Earth curvature. ``lift``: the
    observer stands that many metres above each cell (h0 = z + lift)."""
    z = np.asarray(z, dtype=np.float64)
    rows, cols = z.shape
    dxs = np.broadcast_to(np.asarray(dx, dtype=np.float64), (rows,))
    dys = np.broadcast_to(np.asarray(dy, dtype=np.float64), (rows,))
    a = math.radians(azimuth % 360.0)
    east, north = math.sin(a), math.cos(a)
    beta = np.full((rows, cols), np.nan)
    dist = np.full((rows, cols), np.nan)
    for r in range(rows):
        vc = col_sign * east / dxs[r]
        vr = row_sign * north / dys[r]
        for c in range(cols):
            if math.isnan(z[r, c]):
                continue
            best, where = -math.inf, math.nan
            for t, terrain in _samples(z, r, c, vc, vr):
                if max_distance is not None and t > max_distance * (1 + 1e-12):
                    break
                v = (terrain - (z[r, c] + lift)) / t
                if not math.isnan(v) and v > best + 1e-12 * abs(v):
                    best, where = v, t
            beta[r, c] = -90.0 if best == -math.inf else math.degrees(math.atan(best))
            dist[r, c] = where
    return beta, dist


# --- files ------------------------------------------------------------------------------------

def write_geotiff(path, z, transform=None, crs=None, nodata=None, count=1) -> str:
    """Write array ``z`` (2-D, or 3-D bands-first) as a GeoTIFF; its path as a string."""
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning

    z = np.asarray(z)
    if z.ndim == 2:
        z = z[None]
    prof = dict(driver="GTiff", width=z.shape[2], height=z.shape[1], count=z.shape[0],
                dtype=str(z.dtype), nodata=nodata)
    if transform is not None:
        prof["transform"] = transform
    if crs is not None:
        prof["crs"] = crs
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(path, "w", **prof) as dst:
            dst.write(z)
    return str(path)


def read_band(path, band=1) -> np.ndarray:
    """One band of a raster, as an array."""
    import rasterio
    from rasterio.errors import NotGeoreferencedWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with rasterio.open(path) as ds:
            return ds.read(band)


def split_geotiff(folder, z, transform, crs, cuts_r, cuts_c, nodata=None) -> list[str]:
    """Cut ``z`` (georeferenced by ``transform``, ``crs``) into GeoTIFF tiles
    ``folder/tile_<i><j>.tif``: rows ``cuts_r[i]``, columns ``cuts_c[j]`` ((start, stop) pairs).
    The tiles' paths, row by row."""
    from affine import Affine

    paths = []
    for i, (r0, r1) in enumerate(cuts_r):
        for j, (c0, c1) in enumerate(cuts_c):
            t = transform @ Affine.translation(c0, r0)
            paths.append(write_geotiff(os.path.join(os.fspath(folder), f"tile_{i}{j}.tif"),
                                       z[r0:r1, c0:c1], t, crs, nodata))
    return paths


# --- timing and peers (benchmarks) ------------------------------------------------------------

def median_seconds(fn, repeat: int, warm_up: bool = False) -> float:
    """Median wall seconds of ``repeat`` calls of ``fn``, after one untimed call if ``warm_up``
    (compilation, first touch)."""
    if warm_up:
        fn()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


# Each peer returns (name, callable giving a 0/1 shadow mask), or (name, reason it was skipped)
# where the tool is not installed (``pip install 'hillshade-rt[peers]'``, ``make bench-peers``).

def peer_doshade(z, cell, az, el):
    """``insolation``'s ``doshade`` (Corripio's scan lines from the sun-side edges, nearest
    neighbour, numba-parallel); square cells of ``cell`` metres; no nodata (voids: very low)."""
    try:
        from insolation import insolf
    except ImportError as e:
        return "insolation doshade", f"not installed ({e})"
    # Corripio's sun vector in array axes (x east, y down the rows), from zenith angle and azimuth
    sv = insolf.normalvector(90.0 - el, az)
    zz = np.nan_to_num(z, nan=-1e30).astype(np.float64)   # doshade has no nodata
    return "insolation doshade", lambda: 1 - insolf.doshade(zz, cell, sv)


def _whitebox_raster(z, cell):
    """``(WbEnvironment, raster)``: ``z`` through a temporary GeoTIFF (square cells of ``cell``
    metres, UTM 11N, -9999 nodata) into whitebox-workflows, quiet. ImportError without it."""
    import rasterio
    import whitebox_workflows as wbw
    path = os.path.join(tempfile.mkdtemp(), "dem.tif")
    prof = dict(driver="GTiff", width=z.shape[1], height=z.shape[0], count=1, dtype="float32",
                nodata=-9999.0, crs="EPSG:32611",
                transform=rasterio.transform.from_origin(0, z.shape[0] * cell, cell, cell))
    with rasterio.open(path, "w", **prof) as ds:
        ds.write(np.where(np.isnan(z), -9999.0, z).astype(np.float32), 1)
    wbe = wbw.WbEnvironment()
    wbe.verbose = False
    return wbe, wbe.read_raster(path)


def peer_whitebox(z, cell, az, el):
    """``whitebox-workflows``' ``horizon_angle`` (shadow = horizon angle > sun elevation); the
    DEM goes through a temporary GeoTIFF, only the tool call is in the callable."""
    try:
        wbe, dem = _whitebox_raster(z, cell)
    except ImportError as e:
        return "whitebox-workflows horizon_angle", f"not installed ({e})"
    maxd = float(math.hypot(*z.shape) * cell)

    def run():
        h = wbe.horizon_angle(dem, azimuth=az, max_dist=maxd).to_numpy()
        return (h > el).astype(np.uint8)
    return "whitebox-workflows horizon_angle", run


def peer_topocalc(z, cell, az, el):
    """``topocalc``'s ``hor1d``-based horizon (shadow = horizon tangent > tan(elevation))."""
    try:
        from topocalc.horizon import horizon as tc_horizon
    except ImportError as e:
        return "topocalc horizon", f"not installed ({e})"
    zz = np.nan_to_num(z, nan=0.0).astype(np.float64)
    # topocalc: azimuth 0 = south, +90 = east (IPW convention); returns cos of the zenith angle of
    # the horizon, i.e. sin(horizon angle)
    tc_az = ((180.0 - az) + 180.0) % 360.0 - 180.0

    def run():
        hcos = tc_horizon(tc_az, zz, cell)
        return (hcos > math.sin(math.radians(el))).astype(np.uint8)
    return "topocalc horizon", run


# The sky view factor's peers: (name, callable giving the SVF, float32 0..1, NaN on voids), or
# (name, reason it was skipped). Square cells of ``cell`` metres, ``n`` equal azimuths, a radius
# of ``r`` cells.

def peer_svf_rvt(z, cell, n, r):
    """``rvt-py``'s ``rvt.vis.sky_view_factor`` (Zakšek et al.'s own code: nearest-cell shifts,
    mirrored padding of ``r`` cells at the edges); ``r`` cells (it has no unbounded mode: pass
    the raster's diagonal for one)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            import rvt.vis
    except ImportError as e:
        return "rvt-py sky_view_factor", f"not installed ({e})"

    def run():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return rvt.vis.sky_view_factor(z.astype(np.float32), cell, svf_n_dir=n,
                                           svf_r_max=int(r))["svf"]
    return "rvt-py sky_view_factor", run


def peer_svf_whitebox(z, cell, n, r):
    """``whitebox-workflows``' ``sky_view_factor`` (azimuth step 360/``n``, the observer on the
    ground); ``r`` cells, or None: no radius (its own unbounded mode). The DEM goes through a
    temporary GeoTIFF, only the tool call is in the callable."""
    try:
        wbe, dem = _whitebox_raster(z, cell)
    except ImportError as e:
        return "whitebox-workflows sky_view_factor", f"not installed ({e})"
    maxd = None if r is None else float(r) * cell

    def run():
        return wbe.sky_view_factor(dem, az_fraction=360.0 / n, max_dist=maxd,
                                   observer_hgt_offset=0.0).to_numpy().astype(np.float32)
    return "whitebox-workflows sky_view_factor", run


# --------------------------------------------------------------------------------------------
# The Moon's sun, roughly (tests, benchmarks, the docs' pictures; never for science: a real
# series comes from an ephemeris, docs/subsolar.md)

MOON_R = 1737400.0
SYNODIC_DAYS = 29.530589      # the subsolar longitude goes once round the Moon westward
ECLIPSE_YEAR_DAYS = 346.62    # the subsolar latitude swings +-1.54 deg over an eclipse year
MOON_SUBSOLAR_LAT_MAX = 1.54


def toy_lunar_subsolar(n: int, step_h: float, start: str = "2027-01-01T00:00:00+00:00",
                       lon0: float = 0.0, phase_deg: float = 0.0) -> list[tuple]:
    """``n`` rows (ISO time, lat, lon) of a toy lunar subsolar series ``step_h`` hours apart:
    the longitude falls 360 deg per synodic month, the latitude is
    1.54 sin(2 pi t / eclipse year + phase). Right in kind (the sun circles the pole low over
    the horizon), not in detail."""
    import datetime as dt
    t0 = dt.datetime.fromisoformat(start)
    rows = []
    for i in range(n):
        days = i * step_h / 24.0
        lon = ((lon0 - 360.0 * days / SYNODIC_DAYS + 180.0) % 360.0) - 180.0
        lat = MOON_SUBSOLAR_LAT_MAX * math.sin(2 * math.pi * days / ECLIPSE_YEAR_DAYS
                                               + math.radians(phase_deg))
        rows.append(((t0 + dt.timedelta(hours=i * step_h)).isoformat(), lat, lon))
    return rows


def write_subsolar_csv(path, rows) -> str:
    """``rows`` of (time, lat, lon[, distance_m]) as the plain subsolar CSV
    (``ephemeris.read_subsolar``)."""
    with open(path, "w") as fh:
        fh.write("time,lat,lon" + (",distance_m" if rows and len(rows[0]) > 3 else "") + "\n")
        for r in rows:
            fh.write(",".join(str(v) for v in r) + "\n")
    return str(path)


LUNAR_SOUTH_POLAR_STEREO = ("+proj=stere +lat_0=-90 +lat_ts=-90 +lon_0=0 +k=1 +x_0=0 +y_0=0 "
                            "+R=1737400 +units=m +no_defs")


MOON_GEOGRAPHIC = "+proj=longlat +R=1737400 +no_defs"
MOON_NORTH_POLAR = ("+proj=stere +lat_0=90 +lon_0=0 +k=1 +x_0=0 +y_0=0 +R=1737400 +units=m "
                    "+no_defs")


def http_get(server, path: str):
    """(status, headers, body) of GET ``path`` on ``server`` (``serving``'s): an HTTP error's
    status and body too."""
    import urllib.error
    import urllib.request
    try:
        with urllib.request.urlopen(server.url.rstrip("/") + path, timeout=60) as r:
            return r.status, dict(r.headers), r.read()
    except urllib.error.HTTPError as e:
        return e.code, dict(e.headers), e.read()


def png_pixels(png: bytes) -> np.ndarray:
    """(h, w, 4) uint8 of a PNG, read by GDAL (not by the viewer's encoder)."""
    import warnings

    from rasterio.errors import NotGeoreferencedWarning
    from rasterio.io import MemoryFile
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotGeoreferencedWarning)
        with MemoryFile(png) as mf, mf.open() as ds:
            return np.moveaxis(ds.read(), 0, -1)


@contextlib.contextmanager
def serving(viewer):
    """``viewer`` (``run.viewer.Viewer``) served on a free local port in a thread: yields the
    HTTP server (``server_address``, ``url``); afterwards the server and the viewer are shut."""
    import threading

    from .run.view_server import make_server
    srv = make_server(viewer, 0)
    threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.1}, daemon=True).start()
    try:
        yield srv
    finally:
        srv.shutdown()
        srv.server_close()
        viewer.close()


def memory_dem(z, transform, crs):
    """A ``io.Dem`` of heights ``z`` (float32; NaN voids) with ``transform`` (affine) in ``crs``
    (any text rasterio's CRS takes: PROJ string, EPSG code, WKT), gridded as ``read_dem`` grids
    it, without a file (the per-cell suns' tests)."""
    from rasterio.crs import CRS

    from .model.geometry import grid_from_transform
    from .io.dem import Dem
    c = CRS.from_user_input(crs)
    z = np.asarray(z, np.float32)
    return Dem(z, grid_from_transform(transform, c, z.shape), "memory", "gdal",
               transform=transform, crs=c)
