"""The spatial-order search (core.kernels.kdtree) must give, row for row and bit for bit,
the canonical k nearest: by (distance, the caller's index), distances as cKDTree computes
them, the point itself first; on clouds built to break it (ties, copies, gaps, density
jumps, k = N) and whatever the thread count."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from scipy.spatial import cKDTree

from core import neighbours, noise, shapes
from core.kernels.kdtree import build_tree, query_sorted
from core.tuning import SEARCH_REACH


def _brute(pts, k):
    """Numpy reference in the caller's order: per row lexsort by (distance, index)."""
    n = len(pts)
    idx, dist = np.empty((n, k), dtype=np.int64), np.empty((n, k))
    for i in range(n):
        diff = pts - pts[i]
        d = np.sqrt(((diff[:, 0] * diff[:, 0]) + diff[:, 1] * diff[:, 1]) + diff[:, 2] * diff[:, 2])
        order = np.lexsort((np.arange(n), d))[:k]
        if order[0] != i:  # the point itself first (it ties with its copies at distance 0)
            order = np.concatenate(([i], order[order != i]))[:k]
        idx[i], dist[i] = order, d[order]
    return idx, dist


def _clouds():
    rng = np.random.default_rng(3)
    torus = shapes.torus(1500, seed=1).points
    line = np.zeros((600, 3))
    line[:, 0] = np.arange(600) // 4  # groups of 4 copies on a line: ties everywhere
    far = np.concatenate([rng.random((700, 3)) * 0.01, rng.random((700, 3)) * 0.01 + 1e6])  # a huge gap
    dense = np.concatenate([rng.random((1000, 3)) * [1, 1, 0.01], rng.random((300, 3)) * [30, 30, 0.01] + [1, 0, 0]])
    return {"noisy torus": noise.add_noise(torus, 0.3, seed=2), "quantised torus": np.round(torus * 8) / 8,
            "copies on a line": line, "two clusters 1e6 apart": far, "density 100:1": dense,
            "grid": np.stack(np.meshgrid(np.arange(12), np.arange(12), np.arange(9)), -1).reshape(-1, 3) * 0.5}


CLOUDS = _clouds()


@pytest.mark.parametrize("name", sorted(CLOUDS))
@pytest.mark.parametrize("k", [1, 7, 40])
def test_spatial_search_is_the_canonical_k_nearest(name, k):
    pts = np.ascontiguousarray(CLOUDS[name], dtype=float)
    nb, order = neighbours.search_in_spatial_order(pts, k)
    assert order is not None
    ref_idx, ref_dist = _brute(pts, k)
    back = np.asarray(order)[nb.indices]  # sorted indices -> the caller's
    np.testing.assert_array_equal(back, ref_idx[order])
    np.testing.assert_array_equal(nb.distances, ref_dist[order])
    np.testing.assert_array_equal(nb.points, pts[order])


@pytest.mark.parametrize("name", ["quantised torus", "copies on a line", "noisy torus"])
def test_spatial_search_matches_the_kdtree_search(name):
    pts = np.ascontiguousarray(CLOUDS[name], dtype=float)
    k = 30
    nb, order = neighbours.search_in_spatial_order(pts, k)
    plain = neighbours.search_neighbours(pts, k)
    np.testing.assert_array_equal(np.asarray(order)[nb.indices], plain.indices[order])
    np.testing.assert_array_equal(nb.distances, plain.distances[order])


def test_k_equal_to_n_and_a_single_point():
    pts = np.ascontiguousarray(CLOUDS["grid"][:50], dtype=float)
    nb, order = neighbours.search_in_spatial_order(pts, 50)
    ref_idx, ref_dist = _brute(pts, 50)
    np.testing.assert_array_equal(np.asarray(order)[nb.indices], ref_idx[order])
    nb1, _ = neighbours.search_in_spatial_order(pts[:1], 1)
    assert nb1.indices.tolist() == [[0]] and nb1.distances.tolist() == [[0.0]]


def test_search_does_not_depend_on_the_thread_count():
    pts = np.ascontiguousarray(CLOUDS["noisy torus"], dtype=float)
    order = cKDTree(pts).indices
    p = np.ascontiguousarray(pts[order])
    tree = build_tree(p, 16)
    outs = []
    before = numba.get_num_threads()
    try:
        for threads in (1, before):
            numba.set_num_threads(threads)
            dist, idx = np.empty((len(p), 25)), np.empty((len(p), 25), dtype=np.int64)
            query_sorted(p, tree, order.astype(np.int64), 0, dist, idx, 64, SEARCH_REACH)
            outs.append((dist, idx))
    finally:
        numba.set_num_threads(before)
    np.testing.assert_array_equal(outs[0][0], outs[1][0])
    np.testing.assert_array_equal(outs[0][1], outs[1][1])


def test_tree_nodes_hold_their_points():
    p = np.ascontiguousarray(CLOUDS["density 100:1"], dtype=float)
    lo, hi, child, box = build_tree(p, 16)
    covered = np.zeros(len(p), dtype=int)
    for node in range(len(lo)):
        inside = p[lo[node]:hi[node]]
        assert (inside >= box[node, :3]).all() and (inside <= box[node, 3:]).all()
        if child[node] < 0:
            assert hi[node] - lo[node] <= 16
            covered[lo[node]:hi[node]] += 1
        else:
            c = child[node]
            assert (lo[c], hi[c + 1], hi[c]) == (lo[node], hi[node], lo[c + 1])
    assert (covered == 1).all()
