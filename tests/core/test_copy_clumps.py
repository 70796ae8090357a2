"""Places recorded many times with a jitter far below the spacing (core.duplicates): more
copies than any neighbourhood reaches, in some places or in all of them."""

import numpy as np
import pytest

from core import duplicates, estimate, shapes


def _clumps(places, copies, jitter, seed=0):
    rng = np.random.default_rng(seed)
    return np.repeat(places, copies, axis=0) + rng.normal(0.0, jitter, (len(places) * copies, 3))


@pytest.mark.parametrize("k", [15, "auto"])
def test_one_place_of_many_copies_in_a_clean_cloud_is_one_place(k):
    """300 copies of one place 1e-9 apart, 1.5 % of a sphere: below the share that used to
    start the search for copies, their fits ran on balls of rounding (|H| 6e9) and ruined
    the surface points around them, all reported valid."""
    s = shapes.sphere(5000, seed=1)
    cloud = np.concatenate([s.points, _clumps(s.points[:1], 300, 1e-9)])
    res = estimate(cloud, k=k)
    clean = estimate(s.points, k=k)  # the place is its first point, s.points[0]: the same cloud
    assert res.params["duplicates"] == 300 and res.valid.all()
    np.testing.assert_allclose(res.mean, np.concatenate([clean.mean, np.full(300, clean.mean[0])]), atol=1e-9)


@pytest.mark.parametrize("copies", [130, 300])
def test_every_place_of_more_copies_than_the_wider_search_is_one_place(copies):
    """Every place held more copies than the wider search's 8 k neighbours (120): |H| 1e10."""
    places = shapes.sphere(200, seed=2).points
    cloud = _clumps(places, copies, 1e-7)
    res = estimate(cloud, k=15)
    assert res.params["duplicates"] == len(cloud) - len(places)
    assert res.valid.all() and np.median(np.abs(res.mean - 1.0)) < 0.1


def test_a_small_dense_object_apart_from_the_rest_is_not_copies():
    """A sphere of radius 1e-4 (200 points) far from a unit sphere is sampled ~1000 times
    denser and lies alone: sampling, not copies."""
    big = shapes.sphere(5000, seed=3).points
    small = 1e-4 * shapes.sphere(200, seed=4).points + 10.0
    assert duplicates.near_copies(*_graph(np.concatenate([big, small]))) is None


def test_a_stray_point_far_away_does_not_make_a_cloud_look_clumped(monkeypatch):
    """A georeferenced sphere and one point at the origin: the span of all the points made
    the sphere's spacing look like copies', and paid a search of 120 neighbours (2 GB at 1M)."""
    pts = np.concatenate([shapes.sphere(3000, seed=5).points + [5e5, 4e6, 300.0], [[0.0, 0.0, 0.0]]])
    wide = []
    monkeypatch.setattr(duplicates, "_wider", lambda *a: wide.append(a) or pytest.fail("wide search"))
    assert duplicates.near_copies(*_graph(pts)) is None and not wide


def _graph(points, k=15):
    from scipy.spatial import cKDTree

    dist, idx = cKDTree(points).query(points, k=k)
    return idx, dist, points
