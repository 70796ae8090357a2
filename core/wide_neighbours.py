"""Neighbour graphs that hold the first columns of every row and search the rest on
demand (issue 15, speed).

With k="auto" a plan allows up to 226-320 neighbours per point, but the jet rule stops at
15-28 of them at nearly every point of a noise-free cloud: searching all 226 for every
point was the largest single cost of an estimate of 100k points (0.69 CPU s, against 0.22
for 56), and moving that graph to the caller's order the next. The search's answer is
canonical (the k smallest by distance, then the caller's index), so the first k of a
wider query are a narrower query's and a row searched wider extends the row held, bit
for bit: :class:`WidenableNeighbours` holds :data:`core.tuning.SEARCH_WIDTH` columns and
the tree, :class:`LazyNeighbours` is that graph in the caller's order (what
``CurvatureResult.neighbours`` holds) and :func:`core.wide_rows.rows_at_least` gives a fit every
row at the width it uses.
"""

from __future__ import annotations

import threading

import numpy as np

from ._progress import Progress
from .kernels.kdtree import query_rows
from .neighbours import _CHUNK, Neighbours, _query_tree, _search, _self_first
from .tuning import SEARCH_RADIUS_NODE, SEARCH_REACH

__all__ = ["WidenableNeighbours", "LazyNeighbours", "search_in_spatial_order"]


def search_in_spatial_order(pts: np.ndarray, k_max: int, *, progress=None, width: int | None = None):
    """:func:`core.neighbours.search_in_spatial_order`; with ``width`` < ``k_max`` only
    that many neighbours per point, in a :class:`WidenableNeighbours` that searches further
    rows when asked (not with the duplicate-aware search, which searches ``k_max``)."""
    nb, order, tree = _search(pts, k_max, progress, spatial=True, width=width)
    if tree is None:
        return nb, order
    return WidenableNeighbours(nb.points, nb.indices, nb.distances, k_max=k_max, tree=tree, rank=order), order


