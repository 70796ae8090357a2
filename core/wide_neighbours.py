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
``CurvatureResult.neighbours`` holds) and :func:`rows_at_least` gives a fit every row at
the width it uses.
"""

from __future__ import annotations

import threading

import numpy as np

from ._progress import Progress
from .kernels.kdtree import distances_at, query_rows
from .neighbour_budget import whole_cap
from .neighbours import _CHUNK, Neighbours, _query_tree, _search, _self_first
from .tuning import SEARCH_RADIUS_NODE, SEARCH_REACH

#: (row, neighbour) entries searched at a time for :func:`rows_at_least` (their distances: 32 MB)
_SEARCHED = 1 << 22

__all__ = ["WidenableNeighbours", "LazyNeighbours", "rows_at_least", "held_h", "search_in_spatial_order"]


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
        object.__setattr__(self, "_kept", None)  # (width, [(centres, rows), ...]) while keep_rows asks

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
            if self._kept is not None and self._kept[0] == k:
                self._kept[1].append((centres, idx))
        return idx, dist

    def keep_rows(self, k: int) -> None:
        """Keep the indices of the rows :meth:`rows` searches at width ``k`` from now on, for
        :meth:`kept_rows`: k="auto"'s jets and its anchors' fits read the same rows of 320 at
        nearly the same points, and searching them twice was 5 % of a noisy estimate."""
        with self._lock:
            object.__setattr__(self, "_kept", (int(k), []))

    def kept_rows(self, k: int) -> list:
        """``[(centres, rows), ...]`` searched at width ``k`` since :meth:`keep_rows` (their
        distances are not kept: at 1M points they were 600 MB), handed over: this graph keeps
        no more of them."""
        with self._lock:
            kept, width = self._kept, None if self._kept is None else self._kept[0]
            object.__setattr__(self, "_kept", None)
        return kept[1] if width == k else []

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

    def widen(self, k: int | None = None, *, progress=None):
        """Every row searched to ``k`` (default ``k_max``) neighbours, if fewer are held."""
        k = self._k_max if k is None else k
        self._check_k(k)
        with self._lock:  # a viewer's result may be read on one thread while the next job widens it
            if self.width < k:
                n = len(self._points)
                idx = np.empty((n, k), dtype=self._pair[0].dtype)
                dist = np.empty((n, k), dtype=np.float64)
                _query_tree(self._points, self._tree, self._rank, idx, dist, Progress(progress))
                sheets = self._sheets
                if sheets is not None:
                    sheets.put(idx, dist, self._pair)
                    sheets = sheets.beyond(k - self.width)  # the columns now held are dropped from it
                idx.setflags(write=False)
                dist.setflags(write=False)
                object.__setattr__(self, "_pair", (idx, dist))
                object.__setattr__(self, "_sheets", sheets)
            return self._pair


class LazyNeighbours(Neighbours):
    """The graph ``source`` (a :class:`WidenableNeighbours` on the points in spatial
    order, sorted point s being the caller's ``order[s]``) as neighbours of the caller's
    ``points``, what :attr:`core.CurvatureResult.neighbours` holds when the estimate ran in
    spatial order (converting a graph nobody reads was 1.1 s of a 1M-point estimate; ``source``
    may also be a plain :class:`Neighbours`). The columns held and the rows searched wider are
    served from ``source`` in the caller's order (:meth:`take`, :meth:`rows`, so an
    estimate it is passed back to searches no more than the first one did); reading
    :attr:`indices` or :attr:`distances` makes the whole graph once, by ``make()``."""

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


def rows_at_least(nb, kc, fits=None):
    """``(rows, h)``: the neighbours of every point, at least ``kc[i]`` for point i, as an
    (N, kc.max()) array or, when ``nb`` holds fewer columns and only a minority of the
    points needs more, a :class:`_Rows` that adds them per chunk; ``h[i]`` the distance
    to point i's ``kc[i]``-th neighbour. ``fits`` (N,) bool, optional: the points expected
    to fit (k="auto"'s anchors, :mod:`core.anchors`); the others' wider rows are searched
    when they do (:meth:`_Rows.ensure`), and until then ``h`` is :func:`held_h`'s."""
    n, k = len(kc), int(kc.max())
    wide = np.flatnonzero(kc > nb.width) if k > nb.width else np.empty(0, dtype=np.int64)
    if fits is not None:
        wide = wide[fits[wide]]
    if 2 * len(wide) > n and k <= whole_cap(n, nb.width):
        nb.widen(k)
        wide = wide[:0]
    if k <= nb.width:
        idx, dist = nb.take(k)
        return idx, dist[np.arange(n), kc - 1]
    idx = nb.take(nb.width)[0]
    h = held_h(nb, kc)
    return _Rows(idx, wide, _wide_rows(nb, wide, k, kc, h), kc, nb), h


def _wide_rows(nb, centres, k, kc, h):
    """The ``k`` nearest (indices) of ``centres`` (M,): those the graph kept
    (:meth:`WidenableNeighbours.kept_rows`), the others searched in chunks; writes the
    distance to each one's ``kc``-th into ``h`` (the distances are not kept: at 1M points
    the anchors' 320 were 640 MB)."""
    w_idx = np.empty((len(centres), k), dtype=nb.take(1)[0].dtype)
    step = max(1, _SEARCHED // k)  # rows copied or searched at a time
    todo = np.ones(len(centres), dtype=bool)
    for kept, rows in nb.kept_rows(k) if hasattr(nb, "kept_rows") else ():
        at, pos = _positions(centres, kept)
        for start in range(0, len(at), step):
            a = at[start:start + step]
            w_idx[a] = rows[pos[start:start + step]]
            distances_at(nb.points, centres[a], w_idx, a, kc[centres[a]] - 1, h, centres[a])
        todo[at] = False
    rest = np.flatnonzero(todo)
    for start in range(0, len(rest), step):
        r = rest[start:start + step]
        w_idx[r], dist = nb.rows(centres[r], k)
        h[centres[r]] = dist[np.arange(len(r)), kc[centres[r]] - 1]
    return w_idx


def _positions(centres, kept):
    """``(at, pos)``: the entries ``at`` of ``centres`` that are in ``kept`` (both without
    repeats), at ``kept[pos]``."""
    if not len(kept):
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    order = np.argsort(kept, kind="stable")
    slot = np.minimum(np.searchsorted(kept, centres, sorter=order), len(kept) - 1)
    at = np.flatnonzero(kept[order[slot]] == centres)
    return at, order[slot[at]]


def held_h(nb, kc):
    """(N,): the distance to each point's ``kc``-th neighbour where ``nb`` holds it, else to
    the last neighbour held (a lower bound, > 0 as the exact one is: duplicates are merged before)."""
    dist = nb.take(min(nb.width, int(kc.max())))[1]
    return dist[np.arange(len(kc)), np.minimum(kc, dist.shape[1]) - 1].copy()


class _Rows:
    """The neighbours of a chunk of centres ``c`` (``self[c]``), as wide as the most any of
    them uses (``kc``): the ``held`` columns, and for the centres in ``wide`` (sorted) their
    rows ``w_idx`` searched wider (by ``nb``, :meth:`ensure`). Columns a centre does not use
    hold the centre itself (the fits read a centre's first kc only)."""

    __slots__ = ("held", "wide", "w_idx", "kc", "nb")

    def __init__(self, held, wide, w_idx, kc, nb):
        self.held, self.wide, self.w_idx, self.kc, self.nb = np.ascontiguousarray(held), wide, w_idx, kc, nb

    def ensure(self, c, h) -> None:
        """Search the wider rows of centres ``c`` not held yet, and write their ``h``."""
        c = c[(self.kc[c] > self.held.shape[1]) & ~self._slots(c)[1]]
        if not len(c):
            return
        w_idx = _wide_rows(self.nb, c, self.w_idx.shape[1], self.kc, h)
        wide = np.concatenate([self.wide, c])
        order = np.argsort(wide, kind="stable")
        self.wide, self.w_idx = wide[order], np.concatenate([self.w_idx, w_idx])[order]

    def parts(self, c):
        """The rows of centres ``c`` without a copy where they are held: ``(array, rows,
        centres)`` per part, row ``rows[r]`` of ``array`` listing the neighbours of
        ``centres[r]`` (its first ``kc`` columns: what the fits read): the held columns
        where they suffice, the rows searched wider for those in ``wide``, and a copy
        (:meth:`__getitem__`) for any other (a centre fitted before its rows were searched)."""
        width = self.held.shape[1]
        short = self.kc[c] <= width
        pos, found = self._slots(c)
        searched = ~short & found
        rest = ~short & ~searched
        out = [(self.held, c[short], c[short]), (self.w_idx, pos[searched], c[searched])]
        if rest.any():
            out.append((self[c[rest]], np.arange(np.count_nonzero(rest)), c[rest]))
        return [part for part in out if len(part[2])]

    def __getitem__(self, c):
        k = int(self.kc[c].max()) if len(c) else 1
        width = self.held.shape[1]
        if k <= width:
            return self.held[c, :k]
        idx = np.empty((len(c), k), dtype=self.held.dtype)
        idx[:, :width] = self.held[c]
        idx[:, width:] = c[:, None]
        pos, found = self._slots(c)
        mine = np.flatnonzero(found)
        idx[mine] = self.w_idx[pos[mine], :k]
        return idx

    def _slots(self, c):
        """``(pos, found)``: each centre's row of ``w_idx`` and whether it has one (``wide`` is sorted)."""
        if not len(self.wide):
            return np.zeros(len(c), dtype=np.int64), np.zeros(len(c), dtype=bool)
        pos = np.minimum(np.searchsorted(self.wide, c), len(self.wide) - 1)
        return pos, self.wide[pos] == c
