"""Tiles sized by point count: a k-d split of a sample of the cloud, saved with the run.

Each split halves the number of tiles along the longest side of the box at the quantile
of the sample that gives both halves their share of points, so dense and sparse regions
get tiles of about the same number of points (an octree-like adaptivity without empty
tiles). The outermost faces of the outer tiles are infinite: every point, even one
outside the sample's bounds, falls in exactly one tile.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: points kept for the split (every n-th point of the file): quantiles of 200k points
#: place a split within ~0.2 % of the intended share
SAMPLE = 200_000


@dataclass(frozen=True)
class TilePlan:
    """The tiles of a run.

    Attributes
    ----------
    lo, hi : (T, 3) box corners; -inf / +inf on the cloud's outer faces.
    axis, value, left, right : the split tree (internal nodes; a child < 0 is leaf ``~child``).
    bounds : (2, 3) the cloud's bounds (min, max) as sampled.
    n_points : points in the cloud.
    distinct : its distinct positions where the sample is the whole cloud, else ``n_points``
        (:func:`core.tiled.wholechecks.distinct_count`).
    """

    lo: np.ndarray
    hi: np.ndarray
    axis: np.ndarray
    value: np.ndarray
    left: np.ndarray
    right: np.ndarray
    bounds: np.ndarray
    n_points: int
    distinct: int = -1

    @property
    def n_tiles(self) -> int:
        return len(self.lo)

    def assign(self, points: np.ndarray) -> np.ndarray:
        """Tile id of each point (m,) by descending the split tree."""
        node = np.zeros(len(points), dtype=np.int64)
        tile = np.full(len(points), -1, dtype=np.int64)
        if len(self.axis) == 0:
            tile[:] = 0
            return tile
        active = np.arange(len(points))
        while len(active):
            nd = node[active]
            go_left = points[active, self.axis[nd]] < self.value[nd]
            child = np.where(go_left, self.left[nd], self.right[nd])
            leaf = child < 0
            tile[active[leaf]] = ~child[leaf]
            node[active[~leaf]] = child[~leaf]
            active = active[~leaf]
        return tile

    def touching(self, lo, hi) -> np.ndarray:
        """Ids of the tiles whose box meets the box [lo, hi]."""
        return np.flatnonzero(((self.lo <= hi) & (self.hi >= lo)).all(axis=1))

    def save(self, path) -> None:
        np.savez(path, lo=self.lo, hi=self.hi, axis=self.axis, value=self.value, left=self.left,
                 right=self.right, bounds=self.bounds, n_points=self.n_points, distinct=self.distinct)

    @classmethod
    def load(cls, path) -> "TilePlan":
        with np.load(path) as f:
            return cls(f["lo"], f["hi"], f["axis"], f["value"], f["left"], f["right"], f["bounds"],
                       int(f["n_points"]), int(f["distinct"]))


def make_plan(sample: np.ndarray, n_points: int, tile_points: int, distinct: int | None = None) -> TilePlan:
    """Split the space of ``sample`` (m, 3) into ceil(n_points / tile_points) tiles
    (``distinct``: the cloud's distinct positions, default ``n_points``).

    Examples
    --------
    >>> pts = np.random.default_rng(0).random((10_000, 3))
    >>> plan = make_plan(pts, 10_000, 2_500)
    >>> plan.n_tiles, np.bincount(plan.assign(pts)).tolist()
    (4, [2500, 2500, 2500, 2500])
    """
    if len(sample) == 0:
        raise ValueError("the cloud has no points to tile")
    n_tiles = max(1, -(-n_points // tile_points))
    n_tiles = min(n_tiles, max(1, len(sample) // 2))  # every tile keeps a share of the sample
    lo, hi, axis, value, left, right = [], [], [], [], [], []

    def split(rows, box_lo, box_hi, count):
        if count == 1:
            lo.append(box_lo)
            hi.append(box_hi)
            return ~(len(lo) - 1)
        pts = sample[rows]
        ax = int(np.argmax(pts.max(axis=0) - pts.min(axis=0)))
        n_left = count // 2
        cut = float(np.quantile(pts[:, ax], n_left / count))
        node = len(axis)
        axis.append(ax)
        value.append(cut)
        left.append(0)
        right.append(0)
        mid_hi, mid_lo = box_hi.copy(), box_lo.copy()
        mid_hi[ax] = mid_lo[ax] = cut
        below = pts[:, ax] < cut
        left[node] = split(rows[below], box_lo, mid_hi, n_left)
        right[node] = split(rows[~below], mid_lo, box_hi, count - n_left)
        return node

    split(np.arange(len(sample)), np.full(3, -np.inf), np.full(3, np.inf), n_tiles)
    bounds = np.stack([sample.min(axis=0), sample.max(axis=0)])
    return TilePlan(np.array(lo), np.array(hi), np.array(axis, dtype=np.int64), np.array(value, dtype=float),
                    np.array(left, dtype=np.int64), np.array(right, dtype=np.int64), bounds, int(n_points),
                    int(n_points if distinct is None else distinct))
