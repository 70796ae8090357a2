"""Parts of the orientation graph joined across gaps.

The spanning forest of :func:`core.orientation.orient` joins points by the evidence of
their :data:`core.orientation.ORIENT_K` nearest. Parts those neighbours do not reach
across were each turned outward on their own: scan lines farther apart than the 10
nearest reach, pieces of a wall split by an occlusion shadow, the two skins of a thick
wall. A nearly flat part has no outside, so its sign was a coin flip, and one sheet in
scan lines 12 spacings apart came out as two blocks of opposite orientation, each with
confidence 1.

Here the parts of at least :data:`JOIN_MIN` points are joined by the same
signed evidence (:func:`core.kernels.sign_evidence.sign_evidence`) on the chords between
their closest points: Hoppe's test where a chord lies in both tangent planes (pieces of
one sheet), the chord test where it leaves them. The chord test holds at any distance: a
segment between two surface points that crosses no surface lies wholly inside or wholly
outside the solid, so a consistent orientation leaves both points on the same side of
it; the segment between two parts' closest points crosses neither part. Each part is
offered to its :data:`JOIN_NEAREST` nearest parts, the offers are taken strongest mean
evidence first (Kruskal with parities), and an offer whose mean evidence is below
:data:`JOIN_EVIDENCE` is refused: such parts keep their own outward vote.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .kernels import sign_evidence as kern
from .kernels.union_find import find_signed, join_signed, signed_forest
from .tuning import VOTE_SIZE

#: points of each part that stand for it when the parts' distances are measured (evenly
#: spaced in the caller's order): the distances are those of samples, good to a few spacings
JOIN_SAMPLE = 128
#: parts joined, the largest first; smaller ones keep their own vote (the cost grows with the
#: parts, :class:`_Nearest`: ~0.2 ms a part; 64 until 2026-12-07, when a torus sampled in 200
#: clumps of 25 points had 9-24 % of its points facing in, the clumps beyond the 64th on their own)
JOIN_PARTS = 1024
#: least points of a part that is joined; smaller ones keep their own vote. 16 (VOTE_SIZE) until
#: 2026-12-07, when a torus sampled in 300 clumps of 15 points had 8 % of them facing in at k = 15
JOIN_MIN = 8
#: nearest parts each part is offered to (a part of VOTE_SIZE points or more also to its nearest
#: such parts: small pieces between two large parts do not stand in for their direct tie)
JOIN_NEAREST = 3
#: closest sample pairs whose chords vote on one offer, from each side
JOIN_PAIRS = 8
#: least mean evidence (of +-1) that joins two parts
JOIN_EVIDENCE = 0.25


def join_parts(points, normals, labels, spread, rank, gate):
    """Groups of parts (``labels``: part number per point, -1 where there is no normal)
    whose signs are tied by the evidence between them.

    ``normals`` are the forest's (signs consistent within each part), ``spread`` each
    point's noise spread (:func:`core.kernels.sign_evidence.offset_spread`), ``rank`` each
    point's index in the caller's order (the samples do not depend on the order in memory),
    ``gate`` the forest's multiple of it (:data:`core.orientation.GATE`).

    Returns ``(group, parity)``: per part, its group's number (the lowest part number in
    it) and +1 / -1, what to multiply its normals by to agree with its group.
    """
    n_parts = int(labels.max()) + 1 if len(labels) else 0
    group, parity = np.arange(n_parts), np.ones(n_parts)
    parts, samples, sizes = _samples(labels, rank, n_parts)
    if len(parts) < 2:
        return group, parity
    near = _Nearest(points, samples)
    pairs = set(near.pairs(np.arange(len(parts)))) | set(near.pairs(np.flatnonzero(sizes >= VOTE_SIZE)))
    offers = _offers(points, normals, (spread, gate), near, sorted(pairs))
    link = signed_forest(len(parts))  # the spanning forest's parity union-find
    for strength, a, b in sorted(offers, key=lambda o: (-abs(o[0]), o[1], o[2])):
        ra, pa = find_signed(link, a)
        rb, pb = find_signed(link, b)
        if ra != rb and abs(strength) >= JOIN_EVIDENCE:
            join_signed(link, ra, rb, pa ^ pb ^ int(strength < 0))
    root, flip = np.array([find_signed(link, x) for x in range(len(parts))]).T
    lowest = np.full(len(parts), len(parts))
    np.minimum.at(lowest, root, np.arange(len(parts)))  # each group's lowest part names it
    group[parts], parity[parts] = parts[lowest[root]], np.where(flip ^ flip[lowest[root]], -1.0, 1.0)
    return group, parity


def _samples(labels, rank, n_parts):
    """The parts that take part (at least JOIN_MIN points, the JOIN_PARTS largest; ties
    to the part whose first point comes first in the caller's order), each one's
    sample rows, evenly spaced in the caller's order, and their sizes."""
    have = np.flatnonzero(labels >= 0)
    lab = labels[have]
    size = np.bincount(lab, minlength=n_parts)
    big = np.flatnonzero(size >= JOIN_MIN)
    if len(big) < 2:  # one surface: nothing to join, at the cost of a count
        return big, [], size[big]
    first = np.full(n_parts, np.iinfo(np.int64).max)
    np.minimum.at(first, lab, rank[have])
    parts = np.sort(big[np.lexsort((first[big], -size[big]))][:JOIN_PARTS])
    order = have[np.lexsort((rank[have], lab))]  # by part, then the caller's order
    start = np.concatenate([[0], np.cumsum(size)])
    samples = []
    for part in parts:
        rows = order[start[part]:start[part + 1]]
        samples.append(rows[np.linspace(0, len(rows) - 1, min(len(rows), JOIN_SAMPLE)).astype(np.int64)])
    return parts, samples, size[parts]


class _Nearest:
    """The gaps between the parts' samples, measured only where they can matter: the gap of
    two parts (their closest samples' distance) is at least their centres' distance less
    both radii, so a part's :data:`JOIN_NEAREST` nearest are found by measuring the others
    in the order of that bound until it exceeds the last one kept. The pairs are the ones
    every gap measured would give; the cost grows with the parts, not with their square
    times the samples (a 200 x 200 table of 25 600 samples each was 80 MB)."""

    def __init__(self, points, samples):
        self.points, self.samples = points, samples
        self.trees = [cKDTree(points[rows]) for rows in samples]
        sampled = [points[rows] for rows in samples]
        self.centres = np.array([p.mean(axis=0) for p in sampled])
        self.radii = np.array([np.sqrt(((p - c) ** 2).sum(axis=1)).max() for p, c in zip(sampled, self.centres)])
        self._gaps = {}

    def query(self, x: int, y: int):
        """(distance, row) of part ``x``'s nearest sample to each sample of part ``y``."""
        d, j = self.trees[x].query(self.points[self.samples[y]], k=1)
        return d, self.samples[x][j]

    def gap(self, a: int, b: int) -> float:
        key = (min(a, b), max(a, b))
        if key not in self._gaps:
            self._gaps[key] = float(self.query(*key)[0].min())
        return self._gaps[key]

    def pairs(self, among) -> list:
        """Sorted (a, b), a < b: each part of ``among`` (part positions, ascending) with its
        JOIN_NEAREST nearest of them (ties to the lower index)."""
        found = set()
        centres, radii = self.centres[among], self.radii[among]
        for i, b in enumerate(among.tolist()):
            bound = np.linalg.norm(centres - centres[i], axis=1) - radii - radii[i]
            bound = np.maximum(bound, 0.0) * (1 - 1e-9)  # below every gap, rounding included
            bound[i] = np.inf
            kept = []  # (gap, a), the nearest so far
            for j in np.argsort(bound, kind="stable"):
                if j == i or (len(kept) >= JOIN_NEAREST and bound[j] > kept[JOIN_NEAREST - 1][0]):
                    break
                kept = sorted(kept + [(self.gap(among[j], b), int(among[j]))])
            found.update((min(a, b), max(a, b)) for _, a in kept[:JOIN_NEAREST])
        return sorted(found)


def _offers(points, normals, noise, near, pairs) -> list:
    """(mean evidence, a, b) of each of ``pairs`` (sorted (a, b)): the chords of the
    JOIN_PAIRS closest sample pairs seen from each side, all pairs' chords in one kernel call."""
    ends = []
    for a, b in pairs:
        for x, y in ((a, b), (b, a)):
            d, j = near.query(x, y)
            cols = np.argsort(d, kind="stable")[:JOIN_PAIRS]
            ends.append(np.column_stack([near.samples[y][cols], j[cols]]))
    evidence = _chord_evidence(points, normals, noise, np.concatenate(ends))
    stop = np.cumsum([len(e) for e in ends])[1::2]
    return [(float(np.mean(part)), a, b) for part, (a, b) in zip(np.split(evidence, stop[:-1]), pairs)]


def _chord_evidence(points, normals, noise, ends):
    """The signed evidence (:func:`core.kernels.sign_evidence.sign_evidence`, ``noise`` =
    (spread, gate)) of each chord ``ends[t] = (i, j)``: the kernel run on the 2 t points,
    each row paired with its partner."""
    spread, gate = noise
    rows = ends.reshape(-1)
    m = len(rows)
    graph = np.arange(m).reshape(-1, 2)[:, ::-1].reshape(-1)  # row 2t pairs with 2t + 1 and back
    idx = np.stack([np.arange(m), graph], axis=1)
    out = np.empty((m, 2))
    kern.sign_evidence(points[rows], normals[rows], spread[rows], np.empty(0), idx, np.ones(m, dtype=np.bool_),
                       gate, out, np.empty((0, 0), dtype=np.bool_), np.arange(m), False)
    return out[0::2, 1]
