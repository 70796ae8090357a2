"""Two scans of one surface merged with a small registration offset: a double scan.

Registered with an error of a few spacings, the two samplings of one surface lie a gap apart
with the same outward side. The chord test (:func:`core.kernels.sign_evidence.sign_evidence`)
reads two sheets with parallel normals and a chord across the gap as a thin solid's two
skins, which face away from each other, and turned one copy inward wherever the gap passed
the noise gate (a sphere sampled twice, one copy shifted by 3 mean spacings of the merged
cloud: 22-26 % of its points inward with ``k="auto"``, confidence ~1, H of the wrong sign). The two readings differ only on those edges (:func:`cross_edges`):
the thin solid's (the chord term as it is) and the double scan's (the chord term takes the
sign of Hoppe's, parallel normals agree). Where the gap is the same everywhere (two parallel
planes, concentric cylinder patches) both readings are consistent and nothing tells them
apart: the thin solid is kept. Two copies of one curved surface shifted by a registration
error cross wherever the shift is tangent to the surface (a sphere shifted by t: along the
circle normal to t), and the thin solid's reading then asks each copy to face out on one side
of the crossing and in on the other: a seam of frustrated edges inside one sheet, which the
double scan's reading does not have. A closed thin solid (a lens, a plate, a shell) joins its
skins round its rim, and both readings give it the same signs. :func:`choose_reading` runs
the spanning forest on both and keeps the double scan's where its frustrated evidence is
smaller by more than :data:`SEAM` x sqrt(N) (a seam's length grows as sqrt(N) spacings).
"""

from __future__ import annotations

import numpy as np

from .kernels import sign_evidence as kern
from .kernels.cross import cross_terms
from .kernels.union_find import signed_forest
from .orientation_evidence import GATE, ORIENT_K
from .tuning import VOTE_GROWTH, VOTE_SIZE

#: normals within this angle (either sign) are parallel: the sheets of a double scan, or the
#: skins of a thin solid (one_sheet's "another sheet" angle)
PARALLEL_DEG = 30.0
#: rows of the graph sampled to estimate the cross edges' evidence (evenly in the points' order)
CROSS_SAMPLES = 2048
#: the second forest is run only where the cross edges' chord evidence (|a_i a_j| summed) is at
#: least this much a point: a double scan 1-3 spacings apart 0.09-1.1, the closed thin shapes
#: (plate, shell, wedge, bracket, cube, lenses) at most 0.035, single surfaces ~0
CROSS_SHARE = 0.05
#: least drop of the frustrated evidence, in units of sqrt(N), that takes the double scan's
#: reading (20k points, k = 15 and "auto", noise 0 and 0.2 spacing): double scans 1-4 mean
#: spacings apart 2.0-8.7 where the thin reading turns points inward ("auto"; 0.2-1.5 where it
#: does not), the closed thin shapes at most 0.73 noise-free and 1.58 at 0.2 spacing of noise
#: (the shell, k = 15; the double scan's reading gives them the same signs there), two open
#: sheets 1-2 spacings apart and concentric cylinder patches below 0.1 (the thin reading is kept)
SEAM = 2.0
#: rows of the graph whose double-scan evidence is made at a time (the same numbers): made at
#: once, the temporaries of :func:`cross_edges` (~17 arrays of the graph's size) took a 1M-point
#: torus at 0.5 spacing of noise, whose 2048 sampled rows pass :data:`CROSS_SHARE`, to 4.4 GB
ROWS_AT_A_TIME = 1 << 15


def cross_edges(points, normals, graph, spread, rows=slice(None)):
    """For the edges of ``graph[rows]``: the chord term ``a_i a_j`` of
    :func:`core.kernels.sign_evidence.sign_evidence` (the offsets beyond the noise gate,
    over the chord) where the two normals are parallel (:data:`PARALLEL_DEG`) and it
    opposes Hoppe's term (a chord across a gap between parallel sheets), else 0
    (:func:`core.kernels.cross.cross_terms`, one compiled pass)."""
    rows = np.arange(len(graph))[rows] if isinstance(rows, slice) else np.asarray(rows, dtype=np.int64)
    out = np.empty((len(rows), graph.shape[1]))
    cross_terms(np.asarray(points, dtype=np.float64), np.asarray(normals, dtype=np.float64), graph,
                np.asarray(spread, dtype=np.float64), rows, GATE, np.cos(np.radians(PARALLEL_DEG)), out)
    return out


