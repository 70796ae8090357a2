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
