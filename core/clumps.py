"""Stacked frames: clouds whose every place is recorded many times with a small jitter.

A static scene captured by a depth sensor in 20-300 frames and the frames stacked (or a
scanner that dwells) holds every surface place as a clump of copies jittered far below the
spacing of the places, farther apart than :func:`core.duplicates.near_copies` joins: the k
nearest of every point are copies of its own place and its fits are garbage reported valid.
A clump's signature is a gap in the sorted distances from any of its points, ``d_j`` to
``d_{j+1}`` (its ``j`` other copies, then the next place), seen alike by all its copies;
it is weighed by its surprise under sampling, ``j log(d_{j+1} / d_j)`` (on a surface sampled
at random ``(d_j / d_{j+1})^2`` is Beta(j, 1), so ``P(j log R > s) = exp(-2 s)``), and has no
unit. Where most points lie in such clumps, their places are the clumps' means (the jitter
averaged, sqrt(m) less) and every copy gets its place's answer (:func:`core.duplicates.expand`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .clump_surfaces import SURFACE_NEAREST, object_clumps
from .components import pair_components

#: a cloud may be clumps where a quarter of its sampled points (:func:`screened`) have a gap of this
#: surprise ``j log(d_{j+1} / d_j)`` (see the module): on 20k-point clean clouds (10 shapes, noise
#: 0.1-1 spacing, scan lines 5-10:1) at most 0.4 % do; a hexagonal lattice's ties reach 5.0 at
#: every point (1.32 after 18 neighbours); 5 copies jittered by 0.05 spacing: 94 %, 0.2: 23 %
CLUMP_SURPRISE = 6.0
#: ... and a point's clump is told by a gap of this surprise, where most of its copies agree on it
#: (a clump's copies see the same gap, random sampling's points each their own); 3 split clumps
#: along view rays (a pair of copies 1e-2 apart is a gap of 4.6 within a 20-copy clump)
CLUMP_SEEN = 4.5
#: ... and a ratio ``d_{j+1} / d_j`` of at least this: on a lattice the ties make rare shells'
#: small steps surprising (a cubic grid has no r^2 = 7: 1.155 after 80 points, 11.5)
CLUMP_RATIO = 1.25
#: a clump's gap is the first at least this wide (in log ratio) against the widest (:func:`clump_gaps`)
CLUMP_NEST = 0.5
#: the share of points that must lie in clumps agreed by most of their copies
CLUMP_SHARE = 0.5
#: searches of the points in no agreed clump on their own, after the first
CLUMP_ROUNDS = 3
#: ... and those still in none join the nearest place within this share of its distance to the next
CLUMP_JOIN = 0.75
#: places within this share of the median distance to their 8 nearest are one (:func:`_halves_joined`)
CLUMP_HALVES = 0.15
#: points per block of the wide search (memory only)
CLUMP_BLOCK = 20_000
#: the widest search for clumps (a place of more copies is left to core.duplicates._isolated_clumps)
CLUMP_WIDEST = 256
#: rows of the search's graph looked at before any wider search (speed only) ...
CLUMP_SAMPLE = 256
#: ... each with this many rows on either side of it in the cloud's spatial order
CLUMP_WINDOW = 128


def clump_gaps(dist: np.ndarray):
    """``(inside, seen, sure)`` of each row of sorted distances ``dist`` (N, K) (the point
    itself first): how many neighbours lie before its clump's gap, whether it has one, and
    whether it has one of surprise :data:`CLUMP_SURPRISE`. A gap has a ratio ``d_{j+1} / d_j``
    of at least :data:`CLUMP_RATIO` and a surprise ``j log(d_{j+1} / d_j)`` of at least
    :data:`CLUMP_SEEN`; the clump's is the first whose log ratio is at least :data:`CLUMP_NEST`
    of the widest's (wider than the steps in a clump's tail, and nearer than the gap after
    a pair of places close together)."""
    d = np.maximum(dist[:, 1:], np.finfo(float).tiny)
    step = np.log(d[:, 1:] / d[:, :-1])
    surprise = np.where(step >= np.log(CLUMP_RATIO), np.arange(1, d.shape[1]) * step, 0.0)
    gaps = surprise >= CLUMP_SEEN
    widest = np.where(gaps, step, 0.0).max(axis=1, keepdims=True)
    return np.argmax(gaps & (step >= CLUMP_NEST * widest), axis=1) + 1, gaps.any(axis=1), \
        (surprise >= CLUMP_SURPRISE).any(axis=1)


def screened(idx: np.ndarray, points: np.ndarray, spatial: bool = True) -> int:
    """How many nearest a search must find to tell the clumps of a cloud that may be made of
    them (0: it is not), judged on :data:`CLUMP_SAMPLE` rows of its graph ``idx`` (N, k) of
    ``points`` by their exact distances to their neighbours' neighbours and, if the points
    are in ``spatial`` order, to the rows beside them (the places next to a place of more
    than k copies; in another order those are far points, and every row would show a gap):
    at least half the share of points of a clumped cloud lie before a surprising gap."""
    n, k = idx.shape
    rows = np.unique(np.linspace(0, n - 1, min(n, CLUMP_SAMPLE)).astype(np.int64))
    reach = idx[idx[rows]].reshape(len(rows), -1)
    beside = np.arange(-CLUMP_WINDOW, CLUMP_WINDOW + 1) if spatial else np.zeros(1, dtype=np.int64)
    window = np.clip(rows[:, None] + beside, 0, n - 1)
    near = np.sort(np.concatenate([reach, window], axis=1), axis=1)
    dist = np.linalg.norm(points[near] - points[rows, None], axis=2)
    dist[:, 1:][near[:, 1:] == near[:, :-1]] = np.inf  # each point once
    dist = np.sort(dist, axis=1)[:, : int(np.isfinite(dist).sum(axis=1).min())]
    inside, _, clumped = clump_gaps(dist)
    if np.count_nonzero(clumped) < 0.5 * CLUMP_SHARE * len(rows):
        return 0
    return int(min(CLUMP_WIDEST, max(2 * k, 2 * np.percentile(inside[clumped], 90) + k)))


def stacked_places(points: np.ndarray, rank: np.ndarray, wide: int):
    """``(means, first, inverse)`` of a cloud most of whose points lie in clumps (see the
    module), or None: each place's mean, its copy nearest the mean (a row of ``points``; the
    places in the order of these copies' ``rank``) and the place of every row, from a search
    of ``wide`` nearest. The points in no agreed clump are searched again on their own (the
    clumps whose copies' tails hid their gap); those still in none join the nearest place
    within 3/4 of its distance to the next place, or make places of balls; the parts of a
    clump are joined (:func:`_halves_joined`) and every copy goes to its nearest place."""
    rank = np.asarray(rank, dtype=np.int64)
    label = _agreed_clumps(points, rank, wide)
    if np.count_nonzero(label >= 0) < CLUMP_SHARE * len(points):
        return None
    for _ in range(CLUMP_ROUNDS):
        loose = np.flatnonzero(label < 0)
        again = _agreed_clumps(points[loose], rank[loose], wide) if len(loose) > 2 else loose[:0]
        if not (again >= 0).any():
            break
        label[loose[again >= 0]] = loose[again[again >= 0]]
    lead, place = np.unique(label[label >= 0], return_inverse=True)
    seeded = label >= 0
    means = _means(points[seeded], place.ravel(), len(lead))
    apart = cKDTree(means).query(means, k=2)[0][:, 1]
    loose = np.flatnonzero(~seeded)
    gap, near = cKDTree(means).query(points[loose], k=1)
    joined = gap <= CLUMP_JOIN * apart[near]
    inverse = np.empty(len(points), dtype=np.int64)
    inverse[seeded] = place.ravel()
    inverse[loose[joined]] = near[joined]
    rest = loose[~joined]
    inverse[rest] = len(lead) + _balls(points[rest], rank[rest], 0.5 * apart[near[~joined]])
    inverse = _halves_joined(points, inverse)
    inverse = np.unique(cKDTree(_means(points, inverse, inverse.max() + 1)).query(points, k=1)[1],
                        return_inverse=True)[1].ravel()  # each copy to its nearest place (a step of Lloyd's)
    return _in_rank_order(points, rank, _means(points, inverse, inverse.max() + 1), inverse)


def _halves_joined(points, inverse):
    """``inverse`` with places nearer each other than :data:`CLUMP_HALVES` of the median
    distance to their 8 nearest places and than twice the larger's spread (RMS distance of
    its copies) joined: the parts of a clump whose copies saw gaps within it (along a view
    ray, 20 copies jittered by 0.01 of the spacing: 47 % of the places split)."""
    means = _means(points, inverse, inverse.max() + 1)
    if len(means) < 10:
        return inverse
    spread = np.sqrt(_means(np.sum((points - means[inverse]) ** 2, axis=1)[:, None], inverse, len(means))[:, 0])
    dist, idx = cKDTree(means).query(means, k=9)
    near = dist[:, 1:] < np.minimum(CLUMP_HALVES * np.median(dist[:, 1:], axis=1, keepdims=True),
                                    2.0 * np.maximum(spread[:, None], spread[idx[:, 1:]]))
    rows, cols = np.nonzero(near)
    return pair_components(len(means), rows, idx[rows, cols + 1])[inverse]


def _balls(points, rank, radius):
    """A place of each point in rank order not yet placed and of those not yet placed
    within its ``radius``: its label (0, 1, ...)."""
    label = np.full(len(points), -1, dtype=np.int64)
    tree = cKDTree(points)
    for row in np.argsort(rank, kind="stable"):
        if label[row] < 0:
            ball = np.asarray(tree.query_ball_point(points[row], radius[row]), dtype=np.int64)
            label[ball[label[ball] < 0]] = label.max() + 1
    return label


def _agreed_clumps(points, rank, wide):
    """The row of the lowest ``rank`` in each point's clump where most of its copies see the
    same clump behind a surprising gap, -1 elsewhere."""
    n, k = len(points), min(wide, len(points))
    tree = cKDTree(points)
    inside, sure, label = np.empty(n, dtype=np.int64), np.empty(n, dtype=bool), np.empty(n, dtype=np.int64)
    nearest = np.empty((n, min(k, SURFACE_NEAREST)), dtype=np.int32)  # the rows the object test reads
    for start in range(0, n, CLUMP_BLOCK):
        block = slice(start, min(n, start + CLUMP_BLOCK))
        dist, idx = tree.query(points[block], k=k, workers=-1)
        nearest[block] = idx[:, :SURFACE_NEAREST]
        inside[block], sure[block], _ = clump_gaps(dist)
        within = np.arange(k)[None, :] <= inside[block][:, None]
        lowest = np.argmin(np.where(within, rank[idx], np.iinfo(np.int64).max), axis=1)
        label[block] = idx[np.arange(len(idx)), lowest]
    # a clump seen alike by most of its copies: more than half of its size name its lowest row and its size
    _, at, count = np.unique(label * (k + 1) + inside, return_inverse=True, return_counts=True)
    agreed = (2 * count[at.ravel()] > inside + 1) & sure
    agreed &= ~object_clumps(points, np.where(agreed, label, -1), nearest)  # small objects keep their points
    return np.where(agreed, label, -1)


def _means(values, group, count):
    """The mean of ``values`` (N, d) over each of ``count`` groups ``group`` (N,)."""
    size = np.bincount(group, minlength=count).astype(float)
    sums = np.stack([np.bincount(group, weights=column, minlength=count) for column in values.T], axis=1)
    return sums / np.maximum(size, 1.0)[:, None]


def _in_rank_order(points, rank, means, inverse):
    """``(means, first, inverse)`` with each place's copy nearest its mean as ``first`` and
    the places in the order of those copies' ``rank``."""
    offset = np.linalg.norm(points - means[inverse], axis=1)
    order = np.lexsort((rank, offset, inverse))
    starts = np.flatnonzero(np.r_[True, inverse[order][1:] != inverse[order][:-1]])
    first = order[starts]  # per place (places in label order), its most central copy
    by_rank = np.argsort(rank[first], kind="stable")
    renumber = np.empty(len(first), dtype=np.int64)
    renumber[by_rank] = np.arange(len(first))
    return means[by_rank], first[by_rank], renumber[inverse]