def frustration(ev, graph, flip) -> float:
    """The evidence the signs ``flip`` (1: flipped) leave unsatisfied, summed over edges."""
    sign = 1.0 - 2.0 * flip
    unsatisfied, m = np.empty(ev.size, dtype=np.result_type(ev, np.float64)), 0  # pages touched as written
    for start in range(0, len(ev), ROWS_AT_A_TIME):  # the values in their order, summed once: the same bits
        r = slice(start, start + ROWS_AT_A_TIME)
        agree = ev[r] * sign[r, None] * sign[graph[r]]
        below = agree[agree < 0]
        unsatisfied[m:m + len(below)] = below
        m += len(below)
    return float(-unsatisfied[:m].sum())


def forest_signs(ev, order, levels) -> tuple[np.ndarray, np.ndarray]:
    """``(flip, roots)``: the voted spanning forest (:func:`core.kernels.sign_evidence.voted_signs`)
    on the edge evidence ``ev``, its edges taken strongest first to within 1 / ``levels``;
    ``order`` = (graph, each entry an edge's first copy, the rows in the points' order, each
    point's place in it)."""
    graph, first, rows, rank = order
    flip = np.zeros(len(rows), dtype=np.int8)
    edges = kern.strongest_first(ev, first, levels, rows, graph)
    return flip, kern.voted_signs(edges, signed_forest(len(rows)), flip, rank, VOTE_SIZE, VOTE_GROWTH)


def choose_reading(points, normals, evidence, order, *, spread, weight, levels):
    """``(ev, flip, roots)``: the signs of :func:`forest_signs` (``order``, ``levels``: its)
    on the thin solid's edge evidence ``evidence`` or, where that leaves a seam
    (:data:`SEAM`), on the double scan's (:func:`double_reading`), and the evidence taken.
    ``spread``: each point's noise gate; ``weight``: each point's trust (1 without)."""
    flip, roots = forest_signs(evidence, order, levels)
    graph, rows = order[0], order[2]
    alt = double_reading(points, normals, graph, evidence, (spread, weight), rows)
    if alt is None:
        return evidence, flip, roots
    alt_flip, alt_roots = forest_signs(alt, order, levels)
    drop = frustration(evidence, graph, flip) - frustration(alt, graph, alt_flip)
    if drop > SEAM * np.sqrt(len(points)):
        return alt, alt_flip, alt_roots
    return evidence, flip, roots


def signed_reading(points, normals, graph, evidence, *, spread, weight):
    """The edge evidence of the reading that the signs of ``normals`` (oriented by
    :func:`choose_reading`) follow: the double scan's (:func:`double_reading`) where it
    leaves less of its evidence unsatisfied by them than the thin solid's ``evidence``
    does, by :data:`SEAM` x sqrt(N) (as there; on a double scan's own signs it is less by its
    whole cross area: 8200 against 280 at 20k points). :func:`core.orientation.resettle`
    re-reads the refined normals' signs with it: on the thin solid's evidence its local
    majority turned 0.4 % of a double-scanned sphere back inward (3 spacings, ``k="auto"``)."""
    alt = double_reading(points, normals, graph, evidence, (spread, weight), np.arange(len(points)))
    if alt is None:
        return evidence
    kept = np.zeros(len(points), dtype=np.int8)
    drop = frustration(evidence, graph, kept) - frustration(alt, graph, kept)
    return alt if drop > SEAM * np.sqrt(len(points)) else evidence


def double_reading(points, normals, graph, evidence, gates, rows):
    """The double scan's edge evidence: ``evidence`` (the thin solid's, each edge scaled by
    its points' trust) with the cross edges' chord term (:func:`cross_edges`) of Hoppe's
    sign; None where the cross edges, counted on the first :data:`core.orientation_evidence.ORIENT_K`
    columns of :data:`CROSS_SAMPLES` of the ``rows`` (the points' order), fall below
    :data:`CROSS_SHARE`. ``gates``: each point's noise gate and trust (1 without)."""
    spread, weight = gates
    n = len(points)
    take = rows[np.linspace(0, n - 1, min(n, CROSS_SAMPLES)).astype(np.int64)]
    if np.abs(cross_edges(points, normals, graph[:, :ORIENT_K], spread, take)).sum() < CROSS_SHARE * len(take):
        return None
    alt = np.empty(evidence.shape, dtype=np.result_type(evidence, np.float64))
    for start in range(0, n, ROWS_AT_A_TIME):  # row by row the same numbers, a block's temporaries at a time
        r = slice(start, start + ROWS_AT_A_TIME)
        alt[r] = evidence[r] - 2.0 * cross_edges(points, normals, graph, spread, r) * weight[r, None] * weight[graph[r]]
    return alt
