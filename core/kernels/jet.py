"""Normals of the osculating 2-jet (Cazals & Pouget 2005), the refined initial normals."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS
from .algebra import chol_solve, cholesky, determined, poly_row


@njit(**OPTS, parallel=True)
def jet_normals(points, idx, h, centres, t1, t2, z, rcond, normals, height, ok, slope_se):
    """Normals of the osculating 2-jet (Cazals & Pouget 2005) in the frames given.

    Fits w = c0 + c1 u + c2 v + c3 u^2 + c4 uv + c5 v^2 to the neighbours (lengths / h) by
    least squares (6x6 normal equations, equilibrated, Cholesky); the normal of the graph
    at the origin is (-c1, -c2, 1) / |.|, ``height`` the RMS residual of w (in length
    units, corrected for the 6 fitted terms): the noise of the positions along the
    normal, once the quadric has taken up the curvature, and ``slope_se`` the standard
    error of the slope (c1, c2), sqrt(var c1 + var c2) from that residual: how far the jet
    could tilt the frame's normal by noise alone. ``ok`` is False where the quadratic is not
    determined: the smallest eigenvalue of its scaled normal matrix is at most ``rcond``
    (:func:`~core.kernels.algebra.determined`, the same in any tangent axes).
    """
    m = len(centres)
    k = idx.shape[1]
    n_blocks = (m + BLOCK - 1) // BLOCK
    for blk in prange(n_blocks):
        G = np.empty((6, 6))
        L = np.empty((6, 6))
        b = np.empty(6)
        row = np.empty(6)
        d = np.empty(6)
        x = np.empty(6)
        e = np.zeros(6)
        col = np.empty(6)
        for r in range(blk * BLOCK, min(m, (blk + 1) * BLOCK)):
            ok[r] = False
            i = centres[r]
            hi = h[r]
            G[:, :] = 0.0
            b[:] = 0.0
            ww = 0.0
            for j in range(k):
                q = idx[r, j]
                dx = (points[q, 0] - points[i, 0]) / hi
                dy = (points[q, 1] - points[i, 1]) / hi
                dz = (points[q, 2] - points[i, 2]) / hi
                u = dx * t1[r, 0] + dy * t1[r, 1] + dz * t1[r, 2]
                v = dx * t2[r, 0] + dy * t2[r, 1] + dz * t2[r, 2]
                w = dx * z[r, 0] + dy * z[r, 1] + dz * z[r, 2]
                poly_row(u, v, 2, row)
                ww += w * w
                for a in range(6):
                    b[a] += row[a] * w
                    for c in range(a + 1):
                        G[a, c] += row[a] * row[c]
            if not determined(G, 2, rcond, d, L) or not cholesky(G, 6, 0.0, d, L):
                continue
            chol_solve(L, d, 6, b, x)
            c1, c2 = x[1], x[2]
            nrm = math.sqrt(1.0 + c1 * c1 + c2 * c2)
            for a in range(3):
                normals[r, a] = (-c1 * t1[r, a] - c2 * t2[r, a] + z[r, a]) / nrm
            rss = ww
            for a in range(6):
                rss -= x[a] * b[a]
            var = max(rss, 0.0) / max(k - 6, 1)
            height[r] = hi * math.sqrt(var)
            inv = 0.0  # (G^-1)_11 + (G^-1)_22: the slopes' variances per unit residual variance
            for a in (1, 2):
                e[a] = 1.0
                chol_solve(L, d, 6, e, col)
                inv += col[a]
                e[a] = 0.0
            slope_se[r] = math.sqrt(var * max(inv, 0.0))
            ok[r] = True
