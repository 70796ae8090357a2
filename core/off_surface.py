"""The off-surface score of the outlier flags (:func:`core.stages.outlier_scores`): the distance of
a point from the robust planes of its own and its neighbours' rows (:mod:`core.kernels.off_planes`).

A point a few spacings off a surface escapes the least-squares plane of its neighbours when other
outliers are among them or when, on a coarse curved surface, they form a wide disc whose sag
widens the spread; these planes are Tukey-weighted and their scales pooled, so it does not.
"""

from __future__ import annotations

import numpy as np

from .kernels.off_planes import off_planes, pooled_units, robust_planes
from .tuning import OUTLIER_FLOOR

#: the score is this quantile of a point's distances from the 15 planes of its own and its
#: neighbours' rows: the 4th-5th nearest must leave it off, so a point beside an edge or on a
#: thin part's rim, which the planes on its own side explain, is not flagged (the nearest plane
#: alone let 8 of 14 points 1-2 spacings off a 5000-point saddle through; the median flagged
#: points beside a cube's edges)
QUANTILE = 0.25
#: Tukey reweightings of a row's plane where a neighbour lies more than STANDOUT units off the
#: least-squares one (elsewhere it is kept: every row of a clean noise-free cloud, 87 % at 0.2
#: spacing of noise); at 2.3 units (half Tukey's cut-off) least-squares planes an outlier had
#: pulled towards itself passed, and 3 % outliers on a saddle grew its K error 21 %, not 3 %
REWEIGHTINGS = 3
STANDOUT = 1.5


def off_surface(pts, idx) -> np.ndarray:
    """(N,) the off-surface score on the rows ``idx`` (each point first): the :data:`QUANTILE`
    of its distances from the Tukey-weighted planes of its own row and its neighbours' rows,
    each in that row's unit (the median of its neighbours' scales plus the floor term of
    :data:`core.tuning.OUTLIER_FLOOR`)."""
    idx = np.ascontiguousarray(idx)
    planes, units, out = np.empty((len(pts), 8)), np.empty(len(pts)), np.empty(len(pts))
    robust_planes(pts, idx, OUTLIER_FLOOR, REWEIGHTINGS, STANDOUT, planes)
    pooled_units(idx, planes, units)
    off_planes(pts, idx, planes, units, QUANTILE, out)
    return out
