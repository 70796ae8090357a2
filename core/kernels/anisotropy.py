"""Compiled loop of :mod:`core.anisotropy` (numba, ``nogil``)."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._base import OPTS as _OPTS


@njit(**_OPTS, parallel=True)
def direction_anisotropy(nearest, normals, graph, out):
    """1 - l_min / l_max of T = sum u u^T over the directions ``nearest[j]`` (N, M, 3) of
    the neighbours j = graph[i, :], each projected on point i's tangent plane; NaN where
    the normal is not finite or T is zero. numpy reference::

        u = nearest[graph[i]].reshape(-1, 3); u -= np.outer(u @ n_i, n_i)
        l = np.linalg.eigvalsh(u.T @ u)[1:]; out[i] = 1 - l[0] / l[1]

    (the two tangent eigenvalues from the trace and the Frobenius norm: T has rank 2).
    """
    n, k = graph.shape
    m = nearest.shape[1]
    for i in prange(n):
        nx, ny, nz = normals[i, 0], normals[i, 1], normals[i, 2]
        out[i] = np.nan
        if not (np.isfinite(nx) and np.isfinite(ny) and np.isfinite(nz)):
            continue
        xx = yy = zz = xy = xz = yz = 0.0
        for q in range(k):
            j = graph[i, q]
            for r in range(m):
                d = nearest[j, r, 0] * nx + nearest[j, r, 1] * ny + nearest[j, r, 2] * nz
                ux = nearest[j, r, 0] - d * nx
                uy = nearest[j, r, 1] - d * ny
                uz = nearest[j, r, 2] - d * nz
                xx += ux * ux
                yy += uy * uy
                zz += uz * uz
                xy += ux * uy
                xz += ux * uz
                yz += uy * uz
        trace = xx + yy + zz
        if trace > 0.0:
            frob = xx * xx + yy * yy + zz * zz + 2.0 * (xy * xy + xz * xz + yz * yz)
            disc = np.sqrt(max(2.0 * frob - trace * trace, 0.0))
            out[i] = min(1.0, 2.0 * disc / (trace + disc))


@njit(**_OPTS, parallel=True)
def nearest_directions(points, idx, tie, out):
    """out[i, r] = the unit direction from point i to idx[i, r + 1] (r < out.shape[1]),
    scaled by sqrt(exp(-((d_r / d_0 - 1) / tie)^2)) with d_r its distance; zero where the
    distance is zero (duplicates: no direction, no vote)."""
    n = points.shape[0]
    m = out.shape[1]
    for i in prange(n):
        d0 = 0.0
        for r in range(m):
            j = idx[i, r + 1]
            cx = points[j, 0] - points[i, 0]
            cy = points[j, 1] - points[i, 1]
            cz = points[j, 2] - points[i, 2]
            d = np.sqrt(cx * cx + cy * cy + cz * cz)
            if r == 0:
                d0 = d
            s = 0.0
            if d > 0.0 and d0 > 0.0:
                s = np.exp(-0.5 * ((d / d0 - 1.0) / tie) ** 2) / d
            out[i, r, 0] = cx * s
            out[i, r, 1] = cy * s
            out[i, r, 2] = cz * s
