"""Exact duplicate points are estimated once, at their position (core.duplicates)."""

import numpy as np
import pytest

from core import estimate, shapes
from core.duplicates import find_duplicates
from core.kernels.repeats import any_repeated


def _copies(points, times, seed=0):
    """``points`` each repeated ``times`` times, shuffled; returns (cloud, position of each row)."""
    rng = np.random.default_rng(seed)
    position = rng.permutation(np.repeat(np.arange(len(points)), times))
    return points[position], position


@pytest.mark.parametrize("k", ["auto", 15])
def test_copies_get_their_positions_answer(k):
    """Every point of a sphere 3 times over: before, the default's H error was 4.2 on a torus
    (a cubic on 15 neighbours that were 5 places); now every copy has the distinct cloud's answer."""
    s = shapes.sphere(3000, radius=2.0, seed=1)
    cloud, position = _copies(s.points, 3)
    res = estimate(cloud, k=k)
    merged = find_duplicates(cloud)
    alone = estimate(merged.points, k=k)
    np.testing.assert_array_equal(res.k1, alone.k1[merged.inverse])
    np.testing.assert_array_equal(res.normals, alone.normals[merged.inverse])
    np.testing.assert_array_equal(res.valid, alone.valid[merged.inverse])
    assert res.params["duplicates"] == 6000 and res.params["n_points"] == 9000 and len(res) == 9000
    assert res.valid.all()
    assert abs(np.median(res.mean) - 0.5) < (0.01 if k == "auto" else 0.03)  # k = 1/R, outward normals
    np.testing.assert_array_equal(res.points, cloud)


def test_copies_rows_are_equal_and_each_copy_is_first_in_its_row():
    s = shapes.torus(2000, seed=2)
    cloud, position = _copies(s.points, 2, seed=3)
    res = estimate(cloud, k=15)
    a, b = (np.flatnonzero(position == position[0]))
    assert res.k1[a] == res.k1[b] and (res.e1[a] == res.e1[b]).all()
    idx, dist = res.neighbours.take(15)
    assert (idx[:, 0] == np.arange(len(cloud))).all()
    assert (dist[:, 1] > 0).all()  # a copy is not its own neighbour
    assert not np.isin(b, idx[a, 1:])
    again = estimate(cloud, k=15, neighbours=res.neighbours)
    np.testing.assert_array_equal(again.k1, res.k1)
    assert res.border.shape == res.anisotropy.shape == (len(cloud),)


