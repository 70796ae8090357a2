"""Border points: where the surface sampled by a cloud ends (scan rims, holes, silhouettes).

A point inside a sampled surface has neighbours all around it in its tangent plane; a
border point has an empty side. Two readings of the neighbours projected on the tangent
plane flag it:

- the **angular gap**, the widest angle between consecutive neighbour directions (the
  classic test of PCL's boundary estimation): a point on a straight rim sees about 180
  degrees empty. Random sampling alone leaves gaps of 80-100 degrees inside a surface at
  30 neighbours, so only a wide gap counts (:data:`GAP`);
- the **reach**, the smallest over directions u of the farthest neighbour offset along u,
  in units of the neighbourhood radius: about 1 inside, at most d / r at a distance d from
  a border, since nothing lies beyond it. This catches the points a spacing or so inside
  the rim, whose gap the neighbours between them and the rim have already closed.

A flagged point is read again on a wider neighbourhood (:func:`read_again`): a void of random
sampling closes there, a rim does not; where the 30 nearest lie along one scan line, on
neighbourhoods that reach across the lines.
"""

from __future__ import annotations

import numpy as np

from . import plane_spread
from .duplicates import find_duplicates
from .kernels import border as kern
from ._validate import as_points
from .wide_neighbours import search_in_spatial_order
from .tuning import THIN_SPREAD

#: neighbours per point for the test (the point itself included). With 30 the disc of
#: neighbours reaches ~3.1 spacings, so that a point 1 spacing from a rim has a clear
#: empty side while the chance that random sampling leaves one inside is ~1e-3
#: (measured: tests/core/test_border.py, random planes, noise 0 and 0.2 spacing).
BORDER_K = 30
#: wider neighbourhoods of the test where the BORDER_K nearest lie along one scan line (:func:`across_lines`)
WIDE_KS = (60, 120, 240, 320)
#: ... judged by a plane spread (core.plane_spread) of the BORDER_K nearest below this: a scan
#: line with range noise spreads to 0.10-0.15 (a rotating LiDAR's ring 5-10 m out), the fit's
#: THIN_SPREAD (0.1) left those flagged; the half disc of a straight rim spreads ~0.53, so a
#: uniformly sampled rim is not read again (reading it again would not clear it: a wider
#: neighbourhood of a rim keeps its empty side)
LINE_SPREAD = 0.3
#: the neighbours a flagged point whose BORDER_K nearest span the plane is read again on (every
#: 2nd of them: the disc keeps its shape and density); it stays a border only if that test flags
#: it too (:func:`confirmed`). A random sampling's own voids flagged 0.5 % of every clean closed
#: surface (torus, sphere, ellipsoid at 20k points: grey specks in the viewer); a point within
#: 1.3 spacings of a rim (what the test at 30 flags) is within 0.3 radius of the 60's and stays
CONFIRM_K = 60
#: ... with the reach below this (the gap as :data:`GAP`). Measured on planes of 20k points with
#: round holes (seeds 3, 4): REACH (0.42) cleared 0.50 -> 0.01 % of the interior points but kept
#: 64 % of those within a spacing of a hole of radius 4 spacings (90 % before); 0.55 clears to
#: 0.03 % and keeps 77 % (97 % of those within half a spacing); 0.6: 0.08 %, 85 %. A hole of
#: radius 2 spacings is not told from the sampling's voids at 60 (52 % of its rim flagged at 30)
CONFIRM_REACH = 0.55
#: rows per step of the border test (bounds its int64 copy of the graph)
_ROWS = 131_072
#: flag when the widest empty angle between neighbour directions exceeds this (degrees);
#: at 30 random neighbours an interior gap this wide has a probability of ~2e-4
GAP = 120.0
#: flag when the reach (see module doc) is below this: 1 spacing / 3.1 spacings plus room
#: for noise of 0.2 spacing; interior points measured at >= 0.6 (1st percentile)
REACH = 0.42
#: directions over which the reach is the minimum (every 11.25 degrees)
N_DIRS = 32