class WidenableNeighbours(Neighbours):
    """:class:`Neighbours` of points in spatial order (:func:`search_in_spatial_order`)
    that holds only the first :attr:`width` of its ``k_max`` neighbours per point and
    searches further rows on demand, with the tree and the ranks of the first search.

    The search's answer is canonical (the k smallest by distance, then the caller's
    index), so the first k of a wider query are a narrower query's: a row searched wider
    extends the one held, bit for bit. :meth:`rows` serves some rows at any k up to
    ``k_max``; :meth:`take` beyond the width, :attr:`indices` and :attr:`distances`
    widen every row to ``k_max`` first (:meth:`widen`), once. With k="auto" most points
    of a noise-free cloud use at most 40 neighbours of the 226-320 the plan allows.
    """

    def __init__(self, points, indices, distances, *, k_max, tree, rank, sheets=None):
        object.__setattr__(self, "_points", points)
        object.__setattr__(self, "_sheets", sheets)  # a core.one_sheet.SheetRows, put into every row served
        object.__setattr__(self, "_pair", (indices, distances))  # one attribute: replaced at once
        object.__setattr__(self, "_lock", threading.Lock())
        object.__setattr__(self, "_k_max", int(k_max))
        object.__setattr__(self, "_tree", tree)
        object.__setattr__(self, "_rank", rank)
        object.__setattr__(self, "_kept", None)  # (least width, [(centres, rows), ...]) while keep_rows asks

    def __reduce__(self):  # pickled (and copied) as the whole graph: the lock and tree stay here
        return Neighbours, (self.points, self.indices, self.distances)

    def __repr__(self) -> str:
        return f"WidenableNeighbours(n={len(self._points)}, k_max={self._k_max}, width={self.width})"

    @property
    def points(self) -> np.ndarray:
        return self._points

    @property
    def indices(self) -> np.ndarray:
        return self.widen()[0]

    @property
    def distances(self) -> np.ndarray:
        return self.widen()[1]

    @property
    def complete(self) -> bool:
        """Whether all ``k_max`` neighbours of every row are held."""
        return self.width >= self._k_max

    @property
    def k_max(self) -> int:
        return self._k_max

    @property
    def width(self) -> int:
        return self._pair[0].shape[1]

    def _held(self):
        return self._pair

    def with_sheets(self, indices, distances, sheets):
        """A new graph on the same tree that holds ``indices`` and ``distances`` (this one's
        held rows, some listing their own sheet first) and serves the further columns of
        those rows from ``sheets`` (a :class:`core.one_sheet.SheetRows`), searched rows alike;
        this one is unchanged (a cache may hold it)."""
        indices.setflags(write=False)
        distances.setflags(write=False)
        return WidenableNeighbours(self._points, indices, distances, k_max=self._k_max, tree=self._tree,
                                   rank=self._rank, sheets=sheets)

    def take(self, k: int):
        self._check_k(k)
        idx, dist = self._pair if k <= self.width else self.widen(k)
        return idx[:, :k], dist[:, :k]

    def rows(self, centres: np.ndarray, k: int):
        self._check_k(k)
        pair, sheets = self._state()
        held_idx, held_dist = pair
        if k <= held_idx.shape[1]:
            return held_idx[centres, :k], held_dist[centres, :k]
        centres = np.asarray(centres, dtype=np.int64)
        idx = np.empty((len(centres), k), dtype=held_idx.dtype)
        dist = np.empty((len(centres), k), dtype=np.float64)
        for start in range(0, len(centres), _CHUNK):
            stop = min(len(centres), start + _CHUNK)
            query_rows(self._points, self._tree, self._rank, centres[start:stop], dist[start:stop],
                       idx[start:stop], max(k, SEARCH_RADIUS_NODE), SEARCH_REACH)
        _self_first(idx, dist, centres)
        if sheets is not None:
            sheets.put(idx, dist, pair, centres)
        with self._lock:
            if self._kept is not None and self._kept[0] <= k:
                self._kept[1].append((centres, idx))
        return idx, dist

    def keep_rows(self, k: int) -> None:
        """Keep the indices of the rows :meth:`rows` searches at width ``k`` or more from now on,
        for :meth:`kept_rows`: k="auto"'s jets and its anchors' fits read the same rows of 320 at
        nearly the same points, and searching them twice was 5 % of a noisy estimate."""
        with self._lock:
            object.__setattr__(self, "_kept", (int(k), []))

    def keep_only(self, rows: np.ndarray, keep: np.ndarray) -> None:
        """Of ``rows`` (an array :meth:`rows` returned and kept) keep only the rows ``keep``
        (bool): at 1e-3 spacing of noise every jet of a 1M torus is re-run on 320 and is the
        result, and the kept rows nobody fits on were 1221 MB at the estimate's peak."""
        with self._lock:
            blocks = [] if self._kept is None else self._kept[1]
            at = next((b for b, (_, idx) in enumerate(blocks) if idx is rows), None)
            if at is not None and not keep.all():
                centres = blocks.pop(at)[0]
                if keep.any():
                    blocks.insert(at, (centres[keep], rows[keep]))

    def kept_rows(self, k: int) -> list:
        """``[(centres, rows), ...]`` searched at width ``k`` or more since :meth:`keep_rows`
        (their first k columns are a search's at k, bit for bit; their distances are not kept:
        at 1M points they were 600 MB), handed over: this graph keeps no more of them."""
        with self._lock:
            kept = self._kept
            object.__setattr__(self, "_kept", None)
        return [] if kept is None else [(c, rows) for c, rows in kept[1] if rows.shape[1] >= k]

    def whole_rows(self, centres):
        """All ``k_max`` columns of the rows of ``centres``, which list their own sheet first
        (:class:`core.one_sheet.SheetRows`): their held columns and the rest kept for them."""
        pair, sheets = self._state()
        if sheets is None:  # widened to k_max: all held
            return self.rows(centres, self._k_max)
        rows = sheets.slot[centres]
        return (np.hstack((pair[0][centres], sheets.idx[rows])), np.hstack((pair[1][centres], sheets.dist[rows])))

    def _state(self):
        """The held rows and the :class:`core.one_sheet.SheetRows` beyond them, read as one
        (:meth:`widen` replaces both)."""
        if self._sheets is None:
            return self._pair, None
        with self._lock:
            return self._pair, self._sheets

    def widen(self, k: int | None = None, *, progress=None, found=None):
        """Every row searched to ``k`` (default ``k_max``) neighbours, if fewer are held;
        ``found``: those rows already, ``(idx, dist)`` as :meth:`rows` gives them."""
        k = self._k_max if k is None else k
        self._check_k(k)
        with self._lock:  # a viewer's result may be read on one thread while the next job widens it
            if self.width < k:
                if found is None:
                    found = self._searched(k, progress)
                idx, dist = found
                sheets = self._sheets
                if sheets is not None:
                    sheets = sheets.beyond(k - self.width)  # the columns now held are dropped from it
                idx.setflags(write=False)
                dist.setflags(write=False)
                object.__setattr__(self, "_pair", (idx, dist))
                object.__setattr__(self, "_sheets", sheets)
            return self._pair

    def _searched(self, k, progress):
        """Every row's ``k`` nearest, searched (those listing their own sheet first as :meth:`rows` serves them)."""
        n = len(self._points)
        idx = np.empty((n, k), dtype=self._pair[0].dtype)
        dist = np.empty((n, k), dtype=np.float64)
        _query_tree(self._points, self._tree, self._rank, idx, dist, Progress(progress))
        if self._sheets is not None:
            self._sheets.put(idx, dist, self._pair)
        return idx, dist


