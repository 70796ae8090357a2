"""Degenerate clouds: valid=False with the reason, never a crash or a made-up number;
many duplicate points do not make the neighbour search quadratic."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import core
from core import degenerate, neighbours, shapes
from io_testutils import cpu_seconds


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


@pytest.mark.parametrize("factor, reason", [(1e300, "exceed"), (1e160, "exceed"), (1e40, "exceed"), (1e-300, "spans only"),
                                            (1e-200, "spans only"), (1e-40, "spans only")])
@pytest.mark.parametrize("k", ["auto", 15])
def test_extreme_scale_invalid(sphere, factor, reason, k):
    _all_invalid(core.estimate(sphere.points * factor, k=k), 400, reason)


def test_offset_beyond_float_resolution_invalid(sphere):
    _all_invalid(core.estimate(sphere.points * 1e-6 + 1e7, k=15), 400, "spans only")


@pytest.fixture(scope="module")
def noisy_torus():
    return shapes.torus(3000, seed=1).points + np.random.default_rng(2).normal(scale=0.01, size=(3000, 3))


@pytest.mark.parametrize("k", ["auto", 15])
@pytest.mark.parametrize("power", [-95, 95])
def test_every_output_scales_exactly_inside_the_bounds(noisy_torus, power, k):
    """A cloud scaled by 2^power (coordinates ~1e29, extent ~1e-28: inside MAX_COORD and
    MIN_EXTENT) gives the same bits, lengths and curvatures scaled exactly: no step of the
    estimate overflows or underflows there (the outlier scores did from 2^-125 and 2^130:
    this test fails at 2^+-130)."""
    f = 2.0 ** power
    ref, res = core.estimate(noisy_torus, k=k), core.estimate(noisy_torus * f, k=k)
    assert ref.valid.all() and not degenerate.reason(noisy_torus * f, 15)
    for name in ("normals", "e1", "e2", "valid", "k_point", "outlier_score", "crease", "orientation_confidence"):
        np.testing.assert_array_equal(getattr(res, name), getattr(ref, name), err_msg=name)
    np.testing.assert_array_equal(res.k1 * f, ref.k1)
    np.testing.assert_array_equal(res.gaussian * f * f, ref.gaussian)


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
    distinct = np.random.default_rng(2).random((len(pts), 3))
    built = []
    spent = cpu_seconds(lambda: built.append(neighbours.build_neighbours(pts, 20)), 1)
    nb = built[0]  # CPU against as many distinct points': 0.14x; a plain kd-tree search's 23x
    assert spent < 5 * cpu_seconds(lambda: neighbours.build_neighbours(distinct, 20), 1)
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


@pytest.mark.parametrize("radius, offset", [(1.0, 1e9), (1e-3, 1e6)], ids=["unit_1e9", "1mm_1e6"])
def test_far_apart_parts_are_not_a_line(radius, offset):
    """Two surfaces far apart are thin next to their distance, but each part is a surface:
    the whole cloud's spread called them "one straight line" (all invalid). Each part's
    answer is the one it has alone."""
    a, b = shapes.sphere(1000, seed=1).points, shapes.sphere(1000, radius=radius, seed=2).points + [offset, 0, 0]
    res = core.estimate(np.vstack([a, b]), k=15)
    assert "degenerate" not in res.params and res.valid.all()
    for part, alone in ((res.k1[:1000], core.estimate(a, k=15).k1), (res.k1[1000:], core.estimate(b, k=15).k1)):
        np.testing.assert_allclose(part, alone, rtol=1e-9, atol=1e-9 / radius)
    np.testing.assert_allclose(np.median(res.mean[1000:]) * radius, 1.0, rtol=0.05)


def test_far_apart_grids_are_not_a_line():
    """Runs along the line's direction inside a grid hold points of one column (no extent
    along it): still a surface."""
    g = np.stack(np.meshgrid(np.arange(40.0), np.arange(40.0)), -1).reshape(-1, 2)
    square = np.c_[g, np.zeros(len(g))]
    assert degenerate.reason(np.vstack([square, square + [1e9, 0, 0]]), 4) is None


def _line(n, seed=3):
    t = np.linspace(-1.0, 2.0, n)
    rot = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))[0]
    return np.c_[t, 3 * t + 1, -2 * t] @ rot, np.array([1.0, 3.0, -2.0]) @ rot / np.sqrt(14.0)


@pytest.mark.parametrize("case", ["jitter_1e-9", "1M_jitter_1e-2_spacing", "two_segments_1e9_apart", "copies",
                                  "offset_1e6"])
def test_lines_are_still_lines(case):
    """What was a line still is: within rounding or with a jitter far below the spacing
    (that the whole cloud's spread caught), in pieces far apart, with copies of its
    points, far from 0."""
    line, direction = _line(300)
    rng = np.random.default_rng(5)
    pts = {"jitter_1e-9": lambda: line + 1e-9 * rng.normal(size=line.shape),
           "1M_jitter_1e-2_spacing": lambda: _line(10**6)[0] + 1e-7 * rng.normal(size=(10**6, 3)),
           "two_segments_1e9_apart": lambda: np.vstack([line, line + 1e9 * direction]),
           "copies": lambda: np.repeat(line, 7, axis=0),
           "offset_1e6": lambda: line + 1e6}[case]()
    assert "straight line" in (degenerate.reason(pts, 4) or "")


def test_qn_on_a_grid_at_its_smallest_k_warns_nothing():
    """A neighbour's normal in the tangent plane (Z = 0) made QN's (and CN's, CF's) targets
    -X/Z leak numpy's divide-by-zero RuntimeWarnings; those points stay invalid."""
    g = np.stack(np.meshgrid(np.arange(50), np.arange(60)), -1).reshape(-1, 2)
    pts = np.c_[g, (np.arange(3000) % 7 == 0).astype(int)]
    for method, k in (("qn", 3), ("cn", 5), ("cf", 4)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = core.estimate(pts, k=k, method=method)
        assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], method
        assert 0.5 < res.valid.mean() < 1.0 and np.isfinite(res.k1[res.valid]).all()
        assert np.isnan(res.k1[~res.valid]).all()


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
