"""Global orientation of normals that holds across thin parts, nearby sheets and creases.

Hoppe et al. (1992) propagate signs along a minimum spanning tree of the kNN graph with
the cost 1 - |n_i . n_j|. Across a thin part (a plate a few spacings thick, the two
sides of a thin tube) the opposite sides' normals are anti-parallel, so that cost calls
them the best neighbours and the propagation makes them agree: one side flips. Here
every kNN edge carries a signed evidence that also reads the chord between the points
(:func:`core.kernels.sign_evidence.sign_evidence`): along a sheet it is Hoppe's test, across a
gap, a thin part or a crease it is the side of the chord each normal faces, its offsets
gated by the noise (:mod:`core.orientation_evidence`: a fold does not widen the gate). Signs are
fixed along the maximum spanning forest of |evidence| (Kruskal with a parity
union-find; two registered copies of one surface are read as such where they cross:
:mod:`core.double_scan`), except that two parts of :data:`core.tuning.VOTE_SIZE` points or more are
joined by the summed evidence of all the edges between them, not by their strongest
one (:func:`core.kernels.sign_evidence.voted_signs`: one wrong edge on a plate's rim
flipped its whole other side, 50 % agreement at k="auto"), then every component is turned outward by its points farthest from the
cloud's centre (on a closed surface the point farthest from any centre has its normal
pointing away from it; a thin open part, whose far points lie nearly in its plane, by the
side its other skin lies on: :func:`_thin_parts`). A point that most of its evidence disagrees with is then flipped
(a local majority, a few sweeps). Each point's ``confidence`` is the evidence-weighted share of
its neighbours that agree with its final sign.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kernels import patches
from .kernels import sign_evidence as kern
from .double_scan import choose_reading, signed_reading
from .orientation_evidence import GATE, ORIENT_K, TRUST_FLOOR  # noqa: F401  (re-exported)
from .orientation_evidence import FAR_WEAK, THIN_MIN, THIN_MIN_POINTS, thin_vote
from .orientation_evidence import edge_evidence as _evidence
from .part_joins import join_parts
from .tuning import PATCH_COS, PATCH_MAX, PATCH_ROUNDS, PATCH_TILT, PATCH_TRUST, RESETTLE_K

#: the points of a component that vote on its sign: its outer half by distance from the
#: cloud's centre (where the surface faces away from it), read from a histogram of the
#: distances in units of the component's RMS distance, VOTE_BINS bins over [0, 2) (a tiled
#: run sums the tiles' histograms: :func:`outer_reach`). Not "beyond the RMS distance": a
#: noise-free sphere's points all lie at it, so two stray points 10 radii off raised it past
#: every one of them and were the only voters (the sphere faced inward, H = -1); not "beyond
#: the largest": a single outlier far from a torus was then the only voter.
VOTE_BINS = 64
#: points farther than this many times the RMS distance of the points from the cloud's centre
#: are strays to the outward vote (:func:`_global_signs`): they move no centre and cast no
#: vote. One point 1e6 object sizes away moved the centre 100 sizes off an ellipsoid, so that
#: all its points lay at one distance (one bin of :func:`reach_histogram`) and all of them
#: voted: 2 of 8 directions of the stray point turned it inward, with confidence 1. A point
#: is a stray only while the points that far make up less than 1 / STRAY_RMS^2 of the cloud.
STRAY_RMS = 10.0
#: a part whose mean (sign-propagated) normal is longer than this is an open sheet, not a
#: closed surface (whose outward normals sum to zero); see :func:`floors_up`. Denser sampling
#: on one side of a closed object lengthens its mean (a box with its top 5x as dense: 0.4).
OPEN_SHARE = 0.6
#: edges are taken strongest first to within 1/SORT_LEVELS of evidence (ties below that
#: make no measurable difference; a counting sort is 5x faster than argsort at 10^7 edges)
SORT_LEVELS = 4096
#: local-majority sweeps after the spanning forest (:func:`_settle`). Measured on the thin
#: shapes at noise 0.2 spacing (20k points, k = 15, seeds 0-2): +0.03-0.10 % of the points
#: agree with the truth after 3 sweeps; later sweeps flip almost nothing
SETTLE_SWEEPS = 3
MODES = ("outward", "propagate", "keep")


@dataclass(frozen=True, eq=False)
class Orientation:
    """Oriented normals, a per-point confidence in [0, 1] and a component label per point
    (-1 where there is no normal)."""

    normals: np.ndarray
    confidence: np.ndarray
    labels: np.ndarray


def orient(points, normals, idx, mode="outward", *, ok=None, rank=None, trust=False) -> Orientation:
    """Make normal signs globally consistent.

    Parameters
    ----------
    points : (N, 3) float array.
    normals : (N, 3) unit normals (NaN rows allowed where ``ok`` is False); not modified.
    idx : (N, K) int neighbour indices, the point itself first; the first
        :data:`ORIENT_K` columns form the graph, the first
        :data:`core.orientation_evidence.NOISE_RING` the ring of its noise floor.
    mode : "outward" (each connected component made to face away from the cloud's centre
        at its far points), "propagate" (Hoppe's convention: each component's highest
        point faces +z), "keep" (signs untouched, only the confidence), a (3,)
        viewpoint that every normal is made to face, or (N, 3) viewpoints, one per point.
    ok : (N,) bool, rows that have a normal (default: finite rows).
    rank : (N,) int, optional, each point's index in the caller's order when the points
        are passed in another (:mod:`core.spatial_order`): where the signs are decided
        here, equally strong edges are taken in the order of the points' coordinates
        (:func:`geometric_rank`), and of ``rank`` only between points at one place.
    trust : scale each edge's evidence by its points' flatness (:func:`_evidence`,
        :data:`core.tuning.FOLD_TRUST`): what ``k="auto"``'s wide initial normals need at a
        rim 2 spacings high; on the k = 15 normals it cost the 3-spacing plate and the bowl
        0.02-0.1 % of their points.

    Returns
    -------
    Orientation
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    nrm = np.ascontiguousarray(normals, dtype=np.float64)  # read only: every result below is a new array
    ok = np.isfinite(nrm).all(axis=1) if ok is None else np.asarray(ok, dtype=bool)
    idx = np.asarray(idx)
    graph = idx[:, :ORIENT_K]  # a view in its own int type (as resettle's): no copy of the graph
    if graph.dtype not in (np.int32, np.int64):
        graph = graph.astype(np.int64)
    n = len(pts)
    labels = np.where(ok, 0, -1)
    rank = np.arange(n) if rank is None else np.asarray(rank, dtype=np.int64)
    if isinstance(mode, str) and mode != "keep":  # the signs are decided here: ties go by place, not index
        rank = geometric_rank(pts, rank)
    spread, flat = np.empty(n), np.empty(n)
    # Hoppe's term weighted by the raw chord offsets (as resettle's) on the integer-k normals: a thin rim's
    # inflated gate had it vote the two faces apart (1:1:0.1 ellipsoid, k = 15); k="auto" (``trust``)
    # keeps the gated weight (raw there cost the 2-5 spacing wedge 0.05 % of its face share at seed 4)
    ev, first = _evidence(pts, nrm, graph, ok, rank, trust=trust, raw_weight=not trust, spread=spread, ring=idx,
                          flat=flat)
    sign = np.ones(n)
    if not isinstance(mode, str):
        sign[np.einsum("ij,ij->i", nrm, np.asarray(mode, dtype=float) - pts) < 0] = -1.0
    elif mode != "keep":
        rows = np.empty(n, dtype=np.int64)
        rows[rank] = np.arange(n)
        ev, flip, roots = choose_reading(pts, nrm, ev, (graph, first, rows, rank), spread=spread, weight=flat,
                                         levels=SORT_LEVELS)
        sign[flip == 1] = -1.0
        labels = np.where(ok, _numbered(roots), -1)
        group, parity = join_parts(pts, nrm * sign[:, None], labels, spread, rank, GATE)
        if (parity < 0).any():
            sign[ok] *= parity[labels[ok]]
        _global_signs(pts, nrm * sign[:, None], (labels, group), mode, sign, rank, spread=spread)
        labels = np.append(group, -1)[labels]  # -1 (no normal) stays -1
    confidence = np.empty(n)
    kern.agreement(ev, graph, (sign < 0).astype(np.int8), ok, confidence)
    if isinstance(mode, str) and mode != "keep":
        _settle(ev, graph, ok, sign, confidence)
    return Orientation(nrm * sign[:, None], confidence, labels)


