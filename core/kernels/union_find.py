"""Union-find (disjoint sets) of the orientation's kernels: the plain forest whose roots
are each part's lowest index (:func:`root`: the graph's connected parts, a patch of one
face), and the signed forest of the spanning forest's Kruskal (:func:`find_signed`,
:func:`join_signed`: each node's sign relative to its root rides with its parent).

The signed forest is one integer array ``link`` (:func:`signed_forest`): a root holds
``-size`` of its part, any other node ``2 x parent + parity``. One 4-byte entry per point
instead of an 8-byte parent, a parity byte and an 8-byte size in three arrays: the
Kruskal of a 1M-point cloud reads these at random (edges come strongest first, from all
over the cloud), and 4 MiB stay in cache where 17 MiB did not (voted_signs' first pass
0.28-0.39 -> 0.15-0.19 CPU s, the same joins). ``int32`` below 2^30 points.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._base import OPTS as _OPTS


def signed_forest(n):
    """``n`` single-node parts of the signed forest (each a root of size 1)."""
    return np.full(n, -1, dtype=np.int32 if n < 2**30 else np.int64)


@njit(**_OPTS)
def root(parent, x):
    """Root of x in the plain forest ``parent`` (a root is its own parent), halving the
    path on the way (each node on it pointed at its grandparent)."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(**_OPTS)
def join(parent, a, b):
    """Join the parts of a and b in the plain forest ``parent``: the larger root hangs
    under the smaller, so each part's root stays its lowest index."""
    ra, rb = root(parent, a), root(parent, b)
    parent[max(ra, rb)] = min(ra, rb)


@njit(**_OPTS, parallel=True)
def mask_roots(idx, mask):
    """(N,) each node's root, the lowest index of its part, in the graph that joins row i
    to ``idx[i, m]`` wherever ``mask[i, m]``. The rows are split into two blocks whose
    joins run in parallel, each on a forest of its own, and the second forest is merged
    into the first (every node joined to its root there): the parts are those of one forest
    of all the joins, and so are the roots, on any number of threads. Two blocks, not one
    per thread: the merge is a serial pass over the nodes per extra block (and the thread
    count read in here would keep numba from caching the function)."""
    n, k = idx.shape
    blocks = 2 if n >= 8192 else 1
    forests = np.empty((blocks, n), dtype=np.int64)
    for b in prange(blocks):
        parent = forests[b]
        for x in range(n):
            parent[x] = x
        for i in range(n * b // blocks, n * (b + 1) // blocks):
            for m in range(k):
                if mask[i, m]:
                    join(parent, i, idx[i, m])
    parent = forests[0]
    for b in range(1, blocks):
        other = forests[b]
        for x in range(n):
            if other[x] != x:
                join(parent, x, root(other, x))
    for x in range(n):
        parent[x] = root(parent, x)
    return parent


@njit(**_OPTS)
def find_signed(link, x):
    """Root of x in the signed forest ``link`` and the parity of x relative to it;
    compresses the path (every node on it pointed straight at the root, its parity
    relative to the root with it)."""
    top = x
    acc = 0
    v = link[top]
    while v >= 0:
        acc ^= v & 1
        top = v >> 1
        v = link[top]
    total = acc
    node = x
    while node != top:
        v = link[node]
        link[node] = 2 * top + acc
        acc ^= v & 1
        node = v >> 1
    return top, total


@njit(**_OPTS)
def part_size(link, r):
    """Points in the part of root ``r``."""
    return -link[r]


@njit(**_OPTS)
def join_signed(link, a, b, s):
    """Hang root b under root a with the relative sign s, or a under b if b's part is
    larger (a stays the root on a tie)."""
    sa, sb = -link[a], -link[b]
    if sa < sb:
        a, b = b, a
    link[a] = -(sa + sb)
    link[b] = 2 * a + s
