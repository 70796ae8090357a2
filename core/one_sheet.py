"""Neighbourhoods on the point's own sheet (k="auto").

Two sheets a few spacings apart (the skins of a plate 2-6 spacings thick, a wall scanned
twice and registered a little apart, a floor under a raised panel) share their nearest
points: 20 neighbours reach about 5 spacings. The second sheet's points read as noise to
the noise measure (0.18 spacing on two noise-free planes 4 spacings apart, so the initial
neighbourhood grew to 77 and took in both), and the position jets fitted their heights: a
mean |H| of 1.65 on two flat planes, 1230 points above |k| = 5, every one reported valid.
With the other sheet's points taken out of the rows by hand (an oracle), both planes came
out exact.

A neighbour q lies on another sheet than point p when its normal is parallel to p's (either
sign, within :data:`SHEET_COS`) and its offset from p's tangent plane, less the
sagitta the turn between their normals explains (chord x sin(turn / 2): on one sheet the
offset is that sagitta), exceeds :data:`SHEET_GATE` x p's noise spread (the
median offset of its 10 nearest) and :data:`SHEET_REACH` x the distance to its
15th neighbour. A side of p's plane holds another sheet when at least
:data:`SHEET_MIN` of its first :data:`core.tuning.SEARCH_WIDTH` neighbours lie
there, :data:`SHEET_SIDED` times as many as on the other side (noise's tails fall
on both), and 15 are left on p's own (:mod:`core.kernels.sheets`). Creases and a tube's own
curvature are kept by the parallel test and the sagitta (their normals turn with the offset).
The rule first reads PCA normals of the :data:`SHEET_K` nearest (at 3 spacings
apart the 15 nearest lean towards the other sheet); the initial normals are found again on
the rows so reordered and the rule applied again on them (:data:`SHEET_ROUNDS`).
The rows that hold another sheet are then searched whole (``k_max`` columns, so the order
does not depend on how wide a graph was held) and list p's own sheet first, then the rest,
each in distance order; every stage from the initial normals on reads them. The orientation
and the result's graph keep the plain nearest (the orientation's chord test tells the skins
of a thin part apart across them).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .kernels import sign_evidence
from .kernels.sheets import count_other, own_sheet_first
from . import plane_spread
from .neighbours import Neighbours
from .normals import pca_normals
from .plain_rows import PlainNeighbours
from .plane_spread import LINE_SPREAD
from .tuning import PCA_K, SEARCH_WIDTH
from .wide_neighbours import WidenableNeighbours

#: a neighbour lies on another sheet than the point (k="auto") when its normal
#: is parallel to the point's within SHEET_COS (30 degrees, either sign) and its offset from
#: the point's plane, less the sagitta their normals' turn explains, is beyond SHEET_GATE x the
#: point's noise spread (median offset of its 10 nearest) and SHEET_REACH x the distance to
#: its 15th neighbour; a side of the plane holds another sheet where at least SHEET_MIN of a
#: row's neighbours lie there and SHEET_SIDED times as many as on the other side (noise's
#: tails fall on both). SHEET_ROUNDS: initial normals found again on the reordered rows,
#: and the rule applied again on them
#: The cosine sits 1e-9 below cos 30 deg: sheets that meet at exactly 30 deg (CAD, a test scene) gave
#: cosines within rounding of it, so rounding decided, differently in each pose (a 30 deg T or X junction
#: of 12000 points: k_point moved at 62-81 points, |H| by > 0.1 at 83-441, within 9 spacings
#: of the line); now they are parallel in every pose (README, "Pose does not move the flags")
SHEET_COS = 0.8660254037844387 - 1e-9
SHEET_GATE = 3.0
SHEET_REACH = 0.5
SHEET_MIN = 5
SHEET_SIDED = 4.0
SHEET_ROUNDS = 2
#: the fits' own-sheet graph is made (a copy of the held graph: 480 MB at 1M points) only where
#: at least this share of the rows hold another sheet: noisy single surfaces have a few tilted
#: rows (8000 points: 1-6 at 0.2 spacing of noise, 20-47 at 0.5, 74-119 at 1), a noisy 1M
#: plane peaked at 2228 MiB with them against 1761 without, for the same answer
SHEET_SHARE = 0.01
SHEET_K = 8  # the rule's first normals: PCA of the 8 nearest (the 15 nearest lean across 3 spacings)
#: neighbours whose median offset is a point's noise spread (as the orientation's gate)
SPREAD_K = 10


#: rows ordered per step (bounds the temporary arrays: 200k rows of 56 were 1.8 GB at once)
_CHUNK = 65_536


class SheetRule(NamedTuple):
    """The points' ``normals`` (N, 3), which have one (``ok``) and ``scales`` (N, 2): each
    one's noise spread and the least offset another sheet has (:data:`SHEET_REACH`
    x the distance to its ``k``-th neighbour): what tells a neighbour on another sheet
    (:mod:`core.kernels.sheets`)."""

    normals: np.ndarray
    ok: np.ndarray
    scales: np.ndarray

    def flagged(self, pts, idx) -> np.ndarray:
        """The points whose row of ``idx`` (the graph's first columns) lists another sheet."""
        count = np.empty(len(idx), dtype=np.int64)
        count_other(pts, self.normals, self.ok, self.scales, idx, _RULE, count)
        return np.flatnonzero(count)

    def ordered(self, pts, rows, dist, centres):
        """Copies of ``rows`` and ``dist`` (the neighbour rows of the points ``centres``),
        each listing its own sheet first, then the rest, each in the row's order, and the
        permutation ``perm`` (int64) that made them (``rows[r, perm[r]]``)."""
        perm = np.empty(rows.shape, dtype=np.int64)
        own_sheet_first(pts, self.normals, self.ok, self.scales, rows, centres, _RULE, perm)
        return np.take_along_axis(rows, perm, axis=1), np.take_along_axis(dist, perm, axis=1), perm

    def ordered_in_steps(self, pts, rows_of, centres):
        """:meth:`ordered` of the rows ``rows_of(c)`` of the points ``centres``, :data:`_CHUNK`
        at a time (all at once, the copies were 1.3 GB at 1M points): yields each step's
        slice of ``centres``, its points, their ordered rows and distances and the permutation."""
        for start in range(0, len(centres), _CHUNK):
            part = slice(start, start + _CHUNK)
            yield (part, centres[part], *self.ordered(pts, *rows_of(centres[part]), centres[part]))


_RULE = (SHEET_COS, SHEET_GATE, float(SHEET_MIN), SHEET_SIDED, float(PCA_K))


class SheetRows(NamedTuple):
    """The columns beyond those a graph holds of its rows that list their own sheet first:
    the points ``centres`` (M,), the columns ``width`` to ``k_max`` of their rows, ``idx``
    and ``dist`` (M, k_max - width; the first ``width`` are in the graph's held rows), and
    ``slot`` (N,), each point's row here (-1: its row is the plain nearest). Only the
    columns beyond the held ones are kept: whole rows of a 1M-point cloud of two sheets were
    672 MB on top of the held copy."""

    centres: np.ndarray
    idx: np.ndarray
    dist: np.ndarray
    slot: np.ndarray

    def put(self, idx, dist, held, points=None) -> None:
        """Write these rows into ``idx`` and ``dist`` (a graph's, or the rows of ``points``,
        searched to their width) in place: their first columns from ``held`` (the graph's held
        rows, as wide as these start), the rest from here."""
        if points is None:
            at, mine = self.centres, slice(None)
        else:
            found = self.slot[points]
            at = np.flatnonzero(found >= 0)
            mine = found[at]
        start, mine = held[0].shape[1], np.arange(len(self.centres))[mine]
        stop = idx.shape[1] - start
        for c in range(0, len(at), _CHUNK):  # in steps: a gather of every row at once was 480 MB at 1M
            to, fro = at[c:c + _CHUNK], mine[c:c + _CHUNK]
            rows = self.centres[fro]
            idx[to, :start], dist[to, :start] = held[0][rows], held[1][rows]
            idx[to, start:], dist[to, start:] = self.idx[fro, :stop], self.dist[fro, :stop]

    def beyond(self, k: int) -> "SheetRows | None":
        """These rows once the graph holds ``k`` more columns (None: it holds them all)."""
        if k >= self.idx.shape[1]:
            return None
        return self._replace(idx=self.idx[:, k:].copy(), dist=self.dist[:, k:].copy())


def sheet_width(plan_or_k) -> int:
    """The columns whose rows are judged (:data:`core.tuning.SEARCH_WIDTH`, at most the
    plan's ``k_search`` or the given k)."""
    k = plan_or_k if isinstance(plan_or_k, (int, np.integer)) else plan_or_k.k_search
    return min(SEARCH_WIDTH, int(k))


def rule(pts, normals, ok, idx, dist, k):
    """The :class:`SheetRule` of ``normals`` on the graph rows ``idx``, ``dist`` (their
    ``k``-th neighbour sets the least offset) and the points whose rows it flags, or None if
    it flags none."""
    scales = np.empty((len(pts), 2))
    sign_evidence.offset_spread(pts, np.where(ok[:, None], normals, 0.0), idx[:, :SPREAD_K], ok, scales[:, 0])
    scales[:, 1] = SHEET_REACH * dist[:, k - 1]
    found = SheetRule(normals, ok, scales)
    flagged = found.flagged(pts, idx)
    return (found, flagged) if len(flagged) else None


def _spans_plane(pts, normals, ok, nb, k) -> np.ndarray:
    """(N,) bool: the point's ``k`` nearest spread over its plane (:mod:`core.plane_spread`,
    at least :data:`core.plane_spread.LINE_SPREAD`). Along a scan line the normal is the
    line's guess and the next line, a few spacings off that guessed plane, is no other
    sheet: a sphere or cylinder scanned in rings 8-16 spacings apart had whole rings
    reordered (a cylinder's orientation 100 -> 83-92 % right)."""
    with np.errstate(invalid="ignore"):
        return plane_spread.spreads(pts, np.where(ok[:, None], normals, np.nan), nb, k) >= LINE_SPREAD


class SheetGraphs(NamedTuple):
    """The graph the fits read (``fit``: each point's own sheet first) and the plain nearest
    served from it (``plain``, a :class:`core.plain_rows.PlainNeighbours`)."""

    fit: object
    plain: object


def fit_graph(pts, nb, k):
    """The graph ``nb`` with the rows that list another sheet among their first
    :data:`core.tuning.SEARCH_WIDTH` listing their own sheet first (over all ``k_max``
    columns), as a new graph (``nb`` is not modified: a cache may hold it); None where fewer
    than :data:`SHEET_SHARE` of the rows do (:func:`graphs`, without the plain view: the
    tiles' pre-pass keeps ``nb``)."""
    made = graphs(pts, nb, k, plain=False)
    return None if made is None else made.fit


def graphs(pts, nb, k, *, plain=True) -> SheetGraphs | None:
    """:func:`fit_graph`, and (``plain``) the plain nearest served from it: ``nb`` itself is
    no longer needed (480 MB at 1M points, what a cloud of two sheets went over 2 GB by)."""
    found = _judged(pts, nb, k)
    if found is None:
        return None
    found, centres = found
    wide = isinstance(nb, WidenableNeighbours)  # a search's columns beyond those held come from SheetRows
    idx, dist = (a.copy() for a in (nb._held() if wide else (nb.indices, nb.distances)))  # nb stays as it is
    width = idx.shape[1]
    tail_idx = np.empty((len(centres), nb.k_max - width), dtype=idx.dtype)
    tail_dist = np.empty((len(centres), nb.k_max - width))
    kind = np.min_scalar_type(nb.k_max - 1)  # a byte per column up to 256 (56 MB at 1M points)
    back = np.empty((len(centres), nb.k_max), dtype=kind) if plain else None  # plain row's j-th: column back[r, j]
    for part, at, rows, rows_dist, perm in found.ordered_in_steps(pts, lambda c: nb.rows(c, nb.k_max), centres):
        idx[at], dist[at] = rows[:, :width], rows_dist[:, :width]
        tail_idx[part], tail_dist[part] = rows[:, width:], rows_dist[:, width:]
        if plain:
            np.put_along_axis(back[part], perm, np.arange(nb.k_max, dtype=kind)[None, :], axis=1)
    slot = np.full(len(pts), -1, dtype=np.int64)
    slot[centres] = np.arange(len(centres))
    if wide:
        fit = nb.with_sheets(idx, dist, SheetRows(centres, tail_idx, tail_dist, slot))
        whole = fit.whole_rows
    else:
        fit = Neighbours(nb.points, idx, dist)
        whole = lambda c: fit.rows(c, fit.k_max)  # noqa: E731 - every column held
    return SheetGraphs(fit, PlainNeighbours(fit, centres, back, slot, whole) if plain else None)


def _judged(pts, nb, k):
    """``(rule, centres)``: the :class:`SheetRule` and the points whose rows list another
    sheet, from PCA normals on the :data:`SHEET_K` nearest (then on the ``k`` nearest of the
    reordered rows, :data:`SHEET_ROUNDS` - 1 times); None where fewer than
    :data:`SHEET_SHARE` of the rows do."""
    idx, dist = nb.take(min(nb.width, SEARCH_WIDTH))
    first = min(k, SHEET_K)
    nrm, ok = pca_normals(pts, idx[:, :first], dist[:, :first])
    found = None
    for r in range(SHEET_ROUNDS):
        latest = rule(pts, nrm, ok & _spans_plane(pts, nrm, ok, nb, k), idx, dist, k)
        if latest is None:  # the normals found on the last order see one sheet: keep it
            break
        found, centres = latest
        if r + 1 < SHEET_ROUNDS:
            mine, mine_dist = idx[:, :k].copy(), dist[:, :k].copy()
            for _, at, rows, rows_dist, _ in found.ordered_in_steps(pts, lambda c: (idx[c], dist[c]), centres):
                mine[at], mine_dist[at] = rows[:, :k], rows_dist[:, :k]
            nrm, ok = pca_normals(pts, mine, mine_dist)
    if found is None or len(centres) < SHEET_SHARE * len(pts):  # a copy (480 MB at 1M) for a few noisy rows
        return None
    return found, centres
