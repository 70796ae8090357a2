"""The k nearest neighbours of points already in spatial order (numba, ``nogil``, all cores).

The points come in a kd-tree's leaf order (:func:`core.neighbours.search_in_spatial_order`),
so every range of consecutive indices is a compact piece of space: the tree here halves
index ranges and keeps their bounding boxes. A query finds the smallest node of at least
``want`` points holding the point, takes the k-th distance among that node's points as a
radius that surely holds k points, gathers every point within it and sorts them. The answer
is the canonical one of :mod:`core.neighbours`: the k smallest by (distance, the caller's
index), distances computed as scipy's cKDTree computes them (``sqrt((dx^2 + dy^2) + dz^2)``),
so the rows are bit-identical to a cKDTree query followed by its tie handling.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS

#: a radius found on the node's own points is compared with a box's distance with this
#: relative slack (rounding of the squares; more slack only gathers more candidates)
_SLACK = 1e-9


@njit(**OPTS)
def build_tree(p, leaf):
    """Halve [0, N) until ranges have at most ``leaf`` points: per node its range
    ``lo``, ``hi``, first ``child`` (-1 for a leaf; the second is child + 1) and its
    bounding ``box`` (min xyz, max xyz). Children come after their parent."""
    n = p.shape[0]
    cap = 4 * (n // max(leaf, 1) + 1) + 1
    lo, hi = np.empty(cap, np.int64), np.empty(cap, np.int64)
    child = np.full(cap, -1, np.int64)
    lo[0], hi[0] = 0, n
    count, i = 1, 0
    while i < count:
        if hi[i] - lo[i] > leaf:
            mid = (lo[i] + hi[i]) // 2
            lo[count], hi[count], lo[count + 1], hi[count + 1] = lo[i], mid, mid, hi[i]
            child[i] = count
            count += 2
        i += 1
    box = np.empty((count, 6))
    for i in range(count - 1, -1, -1):
        c = child[i]
        for d in range(3):
            if c < 0:
                box[i, d], box[i, 3 + d] = np.inf, -np.inf
                for j in range(lo[i], hi[i]):
                    box[i, d] = min(box[i, d], p[j, d])
                    box[i, 3 + d] = max(box[i, 3 + d], p[j, d])
            else:
                box[i, d] = min(box[c, d], box[c + 1, d])
                box[i, 3 + d] = max(box[c, 3 + d], box[c + 1, 3 + d])
    return lo[:count], hi[:count], child[:count], box


@njit(**OPTS, inline="always")
def _distance(p, a, b):
    """cKDTree's Euclidean distance (its sum order: the same bits)."""
    dx = p[a, 0] - p[b, 0]
    dy = p[a, 1] - p[b, 1]
    dz = p[a, 2] - p[b, 2]
    s = dx * dx
    s += dy * dy
    s += dz * dz
    return np.sqrt(s)


@njit(**OPTS)
def _radius(p, tree, i, k, want, rank, cd, cj):
    """A distance that at least k points lie within: the k-th smallest distance from point
    i to the points of the smallest node of >= ``want`` points holding i (``cd`` / ``cj``:
    scratch of at least 2 ``want`` + 1)."""
    lo, hi, child = tree[0], tree[1], tree[2]
    node = 0
    while child[node] >= 0:
        c = child[node]
        nxt = c if i < hi[c] else c + 1
        if hi[nxt] - lo[nxt] < want:
            break
        node = nxt
    m = hi[node] - lo[node]
    for j in range(m):
        cd[j], cj[j] = _distance(p, i, lo[node] + j), lo[node] + j
    _select(cd, cj, rank, m, k)
    r = cd[0]
    for c in range(1, k):
        r = max(r, cd[c])
    return r


@njit(**OPTS)
def _gather(p, tree, i, r, cd, cj, stack):
    """Points within ``r`` of point i into ``cd`` (distance) / ``cj`` (index); returns
    their count, or -1 when ``cd`` is too short."""
    lo, hi, child, box = tree
    r2 = r * r * (1.0 + _SLACK)
    m, top = 0, 1
    stack[0] = 0
    while top > 0:
        top -= 1
        node = stack[top]
        s = 0.0
        for d in range(3):
            x = p[i, d]
            g = box[node, d] - x if x < box[node, d] else (x - box[node, 3 + d] if x > box[node, 3 + d] else 0.0)
            s += g * g
        if s > r2:
            continue
        if child[node] >= 0:
            stack[top], stack[top + 1] = child[node], child[node] + 1
            top += 2
            continue
        for j in range(lo[node], hi[node]):
            dj = _distance(p, i, j)
            if dj <= r:
                if m == len(cd):
                    return -1
                cd[m], cj[m] = dj, j
                m += 1
    return m


