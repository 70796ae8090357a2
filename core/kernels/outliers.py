"""Outlier scores: distance from the neighbours' plane in units of their spread; groups too small to be a surface."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import OPTS
from .algebra import row_scatter, smallest_eigvec_sym3
from .kdtree import _distance
from .union_find import mask_roots


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


@njit(**OPTS, parallel=True)
def isolated_groups(points, idx, out):
    """Mark (``out[i] = True``) the points of groups too small to be a surface of their own.

    Two points are joined when each lies within the other's reach (the distance to the
    last neighbour of its row ``idx[i]``, which holds the point itself first): a surface's
    neighbouring points reach each other however dense or sparse its sampling, while a
    clump floating a few reaches off it is reached by none of the surface's points. A
    connected group of fewer points than a row holds (and smaller than the largest group)
    has no neighbourhood of its own: the plane its neighbours span is a mix of itself
    and the surface below, and its distance from that plane says nothing. The joins are
    tested and joined in parallel (:func:`core.kernels.union_find.mask_roots`).
    """
    n, k = idx.shape
    reach = np.empty(n)
    for i in prange(n):
        reach[i] = _distance(points, i, idx[i, k - 1])
    joined = np.zeros((n, k), dtype=np.bool_)
    for i in prange(n):
        for m in range(1, k):
            j = idx[i, m]
            if j != i and j >= 0:
                d = _distance(points, i, j)
                joined[i, m] = d <= reach[i] and d <= reach[j]
    parent = mask_roots(idx, joined)
    size = np.zeros(n, dtype=np.int64)
    for i in range(n):
        size[parent[i]] += 1
    least = min(k, size.max())
    for i in range(n):
        out[i] = size[parent[i]] < least
