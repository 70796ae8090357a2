"""Stacked frames (core.clumps): every place recorded many times with a jitter of 1e-3 to
0.1 of the spacing of the places. The k nearest of every point were copies of its own
place: curvature garbage reported valid."""

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from core import duplicates, estimate, shapes
from core.kernels.kd_order import kd_order


def _stacked(places, copies, jitter, seed=0, rays=False):
    """``places`` each ``copies`` times (an int or a (low, high) range per place) jittered by
    ``jitter`` of their mean spacing, isotropically or along rays from one viewpoint; shuffled.
    Returns (cloud, place of each point)."""
    rng = np.random.default_rng(seed)
    count = np.full(len(places), copies) if np.isscalar(copies) else rng.integers(*copies, len(places), endpoint=True)
    place = rng.permutation(np.repeat(np.arange(len(places)), count))
    step = jitter * cKDTree(places).query(places, k=2)[0][:, 1].mean()
    if rays:
        ray = places[place] - (places.mean(axis=0) + 4.0 * np.ptp(places, axis=0).max() * np.array([0.3, -0.2, 1.0]))
        shift = ray / np.linalg.norm(ray, axis=1, keepdims=True) * rng.normal(0.0, step, (len(place), 1))
    else:
        shift = rng.normal(0.0, step, (len(place), 3))
    return places[place] + shift, place


def _posed(points, scale, seed):
    return scale * (points @ Rotation.random(random_state=seed).as_matrix().T + [3.0, -7.0, 11.0])


def _near_copies(points):
    """core.duplicates.near_copies on the cloud in spatial order, as core.estimate calls it."""
    order, sorted_points = kd_order(np.ascontiguousarray(points), 2)
    dist, idx = cKDTree(sorted_points).query(sorted_points, k=15)
    return duplicates.near_copies(idx, dist, sorted_points, rank=order, spatial=True), order


@pytest.mark.parametrize("k", [15, "auto"])
@pytest.mark.parametrize("copies, jitter, rays", [(5, 0.05, False), (20, 0.01, True), ((1, 50), 0.02, False)])
def test_stacked_frames_are_estimated_at_their_places(k, copies, jitter, rays):
    """A sphere's 2000 places recorded 5, 20 or 1-50 times: H was off by 0.3-15 on a unit
    sphere (every point valid); now every copy has its place's answer, near the clean one's."""
    s = shapes.sphere(2000, seed=3)
    cloud, place = _stacked(s.points, copies, jitter, seed=1, rays=rays)
    res = estimate(_posed(cloud, 1.0, 2), k=k)
    clean = estimate(_posed(s.points, 1.0, 2), k=k)
    places = len(cloud) - res.params["duplicates"]  # close pairs of random places can be one (a lost sample)
    assert 0.85 * len(s.points) < places <= 1.02 * len(s.points) and res.valid.mean() > 0.99
    err, err_clean = np.median(np.abs(np.abs(res.mean) - 1.0)), np.median(np.abs(np.abs(clean.mean) - 1.0))
    assert err < max(3.0 * err_clean, 0.02)


@pytest.mark.parametrize("scale", [1e-3, 1e4])
def test_a_clump_is_one_place_at_its_mean_in_any_unit_and_pose(scale):
    """Every place's copies stay together (close pairs of random places may be one), and
    the place is the clump's mean (the jitter averaged away), whatever the unit and pose."""
    s = shapes.torus(2000, seed=4)
    cloud, place = _stacked(s.points, 20, 0.05, seed=5)
    posed = _posed(cloud, scale, 6)
    found, order = _near_copies(posed)
    assert found is not None and 0.9 * len(s.points) < len(found.first) <= len(s.points)
    inverse = np.empty_like(found.inverse)
    inverse[order] = found.inverse
    pairs = np.unique(np.column_stack([inverse, place]), axis=0)
    assert np.count_nonzero(np.bincount(pairs[:, 1]) > 1) < 0.01 * len(s.points)  # a place's copies stay together
    mean = np.stack([np.bincount(inverse, weights=c) for c in posed.T], axis=1) / np.bincount(inverse)[:, None]
    np.testing.assert_allclose(found.points, mean, rtol=0, atol=1e-9 * scale)


def _hexagonal(n_side):
    i, j = np.mgrid[0:n_side, 0:n_side].reshape(2, -1)
    return np.column_stack([i + 0.5 * (j % 2), j * np.sqrt(3) / 2, np.zeros(len(i))])


def _scan_lines(lines, per_line, ratio, seed):
    """A bent sheet scanned in ``lines`` lines ``ratio`` times farther apart than the points along them."""
    rng = np.random.default_rng(seed)
    u = np.linspace(0.0, 1.0, per_line)[None, :] + rng.normal(0.0, 0.2 / per_line, (lines, per_line))
    v = np.repeat(np.arange(lines)[:, None] * ratio / per_line, per_line, axis=1)
    return np.column_stack([u.ravel(), v.ravel(), 0.3 * np.sin(3.0 * u.ravel()) * np.cos(v.ravel())])


@pytest.mark.parametrize("sampling", ["random", "hexagonal", "scan lines 10:1", "noise 0.5"])
def test_a_sampling_is_not_clumps_but_the_same_sampling_stacked_is(sampling):
    """Random sampling (close pairs), a lattice (the ties of its shells), scan lines (a ball
    keeps growing along the line) and a noisy cloud are not clumps; stacked 5 times with a
    jitter of 0.02 of their spacing they are, one place each."""
    rng = np.random.default_rng(7)
    torus = shapes.torus(4000, seed=7).points
    points = {"random": torus, "hexagonal": _hexagonal(60), "scan lines 10:1": _scan_lines(40, 200, 10.0, 7),
              "noise 0.5": torus + rng.normal(0.0, 0.5 * 0.1, torus.shape)}[sampling]
    assert _near_copies(points)[0] is None
    cloud, _ = _stacked(points, 5, 0.02, seed=8)
    found = _near_copies(cloud)[0]
    assert found is not None and 0.94 * len(points) < len(found.first) <= len(points)


def test_small_dense_objects_beside_a_sparse_one_and_a_dense_noisy_cloud_are_not_clumps():
    """Objects 1000 times denser than the sphere beside them are sampling, and a cloud
    jittered by 0.3 of its spacing around each place is a noisy cloud (the boundary), while
    the same places jittered by 0.05 are clumps."""
    big = shapes.sphere(8000, seed=9).points
    small = [1e-3 * shapes.sphere(50, seed=i).points + 1.05 * big[40 * i] for i in range(60)]
    assert _near_copies(np.concatenate([big, *small]))[0] is None
    places = shapes.sphere(2000, seed=10).points
    assert _near_copies(_stacked(places, 5, 0.3, seed=11)[0])[0] is None
    assert _near_copies(_stacked(places, 5, 0.05, seed=11)[0])[0] is not None