@njit(**OPTS)
def _insertion(cd, cj, rank, lo, hi):
    """Sort candidates [lo, hi] by (distance, ``rank`` of their index)."""
    for a in range(lo + 1, hi + 1):
        vd, vj = cd[a], cj[a]
        vr = rank[vj]
        b = a - 1
        while b >= lo and (cd[b] > vd or (cd[b] == vd and rank[cj[b]] > vr)):
            cd[b + 1], cj[b + 1] = cd[b], cj[b]
            b -= 1
        cd[b + 1], cj[b + 1] = vd, vj


@njit(**OPTS)
def _partition(cd, cj, rank, lo, hi):
    """Hoare's partition of [lo, hi] (hi > lo) around its middle candidate by (distance,
    rank): returns j, lo <= j < hi, with [lo, j] before [j + 1, hi]. The key is a strict
    order (ranks are distinct), so the scans stop at the pivot at the latest."""
    mid = (lo + hi) >> 1
    pd, pr = cd[mid], rank[cj[mid]]
    i, j = lo, hi
    while True:
        while cd[i] < pd or (cd[i] == pd and rank[cj[i]] < pr):
            i += 1
        while cd[j] > pd or (cd[j] == pd and rank[cj[j]] > pr):
            j -= 1
        if i >= j:
            return j
        cd[i], cd[j] = cd[j], cd[i]
        cj[i], cj[j] = cj[j], cj[i]
        i += 1
        j -= 1


@njit(**OPTS)
def _select(cd, cj, rank, m, k):
    """Quickselect: the k smallest of the m candidates moved to [0, k) (in any order)."""
    lo, hi = 0, m - 1
    while hi - lo >= 16:
        j = _partition(cd, cj, rank, lo, hi)
        if k - 1 <= j:
            hi = j
        else:
            lo = j + 1
    _insertion(cd, cj, rank, lo, hi)


@njit(**OPTS)
def _sort(cd, cj, rank, lo, hi, stack):
    """Quicksort of candidates [lo, hi] (the smaller side first: ``stack`` of 2 log2 n)."""
    top = 0
    while True:
        while hi - lo >= 16:
            j = _partition(cd, cj, rank, lo, hi)
            if j - lo < hi - j:
                stack[top], stack[top + 1] = j + 1, hi
                hi = j
            else:
                stack[top], stack[top + 1] = lo, j
                lo = j + 1
            top += 2
        _insertion(cd, cj, rank, lo, hi)
        if top == 0:
            return
        top -= 2
        lo, hi = stack[top], stack[top + 1]


@njit(**OPTS)
def _bucket_sort(cd, cj, m, r, rank, k, work):
    """The first k of the m candidates (all within ``r``) sorted by (distance, rank), into
    ``work``'s (distances, indices) rows [0, k): a counting sort by distance^2 / r^2 into m
    buckets (monotone in the distance; on a surface ~one candidate each), then each bucket
    reaching into the first k sorted by the full key."""
    od, oj, count, stack = work
    nb = m
    scale = nb / (r * r) if r > 0.0 else 0.0
    count[:nb + 1] = 0
    for a in range(m):
        count[min(int(cd[a] * cd[a] * scale), nb - 1) + 1] += 1
    for b in range(nb):
        count[b + 1] += count[b]
    for a in range(m):
        b = min(int(cd[a] * cd[a] * scale), nb - 1)
        od[count[b]], oj[count[b]] = cd[a], cj[a]
        count[b] += 1
    lo = 0  # count[b] is now the end of bucket b
    for b in range(nb):
        hi = count[b]
        if hi - lo > 1:
            _sort(od, oj, rank, lo, hi - 1, stack)
        if hi >= k:
            return
        lo = hi


@njit(**OPTS)
def distances_at(p, centres, idx, rows, col, out):
    """``out[r]``: the distance from point ``centres[r]`` to its neighbour
    ``idx[rows[r], col[r]]``, the bits :func:`query_rows` gives it (:func:`_distance`): a row
    searched earlier, whose distances were not kept."""
    for r in range(len(centres)):
        out[r] = _distance(p, centres[r], idx[rows[r], col[r]])


