"""What the 3D view needs to know about a cloud's shape, computed off the GUI thread.

Framing a 1M-point cloud needs its bounding box, its point spacing (a KD-tree query)
and the extreme points along 13 directions; drawing it within a point budget needs a
random drawing order, and its glyphs within theirs evenly spread positions. Together ~1 s
of numpy on 1M points: :class:`CloudGeometry`
computes them once per cloud on the loader thread (:meth:`app.source.CloudSource.geometry`),
and the GUI thread only reads them. Indices, not coordinates, so one geometry serves
the noisy copies of the same cloud too (noise moves points by a fraction of the spacing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.degenerate import MAX_COORD

from .framing import FIT_SAMPLE, cloud_spacing
from .glyphs import even_order

__all__ = ["CloudGeometry"]

#: Extreme points along these directions bound the cloud's projection in any view.
_DIRECTIONS = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, -1, 0], [1, 0, 1], [1, 0, -1],
                        [0, 1, 1], [0, 1, -1], [1, 1, 1], [1, 1, -1], [1, -1, 1], [-1, 1, 1]], dtype=float)


@dataclass(frozen=True, eq=False)
class CloudGeometry:
    """Frozen facts about one cloud's points (all indices into its rows).

    Attributes
    ----------
    n_points : int
    centre : (3,) centre of the bounding box of the drawable points: finite, and within
        ``core.degenerate.MAX_COORD`` (a coordinate of 1e300 would put the camera at
        infinity; core does not estimate such a cloud either, and says why).
    radius : float, half the box diagonal (1.0 for an empty or single-point cloud).
    spacing : float, mean distance to the 3rd neighbour (:func:`app.framing.cloud_spacing`).
    fit_index : indices of the points whose projection bounds the cloud's
        (extremes along 13 directions plus a random subset, :data:`app.framing.FIT_SAMPLE`).
    order : a random permutation of the finite points' indices: any prefix is a uniform
        random subset, so the moving stand-in (a short prefix) is part of the still
        frame's budget (a longer one), and the points do not jump between the two.
    glyph_order : the glyph positions: at most :data:`app.glyphs.GLYPH_POINTS` indices
        spread evenly over the cloud, any prefix evenly too (:func:`app.glyphs.even_order`);
        a glyph density is a fraction of them.
    """

    n_points: int
    centre: np.ndarray
    radius: float
    spacing: float
    fit_index: np.ndarray
    order: np.ndarray
    glyph_order: np.ndarray

    @classmethod
    def of(cls, points: np.ndarray, *, seed: int = 0) -> "CloudGeometry":
        """Compute the geometry of ``points`` ((N, 3); rows with NaN/inf or a coordinate beyond
        ``MAX_COORD`` are left out: not framed, not drawn)."""
        points = np.asarray(points, dtype=float)
        with np.errstate(invalid="ignore"):
            finite = (np.abs(points) <= MAX_COORD).all(axis=1)  # False for NaN too
        index = np.flatnonzero(finite) if not finite.all() else np.arange(len(points))
        pts = points[index] if len(index) < len(points) else points
        if len(pts) == 0:
            empty = np.zeros(0, dtype=np.intp)
            return cls(len(points), np.zeros(3), 1.0, 0.0, empty, empty, empty)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        radius = 0.5 * float(np.linalg.norm(hi - lo)) or 1.0
        rng = np.random.default_rng(seed)
        if len(pts) <= FIT_SAMPLE:
            fit = index
        else:
            proj = pts @ _DIRECTIONS.T
            extremes = np.r_[proj.argmin(axis=0), proj.argmax(axis=0)]
            fit = index[np.unique(np.r_[extremes, rng.choice(len(pts), size=FIT_SAMPLE, replace=False)])]
        order = index[rng.permutation(len(index))]
        return cls(len(points), 0.5 * (lo + hi), radius, cloud_spacing(pts), fit, order, even_order(points, order))

    def subset(self, budget: int) -> np.ndarray:
        """Sorted indices of at most ``budget`` points, a uniform random subset (all if fewer)."""
        if len(self.order) <= budget and len(self.order) == self.n_points:
            return np.arange(self.n_points)
        return np.sort(self.order[: int(budget)])
