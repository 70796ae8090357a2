"""Clumps that are small objects, not copies of one place.

:mod:`core.clumps` tells stacked frames by a gap in each point's sorted distances that most of
its clump's points see alike. A small object far from the rest (a ball of 50-255 points, a
bolt, a pebble: fewer points than the clump search's widest reach) shows the same gap: 112
points of a sphere 3 spacings in radius, then the next object 4 radii away, a surprise of
112 log 2 = 78. A cloud made mostly of such objects was merged into one place per object:
with 27 spheres in a grid every point came back valid with H ~ 0 instead of 1 and normals at
random (median |cos| 0.5), with 2-8 of them the estimate raised (k exceeds the distinct
positions), in a row they were all invalid.

Copies of a place are scattered by noise: a blob (the frames' jitter) or a segment along the
view ray. An object's points lie on its surface: the 9 nearest of each span a plane, their
smallest covariance eigenvalue far below the middle one (median lambda3 / lambda2 on a sphere
of 50 / 113 / 255 points 0.09 / 0.04 / 0.02, 0.09-0.18 at 0.2 spacing of noise; Gaussian blobs
of 20-300 copies 0.38-0.48; a segment has lambda2 ~ 0, and a segment with lateral jitter
0.37-0.51). A clump of at least :data:`SURFACE_MIN_POINTS` points most of whose points see a
plane so is an object and keeps its points, if it is not flat as a whole (its own smallest
covariance eigenvalue at least :data:`SURFACE_FLAT` of the middle one: a sphere or a box ~1):
copies jittered across the view ray only lie on a disc, locally flat too (20-50 copies at 0.05
spacing of a sphere's 2000 places: merged before, H error 0.036; read as objects by the local
test alone, H error 1.0). Flat or shallow small objects (a coin, a leaf, a small torus whose
tube is thin against its ring) are therefore still merged as before.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from . import kernels

#: a clump is told only from this many points (fewer: a 12-point sphere's neighbourhoods are
#: as round as a blob's, lambda3 / lambda2 0.51 / 0.26)
SURFACE_MIN_POINTS = 20
#: the nearest (the point included) whose covariance tells a plane
SURFACE_NEAREST = 9
#: ... a plane: lambda3 / lambda2 below this (spheres <= 0.18 noisy, blobs >= 0.38) ...
SURFACE_FLAT = 0.2
#: ... and lambda2 / lambda1 above this (a segment along a view ray is no plane: ~0)
SURFACE_WIDE = 0.1


def object_clumps(points: np.ndarray, label: np.ndarray, nearest: np.ndarray | None = None) -> np.ndarray:
    """The points whose clump (``label`` (N,), -1 outside any clump) holds at least
    :data:`SURFACE_MIN_POINTS` points, most of them with nearest that span a plane (see the
    module): small objects, not copies of one place. ``nearest`` (N, m): each point's nearest
    in order, the point first (the clump search's rows, :func:`core.clumps._agreed_clumps`);
    searched here if None or narrower than :data:`SURFACE_NEAREST` (and the cloud wider)."""
    ids, at, size = np.unique(label, return_inverse=True, return_counts=True)
    at = at.ravel()
    tested = (ids[at] >= 0) & (size[at] >= SURFACE_MIN_POINTS)
    out = np.zeros(len(points), dtype=bool)
    if not tested.any():
        return out
    rows = np.flatnonzero(tested)
    k = min(SURFACE_NEAREST, len(points))
    if nearest is not None and nearest.shape[1] >= k:
        idx = nearest[rows, :k]
    else:
        idx = cKDTree(points).query(points[rows], k=k, workers=-1)[1].astype(np.int32)
    flat, line = scatter_shapes(points, idx)
    plane = (flat < np.sqrt(SURFACE_FLAT)) & (line > np.sqrt(SURFACE_WIDE))
    votes = np.bincount(at[rows], weights=plane.astype(float), minlength=len(ids))
    surface = (2.0 * votes > size) & bent(points[rows], at[rows], len(ids))
    out[rows] = surface[at[rows]]
    return out


def scatter_shapes(points, rows) -> tuple[np.ndarray, np.ndarray]:
    """``(flat, line)`` (M,) of each row of ``points[rows]`` ((M, k) int32 indices): sqrt(l0 / l1)
    and sqrt(l1 / l2) of the eigenvalues l0 <= l1 <= l2 of their scatter about its centroid, NaN
    where degenerate (:func:`core.kernels.spread.scatter_shapes`), which the thresholds above
    compare squared: lambda3 < SURFACE_FLAT lambda2 is flat < sqrt(SURFACE_FLAT)."""
    rows = np.ascontiguousarray(rows)
    flat, line = np.empty(len(rows)), np.empty(len(rows))
    kernels.scatter_shapes(np.ascontiguousarray(points, dtype=np.float64), rows, flat, line)
    return flat, line


def bent(points, group, count, flat=SURFACE_FLAT):
    """Whether each of ``count`` groups of ``points`` (``group`` (M,)) is thick as a whole,
    its smallest covariance eigenvalue at least ``flat`` (:data:`SURFACE_FLAT`) of its middle one: a
    surface that bends round (a sphere ~1, a cube ~1), not a flat patch (a coin, a leaf; or
    copies jittered across the view ray only, a disc, which a flat test alone takes for an object)."""
    size = np.maximum(np.bincount(group, minlength=count), 1).astype(float)
    mean = np.stack([np.bincount(group, weights=c, minlength=count) for c in points.T], axis=1) / size[:, None]
    d = points - mean[group]
    cov = np.stack([np.bincount(group, weights=d[:, i] * d[:, j], minlength=count)
                    for i in range(3) for j in range(3)], axis=1).reshape(count, 3, 3)
    low, mid, _ = np.linalg.eigvalsh(cov).T
    return low >= flat * mid