def test_no_copies_no_merge_and_signed_zeros_are_one_place():
    pts = shapes.sphere(500, seed=0).points
    assert find_duplicates(pts) is None
    assert "duplicates" not in estimate(pts, k=15).params
    zeros = np.array([[0.0, 0.0, 0.0], [-0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    assert find_duplicates(zeros).copies == 1


@pytest.mark.parametrize("n, repeats", [(10, 1), (1000, 1), (1000, 37), (100_000, 1)])
def test_the_screen_finds_every_repeat(n, repeats):
    rng = np.random.default_rng(n + repeats)
    h = rng.integers(0, 2**63, size=n, dtype=np.uint64) * np.uint64(2) + np.uint64(1)
    assert not any_repeated(h)
    for _ in range(repeats):
        h[rng.integers(n)] = h[rng.integers(n)]
    assert any_repeated(h) == (len(np.unique(h)) < n)
    assert any_repeated(np.zeros(2, dtype=np.uint64))


def test_given_normals_are_the_first_copys_and_dropped_rows_counted():
    s = shapes.sphere(1000, seed=4)
    cloud = np.concatenate([s.points, s.points[:10], [[np.nan, 0.0, 0.0]]])
    normals = np.concatenate([s.normals, -s.normals[:10], [[0.0, 0.0, 1.0]]])
    res = estimate(cloud, normals, k=15, drop_nonfinite=True)
    assert res.params["duplicates"] == 10 and res.params["dropped"] == 1 and len(res) == 1010
    np.testing.assert_array_equal(res.normals[1000:], res.normals[:10])  # the copies' own normals were flipped
    assert (np.einsum("ij,ij->i", res.normals[:10], s.normals[:10]) > 0.99).all()


def test_too_few_places_is_invalid_not_a_crash_and_k_beyond_them_is_named():
    three = np.repeat([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], 50, axis=0)
    res = estimate(three)
    assert not res.valid.any() and len(res) == 150 and res.params["duplicates"] == 147
    assert "fewer than" in res.params["degenerate"]
    cloud, _ = _copies(shapes.sphere(40, seed=0).points, 3)
    with pytest.raises(ValueError, match="k=60 exceeds the 40 distinct positions"):
        estimate(cloud, k=60)


def test_a_viewers_cache_merges_once_and_serves_the_copies_stages():
    from core.stage_cache import StageCache

    cloud, _ = _copies(shapes.sphere(2000, seed=5).points, 2)
    cache = StageCache()
    a = estimate(cloud, k=15, passes=1, cache=cache)
    b = estimate(cloud, k=15, passes=3, cache=cache)
    assert cache.computed["merged"] == 1 and cache.reused["merged"] == 1
    assert cache.reused["initial"] == 1  # the distinct cloud's stages are kept between the calls
    np.testing.assert_array_equal(a.normals.shape, b.normals.shape)
    np.testing.assert_array_equal(estimate(cloud, k=15, passes=3).k1, b.k1)


def _twins(points, gap, seed=0):
    """Every point twice, the second ``gap`` away in a random direction; shuffled."""
    rng = np.random.default_rng(seed)
    step = rng.normal(size=points.shape)
    twins = points + gap * step / np.linalg.norm(step, axis=1, keepdims=True)
    order = rng.permutation(2 * len(points))
    return np.concatenate([points, twins])[order], order


def test_near_copies_are_one_place():
    """A point written twice with float32 rounding lies ~1e-5 of a spacing from itself: the
    default's H error on a torus went 1e-4 -> 0.08 with every point so doubled."""
    s = shapes.torus(6000, seed=1)
    alone = estimate(s.points)
    cloud, order = _twins(s.points, 1e-6)
    res = estimate(cloud)
    assert res.params["duplicates"] == 6000 and res.valid.all()
    truth = np.concatenate([s.mean, s.mean])[order]
    err, err_alone = np.mean(np.abs(res.mean - truth)), np.mean(np.abs(alone.mean - s.mean))
    assert err < 1.5 * err_alone < 1e-3
    np.testing.assert_array_equal(res.points, cloud)


def test_near_copies_with_a_cache_are_found_once():
    from core.stage_cache import StageCache

    cloud, _ = _twins(shapes.sphere(2000, seed=6).points, 1e-7)
    cache = StageCache()
    a = estimate(cloud, k=15, passes=1, cache=cache)
    b = estimate(cloud, k=15, passes=2, cache=cache)
    assert a.params["duplicates"] == b.params["duplicates"] == 2000
    assert cache.computed["merged"] == 1 and cache.reused["merged"] == 1 and cache.reused["initial"] == 1


@pytest.mark.parametrize("shape", ["graded", "range_scan"])
def test_dense_sampling_is_not_taken_for_copies(shape):
    pts = getattr(shapes, shape)(6000, seed=0).points
    assert "duplicates" not in estimate(pts, k=15).params


def test_a_few_near_twins_are_left_alone():
    """Below 1 % of the points (random sampling leaves ~1e-5 that close) nothing is redone."""
    s = shapes.sphere(4000, seed=2)
    cloud = np.concatenate([s.points, s.points[:15] + 1e-7])  # 30 of 4015 points have a twin
    res = estimate(cloud, k=15)
    assert "duplicates" not in res.params and res.valid.all()
    clean = estimate(s.points, k=15)
    assert abs(np.median(res.mean) - np.median(clean.mean)) < 1e-3


@pytest.mark.parametrize("k", [15, "auto"])
@pytest.mark.parametrize("copies", [16, 40])
def test_places_of_more_copies_than_k_are_one_place(k, copies):
    """With k copies or more at every place (1e-7 apart) the k nearest all lie in the
    place, and the near-copy test measured against the k-th of them: the fits ran on balls
    of rounding, |H - 1| 6e5 on a unit sphere, every point valid. The copies are now told
    on a wider search (core.duplicates._clumped)."""
    places = shapes.sphere(1500, seed=4).points
    rng = np.random.default_rng(0)
    cloud = np.repeat(places, copies, axis=0) + rng.normal(0.0, 1e-7, (len(places) * copies, 3))
    res = estimate(cloud, k=k)
    assert res.params["duplicates"] == len(cloud) - len(places)
    assert res.valid.all() and np.median(np.abs(np.abs(res.mean) - 1.0)) < 0.05


def test_a_dense_cluster_is_not_taken_for_copies():
    """A blob of 2 % of the points, some 500 times denser than the rest, is sampling, not
    copies."""
    s = shapes.sphere(5000, seed=3)
    rng = np.random.default_rng(1)
    blob = s.points[0] + rng.normal(0.0, 1e-4, (100, 3))
    assert "duplicates" not in estimate(np.concatenate([s.points, blob]), k=15).params


@pytest.mark.parametrize("places, copies", [(16, 2), (20, 15), (25, 5)])
def test_fewer_places_than_the_border_test_reads_are_estimated(places, copies):
    """16-29 places with copies: the border test's second reading asked the places' graph
    for its 30 nearest and raised "k=30 exceeds the cached neighbourhood size"."""
    rng = np.random.default_rng(0)
    u, v = rng.uniform(-1, 1, (2, places))
    cloud = np.repeat(np.column_stack([u, v, 0.3 * u * u - 0.2 * v * v]), copies, axis=0)
    res = estimate(cloud, k=15)
    assert res.params["duplicates"] == places * (copies - 1) and len(res.border) == len(cloud)
