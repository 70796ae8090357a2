"""Orientation across tiles: tiles orient their normals independently (Hoppe et al. 1992
propagation inside the tile and its halo), then agree by their overlaps.

Each connected part of a tile's own points is a node. A halo point is oriented both by
the tile that owns it and by the tile that sees it in its halo: each such point votes
"same" or "opposite" on the edge between the two nodes. Signs are fixed along a maximum
spanning tree of that graph (the strongest agreements first, as Hoppe's tree follows the
most parallel normals), then each connected part of the whole cloud gets the in-memory
rule (:func:`core.orientation.orient`): "outward" by a vote of its points farthest from
the cloud's centre, "propagate" so that its highest point's normal points up (+z).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree

from ..orientation import (STRAY_RMS, VOTE_BINS, centre_beside, far_facing, floors_up, normal_sums, outer_reach,
                           reach_histogram)
from .store import TileStore

_CHUNK = 1_000_000


def tile_signs(store: TileStore, n_tiles: int, rule: str):
    """+1/-1 per connected part of each tile, and the share of halo points that agree.

    Returns ``(signs, agreement)``: ``signs[t]`` is a (C_t,) array aligned with the
    tile's ``.nodes`` rows; ``agreement`` is the fraction of halo votes that agree once
    the signs are applied (1.0 when there are none).
    """
    nodes = [np.asarray(store.load_result(t, ".nodes", mmap=False)) for t in range(n_tiles)]
    offset = np.concatenate([[0], np.cumsum([len(n) for n in nodes])])
    n_nodes = int(offset[-1])
    if rule == "none" or n_nodes == 0:
        return [np.ones(len(n)) for n in nodes], 1.0
    u, v, w = _votes(store, nodes, offset)
    graph = coo_matrix((w, (u, v)), shape=(n_nodes, n_nodes)).tocsr()
    parity = _spanning_parity(graph, n_nodes)
    votes = float(np.abs(w).sum())  # none with one tile, or tiles whose halos hold no oriented point
    agree = float(np.sum(np.abs(w)[(w * parity[u] * parity[v]) > 0])) / votes if votes else 1.0
    _, part = connected_components(graph, directed=False)
    flat = np.concatenate(nodes)
    if rule == "outward":
        parity *= _outward(store, nodes, offset, flat, part, parity)
    elif rule == "propagate":
        parity *= _upward(flat, part, parity)
    else:
        raise ValueError(f"orientation rule {rule!r} is invalid; must be none, outward or propagate")
    return [parity[offset[t]:offset[t + 1]] for t in range(n_tiles)], agree


def _node_of(nodes_t, offset_t, comp):
    """Global node ids of ``comp`` labels in one tile (-1 where the label has no own points)."""
    if len(nodes_t) == 0:
        return np.full(len(comp), -1, dtype=np.int64)
    pos = np.minimum(np.searchsorted(nodes_t["comp"], comp), len(nodes_t) - 1)
    return np.where(nodes_t["comp"][pos] == comp, offset_t + pos, -1)


def _votes(store, nodes, offset):
    """Edges (u, v, +1 same / -1 opposite) from every halo point seen by two tiles."""
    us, vs, ws = [], [], []
    for b in range(len(nodes)):
        links = np.asarray(store.load_result(b, ".links", mmap=False))
        for a in np.unique(links["owner"]):
            mine = links[links["owner"] == a]
            rows = store.load_result(int(a))
            pos = np.searchsorted(rows["index"], mine["index"])
            pos = np.minimum(pos, len(rows) - 1)
            found = rows["index"][pos] == mine["index"]
            mine, pos = mine[found], pos[found]
            ua = _node_of(nodes[a], offset[a], rows["comp"][pos])
            ub = _node_of(nodes[b], offset[b], mine["comp"])
            dot = np.einsum("ij,ij->i", rows["n"][pos], mine["n"])
            ok = (ua >= 0) & (ub >= 0) & np.isfinite(dot) & (dot != 0)
            us.append(ua[ok])
            vs.append(ub[ok])
            ws.append(np.sign(dot[ok]))
    if not us:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    return np.concatenate(us), np.concatenate(vs), np.concatenate(ws)


def _spanning_parity(graph, n_nodes) -> np.ndarray:
    """+1/-1 per node so that the maximum spanning tree's edges agree."""
    sym = graph + graph.T
    sym.data = np.where(sym.data == 0, 0.5, sym.data)  # a tied vote still connects the parts
    cost = sym.copy()
    cost.data = 1.0 / (1.0 + np.abs(cost.data))  # strongest agreement = cheapest edge
    tree = minimum_spanning_tree(cost)
    tree = tree + tree.T
    parity = np.ones(n_nodes)
    seen = np.zeros(n_nodes, bool)
    for root in range(n_nodes):
        if seen[root]:
            continue
        order, pred = breadth_first_order(tree, root, directed=False, return_predecessors=True)
        seen[order] = True
        for node in order[1:]:
            parity[node] = parity[pred[node]] * np.sign(sym[pred[node], node])
    return parity


