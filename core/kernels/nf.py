"""NF, normal fitting (Cheng & Zhang 2009, §4.3-4.4), at every centre of a chunk.

In a local frame (t1, t2, z) at p, with the neighbours' offsets (u, v) (eq. 23's
coordinates, divided by h) and their normals' components (X, Y) flipped to agree with
z, the normal field is modelled as

    X ~ mu1 + w11 u + w12 v,    Y ~ mu2 + w21 u + w22 v          (eqs. 23-24)

and fitted by least squares (eqs. 25-26; :mod:`core.kernels.lstsq`, optionally
reweighted by :mod:`core.kernels.robust`). (mu1, mu2) is the refined normal at p and
W = [[w11, w12], [w21, w22]] the matrix of dn in the basis (r_u, r_v) (eq. 21). W must
satisfy the symmetry constraint of eq. 22, g . (w11, w12, w21, w22) = 0 with
g = (mu1 mu2, -(1 - mu2^2), 1 - mu1^2, -mu1 mu2): "project" removes W's component
along g (§4.4), "exact" solves the constrained least squares with a Lagrange
multiplier in the metric of the normal equations. Degrees 2 and 3 add the higher
monomials of (u, v) to both models, so the slopes at p are not biased by the curving
of the normal field over a wide neighbourhood (k="auto").
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ._base import BLOCK, LEAF, OPTS, theta
from .algebra import n_terms
from .lstsq import (BX, BY, C1, C2, CX, CY, NO_LINEAR_SUMS, accumulate, add_linear, fit_scratch, monomials,
                    put_linear, reset, slope_variances, solve, solve_coefficients, solve_determined)
from .robust import robust_weights


class Frames(NamedTuple):
    """M centres with their neighbours and local frames (a :class:`core.patch.Chunk`).

    points, normals : the whole cloud's (N, 3) arrays (normals NaN where a point has none);
    idx : (M, k) neighbours of each centre; kc : (M,) how many of them are used;
    h : (M,) length unit of each centre; centres : (M,) point indices;
    t1, t2, z : (M, 3) local frames (z = the centre's current normal).
    """

    points: np.ndarray
    normals: np.ndarray
    idx: np.ndarray
    kc: np.ndarray
    h: np.ndarray
    centres: np.ndarray
    t1: np.ndarray
    t2: np.ndarray
    z: np.ndarray


class Settings(NamedTuple):
    """The options of the fit as kernel codes.

    theta_reach : h of eq. 14's weight in units of the centre's h (weighting 1);
    weighting : 0 uniform (eqs. 25-26), 1 theta of eq. 14;
    constraint : 0 none, 1 projection onto eq. 22's plane (§4.4), 2 exact;
    robust : 0 none, 1 Huber, 2 Tukey, with ``irls`` reweighting iterations;
    degree : 1 (the paper's linear model), 2 or 3, the most a centre's fit uses;
    rcond : singularity threshold; pivot : the smallest Cholesky pivot of a determined fit
    of degree 2 or 3 (below it the centre's fit falls a degree: :func:`solve_determined`);
    spread : the plane spread a robust reweighting must leave the neighbours (:func:`_fit_point`);
    rows : 0 (all), or the fewest neighbours a centre fits on: of k >= 2 x rows it fits
    every (k // rows)-th by distance (the same reach, :func:`thinned`).
    """

    theta_reach: float
    weighting: int
    constraint: int
    robust: int
    irls: int
    degree: int
    rcond: float
    pivot: float
    spread: float
    rows: int


class Fits(NamedTuple):
    """What the fit writes per centre: mu (M, 2), W (M, 2, 2) in units of 1/h, var (M, 3)
    the least-squares variances of W11, (W12 + W21)/2, W22, rms (M,) the weighted RMS
    residual of the normal components, spread (M,) their weighted RMS deviation from
    their mean (how much the normals turn), degree (M,) the degree fitted
    (:func:`solve_determined`; 0 where no fit) and coef (M, 2, MAX_TERMS) the polynomials of
    X and Y in (u, v) by :func:`poly_row`'s monomials (zero past the degree fitted; without
    the constraint), which :mod:`core.anchors` evaluates at the points around the centre
    (M, 2, 0 where no one reads them)."""

    mu: np.ndarray
    W: np.ndarray
    var: np.ndarray
    rms: np.ndarray
    spread: np.ndarray
    degree: np.ndarray
    coef: np.ndarray


@njit(**OPTS, inline="always")
def gather(f, r, row, n, weighting, theta_reach, s, stride=1):
    """Neighbours 0..n-1 of centre r of the :class:`Frames` ``f`` (row ``row`` of
    ``f.idx``) in its frame, into the scratch ``s`` (:func:`_neighbour`)."""
    frame = _frame(f, r)
    i, hi = f.centres[r], f.h[r]
    for j in range(n):
        s.u[j], s.v[j], s.X[j], s.Y[j], s.base[j] = _neighbour(f.points, f.normals, i, f.idx[row, j * stride], hi,
                                                               frame, weighting, theta_reach)


@njit(**OPTS, inline="always")
def _frame(f, r):
    """Centre r's frame (t1, t2, z) as nine numbers."""
    return (f.t1[r, 0], f.t1[r, 1], f.t1[r, 2], f.t2[r, 0], f.t2[r, 1], f.t2[r, 2], f.z[r, 0], f.z[r, 1], f.z[r, 2])


@njit(**OPTS, inline="always")
def _neighbour(points, normals, i, q, hi, frame, weighting, theta_reach):
    """Neighbour q of point i in i's ``frame`` (:func:`_frame`): offsets (u, v) / h, normal
    components (X, Y) flipped to agree with the frame's z (§4.3), and the base weight (0
    without a normal)."""
    a0, a1, a2, b0, b1, b2, c0, c1, c2 = frame
    nx, ny, nz = normals[q, 0], normals[q, 1], normals[q, 2]
    dx = (points[q, 0] - points[i, 0]) / hi
    dy = (points[q, 1] - points[i, 1]) / hi
    dz = (points[q, 2] - points[i, 2]) / hi
    u = dx * a0 + dy * a1 + dz * a2
    v = dx * b0 + dy * b1 + dz * b2
    if not math.isfinite(nx):
        return u, v, 0.0, 0.0, 0.0
    sgn = 1.0 if nx * c0 + ny * c1 + nz * c2 >= 0.0 else -1.0
    w = theta(math.sqrt(dx * dx + dy * dy + dz * dz) / theta_reach) if weighting == 1 else 1.0
    return u, v, sgn * (nx * a0 + ny * a1 + nz * a2), sgn * (nx * b0 + ny * b1 + nz * b2), w


@njit(**OPTS, parallel=True)
def normal_fit(f, opt, out, rows):
    """NF at every centre of the :class:`Frames` ``f`` with the :class:`Settings` ``opt``,
    written into the :class:`Fits` ``out`` (see the module docstring). Centre r's
    neighbours are row ``rows[r]`` of ``f.idx``, which may be the whole cloud's graph: a
    chunk of centres then needs no copy of its rows (320 wide with noise at k="auto")."""
    m = len(f.centres)
    kmax = f.idx.shape[1]
    n_blocks = (m + BLOCK - 1) // BLOCK
    linear = opt.degree == 1 and opt.robust == 0
    for blk in prange(n_blocks):
        _fit_block(f, opt, out, rows, blk * BLOCK, min(m, (blk + 1) * BLOCK), fit_scratch(kmax), linear)


@njit(**LEAF)
def _fit_block(f, opt, out, rows, start, stop, s, linear):
    """NF at centres start..stop-1 with the scratch ``s`` (allocated once per block: a
    per-point allocation would cost more than the fit); ``linear``: the paper's linear model
    without reweighting (:func:`_fit_linear`). Compiled without reference counting, as are the
    helpers it calls (:data:`~core.kernels._base.LEAF`: it allocates nothing; each record field
    read per centre otherwise counts its array, NR k = 15's fits 12 % faster without)."""
    for r in range(start, stop):
        stride = thinned(f.kc[r], opt.rows)
        n = (f.kc[r] + stride - 1) // stride
        if linear:
            degree = _fit_linear(f, opt, r, rows[r], n, s, stride)
        else:
            degree = _fit_point(f, opt, r, rows[r], n, s, stride)
        out.degree[r] = degree
        if degree > 0:
            _store(opt, degree, r, n, s, out)


@njit(**OPTS, inline="always")
def _fit_point(f, opt, r, row, n, s, stride):
    """Least squares (eqs. 25-26) of centre r's n neighbours (row ``row`` of f.idx), then ``opt.irls`` robust
    reweightings; returns the degree fitted, the highest up to ``opt.degree`` that the
    neighbourhood determines (at every solve: a reweighting that drops a far scan line
    can leave the rest too few lines for it), or 0 when the system is singular. Only the last solve computes the columns of G^-1 that the variances and the
    exact constraint need. A reweighting must leave the linear fit determined with
    ``opt.spread``-wide (:func:`_spans`): where it does not, its weights left one scan line
    (on a grid 5x sparser across its rows the Tukey weights of 20 exact neighbours kept the
    point's own row, whose residuals are nil, and a linear fit on it passed ``opt.rcond``:
    |H error| 1.3 with exact normals); the unweighted fit is kept."""
    gather(f, r, row, n, opt.weighting, opt.theta_reach, s, stride)
    for j in range(n):
        s.wt[j] = s.base[j]
    monomials(s.u, s.v, n, opt.degree, s.R)
    rounds = opt.irls if opt.robust > 0 else 0
    degree = opt.degree
    for it in range(rounds + 1):
        if it > 0:
            robust_weights(s, n, degree, opt.robust)
        reset(degree, s.vec, s.G, s.acc)
        accumulate(s.R, s.X, s.Y, s.wt, 0, n, degree, s.vec, s.G, s.acc, s.WR)
        if it > 0 and not _spans(s.G, opt.spread):
            return _unweighted(degree, opt, n, s)
        fitted = _solve_round(degree, opt.rcond, opt.pivot, s, it == rounds)
        if fitted == 0:
            return 0
        degree = fitted
    return degree


@njit(**OPTS, inline="always")
def _fit_linear(f, opt, r, row, n, s, stride):
    """:func:`_fit_point` for the paper's linear model without reweighting (eqs. 25-26):
    the sums straight from the neighbours, with no scratch rows (NR k = 15 at 100k points:
    a pass 48 -> 24 ms on one thread); the scratch path's numbers to rounding (~1e-16: the sums
    run in another order)."""
    frame, i, hi = _frame(f, r), f.centres[r], f.h[r]
    t = NO_LINEAR_SUMS
    for j in range(n):
        u, v, X, Y, w = _neighbour(f.points, f.normals, i, f.idx[row, j * stride], hi, frame, opt.weighting,
                                   opt.theta_reach)
        t = add_linear(t, w, u, v, X, Y)
    put_linear(t, s.vec, s.G, s.acc, False)
    return _solve_round(1, opt.rcond, opt.pivot, s, True)


@njit(**OPTS, inline="always")
def thinned(k, rows):
    """The stride of a centre's k neighbours when it fits on at least ``rows`` (0: all)."""
    return max(1, k // rows) if rows > 0 else 1


@njit(**OPTS, inline="always")
def _spans(G, spread):
    """Whether the weighted neighbours of the normal matrix ``G`` (its sums of 1, u, v)
    span the plane: sqrt(lambda_min / lambda_max) of their centred offsets at least
    ``spread`` (the plane spread of :mod:`core.plane_spread`, weighted; turning the frame
    does not change it, unlike the pivots of the equilibrated matrix)."""
    s1 = G[0, 0]
    if not s1 > 0.0:
        return False
    mu, mv = G[1, 0] / s1, G[2, 0] / s1
    a, b, c = G[1, 1] / s1 - mu * mu, G[2, 1] / s1 - mu * mv, G[2, 2] / s1 - mv * mv
    half = 0.5 * (a + c)
    root = math.sqrt(max(half * half - (a * c - b * b), 0.0))
    return half - root >= spread * spread * (half + root)


@njit(**OPTS, inline="always")
def _solve_round(degree, rcond, pivot, s, last):
    """One solve of :func:`_fit_point`: the degree fitted (0: singular), with the columns of
    G^-1 on the ``last`` round only."""
    if degree > 1:  # (the paper's linear fit takes the direct path: a third faster)
        return solve_determined(degree, rcond, pivot, s.vec, s.G, s.L, s.acc, last)
    if not last:
        return 1 if solve_coefficients(degree, rcond, s.vec, s.G, s.L, s.acc) else 0
    return 1 if solve(degree, rcond, s.vec, s.G, s.L, s.acc) else 0


@njit(**LEAF)
def _unweighted(degree, opt, n, s):
    """The plain least squares of :func:`_fit_point` up to ``degree``, where a reweighting
    left it undetermined."""
    for j in range(n):
        s.wt[j] = s.base[j]
    reset(degree, s.vec, s.G, s.acc)
    accumulate(s.R, s.X, s.Y, s.wt, 0, n, degree, s.vec, s.G, s.acc, s.WR)
    return _solve_round(degree, opt.rcond, opt.pivot, s, True)


@njit(**LEAF)
def _exact_constraint(vec):
    """mu and W of the least squares under eq. 22 (Lagrange multiplier in the metric of
    the normal equations; two fixed-point iterations on mu, which g depends on)."""
    cx0, cx1, cx2 = vec[CX, 0], vec[CX, 1], vec[CX, 2]
    cy0, cy1, cy2 = vec[CY, 0], vec[CY, 1], vec[CY, 2]
    # G^-1 a for a = (0, g1, g2, 0.. | 0, g3, g4, 0..): columns 1, 2 of G^-1 are needed
    e01, e11, e12 = vec[C1, 0], vec[C1, 1], vec[C1, 2]
    e02, e22 = vec[C2, 0], vec[C2, 2]
    ex0, ex1, ex2, ey0, ey1, ey2 = cx0, cx1, cx2, cy0, cy1, cy2
    for _ in range(2):
        m1, m2 = cx0, cy0
        g1, g2, g3, g4 = m1 * m2, -(1.0 - m2 * m2), 1.0 - m1 * m1, -m1 * m2
        ax0, ax1, ax2 = e01 * g1 + e02 * g2, e11 * g1 + e12 * g2, e12 * g1 + e22 * g2
        ay0, ay1, ay2 = e01 * g3 + e02 * g4, e11 * g3 + e12 * g4, e12 * g3 + e22 * g4
        num = g1 * ex1 + g2 * ex2 + g3 * ey1 + g4 * ey2
        den = g1 * ax1 + g2 * ax2 + g3 * ay1 + g4 * ay2
        if den == 0.0:
            break
        lam = num / den
        cx0, cx1, cx2 = ex0 - lam * ax0, ex1 - lam * ax1, ex2 - lam * ax2
        cy0, cy1, cy2 = ey0 - lam * ay0, ey1 - lam * ay1, ey2 - lam * ay2
    return cx0, cy0, cx1, cx2, cy1, cy2


@njit(**OPTS, inline="always")
def _store(opt, degree, r, n, s, out):
    """Write centre r's mu and W (under the constraint of eq. 22) and diagnostics of its fit of ``degree``."""
    vec, acc = s.vec, s.acc
    if opt.constraint == 2:
        cx0, cy0, w11, w12, w21, w22 = _exact_constraint(vec)
    else:
        cx0, cy0 = vec[CX, 0], vec[CY, 0]
        w11, w12, w21, w22 = vec[CX, 1], vec[CX, 2], vec[CY, 1], vec[CY, 2]
    if opt.constraint == 1:  # §4.4: the Euclidean projection onto g . w = 0
        g1, g2, g3, g4 = cx0 * cy0, -(1.0 - cy0 * cy0), 1.0 - cx0 * cx0, -cx0 * cy0
        t = (g1 * w11 + g2 * w12 + g3 * w21 + g4 * w22) / (g1 * g1 + g2 * g2 + g3 * g3 + g4 * g4)
        w11 -= t * g1
        w12 -= t * g2
        w21 -= t * g3
        w22 -= t * g4
    p = n_terms(degree)
    for a in range(out.coef.shape[2]):
        out.coef[r, 0, a] = vec[CX, a] if a < p else 0.0
        out.coef[r, 1, a] = vec[CY, a] if a < p else 0.0
    out.mu[r, 0] = cx0
    out.mu[r, 1] = cy0
    out.W[r, 0, 0] = w11
    out.W[r, 0, 1] = w12
    out.W[r, 1, 0] = w21
    out.W[r, 1, 1] = w22
    out.var[r, 0], out.var[r, 1], out.var[r, 2] = slope_variances(degree, n, vec, acc)
    sw = max(acc[0], 1e-300)
    out.rms[r] = math.sqrt((acc[3] + acc[4]) / sw)
    mx, my = vec[BX, 0] / sw, vec[BY, 0] / sw
    out.spread[r] = math.sqrt(max(acc[1] / sw - mx * mx + acc[2] / sw - my * my, 0.0))
