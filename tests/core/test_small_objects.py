"""Clouds made of small objects (core.clump_surfaces): spheres of 80-200 points far apart show
the gap of stacked frames (core.clumps) and were merged into one place each: garbage reported
valid (27 in a grid: H ~ 0 instead of 1, normals at random), a ValueError (2-8 of them at
k = 15), or every point invalid (in a row)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from core import estimate, shapes
from core.clump_surfaces import object_clumps


def _objects(count, per, layout, seed):
    """``count`` unit spheres of ``per`` points each, centres 6-10 radii apart in a grid, a row
    or at random; returns (points, true normals)."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(count ** (1 / 3)))
    pts, nrm = [], []
    for i in range(count):
        if layout == "grid":
            centre = 8.0 * np.array(np.unravel_index(i, (side,) * 3), float) + rng.uniform(-1, 1, 3)
        elif layout == "row":
            centre = np.array([8.0 * i, 0.0, 0.0])
        else:
            centre = rng.uniform(-1, 1, 3) * 10.0 * side + 20.0 * i * np.array([1.0, 0.0, 0.0])
        s = shapes.sphere(per, seed=seed * 1000 + i)
        pts.append(s.points + centre)
        nrm.append(s.normals)
    return np.concatenate(pts), np.concatenate(nrm)


@pytest.mark.parametrize("k", [15, "auto"])
@pytest.mark.parametrize("count, per, layout, scale, seed", [
    (27, 113, "grid", 1.0, 0), (2, 113, "row", 1e-3, 1), (27, 150, "grid", 1e4, 2),
    (8, 80, "scatter", 1.0, 3), (5, 150, "grid", 1e-3, 4), (12, 150, "scatter", 1e3, 4)])
def test_small_objects_far_apart_are_estimated_not_merged(k, count, per, layout, scale, seed):
    """Every point valid, normals along the truth and |H| near 1 / radius, in any pose and unit."""
    pts, truth = _objects(count, per, layout, seed)
    turn = Rotation.random(random_state=seed).as_matrix()
    res = estimate(scale * (pts @ turn.T) + [1e3, -2e3, 5e2], k=k)
    assert res.params.get("duplicates", 0) == 0
    assert res.valid.mean() > 0.99
    cos = np.abs(np.einsum("ij,ij->i", res.normals, truth @ turn.T))
    assert np.median(cos) > 0.98
    err = np.abs(np.abs(res.mean[res.valid]) * scale - 1.0)
    assert np.median(err) < 0.1


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_objects_are_told_from_blobs_and_segments_of_copies(seed):
    """Spheres of 50-255 points (clean or at 0.2 spacing of noise) are objects; Gaussian blobs
    of 20-300 copies, segments along a view ray (with or without a little lateral jitter) and
    discs across it (locally flat like a surface, but flat as a whole) are copies, in any pose."""
    rng = np.random.default_rng(seed)
    turn = Rotation.random(random_state=seed).as_matrix()
    groups, objects = [], []
    for m in (50, 113, 255):
        s = shapes.sphere(m, seed=seed + m).points
        groups += [s, s + rng.normal(0.0, 0.2 * np.sqrt(4 * np.pi / m), s.shape)]
        objects += [True, True]
    for m in (20, 80, 300):
        ray = rng.normal(size=(m, 1)) * [[0.3, 0.2, 1.0]]
        disc = rng.normal(size=(m, 3)) * [1.0, 1.0, 0.0]  # jittered across the view ray only
        groups += [rng.normal(size=(m, 3)), ray, ray + rng.normal(0.0, 0.1, (m, 3)), disc,
                   disc + rng.normal(0.0, 0.2, (m, 3)) * [0.0, 0.0, 1.0]]
        objects += [False] * 5
    points = np.concatenate([g + [50.0 * i, 0.0, 0.0] for i, g in enumerate(groups)]) @ turn.T
    label = np.concatenate([np.full(len(g), i) for i, g in enumerate(groups)])
    found = object_clumps(points, label)
    for i, expected in enumerate(objects):
        assert found[label == i].all() == expected and found[label == i].any() == expected, i


def test_no_clump_and_tiny_clumps_are_never_objects():
    """Points outside any clump (-1) and clumps under 20 points stay as they are."""
    s = shapes.sphere(200, seed=5).points
    label = np.r_[np.full(100, -1), np.repeat(np.arange(10), 10)]
    assert not object_clumps(s, label).any()
