"""k-nearest-neighbour search, done once and reused (Open3D-style: *which neighbours*
is kept apart from *which estimator*)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, ClassVar, Union

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from ._progress import Progress
from ._validate import as_points, check_int
from .kernels.kd_order import kd_order
from .kernels.kdtree import build_tree, query_sorted
from .kernels.knn import keep_nearest, unflagged_first
from .kernels.repeats import coordinate_hashes
from .spacing import mean_spacing
from .tuning import ORDER_LEAF, SEARCH_LEAF, SEARCH_RADIUS_NODE, SEARCH_REACH

#: ``progress(fraction, stage)``; returning False cancels
ProgressCallback = Callable[[float, str], Union[bool, None]]
_CHUNK = 200_000
#: a kd-tree query inside a group of c identical points costs O(c): 80k copies take 17 s
#: for k=20 (4x per doubling). Larger groups are searched once, on the distinct points.
MAX_DUPLICATES = 256
#: rows per step when neighbours are re-ordered (bounds the temporary arrays)
_ROWS = 65_536


@dataclass(frozen=True, eq=False)
class Neighbours:
    """The ``k_max`` nearest neighbours of every point (the point itself first).

    Attributes
    ----------
    points : (N, 3) float64 array the search was run on.
    indices : (N, k_max) int array, sorted by distance, ``indices[:, 0]`` is the point.
    distances : (N, k_max) float array of Euclidean distances.

    :meth:`take`, :meth:`rows` and :meth:`take_without` are what the estimate reads; a
    :class:`core.wide_neighbours.WidenableNeighbours` (k="auto") holds only the first
    :attr:`width` columns and serves the rest through them by searching.
    """

    points: np.ndarray
    indices: np.ndarray
    distances: np.ndarray

    #: True where :meth:`take` serves the held rows in place (views): a caller that reads only
    #: the first k columns may take :attr:`width` of them and skip a copy of every row
    served_in_place: ClassVar[bool] = True

    @property
    def k_max(self) -> int:
        return self.indices.shape[1]

    def take(self, k: int):
        """Indices and distances of the ``k`` nearest (views, no copy)."""
        self._check_k(k)
        return self.indices[:, :k], self.distances[:, :k]

    def take_indices(self, k: int) -> np.ndarray:
        """The indices of :meth:`take` alone (a graph that builds its rows then skips the distances)."""
        return self.take(k)[0]

    @property
    def width(self) -> int:
        """Columns held in memory: every row's first ``width`` neighbours are at hand
        (``k_max`` here; fewer for a :class:`WidenableNeighbours`, which searches the rest)."""
        return self.k_max

    def rows(self, centres: np.ndarray, k: int):
        """The ``k`` nearest of the points ``centres`` (M,) int: (M, k) indices and distances."""
        self._check_k(k)
        return self.indices[centres, :k], self.distances[centres, :k]

    def take_without(self, k: int, drop: np.ndarray):
        """The ``k`` nearest not flagged in ``drop`` (N,) bool, each point itself first;
        a row short of unflagged neighbours ends with its nearest flagged ones (copies)."""
        self._check_k(k)
        held_idx, held_dist = self._held()
        n, width = held_idx.shape
        idx = np.empty((n, k), dtype=held_idx.dtype)
        dist = np.empty((n, k), dtype=held_dist.dtype)
        free = np.empty(n, dtype=np.int64)
        drop = np.ascontiguousarray(drop, dtype=np.bool_)
        unflagged_first(held_idx, held_dist, drop, idx, dist, free)
        short = np.flatnonzero(free < k) if width < self.k_max else free[:0]
        for start in range(0, len(short), _ROWS):  # fewer than k unflagged among those held: their whole list
            rows = short[start:start + _ROWS]
            w_idx, w_dist = self.rows(rows, self.k_max)
            w_idx.setflags(write=False)  # the held rows' type (a cached graph's are read-only): one compiled variant
            w_dist.setflags(write=False)
            part_idx, part_dist = np.empty((len(rows), k), dtype=idx.dtype), np.empty((len(rows), k))
            unflagged_first(w_idx, w_dist, drop, part_idx, part_dist, np.empty(len(rows), dtype=np.int64))
            idx[rows], dist[rows] = part_idx, part_dist
        return idx, dist

    def _held(self):
        """The (N, width) indices and distances in memory."""
        return self.indices, self.distances

    def widen(self, k: int | None = None, *, progress=None):
        """Hold at least ``k`` (default ``k_max``) neighbours of every row; returns the
        (N, width) indices and distances held (here all ``k_max`` always are)."""
        return self.indices, self.distances

    def _check_k(self, k: int) -> None:
        if k > self.k_max:
            raise ValueError(f"k={k} exceeds the cached neighbourhood size k_max={self.k_max}")

    def matches(self, points: np.ndarray) -> bool:
        """True when these neighbours were computed on exactly ``points``."""
        return self.points is points or (
            self.points.shape == points.shape and np.array_equal(self.points, points)
        )

    def mean_spacing(self) -> float:
        """Mean distance to the nearest other point (the unit of relative noise)."""
        return mean_spacing(self.points, neighbours=self)


def build_neighbours(points: ArrayLike, k_max: int, *, progress: ProgressCallback | None = None) -> Neighbours:
    """Find the ``k_max`` nearest neighbours of each point with scipy's cKDTree (all cores).

    Parameters
    ----------
    points : (N, 3) array_like
    k_max : int, 1 <= k_max <= N. The largest k the neighbours will serve.
    progress : callable(fraction, stage) -> None | False, optional. False cancels.

    Examples
    --------
    >>> import numpy as np
    >>> nb = build_neighbours(np.random.default_rng(0).random((100, 3)), 8)
    >>> nb.indices.shape, bool((nb.indices[:, 0] == np.arange(100)).all())
    ((100, 8), True)
    """
    pts, _ = as_points(points)
    nb = search_neighbours(pts, k_max, progress=progress)
    pts.setflags(write=False)
    return nb


def search_neighbours(pts: np.ndarray, k_max: int, *, progress=None) -> Neighbours:
    """:func:`build_neighbours` on points already validated (a C-contiguous (N, 3)
    float64 array, e.g. from :func:`core.estimate`), which are kept, not copied."""
    return _search(pts, k_max, progress, spatial=False)[0]


def search_in_spatial_order(pts: np.ndarray, k_max: int, *, progress=None) -> tuple[Neighbours, np.ndarray | None]:
    """:func:`search_neighbours` on the points put in a kd-tree's leaf order
    (:mod:`core.kernels.kd_order`; neighbours in space are neighbours in memory: every later
    loop over the neighbours reads cache lines already loaded, 2-3x faster at 1M points, and
    the search itself too).

    Returns ``(nb, order)``: ``nb`` holds the points ``pts[order]`` and their neighbours
    as indices into that array; each row holds the same neighbours in the same order as
    :func:`search_neighbours` gives (ties are broken by the caller's index, not by the
    sorted one). ``order`` is None, and ``nb`` in the caller's order, when large groups of
    identical points take the duplicate-aware search.
    """
    return _search(pts, k_max, progress, spatial=True)[:2]


def _search(pts, k_max, progress, *, spatial, width=None):
    """``(nb, order, tree)``: the search; with ``width`` < ``k_max`` in spatial order (and
    without the duplicate-aware search) only the first ``width`` neighbours, and the tree
    of the sorted points that finds the rest (else None; see
    :func:`core.wide_neighbours.search_in_spatial_order`)."""
    k_max = check_int(k_max, name="k_max", low=1, high=len(pts))
    report = Progress(progress)
    report(0.0, "neighbours")
    n = len(pts)
    dtype = np.int64 if n > 2**31 - 1 else np.int32
    groups = _duplicate_groups(pts) if _largest_group_bound(pts) > MAX_DUPLICATES else None
    narrow = spatial and groups is None and width is not None and width < k_max
    cols = width if narrow else k_max
    idx = np.empty((n, cols), dtype=dtype)
    dist = np.empty((n, cols), dtype=np.float64)
    if groups is not None:
        _query_with_duplicates(pts, groups, idx, dist, report)
        spatial = False
    else:
        if spatial:
            order, pts = leaf_order(pts, idx.dtype)
            sorted_tree = build_tree(pts, SEARCH_LEAF)
            _query_tree(pts, sorted_tree, order, idx, dist, report)
        else:
            _query_distinct(cKDTree(pts), pts, None, idx, dist, report)
    idx.setflags(write=False)
    dist.setflags(write=False)
    nb = Neighbours(points=pts, indices=idx, distances=dist)
    return nb, (order if spatial else None), (sorted_tree if narrow else None)


def leaf_order(pts, dtype) -> tuple[np.ndarray, np.ndarray]:
    """``(order, pts[order])``: the points' spatial order (:func:`core.kernels.kd_order.kd_order`,
    ranges of :data:`~core.tuning.ORDER_LEAF`), as ``dtype`` indices, and the points in it."""
    order, in_order = kd_order(np.ascontiguousarray(pts, dtype=np.float64), ORDER_LEAF)
    return order.astype(dtype), in_order


def _largest_group_bound(pts) -> int:
    """An upper bound on the size of the largest group of identical points, from a hash
    of their coordinates (a collision only overestimates): the largest of ~2N buckets of
    the hashes' top bits (a count, no sort), and where that exceeds :data:`MAX_DUPLICATES`
    the largest group of equal hashes (a sort of N integers, 30x faster than sorting the
    points by their three coordinates), so the search is chosen as by the sort alone
    (100k torus: 7.8 -> 2.0 CPU ms; 1M: 88 -> 25)."""
    h = coordinate_hashes(pts)
    shift = np.uint64(64 - max(int(2 * len(h) - 1).bit_length(), 1))  # the top bits mix every input bit
    bound = int(np.bincount((h >> shift).astype(np.int64)).max())
    if bound <= MAX_DUPLICATES:
        return bound
    h.sort()
    new = np.ones(len(h) + 1, dtype=bool)
    np.not_equal(h[1:], h[:-1], out=new[1:-1])
    return int(np.diff(np.flatnonzero(new)).max())


def _query_distinct(tree, pts, order, idx, dist, report) -> None:
    """Plain kd-tree search (few or no duplicates); row r of ``idx`` / ``dist`` holds the
    neighbours of point ``order[r]`` (of point r without ``order``), as the caller's indices."""
    n, k_max = idx.shape
    k_query = min(k_max + 1, n)  # one more: a tie at the cut shows as equal k-th and (k+1)-th distances
    for start in range(0, n, _CHUNK):
        stop = min(n, start + _CHUNK)
        query = pts[start:stop] if order is None else pts[order[start:stop]]
        d, i = tree.query(query, k=k_query, workers=-1)
        d, i = np.reshape(d, (stop - start, k_query)), np.reshape(i, (stop - start, k_query))
        if k_query > k_max:
            _canonical_cut(tree, pts, query, d, i, k_max)
        tied = np.empty(stop - start, dtype=np.bool_)
        keep_nearest(d, i, dist[start:stop], idx[start:stop], tied)
        _ties_by_index(dist[start:stop], idx[start:stop], np.flatnonzero(tied))
        report(stop / n, "neighbours")
    _self_first(idx, dist, np.arange(n) if order is None else order)