def geometric_rank(points, rank) -> np.ndarray:
    """(N,) each point's place in the order of its coordinates (by x, then y, then z; points
    at one place by ``rank``). :func:`orient` takes equally strong edges (the counting sort's
    levels of :data:`SORT_LEVELS`), the first copy of an edge, the seam sums and the parts'
    samples in this order, so the signs do not depend on the order of the points: in the
    caller's order a thin ellipsoid (axes 1:1:0.1, 3000 points, k = 15) turned 62 points of
    its rim inward, or a whole face, as the points were permuted. A lexicographic order, as
    against an index, is the same on any subset (a tile orders its points as the cloud
    does). One argsort of x (0.1 s at 1M points); a full lexsort only where x ties."""
    x = points[:, 0]
    order = np.argsort(x)
    ordered = x[order]
    if len(x) > 1 and (ordered[1:] == ordered[:-1]).any():  # a grid's rows, a plane x = c
        order = np.lexsort((rank, points[:, 2], points[:, 1], x))
    place = np.empty(len(x), dtype=np.int64)
    place[order] = np.arange(len(x))
    return place


def _numbered(roots):
    """Component numbers 0, 1, ... in the order of their roots' indices (what
    ``np.unique(roots, return_inverse=True)[1]`` gives, without sorting N values)."""
    is_root = roots == np.arange(len(roots))
    return (np.cumsum(is_root) - 1)[roots]


