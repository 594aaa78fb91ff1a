"""``sweep``: the flag-map propagation ("Faster Ray Traced Terrain Shadow Maps", seed 001).

The tutorial's idea: process cells from the sun's side and let every cell store what its own ray
met, so that a later ray reaching an already visited cell reuses that instead of marching on.
What each cell stores here is the **left-over height** of its ray, in absolute form: ``S``, the
lowest height at the cell's position from which a ray toward the sun clears every sample ahead
(``S - h`` is the most by which the cell's own ray passes under the terrain, negative when it
clears, ``-inf`` when it never meets terrain). It obeys an exact recurrence along a ray:

    S(cell) = max( max_{k<=K} (T_k - k*rise) , S(K-th sample point) - K*rise )

where ``T_k`` are the model's samples on the next K grid lines toward the sun (marched exactly).
The K-th sample point lies between two cells of its line, whose ``S`` are already known: it is
interpolated linearly between them (the tutorial's interpolation of stored values). Only the last
K lines of ``S`` are kept (a ring buffer), not a flag map of the whole DEM. A cell is shadowed iff
``S > h`` (strict, as in the model).

**Unsure cells.** The two stored neighbours ``S_a``, ``S_b`` bracket the interpolated value. When
the decision would differ between them (``max(E, min(S_a,S_b) - K*rise) <= h <
max(E, max(S_a,S_b) - K*rise)``, E the exact part), the cell is near a shadow edge where the
interpolation can err: it is flagged and, after the sweep, decided by brute's exact march
(``brute.refine``; parallel). Elsewhere both neighbouring rays agree and so, almost always, does
the ray between them. The report gives the flagged share (``unsure_fraction``: 0 at high sun,
0.35-0.56 % at 3° on a 2048² fractal terrain with K = 8).

Speed. With one ray direction for the raster (projected CRS) every cell of a line has the same
sample offsets and interpolation fractions, so each exact sample and the stored-value lookup is
one SIMD pass along a contiguous line buffer; the DEM is read and the mask written a block of
lines at a time (also when the lines are DEM columns). The lines depend on each other in order,
so this pass is sequential; the refinement is parallel. Rays that differ per row (geographic CRS)
take a per-cell kernel, parallel over the cells of a line.

Fixes of the published code: no restart of the inner loop at a wrong index (the loops run over
canonical lines and positions, ``frames``); no ±0.5 epsilon around an interpolated "never hit"
flag of -1 (``-inf`` is kept apart from real heights: when one of the two stored values is
``-inf``, i.e. that neighbour's ray left the raster, the cell marches on exactly instead); no
square root per pixel (the k-th sample is ``k`` steps on).

**Approximate.** On the axes and diagonals the K-th sample is a cell centre, nothing is
interpolated and ``sweep`` equals ``brute`` (tests). Elsewhere a cell is wrong only when both
neighbouring rays agree and the ray between them does not (a thin ridge or a void between them).
Measured against ``brute`` on the real DEMs of the project: ``ERROR_SUMMARY`` below and
docs/algorithms.md.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..geometry import SunRays
from . import brute
from .frames import frame_of, uniform_rays
from .raymath import line_position, terrain_on_line

EXACT_STEPS = 8   # samples marched exactly before the stored values are used
UNSURE = 2        # mask code of a cell left to the exact refinement pass

ERROR_SUMMARY = (
    "K=8 vs brute, 7 real DEMs x 8 suns (benchmarks/accuracy.py): mean 0.009-0.059 % of cells per "
    "DEM, worst sun 0.30 %; wrong cells within 1 deg of the sun elevation on void-free DEMs, up "
    "to 13 deg next to SRTM voids and 2.6 deg at a nodata coast (voids are holes in the model)")


@njit(cache=True)
def _stored_pair(ring, row, x):
    """The two stored S bracketing position x of a ring-buffer row and the fraction between them
    (b = a when x is a cell centre)."""
    i0 = int(math.floor(x))
    f = x - i0
    a = ring[row, i0]
    b = a if f == 0.0 else ring[row, i0 + 1]
    return a, b, f


@njit(cache=True)
def _decide(S, lo, hi, h):
    """Mask code of a cell: 255 void, 1 / 0 when its two stored neighbours agree, UNSURE when the
    decision would flip between them (the refinement pass then marches it exactly). Written as
    selects, without branches, so that the line pass that calls it stays vectorised."""
    sh = np.uint8(1) if S > h else np.uint8(0)
    c = np.uint8(UNSURE) if (lo <= h and h < hi) else sh
    return np.uint8(255) if h != h else c


@njit(cache=True)
def _march_cell(Z, ring, v, p, s, rise, K):
    """(S, lo, hi) of canonical cell (v, p): K samples marched exactly, then the stored S of the
    K-th sample's neighbours, interpolated (S) and taken at either neighbour (lo, hi). When a
    neighbour holds -inf (its ray left the raster without meeting terrain) the march goes on to
    the edge instead and S is exact (lo = -inf, hi = S: never unsure)."""
    L, P = Z.shape
    S = -np.inf
    k = 1
    march_on = False
    while (k <= K or march_on) and v + k < L:
        x = line_position(p + k * s, P)
        if x < 0.0:
            break
        t = terrain_on_line(Z, False, v + k, x)
        if t - k * rise > S:   # NaN (void) compares false
            S = t - k * rise
        if k == K:
            a, b, f = _stored_pair(ring, (v + k) % (K + 1), x)
            if a == -np.inf or b == -np.inf:
                march_on = True
            else:
                lo = max(S, min(a, b) - k * rise)
                hi = max(S, max(a, b) - k * rise)
                return max(S, a + f * (b - a) - k * rise), lo, hi
        k += 1
    return S, -np.inf, S


@njit(cache=True)
def _line_pass(ZL, ring, E, LO, HI, ol, d, fr, v, K, rise, n, Z, s):
    """Positions 0 <= p < n of line v (all inside the line: K samples and both stored
    neighbours): K exact sample passes, the stored-value pass, the decision pass."""
    R = K + 1
    row = v % R
    e = E[:n]
    e[:] = -np.inf
    for k in range(1, R):
        dk = d[k]
        f = fr[k]
        kr = k * rise
        za = ZL[(v + k) % R, dk:dk + n]
        if f == 0.0:
            for p in range(n):
                t = za[p] - kr
                e[p] = t if t > e[p] else e[p]   # NaN (void) compares false
        else:
            zb = ZL[(v + k) % R, dk + 1:dk + 1 + n]
            for p in range(n):
                t = za[p] + f * (zb[p] - za[p]) - kr
                e[p] = t if t > e[p] else e[p]
    dK = d[K]
    fK = fr[K]
    rK = K * rise
    sa = ring[(v + K) % R, dK:dK + n]
    sb = ring[(v + K) % R, dK + 1:dK + 1 + n] if fK > 0.0 else sa
    srow = ring[row]
    for p in range(n):
        a = sa[p]
        b = sb[p]
        t = a + fK * (b - a) - rK
        srow[p] = t if t > e[p] else e[p]
        t = min(a, b) - rK
        LO[p] = t if t > e[p] else e[p]
        t = max(a, b) - rK
        HI[p] = t if t > e[p] else e[p]
    for p in range(n):
        if sa[p] == -np.inf or sb[p] == -np.inf:   # rare: next to the far edge
            srow[p], LO[p], HI[p] = _march_cell(Z, ring, v, p, s, rise, K)
    zl = ZL[row]
    for p in range(n):
        ol[p] = _decide(srow[p], LO[p], HI[p], zl[p])


@njit(cache=True)
def _dem_index(i, n, flip):
    return n - 1 - i if flip else i


@njit(cache=True)
def _block_io(z, blk, v, nb, dom_col, flip_line, flip_pos, load):
    """Copy canonical lines v, v-1, ..., v-nb+1 between the DEM-shaped array ``z`` (C order) and
    the rows of ``blk`` (load: z -> blk, else blk -> z). Lines that are DEM columns go position by
    position, so that each DEM row is touched once per block, contiguously."""
    if dom_col:
        P, L = z.shape
        for p in range(P):
            r = _dem_index(p, P, flip_pos)
            for i in range(nb):
                c = _dem_index(v - i, L, flip_line)
                if load:
                    blk[i, p] = z[r, c]
                else:
                    z[r, c] = blk[i, p]
    else:
        L, P = z.shape
        for i in range(nb):
            r = _dem_index(v - i, L, flip_line)
            for p in range(P):
                c = _dem_index(p, P, flip_pos)
                if load:
                    blk[i, p] = z[r, c]
                else:
                    z[r, c] = blk[i, p]


@njit(cache=True)
def _sweep_uniform(z, Z, dom_col, flip_line, flip_pos, s, rise, K, out):
    """One ray direction for the whole raster: every cell of a line has the same sample offsets,
    so each of the K exact samples and the stored-value lookup is one pass along the line with a
    constant interpolation fraction, over contiguous line buffers (SIMD). ``z`` and ``out`` are
    the DEM-shaped arrays, read and written a block of lines at a time; ``Z`` is the canonical
    view of ``z`` for the few cells that take ``_march_cell`` (samples running off the far end
    of the line, and the K lines at the sun's edge)."""
    L, P = Z.shape
    R = K + 1
    ring = np.full((R, P), -np.inf)   # S of lines v .. v+K
    ZL = np.empty((R, P))             # heights of lines v .. v+K, float64, canonical order
    E = np.empty(P)
    LO = np.empty(P)
    HI = np.empty(P)
    d = np.empty(R, np.int64)
    fr = np.empty(R)
    for k in range(1, R):
        d[k] = int(math.floor(k * s))
        fr[k] = k * s - d[k]
    # positions whose K samples and both stored neighbours lie inside the line
    n_in = max(0, P - d[K] - (1 if fr[K] > 0.0 else 0))
    B = 32                            # lines per block read from / written to the DEM
    TB = np.empty((B, P + 17), np.float32)   # padded: rows of a power-of-two length would
    OB = np.empty((B, P + 67), np.uint8)     # share cache sets when filled column-wise
    for v in range(L - 1, -1, -1):
        j = (L - 1 - v) % B
        if j == 0:
            _block_io(z, TB, v, min(B, v + 1), dom_col, flip_line, flip_pos, True)
        row = v % R
        zl = ZL[row]
        for p in range(P):
            zl[p] = TB[j, p]
        first = n_in if v + K < L else 0
        _line_pass(ZL, ring, E, LO, HI, OB[j], d, fr, v, K, rise, first, Z, s)
        for p in range(first, P):
            S, lo, hi = _march_cell(Z, ring, v, p, s, rise, K)
            ring[row, p] = S
            OB[j, p] = _decide(S, lo, hi, zl[p])
        if j == B - 1 or v == 0:
            _block_io(out, OB, v + j, j + 1, dom_col, flip_line, flip_pos, False)


@njit(parallel=True, cache=True)
def _sweep_kernel(Z, s_arr, rise_arr, per_line, K, out):
    """Rays that differ from row to row (geographic CRS): lines from the sun's edge, the cells of
    a line in parallel, each through ``_march_cell`` with its own row's ray."""
    L, P = Z.shape
    ring = np.full((K + 1, P), -np.inf)
    for v in range(L - 1, -1, -1):
        row = v % (K + 1)
        for pp in prange(P):
            p = np.int64(pp)   # prange indices may be unsigned; keep integer arithmetic integral
            i = np.int64(v) if per_line else p
            S, lo, hi = _march_cell(Z, ring, v, p, s_arr[i], rise_arr[i], K)
            ring[row, p] = S
            out[v, p] = _decide(S, lo, hi, Z[v, p])


def _per_cell_rays(rays: SunRays):
    """Frame of the centre row, and s / rise of every row expressed in that frame, indexed by the
    canonical index that runs over the DEM's rows (lines when lines are rows, else positions;
    ``per_line`` says which).

    With per-row spacing (geographic CRS) each row keeps its own direction; a row whose own
    dominant axis differs (sun near a diagonal) is re-expressed in the frame's axis (|s| > 1)."""
    f = frame_of(rays, len(rays.rise) // 2)
    same = rays.dom_col.astype(bool) == f.dom_col
    so = np.abs(rays.step_other)
    s = np.where(same, so, 1.0 / np.maximum(so, 1e-300)).astype(np.float64)
    rise = np.where(same, rays.rise, rays.rise / np.maximum(so, 1e-300)).astype(np.float64)
    per_line = not f.dom_col
    if f.flip_line if per_line else f.flip_pos:
        s, rise = s[::-1].copy(), rise[::-1].copy()
    return f, s, rise, per_line


def shadow_mask(z: np.ndarray, rays: SunRays, zmax: float | None = None,
                stats: dict | None = None, exact_steps: int = EXACT_STEPS) -> np.ndarray:
    """Shadow mask by the flag-map sweep: uint8 1 shadow / 0 lit / 255 void."""
    out = np.empty(z.shape, np.uint8)
    if not math.isfinite(float(rays.rise[0])):   # sun at the zenith
        out[...] = np.where(np.isnan(z), 255, 0)
        return out
    K = np.int64(max(1, int(exact_steps)))
    if uniform_rays(rays):
        f = frame_of(rays)
        _sweep_uniform(z, f.view(z), f.dom_col, f.flip_line, f.flip_pos, f.s, f.rise, K, out)
    else:
        f, s, rise, per_line = _per_cell_rays(rays)
        _sweep_kernel(f.view(z), s, rise, per_line, K, f.view(out))
    if zmax is None:
        zmax = float(np.nanmax(z))
    unsure = brute.refine(z, rays, out, UNSURE, zmax)
    if stats is not None:
        stats["unsure_fraction"] = unsure / max(1, out.size)
    return out
