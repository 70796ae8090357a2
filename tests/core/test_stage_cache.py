"""core.estimate(..., cache=StageCache): the stages a change does not touch are re-used,
and the result is bit-identical to an estimate without a cache (issue 11)."""

import numpy as np
import pytest

from core import build_neighbours, estimate, shapes
from core.stage_cache import StageCache

_FIELDS = ("normals", "k1", "k2", "e1", "e2", "valid", "k_point", "outlier_score", "crease", "border",
           "orientation_confidence")


def _same(a, b):
    for name in _FIELDS:
        x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
        assert x.shape == y.shape and x.tobytes() == y.tobytes(), name  # bit-identical, NaN included
    assert a.params == b.params


@pytest.fixture(scope="module")
def torus():
    s = shapes.torus(1500, seed=4)
    rng = np.random.default_rng(0)
    return s.points + rng.normal(scale=0.01, size=s.points.shape)


@pytest.mark.parametrize("k", [15, "auto"])
def test_passes_only_change_reuses_every_early_stage_and_matches(torus, k):
    cache = StageCache()
    first = estimate(torus, k=k, passes=1, cache=cache)
    _same(first, estimate(torus, k=k, passes=1))
    second = estimate(torus, k=k, passes=3, cache=cache)
    _same(second, estimate(torus, k=k, passes=3))
    early = ["neighbours", "scores", "initial", "orientation", "scale"] + (["reference"] if k == "auto" else [])
    assert all(cache.computed[s] == 1 and cache.reused[s] == 1 for s in early), (cache.computed, cache.reused)
    assert not np.array_equal(first.normals, second.normals, equal_nan=True)  # the passes did change it


def test_changes_upstream_recompute_what_they_touch(torus):
    cache = StageCache()
    estimate(torus, k=15, cache=cache)
    estimate(torus, k=15, orientation="propagate", cache=cache)  # signs differ: orientation on
    assert cache.reused["initial"] == 1 and cache.computed["orientation"] == 2 and cache.computed["scale"] == 2
    estimate(torus, k=20, cache=cache)  # another k: another search and another scale
    assert cache.computed["neighbours"] == 2 and cache.computed["scale"] == 3
    moved = torus + 1e-3
    _same(estimate(moved, k=15, cache=cache), estimate(moved, k=15))  # another cloud: nothing re-used
    assert cache.computed["neighbours"] == 3 and cache.computed["initial"] == 3  # k=15, k=20, moved


def test_given_neighbours_and_normals_are_part_of_the_key(torus):
    s = shapes.torus(1500, seed=4)
    nb = build_neighbours(s.points, 32)
    cache = StageCache()
    a = estimate(s.points, s.normals, k=15, neighbours=nb, cache=cache)
    _same(a, estimate(s.points, s.normals, k=15, neighbours=nb))
    _same(estimate(s.points, -s.normals, k=15, neighbours=nb, cache=cache), estimate(s.points, -s.normals, k=15))
    assert cache.computed["initial"] == 2 and "neighbours" not in cache.computed  # the caller's graph, not searched
    estimate(s.points, s.normals, k=15, neighbours=build_neighbours(s.points, 32), cache=cache)  # a new graph
    assert cache.computed["initial"] == 3
    _same(estimate(s.points, s.normals, k=15, passes=3, neighbours=nb, cache=cache),
          estimate(s.points, s.normals, k=15, passes=3, neighbours=nb))
    assert cache.computed["initial"] == 4 and cache.reused["initial"] == 0
    estimate(s.points, s.normals, k=15, neighbours=nb, cache=cache)  # the same graph again: its stages kept
    assert cache.computed["initial"] == 4 and cache.reused["initial"] == 1
    with pytest.raises(ValueError, match="different points"):  # a kept graph is not taken for other points
        estimate(s.points + 1.0, k=15, neighbours=nb, cache=cache)


