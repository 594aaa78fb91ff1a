"""``bounds`` with every cell's own sun (a sun that varies across the raster: the SPA's lattice,
``per_cell_sun``): what the bounds sweep adds for it, called by ``bounds``' kernels when their
field is in use (``bounds.shadow_mask_field`` is the entry point).

* :func:`field_fit`: the potential Phi(v, p) = A v^2 + B v p fitted to the cells' rays, so that
  over the heights less Phi (:func:`less_potential`) every cell's ray is nearly one straight ray,
  and the ranges of the rays' step, rise and curvature the bounds are made for;
* :func:`field_line`: each position's own ray along a canonical line (``per_cell_sun.ray_of``,
  the lattice's values hoisted out of each run of cells between two of its nodes,
  :func:`field_runs`), in the lessened frame, and whether the bounds may decide it;
* :func:`field_args`: the field tuple the kernels take (the same types with no field: one
  compiled sweep).
"""

from __future__ import annotations

import numpy as np

from ._jitcache import njit
from .per_cell_sun import lattice_scale, ray_of, sun_args


@njit(cache=True)
def less_potential(ZB, zo, v_top, nb, p0, p1, A, B):
    """Lines v_top .. v_top-nb+1 of the ring, positions [p0, p1): the heights less the field's
    potential A v^2 + B v p (``field_fit``), linear along a line, so that the model's
    interpolation between two centres carries it exactly; ``zo``: the NaN positions before each
    line of the ring (``bounds.ZO``)."""
    R = ZB.shape[0]
    for i in range(nb):
        w = v_top - i
        zr = ZB[w % R, zo + p0:zo + p1]     # (a row of ZB: contiguous, the loop vectorises)
        aw = A * w * w
        bw = B * w
        for q in range(p1 - p0):
            zr[q] -= aw + bw * (p0 + q)


@njit(cache=True, error_model="numpy")
def field_line(fld, v, p0, p1, L, P, FS, FR, FC, FOK, FN, IX, XP, PF, DXL, DYL, RUNS, nruns):
    """The rays of positions [p0, p1) of canonical line v with each cell's own sun (``fld``:
    ``field_args``), indexed by position, in the frame of the heights less the potential: s,
    rise - its gradient along the ray, curv - its second difference; ``FOK``: the sun is up,
    the ray in the frame's octant and within the ranges the bounds were made for; ``FN``:
    night (the sun at or below the horizon). The same arithmetic as ``per_cell_sun.cell_ray``, cell
    for cell, with the lattice's values hoisted out of each run of cells between two of its
    nodes, over views that start at 0 (numba then drops its negative-index wrap, which made
    the loop gather and scatter: 8 ns a cell, 1 ns now). ``XP``, ``PF``: each position's DEM
    index along the line and itself, as floats; ``DXL``, ``DYL``: each position's spacing
    (lines that are DEM columns); ``IX``, ``RUNS``, ``nruns``: each position's node interval and
    the runs of positions that share one (``field_runs``, the same for every line)."""
    (_, vec, fdx, fdy, cs, rs, ccoef, r0, c0, nrows, ncols, fdom, fsd, fl_line, fl_pos, _, A, B,
     s_lo, s_hi, r_lo, r_hi, c_lo, c_hi) = fld
    n = vec.shape[0]
    si = lattice_scale(n, nrows)
    sj = lattice_scale(n, ncols)
    line = L - 1 - v if fl_line else v          # the DEM index the line fixes
    s_pos = si if fdom else sj                  # lattice scale along the positions
    fl = (line + (c0 if fdom else r0)) * (sj if fdom else si)
    l0 = min(int(fl), n - 2) if n > 1 else 0
    l1 = min(l0 + 1, n - 1)
    tl = fl - l0
    fv = float(v)
    sgn = -1.0 if fl_pos else 1.0
    for ir in range(nruns):
        qa = RUNS[ir]
        qb = RUNS[ir + 1]
        k0 = IX[qa]
        k1 = min(k0 + 1, n - 1)
        # lattice_at: along the columns first (at the two node rows), then along the rows
        if fdom:     # lines are DEM columns: j fixed (l0, tl), i varies (k0, t)
            a0 = vec[k0, l0, 0] + tl * (vec[k0, l1, 0] - vec[k0, l0, 0])
            b0 = vec[k1, l0, 0] + tl * (vec[k1, l1, 0] - vec[k1, l0, 0])
            a1 = vec[k0, l0, 1] + tl * (vec[k0, l1, 1] - vec[k0, l0, 1])
            b1 = vec[k1, l0, 1] + tl * (vec[k1, l1, 1] - vec[k1, l0, 1])
            a2 = vec[k0, l0, 2] + tl * (vec[k0, l1, 2] - vec[k0, l0, 2])
            b2 = vec[k1, l0, 2] + tl * (vec[k1, l1, 2] - vec[k1, l0, 2])
            _field_run_i(XP[qa:qb], PF[qa:qb], DXL[qa:qb], DYL[qa:qb], s_pos, float(k0), a0,
                         b0, a1, b1, a2, b2, cs, rs, ccoef, fv, A, B, fdom, fsd, sgn, s_lo,
                         s_hi, r_lo, r_hi, c_lo, c_hi, FS[qa:qb], FR[qa:qb], FC[qa:qb],
                         FOK[qa:qb], FN[qa:qb])
        else:        # lines are DEM rows: i fixed (l0, tl), j varies (k0, t)
            _field_run_j(XP[qa:qb], PF[qa:qb], fdx[line], fdy[line], s_pos, float(k0), tl,
                         vec[l0, k0], vec[l0, k1], vec[l1, k0], vec[l1, k1], cs, rs, ccoef, fv,
                         A, B, fdom, fsd, sgn, s_lo, s_hi, r_lo, r_hi, c_lo, c_hi, FS[qa:qb],
                         FR[qa:qb], FC[qa:qb], FOK[qa:qb], FN[qa:qb])


