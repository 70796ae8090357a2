"""Whether a neighbourhood spans the tangent plane (numba, ``nogil``, all cores)."""

from __future__ import annotations

import math

from numba import njit, prange

from ._base import OPTS
from .algebra import row_scatter, smallest_eigvec_sym3


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
            m00 += dx * dx
            m01 += dx * dy
            m02 += dx * dz
            m11 += dy * dy
            m12 += dy * dz
            m22 += dz * dz
        tr = m00 + m11 + m22
        e2 = m00 * m11 - m01 * m01 + m00 * m22 - m02 * m02 + m11 * m22 - m12 * m12
        half = 0.5 * tr
        top = half + math.sqrt(max(half * half - e2, 0.0))
        out[r] = math.sqrt(max(e2, 0.0) / (top * top)) if top > 0.0 else math.nan  # lambda_min = e2 / lambda_max


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