@pytest.mark.parametrize("given", [False, True])
def test_editing_a_result_never_changes_the_next_one_and_a_bad_cache_is_refused(torus, given):
    nb = build_neighbours(torus, 32) if given else None  # given neighbours: no spatial order, shared arrays
    cache = StageCache()
    res = estimate(torus, k=15, cache=cache, neighbours=nb)
    for name in ("k_point", "normals"):
        arr = getattr(res, name)
        if arr.flags.writeable:  # a copy (back from the spatial order)
            arr[0] = 3
        else:  # shared with the cache: editing it would change the next result
            with pytest.raises(ValueError):
                arr[0] = 3
    _same(estimate(torus, k=15, cache=cache, neighbours=nb), estimate(torus, k=15, neighbours=nb))
    with pytest.raises(ValueError, match="cache must be a core.stage_cache.StageCache"):
        estimate(torus, k=15, cache={})


def _grid():
    """A plane on a regular grid, slightly bent: every point has many neighbours at exactly
    equal distances (the ties a quantised scan has), where a k cut could differ."""
    u, v = np.meshgrid(np.arange(40.0), np.arange(40.0))
    pts = np.column_stack([u.ravel(), v.ravel(), 0.002 * (u.ravel() - 20.0) ** 2])
    return pts[np.random.default_rng(3).permutation(len(pts))]  # no order to lean on


@pytest.mark.parametrize("cloud", ["torus", "grid"])
def test_head_room_serves_every_k_up_to_k_max_in_spatial_order_and_matches(torus, cloud):
    pts = torus if cloud == "torus" else _grid()
    cache = StageCache(k_max=32)
    results = {k: estimate(pts, k=k, cache=cache) for k in (15, 24, 9, 32)}
    assert cache.computed["neighbours"] == 1 and cache.reused["neighbours"] == 3  # one search for all
    assert cache._graph[1][1].order is not None  # searched on the points in spatial order
    for k, res in results.items():
        _same(res, estimate(pts, k=k))  # bit-identical to a fresh estimate at that k
    assert results[15].neighbours is results[9].neighbours and results[15].neighbours.k_max == 32
    assert results[15].neighbours.matches(pts)  # the graph handed back is in the caller's order
    estimate(pts, k=40, cache=cache)  # beyond the head room: searched again, and kept instead
    assert cache.computed["neighbours"] == 2 and cache._graph[1][0].k_max == 40


def test_auto_k_beyond_the_head_room_and_keep_two_methods(torus):
    cache = StageCache(k_max=32, keep=2)
    auto = estimate(torus, k="auto", passes=2, cache=cache)
    fixed = estimate(torus, k=15, method="ct", cache=cache)  # within the auto search: not searched again
    assert cache.computed["neighbours"] == 1 and cache.reused["neighbours"] == 1
    again = estimate(torus, k="auto", passes=2, cache=cache)  # the first method's stages were kept
    assert cache.reused["scale"] == 1 and cache.reused["orientation"] >= 1
    _same(again, auto)
    _same(auto, estimate(torus, k="auto", passes=2))
    _same(fixed, estimate(torus, k=15, method="ct"))
    one = StageCache(k_max=32)  # keep=1: the compared method evicts the first one's stages
    for kw in (dict(k="auto", passes=2), dict(k=15, method="ct"), dict(k="auto", passes=2)):
        estimate(torus, cache=one, **kw)
    assert one.reused["scale"] == 0


def test_a_cached_scale_holds_for_any_constraint():
    """k="auto" shares its wide scale at anchors whatever eq. 22's constraint (core.anchors.shares_scale),
    so the cached choice of a projected fit is the one an "exact" fit makes afresh, and back."""
    s = shapes.torus(6000, seed=5)
    pts = s.points + np.random.default_rng(1).normal(scale=0.02, size=s.points.shape)  # noisy: k = 320 at anchors
    cache = StageCache()
    for constraint in ("project", "exact", "project"):
        _same(estimate(pts, options={"constraint": constraint}, cache=cache), estimate(pts, options={"constraint": constraint}))
    assert cache.computed["scale"] == 1 and cache.reused["scale"] == 2
