"""The estimate runs on the points in spatial order and answers in the caller's order:
every number must be the one the caller's order gives (ties, orientation forests and
the thread count included), and the reordering helpers must be exact permutations."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import core
from core import neighbours, shapes, shapes_thin, spatial_order, stages
from core.kernels.permute import move_rows
from core.kernels.sign_evidence import strongest_first
from core.orientation import ORIENT_K, SORT_LEVELS, _evidence, orient

FIELDS = ("normals", "k1", "k2", "e1", "e2", "valid", "k_point", "outlier_score", "crease",
          "orientation_confidence")


def _unsorted(pts, k_max, *, progress=None, width=None):  # width: the whole lists, the reference
    return neighbours.search_neighbours(pts, k_max, progress=progress), None


def _same(a, b):
    for f in FIELDS:
        np.testing.assert_array_equal(np.asarray(getattr(a, f)), np.asarray(getattr(b, f)), err_msg=f)
    np.testing.assert_array_equal(a.neighbours.indices, b.neighbours.indices)
    np.testing.assert_array_equal(a.neighbours.distances, b.neighbours.distances)
    assert a.neighbours.points is a.points


def _clouds():
    rng = np.random.default_rng(7)
    grid = np.round(shapes.sphere(3000, seed=2).points * 12) / 12  # many ties between equal distances
    noisy = shapes.torus(3000, seed=3).points + rng.normal(scale=0.03, size=(3000, 3))
    return {"ties": grid, "noisy torus": noisy, "thin plate": shapes_thin.thin_plate(3000, seed=1).points,
            "two sheets": shapes_thin.two_sheets(3000, seed=1).points}


CLOUDS = _clouds()


@pytest.mark.parametrize("name", sorted(CLOUDS))
@pytest.mark.parametrize("orientation", ["auto", "propagate"])
def test_spatial_order_changes_no_number(name, orientation, monkeypatch):
    pts = CLOUDS[name]
    sorted_run = core.estimate(pts, k=15, orientation=orientation)
    monkeypatch.setattr(stages, "search_in_spatial_order", _unsorted)
    _same(sorted_run, core.estimate(pts, k=15, orientation=orientation))


def test_spatial_order_changes_no_number_with_k_auto(monkeypatch):
    pts = CLOUDS["noisy torus"]
    sorted_run = core.estimate(pts)
    monkeypatch.setattr(stages, "search_in_spatial_order", _unsorted)
    _same(sorted_run, core.estimate(pts))


def test_large_neighbour_arrays_are_reordered_in_place(monkeypatch):
    pts = CLOUDS["ties"]
    copied = core.estimate(pts, k=15)
    monkeypatch.setattr(spatial_order, "COPY_BYTES", 0)
    _same(copied, core.estimate(pts, k=15))


def test_sorted_search_is_the_plain_search_relabelled():
    pts = CLOUDS["ties"]
    plain = neighbours.search_neighbours(pts, 20)
    nb, order = neighbours.search_in_spatial_order(pts, 20)
    assert sorted(order) == list(range(len(pts))) and not np.array_equal(order, np.arange(len(pts)))
    np.testing.assert_array_equal(nb.points, pts[order])
    np.testing.assert_array_equal(order[nb.indices], plain.indices[order])
    np.testing.assert_array_equal(nb.distances, plain.distances[order])


def test_given_neighbours_still_work_and_agree():
    pts = CLOUDS["noisy torus"]
    nb = core.build_neighbours(pts, 20)
    a, b = core.estimate(pts, k=15), core.estimate(pts, k=15, neighbours=nb)
    for f in FIELDS:
        np.testing.assert_array_equal(np.asarray(getattr(a, f)), np.asarray(getattr(b, f)), err_msg=f)
    assert b.neighbours is nb


def test_given_neighbours_run_in_spatial_order(monkeypatch):
    """A caller's graph is copied into the kd-tree's leaf order (shuffled points ran the
    stages 1.5-2x slower in the caller's order); a result's graph is used as it is held;
    the numbers are those of the caller's order either way."""
    pts = CLOUDS["noisy torus"]
    plan = core.plan(len(pts), k=15)
    nb = core.build_neighbours(pts, 20)
    got, order = stages.spatial_neighbours(pts, plan, nb, None, sort_given=True)
    assert order.order is not None and not np.array_equal(order.order, np.arange(len(pts)))
    np.testing.assert_array_equal(got.points, pts[order.order])
    np.testing.assert_array_equal(order.order[got.indices], nb.indices[order.order])
    np.testing.assert_array_equal(got.distances, nb.distances[order.order])
    res = core.estimate(pts, k=15)
    held, held_order = stages.spatial_neighbours(pts, plan, res.neighbours, None, sort_given=True)
    assert held is res.neighbours.spatial()[0] and held_order.order is res.neighbours.spatial()[1]
    _same(res, core.estimate(pts, k=15, neighbours=res.neighbours))
    monkeypatch.setattr(spatial_order, "COPY_BYTES", 0)  # too large to copy: the caller's order
    assert stages.spatial_neighbours(pts, plan, nb, None, sort_given=True)[1].order is None
    same = core.estimate(pts, k=15, neighbours=nb)
    for f in FIELDS:
        np.testing.assert_array_equal(np.asarray(getattr(res, f)), np.asarray(getattr(same, f)), err_msg=f)


def test_results_do_not_depend_on_the_thread_count():
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread only")
    pts = CLOUDS["two sheets"]
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = core.estimate(pts, k=15)
        numba.set_num_threads(2)
        two = core.estimate(pts, k=15)
    finally:
        numba.set_num_threads(before)
    _same(one, two)


def test_duplicates_keep_the_caller_order():
    pts = np.vstack([CLOUDS["noisy torus"], np.repeat(CLOUDS["noisy torus"][:1], 300, axis=0)])
    nb, order = neighbours.search_in_spatial_order(pts, 15)
    assert order is None and nb.points is pts  # the duplicate-aware search, in the caller's order
    assert (nb.indices[:, 0] == np.arange(len(pts))).all()


@pytest.mark.parametrize("groups", [[1], [3, 300], [257, 2, 900]])
def test_largest_group_bound_is_at_least_the_largest_group(groups):
    rng = np.random.default_rng(len(groups))
    base = rng.random((len(groups) + 50, 3))
    pts = np.vstack([base[len(groups):]] + [np.repeat(base[i:i + 1], g, axis=0) for i, g in enumerate(groups)])
    pts[-1] = pts[-2] * -0.0 if groups == [1] else pts[-1]  # -0.0 and 0.0 are the same coordinate
    bound = neighbours._largest_group_bound(pts)
    assert bound >= max(groups)  # the duplicate-aware search is chosen exactly where a group is too large:
    assert bound <= (max(groups) + 1 if max(groups) > neighbours.MAX_DUPLICATES else neighbours.MAX_DUPLICATES)
    assert neighbours._largest_group_bound(np.array([[0.0, -0.0, 1.0], [-0.0, 0.0, 1.0]])) == 2


def test_orient_with_rank_matches_the_caller_order():
    s = shapes_thin.thin_plate(3000, seed=4)
    pts = s.points
    idx = core.build_neighbours(pts, 12).indices
    nrm = core.estimate(pts, k=12, orientation="keep").normals * np.where(np.arange(len(pts)) % 3, 1.0, -1.0)[:, None]
    perm = np.random.default_rng(0).permutation(len(pts))
    inverse = np.argsort(perm)
    for mode in ("outward", "propagate"):
        ref = orient(pts, nrm, idx, mode)
        got = orient(pts[perm], nrm[perm], inverse[idx[perm]], mode, rank=perm)
        np.testing.assert_array_equal(got.normals, ref.normals[perm])
        np.testing.assert_array_equal(got.confidence, ref.confidence[perm])


@pytest.mark.parametrize("shape", [(500,), (500, 3), (500, 1), (500, 0)])
@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.bool_, np.int32])
def test_to_caller_and_move_rows_are_the_numpy_permutation(shape, dtype):
    rng = np.random.default_rng(1)
    order = rng.permutation(500).astype(np.int32)
    a = (rng.random(shape) * 100).astype(dtype)
    ref = np.empty_like(a)
    ref[order] = a
    back = spatial_order.SpatialOrder(order)
    np.testing.assert_array_equal(back.to_caller(a), ref)
    np.testing.assert_array_equal(back.to_caller(np.asfortranarray(a)), ref)
    assert back.to_caller((a, 3.0))[1] == 3.0 and spatial_order.SpatialOrder(None).to_caller(a) is a
    if a.ndim == 2:
        moved = a.copy()
        move_rows(moved, order)
        np.testing.assert_array_equal(moved, ref)


