"""The points of an estimate in spatial order inside, the caller's order outside.

:func:`core.estimate` runs its stages on the points permuted into the kd-tree's leaf
order (:func:`core.neighbours.search_in_spatial_order`): the loops over neighbours then
read memory that the previous point already brought into cache (NR at k = 15 on 1M
shuffled points: half the CPU time). Every result goes back to the caller's order here. Each
point's numbers do not change: its neighbours come in the same order, and whatever
depends on the order of the points (ties between equal distances, the order of equally
strong edges in :mod:`core.orientation`) follows the caller's index,
:attr:`SpatialOrder.order`.
"""

from __future__ import annotations

import numpy as np

from .kernels.permute import move_rows, relabel_rows
from .neighbours import Neighbours, leaf_order
from .wide_neighbours import LazyNeighbours

#: neighbour arrays up to this size are reordered into new arrays (on all cores); larger
#: ones (k = "auto": 56 neighbours at 1M points, 670 MB) in place, one cycle at a time,
#: so that the peak memory does not grow by their size
COPY_BYTES = 256 * 2**20


class SpatialOrder:
    """A permutation of N points: sorted point s is the caller's point ``order[s]``.

    ``SpatialOrder(None)`` is the identity (nothing is copied either way).
    """

    def __init__(self, order: np.ndarray | None):
        self.order = order
        self._inverse = None

    def to_sorted(self, a):
        """Per-point array ``a`` (caller's order, or None) in the sorted order."""
        return a if a is None or self.order is None else a[self.order]

    def to_caller(self, obj):
        """``obj`` with every per-point array (leading dimension N) in the caller's order;
        tuples and named tuples are converted field by field, anything else is kept."""
        if self.order is None:
            return obj
        if isinstance(obj, tuple):
            fields = [self.to_caller(f) for f in obj]
            return type(obj)(*fields) if hasattr(obj, "_fields") else tuple(fields)
        if isinstance(obj, np.ndarray) and obj.ndim >= 1 and len(obj) == len(self.order):
            return self._scatter(obj)
        return obj

    @property
    def inverse(self) -> np.ndarray:
        """Where each caller's point sits in the sorted order (``order``'s inverse; computed once)."""
        if self._inverse is None:
            self._inverse = np.empty_like(self.order)
            self._inverse[self.order] = np.arange(len(self.order), dtype=self.order.dtype)
        return self._inverse

    def _scatter(self, a):
        # a gather by the inverse permutation: numpy's take, single-threaded, beats a parallel
        # kernel on the ~20 small per-point arrays of a result (no thread start per array)
        return np.take(a, self.inverse, axis=0)

    def neighbours_to_caller(self, nb: Neighbours, points: np.ndarray, *, in_place=True) -> Neighbours:
        """``nb`` (found on the sorted points) as neighbours of ``points``, the caller's;
        large arrays are reordered in place (``nb`` must not be used afterwards) unless
        ``in_place`` is False (a :class:`core.stage_cache.StageCache` keeps ``nb``)."""
        if self.order is None:
            return nb
        idx, dist = nb.indices, nb.distances
        if idx.nbytes + dist.nbytes <= COPY_BYTES or not in_place:
            idx, dist = np.empty_like(nb.indices), np.empty_like(nb.distances)
            relabel_rows(nb.indices, nb.distances, self.order, idx, dist)
        else:
            idx.setflags(write=True)
            dist.setflags(write=True)
            rows = 65_536
            for start in range(0, len(idx), rows):  # sorted indices -> the caller's
                idx[start:start + rows] = self.order[idx[start:start + rows]]
            move_rows(idx, self.order)
            move_rows(dist, self.order)
        idx.setflags(write=False)
        dist.setflags(write=False)
        return Neighbours(points=points, indices=idx, distances=dist)


def given_in_spatial_order(pts: np.ndarray, nb: Neighbours) -> tuple[Neighbours, SpatialOrder]:
    """A caller's graph ``nb`` on ``pts`` (checked) as the stages read it best: on the points
    in spatial order, as :func:`core.estimate` searches its own. A result's graph still
    held in that order (:class:`core.wide_neighbours.LazyNeighbours`) is used as it is; a
    plain graph up to :data:`COPY_BYTES` is copied into the kd-tree's leaf order
    (:func:`core.kernels.kd_order.kd_order`, 20 ms at 100k points: on shuffled points the
    stages after it ran 1.5-2x slower in the caller's order, the re-decided signs 7x).
    Larger or other graphs stay in the caller's order. The answer is the same either way
    (see the module's docstring)."""
    held = nb.spatial() if isinstance(nb, LazyNeighbours) else None
    if held is not None:
        return held[0], SpatialOrder(held[1])
    if type(nb) is not Neighbours or nb.indices.nbytes + nb.distances.nbytes > COPY_BYTES:
        return nb, SpatialOrder(None)
    sorted_order, sorted_pts = leaf_order(pts, nb.indices.dtype)
    order = SpatialOrder(sorted_order)
    idx, dist = np.empty_like(nb.indices), np.empty_like(nb.distances)  # its inverse serves the results too
    relabel_rows(np.ascontiguousarray(nb.indices), np.ascontiguousarray(nb.distances), order.inverse, idx, dist)
    idx.setflags(write=False)
    dist.setflags(write=False)
    return Neighbours(points=sorted_pts, indices=idx, distances=dist), order
