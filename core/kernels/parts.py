"""The connected parts of the k-nearest graph cut at wide gaps (:mod:`core.parts`)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ._base import OPTS as _OPTS
from .union_find import join, root


@njit(**_OPTS)
def gap_components(idx, dist, near, gap):
    """Each point's root (the lowest index of its part) in the graph joining row i to its
    neighbours ``idx[i, 1:]`` no farther than ``gap`` x its ``near``-th nearest (``dist[i,
    near - 1]``): a gap much wider than the local spacing parts the cloud."""
    n = idx.shape[0]
    parent = np.arange(n)
    for i in range(n):
        reach = gap * dist[i, near - 1]
        for m in range(1, idx.shape[1]):
            j = idx[i, m]
            if j != i and 0 <= j < n and dist[i, m] <= reach:
                join(parent, i, j)
    roots = np.empty(n, dtype=np.int64)
    for x in range(n):
        roots[x] = root(parent, x)
    return roots
