"""The least-squares sums of the jets of the automatic scale (:mod:`core.kernels.jets`,
:mod:`core.kernels.jet_degree`): a centre's neighbours in its frame, and the normal
equations of a height field w = sum c_ab u^a v^b grown neighbour by neighbour."""

from __future__ import annotations

import math

from numba import njit

from ._base import OPTS
from .algebra import poly_row

#: terms of the cubic jet
P3 = 10
#: terms of the largest jet the degree rule fits (degree 5)
P5 = 21


@njit(**OPTS)
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


@njit(**OPTS)
def _add(uvw, j0, j1, row, G, b, acc):
    """Cubic sums of neighbours j0 <= j < j1 into G (lower triangle), b and acc[0] = sum w^2."""
    for j in range(j0, j1):
        w = uvw[2, j]
        if not math.isfinite(w):
            continue
        poly_row(uvw[0, j], uvw[1, j], 3, row)
        acc[0] += w * w
        for a in range(P3):
            b[a] += row[a] * w
            for c in range(a + 1):
                G[a, c] += row[a] * row[c]


@njit(**OPTS)
def _sums(uvw, j0, j1, degree, row, G, b, acc):
    """Least-squares sums of the jet of ``degree`` over neighbours j0 <= j < j1 (offsets in
    ``uvw``, NaN heights left out) added onto G (lower triangle), b, acc[0] = sum w^2 and
    acc[1] = their count. Sums of a lower degree are the leading block of these (the
    monomials come by total degree, each computed the same way at every degree, and each
    entry adds the same products in the same order as :func:`_add`)."""
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
