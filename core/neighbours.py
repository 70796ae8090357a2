"""k-nearest-neighbour search, done once and reused (Open3D-style: *which neighbours*
is kept apart from *which estimator*)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ._progress import Progress
from ._validate import as_points, check_int
from .spacing import mean_spacing

_CHUNK = 200_000
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
    """

    points: np.ndarray
    indices: np.ndarray
    distances: np.ndarray

    @property
    def k_max(self) -> int:
        return self.indices.shape[1]

    def take(self, k: int):
        """Indices and distances of the ``k`` nearest (views, no copy)."""
        self._check_k(k)
        return self.indices[:, :k], self.distances[:, :k]

    def take_without(self, k: int, drop: np.ndarray):
        """The ``k`` nearest not flagged in ``drop`` (N,) bool, each point itself first;
        a row short of unflagged neighbours ends with its nearest flagged ones (copies)."""
        self._check_k(k)
        n = len(self.indices)
        idx = np.empty((n, k), dtype=self.indices.dtype)
        dist = np.empty((n, k), dtype=self.distances.dtype)
        for start in range(0, n, _ROWS):
            rows = slice(start, min(n, start + _ROWS))
            flagged = drop[self.indices[rows]]
            flagged[:, 0] = False
            order = np.argsort(flagged, axis=1, kind="stable")[:, :k]
            idx[rows] = np.take_along_axis(self.indices[rows], order, axis=1)
            dist[rows] = np.take_along_axis(self.distances[rows], order, axis=1)
        return idx, dist

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


def build_neighbours(points, k_max: int, *, progress=None) -> Neighbours:
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
    k_max = check_int(k_max, name="k_max", low=1, high=len(pts))
    report = Progress(progress)
    report(0.0, "neighbours")
    tree = cKDTree(pts)
    n = len(pts)
    idx = np.empty((n, k_max), dtype=np.int64 if n > 2**31 - 1 else np.int32)
    dist = np.empty((n, k_max), dtype=np.float64)
    for start in range(0, n, _CHUNK):
        stop = min(n, start + _CHUNK)
        d, i = tree.query(pts[start:stop], k=k_max, workers=-1)
        dist[start:stop] = np.reshape(d, (stop - start, k_max))
        idx[start:stop] = np.reshape(i, (stop - start, k_max))
        report(stop / n, "neighbours")
    _self_first(idx, dist)
    idx.setflags(write=False)
    dist.setflags(write=False)
    return Neighbours(points=pts, indices=idx, distances=dist)


def _self_first(idx: np.ndarray, dist: np.ndarray) -> None:
    """Duplicate points can tie with the point itself; put the point first."""
    rows = np.arange(len(idx))
    wrong = idx[:, 0] != rows
    if not wrong.any():
        return
    for r in np.flatnonzero(wrong):
        pos = np.flatnonzero(idx[r] == r)
        if len(pos):
            j = pos[0]
            idx[r, 1 : j + 1] = idx[r, 0:j].copy()
        else:  # more than k_max exact duplicates: the point was not returned at all
            idx[r, 1:] = idx[r, :-1].copy()
            dist[r, 1:] = dist[r, :-1].copy()
        idx[r, 0] = r
        dist[r, 0] = 0.0
