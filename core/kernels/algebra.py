"""Small dense linear algebra inside the kernels: 3x3 symmetric eigenvector, Cholesky."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._base import LEAF, OPTS


@njit(**OPTS)
def smallest_eigvec_sym3(a00, a01, a02, a11, a12, a22):
    """Eigenvalues (ascending) of a symmetric 3x3 and the unit eigenvector of the smallest.

    Closed-form eigenvalues (Smith 1961); the eigenvector is the largest cross product of
    two rows of A - l_min I. Returns (l0, l1, l2, x, y, z); NaN vector if A = c I.
    """
    p1 = a01 * a01 + a02 * a02 + a12 * a12
    q = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p2 = b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * p1
    if p2 <= 0.0:
        return q, q, q, math.nan, math.nan, math.nan
    p = math.sqrt(p2 / 6.0)
    if p * p * p == 0.0:  # harden: underflows for entries below ~1e-103; no direction then
        return q, q, q, math.nan, math.nan, math.nan
    det = (
        b00 * (b11 * b22 - a12 * a12)
        - a01 * (a01 * b22 - a12 * a02)
        + a02 * (a01 * a12 - b11 * a02)
    )
    r = det / (2.0 * p * p * p)
    r = min(1.0, max(-1.0, r))
    phi = math.acos(r) / 3.0
    l2 = q + 2.0 * p * math.cos(phi)
    l0 = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    l1 = 3.0 * q - l2 - l0
    r0x, r0y, r0z = a00 - l0, a01, a02
    r1x, r1y, r1z = a01, a11 - l0, a12
    r2x, r2y, r2z = a02, a12, a22 - l0
    best = -1.0
    ox = oy = oz = 0.0
    for c in range(3):
        if c == 0:
            x, y, z = r0y * r1z - r0z * r1y, r0z * r1x - r0x * r1z, r0x * r1y - r0y * r1x
        elif c == 1:
            x, y, z = r0y * r2z - r0z * r2y, r0z * r2x - r0x * r2z, r0x * r2y - r0y * r2x
        else:
            x, y, z = r1y * r2z - r1z * r2y, r1z * r2x - r1x * r2z, r1x * r2y - r1y * r2x
        nn = x * x + y * y + z * z
        if nn > best:
            best = nn
            ox, oy, oz = x, y, z
    s = math.sqrt(best)
    if not s > 0.0:
        return l0, l1, l2, math.nan, math.nan, math.nan
    return l0, l1, l2, ox / s, oy / s, oz / s


#: most monomials of the normal fit (degree 3: 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3)
MAX_TERMS = 10
#: their binomial coefficients: u^a v^b times its root is an orthonormal basis of each degree
#: for the turns of the (u, v) plane (:func:`determined`)
_BINOMIAL = np.array([1.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 3.0, 3.0, 1.0])


@njit(**OPTS, inline="always")
def n_terms(degree):
    """Monomials of a bivariate polynomial of ``degree``."""
    return (degree + 1) * (degree + 2) // 2


@njit(**OPTS, inline="always")
def poly_row(u, v, degree, row):
    """Monomials of (u, v) by total degree: 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3."""
    row[0] = 1.0
    prev = 0
    c = 1
    for d in range(1, degree + 1):
        for b in range(d):
            row[c] = row[prev + b] * u
            c += 1
        row[c] = row[prev + d - 1] * v
        c += 1
        prev += d


@njit(**LEAF)
def cholesky(G, p, rcond, d, L):
    """Cholesky factor L of the equilibrated p x p matrix G (lower triangle used; unit
    diagonal after scaling by d = sqrt(diag G)). False when a pivot is <= rcond
    (rank deficient: too few or collinear neighbours for the polynomial)."""
    for a in range(p):
        if not G[a, a] > 0.0:
            return False
        d[a] = math.sqrt(G[a, a])
    for a in range(p):
        for c in range(a + 1):
            s = G[a, c] / (d[a] * d[c])
            for e in range(c):
                s -= L[a, e] * L[c, e]
            if a == c:
                if not s > rcond:
                    return False
                L[a, a] = math.sqrt(s)
            else:
                L[a, c] = s / L[c, c]
    return True


@njit(**LEAF)
def determined(G, degree, tau, d, L):
    """Whether the smallest eigenvalue of the normal matrix G (lower triangle used) of a
    polynomial of ``degree`` in (u, v) exceeds ``tau`` once the monomials are scaled as an
    orthonormal basis of each degree under turns of the (u, v) plane (u^a v^b times the
    square root of its binomial coefficient) and to a mean diagonal of 1 per degree: the
    Cholesky factor of that matrix minus ``tau`` I exists (``d``, ``L``: scratch). The
    equilibrated pivots of :func:`cholesky` depend on the tangent axes, so a cloud and the
    same cloud turned could fit different degrees; this does not (each degree's block turns
    by an orthogonal matrix and keeps its trace), and it also sees a dependence among
    monomials that the order of the pivots hides."""
    p = n_terms(degree)
    start = 0
    for e in range(degree + 1):
        s = 0.0
        for a in range(start, start + e + 1):
            s += _BINOMIAL[a] * G[a, a]
        if not s > 0.0:
            return False
        for a in range(start, start + e + 1):
            d[a] = math.sqrt(_BINOMIAL[a] * (e + 1) / s)
        start += e + 1
    for a in range(p):
        for c in range(a + 1):
            s = G[a, c] * d[a] * d[c] - (tau if a == c else 0.0)
            for e in range(c):
                s -= L[a, e] * L[c, e]
            if a == c:
                if not s > 0.0:
                    return False
                L[a, a] = math.sqrt(s)
            else:
                L[a, c] = s / L[c, c]
    return True


@njit(**LEAF)
def chol_solve(L, d, p, b, x):
    """x = G^-1 b with the factor of :func:`cholesky` (x must not alias b)."""
    for a in range(p):
        s = b[a] / d[a]
        for e in range(a):
            s -= L[a, e] * x[e]
        x[a] = s / L[a, a]
    for a in range(p - 1, -1, -1):
        s = x[a]
        for e in range(a + 1, p):
            s -= L[e, a] * x[e]
        x[a] = s / L[a, a]
    for a in range(p):
        x[a] /= d[a]


@njit(**OPTS, inline="always")
def tangent_pair(nx, ny, nz):
    """An orthonormal tangent basis of the unit normal n: t1 = n x a / |n x a| (a the x axis,
    or the y axis where n is near x) and t2 = n x t1; (t1x, t1y, t1z, t2x, t2y, t2z)."""
    if abs(nx) < 0.9:
        ax, ay, az = 1.0, 0.0, 0.0
    else:
        ax, ay, az = 0.0, 1.0, 0.0
    t1x, t1y, t1z = ny * az - nz * ay, nz * ax - nx * az, nx * ay - ny * ax
    s = math.sqrt(t1x * t1x + t1y * t1y + t1z * t1z)
    t1x, t1y, t1z = t1x / s, t1y / s, t1z / s
    return t1x, t1y, t1z, ny * t1z - nz * t1y, nz * t1x - nx * t1z, nx * t1y - ny * t1x


@njit(**OPTS, inline="always")
def add_outer(m00, m01, m02, m11, m12, m22, w, dx, dy, dz):
    """The six entries of a symmetric 3x3 moment matrix plus w d d^T."""
    return (m00 + w * dx * dx, m01 + w * dx * dy, m02 + w * dx * dz,
            m11 + w * dy * dy, m12 + w * dy * dz, m22 + w * dz * dz)


@njit(**OPTS, inline="always")
def row_scatter(points, idx, r, j0, k):
    """The centroid of the points ``idx[r, j0:k]`` and their second moments about it:
    (cx, cy, cz, c00, c01, c02, c11, c12, c22)."""
    m = k - j0
    cx = cy = cz = 0.0
    for j in range(j0, k):
        q = idx[r, j]
        cx += points[q, 0]
        cy += points[q, 1]
        cz += points[q, 2]
    cx, cy, cz = cx / m, cy / m, cz / m
    c00 = c01 = c02 = c11 = c12 = c22 = 0.0
    for j in range(j0, k):
        q = idx[r, j]
        dx, dy, dz = points[q, 0] - cx, points[q, 1] - cy, points[q, 2] - cz
        c00, c01, c02, c11, c12, c22 = add_outer(c00, c01, c02, c11, c12, c22, 1.0, dx, dy, dz)
    return cx, cy, cz, c00, c01, c02, c11, c12, c22