def _query_tree(pts, tree, rank, idx, dist, report) -> None:
    """:func:`_query_distinct`'s answer for points in the kd-tree's leaf order, found by
    :mod:`core.kernels.kdtree` on its ``tree`` of them (indices into ``pts``, ties by
    ``rank``, the caller's index): the same rows, bit for bit, at a fraction of the cost
    for k in the hundreds."""
    n, k_max = idx.shape
    want = max(k_max, SEARCH_RADIUS_NODE)
    for start in range(0, n, _CHUNK):
        stop = min(n, start + _CHUNK)
        query_sorted(pts, tree, rank, start, dist[start:stop], idx[start:stop], want, SEARCH_REACH)
        report(stop / n, "neighbours")
    _self_first(idx, dist, np.arange(n))


def _duplicate_groups(pts):
    """``(order, starts, counts, inverse)`` of the groups of identical points (``order``
    sorts the points by group, group g is ``order[starts[g]:starts[g] + counts[g]]``,
    ``inverse`` maps a point to its group), or None when no group exceeds MAX_DUPLICATES."""
    n = len(pts)
    order = np.lexsort(pts.T[::-1])
    srt = pts[order]
    new = np.ones(n, dtype=bool)
    np.any(srt[1:] != srt[:-1], axis=1, out=new[1:])
    starts = np.flatnonzero(new)
    counts = np.diff(np.append(starts, n))
    if len(counts) == 0 or counts.max() <= MAX_DUPLICATES:
        return None
    inverse = np.empty(n, dtype=np.intp)
    inverse[order] = np.cumsum(new) - 1
    return order, starts, counts, inverse


