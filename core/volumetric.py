"""Points that lie on no surface at any scale: a volume of points (foliage, hair, fur, smoke,
rain or dust clutter, the inside of a volumetric scan), flagged invalid by :func:`core.stages.flags`.

At each size k of the ladder :data:`core.tuning.JET_KS` the test reads the share of the smallest
eigenvalue in the scatter of a point's k nearest, lambda_0 / (lambda_0 + lambda_1 + lambda_2): about
1/3 in a volume at every k (a ball), noise^2 / (noise^2 + r^2 / 2) on a surface, which falls as the
neighbourhood's radius r grows until the curvature takes over, and small on a curved object's small
neighbourhoods. A rung "sees a surface" where the share is below :data:`SURFACE_SHARE`; a point is
volumetric where no rung does at most of its nearest (a vote, :data:`CONSENSUS`). The rungs are read smallest first and a point leaves as soon as one
sees a surface: on a clean or mildly noisy surface the 15 nearest already do (the cheap test that
most points of most clouds stop at), so the wider searches are made for the rest only.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .components import pair_components
from .kernels.surface_share import sees_surface
from .tuning import JET_KS

#: per rung of :data:`core.tuning.JET_KS`: the share below which the rung sees a surface, from
#: the shares of 151k points of uniform cubes and balls and Gaussian blobs of 1k-50k points (three
#: seeds, their boundaries included). At 15, the cheap test most points stop at, their 0.1 %
#: quantile (a clean surface reads 0.000-0.002, one at 0.2 spacing of noise 0.016). At 20-56 about
#: the smallest share of any of them (their 1e-5 quantile): a volume's k nearest are few there
#: and their shares spread (median 0.17 at 15). At 80-320, where surfaces at 1 spacing of noise
#: are seen (median 0.018-0.06 at 160-320, plane to torus) and a volume's shares are tight
#: (median 0.28), their 0.3 % quantile
SURFACE_SHARE = (0.041, 0.036, 0.048, 0.064, 0.072, 0.111, 0.114, 0.117, 0.119, 0.120)
#: a point is volumetric where no rung sees a surface at :data:`CONSENSUS` of its
#: :data:`CONSENSUS_K` nearest (itself included), read at those points and at their neighbours:
#: a volume is a region. Alone, the rungs missed 1 % of a uniform cube and 6 % of a ball in
#: their outermost layer (one spacing deep), which the vote adds; and they flagged a cube's
#: corners, alike at every scale (three faces), and a small object touching the ground (a sphere
#: of radius 3 spacings 0.6 spacing above a plane): 35 and 68 points in groups of a few, which
#: it removes (the 15 nearest at 0.5 kept 17 and 52)
CONSENSUS = 0.7
CONSENSUS_K = 80
#: the fewest points a volume's region holds: as many as the widest rung's neighbourhood
#: (:func:`_regions_of_a_volume`)
MIN_VOLUME = 320
#: the rungs read on one fetch of rows (the widest of each; the narrower are their first columns)
FETCHES = ((15,), (20, 28, 40), (56, 80), (113, 160), (226, 320))


def volumetric(points, nb) -> np.ndarray:
    """(N,) bool: the points most of whose :data:`CONSENSUS_K` nearest no neighbourhood of the
    ladder shows a surface at (see the module), on the neighbours ``nb`` (a :class:`core.Neighbours`
    on ``points``) and, past its ``k_max``, a search of their own for the points still undecided."""
    n = len(points)
    search = _Rows(points, nb)
    seen = np.zeros(n, dtype=bool)
    seen[_unseen(points, search)] = True
    out = np.zeros(n, dtype=bool)
    if not seen.any():
        return out
    at = np.flatnonzero(seen)
    rows = search(at, min(CONSENSUS_K, n))
    near = np.setdiff1d(rows, at)  # unseen points' neighbours that a rung saw a surface at: a volume's chance
    at, rows = np.concatenate([at, near]), np.vstack([rows, search(near, rows.shape[1])]) if len(near) else rows
    out[at] = seen[rows].mean(axis=1) >= CONSENSUS
    return _regions_of_a_volume(out, search)


def _regions_of_a_volume(flagged, search) -> np.ndarray:
    """``flagged`` where its points join (among their 15 nearest) in groups of at least
    :data:`MIN_VOLUME` points: a small closed object (a sphere of 16-150 points) is enclosed by
    the wider rungs' neighbourhoods and reads as a volume at all of them, as a volume's points
    do; fewer points than the widest rungs hold cannot tell the two apart."""
    at = np.flatnonzero(flagged)
    if len(at) < MIN_VOLUME:
        return np.zeros_like(flagged)
    rows = search(at, min(JET_KS[0], len(flagged)))
    place = np.full(len(flagged), -1, dtype=np.int64)
    place[at] = np.arange(len(at))
    inside = place[rows] >= 0
    src = np.repeat(np.arange(len(at)), rows.shape[1])[inside.ravel()]
    label = pair_components(len(at), src, place[rows][inside])
    out = np.zeros_like(flagged)
    out[at] = np.bincount(label)[label] >= MIN_VOLUME
    return out


def _unseen(points, search) -> np.ndarray:
    """The points at which no rung of the ladder sees a surface (none on fewer points than its first)."""
    n = len(points)
    threshold = dict(zip(JET_KS, SURFACE_SHARE))
    todo = np.arange(n) if n >= JET_KS[0] else np.arange(0)
    for ks in FETCHES:
        ks = [k for k in ks if k <= n]
        if not (ks and len(todo)):
            break
        idx = search(todo, ks[-1])
        for k in ks:
            surface = np.empty(len(todo), dtype=bool)
            sees_surface(points, todo, idx[:, :k], threshold[k], surface)
            todo, idx = todo[~surface], idx[~surface]
    return todo


class _Rows:
    """The ``k`` nearest of some points: from the neighbours ``nb`` up to their ``k_max`` (all
    points: their columns as they are), past it from a search of its own."""

    def __init__(self, points, nb):
        self.points, self.nb, self.tree = points, nb, None

    def __call__(self, centres, k):
        if k <= self.nb.k_max:
            return self.nb.take_indices(k) if len(centres) == len(self.points) else self.nb.rows(centres, k)[0]
        if self.tree is None:  # unbalanced, uncompacted: built 2x faster, queried as exactly
            self.tree = cKDTree(self.points, balanced_tree=False, compact_nodes=False)
        return self.tree.query(self.points[centres], k=k, workers=-1)[1]