class LazyNeighbours(Neighbours):
    """The graph ``source`` (a :class:`WidenableNeighbours` on the points in spatial
    order, sorted point s being the caller's ``order[s]``) as neighbours of the caller's
    ``points``, what :attr:`core.CurvatureResult.neighbours` holds when the estimate ran in
    spatial order (converting a graph nobody reads was 1.1 s of a 1M-point estimate; ``source``
    may also be a plain :class:`Neighbours`). The columns held and the rows searched wider are
    served from ``source`` in the caller's order (:meth:`take`, :meth:`rows`, so an
    estimate it is passed back to searches no more than the first one did); reading
    :attr:`indices` or :attr:`distances` makes the whole graph once, by ``make()``."""

    served_in_place = False  # its rows are copies

    def __init__(self, points, source, order, make):
        inverse = np.empty_like(order)
        inverse[order] = np.arange(len(order), dtype=order.dtype)
        for name, value in dict(_points=points, _source=source, _order=order, _inverse=inverse, _make=make,
                                _made=None, _k_max=source.k_max, _lock=threading.Lock()).items():
            object.__setattr__(self, name, value)

    def __reduce__(self):  # pickled (and copied) as the whole graph
        return Neighbours, (self.points, self.indices, self.distances)

    def __repr__(self) -> str:
        return f"LazyNeighbours(n={len(self._points)}, k_max={self._k_max}, made={self._made is not None})"

    def spatial(self):
        """``(source, order)`` while the graph is still held in spatial order, else None."""
        with self._lock:
            return None if self._source is None else (self._source, self._order)

    def _graph(self) -> Neighbours:
        with self._lock:
            if self._made is None:
                made = self._make()
                for name, value in dict(_made=made, _make=None, _source=None, _order=None, _inverse=None).items():
                    object.__setattr__(self, name, value)
        return self._made

    @property
    def points(self) -> np.ndarray:
        return self._points

    @property
    def indices(self) -> np.ndarray:
        return self._graph().indices

    @property
    def distances(self) -> np.ndarray:
        return self._graph().distances

    @property
    def k_max(self) -> int:
        return self._k_max

    @property
    def width(self) -> int:
        source = self._source
        return self._k_max if source is None else source.width

    def _held(self):
        return self.take(self.width)

    def take(self, k: int):
        self._check_k(k)
        with self._lock:
            source, order, inverse = self._source, self._order, self._inverse
        if source is None or k > source.width:
            return self._graph().take(k)
        idx, dist = source.take(k)
        return order[idx[inverse]], dist[inverse]

    def rows(self, centres: np.ndarray, k: int):
        self._check_k(k)
        with self._lock:
            source, order, inverse = self._source, self._order, self._inverse
        if source is None:
            return self._made.rows(centres, k)
        idx, dist = source.rows(inverse[np.asarray(centres)], k)
        return order[idx], dist

    def widen(self, k: int | None = None, *, progress=None):
        if k is not None and k <= self.width:
            return self._held()
        graph = self._graph()
        return graph.indices, graph.distances
