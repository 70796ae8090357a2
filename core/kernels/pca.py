"""Initial normals by weighted PCA (paper eqs. 13-14)."""

from __future__ import annotations

import math

from numba import njit, prange

from ._base import OPTS, theta
from .algebra import add_outer, smallest_eigvec_sym3


@njit(**OPTS, parallel=True)
def pca_normals(points, idx, dist, start, reach, collinear, normals, ok):
    """Weighted-PCA normal of points ``start + i`` (eqs. 13–14), written into ``normals`` / ``ok``.

    Numpy reference: C = sum_i theta(d_i/h) (p_i - q)(p_i - q)^T / h^2, with h =
    reach x distance to the k-th neighbour; n = eigenvector of the smallest eigenvalue.
    """
    for i in prange(idx.shape[0]):
        _pca_row(points, start + i, idx, dist, i, reach, collinear, normals, ok)


@njit(**OPTS, parallel=True)
def pca_normals_at(points, centres, idx, dist, reach, collinear, normals, ok):
    """:func:`pca_normals` of points ``centres[i]`` (any), on row i of ``idx`` / ``dist``."""
    for i in prange(len(centres)):
        _pca_row(points, centres[i], idx, dist, i, reach, collinear, normals, ok)


@njit(**OPTS)
def _pca_row(points, g, idx, dist, i, reach, collinear, normals, ok):
    """The weighted-PCA normal of point ``g`` on row i of ``idx`` / ``dist`` into row i of the outputs."""
    k = idx.shape[1]
    h = dist[i, k - 1] * reach
    ok[i] = False
    normals[i, 0] = math.nan
    normals[i, 1] = math.nan
    normals[i, 2] = math.nan
    if not h > 0.0:
        return
    c00 = c01 = c02 = c11 = c12 = c22 = 0.0
    for j in range(k):
        q = idx[i, j]
        w = theta(dist[i, j] / h)
        dx = (points[q, 0] - points[g, 0]) / h
        dy = (points[q, 1] - points[g, 1]) / h
        dz = (points[q, 2] - points[g, 2]) / h
        c00, c01, c02, c11, c12, c22 = add_outer(c00, c01, c02, c11, c12, c22, w, dx, dy, dz)
    l0, l1, l2, x, y, z = smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
    if l1 > collinear * max(l2, 1e-300) and l1 > l0 and math.isfinite(x):
        normals[i, 0], normals[i, 1], normals[i, 2] = x, y, z
        ok[i] = True


@njit(**OPTS, parallel=True)
def normal_spread(normals, idx, out):
    """``out[i]``: how much the normals of the neighbours ``idx[i]`` agree with each other,
    as the largest eigenvalue of their unsigned scatter mean(n n^T) (1: all on one line;
    about 1/2 where two faces at 90 degrees share the neighbourhood), in closed form
    (:func:`core.kernels.algebra.smallest_eigvec_sym3`). Neighbours without a normal (NaN) are left out; NaN
    where none has one."""
    n, k = idx.shape
    for i in prange(n):
        c00 = c01 = c02 = c11 = c12 = c22 = 0.0
        seen = 0
        for j in range(k):
            q = idx[i, j]
            x, y, z = normals[q, 0], normals[q, 1], normals[q, 2]
            if not math.isfinite(x):
                continue
            c00 += x * x
            c01 += x * y
            c02 += x * z
            c11 += y * y
            c12 += y * z
            c22 += z * z
            seen += 1
        out[i] = math.nan
        if seen > 0:
            _, _, largest, _, _, _ = smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
            out[i] = largest / seen
