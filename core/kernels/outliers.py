"""Outlier scores: distance from the neighbours' plane in units of their spread."""

from __future__ import annotations

import math

from numba import njit, prange

from ._base import OPTS
from .algebra import row_scatter, smallest_eigvec_sym3


@njit(**OPTS, parallel=True)
def outlier_scores(points, idx, floor, score):
    """Distance of each point from the plane of its neighbours, in units of their spread.

    The plane is the least-squares plane of the neighbours without the point itself
    (centroid and smallest principal axis); the unit is the neighbours' RMS distance to
    that plane plus ``floor`` x their mean distance to the centroid, so that a clean flat
    patch does not make every tiny offset look infinite.
    """
    n, k = idx.shape
    for i in prange(n):
        m = k - 1
        if m < 3:
            score[i] = math.nan
            continue
        cx, cy, cz, c00, c01, c02, c11, c12, c22 = row_scatter(points, idx, i, 1, k)
        spread = 0.0
        for j in range(1, k):
            q = idx[i, j]
            dx, dy, dz = points[q, 0] - cx, points[q, 1] - cy, points[q, 2] - cz
            spread += math.sqrt(dx * dx + dy * dy + dz * dz)
        l0, l1, l2, x, y, z = smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
        if not math.isfinite(x):
            score[i] = math.nan
            continue
        d = abs((points[i, 0] - cx) * x + (points[i, 1] - cy) * y + (points[i, 2] - cz) * z)
        unit = math.sqrt(max(l0, 0.0) / m) + floor * spread / m
        score[i] = d / unit if unit > 0.0 else (0.0 if d == 0.0 else math.inf)