def test_orientation_edges_are_taken_in_the_caller_order():
    """The spanning forest's input, edge by edge: the same evidence, the same first copies
    and the same order of equally strong edges whatever the order of the points."""
    rng = np.random.default_rng(5)
    pts = rng.random((2000, 3))
    nrm = rng.normal(size=(2000, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    graph = core.build_neighbours(pts, ORIENT_K).indices.astype(np.int64)
    ok = np.ones(len(pts), dtype=bool)
    perm = rng.permutation(len(pts))
    inverse = np.argsort(perm)
    ev, first = _evidence(pts, nrm, graph, ok, np.arange(len(pts)))
    ev_s, first_s = _evidence(pts[perm], nrm[perm], inverse[graph[perm]], ok[perm], perm)
    np.testing.assert_array_equal(ev_s, ev[perm])
    np.testing.assert_array_equal(first_s, first[perm])
    ei, ej, ew = strongest_first(ev, first, SORT_LEVELS, np.arange(len(pts)), graph)
    ei_s, ej_s, ew_s = strongest_first(ev_s, first_s, SORT_LEVELS, inverse, inverse[graph[perm]])
    np.testing.assert_array_equal(perm[ei_s], ei)
    np.testing.assert_array_equal(perm[ej_s], ej)
    np.testing.assert_array_equal(ew_s, ew)


@pytest.mark.parametrize("leaf", [1, 2, 32])
def test_kd_order_splits_every_range_at_its_middle_by_a_median(leaf):
    """core.kernels.kd_order: a permutation, the points moved with it, and every range the
    search tree halves (core.kernels.kdtree.build_tree) split by a plane along one axis:
    no point of the lower half beyond the upper half's lowest along that axis. Ties of
    equal coordinates (a rounded grid) included; the same order on one thread."""
    from core.kernels.kd_order import kd_order
    from core.kernels.kdtree import build_tree

    pts = np.round(shapes.torus(5000, seed=4).points * 8) / 8
    order, q = kd_order(pts, leaf)
    assert np.array_equal(np.sort(order), np.arange(len(pts))) and np.array_equal(q, pts[order])
    lo, hi, child, _ = build_tree(q, leaf)
    for node in np.flatnonzero(child >= 0):
        a, m, b = lo[node], hi[child[node]], hi[node]
        assert any(q[a:m, d].max() <= q[m:b, d].min() for d in range(3)), node
    assert (hi - lo)[child < 0].max() <= leaf
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        assert np.array_equal(kd_order(pts, leaf)[0], order)
    finally:
        numba.set_num_threads(before)


def test_kd_order_is_not_quadratic_on_a_back_and_forth_sweep():
    """A coordinate that rises then falls (a scanner sweeping back and forth) made a
    median-of-first-middle-last pivot quadratic: 111 s on 1M points against 0.4 s for
    random ones. Timed as a ratio of CPU times in one run (the least of 3 each: a loaded
    machine stretches wall times unevenly)."""
    import time

    from core.kernels.kd_order import kd_order

    n = 100_000
    t = np.arange(n, dtype=float)
    sweep = np.c_[np.r_[t[: n // 2], t[: n // 2][::-1]], t % 7, np.zeros(n)]
    scattered = np.random.default_rng(3).random((n, 3)) * [n, 7, 0]

    def fastest(p):
        kd_order(p[:100], 2)
        times = []
        for _ in range(3):
            start = time.process_time()
            kd_order(p, 2)
            times.append(time.process_time() - start)
        return min(times)

    assert fastest(sweep) < 10 * fastest(scattered)
