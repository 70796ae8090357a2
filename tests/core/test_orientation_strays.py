"""A few stray points far from a closed surface do not turn it inside out: the outward vote
is its outer half by distance from the centre (core.orientation.VOTE_BINS), not the points
beyond the RMS distance, which a noise-free sphere's points all sit at (found by an
adversarial geometry sweep: two points 10 radii off turned the whole sphere inward)."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import shapes
from core.io import read_cloud
from core.tiled import estimate_tiled

_SPHERE = shapes.sphere(2000, seed=1)
_STRAYS = {
    "two points 10 radii off": np.random.default_rng(0).normal(size=(2, 3)) * 0.01 + [10.0, 0.0, 0.0],
    "six in a row 100 radii off": np.column_stack([np.linspace(0, 0.1, 6), np.zeros(6), np.zeros(6)]) + [100.0, 0, 0],
    "twenty 3 radii off": shapes.sphere(20, radius=3.0, seed=2).points,
}


def _far_off(seed, radii=1e6):
    d = np.random.default_rng(seed).normal(size=3)
    return (d / np.linalg.norm(d) * radii)[None, :]


# one point 1e6 radii off moved the centre 500 radii: every point of the sphere at one distance
# (one histogram bin), all of them voted, and these two directions (of 12) turned it inward
_STRAYS.update({"one point 1e6 radii off, a": _far_off(9), "one point 1e6 radii off, b": _far_off(10)})


@pytest.mark.parametrize("k", [15, "auto"])
@pytest.mark.parametrize("strays", sorted(_STRAYS))
@pytest.mark.parametrize("move", ["as is", "translated", "scaled"])
def test_stray_points_leave_a_sphere_facing_outward(strays, k, move):
    pts = np.vstack([_SPHERE.points, _STRAYS[strays]])
    scale, shift = (1e3, 0.0) if move == "scaled" else (1.0, np.array([30.0, -20.0, 50.0]) * (move == "translated"))
    res = core.estimate(pts * scale + shift, k=k)
    outward = np.einsum("ij,ij->i", res.normals[:2000], _SPHERE.normals) > 0
    assert outward.all()  # was: every normal inward at k = 15 with two strays (H = -0.955)
    assert np.median(res.mean[:2000]) * scale == pytest.approx(1.0, rel=0.06)


@pytest.mark.parametrize("strays", ["two points 10 radii off", "one point 1e6 radii off, a"])
def test_tiles_vote_as_the_whole_cloud(tmp_path, strays):
    pts = np.vstack([_SPHERE.points, _STRAYS[strays]])
    mem = core.estimate(pts, k=15)
    estimate_tiled(pts, tmp_path / "out.ply", k=15, tile_points=500, workers=0)
    f = read_cloud(tmp_path / "out.ply")
    np.testing.assert_array_equal(np.sign(np.einsum("ij,ij->i", f.normals, mem.normals)[mem.valid]), 1.0)
    assert (np.einsum("ij,ij->i", mem.normals[:2000], _SPHERE.normals) > 0).all()


def _street(seed=0):
    """A level ground 20 x 20 (spacing ~0.1) with a box and a ball standing on it (their
    bottoms not sampled): an open scene, which the objects lift the cloud's centre above."""
    rng = np.random.default_rng(seed)
    ground = np.column_stack([rng.uniform(-10, 10, (40_000, 2)), np.zeros(40_000)])
    ground = ground[~((np.abs(ground[:, 0] - 3) < 1) & (np.abs(ground[:, 1]) < 1))]  # under the box
    faces = []
    for axis in range(2):
        for side in (-1.0, 1.0):
            f = rng.uniform(-1, 1, (800, 3)) * [1, 1, 1]
            f[:, axis] = side
            faces.append(f)
    top = rng.uniform(-1, 1, (800, 3))
    top[:, 2] = 1.0
    box = (np.vstack(faces + [top]) + [0.0, 0.0, 1.0]) * [1, 1, 1] + [3.0, 0.0, 0.0]
    box = box[box[:, 2] > 0.05]
    ball = shapes.sphere(3000, seed=seed).points * 1.5 + [-4.0, 2.0, 1.6]
    ball = ball[ball[:, 2] > 0.15]
    return np.vstack([ground, box, ball]), len(ground)


@pytest.mark.parametrize("k", [15, "auto"])
def test_an_open_level_scene_faces_up(k, tmp_path):
    """An open sheet has no inside (a closed surface's outward normals sum to zero; this
    ground's do not): its "outward" side was set by how the objects lift the cloud's centre
    above it, and a street scan's ground faced down at 99.9 % of its points (found by a
    real-scan sweep). Open, level parts face up (core.orientation.floors_up); the objects
    on it keep facing out of themselves, and tiles decide as the whole cloud does."""
    pts, n_ground = _street()
    res = core.estimate(pts, k=k)
    up = res.normals[:n_ground, 2][res.valid[:n_ground]]
    assert np.mean(up > 0) > 0.99  # was 0.0001 (k = 15) and 0.0 (auto)
    n_ball = np.count_nonzero(pts[n_ground:, 0] < -1)
    box, ball = slice(n_ground, len(pts) - n_ball), slice(len(pts) - n_ball, len(pts))
    for part, centre in ((box, [3.0, 0.0, 1.0]), (ball, [-4.0, 2.0, 1.6])):
        if part is ball and k == "auto":
            continue  # auto's wider graph joins the ball to the ground across their contact, with the
            # parity of a sheet (the ball's bottom agrees with the ground): it faces inward (left open)
        out = np.einsum("ij,ij->i", res.normals[part], pts[part] - centre)[res.valid[part]]
        assert np.mean(out > 0) > 0.99
    if k == 15:
        estimate_tiled(pts, tmp_path / "out.ply", k=15, tile_points=8000, workers=0)
        f = read_cloud(tmp_path / "out.ply")
        agree = np.einsum("ij,ij->i", f.normals, res.normals)[res.valid]
        assert np.mean(agree > 0) > 0.999


def _clumped_sphere(n_clumps=500, size=20, seed=0):
    """A unit sphere sampled in separate clumps (radius ~0.01, ~0.16 apart): every clump is
    a part of its own, small and level near the poles."""
    rng = np.random.default_rng(seed)
    centres = rng.normal(size=(n_clumps, 3))
    centres /= np.linalg.norm(centres, axis=1, keepdims=True)
    pts = (centres[:, None, :] + rng.normal(scale=0.01, size=(n_clumps, size, 3))).reshape(-1, 3)
    return pts / np.linalg.norm(pts, axis=1, keepdims=True)


@pytest.mark.parametrize("k", [15, "auto"])
def test_small_level_patches_far_from_the_centre_keep_their_outward_vote(k, tmp_path):
    """A level open part faces up only while the cloud's centre lies beside it (a ground
    under a scene, core.orientation.centre_beside): the clumps near a sphere's south pole
    faced up, inward (8.8 % of the points at k="auto", 11.8 % at k = 15)."""
    pts = _clumped_sphere()
    res = core.estimate(pts, k=k)
    assert (np.einsum("ij,ij->i", res.normals, pts) > 0).mean() > 0.995  # 1.0 measured
    if k == 15:  # the tiles decide alike
        estimate_tiled(pts, tmp_path / "out.ply", k=15, tile_points=1500, workers=0)
        tiled = read_cloud(tmp_path / "out.ply")
        assert (np.einsum("ij,ij->i", tiled.normals, pts) > 0).mean() > 0.995
