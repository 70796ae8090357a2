"""Degenerate clouds: valid=False with the reason, never a crash or a made-up number;
many duplicate points do not make the neighbour search quadratic."""

from __future__ import annotations

import time

import numpy as np
import pytest

import core
from core import neighbours, shapes


@pytest.fixture(scope="module")
def sphere():
    return shapes.sphere(400, seed=3)


def _all_invalid(res, n, reason):
    assert len(res) == n and not res.valid.any()
    assert np.isnan(res.k1).all() and np.isnan(res.mean).all() and np.isnan(res.e1).all()
    assert reason in res.params["degenerate"]


@pytest.mark.parametrize("k", ["auto", 15])
def test_identical_points_invalid(k):
    _all_invalid(core.estimate(np.zeros((100, 3)), k=k), 100, "identical")
    _all_invalid(core.estimate(np.full((50, 3), 7.25), k=k), 50, "identical")


@pytest.mark.parametrize("factor, reason", [(1e300, "exceed"), (1e160, "exceed"), (1e-300, "spans only"),
                                            (1e-200, "spans only")])
@pytest.mark.parametrize("k", ["auto", 15])
def test_extreme_scale_invalid(sphere, factor, reason, k):
    _all_invalid(core.estimate(sphere.points * factor, k=k), 400, reason)


def test_offset_beyond_float_resolution_invalid(sphere):
    _all_invalid(core.estimate(sphere.points * 1e-6 + 1e7, k=15), 400, "spans only")


@pytest.mark.parametrize("factor", [1e-140, 1e140])
def test_large_but_representable_scale_is_right(sphere, factor):
    res = core.estimate(sphere.points * factor, k=15)
    assert res.valid.all()
    np.testing.assert_allclose(np.median(res.mean) * factor, 1.0, rtol=0.05)


@pytest.mark.parametrize("k", ["auto", 3, 15])
def test_three_points_are_not_a_surface(sphere, k):
    res = core.estimate(sphere.points[:3], k=k)
    _all_invalid(res, 3, "fewer than")


def test_given_normals_kept_on_degenerate_cloud():
    nrm = np.tile([0.0, 0.0, 2.0], (20, 1))
    res = core.estimate(np.zeros((20, 3)), nrm, k=10)
    np.testing.assert_allclose(res.normals, np.tile([0.0, 0.0, 1.0], (20, 1)))


@pytest.mark.parametrize("scale", [1e300, 1e-9])
def test_huge_or_small_given_normals_normalised(sphere, scale):
    res = core.estimate(sphere.points, sphere.normals * scale, k=15)
    assert res.valid.all()
    np.testing.assert_allclose(np.median(res.mean), 1.0, rtol=0.05)
    np.testing.assert_allclose(np.linalg.norm(res.normals, axis=1), 1.0)


def test_zero_and_tiny_normals(sphere):
    """A zero row is repaired (issue 12: estimated from its neighbours); a file whose
    normals are all tiny is merely unscaled."""
    nrm = sphere.normals.copy()
    nrm[5] = 0.0
    res = core.estimate(sphere.points, nrm, k=15)
    assert res.valid.all() and res.params["normals_repaired"]["estimated"] == 1
    assert np.dot(res.normals[5], sphere.normals[5]) > 0.99
    res = core.estimate(sphere.points, sphere.normals * 1e-300, k=15)
    assert res.valid.all() and res.params["normals_repaired"]["renormalised"] == len(sphere.points)
    np.testing.assert_allclose(np.median(res.mean), 1.0, rtol=0.05)


def test_check_int_empty_range_message():
    from core._validate import check_int

    with pytest.raises(ValueError, match="no value is allowed"):
        check_int(3, name="k", low=4, high=3)


@pytest.fixture
def dup_cloud():
    rng = np.random.default_rng(0)
    base = rng.random((1500, 3))
    pts = np.vstack([base, np.repeat(base[:4], [300, 2, 500, 40], axis=0), np.zeros((700, 3))])
    return pts[rng.permutation(len(pts))]


@pytest.mark.parametrize("k", [1, 7, 30])
def test_duplicate_search_matches_plain_search(dup_cloud, k, monkeypatch):
    monkeypatch.setattr(neighbours, "MAX_DUPLICATES", 10**9)
    plain = neighbours.build_neighbours(dup_cloud, k)
    monkeypatch.setattr(neighbours, "MAX_DUPLICATES", 1)
    grouped = neighbours.build_neighbours(dup_cloud, k)
    np.testing.assert_array_equal(grouped.indices[:, 0], np.arange(len(dup_cloud)))
    np.testing.assert_array_equal(grouped.distances, plain.distances)
    assert all(len(set(row)) == k for row in grouped.indices)  # distinct neighbours
    d = np.linalg.norm(dup_cloud[grouped.indices] - dup_cloud[:, None], axis=2)
    np.testing.assert_allclose(d, grouped.distances, atol=1e-15)


def test_many_duplicates_not_quadratic():
    pts = np.vstack([np.zeros((60_000, 3)), np.random.default_rng(1).random((2000, 3))])
    t0 = time.perf_counter()
    nb = neighbours.build_neighbours(pts, 20)
    assert time.perf_counter() - t0 < 5.0  # the plain kd-tree search takes ~10 s here
    assert (nb.distances[:60_000] == 0).all()
    res = core.estimate(pts, k=20, neighbours=nb)  # the copies are one place (core.duplicates): nb is not used
    assert res.params["duplicates"] == 59_999 and res.valid[60_000:].mean() > 0.9
    np.testing.assert_array_equal(res.k1[:60_000], np.full(60_000, res.k1[0]))


@pytest.mark.parametrize("k", [15, "auto"])
def test_collinear_cloud_invalid_with_reason(k):
    t = np.linspace(-1.0, 2.0, 300)
    line = np.c_[t, 3 * t + 1, -2 * t] @ np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))[0]
    _all_invalid(core.estimate(line, k=k), 300, "straight line")


def test_thin_but_honest_cloud_is_not_called_a_line():
    rng = np.random.default_rng(4)
    t, a = rng.uniform(0, 1000, 3000), rng.uniform(0, 2 * np.pi, 3000)
    tube = np.c_[t, np.cos(a), np.sin(a)]  # 1000:1, still a surface
    assert "degenerate" not in core.estimate(tube, k=15).params


def test_bounds_kernel_is_numpys_min_and_max():
    """core.kernels.bounds (the degenerate check's bounding box in one pass) gives
    ``points.min(axis=0)``, ``points.max(axis=0)``: on one point, on signed values and on
    extremes of the float range."""
    from core.kernels.bounds import bounds

    rng = np.random.default_rng(3)
    clouds = [rng.normal(size=(1, 3)), rng.normal(size=(1000, 3)) * [1e-300, 1.0, 1e300],
              np.array([[0.0, -0.0, 5.0], [-1.0, 2.0, 5.0], [3.0, -7.0, 5.0]])]
    for pts in clouds:
        lo, hi = np.empty(3), np.empty(3)
        bounds(pts, lo, hi)
        np.testing.assert_array_equal(lo, pts.min(axis=0))
        np.testing.assert_array_equal(hi, pts.max(axis=0))
