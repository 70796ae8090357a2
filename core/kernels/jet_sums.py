"""The least-squares sums of the jets of the automatic scale (:mod:`core.kernels.jets`,
:mod:`core.kernels.jet_degree`): a centre's neighbours in its frame, and the normal
equations of a height field w = sum c_ab u^a v^b grown neighbour by neighbour."""

from __future__ import annotations

import math

from numba import njit

from ._base import LEAF, OPTS
from .algebra import n_terms, poly_row
from .lstsq import MOMENT_PAIR, copy_moments, monomials

#: terms of the cubic jet
P3 = 10
#: terms of the largest jet the degree rule fits (degree 5)
P5 = 21


@njit(**OPTS, inline="always")
def _offsets(f, r, j0, j1, uvw):
    """Neighbours j0 <= j < j1 of centre r in its frame, lengths in units of f.h[r]; the
    height uvw[2, j] is NaN for a neighbour without a normal (a known outlier), which the
    sums leave out."""
    i = f.centres[r]
    for j in range(j0, j1):
        q = f.idx[r, j]
        if not math.isfinite(f.normals[q, 0]):
            uvw[2, j] = math.nan
            continue
        dx = (f.points[q, 0] - f.points[i, 0]) / f.h[r]
        dy = (f.points[q, 1] - f.points[i, 1]) / f.h[r]
        dz = (f.points[q, 2] - f.points[i, 2]) / f.h[r]
        uvw[0, j] = dx * f.t1[r, 0] + dy * f.t1[r, 1] + dz * f.t1[r, 2]
        uvw[1, j] = dx * f.t2[r, 0] + dy * f.t2[r, 1] + dz * f.t2[r, 2]
        uvw[2, j] = dx * f.z[r, 0] + dy * f.z[r, 1] + dz * f.z[r, 2]


@njit(**LEAF)
def ring_sums(uvw, j0, j1, G, b, acc, pu, pv, pw, R):
    """Cubic sums of the neighbours j0 <= j < j1 added onto G (lower triangle), b and acc[0] =
    sum w^2 (NaN heights left out), by moments: those neighbours packed into ``pu``, ``pv``, ``pw``
    (>= j1 - j0 each), their monomials row by row (:func:`core.kernels.lstsq.monomials`), then each
    of the 28 distinct moments of G as one dot product over them (:func:`_moments`). Adding
    the 55 products of each neighbour into G one at a time (as :func:`_sums` does) took twice
    as long (320 neighbours in the jet rule's 10 rings: 7.5 -> 3.8 us). The same sums to
    rounding, not the same bits; the quiet points' degree rule keeps :func:`_sums`, whose
    sums must not depend on where the neighbours are split (:mod:`core.kernels.jet_degree`)."""
    n = 0
    for j in range(j0, j1):
        w = uvw[2, j]
        if math.isfinite(w):
            pu[n], pv[n], pw[n] = uvw[0, j], uvw[1, j], w
            n += 1
    monomials(pu, pv, n, 3, R)
    _moments(R, pw, n, G, b, acc)


@njit(**LEAF, fastmath=True)
def _moments(R, w, n, G, b, acc):
    """G (lower triangle), b and acc[0] += the cubic sums over the n monomial columns of R
    and heights w, one dot product per distinct moment (vectorised)."""
    s = 0.0
    for j in range(n):
        s += w[j] * w[j]
    acc[0] += s
    for a in range(P3):
        s = 0.0
        for j in range(n):
            s += R[a, j] * w[j]
        b[a] += s
    for m in range(n_terms(6)):
        a, c = MOMENT_PAIR[m, 0], MOMENT_PAIR[m, 1]
        s = 0.0
        for j in range(n):
            s += R[a, j] * R[c, j]
        G[a, c] += s
    copy_moments(G, P3)


@njit(**LEAF)
def _sums(uvw, j0, j1, degree, row, G, b, acc):
    """Least-squares sums of the jet of ``degree`` over neighbours j0 <= j < j1 (offsets in
    ``uvw``, NaN heights left out) added onto G (lower triangle), b, acc[0] = sum w^2 and
    acc[1] = their count. Sums of a lower degree are the leading block of these (the
    monomials come by total degree, each computed the same way at every degree, and each
    entry adds the same products in the same order); a neighbour at a time, so the sums do
    not depend on where the neighbours are split into rings."""
    p = (degree + 1) * (degree + 2) // 2
    for j in range(j0, j1):
        w = uvw[2, j]
        if not math.isfinite(w):
            continue
        acc[1] += 1.0
        poly_row(uvw[0, j], uvw[1, j], degree, row)
        acc[0] += w * w
        for a in range(p):
            b[a] += row[a] * w
            for c in range(a + 1):
                G[a, c] += row[a] * row[c]
