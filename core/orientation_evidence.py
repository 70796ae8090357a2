"""The signed evidence of the orientation graph's edges (:func:`core.orientation.orient`,
:func:`core.orientation.resettle`), with a noise gate that a fold does not widen.

Each point's gate is its spread, the median offset of its neighbours from its plane
(:func:`core.kernels.sign_evidence.offset_spread`), but at most :data:`NOISE_CAP` x the least
spread within two hops of its :data:`NOISE_RING` nearest (:func:`noise_floor`). Where a thin
part folds over within a neighbourhood (the knife edge of a closed lens, a plate's rim, a
sheet pair closer than the normals' fit radius) the neighbours lie on both faces and the
normals are blends of them: the median offset there measures the fold (on a noise-free
1:1:0.1 ellipsoid 0.1-0.3 spacing, 40x the flat faces', over a band as wide as the normals'
fit), not noise, and gated away the chord test that tells the faces apart. Hoppe's term then
joined them as one folded sheet, and a whole face turned inward (50 % of the lens's points,
confidence 1, at k = 40 and "auto"). A fold is narrower than the two hops; noise covers a
region, so in a noisy region the least spread nearby is of the same noise and the gate stays
at its level (about half the median spread: 0.52x on a plane at 0.3 spacing of noise). A cap
from the cloud's low quantile of spread instead closed the gate on the noisy half of a
half-noisy torus (its K error 1.08 -> 1.27x that of the cloud noisy everywhere). Left: the
1:1:0.1 lens at 0.2 spacing of noise and k = 40 keeps a face inward; there the gate at the
noise's own level swallows the chord test across the knife edge (no gate at all: 1-2 %).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .kernels import sign_evidence as kern
from .tuning import FOLD_TRUST

#: neighbours per point in the orientation graph. 10 rather than Hoppe's 8: the chord
#: test needs the graph to reach across a thin part's edges; measured on the thin shapes
#: (tests/test_orientation.py) at noise 0.2 spacing.
ORIENT_K = 10
#: an offset along a normal counts in the chord test only beyond this many times the
#: pair's spread (median offset of their neighbours from their planes): below it, it is noise
GATE = 2.0
#: the least trust an edge's point keeps (:func:`edge_evidence`): with none, a point whose edges
#: all had zero evidence was left out of the forest and kept the sign its eigenvector
#: happened to have, which depends on the order of the points in memory (3 of 3000 points
#: of a sphere quantised to a grid, tests/core/test_spatial_order.py)
TRUST_FLOOR = 0.01
#: the noise floor of a point (:func:`noise_floor`) is the least spread over NOISE_HOPS hops of
#: its NOISE_RING nearest (about 4.5 spacings: past the band a fold blends, ~3.6 spacings with
#: k = 40's normals); its gate is at most NOISE_CAP x that. Nine lenses (1:1:0.05-0.1 and
#: 1:0.6:0.06, k = 30-80 and "auto", turned; tests/core/test_round4_geometry.py), inward share:
#: 49-51 % -> 0.7-4 %. One hop (the point's own 15 nearest) left k = 40's 1:1:0.1 lens at 51 %,
#: and "auto"'s noisy one (normals over 45 neighbours); the 10 % quantile for the least, two of
#: them; NOISE_CAP 3 two of them, 2 none (but the 2-spacing lens at 5.2 %, against 4.0 %).
#: The thin shapes (core.shapes_thin, 20k points, noise 0 and 0.2 spacing, k = 15 and "auto",
#: seeds 0-2): face shares within -0.08 % (the shell, noise 0.2, k = 15, seed 0) and +0.16 %
NOISE_RING = 15
NOISE_HOPS = 2
NOISE_CAP = 1.5


def noise_floor(spread, ring, ok) -> np.ndarray:
    """(N,) the least ``spread`` of the rows ``ok`` within :data:`NOISE_HOPS` hops of each
    point's first :data:`NOISE_RING` neighbours in ``ring`` (the point itself included); inf
    where none is ``ok``."""
    pool = ring[:, :NOISE_RING]  # a view (a contiguous copy: 60 MiB at 1M points)
    if pool.dtype not in (np.int32, np.int64):
        pool = pool.astype(np.int64)
    floor = np.where(ok, spread, np.inf)
    for _ in range(NOISE_HOPS):
        least = np.empty(len(floor))
        kern.least_near(floor, pool, least)
        floor = least
    return floor


def edge_evidence(points, normals, graph, ok, rank, *, trust=False, want_first=True, raw_weight=False, flat=None,
                  spread=None, ring=None):
    """The signed evidence of every graph edge, and which entries are an edge's first copy
    (None without ``want_first``: :func:`core.orientation.resettle` reads only the evidence;
    each point's spread from its first :data:`ORIENT_K` neighbours, however wide the graph, its
    gate capped by :func:`noise_floor` over ``ring``, default ``graph``). With ``trust`` each
    edge is scaled by its two points' trust, 1 - :data:`core.tuning.FOLD_TRUST` x (the median
    offset of their neighbours from their plane, uncapped) / (the distance to the farthest of
    them), clipped to [:data:`TRUST_FLOOR`, 1]: ~1 on a sheet, small where the neighbours fold
    over. ``raw_weight``: as :func:`core.kernels.sign_evidence.sign_evidence`'s; ``flat``: an
    (N,) array that receives each point's trust (1 without ``trust``); ``spread``: one that
    receives each point's gate (its capped spread)."""
    n = len(points)
    spread_graph = graph[:, :ORIENT_K]  # a view: the kernels read strided rows as fast
    raw = np.empty(n)
    kern.offset_spread(points, normals, spread_graph, ok, raw)
    gated = np.minimum(raw, NOISE_CAP * noise_floor(raw, graph if ring is None else ring, ok))
    if spread is not None:
        spread[:] = gated
    weight = np.empty(0)  # none: every trust 1
    if trust:
        reach = np.linalg.norm(points[spread_graph[:, -1]] - points, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            weight = np.clip(1.0 - FOLD_TRUST * raw / reach, TRUST_FLOOR, 1.0)
        weight[reach == 0.0] = 1.0  # a point whose neighbours all coincide with it: nothing to read a fold from
    ev = np.empty(graph.shape)
    first = np.empty(graph.shape if want_first else (0, 0), dtype=np.bool_)
    kern.sign_evidence(points, normals, gated, weight, graph, ok, GATE, ev, first, rank, raw_weight)
    if flat is not None:
        flat[:] = weight if trust else 1.0
    return ev, first if want_first else None


#: a group's far-point vote (:func:`core.orientation._global_signs`) is weak below this mean
#: facing of its voters; only then, and only for a group whose normals sum to almost nothing
#: (both skins of a thin part, ``OPEN_SHARE``), is its sign read from :func:`thin_vote`. Two
#: open 2 x 2 sheets 0.1 apart (2.2 spacings, 2000 points each, k = 40): their far points are
#: the corners, whose directions from the centre lie within 3 degrees of the sheets' plane, so
#: the true vote was +0.05 a voter (100 / 2042) and the rim normals' in-plane tilts, -0.053,
#: outvoted it: the sheets faced each other. A sphere's voters face out at 1.0, a 1:1:0.1 lens's
#: at 0.51-0.55 (k = 15, 40).
FAR_WEAK = 0.2
#: points of a group that :func:`thin_vote` samples (evenly in the order of their coordinates),
#: the neighbours each one reads, and the least mean vote of theirs that decides the group
THIN_SAMPLES = 2048
THIN_NEIGHBOURS = 48
THIN_MIN = 0.1
#: least points of a group that is read as a thin part
THIN_MIN_POINTS = 64


def thin_vote(points, normals, order, spread) -> float:
    """Which way a thin part's skins face, from the points ``order`` (rows of one group in the
    order of their coordinates): the mean, over up to :data:`THIN_SAMPLES` of them, of the share
    of their :data:`THIN_NEIGHBOURS` nearest in the group that lie behind the point's
    normal less the share in front of it (offsets within 3x the point's ``spread`` or half the
    distance to its 6th nearest count as its own sheet). On a thin part the other skin lies
    behind each point (the segment between the skins is inside the solid): > 0 when the skins
    face away from each other, outward. On one open sheet both sides are empty: ~0."""
    pts = points[order]
    tree = cKDTree(pts)
    take = order[np.linspace(0, len(order) - 1, min(len(order), THIN_SAMPLES)).astype(np.int64)]
    m = min(THIN_NEIGHBOURS + 1, len(order))
    dist, near = tree.query(points[take], k=m)
    offset = np.einsum("ijk,ik->ij", pts[near] - points[take][:, None, :], normals[take])
    tol = np.maximum(3.0 * spread[take], 0.5 * dist[:, min(6, m - 1)])[:, None]
    score = (np.count_nonzero(offset < -tol, axis=1) - np.count_nonzero(offset > tol, axis=1)) / max(m - 1, 1)
    return float(np.mean(score))
