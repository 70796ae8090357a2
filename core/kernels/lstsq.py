"""The weighted least squares of the normal fit (eqs. 25-26, and degree 2-3 models).

Per centre a scratch record holds the monomials R of the neighbours' offsets, the normal
matrix G (lower triangle), its Cholesky factor L, the vectors ``vec`` (rows BX, BY:
right-hand sides; CX, CY: coefficients; C1, C2: columns 1, 2 of G^-1; D, E: work) and
the sums ``acc`` = (sum w, sum w X^2, sum w Y^2, RSS X, RSS Y).

G[a, c] = sum w R_a R_c depends on (a, c) only through the monomial R_a R_c, of degree
<= 2 x degree: a cubic's 55 entries are 28 distinct moments sum w u^i v^j, and only those
are summed (:data:`MOMENT_OF`, :data:`MOMENT_PAIR`). Measured on 226 neighbours: 0.78 us
per cubic accumulation against 1.19 us for the 55 sums.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ._base import LEAF, OPTS
from .algebra import MAX_TERMS, chol_solve, cholesky, determined, n_terms

# rows of the per-block vector scratch of the NF kernels
BX, BY, CX, CY, C1, C2, D, E = range(8)


def _moment_tables(max_degree):
    """Monomials are numbered by total degree t, then by the power of v (the order of
    :func:`poly_row`): u^i v^j is number t (t + 1) / 2 + j. Returns MOMENT_OF[a, c], the
    number of R_a R_c, and MOMENT_PAIR[m], the entry (a, c) with a >= c of G (a, c of
    degree ceil(t / 2) and floor(t / 2)) whose sum stands for monomial m, for every
    monomial of degree t <= 2 x max_degree: any fit of degree d <= max_degree finds the
    moments of degree <= 2 d among the entries of its own G."""
    def number(i, j):
        return (i + j) * (i + j + 1) // 2 + j

    powers = [(t - j, j) for t in range(2 * max_degree + 1) for j in range(t + 1)]
    p = (max_degree + 1) * (max_degree + 2) // 2
    of = np.array([[number(powers[a][0] + powers[c][0], powers[a][1] + powers[c][1]) for c in range(p)]
                   for a in range(p)], dtype=np.int64)
    pair = np.empty((len(powers), 2), dtype=np.int64)
    for m, (i, j) in enumerate(powers):
        half = (i + j + 1) // 2
        ai = min(i, half)
        a, c = number(ai, half - ai), number(i - ai, j - half + ai)
        pair[m] = max(a, c), min(a, c)
    return of, pair


MOMENT_OF, MOMENT_PAIR = _moment_tables(3)


class Scratch(NamedTuple):
    """Per-block work arrays of the NF kernels (allocated once per block of centres: a
    per-point allocation would cost more than the fit). Per neighbour: offsets u, v (in
    units of h), normal components X, Y, base and current weights, residuals res and a
    copy tmp for the median; then the monomials R, the vectors of :func:`solve` (rows
    BX..E), the normal matrix G, its factor L, the sums acc and WR, the weighted
    monomials of :func:`accumulate`."""

    u: np.ndarray
    v: np.ndarray
    X: np.ndarray
    Y: np.ndarray
    base: np.ndarray
    wt: np.ndarray
    res: np.ndarray
    tmp: np.ndarray
    R: np.ndarray
    vec: np.ndarray
    G: np.ndarray
    L: np.ndarray
    acc: np.ndarray
    WR: np.ndarray


@njit(**OPTS)
def fit_scratch(kmax):
    """A :class:`Scratch` for neighbourhoods of up to ``kmax`` points."""
    return Scratch(np.empty(kmax), np.empty(kmax), np.empty(kmax), np.empty(kmax), np.empty(kmax),
                   np.empty(kmax), np.empty(kmax), np.empty(kmax), np.empty((MAX_TERMS, kmax)),
                   np.zeros((E + 1, MAX_TERMS)), np.zeros((MAX_TERMS, MAX_TERMS)),
                   np.zeros((MAX_TERMS, MAX_TERMS)), np.zeros(5), np.empty((MAX_TERMS, kmax)))


@njit(**OPTS, inline="always")
def monomials(u, v, n, degree, R):
    """R[:, j] = the monomials (:func:`poly_row`) of neighbour j < n, once per point:
    every reweighting and every nested size reuses them. Row by row (each monomial is the
    same product of an earlier one and u or v as in :func:`poly_row`, so the same bits):
    the loops over the neighbours vectorise, where :func:`poly_row` into each column
    wrote strided and read back what it had just written (320 neighbours of a cubic:
    9.9 -> 0.6 us)."""
    for j in range(n):
        R[0, j] = 1.0
    prev = 0
    c = 1
    for d in range(1, degree + 1):
        for b in range(d):
            _times(R[prev + b], u, n, R[c])
            c += 1
        _times(R[prev + d - 1], v, n, R[c])
        c += 1
        prev += d


@njit(**OPTS, inline="always")
def _times(src, x, n, out):
    """out[:n] = src[:n] * x[:n]."""
    for j in range(n):
        out[j] = src[j] * x[j]


#: no sums yet (:func:`add_linear`)
NO_LINEAR_SUMS = (0.0,) * 14


@njit(**OPTS, inline="always")
def add_linear(t, w, u, v, X, Y):
    """The 14 sums ``t`` of the linear normal equations (sum w, w u, w v, w uu, w uv, w vv, w X,
    w X u, w X v, w Y, w Y u, w Y v, w XX, w YY) with a neighbour of weight w at (u, v) whose
    normal components are (X, Y) added."""
    wu, wv = w * u, w * v
    return (t[0] + w, t[1] + wu, t[2] + wv, t[3] + wu * u, t[4] + wu * v, t[5] + wv * v, t[6] + w * X,
            t[7] + wu * X, t[8] + wv * X, t[9] + w * Y, t[10] + wu * Y, t[11] + wv * Y, t[12] + w * X * X,
            t[13] + w * Y * Y)


@njit(**OPTS, inline="always")
def put_linear(t, vec, G, acc, add):
    """The sums ``t`` of :func:`add_linear` into G, the right-hand sides and acc: added to
    what they hold (``add``), else in place of it (no :func:`reset` needed)."""
    for a, b, c in ((0, 0, 0), (1, 0, 1), (2, 0, 2), (1, 1, 3), (2, 1, 4), (2, 2, 5)):
        G[a, b] = G[a, b] + t[c] if add else t[c]
    for a in range(3):
        vec[BX, a] = vec[BX, a] + t[6 + a] if add else t[6 + a]
        vec[BY, a] = vec[BY, a] + t[9 + a] if add else t[9 + a]
    for a, c in ((0, 0), (1, 12), (2, 13)):
        acc[a] = acc[a] + t[c] if add else t[c]


@njit(**LEAF, fastmath=True)
def _accumulate_linear(R, X, Y, wt, j0, j1, vec, G, acc):
    """:func:`accumulate` for degree 1: all sums in one pass (short neighbourhoods
    gain nothing from vectors)."""
    t = NO_LINEAR_SUMS
    for j in range(j0, j1):
        t = add_linear(t, wt[j], R[1, j], R[2, j], X[j], Y[j])
    put_linear(t, vec, G, acc, True)


@njit(**OPTS, inline="always")
def accumulate(R, X, Y, wt, j0, j1, degree, vec, G, acc, WR):
    """Add neighbours j0..j1-1 to the weighted normal equations of X and Y on the
    monomials R (G lower triangle, right-hand sides vec[BX], vec[BY]) and to acc =
    (sum w, sum w X^2, sum w Y^2). Sums run over neighbours innermost (vectorised), once
    per distinct moment of G (the other entries are copies); degree 1 sums everything in
    one pass (its few sums over short neighbourhoods gain nothing from vectors). Inlined
    into the caller, so a centre pays one call, not two (a call that passes arrays costs
    about as much as the linear sums of 15 neighbours); the sums themselves keep their
    own fastmath, which inlining would drop. ``WR`` (MAX_TERMS, >= j1): scratch for the
    weighted monomials."""
    if degree == 1:
        _accumulate_linear(R, X, Y, wt, j0, j1, vec, G, acc)
    else:
        _accumulate_moments(R, X, Y, wt, j0, j1, degree, vec, G, acc, WR)


@njit(**LEAF, fastmath=True)
def _accumulate_moments(R, X, Y, wt, j0, j1, degree, vec, G, acc, WR):
    """:func:`accumulate` for degree 2 or 3: the weighted monomials w R_a are kept (WR)
    from the right-hand sides' loop, so each moment is a dot product of two rows (the same
    products: 4.3 -> 3.6 us on 320 neighbours of a cubic)."""
    p = n_terms(degree)
    for a in range(p):
        sx = 0.0
        sy = 0.0
        for j in range(j0, j1):
            t = wt[j] * R[a, j]
            WR[a, j] = t
            sx += t * X[j]
            sy += t * Y[j]
        vec[BX, a] += sx
        vec[BY, a] += sy
    for m in range(n_terms(2 * degree)):
        a, c = MOMENT_PAIR[m, 0], MOMENT_PAIR[m, 1]
        g = 0.0
        for j in range(j0, j1):
            g += WR[a, j] * R[c, j]
        G[a, c] += g
    copy_moments(G, p)
    s1 = 0.0
    s2 = 0.0
    for j in range(j0, j1):
        s1 += wt[j] * X[j] * X[j]
        s2 += wt[j] * Y[j] * Y[j]
    acc[0] = G[0, 0]  # sum w: both are summed since the last reset
    acc[1] += s1
    acc[2] += s2


@njit(**OPTS, inline="always")
def copy_moments(G, p):
    """Fill the lower triangle of the first ``p`` rows of G from its distinct moments: each
    entry (a, c) becomes the one entry :data:`MOMENT_PAIR` sums for their moment R_a R_c."""
    for a in range(p):
        for c in range(a + 1):
            m = MOMENT_OF[a, c]
            G[a, c] = G[MOMENT_PAIR[m, 0], MOMENT_PAIR[m, 1]]


@njit(**OPTS, inline="always")
def reset(degree, vec, G, acc):
    """Zero the sums of :func:`accumulate` for a fit of ``degree`` (loops: slices of these
    small arrays cost more than zeroing them)."""
    p = n_terms(degree)
    for a in range(p):
        for c in range(p):
            G[a, c] = 0.0
        vec[BX, a] = 0.0
        vec[BY, a] = 0.0
    for a in range(len(acc)):
        acc[a] = 0.0


@njit(**OPTS, inline="always")
def solve_linear(rcond, vec, G, acc):
    """:func:`solve` for degree 1 (the paper's eqs. 25–26) by the closed-form inverse of
    the equilibrated 3x3 matrix: the common case, and twice as fast as a Cholesky."""
    s1, su, sv, suu, suv, svv = G[0, 0], G[1, 0], G[2, 0], G[1, 1], G[2, 1], G[2, 2]
    if not (s1 > 0.0 and suu > 0.0 and svv > 0.0):
        return False
    d0, d1, d2 = math.sqrt(s1), math.sqrt(suu), math.sqrt(svv)
    g01, g02, g12 = su / (d0 * d1), sv / (d0 * d2), suv / (d1 * d2)
    i00 = 1.0 - g12 * g12
    i01 = g02 * g12 - g01
    i02 = g01 * g12 - g02
    i11 = 1.0 - g02 * g02
    i12 = g01 * g02 - g12
    i22 = 1.0 - g01 * g01
    det = i00 + g01 * i01 + g02 * i02
    if not det > rcond:
        return False
    # G = D Gs D, so G^-1 = D^-1 adj(Gs) D^-1 / det
    e00 = i00 / (det * d0 * d0)
    e01 = i01 / (det * d0 * d1)
    e02 = i02 / (det * d0 * d2)
    e11 = i11 / (det * d1 * d1)
    e12 = i12 / (det * d1 * d2)
    e22 = i22 / (det * d2 * d2)
    x0, x1, x2 = vec[BX, 0], vec[BX, 1], vec[BX, 2]
    y0, y1, y2 = vec[BY, 0], vec[BY, 1], vec[BY, 2]
    vec[CX, 0] = e00 * x0 + e01 * x1 + e02 * x2
    vec[CX, 1] = e01 * x0 + e11 * x1 + e12 * x2
    vec[CX, 2] = e02 * x0 + e12 * x1 + e22 * x2
    vec[CY, 0] = e00 * y0 + e01 * y1 + e02 * y2
    vec[CY, 1] = e01 * y0 + e11 * y1 + e12 * y2
    vec[CY, 2] = e02 * y0 + e12 * y1 + e22 * y2
    vec[C1, 0], vec[C1, 1], vec[C1, 2] = e01, e11, e12
    vec[C2, 0], vec[C2, 1], vec[C2, 2] = e02, e12, e22
    acc[3] = max(acc[1] - (vec[CX, 0] * x0 + vec[CX, 1] * x1 + vec[CX, 2] * x2), 0.0)
    acc[4] = max(acc[2] - (vec[CY, 0] * y0 + vec[CY, 1] * y1 + vec[CY, 2] * y2), 0.0)
    return True


@njit(**OPTS, inline="always")
def solve(degree, rcond, vec, G, L, acc):
    """Least squares of X and Y on the monomials (eqs. 25–26 for degree 1).

    Fills vec[CX], vec[CY] (coefficients: constant = mu, then the slopes = W rows),
    vec[C1], vec[C2] (columns 1, 2 of G^-1) and acc[3], acc[4] (residual sums of
    squares of X, Y). False when G is near singular.
    """
    if degree == 1:
        return solve_linear(rcond, vec, G, acc)
    if not solve_coefficients(degree, rcond, vec, G, L, acc):
        return False
    p = n_terms(degree)
    e = vec[E]
    e[:p] = 0.0
    e[1] = 1.0
    chol_solve(L, vec[D], p, e, vec[C1])
    e[1] = 0.0
    e[2] = 1.0
    chol_solve(L, vec[D], p, e, vec[C2])
    return True


@njit(**LEAF)
def solve_coefficients(degree, rcond, vec, G, L, acc):
    """:func:`solve` without the columns of G^-1 (vec[C1], vec[C2]), which only the
    variances and the exact constraint need: what an intermediate reweighting needs."""
    if degree == 1:
        return solve_linear(rcond, vec, G, acc)
    p = n_terms(degree)
    if not cholesky(G, p, rcond, vec[D], L):
        return False
    chol_solve(L, vec[D], p, vec[BX], vec[CX])
    chol_solve(L, vec[D], p, vec[BY], vec[CY])
    fx = fy = 0.0
    for a in range(p):
        fx += vec[CX, a] * vec[BX, a]
        fy += vec[CY, a] * vec[BY, a]
    acc[3] = max(acc[1] - fx, 0.0)
    acc[4] = max(acc[2] - fy, 0.0)
    return True


@njit(**LEAF)
def solve_determined(degree, rcond, pivot, vec, G, L, acc, columns):
    """The highest degree d <= ``degree`` whose fit the sums determine, solved: for d >= 2
    the smallest eigenvalue of the scaled normal matrix above ``pivot``
    (:func:`~core.kernels.algebra.determined`: the same in any tangent axes), for d = 1 (the
    paper's model) every equilibrated Cholesky pivot above ``rcond``. The sums of degree d hold those of every lower degree
    (monomials are numbered by total degree, so a lower degree's normal matrix is a
    leading block), so a fit that its neighbourhood does not determine (the neighbours on
    two or three scan lines: u^3 is a combination of 1, u, u^2 on three values of u) falls
    to a lower degree without new sums. ``columns``: :func:`solve`, else
    :func:`solve_coefficients`. Returns d, or 0 when not even the linear fit is determined."""
    for d in range(degree, 0, -1):
        if d > 1 and not determined(G, d, pivot, vec[D], L):
            continue
        if solve(d, rcond, vec, G, L, acc) if columns else solve_coefficients(d, rcond, vec, G, L, acc):
            return d
    return 0


@njit(**OPTS, inline="always")
def slope_variances(degree, n, vec, acc):
    """Least-squares variances of W11, (W12 + W21)/2 and W22 from the residuals."""
    p = n_terms(degree)
    dof = max(acc[0] * (1.0 - p / max(n, p + 1)), 1e-12)
    sx2 = acc[3] / dof
    sy2 = acc[4] / dof
    e11, e22 = vec[C1, 1], vec[C2, 2]
    return sx2 * e11, 0.25 * (sx2 * e22 + sy2 * e11), sy2 * e22
