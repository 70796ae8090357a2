"""The off-surface score: how far a point lies from the robust planes of its neighbourhood.

:func:`core.kernels.outlier_scores` measures a point against the least-squares plane of its
neighbours, in units of their spread about it. Points a few spacings off a surface escape
it when other outliers are among those neighbours (they tilt the plane and widen the
spread) or when the neighbours form a wide disc on a curved surface (its sag is spread too).
Here each row's plane is Tukey-weighted, so the surface points decide it and its scale is
theirs, and a point is measured against the planes of its own row and of each of its
neighbours' rows: it is off the surface when even the nearer of those planes (a lower
quantile, so a point beside an edge, explained by the planes on its own face, stays in)
leave it many of their scales away.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS
from .algebra import add_outer, smallest_eigvec_sym3
from .network import SHORT, sorted_short
from .pool import linear_quantile, selected_quantile
from .robust import MAD_SIGMA, TUKEY_C, root_median, selected_root_median

@njit(**OPTS)
def _root_median(a, m):
    """:func:`core.kernels.robust.root_median` of a[:m], by :func:`core.kernels.network.sorted_short`
    where it is short (its values hold no NaN: squares of finite offsets, a row's scales)."""
    if m > SHORT:
        return root_median(a, m)
    sorted_short(a, m)
    return selected_root_median(a, m)


@njit(**OPTS)
def _quantile(a, m, q):
    """:func:`core.kernels.pool.linear_quantile` of a[:m], by :func:`core.kernels.network.sorted_short`
    where it is short (its values hold no NaN: distances of finite points over positive units)."""
    if m > SHORT:
        return linear_quantile(a, m, q)
    sorted_short(a, m)
    return selected_quantile(a, m, q)


@njit(**OPTS, parallel=True)
def robust_planes(points, idx, floor, reweightings, standout, planes):
    """``planes[i]`` = (cx, cy, cz, nx, ny, nz, scale, floor term): the plane of the
    neighbours ``idx[i, 1:]`` (the point itself left out), their MAD scale about it
    (x 1.4826) and ``floor`` x their mean distance to its centre (its unit is the sum);
    NaN where the neighbours span no plane. Where a neighbour lies more than ``standout``
    units off the least-squares plane, the plane is reweighted ``reweightings`` times by
    Tukey's weights of the distances to it (elsewhere no neighbour stands out and it is kept).

    Numpy reference: w = 1; repeat: c = sum(w p) / sum(w), n = smallest eigenvector of
    sum(w (p - c)(p - c)^T), r = (p - c).n, unit = 1.4826 median|r| + floor mean|p - c|,
    w = (1 - (r / (4.685 unit))^2)^2 where |r| < 4.685 unit, else 0.
    """
    n, k = idx.shape
    for b in prange((n + BLOCK - 1) // BLOCK):
        rows = np.empty((k, 3))
        w, r, a = np.empty(k), np.empty(k), np.empty(k)
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            for c in range(8):
                planes[i, c] = math.nan
            if k - 1 < 3 or idx[i, 1:].min() < 0:  # (a short row: no plane)
                continue
            for j in range(1, k):  # the row about point i, gathered once
                q = idx[i, j]
                for c in range(3):
                    rows[j, c] = points[q, c] - points[i, c]
                w[j] = 1.0
            for it in range(reweightings + 1):
                worst = _weighted_plane(rows, w, r, a, floor, planes[i])
                unit = planes[i, 6] + planes[i, 7]
                if it == reweightings or not unit > 0.0 or (it == 0 and worst <= standout * unit):
                    break
                for j in range(1, k):
                    u = r[j] / (TUKEY_C * unit)
                    t = max(0.0, 1.0 - u * u)
                    w[j] = t * t
            for c in range(3):
                planes[i, c] += points[i, c]


@njit(**OPTS)
def _weighted_plane(rows, w, r, a, floor, out):
    """The w-weighted plane of rows[1:] into ``out`` (centre, normal, unit; left as it
    was if it has none), the distances to it into r[1:]; returns the largest."""
    k = rows.shape[0]
    sw = cx = cy = cz = 0.0
    for j in range(1, k):
        sw += w[j]
        cx += w[j] * rows[j, 0]
        cy += w[j] * rows[j, 1]
        cz += w[j] * rows[j, 2]
    if not sw > 0.0:
        return 0.0
    cx, cy, cz = cx / sw, cy / sw, cz / sw
    c00 = c01 = c02 = c11 = c12 = c22 = 0.0
    for j in range(1, k):
        c00, c01, c02, c11, c12, c22 = add_outer(c00, c01, c02, c11, c12, c22, w[j], rows[j, 0] - cx,
                                                 rows[j, 1] - cy, rows[j, 2] - cz)
    _, _, _, nx, ny, nz = smallest_eigvec_sym3(c00, c01, c02, c11, c12, c22)
    if not math.isfinite(nx):
        return 0.0
    spread = worst = 0.0
    for j in range(1, k):
        dx, dy, dz = rows[j, 0] - cx, rows[j, 1] - cy, rows[j, 2] - cz
        r[j] = dx * nx + dy * ny + dz * nz
        a[j - 1] = r[j] * r[j]
        worst = max(worst, abs(r[j]))
        spread += math.sqrt(dx * dx + dy * dy + dz * dz)
    out[0], out[1], out[2], out[3], out[4], out[5] = cx, cy, cz, nx, ny, nz
    out[6], out[7] = MAD_SIGMA * _root_median(a, k - 1), floor * spread / (k - 1)
    return worst


@njit(**OPTS, parallel=True)
def pooled_units(idx, planes, units):
    """``units[i]``: the median of the scales of the rows ``idx[i, 1:]`` (those with a
    plane) plus row i's floor term; NaN where row i has no plane. A row's own MAD scale
    rests on 14 residuals: its neighbours' median is steadier and, since their planes
    leave the point out of most of them, not widened by an outlier among them."""
    n, k = idx.shape
    for b in prange((n + BLOCK - 1) // BLOCK):
        a = np.empty(k)
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            m = 0
            for j in range(1, k):
                q = idx[i, j]
                if q >= 0 and math.isfinite(planes[q, 6]):
                    a[m] = planes[q, 6] * planes[q, 6]
                    m += 1
            units[i] = _root_median(a, m) + planes[i, 7] if m and math.isfinite(planes[i, 7]) else math.nan


@njit(**OPTS, parallel=True)
def off_planes(points, idx, planes, units, quantile, out):
    """``out[i]``: the ``quantile`` (linear, as numpy's) of the distances of point i from
    the planes of the rows ``idx[i, :]`` (its own first, then its neighbours'), each in
    that row's unit (:func:`pooled_units`); planes that are NaN are left out (NaN when all
    are), a unit of 0 gives 0 on the plane and inf off it."""
    n, k = idx.shape
    for b in prange((n + BLOCK - 1) // BLOCK):
        d = np.empty(k)
        for i in range(b * BLOCK, min(n, (b + 1) * BLOCK)):
            m = 0
            for j in range(k):
                q = idx[i, j]
                if q < 0 or not (math.isfinite(planes[q, 3]) and math.isfinite(units[q])):
                    continue
                dist = abs((points[i, 0] - planes[q, 0]) * planes[q, 3] + (points[i, 1] - planes[q, 1]) * planes[q, 4]
                           + (points[i, 2] - planes[q, 2]) * planes[q, 5])
                unit = units[q]
                d[m] = dist / unit if unit > 0.0 else (0.0 if dist == 0.0 else math.inf)
                m += 1
            out[i] = _quantile(d, m, quantile) if m else math.nan
