"""Gauss-Bonnet on a point cloud: per-point areas and the total curvature, integral of K dA.

For a closed surface the Gauss-Bonnet theorem gives  integral of K dA = 2 pi chi, with chi the
Euler characteristic (sphere 2, torus 0): a check of an estimate that a student can read.
Each point's area is its Voronoi cell among its neighbours, projected on its tangent plane
(the cells of a well-sampled surface tile it, so their sum is its area).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit, prange
from scipy.spatial import cKDTree

from ._progress import Progress
from ._validate import as_normals, as_points, check_int, check_result
from .duplicates import find_duplicates

#: neighbours around each point whose bisectors bound its cell. Random (Poisson) samples have
#: 6 Voronoi neighbours on average, but a cell can be cut by a far one: against scipy's exact
#: Voronoi of 3000 random points, 16 neighbours overestimate the total area by 1.8 %, 24 by
#: 0.06 %, 32 by 0.001 % and 40 are exact (worst cell 1e-11).
VORONOI_NEIGHBOURS = 40
#: points per call of the cell kernel (progress and cancel are checked between calls)
_CHUNK = 16_384
#: a point whose neighbours leave an empty angular sector wider than this is on a boundary
#: (120 degrees: interior points of random samples have gaps below 90 degrees, measured on the
#: plane sample; boundary points see a half-plane, 180).
BOUNDARY_GAP = np.deg2rad(120.0)


@dataclass(frozen=True, eq=False)
class GaussBonnet:
    """Total curvature of a cloud.

    Attributes
    ----------
    total : float, sum of K_i A_i over the valid points (integral of K dA); NaN without any.
    chi : float, total / (2 pi); an integer (2 - 2 genus) for a closed surface.
    area : float, the sum of the per-point areas.
    areas : (N,) per-point areas (Voronoi cells in the tangent plane).
    boundary : (N,) bool, points on a boundary of the cloud (an open surface).
    closed : bool, no boundary point: chi is meaningful.
    n_invalid : int, points without a curvature (left out of ``total``, their area kept).
    """

    total: float
    chi: float
    area: float
    areas: np.ndarray
    boundary: np.ndarray
    closed: bool
    n_invalid: int


@njit(cache=True, nogil=True)
def _cell_area(q):
    """Area of {x : |x| <= |x - q_j| for all j} (q: (m, 2) offsets), clipped to a square of
    half-size max |q_j| (a bounded cell for boundary points). Sutherland-Hodgman clipping."""
    half = 0.0
    for j in range(q.shape[0]):
        half = max(half, np.sqrt(q[j, 0] ** 2 + q[j, 1] ** 2))
    poly = np.empty((4 + q.shape[0], 2))
    poly[0, 0], poly[0, 1] = -half, -half
    poly[1, 0], poly[1, 1] = half, -half
    poly[2, 0], poly[2, 1] = half, half
    poly[3, 0], poly[3, 1] = -half, half
    n = 4
    out = np.empty_like(poly)
    for j in range(q.shape[0]):
        a, b = q[j, 0], q[j, 1]
        c = 0.5 * (a * a + b * b)  # half-plane a x + b y <= c
        if c <= 0.0:
            continue
        m = 0
        for i in range(n):
            x0, y0 = poly[i, 0], poly[i, 1]
            x1, y1 = poly[(i + 1) % n, 0], poly[(i + 1) % n, 1]
            s0, s1 = a * x0 + b * y0 - c, a * x1 + b * y1 - c
            if s0 <= 0.0:
                out[m, 0], out[m, 1] = x0, y0
                m += 1
            if (s0 < 0.0) != (s1 < 0.0) and s0 != s1:
                t = s0 / (s0 - s1)
                out[m, 0], out[m, 1] = x0 + t * (x1 - x0), y0 + t * (y1 - y0)
                m += 1
        poly[:m] = out[:m]
        n = m
        if n < 3:
            return 0.0
    area = 0.0
    for i in range(n):
        area += poly[i, 0] * poly[(i + 1) % n, 1] - poly[(i + 1) % n, 0] * poly[i, 1]
    return 0.5 * abs(area)


@njit(cache=True, nogil=True, parallel=True)
def _areas_kernel(points, normals, idx, gap_limit, areas, boundary, start, stop):
    for i in prange(start, stop):
        nrm = normals[i]
        t1 = np.array([1.0, 0.0, 0.0]) if abs(nrm[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        t1 = t1 - nrm * np.dot(t1, nrm)
        t1 /= np.linalg.norm(t1)
        t2 = np.cross(nrm, t1)
        m = idx.shape[1] - 1
        q = np.empty((m, 2))
        ang = np.empty(m)
        for j in range(m):
            d = points[idx[i, j + 1]] - points[i]
            q[j, 0], q[j, 1] = np.dot(d, t1), np.dot(d, t2)
            ang[j] = np.arctan2(q[j, 1], q[j, 0])
        areas[i] = _cell_area(q)
        ang.sort()
        gap = ang[0] + 2 * np.pi - ang[m - 1]
        for j in range(m - 1):
            gap = max(gap, ang[j + 1] - ang[j])
        boundary[i] = gap > gap_limit


def point_areas(points, normals, *, k: int = VORONOI_NEIGHBOURS, progress=None):
    """Per-point areas: each point's Voronoi cell among its ``k`` nearest neighbours, in its
    tangent plane.

    Parameters
    ----------
    points, normals : (N, 3) arrays (normals need not be oriented).
    k : int, neighbours per cell (>= 4).
    progress : callable(fraction, stage) -> None | False, optional; returning False cancels
        (:class:`core.Cancelled`), as in :func:`core.estimate`.

    Returns
    -------
    areas : (N,) float array.
    boundary : (N,) bool, points with an empty angular sector wider than 120 degrees around
        them (the boundary of an open surface); their cells are clipped to their neighbours'
        extent.
    Copies of one point share its cell's area equally (all points at one place: no area).
    """
    pts, _ = as_points(points)
    nrm = as_normals(normals, len(pts))
    k = check_int(k, name="k", low=4)
    merged = find_duplicates(pts)  # copies of a point (a cloud stored twice) share its one cell
    if merged is not None and len(merged.first) == 1:  # one place: no cell, no area (no curvature either)
        return np.zeros(len(pts)), np.ones(len(pts), dtype=bool)
    if merged is not None:
        counts = np.bincount(merged.inverse)
        areas, boundary = point_areas(merged.points, nrm[merged.first], k=k, progress=progress)
        return areas[merged.inverse] / counts[merged.inverse], boundary[merged.inverse]
    if len(pts) < k + 1:
        raise ValueError(f"points: point_areas needs more than k={k} distinct points, got {len(pts)}")
    report = Progress(progress)
    _, idx = cKDTree(pts).query(pts, k=k + 1, workers=-1)
    idx = idx.astype(np.int64)
    areas = np.empty(len(pts))
    boundary = np.zeros(len(pts), dtype=bool)
    for start in range(0, len(pts), _CHUNK):  # chunks: a cancel is seen within a fraction of a second
        report(start / len(pts), "point areas")
        _areas_kernel(pts, nrm, idx, BOUNDARY_GAP, areas, boundary, start, min(start + _CHUNK, len(pts)))
    if boundary.any() and not boundary.all():
        # a boundary cell is open on one side: give it the median area of its interior
        # neighbours (the local density) instead of an arbitrary clip
        near = idx[boundary, 1:9]
        local = np.where(boundary[near], np.nan, areas[near])
        fallback = np.nanmedian(np.where(np.isnan(local).all(axis=1)[:, None], np.median(areas[~boundary]), local), axis=1)
        areas[boundary] = fallback
    return areas, boundary


def gauss_bonnet(res, *, k: int = VORONOI_NEIGHBOURS, progress=None) -> GaussBonnet:
    """Total curvature of a :class:`core.CurvatureResult`, integral of K dA, and chi
    (``progress``: as :func:`point_areas`').

    Examples
    --------
    >>> import core
    >>> sample = core.shapes.sphere(2000, seed=1)
    >>> res = core.estimate(sample.points, sample.normals, k=20)
    >>> round(core.gauss_bonnet(res).chi, 1)
    2.0
    """
    normals = np.where(np.isfinite(check_result(res).normals), res.normals, [[0.0, 0.0, 1.0]])
    areas, boundary = point_areas(res.points, normals, k=k, progress=progress)
    K = res.gaussian
    ok = res.valid & np.isfinite(K)
    total = float(np.sum(K[ok] * areas[ok])) if ok.any() else math.nan  # nothing to integrate: not 0
    return GaussBonnet(total=total, chi=total / (2 * np.pi), area=float(areas.sum()),
                       areas=areas, boundary=boundary, closed=not bool(boundary.any()),
                       n_invalid=int(np.count_nonzero(~ok)))


def total_curvature(res, *, k: int = VORONOI_NEIGHBOURS) -> float:
    """The integral of the Gaussian curvature over the cloud, sum of K_i A_i (a float).

    2 pi chi for a closed surface (Gauss-Bonnet): 4 pi on a sphere, 0 on a torus. The
    per-point areas come from :func:`point_areas` (or :func:`gauss_bonnet`). NaN when no
    point is valid (its ``n_invalid`` counts them).
    """
    return gauss_bonnet(res, k=k).total
