"""Compiled loops of :mod:`core.orientation` (numba, ``nogil``)."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS as _OPTS
from .network import SHORT, sorted_short
from .union_find import find_signed, join, join_signed, part_size, root


@njit(**_OPTS, parallel=True)
def offset_spread(points, normals, idx, ok, out):
    """Median |n_i . (p_j - p_i)| over point i's neighbours j: the noise (and sagitta) that
    an offset along the normal must exceed to mean something. A median, not an RMS about
    the neighbours' centroid: across a thin part (a shell or sheet pair 2-3 spacings apart)
    a few neighbours lie on the other side, and an RMS counted their offset as noise, which
    gated the very chord test that tells the two sides apart (a 3-spacing bowl at noise 0.2
    spacing had its whole inner side flipped: 54 % agreement; 99.3-99.6 % with the median)."""
    n, k = idx.shape
    for blk in prange((n + BLOCK - 1) // BLOCK):
        t = np.empty(max(k - 1, 0))  # scratch of the block: an allocation per point cost as much as its median
        for i in range(blk * BLOCK, min(n, (blk + 1) * BLOCK)):
            out[i] = 0.0
            if not ok[i] or k < 2:
                continue
            for q in range(1, k):  # column 0 is the point itself
                j = idx[i, q]
                t[q - 1] = abs(normals[i, 0] * (points[j, 0] - points[i, 0])
                               + normals[i, 1] * (points[j, 1] - points[i, 1])
                               + normals[i, 2] * (points[j, 2] - points[i, 2]))
            out[i] = _median(t)


@njit(**_OPTS)
def _median(t):
    """The median of a short array (reordered): sorted by
    :func:`core.kernels.network.sorted_short` (9 offsets at k = 10: half the time of counting
    each one's rank, 2x faster than an insertion sort itself), longer ones by counting ranks."""
    m = len(t)
    lo, hi = (m - 1) // 2, m // 2
    if m <= SHORT:
        sorted_short(t, m)
        return 0.5 * (t[lo] + t[hi])
    a = b = 0.0
    for x in range(m):
        tx = t[x]
        less = 0
        leq = 0
        for y in range(m):
            less += t[y] < tx
            leq += t[y] <= tx
        a = tx if less <= lo < leq else a
        b = tx if less <= hi < leq else b
    return 0.5 * (a + b)


@njit(**_OPTS, parallel=True)
def sign_evidence(points, normals, spread, weight, idx, ok, gate, out, first, rank, raw_weight=False):
    """Signed evidence that normals i and j = idx[i, m] point the same way (> 0) or not (< 0).

    With the chord c = p_j - p_i, d = |c|, the offsets t_i = n_i . c and t_j = -n_j . c,
    shrunk towards 0 by ``gate`` x the pair's ``spread`` (so noise is not read as an
    offset), and a_i = t_i / d, a_j = t_j / d:

        e = (1 - |a_i|)(1 - |a_j|) (n_i . n_j)  +  a_i a_j

    The first term is Hoppe's test, trusted where the chord lies in both tangent planes
    (neighbours on one sheet); the second is the chord test, trusted where the chord leaves
    them (across a thin part, a gap or a crease): a segment between two surface points that
    does not cross the surface lies wholly inside or wholly outside the solid, so it leaves
    both points on the same side of their consistently oriented normals (a_i a_j > 0).
    The whole is scaled by the two points' ``weight`` (their trust: how flat each one's
    neighbourhood is, :func:`core.orientation._evidence`; an empty ``weight``: 1 for all):
    where a point's neighbours lie off its plane, a fold (the thin rim of a part, its faces
    a spacing or two away), neither term means much.
    ``out[i, m]`` is 0 where either point has no normal or the chord has zero length;
    ``first[i, m]`` is False where the edge also appears in row j with rank[j] < rank[i]
    (``rank``: the point's index in the caller's order, whatever the order in memory); an
    empty ``first`` (0 rows) is not written and row j not searched.
    With ``raw_weight`` Hoppe's term is weighted by the offsets before the gate,
    (1 - |t_i| / d)(1 - |t_j| / d): the gate keeps noise out of the chord test, but it
    also gave Hoppe's term its full weight across a rim whose offsets it swallowed
    (:func:`core.orientation.resettle`).

    Points, normals, spread and weight are read from their own arrays: (N, 8) rows (p, n,
    spread, trust) packed for this loop cost a fresh 64 MiB array and five strided numpy
    copies a call at 1M points, for a loop ~5 % faster.
    """
    n, k = idx.shape
    want_first = first.shape[0] > 0
    trusted = len(weight) > 0
    for i in prange(n):
        for m in range(k):
            j = idx[i, m]
            out[i, m] = 0.0
            if want_first:
                first[i, m] = True
            if j == i or not ok[i] or not ok[j]:
                continue
            if want_first:  # the whole row j read without a branch: whether it holds i is a coin flip
                held = False
                for q in range(k):
                    held |= idx[j, q] == i
                first[i, m] = not (held & (rank[j] < rank[i]))
            cx = points[j, 0] - points[i, 0]
            cy = points[j, 1] - points[i, 1]
            cz = points[j, 2] - points[i, 2]
            d = np.sqrt(cx * cx + cy * cy + cz * cz)
            if d == 0.0:
                continue
            floor = gate * np.sqrt(spread[i] * spread[i] + spread[j] * spread[j])
            ti = normals[i, 0] * cx + normals[i, 1] * cy + normals[i, 2] * cz
            tj = -(normals[j, 0] * cx + normals[j, 1] * cy + normals[j, 2] * cz)
            ai = np.sign(ti) * max(0.0, abs(ti) - floor) / d
            aj = np.sign(tj) * max(0.0, abs(tj) - floor) / d
            nn = normals[i, 0] * normals[j, 0] + normals[i, 1] * normals[j, 1] + normals[i, 2] * normals[j, 2]
            wi, wj = (abs(ti) / d, abs(tj) / d) if raw_weight else (abs(ai), abs(aj))
            e = (1.0 - wi) * (1.0 - wj) * nn + ai * aj
            out[i, m] = e * weight[i] * weight[j] if trusted else e  # e x 1.0 x 1.0 is e: the same bits


@njit(**_OPTS, parallel=True)
def strongest_first(evidence, use, levels, rows, idx):
    """The non-zero entries of ``evidence`` (N, k) where ``use``, as the edge list
    ``(ei, ej, ew)`` (the row i, its neighbour ``idx[i, m]`` and the evidence) by
    decreasing |evidence| to within 1 / ``levels`` (a counting sort: linear time, where a
    comparison sort of 10^7 edges costs more than the whole spanning forest); within a
    level, row by row in the order ``rows`` (the caller's order of the points), so the
    forest does not depend on the order of the points in memory. The list is what
    :func:`voted_signs` reads, in order: written here, where each row's ``idx`` and
    ``evidence`` are read in one go, it spares the forest two scattered reads per edge
    (100k torus, one thread: forest 0.075 -> 0.028 CPU s, this sort +0.004). The ends are
    in ``idx``'s integer type (int32 below 2^31 points: 8 bytes an edge fewer, 41 MiB at
    1M points). Both passes run over blocks of ``rows`` in parallel, each block writing
    from its own offset in each level (the count of the blocks before it): the same list.
    The rows are read in the caller's order, scattered in memory: at 1M points one
    thread took 0.32 s, the longest serial step of NR k = 15."""
    n, k = evidence.shape
    n_blocks = max(1, min(64, n // 4096))
    count = np.zeros((n_blocks + 1, levels + 1), dtype=np.int64)
    for b in prange(n_blocks):
        for t in range(n * b // n_blocks, n * (b + 1) // n_blocks):
            i = rows[t]
            for m in range(k):
                if evidence[i, m] != 0.0 and use[i, m]:
                    count[b + 1, _level(evidence[i, m], levels)] += 1
    total = 0
    for lv in range(levels + 1):  # count[b, lv] becomes block b's first slot in level lv
        for b in range(n_blocks + 1):
            c = count[b, lv]
            count[b, lv] = total
            total += c
    ei, ej, ew = np.empty(total, dtype=idx.dtype), np.empty(total, dtype=idx.dtype), np.empty(total)
    for b in prange(n_blocks):
        slot = count[b + 1]
        for t in range(n * b // n_blocks, n * (b + 1) // n_blocks):
            i = rows[t]
            for m in range(k):
                e = evidence[i, m]
                if e != 0.0 and use[i, m]:
                    lv = _level(e, levels)
                    s = slot[lv]
                    ei[s], ej[s], ew[s] = i, idx[i, m], e
                    slot[lv] = s + 1
    return ei, ej, ew


@njit(**_OPTS, inline="always")
def _level(e, levels):
    """The counting sort's bucket of the evidence ``e``: 1 (strongest) .. ``levels``."""
    return levels - min(levels - 1, int(abs(e) * levels))


@njit(**_OPTS, parallel=True)
def agreement(evidence, idx, flip, ok, out):
    """Evidence-weighted share of each point's edges that agree with the signs after
    ``flip`` (the evidence is bilinear in the two normals: flipping one flips it); 0.5
    where a point has no evidence, 0 where it has no normal."""
    n, k = idx.shape
    for i in prange(n):
        if not ok[i]:
            out[i] = 0.0
            continue
        total = 0.0
        agree = 0.0
        for m in range(k):
            e = evidence[i, m]
            if flip[i] != flip[idx[i, m]]:
                e = -e
            total += abs(e)
            agree += max(e, 0.0)
        out[i] = agree / total if total > 0.0 else 0.5


@njit(**_OPTS)
def knn_components(idx, source, ok, width):
    """Connected parts of the graph joining every ``source`` row i to its neighbours
    ``idx[i, 1:width]`` that are ``ok`` (union-find, no edge list: 9 bytes a point where
    scipy's sparse graph of the same edges peaked at ~500). Returns each node's root, the
    lowest index of its part (-1 where not ``ok``)."""
    n = idx.shape[0]
    parent = np.arange(n)
    for i in range(n):
        if not source[i]:
            continue
        for m in range(1, min(width, idx.shape[1])):
            j = idx[i, m]
            if j == i or not ok[j]:
                continue
            join(parent, i, j)
    roots = np.full(n, -1, dtype=np.int64)
    for x in range(n):
        if ok[x]:
            roots[x] = root(parent, x)
    return roots


@njit(**_OPTS)
def voted_signs(edges, link, flip, rank, min_size, growth):
    """Maximum spanning forest (Kruskal) of the evidence graph with a parity union-find,
    where two parts both of at least ``min_size`` points are not joined by their strongest
    edge alone.

    ``edges`` = (ei, ej, ew) from :func:`strongest_first`: edge t joins points ei[t] and
    ej[t] of the N in ``link`` (:func:`core.kernels.union_find.signed_forest`, N single
    points; it ends as their forest) with the evidence ew[t], taken in that order (decreasing
    |evidence|); an edge joining two parts fixes their relative sign (flip when its evidence is
    negative). Writes ``flip`` (1: flip the normal) and returns the component root of
    every node. Edges between two parts of ``min_size`` points or more (``min_size`` > N:
    none, the plain forest) are set aside (into the edge list's own entries already read: the
    list is overwritten), and once the pass is
    over, the evidence of all set-aside edges between the same two parts is summed (signed
    by the parts' current parities) and the parts are joined strongest sum first, parts of
    ``min_size x growth`` points again by a sum, and so on. Kruskal's one strongest edge
    decides which way a small part hangs; between large parts (the two sides of a plate
    met along its rim, a tube's halves) one wrong edge would flip a whole side, and the
    vote of the whole seam does not. ``rank``: each point's index in the caller's order
    (the sums are taken in an order that does not depend on the order in memory)."""
    ea, eb, ew = edges
    n = len(link)
    nd = 0
    for t in range(len(ea)):
        ri, pi = find_signed(link, ea[t])
        rj, pj = find_signed(link, eb[t])
        if ri == rj:
            continue
        w = ew[t]
        if min(part_size(link, ri), part_size(link, rj)) >= min_size:  # nd <= t: entry t has been read
            ea[nd], eb[nd], ew[nd] = ri, rj, w * (1.0 - 2.0 * (pi ^ pj))
            nd += 1
            continue
        join_signed(link, ri, rj, pi ^ pj ^ (1 if w < 0.0 else 0))
    limit = min_size
    while nd > 0:
        limit *= growth
        nd = _vote_level(link, ea, eb, ew, nd, rank, limit)
    roots = np.empty(n, dtype=np.int64)
    for x in range(n):
        r, p = find_signed(link, x)
        roots[x] = r
        flip[x] = p
    return roots


@njit(**_OPTS)
def _vote_level(link, ea, eb, ew, nd, rank, limit):
    """One level of :func:`voted_signs`: the set-aside edges ``ea, eb, ew[:nd]`` (roots
    then, and their signed evidence) summed per pair of parts now, the sums taken
    strongest first, those joining two parts of ``limit`` points or more set aside again
    (written back into ``ea, eb, ew``); returns how many were set aside."""
    n = len(link)
    key = np.empty(nd, dtype=np.int64)
    w = np.empty(nd)
    live = 0
    for t in range(nd):  # still between two parts: kept (in order), with its sign now
        ra, pa = find_signed(link, ea[t])
        rb, pb = find_signed(link, eb[t])
        if ra == rb:
            continue
        if rank[ra] > rank[rb]:
            ra, rb = rb, ra
        key[live] = rank[ra] * n + rank[rb]
        ea[live], eb[live], w[live] = ra, rb, ew[t] * (1.0 - 2.0 * (pa ^ pb))
        live += 1
    key = key[:live]
    by_pair = np.argsort(key)  # the same keys in the same order in any memory order: the same sums
    head = np.empty(live, dtype=np.int64)
    total = np.empty(live)
    pairs = 0
    t = 0
    while t < live:  # sum each pair's run of edges
        head[pairs] = by_pair[t]
        total[pairs] = 0.0
        while t < live and key[by_pair[t]] == key[head[pairs]]:
            total[pairs] += w[by_pair[t]]
            t += 1
        pairs += 1
    a, b = ea[head[:pairs]], eb[head[:pairs]]  # copies: ea, eb, ew are reused below
    total = total[:pairs]
    again = 0
    for p in np.argsort(-np.abs(total)):
        ra, pa = find_signed(link, a[p])
        rb, pb = find_signed(link, b[p])
        if ra == rb:
            continue
        if min(part_size(link, ra), part_size(link, rb)) >= limit:
            ea[again], eb[again], ew[again] = ra, rb, total[p] * (1.0 - 2.0 * (pa ^ pb))
            again += 1
            continue
        join_signed(link, ra, rb, pa ^ pb ^ (1 if total[p] < 0.0 else 0))
    return again


@njit(**_OPTS, parallel=True)
def least_near(values, ring, out):
    """out[i]: the least values[j] over the j in ring[i] (branch-free: 1.7 ms for two hops at
    100k points, against 6 ms with a test of each j's ``ok`` and 30 ms by
    :func:`core.kernels.pool.pooled_above`'s selection)."""
    n, k = ring.shape
    for i in prange(n):
        least = np.inf
        for q in range(k):
            least = min(least, values[ring[i, q]])
        out[i] = least
