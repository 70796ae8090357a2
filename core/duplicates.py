"""Duplicate points: estimated once, at their place.

Merged scans, double exports and quantised coordinates put several points at one place.
Copies carry no geometry, but they fill a point's k nearest neighbours: with every point
of a 20k torus tripled, 15 neighbours are 5 places, a cubic jet (10 terms) on them is
underdetermined, and the default's H error went from 1e-4 to 4.2 (e1 35 degrees), with
every point reported valid; with every point doubled 1e-6 apart (float32 rounding of a
point written twice), 0.08. :func:`core.estimate` therefore estimates the places and gives
every copy its place's answer (:func:`expand`); ``params["duplicates"]`` counts the copies.
Exact copies are found before the search (:func:`find_duplicates`: a hash table of the
coordinates, :func:`core.kernels.repeats.any_repeated`, 25 ms at 1M points), near ones on
its graph (:func:`near_copies`), places of more near copies than a neighbourhood holds as
isolated balls (:func:`_isolated_clumps`), and clouds of clumps jittered 1e-3 to 0.1 of their
spacing (stacked frames) at the clumps' means (:mod:`core.clumps`). Given normals are the first copy's.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np
from scipy.spatial import cKDTree

from .clumps import screened, stacked_places
from .components import pair_components
from .kernels.repeats import any_repeated, coordinate_hashes
from .neighbours import Neighbours
from .tuning import NEAR_COPY, NEAR_COPY_SHARE

#: where a place may hold k copies or more, its copies are told on this many times k nearest
CLUMP_WIDER = 8
#: a clump's ball grows (3x) at most this many times before it is taken for sampling
CLUMP_GROWTH = 4

__all__ = ["Merged", "NearCopies", "find_duplicates", "near_copies", "expand", "CopiesNeighbours"]

class NearCopies(Exception):
    """Raised by :func:`core.estimate.prepare` (when asked) on finding :func:`near_copies`:
    :func:`core.estimate` then estimates their places."""

    def __init__(self, merged: "Merged"):
        super().__init__(f"{merged.copies} points lie on top of others")
        self.merged = merged


class Merged(NamedTuple):
    """The distinct positions of a cloud: ``points`` (M, 3) in the order of their first
    copy (a clump's mean, :mod:`core.clumps`), ``first`` (M,) the caller's index of that
    copy, ``inverse`` (N,) the distinct position of every caller's point."""

    points: np.ndarray
    first: np.ndarray
    inverse: np.ndarray

    @property
    def copies(self) -> int:
        """Points beyond the first at their position."""
        return len(self.inverse) - len(self.first)


def find_duplicates(pts: np.ndarray, *, cache=None) -> Merged | None:
    """The distinct positions of ``pts`` (N, 3) finite float64, or None when all differ;
    with a :class:`core.stage_cache.StageCache` the last cloud's are kept."""
    known = None if cache is None else cache.known_merge(pts)  # a viewer's cloud seen before
    if known is not None:
        return known
    if len(pts) < 2 or not any_repeated(coordinate_hashes(pts)):
        return None
    merged = _merge(pts)
    if cache is not None and merged is not None:
        cache.remember(pts, merged)
    return merged


def _merge(pts: np.ndarray) -> Merged | None:
    """:func:`find_duplicates` once the hashes repeat (None if only the hashes do)."""
    order = np.lexsort(pts.T[::-1])  # stable: each group's first entry is its first copy
    srt = pts[order]
    new = np.ones(len(pts), dtype=bool)
    np.any(srt[1:] != srt[:-1], axis=1, out=new[1:])
    if new.all():
        return None  # equal hashes of different points
    group = np.cumsum(new) - 1
    first_of_group = order[new]
    rank = np.argsort(first_of_group, kind="stable")  # groups in the order of their first copy
    position = np.empty_like(rank)
    position[rank] = np.arange(len(rank))
    inverse = np.empty(len(pts), dtype=np.int64)
    inverse[order] = position[group]
    first = first_of_group[rank]
    return Merged(pts[first], first, inverse)


def near_copies(idx: np.ndarray, dist: np.ndarray, points: np.ndarray, rank=None, *,
                spatial: bool = False) -> Merged | None:
    """Places of points nearer each other than :data:`core.tuning.NEAR_COPY` of their
    neighbourhood radius (the last column of ``dist``), from a kNN graph ``idx`` (N, k) of
    ``points`` (its point first), and places of more copies than the graph reaches
    (:func:`_isolated_clumps`); or None when there are none, or only twins of fewer than
    :data:`core.tuning.NEAR_COPY_SHARE` of the points (no place of three or more). Such
    points are connected into places; a place is its first point's (lowest ``rank``, the
    caller's index of each row, default the row) coordinates. A cloud of clumps (stacked
    frames, :mod:`core.clumps`) gives its clumps' means as places, its copy nearest the mean
    first; clumps of more copies than ``idx`` holds are screened for only where ``points``
    are in ``spatial`` order (rows beside a row are near it). ``first`` and ``inverse`` are
    in rows of ``points``."""
    if idx.shape[1] < 2:
        return None
    rank = np.arange(len(points)) if rank is None else np.asarray(rank)
    wide = screened(idx, points, spatial)  # a cloud of clumps (core.clumps), else copies within NEAR_COPY
    places = stacked_places(points, rank, wide) if wide else None
    return _near_places(idx, dist, points, rank) if places is None else Merged(*places)


def _near_places(idx, dist, points, rank) -> Merged | None:
    """:func:`near_copies` of copies within :data:`core.tuning.NEAR_COPY` of the radius."""
    span, k = _span(points), idx.shape[1]
    inside, wide, typical = _clumped(dist[:, -1], span)
    if wide:
        idx, dist = _wider(points, CLUMP_WIDER * idx.shape[1])
    close = dist[:, 1:] < NEAR_COPY * dist[:, -1:]
    # a copy lies within NEAR_COPY of the typical radius; where that measures nothing, of the
    # spacing of as many places as points on a surface across the cloud (below any surface's)
    largest = NEAR_COPY * (typical if typical > 0.0 else span / np.sqrt(len(points)))
    lead, members = _isolated_clumps(points, np.flatnonzero(inside & ~close[:, 0]), dist[:, -1], rank, largest)
    if typical == 0.0 and len(np.unique(lead)) < k:  # a few parts far apart: not places of one surface
        lead, members = lead[:0], members[:0]
    twins_only = not close[:, 1:].any() if close.shape[1] > 1 else True
    if len(lead) == 0 and twins_only and np.count_nonzero(close[:, 0]) < NEAR_COPY_SHARE * len(idx):
        return None  # distances ascend: the nearest tells
    rows, cols = np.nonzero(close)
    rows, cols = np.concatenate([rows, lead]), np.concatenate([idx[rows, cols + 1], members])
    return _places(rows, cols, points, rank)


def _places(rows, cols, points, rank) -> Merged:
    """The places of the pairs ``rows``-``cols`` of points on top of each other."""
    label = pair_components(len(points), rows, cols)
    by_rank = np.argsort(rank, kind="stable")
    _, at = np.unique(label[by_rank], return_index=True)  # each place's first point, places by label
    lead_rows = by_rank[at]
    places = np.argsort(rank[lead_rows], kind="stable")  # the places in the order of their first point
    place_of_label = np.empty(len(places), dtype=np.int64)
    place_of_label[places] = np.arange(len(places))
    first = lead_rows[places]
    return Merged(points[first], first, place_of_label[label])


def _isolated_clumps(points, rows, radius, rank, largest):
    """``(lead, members)`` pairs joining the points of each clump that holds more copies
    than its graph rows reach: ``rows`` are points none of whose neighbours is a near copy
    while their radius (``radius``) lies far below the cloud's. A clump is the ball around
    such a point that stops growing (the same count at 3x its radius), where no other point
    lies within 2 / NEAR_COPY of its extent, and whose extent is below ``largest``: its
    points are then copies as :func:`near_copies` joins them. 100 copies 1e-9 of a spacing
    apart in a 20k sphere gave |H| 6e9 at them and ruined 15 points around them, and 130
    copies of each of 200 places |H| 1e10, all reported valid."""
    lead, members = [np.empty(0, dtype=np.int64)], [np.empty(0, dtype=np.int64)]
    if len(rows) == 0:
        return lead[0], members[0]
    tree, taken = cKDTree(points), np.zeros(len(points), dtype=bool)
    for row in rows[np.argsort(rank[rows], kind="stable")]:
        if taken[row]:
            continue
        clump = _clump_of(tree, points[row], float(radius[row]), largest)
        if clump is not None:
            taken[clump] = True
            lead.append(np.full(len(clump), row, dtype=np.int64))
            members.append(clump)
    return np.concatenate(lead), np.concatenate(members)


def _clump_of(tree, centre, radius, largest):
    """The points of the isolated clump around ``centre`` (see :func:`_isolated_clumps`),
    or None when the ball around it keeps growing or has neighbours within 2 / NEAR_COPY
    of its extent."""
    reach = 10.0 * radius
    for _ in range(CLUMP_GROWTH):
        if reach >= largest:
            return None
        if reach <= 0.0 or tree.query_ball_point(centre, reach, return_length=True) == \
                tree.query_ball_point(centre, 3.0 * reach, return_length=True):
            break
        reach *= 3.0
    else:
        return None
    clump = np.asarray(tree.query_ball_point(centre, reach), dtype=np.int64)
    extent = float(np.max(np.linalg.norm(tree.data[clump] - centre, axis=1))) if len(clump) else 0.0
    apart = 2.0 * extent / NEAR_COPY
    if len(clump) < 2 or extent >= largest or tree.query_ball_point(centre, apart, return_length=True) != len(clump):
        return None
    return clump


def _clumped(radius: np.ndarray, span: float):
    """``(inside, wide, typical)``: the points whose k nearest may all be copies of them, so that the
    radius of those k (``radius`` (N,)) cannot tell a copy from a neighbour (where a place
    holds k copies or more), and whether a wider search must tell them. Such points have a
    radius below NEAR_COPY of the typical one; all do when the typical radius is below the
    spacing of the points strung along a line across the cloud (``span``: the sparsest a
    sampling that connects them can be: a surface's spacing is ~sqrt(N) times that; the
    typical radius then measures nothing: 0). The wider search runs then, or when at least
    :data:`core.tuning.NEAR_COPY_SHARE` are inside."""
    typical = float(np.median(radius))
    if typical < span / len(radius):
        return np.ones(len(radius), dtype=bool), True, 0.0
    inside = radius < NEAR_COPY * typical
    return inside, np.count_nonzero(inside) >= NEAR_COPY_SHARE * len(radius), typical


def _span(points: np.ndarray) -> float:
    """The diagonal of the box of the cloud's bulk (0.5-99.5 % on each axis, on at most
    ~100k points): a stray point far away (a scanner's origin in a georeferenced cloud)
    would make the cloud look clumped, and pay a wide search."""
    bulk = points[:: max(1, len(points) // 100_000)]
    low, high = np.percentile(bulk, [0.5, 99.5], axis=0)
    return float(np.linalg.norm(high - low))


def _wider(points: np.ndarray, k: int):
    """The ``k`` nearest of every point (itself first), searched afresh: only a cloud with
    places of many copies (:func:`_clumped`) pays for it."""
    k = min(k, len(points))
    dist, idx = cKDTree(points).query(points, k=k, workers=-1)
    return idx, dist


def expand(res, merged: Merged, points: np.ndarray, params: dict):
    """The result ``res`` of the distinct positions as a result of every point of ``points``
    (each copy its position's row); ``params`` are added to its params. Its neighbours are
    the distinct positions' graph (:class:`CopiesNeighbours`); the border and the
    anisotropy are taken from the distinct positions (copies would read as a border of
    nothing and as a degenerate sampling)."""
    inv = merged.inverse
    if res.valid.any():
        border, aniso = res.border[inv], res.anisotropy[inv]
    else:  # a degenerate cloud: nothing to judge
        border, aniso = np.zeros(len(inv), dtype=bool), np.full(len(inv), np.nan)
    rows = {name: getattr(res, name)[inv] for name in ("normals", "k1", "k2", "e1", "e2", "valid", "k_point",
                                                      "degree_point", "outlier_score", "crease",
                                                      "orientation_confidence")}
    return replace(res, points=points, **rows, params={**res.params, **params, "n_points": len(points)},
                   neighbours=None if res.neighbours is None else CopiesNeighbours(res.neighbours, merged, points), _border=border,
                   _anisotropy=aniso, _crease_residual=None if res._crease_residual is None else res._crease_residual[inv])


class CopiesNeighbours(Neighbours):
    """The distinct positions' graph ``nb`` as neighbours of every caller's point: a copy's
    row is its position's, itself first (its own copies are not its neighbours)."""

    served_in_place = False  # its rows are copies

    def __init__(self, nb, merged: Merged, points):
        for name, value in dict(_nb=nb, _merged=merged, _points=points).items():
            object.__setattr__(self, name, value)

    def __reduce__(self):  # pickled (and copied) as the whole graph
        return Neighbours, (self.points, self.indices, self.distances)

    def __repr__(self) -> str:
        return f"CopiesNeighbours(n={len(self._points)}, distinct={len(self._merged.first)}, k_max={self.k_max})"

    @property
    def points(self) -> np.ndarray:
        return self._points

    @property
    def k_max(self) -> int:
        return self._nb.k_max

    @property
    def width(self) -> int:
        return self._nb.width

    @property
    def indices(self) -> np.ndarray:
        return self.take(self.k_max)[0]

    @property
    def distances(self) -> np.ndarray:
        return self.take(self.k_max)[1]

    def _held(self):
        return self.take(self.width)

    def take(self, k: int):
        return self.rows(np.arange(len(self._points)), k)

    def rows(self, centres: np.ndarray, k: int):
        self._check_k(k)
        centres = np.asarray(centres, dtype=np.int64)
        idx, dist = self._nb.rows(self._merged.inverse[centres], k)
        idx = self._merged.first[idx]
        idx[:, 0] = centres
        return idx, dist

    def widen(self, k: int | None = None, *, progress=None):
        return self.take(self.k_max if k is None else max(k, self.width))
