"""The rows k="auto"'s fits read (issue 15, speed): the columns a
:class:`core.wide_neighbours.WidenableNeighbours` holds, and for the points that fit on more
neighbours than that, their rows searched wider: those the scale's jets searched at nearly
the same points, which the graph kept for the fits
(:meth:`~core.wide_neighbours.WidenableNeighbours.keep_rows`), and the others searched here.
Only indices are held (the anchors' 320 distances were 640 MB at 1M points)."""

from __future__ import annotations

import numpy as np

from .kernels.kdtree import distances_at
from .kernels.kept_rows import rows_with_distances
from .kernels.permute import copy_rows
from .neighbour_budget import whole_cap

#: (row, neighbour) entries searched at a time (their distances: 32 MB)
_SEARCHED = 1 << 22

__all__ = ["rows_at_least", "held_h", "keep_only"]


def rows_at_least(nb, kc, fits=None):
    """``(rows, h)``: the neighbours of every point, at least ``kc[i]`` for point i, as an
    (N, kc.max()) array or, when ``nb`` holds fewer columns and only a minority of the
    points needs more, a :class:`_Rows` that adds them per chunk; ``h[i]`` the distance
    to point i's ``kc[i]``-th neighbour. ``fits`` (N,) bool, optional: the points expected
    to fit (k="auto"'s anchors, :mod:`core.anchors`); the others' wider rows are searched
    when they do (:meth:`_Rows.ensure`), and until then ``h`` is :func:`held_h`'s. Takes
    over the rows ``nb`` kept (:meth:`~core.wide_neighbours.WidenableNeighbours.kept_rows`)."""
    n, k = len(kc), int(kc.max())
    kept = nb.kept_rows(k) if hasattr(nb, "kept_rows") else []  # the graph holds them no more, used or not
    wide = np.flatnonzero(kc > nb.width) if k > nb.width else np.empty(0, dtype=np.int64)
    if fits is not None:
        wide = wide[fits[wide]]
    if 2 * len(wide) > n and k <= whole_cap(n, nb.width):
        nb.widen(k, **({"found": _whole_rows(nb, k, kept)} if kept else {}))
        wide = wide[:0]
    if k <= nb.width:
        idx, dist = nb.take(k)
        return idx, dist[np.arange(n), kc - 1]
    idx = nb.take(nb.width)[0]
    h = held_h(nb, kc)
    return _Rows(idx, wide, _wide_rows(nb, wide, k, kc, h, kept), kc, nb), h


def keep_only(nb, rows, keep):
    """Of the rows ``nb`` kept (:meth:`~core.wide_neighbours.WidenableNeighbours.keep_only`),
    only those ``keep``; the others a fit reads are searched again (:func:`_wide_rows`)."""
    if hasattr(nb, "keep_only"):
        nb.keep_only(rows, keep)


