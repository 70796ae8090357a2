"""The plain nearest, served from the own-sheet graph (k="auto", :mod:`core.one_sheet`).

Where a point's row lists its own sheet first, the fits read that graph and the orientation,
the sign checks, the border flags and the result read the plain nearest. Both graphs held
side by side were 480 MB more at 1M points of two sheets (2.4 GB peak): the plain rows are
a permutation of the reordered ones, so :class:`PlainNeighbours` keeps that permutation
(a byte per column of a reordered row up to 256 columns) and serves the plain rows from the
own-sheet graph; once the fits are done, :meth:`PlainNeighbours.release` turns that graph
into the plain one in place.
"""

from __future__ import annotations

import threading

import numpy as np

from .neighbours import Neighbours

#: reordered rows put back per step (bounds the temporary arrays)
_CHUNK = 65_536


class PlainNeighbours(Neighbours):
    """The plain nearest neighbours of the points of ``fit`` (a graph some of whose rows list
    the point's own sheet first): the rows of the points ``centres`` (M,) are read from
    ``fit``'s whole row through ``plain`` (M, k_max) unsigned ints, the column of ``fit``'s
    row that is the plain row's j-th; the other rows are ``fit``'s. ``whole(centres)`` gives those
    whole rows of ``fit``; ``slot`` (N,) is each point's row of ``plain`` (-1: none)."""

    served_in_place = False  # its rows are copies

    def __init__(self, fit, centres, plain, slot, whole):
        for name, value in dict(_fit=fit, _centres=centres, _plain=plain, _slot=slot, _whole=whole,
                                _made=None, _lock=threading.Lock()).items():
            object.__setattr__(self, name, value)

    def __reduce__(self):  # pickled (and copied) as the whole graph
        return Neighbours, (self.points, self.indices, self.distances)

    def __repr__(self) -> str:
        return f"PlainNeighbours(n={len(self.points)}, k_max={self.k_max}, reordered={len(self._centres)})"

    @property
    def points(self) -> np.ndarray:
        return self._fit.points

    @property
    def k_max(self) -> int:
        return self._fit.k_max

    @property
    def width(self) -> int:
        return self._fit.width

    @property
    def indices(self) -> np.ndarray:
        return self._graph()[0]

    @property
    def distances(self) -> np.ndarray:
        return self._graph()[1]

    def _graph(self):
        with self._lock:
            if self._made is None:
                self._fit.widen()
                made = self.take(self.k_max)
                for a in made:
                    a.setflags(write=False)
                object.__setattr__(self, "_made", made)
        return self._made

    def _held(self):
        return self.take(self.width)

    def widen(self, k: int | None = None, *, progress=None):
        self._fit.widen(k, progress=progress)
        return self._held()

    def take(self, k: int):
        """The ``k`` nearest of every point (copies)."""
        return self._taken(k, distances=True)

    def take_indices(self, k: int) -> np.ndarray:
        """The indices of :meth:`take` alone (the orientation, the sign checks and the border
        flags read no distance: 8 of the 12 bytes per entry not copied)."""
        return self._taken(k, distances=False)[0]

    def _taken(self, k, *, distances):
        self._check_k(k)
        idx, dist = self._fit.take(k)
        idx, dist = np.array(idx), np.array(dist) if distances else None
        self._put_back(idx, dist, np.arange(len(self._centres)), self._centres)
        return idx, dist

    def rows(self, centres: np.ndarray, k: int):
        self._check_k(k)
        idx, dist = (np.array(a) for a in self._fit.rows(centres, k))
        found = self._slot[np.asarray(centres)]
        at = np.flatnonzero(found >= 0)
        self._put_back(idx, dist, found[at], at)
        return idx, dist

    def _put_back(self, idx, dist, mine, at) -> None:
        """Rows ``at`` of ``idx`` and ``dist`` (None: not wanted): the plain rows ``mine`` (rows of ``plain``)."""
        if self._plain is None:  # released: ``fit`` holds the plain rows
            return
        k = idx.shape[1]
        for start in range(0, len(mine), _CHUNK):
            part, to = mine[start:start + _CHUNK], at[start:start + _CHUNK]
            whole_idx, whole_dist = self._whole(self._centres[part])
            cols = self._plain[part, :k].astype(np.intp)
            idx[to] = np.take_along_axis(whole_idx, cols, axis=1)
            if dist is not None:
                dist[to] = np.take_along_axis(whole_dist, cols, axis=1)

    def release(self):
        """The plain graph made in place of the fits' one once they are done (``fit`` is then
        the plain nearest and must not be fitted on again), where ``fit`` holds every
        column (its arrays are :func:`core.one_sheet.graphs`' own copies or searches): the
        permutation and the copies of the rows served are then no longer needed. Otherwise self."""
        fit = self._fit
        if fit.width < fit.k_max:
            return self
        idx, dist = fit.widen()
        for a in (idx, dist):
            a.setflags(write=True)
        for start in range(0, len(self._centres), _CHUNK):
            part = slice(start, start + _CHUNK)
            rows, cols = self._centres[part], self._plain[part].astype(np.intp)
            idx[rows] = np.take_along_axis(idx[rows], cols, axis=1)
            dist[rows] = np.take_along_axis(dist[rows], cols, axis=1)
        for a in (idx, dist):
            a.setflags(write=False)
        object.__setattr__(self, "_plain", None)  # this view now serves ``fit`` as it is
        return fit
