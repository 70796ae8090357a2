"""The kd-tree's answer copied into the neighbour arrays (numba, ``nogil``)."""

from __future__ import annotations

from numba import njit, prange

from ._base import OPTS


@njit(**OPTS, parallel=True)
def keep_nearest(d, i, dist, idx, tied):
    """Copy the first ``dist.shape[1]`` columns of the query's distances ``d`` and indices
    ``i`` into ``dist`` / ``idx`` (on all cores, converting the indices to ``idx``'s type),
    and flag in ``tied`` the rows with two equal distances among them.

    Numpy reference: ``dist[:] = d[:, :k]; idx[:] = i[:, :k];
    tied[:] = (dist[:, 1:] == dist[:, :-1]).any(axis=1)``, one pass instead of three
    (at k = 226 the single-threaded copies took 0.6 s per 100k points).
    """
    n, k = dist.shape
    for r in prange(n):
        tie = False
        for c in range(k):
            dist[r, c] = d[r, c]
            idx[r, c] = i[r, c]
            if c > 0 and d[r, c] == d[r, c - 1]:
                tie = True
        tied[r] = tie


@njit(**OPTS, parallel=True)
def unflagged_first(held_idx, held_dist, drop, idx, dist, free):
    """Row r of ``idx`` / ``dist`` (k columns, k <= the held width) = the first k of row r of
    ``held_idx`` / ``held_dist`` with the neighbours flagged in ``drop`` moved after the
    others (each part in its order; column 0, the point itself, is never moved), and
    ``free[r]`` the number not flagged among those held.

    Numpy reference: ``f = drop[held_idx]; f[:, 0] = False; o = np.argsort(f, axis=1,
    kind="stable")[:, :k]``, the rows taken along ``o``, ``free = (~f).sum(1)`` (a sort and
    two gathers per row took 1.2 s at 1M points)."""
    n, width = held_idx.shape
    k = idx.shape[1]
    for r in prange(n):
        m = 0
        count = 0
        for c in range(width):
            q = held_idx[r, c]
            if c > 0 and drop[q]:
                continue
            count += 1
            if m < k:
                idx[r, m], dist[r, m] = q, held_dist[r, c]
                m += 1
        free[r] = count
        for c in range(1, width):
            if m == k:
                break
            q = held_idx[r, c]
            if drop[q]:
                idx[r, m], dist[r, m] = q, held_dist[r, c]
                m += 1