def border_flags(points, normals, idx):
    """Flag border points from their neighbours in the tangent plane.

    Parameters
    ----------
    points : (N, 3) float array.
    normals : (N, 3) unit normals (sign irrelevant), NaN rows where there is none.
    idx : (N, K) int neighbour indices, the point first; the first :data:`BORDER_K`
        columns are used.

    Returns
    -------
    border : (N,) bool, False where there is no normal.
    gap : (N,) widest empty angle (degrees), NaN where there is no normal.
    reach : (N,) float, see the module doc, NaN where there is no normal.
    """
    gap, reach = _extents(points, normals, idx, bounded=False)
    gap = np.degrees(gap)
    return _flagged(gap, reach), gap, reach


def _border_flags(points, normals, idx):
    """:func:`border_flags`' verdict alone, the same: the widest gap is measured only where a
    quarter turn around the point holds no neighbour; elsewhere it lies below 112.5 degrees,
    under :data:`GAP` (:data:`core.kernels.border.GAP_BOUND`). The 30 angles taken and sorted
    per point were most of the test: 0.24 -> 0.06 s CPU on a 100k torus."""
    gap, reach = _extents(points, normals, idx, bounded=True)
    return _flagged(np.degrees(gap), reach)


def _extents(points, normals, idx, *, bounded):
    """(gap (radians), reach) of :func:`core.kernels.border.tangent_extent` on the first
    :data:`BORDER_K` columns of ``idx``."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    nrm = np.ascontiguousarray(normals, dtype=np.float64)
    graph = np.asarray(idx)[:, :BORDER_K]  # a view: the kernel reads the columns in place
    gap = np.empty(len(pts))
    reach = np.empty(len(pts))
    for start in range(0, len(graph), _ROWS):  # int64 by steps: the whole graph's copy was 240 MB at 1M points
        rows = slice(start, start + _ROWS)
        kern.tangent_extent(pts, nrm, graph[rows].astype(np.int64, copy=False), N_DIRS, gap[rows], reach[rows], start,
                            bounded)
    return gap, reach


def _flagged(gap_deg, reach, reach_below=REACH):
    """The test's verdict: a gap over :data:`GAP` degrees or a reach below ``reach_below``
    (False where there is no normal: NaN)."""
    with np.errstate(invalid="ignore"):
        return (gap_deg > GAP) | (reach < reach_below)


def border_of(points, normals, nb):
    """:func:`border_flags` with :data:`BORDER_K` neighbours from ``nb`` (a
    :class:`core.Neighbours`), or from a search of their own when ``nb`` holds fewer than
    :data:`CONFIRM_K` (or is None);
    read again across scan lines (:func:`across_lines`) where ``nb`` reaches that far."""
    k = min(BORDER_K, len(points))
    if served_by(nb, len(points)):
        return read_again(points, normals, nb, _border_flags(points, normals, nb.take_indices(k)))
    # e.g. an integer k < 60: one more search (30 columns held, 60 for the flagged rows). In spatial
    # order (the same rows as build_neighbours, 5x faster at 100k points); each point's test
    # reads only its own row, so the flags are the same
    pts, _ = as_points(points)
    merged = find_duplicates(pts)
    if merged is not None:  # copies are one place (core.duplicates): judged there, on its distinct neighbours
        return border_of(merged.points, np.asarray(normals)[merged.first], None)[merged.inverse]
    own, order = search_in_spatial_order(pts, min(CONFIRM_K, len(pts)), width=k)  # wider rows: flagged points only
    if order is None:  # large groups of identical points: searched in the caller's order
        return read_again(pts, normals, own, _border_flags(pts, normals, own.take(k)[0]))
    border = np.empty(len(pts), dtype=bool)
    nrm = np.asarray(normals)[order]
    border[order] = read_again(own.points, nrm, own, _border_flags(own.points, nrm, own.take(k)[0]))
    return border


def read_again(points, normals, nb, border):
    """``border`` read again on wider neighbourhoods of ``nb`` where it is flagged: across scan
    lines where the :data:`BORDER_K` nearest lie along one (:func:`across_lines`), else on
    :data:`CONFIRM_K` (:func:`confirmed`)."""
    todo = np.flatnonzero(border)
    if not len(todo):
        return border
    nrm = np.ascontiguousarray(normals, dtype=np.float64)
    k = min(BORDER_K, len(points))  # as border_of: a cloud of fewer points reads all of them
    spans = plane_spread.spans_plane(points, nrm, nb, np.full(len(todo), k), LINE_SPREAD, todo)
    border = border.copy()
    confirmed(points, nrm, nb, border, todo[spans])
    return across_lines(points, nrm, nb, border, todo[~spans])


def confirmed(points, normals, nb, border, at):
    """``border[at]`` kept only where the test on every 2nd of the :data:`CONFIRM_K` nearest
    flags it too, with :data:`CONFIRM_REACH` (in place; ``nb`` serves that many: :func:`served_by`,
    or :func:`border_of`'s own search; nothing on a cloud of fewer than 2 x BORDER_K points)."""
    k = min(CONFIRM_K, len(points))
    if not len(at) or k < 2 * BORDER_K:
        return
    border[at] = _flags_at(points, normals, np.ascontiguousarray(nb.rows(at, k)[0][:, ::2], dtype=np.int64), at,
                           CONFIRM_REACH)


def _flags_at(points, normals, idx, at, reach_below=REACH):
    """The test's flags at the points ``at`` with ``idx`` (m, K) their neighbours' rows (a reach
    below ``reach_below`` flags)."""
    gap, reach = np.empty(len(at)), np.empty(len(at))
    kern.tangent_extent_at(np.ascontiguousarray(points, dtype=np.float64), normals, idx, at, N_DIRS, gap, reach, True)
    return _flagged(np.degrees(gap), reach, reach_below)


def across_lines(points, normals, nb, border, thin):
    """``border`` (changed in place, returned) read again at the flagged points ``thin``, whose
    :data:`BORDER_K` nearest lie along one line (plane spread below :data:`LINE_SPREAD`,
    :mod:`core.plane_spread`): on each of :data:`WIDE_KS` (up to what ``nb`` serves) whose neighbours span the tangent
    plane, every s-th of them (sorted by distance: the disc keeps its shape) so that about
    2 x BORDER_K are read; the point is a border only if every one of them leaves an empty
    side (unevenly spaced lines are reached on the nearer side first: the 120 nearest on a
    LiDAR's ground span the plane with one neighbouring ring, the 240 with both). Scan
    lines farther apart than the 30 nearest reach (a rotating LiDAR's rings 15-50 points
    apart) left every point with an empty side: all of its ground 5-40 m out was flagged."""
    for k in (c for c in WIDE_KS if c <= min(nb.k_max, len(points))):
        if not len(thin):
            break
        at = thin[~(plane_spread.spreads(points, normals, nb, k, thin) < THIN_SPREAD)]
        if len(at):
            border[at] = _flags_at(points, normals, np.ascontiguousarray(
                nb.rows(at, k)[0][:, ::max(k // (2 * BORDER_K), 1)], dtype=np.int64), at)
            thin = thin[border[thin]]
    return border


def served_by(nb, n_points: int) -> bool:
    """Whether the neighbours ``nb`` (or None) serve the test, its reading again on
    :data:`CONFIRM_K` included, without a search of its own (so that the flags do not depend
    on the graph the caller has)."""
    return nb is not None and nb.k_max >= min(CONFIRM_K, n_points)


def border_of_valid(points, normals, valid, nb):
    """:func:`border_of` judged on the valid points' normals; False where not valid (what
    :attr:`core.CurvatureResult.border` holds)."""
    if not valid.any():
        return np.zeros(len(points), dtype=bool)
    return valid & border_of(points, np.where(valid[:, None], normals, np.nan), nb)
