"""The mean point spacing: the length unit of relative noise, glyphs and outlier distances."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ._validate import as_points


def mean_spacing(points, *, neighbours=None, sample=None, seed=0) -> float:
    """Mean distance from each point to its nearest other point.

    Parameters
    ----------
    points : (N, 3) array_like, N >= 2.
    neighbours : :class:`core.Neighbours`, optional, built on ``points`` with
        ``k_max >= 2``: its cached distances are used instead of a new search.
    sample : int, optional. Average over this many points drawn at random (seeded by
        ``seed``) instead of all: a quick estimate for a large cloud.

    Raises
    ------
    ValueError
        With fewer than 2 points, or neighbours with ``k_max < 2``.
    """
    if neighbours is not None:
        if neighbours.k_max < 2:
            raise ValueError(f"mean spacing needs neighbours with k_max >= 2, got k_max={neighbours.k_max}")
        return float(np.mean(neighbours.take(2)[1][:, 1]))  # take: a graph that searches on demand holds these
    pts, _ = as_points(points)
    n = len(pts)
    if n < 2:
        raise ValueError(f"mean spacing needs at least 2 points, got {n}")
    query = pts
    if sample is not None and sample < n:
        query = pts[np.random.default_rng(seed).choice(n, size=sample, replace=False)]
    d, _ = cKDTree(pts).query(query, k=2, workers=-1)
    return float(np.mean(d[:, 1]))