def _upward(flat, part, parity) -> np.ndarray:
    """Flip each part so its highest point (lowest input row among equals) faces +z."""
    flip = np.ones(len(flat))
    for p in np.unique(part):
        members = np.flatnonzero(part == p)
        best = members[np.lexsort((flat["top_index"][members], -flat["top_z"][members]))[0]]
        if flat["top_nz"][best] * parity[best] < 0:
            flip[members] = -1.0
    return flip


def _outward(store, nodes, offset, flat, part, parity) -> np.ndarray:
    """Flip each part as :func:`core.orientation.orient` does in memory: a vote of its
    outer half by distance from the cloud's centre (:func:`core.orientation.far_facing`), each
    weighted by how squarely its normal faces away from the centre; open level parts face up
    (:func:`core.orientation.floors_up`, on their normals summed over the tiles)."""
    n_parts = int(part.max()) + 1
    counts = np.bincount(part, flat["count"], n_parts)
    kept, centre = _strays_out(store, nodes, offset, flat["sum"].sum(axis=0) / max(float(counts.sum()), 1.0))
    square, kept_counts, offsets = np.zeros(n_parts), np.zeros(n_parts), np.zeros((n_parts, 3))
    for chunk, node, k in kept():
        square += np.bincount(part[node[k]], np.sum((chunk["xyz"][k] - centre) ** 2, axis=1), n_parts)
        kept_counts += np.bincount(part[node[k]], minlength=n_parts)
        offsets += normal_sums(chunk["xyz"][k] - centre, part[node[k]], n_parts)
    rms = np.sqrt(square / np.maximum(kept_counts, 1))
    hist = np.zeros((n_parts, VOTE_BINS), dtype=np.int64)
    for chunk, node, k in kept():
        hist += reach_histogram(np.linalg.norm(chunk["xyz"][k] - centre, axis=1), rms, part[node[k]], n_parts)
    reach = outer_reach(hist) * rms
    vote = np.zeros(n_parts)
    sums = np.zeros((n_parts, 3))
    for chunk, node, k in kept():
        far, facing = far_facing(chunk["xyz"][k] - centre, chunk["n"][k], reach[part[node[k]]])
        voters = node[k][far]
        vote += np.bincount(part[voters], facing * parity[voters], n_parts)
        sums += normal_sums(chunk["n"] * parity[node][:, None], part[node], n_parts)
    vote = floors_up(vote, sums, counts, centre_beside(sums, offsets, square, kept_counts))
    return np.where(vote[part] < 0, -1.0, 1.0)


def _strays_out(store, nodes, offset, centre):
    """``(kept, centre)``: the chunks of :func:`_own_chunks` with a mask of the points that
    are no strays (:data:`core.orientation.STRAY_RMS`), and their centre, as
    :func:`core.orientation.orient` finds them in memory."""
    square, n, farthest = 0.0, 0, 0.0
    for chunk, _ in _own_chunks(store, nodes, offset):
        d2 = np.sum((chunk["xyz"] - centre) ** 2, axis=1)
        square, n, farthest = square + float(d2.sum()), n + len(d2), max(farthest, float(d2.max(initial=0.0)))
    limit = STRAY_RMS ** 2 * square / max(n, 1)

    def kept():
        for chunk, node in _own_chunks(store, nodes, offset):
            yield chunk, node, np.sum((chunk["xyz"] - centre) ** 2, axis=1) <= limit

    if farthest <= limit:  # none: the centre as it was (the in-memory run does not recompute it either)
        return kept, centre
    total, m = np.zeros(3), 0
    for chunk, _, k in kept():
        total += chunk["xyz"][k].sum(axis=0)
        m += int(k.sum())
    return kept, total / max(m, 1)


def _own_chunks(store, nodes, offset):
    """(rows, global node id) of every tile's own points that have a normal, in chunks."""
    for t in range(len(nodes)):
        rows = store.load_result(t)
        for start in range(0, len(rows), _CHUNK):
            chunk = rows[start:start + _CHUNK]
            node = _node_of(nodes[t], offset[t], chunk["comp"])
            have = node >= 0
            yield chunk[have], node[have]