def _query_with_duplicates(pts, groups, idx, dist, report) -> None:
    """The same neighbours as a plain search, found on the distinct points only: each
    distinct neighbour stands for its copies (nearest first, itself first among them)."""
    order, starts, counts, inverse = groups
    n, k_max = idx.shape
    distinct = pts[order[starts]]
    tree = cKDTree(distinct)
    k_u = min(k_max, len(distinct))
    rows = max(1, _CHUNK // 8)
    for g0 in range(0, len(distinct), rows):
        g1 = min(len(distinct), g0 + rows)
        d, q = tree.query(distinct[g0:g1], k=k_u, workers=-1)
        d, q = np.reshape(d, (g1 - g0, k_u)), np.reshape(q, (g1 - g0, k_u))
        # copies each distinct neighbour contributes: all of them until k_max are taken
        cnt = counts[q]
        take = np.clip(k_max - (np.cumsum(cnt, axis=1) - cnt), 0, cnt).ravel()
        first = np.repeat(np.cumsum(take) - take, take)
        member = order[np.repeat(starts[q.ravel()], take) + np.arange(len(first)) - first]
        g_idx = member.reshape(g1 - g0, k_max)
        g_dist = np.repeat(d.ravel(), take).reshape(g1 - g0, k_max)
        pts_in = order[starts[g0]:(starts[g1] if g1 < len(starts) else n)]
        rows_idx = g_idx[inverse[pts_in] - g0]
        hit = rows_idx == pts_in[:, None]  # put the point itself first, swapping with a copy
        has = hit.any(axis=1)
        where = np.flatnonzero(has)
        rows_idx[where, hit[where].argmax(axis=1)] = rows_idx[where, 0]
        rows_idx[:, 0] = pts_in
        idx[pts_in] = rows_idx
        dist[pts_in] = g_dist[inverse[pts_in] - g0]
        report(g1 / len(distinct), "neighbours")


def _canonical_cut(tree, pts, query, d, i, k_max) -> None:
    """Rows whose k_max-th and next neighbours are equally far: keep the lowest indices.

    The kd-tree keeps whichever tied point it met first, which depends on the tree; with
    quantised coordinates (a LAS at cm scale: 0.7 % of rows at k = 15) the neighbourhood
    would then depend on which other points were in the tree. "The k nearest, ties to the
    lowest index" is the same for the whole cloud and any subset holding the ball in the
    same order, so a tile reproduces the in-memory neighbours (:mod:`core.tiled.halo`).
    """
    rows = np.flatnonzero(d[:, k_max] == d[:, k_max - 1])
    if not len(rows):
        return
    balls = tree.query_ball_point(query[rows], r=d[rows, k_max - 1] * (1 + 1e-12) + 1e-300)
    for r, ball in zip(rows, balls):
        ball = np.asarray(ball, dtype=np.int64)
        dd = np.sqrt(((pts[ball] - query[r]) ** 2).sum(axis=1))
        order = np.lexsort((ball, dd))[: k_max]
        d[r, :k_max], i[r, :k_max] = dd[order], ball[order]


def _ties_by_index(dist: np.ndarray, idx: np.ndarray, rows: np.ndarray) -> None:
    """Within equal distances, order neighbours by index (so that ``take(k)`` for a smaller
    k, and the sums over neighbours, do not depend on the kd-tree); ``rows``: those with a tie."""
    if len(rows):
        order = _row_lexsort(dist[rows], idx[rows])
        dist[rows] = np.take_along_axis(dist[rows], order, axis=1)
        idx[rows] = np.take_along_axis(idx[rows], order, axis=1)


def _row_lexsort(dist, idx):
    """Per row, the order by (distance, index)."""
    order = np.argsort(idx, axis=1, kind="stable")
    by_dist = np.argsort(np.take_along_axis(dist, order, axis=1), axis=1, kind="stable")
    return np.take_along_axis(order, by_dist, axis=1)


def _self_first(idx: np.ndarray, dist: np.ndarray, own: np.ndarray) -> None:
    """Duplicate points can tie with the point itself; put the point (row r's is
    ``own[r]``) first."""
    wrong = idx[:, 0] != own
    if not wrong.any():
        return
    for r in np.flatnonzero(wrong):
        me = own[r]
        pos = np.flatnonzero(idx[r] == me)
        if len(pos):
            j = pos[0]
            idx[r, 1 : j + 1] = idx[r, 0:j].copy()
        else:  # more than k_max exact duplicates: the point was not returned at all
            idx[r, 1:] = idx[r, :-1].copy()
            dist[r, 1:] = dist[r, :-1].copy()
        idx[r, 0] = me
        dist[r, 0] = 0.0