def _settle(ev, graph, ok, sign, confidence):
    """Flip (in ``sign``, updating ``confidence``) the points whose evidence-weighted
    neighbours mostly disagree with them (confidence < 0.5), up to :data:`SETTLE_SWEEPS`
    times: the spanning forest fixed each sign by one edge, and a point hung on a wrong
    one (a noisy normal, a blended rim normal) is outvoted by the rest of its edges."""
    for _ in range(SETTLE_SWEEPS):
        outvoted = ok & (confidence < 0.5)
        if not outvoted.any():
            return
        sign[outvoted] *= -1.0
        kern.agreement(ev, graph, (sign < 0).astype(np.int8), ok, confidence)


def resettle(points, normals, idx, mode, *, ok=None, trust=False):
    """Signs re-decided on better normals than the ones :func:`orient` was given: each
    point's chord-aware evidence (:func:`_evidence`) recomputed on ``normals`` (the
    refined ones, whose signs :func:`orient` fixed) with its :data:`core.tuning.RESETTLE_K`
    nearest, a wider ring than the forest's (the noise gate still from the
    :data:`ORIENT_K` nearest), and the local majority of :func:`_settle` run on it. At a
    sharp rim the initial normals are blends, and a point or two hung on a blended
    neighbour keep a sign that their refined neighbours outvote; the 10 nearest of a
    blended rim point are mostly blends like it, the wider ring reaches the clean faces
    (measured on the thin shapes at noise 0.2 spacing, 20k points, k=15: with 10
    neighbours 0.06-0.11 % more of the points face the truth on the 3-spacing plate,
    0.14-0.20 % on the 2-spacing tube (seeds 0-4); with 30, up to 0.1 % more again,
    tuning.RESETTLE_K). Hoppe's term is weighted here by the chord offsets before the noise
    gate (``raw_weight``: at a rim the gate, inflated by the fold, zeroed them and gave a rim
    point's edges to the other face full weight), and patches that disagree with their seam
    are flipped whole (:func:`_flip_patches`; up to :data:`core.tuning.PATCH_MAX` points).
    Whole faces are not re-decided: their signs came from the
    spanning forest's seams, which the refined normals would not judge better. Only for
    the modes that decide signs ("outward", "propagate"); otherwise every sign is kept.
    ``idx`` (N, K) holds at least :data:`ORIENT_K` neighbours; its first RESETTLE_K vote (its
    first :data:`core.orientation_evidence.NOISE_RING`: the noise floor's ring).
    ``trust``: as :func:`orient`'s.

    Returns ``(sign, confidence)``: (N,) +1 / -1 to multiply the normals by and each point's
    evidence-weighted agreement with its new sign (as :attr:`Orientation.confidence`)."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    nrm = np.ascontiguousarray(normals, dtype=np.float64)
    ok = np.isfinite(nrm).all(axis=1) if ok is None else np.asarray(ok, dtype=bool)
    if not ok.all():  # one zeroed copy for the evidence and the patches (it was made twice), none if all have a normal
        nrm = np.where(ok[:, None], nrm, 0.0)
    graph = idx[:, :RESETTLE_K]  # a view in its own int type (an int64 copy: 229 MiB at 1M points)
    n = len(pts)
    flat, spread = np.empty(n), np.empty(n)
    ev, _ = _evidence(pts, nrm, graph, ok, np.arange(n), want_first=False, trust=trust, raw_weight=True, flat=flat,
                      ring=idx, spread=spread)
    ev = signed_reading(pts, nrm, graph, ev, spread=spread, weight=flat)  # a double scan's signs: its reading
    sign = np.ones(n)
    confidence = np.empty(n)
    kern.agreement(ev, graph, np.zeros(n, dtype=np.int8), ok, confidence)
    if isinstance(mode, str) and mode != "keep":
        _settle(ev, graph, ok, sign, confidence)
        joins = ok & (flat > PATCH_TRUST) if trust else ok
        _flip_patches(pts, nrm, graph, (ok, joins), ev, sign, confidence)
    return sign, confidence


def _flip_patches(points, normals, graph, masks, ev, sign, confidence):
    """Patches that disagree with their seam flipped whole (in ``sign``, updating
    ``confidence``; :func:`core.kernels.patches.flip_patches`), then the local majority once
    more. The local majority flips a point at a time, and a patch of points that agree with
    each other keeps whatever sign the forest gave it, however its rim votes: a patch of
    120 points of the thin end of :func:`core.shapes_thin.thin_wedge`'s top (k = 15, noise
    0.2 spacing, seed 1), of 10-20 points of the plate's side strips. A patch is a smooth
    face's piece whose chords stay near its tangent planes (:data:`core.tuning.PATCH_TILT`),
    so it does not grow round a rim into the other face, and at most
    :data:`core.tuning.PATCH_MAX` points: a whole face is the forest's to decide. ``masks``:
    the rows with a normal, and those that may join a patch (with ``trust``, only the flat
    ones, :data:`core.tuning.PATCH_TRUST`: k="auto"'s wide normals at a 2-spacing rim are
    smooth blends that chained the top and the bottom into one patch)."""
    ok, joins = masks
    flipped = 0
    for _ in range(PATCH_ROUNDS):
        step = patches.flip_patches(points, normals, graph, joins, sign, ev, PATCH_COS, PATCH_TILT, PATCH_MAX)
        flipped += step
        if not step:
            break
    if flipped:
        kern.agreement(ev, graph, (sign < 0).astype(np.int8), ok, confidence)
        _settle(ev, graph, ok, sign, confidence)


def orient_normals(points, normals, idx, mode, *, ok=None):
    """:func:`orient` returning the normals only."""
    return orient(points, normals, idx, mode, ok=ok).normals


def _global_signs(points, normals, parts, mode, sign, rank, *, spread=None):
    """Flip whole groups of components (in ``sign``; ``parts`` = (component label per point,
    group per component), :func:`core.part_joins.join_parts`): "outward" by the sum of its
    components' votes, each by its outer half by distance from the cloud's centre
    (:data:`VOTE_BINS`) (weighted by how squarely they face away), "propagate" by the sign
    of the group's highest point's normal z (of equally high ones, the lowest ``rank``).
    A group whose normals sum to almost nothing and whose far points vote weakly (a thin
    part's two skins, open) takes the vote of its skins instead (:func:`_thin_parts`)."""
    labels, group = parts
    have = np.flatnonzero(labels >= 0)
    if not len(have):
        return
    rows = slice(None) if len(have) == len(labels) else have  # a view, not a copy, when all have a normal
    lab = labels[rows]
    n_comp = int(lab.max()) + 1
    if mode == "propagate":
        lab = group[lab]
        z = points[rows, 2]
        order = np.lexsort((rank[rows], -z, lab))  # by component, highest first
        first = order[np.r_[0, np.flatnonzero(np.diff(lab[order])) + 1]]
        vote = np.zeros(n_comp)
        vote[lab[first]] = normals[have[first], 2]
    else:
        pts, nrm = points[rows], normals[rows]
        sums, counts = normal_sums(nrm, group[lab], n_comp), np.bincount(group[lab], minlength=n_comp)
        rel = pts - pts.mean(axis=0)
        square = np.einsum("ij,ij->i", rel, rel)
        kept = square <= STRAY_RMS ** 2 * square.mean()
        if not kept.all():  # stray points far off: not in the centre, nor the distances, nor the vote
            rel = pts[kept] - pts[kept].mean(axis=0)
            square, lab, nrm = np.einsum("ij,ij->i", rel, rel), lab[kept], nrm[kept]
        rms = np.sqrt(np.bincount(lab, square, n_comp) / np.maximum(np.bincount(lab, minlength=n_comp), 1))
        reach = outer_reach(reach_histogram(np.sqrt(square), rms, lab, n_comp)) * rms
        far, facing = far_facing(rel, nrm, reach[lab])
        grp = group[lab]
        beside = centre_beside(sums, normal_sums(rel, grp, n_comp), np.bincount(grp, square, n_comp),
                               np.bincount(grp, minlength=n_comp))
        vote = np.bincount(group, np.bincount(lab[far], facing, n_comp), n_comp)
        if spread is not None:
            voters = np.bincount(group, np.bincount(lab[far], minlength=n_comp), n_comp)
            _thin_parts(points, normals, (have, group[labels[have]]), (vote, voters, sums, counts), rank, spread)
        vote = floors_up(vote, sums, counts, beside)
        lab = group[labels[rows]]
    sign[have[vote[lab] < 0]] *= -1.0


def _thin_parts(points, normals, members, votes, rank, spread):
    """Each group (``members``: rows with a normal and their group) whose far points'
    ``vote`` is weak (mean facing of its ``voters`` below
    :data:`core.orientation_evidence.FAR_WEAK`) and whose normals ``sums`` are short
    (mean below :data:`OPEN_SHARE`: both skins of a thin part, or a closed surface) takes, in
    ``vote``, :func:`core.orientation_evidence.thin_vote` where that reads at least
    :data:`core.orientation_evidence.THIN_MIN` either way: its skins face away from each
    other. Its far points are its rim, nearly in its plane: its outside barely shows there."""
    vote, voters, sums, counts = votes
    with np.errstate(invalid="ignore", divide="ignore"):
        weak = np.abs(vote) < FAR_WEAK * voters
        short = np.linalg.norm(sums, axis=1) <= OPEN_SHARE * counts
    rows, grp = members
    read = weak & short & (counts > THIN_MIN_POINTS)
    if not read.any():
        return
    rows, grp = rows[read[grp]], grp[read[grp]]
    rows = rows[np.lexsort((rank[rows], grp))]  # by group, then in the order of their coordinates
    sizes = np.bincount(grp, minlength=len(vote))
    ends = np.cumsum(sizes)
    for g in np.flatnonzero(read):
        score = thin_vote(points, normals, rows[ends[g] - sizes[g]:ends[g]], spread)
        if abs(score) >= THIN_MIN:
            vote[g] = score


def normal_sums(normals, part, n_parts) -> np.ndarray:
    """(n_parts, 3) sum of each part's (sign-propagated) normals (summed over tiles in a
    tiled run)."""
    return np.stack([np.bincount(part, normals[:, a], n_parts) for a in range(3)], axis=1)


def floors_up(vote, sums, counts, beside) -> np.ndarray:
    """The outward ``vote`` per part, except for open sheets that lie mostly level (a
    ground, a floor with things on it, terrain) with the cloud's centre ``beside`` them
    (:func:`centre_beside`): their vote is their mean normal's z, so they
    face up. A closed surface's outward normals sum to zero (the divergence theorem); a part
    whose mean normal is longer than :data:`OPEN_SHARE` is open, has no inside, and its
    "outward" side is decided by how the cloud's centre sits above or below it: a street
    scan's ground (objects lift the centre above it) faced down at 99.9 % of its points.
    Level: the mean normal within 45 degrees of vertical (a facade keeps the vote). A small
    level patch far from the centre keeps its vote: a sphere sampled in 500 separate clumps
    had those near its south pole face up, inward (8.8 % of its points)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = sums / np.maximum(counts, 1)[:, None]
    length = np.linalg.norm(mean, axis=1)
    level = (length > OPEN_SHARE) & (np.abs(mean[:, 2]) >= np.cos(np.radians(45.0)) * length) & beside
    return np.where(level, mean[:, 2], vote)


def centre_beside(sums, offsets, squares, counts) -> np.ndarray:
    """(n_parts,) bool: the cloud's centre lies beside each part rather than off its plane,
    nearer to the plane (of the part's mean normal ``sums``, through its centroid) than the
    part's RMS radius. From sums over the part's points of their positions relative to the
    centre (``offsets``), of their squared distances from it (``squares``) and ``counts``: the
    radius about the centroid by the parallel axis theorem, so tiles can sum them too."""
    with np.errstate(invalid="ignore", divide="ignore"):
        n = np.maximum(counts, 1)[:, None]
        centroid = offsets / n
        radius2 = squares / n[:, 0] - np.einsum("ij,ij->i", centroid, centroid)
        unit = sums / np.linalg.norm(sums, axis=1, keepdims=True)
        off_plane = np.abs(np.einsum("ij,ij->i", np.nan_to_num(unit), centroid))
    return off_plane * off_plane < np.maximum(radius2, 0.0)


def reach_histogram(dist, rms, lab, n_comp) -> np.ndarray:
    """(n_comp, VOTE_BINS) counts of the points' distances ``dist`` from the cloud's centre in
    units of their component's RMS distance ``rms`` (``lab``: component per point), over [0, 2)
    (farther: the last bin); summed over tiles in a tiled run."""
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.nan_to_num(dist / rms[lab], nan=0.0, posinf=2.0)
    b = np.minimum((unit * (VOTE_BINS / 2.0)).astype(np.int64), VOTE_BINS - 1)
    return np.bincount(lab * VOTE_BINS + b, minlength=n_comp * VOTE_BINS).reshape(n_comp, VOTE_BINS)


def outer_reach(hist) -> np.ndarray:
    """Per component, the distance (in units of its RMS distance) from which its outer half
    lies: the lower edge of the bin of :func:`reach_histogram` where the count from the
    farthest bin down reaches half the component's points (:data:`VOTE_BINS`)."""
    from_top = np.cumsum(hist[:, ::-1], axis=1)
    first = np.argmax(2 * from_top >= from_top[:, -1:], axis=1)  # bins from the top to cover half
    return (VOTE_BINS - 1 - first) * (2.0 / VOTE_BINS)


def far_facing(rel, normals, reach):
    """The outward vote's voters and their votes: which points lie at least ``reach`` (their
    component's, :func:`outer_reach` x its RMS distance) from the cloud's centre (``rel``:
    positions relative to it), and how squarely each one's normal faces away from the centre
    (cosine, NaN-free). Shared by :func:`orient` and the tiled engine (:mod:`core.tiled.signs`)."""
    dist = np.linalg.norm(rel, axis=1)
    far = dist >= reach
    with np.errstate(invalid="ignore", divide="ignore"):
        facing = np.einsum("ij,ij->i", normals[far], rel[far]) / dist[far]
    return far, np.nan_to_num(facing)
