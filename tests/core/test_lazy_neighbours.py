"""A result's neighbours are converted from the estimate's spatial order on first access
(most callers never read them): the graph handed back must be the caller's, the same on
every read, and the conversion must never touch a graph a StageCache keeps."""

from __future__ import annotations

import pickle
import threading

import numpy as np
import pytest

import core
from core import shapes
from core.stage_cache import StageCache
from core.wide_neighbours import LazyNeighbours


@pytest.fixture(scope="module")
def torus():
    return shapes.torus(3000, seed=0).points


def _caller_graph(res, pts):
    nb = res.neighbours
    ref = core.build_neighbours(pts, nb.k_max)
    np.testing.assert_array_equal(nb.indices, ref.indices)
    np.testing.assert_array_equal(nb.distances, ref.distances)
    assert nb.matches(pts)  # with a cache: the points of the graph's first result (equal)


def test_neighbours_wait_for_the_first_read_then_stay(torus):
    res = core.estimate(torus, k=15)
    first = res.neighbours
    assert isinstance(first, LazyNeighbours) and first._made is None  # not converted yet
    assert isinstance(first, core.Neighbours) and res.neighbours is first and first.points is res.points
    np.testing.assert_array_equal(first.take(8)[0], core.build_neighbours(torus, 8).indices)  # served unconverted
    assert first._made is None
    _caller_graph(res, torus)
    again = core.estimate(torus, k=15, method="nf", neighbours=first)  # passable back
    np.testing.assert_array_equal(again.k1, core.estimate(torus, k=15, method="nf").k1)


def test_given_or_absent_neighbours_are_kept_as_they_are(torus):
    nb = core.build_neighbours(torus, 20)
    assert core.estimate(torus, k=15, neighbours=nb).neighbours is nb
    n = len(torus)
    bare = core.CurvatureResult(torus, torus, np.zeros(n), np.zeros(n), torus, torus, np.ones(n, bool), "nr", 15, 1)
    assert bare.neighbours is None
    with pytest.raises(AttributeError):
        bare.neighbours = nb  # frozen


def test_a_cached_graph_is_never_converted_in_place(torus):
    cache = StageCache(k_max=32)
    a = core.estimate(torus, k=15, cache=cache)
    b = core.estimate(torus, k=24, cache=cache)
    sorted_nb = cache._graph[1][0]
    before = sorted_nb.indices.copy()
    assert a.neighbours is b.neighbours  # one shared copy per graph
    np.testing.assert_array_equal(sorted_nb.indices, before)
    core.estimate(torus, k=40, cache=cache)  # the cache moves to a new graph: old results still resolve
    _caller_graph(a, torus)
    c = core.estimate(torus, k=40, cache=cache)
    _caller_graph(c, torus)
    fresh = core.estimate(torus, k=40)
    np.testing.assert_array_equal(core.estimate(torus, k=40, cache=cache).k1, fresh.k1)


def test_threads_reading_at_once_get_one_graph_and_pickling_converts(torus):
    res = core.estimate(torus, k=15)
    seen = []
    threads = [threading.Thread(target=lambda: seen.append(res.neighbours.indices)) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert all(nb is seen[0] for nb in seen)
    _caller_graph(res, torus)
    copy = pickle.loads(pickle.dumps(core.estimate(torus, k=15)))
    np.testing.assert_array_equal(copy.neighbours.indices, res.neighbours.indices)
