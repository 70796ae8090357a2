"""Whether a neighbourhood spans the tangent plane (numba, ``nogil``, all cores)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS, theta
from .algebra import add_outer, chol_solve, cholesky, row_scatter, smallest_eigvec_sym3, tangent_pair


@njit(**OPTS, parallel=True)
def plane_spread(points, normals, centres, idx, rows, kc, out):
    """out[r] = sqrt(lambda_min / lambda_max) of the second moments about centre
    ``centres[r]`` of its first ``kc[r]`` neighbours (row ``rows[r]`` of ``idx``, which may
    be the whole cloud's graph, read in place), projected on the
    plane normal to its normal: 1 for neighbours all around, 0 for neighbours on a line
    through it. NaN where the normal is not finite or every neighbour sits on the centre.

    The projected moment matrix M has the eigenvalue 0 along the normal, so its other two
    are the roots of x^2 - tr(M) x + e2(M) (e2: the sum of its principal 2x2 minors)."""
    for r in prange(len(centres)):
        i = centres[r]
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        if not (math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)):
            out[r] = math.nan
            continue
        m00 = m01 = m02 = m11 = m12 = m22 = 0.0
        row = rows[r]
        for j in range(kc[r]):
            q = idx[row, j]
            dx, dy, dz = points[q, 0] - points[i, 0], points[q, 1] - points[i, 1], points[q, 2] - points[i, 2]
            s = dx * nx + dy * ny + dz * nz
            dx, dy, dz = dx - s * nx, dy - s * ny, dz - s * nz
            m00, m01, m02, m11, m12, m22 = add_outer(m00, m01, m02, m11, m12, m22, 1.0, dx, dy, dz)
        out[r] = _spread(m00, m01, m02, m11, m12, m22)


@njit(**OPTS, parallel=True)
def thin_shapes(points, normals, start, idx, dist, reach, spread, weighted, flat):
    """Three shapes of the neighbours of points ``start + i`` (row i of ``idx``, distances
    ``dist``), each row read once (three kernels before; the same operations, the same bits):
    spread[i] as :func:`plane_spread`; weighted[i] the same with each neighbour weighted by
    eq. 14 as in the weighted PCA (:func:`core.kernels.pca.pca_normals`, h = ``reach`` x the
    row's last distance), the spread the PCA normal was fitted on, where the farthest
    neighbours, weighed about 1e-3, count for little; flat[i] as :func:`scatter_shapes`.
    spread and weighted are NaN where the normal is not finite, weighted also where h <= 0."""
    k = idx.shape[1]
    for i in prange(idx.shape[0]):
        _, _, _, c00, c01, c02, c11, c12, c22 = row_scatter(points, idx, i, 0, k)
        l0, l1, _, _, _, _ = smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
        flat[i] = math.sqrt(max(l0, 0.0) / l1) if l1 > 0.0 else math.nan
        g = start + i
        nx, ny, nz = normals[g, 0], normals[g, 1], normals[g, 2]
        h = dist[i, k - 1] * reach
        if not (math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)):
            spread[i] = weighted[i] = math.nan
            continue
        m00 = m01 = m02 = m11 = m12 = m22 = 0.0
        w00 = w01 = w02 = w11 = w12 = w22 = 0.0
        for j in range(k):
            q = idx[i, j]
            dx, dy, dz = points[q, 0] - points[g, 0], points[q, 1] - points[g, 1], points[q, 2] - points[g, 2]
            s = dx * nx + dy * ny + dz * nz
            dx, dy, dz = dx - s * nx, dy - s * ny, dz - s * nz
            m00, m01, m02, m11, m12, m22 = add_outer(m00, m01, m02, m11, m12, m22, 1.0, dx, dy, dz)
            if h > 0.0:
                w = theta(dist[i, j] / h)
                w00, w01, w02, w11, w12, w22 = add_outer(w00, w01, w02, w11, w12, w22, w, dx, dy, dz)
        spread[i] = _spread(m00, m01, m02, m11, m12, m22)
        weighted[i] = _spread(w00, w01, w02, w11, w12, w22) if h > 0.0 else math.nan


@njit(**OPTS, inline="always")
def _spread(m00, m01, m02, m11, m12, m22):
    """sqrt(lambda_min / lambda_max) of the two non-zero eigenvalues of a projected
    moment matrix (the roots of x^2 - tr x + e2); NaN where it is zero."""
    tr = m00 + m11 + m22
    e2 = m00 * m11 - m01 * m01 + m00 * m22 - m02 * m02 + m11 * m22 - m12 * m12
    half = 0.5 * tr
    top = half + math.sqrt(max(half * half - e2, 0.0))
    return math.sqrt(max(e2, 0.0) / (top * top)) if top > 0.0 else math.nan  # lambda_min = e2 / lambda_max


@njit(**OPTS, parallel=True)
def scatter_shapes(points, rows, flat, line):
    """The shape of the scatter of the points ``rows[r]`` about their centroid, from its
    eigenvalues l0 <= l1 <= l2: flat[r] = sqrt(l0 / l1), near 0 for points near a plane and
    near 1 for a noisy line (its noise is as wide both ways across it) or a cloud with no
    plane; line[r] = sqrt(l1 / l2), near 0 for points along a line. NaN where degenerate."""
    k = rows.shape[1]
    for r in prange(rows.shape[0]):
        _, _, _, c00, c01, c02, c11, c12, c22 = row_scatter(points, rows, r, 0, k)
        l0, l1, l2, _, _, _ = smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
        flat[r] = math.sqrt(max(l0, 0.0) / l1) if l1 > 0.0 else math.nan
        line[r] = math.sqrt(max(l1, 0.0) / l2) if l2 > 0.0 else math.nan


#: terms of the quartic :func:`curve_shares` fits across a row's widest axis
_CURVE_TERMS = 5


@njit(**OPTS, parallel=True)
def curve_shares(points, rows, flat, curve):
    """flat[r] as in :func:`scatter_shapes`; curve[r] the RMS residual of the quartic
    v = c0 + c1 u + ... + c4 u^4 fitted to the points ``rows[r]`` in their principal plane
    (u along its widest axis, scaled to [-1, 1]; v along the middle one), over the RMS of
    v: about noise / width for points along one curve, near 1 for a surface's. NaN where
    degenerate or the quartic is not determined."""
    k = rows.shape[1]
    for blk in prange((rows.shape[0] + BLOCK - 1) // BLOCK):
        work = np.empty((4, 2 * _CURVE_TERMS - 1))  # scratch of the block: six allocations per row cost more
        gram, low = np.empty((_CURVE_TERMS, _CURVE_TERMS)), np.empty((_CURVE_TERMS, _CURVE_TERMS))
        for r in range(blk * BLOCK, min(rows.shape[0], (blk + 1) * BLOCK)):
            _curve_share(points, rows, r, k, flat, curve, work, gram, low)


@njit(**OPTS)
def _curve_share(points, rows, r, k, flat, curve, work, gram, low):
    """:func:`curve_shares` at row r with the block's scratch (``low``: only its lower
    triangle is read, as :func:`cholesky` writes it)."""
    cx, cy, cz, c00, c01, c02, c11, c12, c22 = row_scatter(points, rows, r, 0, k)
    l0, l1, _, nx, ny, nz = smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
    flat[r] = math.sqrt(max(l0, 0.0) / l1) if l1 > 0.0 else math.nan
    curve[r] = math.nan
    if not math.isfinite(nx):
        return
    ax, ay, az, bx, by, bz = tangent_pair(nx, ny, nz)  # of the plane normal to n
    saa = ax * (c00 * ax + c01 * ay + c02 * az) + ay * (c01 * ax + c11 * ay + c12 * az) + az * (c02 * ax + c12 * ay + c22 * az)
    sbb = bx * (c00 * bx + c01 * by + c02 * bz) + by * (c01 * bx + c11 * by + c12 * bz) + bz * (c02 * bx + c12 * by + c22 * bz)
    sab = ax * (c00 * bx + c01 * by + c02 * bz) + ay * (c01 * bx + c11 * by + c12 * bz) + az * (c02 * bx + c12 * by + c22 * bz)
    t = 0.5 * math.atan2(2.0 * sab, saa - sbb)  # the widest axis of the plane's 2x2 scatter
    ct, st = math.cos(t), math.sin(t)
    ux, uy, uz = ct * ax + st * bx, ct * ay + st * by, ct * az + st * bz
    vx, vy, vz = -st * ax + ct * bx, -st * ay + ct * by, -st * az + ct * bz
    reach = 0.0
    for j in range(k):
        q = rows[r, j]
        reach = max(reach, abs((points[q, 0] - cx) * ux + (points[q, 1] - cy) * uy + (points[q, 2] - cz) * uz))
    if not reach > 0.0:
        return
    power, rhs, d, coef = work[0], work[1, :_CURVE_TERMS], work[2, :_CURVE_TERMS], work[3, :_CURVE_TERMS]
    power[:] = 0.0  # sums of u^p: the Gram matrix is a Hankel matrix
    rhs[:] = 0.0
    vv = 0.0
    for j in range(k):
        q = rows[r, j]
        dx, dy, dz = points[q, 0] - cx, points[q, 1] - cy, points[q, 2] - cz
        u = (dx * ux + dy * uy + dz * uz) / reach
        v = dx * vx + dy * vy + dz * vz
        vv += v * v
        up = 1.0
        for p in range(2 * _CURVE_TERMS - 1):
            power[p] += up
            if p < _CURVE_TERMS:
                rhs[p] += v * up
            up *= u
    for a in range(_CURVE_TERMS):
        for c in range(_CURVE_TERMS):
            gram[a, c] = power[a + c]
    if not vv > 0.0 or not cholesky(gram, _CURVE_TERMS, 1e-12, d, low):
        return
    chol_solve(low, d, _CURVE_TERMS, rhs, coef)
    fitted = 0.0
    for a in range(_CURVE_TERMS):
        fitted += coef[a] * rhs[a]
    curve[r] = math.sqrt(max(vv - fitted, 0.0) / vv)  # residual sum of squares: v.v - c.b