@njit(cache=True)
def field_runs(fld, p0, p1, XP, IX, RUNS):
    """Each position's lattice node interval along the line (``lattice_at``'s, from ``XP``)
    into ``IX`` and the runs of positions sharing one into ``RUNS`` (starts, then the end):
    returns how many runs."""
    n = fld[1].shape[0]
    s_pos = lattice_scale(n, fld[9] if fld[11] else fld[10])
    for p in range(p0, p1):
        IX[p] = min(int(XP[p] * s_pos), n - 2) if n > 1 else 0
    k = 0
    RUNS[0] = p0
    for p in range(p0 + 1, p1):
        if IX[p] != IX[p - 1]:
            k += 1
            RUNS[k] = p
    RUNS[k + 1] = p1
    return k + 1


@njit(cache=True, error_model="numpy")
def _field_run_i(XP, PF, DXL, DYL, s_pos, k0, a0, b0, a1, b1, a2, b2, cs, rs, ccoef, fv, A, B,
                 fdom, fsd, sgn, s_lo, s_hi, r_lo, r_hi, c_lo, c_hi, FS, FR, FC, FOK, FN):
    """Cells of one node interval of a line that is a DEM column (``field_line``)."""
    for i in range(XP.shape[0]):
        t = XP[i] * s_pos - k0
        e = a0 + t * (b0 - a0)
        no = a1 + t * (b1 - a1)
        up = a2 + t * (b2 - a2)
        _field_ray(e, no, up, DXL[i], DYL[i], cs, rs, ccoef, fv, PF[i], A, B, fdom, fsd, sgn,
                   s_lo, s_hi, r_lo, r_hi, c_lo, c_hi, i, FS, FR, FC, FOK, FN)


@njit(cache=True, error_model="numpy")
def _field_run_j(XP, PF, dxr, dyr, s_pos, k0, tl, q00, q01, q10, q11, cs, rs, ccoef, fv, A, B,
                 fdom, fsd, sgn, s_lo, s_hi, r_lo, r_hi, c_lo, c_hi, FS, FR, FC, FOK, FN):
    """Cells of one node interval of a line that is a DEM row (``field_line``; q.. the four
    nodes' vectors)."""
    u0, u1, w0, w1 = q00[0], q01[0] - q00[0], q10[0], q11[0] - q10[0]
    m0, m1, n0, n1 = q00[1], q01[1] - q00[1], q10[1], q11[1] - q10[1]
    g0, g1, h0, h1 = q00[2], q01[2] - q00[2], q10[2], q11[2] - q10[2]
    for i in range(XP.shape[0]):
        t = XP[i] * s_pos - k0
        a = u0 + t * u1
        e = a + tl * ((w0 + t * w1) - a)
        a = m0 + t * m1
        no = a + tl * ((n0 + t * n1) - a)
        a = g0 + t * g1
        up = a + tl * ((h0 + t * h1) - a)
        _field_ray(e, no, up, dxr, dyr, cs, rs, ccoef, fv, PF[i], A, B, fdom, fsd, sgn,
                   s_lo, s_hi, r_lo, r_hi, c_lo, c_hi, i, FS, FR, FC, FOK, FN)