@njit(**OPTS, parallel=True)
def query_sorted(p, tree, rank, start, dist, idx, want, reach):
    """Rows ``start .. start + len(dist)`` of the k = ``dist.shape[1]`` nearest neighbours of
    the points ``p`` (in the order ``tree`` was built on), into ``dist`` / ``idx`` (indices
    into ``p``), ties in distance by ``rank`` (the caller's index of each point).

    Numpy reference, row i: ``d = sqrt(((p - p[i]) ** 2).sum(1)); o = np.lexsort((rank, d))[:k];
    dist[i], idx[i] = d[o], o``. ``reach``: see :func:`_query_block` (speed only)."""
    rows = dist.shape[0]
    depth = 2 * int(np.log2(max(p.shape[0], 2))) + 8
    for b in prange((rows + BLOCK - 1) // BLOCK):
        _query_block(p, tree, rank, start, None, b * BLOCK, min(rows, (b + 1) * BLOCK), dist, idx, (want, reach), depth)


@njit(**OPTS, parallel=True)
def query_rows(p, tree, rank, rows, dist, idx, want, reach):
    """:func:`query_sorted` for the points ``rows`` (any indices into ``p``, best in
    ascending order: each query starts from the previous one's radius): row r of
    ``dist`` / ``idx`` holds the k = ``dist.shape[1]`` nearest neighbours of point
    ``rows[r]``, the same bits as :func:`query_sorted` gives for that point."""
    m = dist.shape[0]
    depth = 2 * int(np.log2(max(p.shape[0], 2))) + 8
    for b in prange((m + BLOCK - 1) // BLOCK):
        _query_block(p, tree, rank, 0, rows, b * BLOCK, min(m, (b + 1) * BLOCK), dist, idx, (want, reach), depth)


@njit(**OPTS)
def _query_block(p, tree, rank, start, rows, r0, r1, dist, idx, sizes, depth):
    """Rows r0 .. r1 - 1 of :func:`query_sorted` (point ``start + r``) or of
    :func:`query_rows` (point ``rows[r]``), scratch allocated once. ``sizes`` = (want,
    reach): a query first gathers within the previous point's k-th distance plus ``reach``
    x the step between the two, then, short of k points, within the sure radius (plus the
    whole step: the triangle inequality), then within its node's (:func:`_radius`). Any
    radius holding k points gives the same rows (all points within it are gathered, ties
    at the k-th distance included), so ``reach`` trades candidates against retries only."""
    want, reach = sizes
    k = dist.shape[1]
    stack = np.empty(2 * depth + 4, np.int64)
    cap = 8 * want + 2
    cd, cj = np.empty(cap, np.float64), np.empty(cap, np.int64)
    work = (np.empty(cap, np.float64), np.empty(cap, np.int64), np.empty(cap + 1, np.int64), stack)
    last = -1.0
    prev = -1
    for r in range(r0, r1):
        if rows is None:
            i = start + r
        else:
            i = rows[r]
        # the previous point's k nearest lie within d(i, prev) + its k-th distance of i
        step = _distance(p, i, prev) if last >= 0.0 else np.inf
        sure = (step + last) * (1.0 + _SLACK) if step <= last else -1.0
        radius = (reach * step + last) * (1.0 + _SLACK) if sure >= 0.0 else _radius(p, tree, i, k, want, rank, cd, cj)
        while True:
            m = _gather(p, tree, i, radius, cd, cj, stack)
            if m < 0:
                cap *= 2
                cd, cj = np.empty(cap, np.float64), np.empty(cap, np.int64)
                work = (np.empty(cap, np.float64), np.empty(cap, np.int64), np.empty(cap + 1, np.int64), stack)
            elif m < k and radius < sure:  # the guess was short: the sure radius
                radius = sure
            elif m < k:  # short of k by rounding: the node's own radius
                radius = _radius(p, tree, i, k, want, rank, cd, cj)
                sure = -1.0
            else:
                break
        _bucket_sort(cd, cj, m, radius, rank, k, work)
        for c in range(k):
            dist[r, c], idx[r, c] = work[0][c], work[1][c]
        last = dist[r, k - 1]
        prev = i