def _wide_rows(nb, centres, k, kc, h, kept=None):
    """The ``k`` nearest (indices) of ``centres`` (M,): those in the ``kept`` blocks
    ``(centres, rows)`` copied (:func:`core.kernels.permute.copy_rows`), the others searched
    in chunks; writes the distance to each one's ``kc``-th into ``h`` (for a kept row, the
    search's own distance recomputed: :func:`core.kernels.kdtree.distances_at`). The list
    ``kept`` (rows at least ``k`` wide, a centre's first block read) is emptied, each block
    freed once copied (all of them beside the new rows were 365 MB more at 1M points)."""
    w_idx = np.empty((len(centres), k), dtype=nb.take(1)[0].dtype)
    todo = np.ones(len(centres), dtype=bool)
    while kept:
        got, rows = kept.pop(0)
        at, pos = _positions(centres, got)
        at, pos = at[todo[at]], pos[todo[at]]  # a row kept twice (searched at two widths) is copied once
        copy_rows(rows, pos, w_idx, at)
        c, dist = centres[at], np.empty(len(at))
        distances_at(nb.points, c, rows, pos, kc[c] - 1, dist)
        h[c] = dist
        todo[at] = False
    rest = np.flatnonzero(todo)
    step = max(1, _SEARCHED // k)
    for start in range(0, len(rest), step):
        r = rest[start:start + step]
        c = centres[r]
        w_idx[r], dist = nb.rows(c, k)
        h[c] = dist[np.arange(len(r)), kc[c] - 1]
    return w_idx


def _whole_rows(nb, k, kept):
    """``(idx, dist)``: every point's ``k`` nearest, those of the ``kept`` blocks ``(centres,
    rows)`` read there (the distances recomputed, the search's bits), the others searched:
    at 1e-3 spacing of noise the anchors' rows of 320 held nearly every point, and the graph
    widened to 320 searched them all again (0.8 s CPU of a 100k estimate). Empties ``kept``."""
    n = len(nb.points)
    idx = np.empty((n, k), dtype=nb.take(1)[0].dtype)
    dist = np.empty((n, k))
    todo = np.ones(n, dtype=bool)
    while kept:
        got, rows = kept.pop(0)
        pos = np.flatnonzero(todo[got])
        rows_with_distances(nb.points, rows, pos, got[pos], idx, dist)
        todo[got] = False
    rest = np.flatnonzero(todo)
    step = max(1, _SEARCHED // k)
    for start in range(0, len(rest), step):
        c = rest[start:start + step]
        idx[c], dist[c] = nb.rows(c, k)
    return idx, dist


def _positions(centres, got):
    """``(at, pos)``: the entries ``at`` of ``centres`` that are in ``got`` (both without
    repeats), at ``got[pos]``."""
    slot, found = _found(got, centres, np.argsort(got, kind="stable"))
    at = np.flatnonzero(found)
    return at, slot[at]


def _found(keys, c, order=None):
    """``(slot, found)``: for each of ``c``, an index into ``keys`` (sorted, or sorted by the
    permutation ``order``) and whether ``keys[slot]`` is that value."""
    if not len(keys):
        return np.zeros(len(c), dtype=np.int64), np.zeros(len(c), dtype=bool)
    slot = np.minimum(np.searchsorted(keys, c, sorter=order), len(keys) - 1)
    if order is not None:
        slot = order[slot]
    return slot, keys[slot] == c


def held_h(nb, kc):
    """(N,): the distance to each point's ``kc``-th neighbour where ``nb`` holds it, else to
    the last neighbour held (a lower bound, > 0 as the exact one is: duplicates are merged before)."""
    dist = nb.take(min(nb.width, int(kc.max())))[1]
    return dist[np.arange(len(kc)), np.minimum(kc, dist.shape[1]) - 1].copy()


class _Rows:
    """The neighbours of a chunk of centres ``c`` (``self[c]``), as wide as the most any of
    them uses (``kc``): the ``held`` columns, and for the centres of each of the ``blocks``
    ``(centres, rows)`` (centres sorted) their rows searched wider: the first block by
    :func:`rows_at_least`, one more per :meth:`ensure` that searched any (a new block, never
    a copy of the others: at 1M points the first holds 365 MB, and joining 12 rows to it
    took 730 MB more). Columns a centre does not use hold the centre itself (the fits read
    a centre's first kc only)."""

    __slots__ = ("held", "blocks", "kc", "nb")

    def __init__(self, held, wide, w_idx, kc, nb):
        self.held, self.blocks, self.kc, self.nb = np.ascontiguousarray(held), [(wide, w_idx)], kc, nb

    def ensure(self, c, h) -> None:
        """Search the wider rows of centres ``c`` not held yet, and write their ``h``."""
        c = np.unique(c[(self.kc[c] > self.held.shape[1]) & (self._slots(c)[0] < 0)])  # a block's centres are sorted
        if len(c):
            self.blocks.append((c, _wide_rows(self.nb, c, self.blocks[0][1].shape[1], self.kc, h)))

    def parts(self, c):
        """The rows of centres ``c`` without a copy where they are held: ``(array, rows,
        centres)`` per part, row ``rows[r]`` of ``array`` listing the neighbours of
        ``centres[r]`` (its first ``kc`` columns: what the fits read): the held columns
        where they suffice, the rows of each block for its centres, and a copy
        (:meth:`__getitem__`) for any other (a centre fitted before its rows were searched)."""
        short = self.kc[c] <= self.held.shape[1]
        block, pos = self._slots(c)
        out = [(self.held, c[short], c[short])]
        for b, (_, rows) in enumerate(self.blocks):
            mine = ~short & (block == b)
            out.append((rows, pos[mine], c[mine]))
        rest = ~short & (block < 0)
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
        block, pos = self._slots(c)
        for b, (_, rows) in enumerate(self.blocks):
            mine = np.flatnonzero(block == b)
            idx[mine] = rows[pos[mine], :k]
        return idx

    def _slots(self, c):
        """``(block, pos)``: each centre's block and its row there (block -1: none)."""
        block = np.full(len(c), -1)
        pos = np.zeros(len(c), dtype=np.int64)
        for b, (centres, _) in enumerate(self.blocks):
            at, found = _found(centres, c)
            mine = found & (block < 0)
            block[mine], pos[mine] = b, at[mine]
        return block, pos