@njit(cache=True, inline="always", error_model="numpy")
def _field_ray(e, no, up, dxr, dyr, cs, rs, ccoef, fv, fp, A, B, fdom, fsd, sgn, s_lo, s_hi,
               r_lo, r_hi, c_lo, c_hi, i, FS, FR, FC, FOK, FN):
    """One cell of ``field_line``: its ray (``per_cell_sun.ray_of``) in the lessened frame, at i."""
    night, dc, sd, so, rise, curv = ray_of(e, no, up, dxr, dyr, cs, rs, ccoef)
    sp = sgn * so
    q = A + sp * B
    rp = rise - ((A + q) * fv + B * fp)
    cp = curv - q
    FS[i] = sp
    FR[i] = rp
    FC[i] = cp
    FN[i] = night
    FOK[i] = ((not night) & (dc == fdom) & (sd == fsd) & (sp >= s_lo) & (sp <= s_hi)
              & (rp >= r_lo) & (rp <= r_hi) & (cp >= c_lo) & (cp <= c_hi))


def field_args(vec=None, grid=None, curv_coef=0.0, f=None, L=1, fit=None, place=None):
    """The field tuple of the kernels: (use, lattice, dx, dy, col sign, row sign, curvature,
    r0, c0, rows, cols (``per_cell_sun.sun_args``, ``place``), frame dom_col, frame step_dom,
    flip_line, flip_pos, L, A, B, s_lo, s_hi, r_lo, r_hi, c_lo, c_hi) (``fit``:
    ``field_fit``'s A, B and ranges); unused without a field (the same types: one compiled
    sweep)."""
    if vec is None:
        i0, i1 = np.int64(0), np.int64(1)
        return (False, np.zeros((2, 2, 3)), np.ones(1), np.ones(1), 1.0, -1.0, 0.0, i0, i0, i1,
                i1, False, i1, False, False, i1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    return (True, *sun_args(grid, vec, curv_coef, place), bool(f.dom_col), np.int64(f.sd),
            bool(f.flip_line), bool(f.flip_pos), np.int64(L), *(float(x) for x in fit))


def field_fit(sample: np.ndarray, L: int, P: int):
    """(A, B, s range, rise range, curv range, potential range) of a sun per cell from the rays
    ``per_cell_sun.field_sample`` took (line v, position p, s, rise, curv).

    A time-based sun rises toward the sun by about the arc the ground covers, the Earth's
    curvature seen from the sky: across a 61 km DEM at 5 deg its rays' rise per step varies by
    7 %, and bounds made for that whole range leave 3x the cells undecided. Let the heights
    be lessened by a potential Phi(v, p) = A v^2 + B v p whose gradient along the rays is the
    rise's variation (fitted: rise ~ r0 + a v + b p, so B = b, A = (a - s b) / 2); along a ray
    of cell (v, p) with step s, Phi grows k ((A + q) v + B p) + k^2 q over k steps (q = A +
    s B) exactly, so the ray over the lessened heights rises rise - ((A + q) v + B p) per step
    with curvature curv - q: nearly one straight ray for every cell (the rest of the Earth's
    curvature, the refraction's share, stays in the curvature). Phi is linear along a line,
    so the interpolated terrain is lessened exactly: the same shadows, in another frame."""
    v, p, s, rise, curv = (sample[:, i] for i in range(5))
    A = B = 0.0
    if len(v) >= 3:
        X = np.stack([np.ones_like(v), v, p], axis=1)
        coef, *_ = np.linalg.lstsq(X, rise, rcond=None)
        if np.all(np.isfinite(coef)):
            B = float(coef[2])
            A = 0.5 * (float(coef[1]) - float(np.median(s)) * B)
    q = A + s * B
    rp = rise - ((A + q) * v + B * p)
    cp = curv - q

    def padded(x, lo_limit=-np.inf):
        lo, hi = float(x.min()), float(x.max())
        pad = 0.02 * (hi - lo) + 1e-9 * max(abs(lo), abs(hi))
        return max(lo - pad, lo_limit), hi + pad
    # the potential's extremes: linear in p, so at p = 0 or P - 1; there quadratic in v
    vs = [0.0, L - 1.0]
    phis = []
    for pp in (0.0, P - 1.0):
        if A != 0.0:
            vv = -B * pp / (2.0 * A)
            vs_ = vs + ([vv] if 0.0 < vv < L - 1.0 else [])
        else:
            vs_ = vs
        phis += [A * x * x + B * x * pp for x in vs_]
    return A, B, padded(s, 0.0), padded(rp), padded(cp), (min(phis), max(phis))
