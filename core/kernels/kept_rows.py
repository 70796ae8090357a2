"""Rows searched earlier, whose distances were not kept, put into a whole graph (issue 15, speed)."""

from __future__ import annotations

from numba import njit, prange

from ._base import OPTS
from .kdtree import _distance


@njit(**OPTS, parallel=True)
def rows_with_distances(p, src, pos, at, idx, dist):
    """``idx[at[r]] = src[pos[r], :k]`` and ``dist[at[r], c]`` the distance from point ``at[r]``
    to each, the bits the search gives it (:func:`core.kernels.kdtree._distance`), k = ``idx.shape[1]``."""
    k = idx.shape[1]
    for r in prange(len(pos)):
        i = at[r]
        for c in range(k):
            j = src[pos[r], c]
            idx[i, c] = j
            dist[i, c] = _distance(p, i, j)
