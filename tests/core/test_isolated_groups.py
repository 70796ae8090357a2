"""Groups too small to be a surface (core.kernels.isolated_groups): floating clumps and
lone points off a surface are outliers, whatever their neighbours' plane says."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import core
import core.shapes_thin
from core import kernels
from core.neighbours import build_neighbours


def _isolated(points, k=15):
    idx = np.ascontiguousarray(build_neighbours(points, k).take(k)[0])
    out = np.zeros(len(points), dtype=bool)
    kernels.isolated_groups(points, idx, out)
    return out


def _grid(n=30):
    x, y = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    return np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])


def _clump(centre, size, seed):
    return centre + np.random.default_rng(seed).normal(scale=0.3, size=(size, 3))


def test_known_groups_on_a_grid():
    """A unit grid with, 6 spacings above it, a clump of 5 (apart), a clump of 20 (a
    neighbourhood of its own: kept) and one lone point (apart)."""
    plane = _grid()
    small, large = _clump([10.0, 10.0, 6.0], 5, 1), _clump([20.0, 20.0, 6.0], 20, 2)
    lone = np.array([[5.0, 25.0, 6.0]])
    out = _isolated(np.vstack([plane, small, large, lone]))
    n = len(plane)
    assert not out[:n].any()
    assert out[n:n + 5].all()
    assert not out[n + 5:n + 25].any()
    assert out[-1]


def test_a_cloud_smaller_than_a_neighbourhood_is_not_apart():
    pts = _clump([0.0, 0.0, 0.0], 10, 3)
    assert not _isolated(pts, k=10).any()


@pytest.mark.parametrize("make", [
    lambda: core.shapes.graded(6000, seed=0).points,  # 10:1 density
    lambda: core.shapes.range_scan(6000, seed=0).points,  # one viewpoint: density falls with range
    lambda: core.shapes_thin.stripe_scan(8000, ratio=10.0).points,  # scan lines 10 x their spacing apart
    lambda: core.noise.add_noise(core.shapes.torus(6000, seed=1).points, 0.5, seed=2),
    lambda: _grid(),  # exact ties at every reach
])
def test_no_surface_point_is_apart(make):
    assert not _isolated(make()).any()


def test_floating_clumps_and_lone_points_are_outliers():
    """Before the groups rule, clumps of 5 floating 6-10 spacings off a torus were flagged
    outliers at 0 % (their own points made up their neighbours' plane) and got curvatures;
    lone points anywhere in the bounding box at 64 %."""
    s = core.shapes.torus(8000, seed=4)
    h = core.noise.mean_spacing(s.points)
    rng = np.random.default_rng(5)
    at = rng.choice(len(s.points), 30, replace=False)
    off = (s.points[at] + s.normals[at] * rng.uniform(6.0, 10.0, (30, 1)) * h * rng.choice([-1.0, 1.0], (30, 1)))
    clumps = (off[:, None, :] + rng.normal(scale=0.4 * h, size=(30, 5, 3))).reshape(-1, 3)
    lo, hi = s.points.min(0), s.points.max(0)
    lone = rng.uniform(lo, hi, (100, 3))
    lone = lone[cKDTree(s.points).query(lone)[0] > 4 * h]  # off the surface by 4 spacings or more
    r = core.estimate(np.vstack([s.points, clumps, lone]))
    n = len(s.points)
    assert r.outlier[n:n + len(clumps)].mean() > 0.9
    assert r.outlier[n + len(clumps):].mean() > 0.9
    assert not np.isinf(r.outlier_score[:n]).any()
    assert not r.valid[n:][r.outlier[n:]].any()  # the default leaves outliers unestimated
    assert r.valid[:n].mean() > 0.99
