"""Compiled loop of :mod:`core.border` (numba, ``nogil``)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import BLOCK
from ._base import OPTS as _OPTS
from .algebra import tangent_pair


@njit(**_OPTS)
def tangent_extent(points, normals, idx, n_dirs, gap, reach, start, bounded=False):
    """Per point, from its neighbours projected on its tangent plane:

    - ``gap``: the largest angle between consecutive neighbour directions (radians);
      with ``bounded``, where no quarter turn of the circle is empty (no run of
      :data:`EMPTY_RUN` empty sectors of :data:`SECTORS`), :data:`GAP_BOUND` instead, a
      bound the gap lies below (no angles taken: the verdict of a gap test of 120 degrees
      is the same, see :func:`_sector`);
    - ``reach``: the smallest, over ``n_dirs`` directions u, of the farthest neighbour
      offset along u, divided by the farthest neighbour distance: ~1 inside a surface, and
      at most d / r at distance d from a border (nothing lies beyond it).
    NaN where the point has no normal or no distinct neighbour. Row r of ``idx``, ``gap`` and
    ``reach`` is point ``start + r`` (a step of the whole cloud's rows).
    """
    tangent_extent_at(points, normals, idx, np.arange(start, start + idx.shape[0]), n_dirs, gap, reach, bounded)


@njit(**_OPTS, parallel=True)
def tangent_extent_at(points, normals, idx, centres, n_dirs, gap, reach, bounded=False):
    """:func:`tangent_extent` of the points ``centres`` (M,), row r of ``idx`` holding the
    neighbours of ``centres[r]``."""
    n, k = idx.shape
    dirs = _directions(n_dirs)  # the same directions for every point: computed once
    for blk in prange((n + BLOCK - 1) // BLOCK):
        scratch = np.empty((3, k))  # xs, ys, angles: once per block, not per point
        far = np.empty(n_dirs)
        for i in range(blk * BLOCK, min(n, (blk + 1) * BLOCK)):
            _extent(points, normals, idx, i, centres[i], dirs, scratch, far, gap, reach, bounded)


#: sectors of the circle a neighbour direction falls in (:func:`_sector`), 22.5 degrees each
SECTORS = 16
#: an empty arc wider than (EMPTY_RUN + 1) sectors holds EMPTY_RUN whole sectors: with none
#: of 4 sectors in a row empty, no gap between neighbours exceeds 5 x 22.5 = 112.5 degrees
EMPTY_RUN = 4
GAP_BOUND = (EMPTY_RUN + 1) * 2 * math.pi / SECTORS
_TAN = math.tan(math.pi / 8)  # the sectors' edges within a quadrant: 22.5 and 67.5 degrees


@njit(**_OPTS)
def _directions(n_dirs):
    """(2, n_dirs): the x and y rows of unit vectors evenly around the circle (contiguous rows:
    the reach loop over them is vectorised)."""
    dirs = np.empty((2, n_dirs))
    for d in range(n_dirs):
        dirs[0, d], dirs[1, d] = math.cos(2 * math.pi * d / n_dirs), math.sin(2 * math.pi * d / n_dirs)
    return dirs


@njit(**_OPTS)
def _sector(x, y):
    """The sector (0..15, in order around the circle) of the direction (x, y), by comparisons
    only: the quadrant by the signs, then within it the edges at 22.5, 45 and 67.5 degrees
    (their rounding moves an edge by ~1e-16 radians, against the 7.5 degrees the bound of
    :data:`GAP_BOUND` leaves below the test's 120)."""
    ax, ay = abs(x), abs(y)
    s = int(ay >= _TAN * ax) + int(ay >= ax) + int(ay * _TAN >= ax)  # each implies the one before (tan < 1)
    below, left = int(y < 0.0), int(x < 0.0)
    turned = below ^ left  # quadrants 1 and 3 (of 0..3, counter-clockwise) are read from their far edge
    return 4 * (2 * below + turned) + s + turned * (3 - 2 * s)  # without branches: the sectors come at random


@njit(**_OPTS)
def _quarter_empty(occupied):
    """Whether the 16-bit mask ``occupied`` of sectors leaves :data:`EMPTY_RUN` in a row
    empty, around the circle."""
    e = ~occupied & 0xFFFF
    e |= e << SECTORS  # runs across sector 15 -> 0
    run = e
    for s in range(1, EMPTY_RUN):
        run &= e >> s
    return (run & 0xFFFF) != 0


@njit(**_OPTS)
def _extent(points, normals, idx, i, p, dirs, scratch, far, gap, reach, bounded):
    """:func:`tangent_extent` at point ``p``, row ``i``."""
    gap[i] = math.nan
    reach[i] = math.nan
    nx, ny, nz = normals[p, 0], normals[p, 1], normals[p, 2]
    if not (math.isfinite(nx) and math.isfinite(ny) and math.isfinite(nz)):
        return
    t1x, t1y, t1z, t2x, t2y, t2z = tangent_pair(nx, ny, nz)
    xs, ys, ang = scratch[0], scratch[1], scratch[2]
    m = 0
    r = 0.0
    occupied = 0
    for c in range(idx.shape[1]):
        j = idx[i, c]
        dx = points[j, 0] - points[p, 0]
        dy = points[j, 1] - points[p, 1]
        dz = points[j, 2] - points[p, 2]
        x = dx * t1x + dy * t1y + dz * t1z
        y = dx * t2x + dy * t2y + dz * t2z
        rr = math.sqrt(x * x + y * y)
        if rr == 0.0:
            continue
        xs[m], ys[m] = x, y
        occupied |= 1 << _sector(x, y)
        r = max(r, rr)
        m += 1
    if m == 0:
        return
    gap[i] = GAP_BOUND if bounded and not _quarter_empty(occupied) else _widest_gap(xs, ys, ang, m)
    far[:] = 0.0  # the point itself is at the origin; directions innermost: independent maxima (vectorised)
    ux, uy = dirs[0], dirs[1]
    for c in range(m):
        x, y = xs[c], ys[c]
        for d in range(len(ux)):
            far[d] = max(far[d], x * ux[d] + y * uy[d])
    low = math.inf
    for d in range(len(ux)):
        low = min(low, far[d])
    reach[i] = low / r


@njit(**_OPTS)
def _widest_gap(xs, ys, ang, m):
    """The widest angle between consecutive directions of the m offsets (xs, ys)."""
    a = ang[:m]
    for c in range(m):
        a[c] = math.atan2(ys[c], xs[c])
    _sort_small(a)
    g = a[0] + 2 * math.pi - a[m - 1]
    for c in range(1, m):
        g = max(g, a[c] - a[c - 1])
    return g


@njit(**_OPTS)
def _sort_small(a):
    """``a.sort()`` by insertion: the same sorted values (a float's place in a sorted array is
    unique, +-0 aside, whose gaps are the same), 0.8 -> 0.55 us on 30 angles where numba's
    quicksort spent a third of the border test."""
    for c in range(1, len(a)):
        v = a[c]
        e = c - 1
        while e >= 0 and a[e] > v:
            a[e + 1] = a[e]
            e -= 1
        a[e + 1] = v
