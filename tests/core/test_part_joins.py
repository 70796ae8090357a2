"""Parts of the orientation graph joined across gaps (core.part_joins): one sheet in pieces
the 10 nearest do not join comes out with one orientation, whatever the gap."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import core
from core import shapes, shapes_thin
from core.noise import add_noise
from core.orientation import GATE
from core.part_joins import JOIN_PARTS, join_parts


def _facing(r, truth):
    return np.einsum("ij,ij->i", r.normals, truth) > 0


@pytest.mark.parametrize("k", ["auto", 15])
@pytest.mark.parametrize("ratio", [12.0, 24.0])
def test_scan_lines_farther_apart_than_the_graph_reaches_agree(ratio, k):
    """Each scan line of one waved sheet is its own part of the 10-nearest graph; every line
    now faces the way the others do (before: a block of lines flipped, 75 % agreement, with
    orientation confidence 1)."""
    s = shapes_thin.stripe_scan(15000, ratio=ratio, seed=0)
    r = core.estimate(s.points, k=k)
    up = _facing(r, s.normals)
    assert up.all() or not up.any(), up.mean()


def test_pieces_of_a_noisy_sheet_agree_across_wide_gaps():
    """A waved sheet cut into a 3 x 3 grid of pieces by gaps 10 spacings wide, noise 0.2
    spacing: one orientation for all nine."""
    rng = np.random.default_rng(3)
    xy = rng.uniform(0.0, 3.0, (20000, 2))
    spacing = 3.0 / np.sqrt(len(xy))
    cut = (np.abs(xy[:, :, None] - np.array([1.0, 2.0])) < 5 * spacing).any(axis=(1, 2))
    xy = xy[~cut]
    pts = add_noise(np.c_[xy, 0.2 * np.sin(2 * xy[:, 0]) * np.cos(xy[:, 1])], 0.2 * spacing, seed=4)
    grad = np.c_[0.4 * np.cos(2 * xy[:, 0]) * np.cos(xy[:, 1]), -0.2 * np.sin(2 * xy[:, 0]) * np.sin(xy[:, 1])]
    truth = np.c_[-grad, np.ones(len(xy))]
    r = core.estimate(pts, k=15)
    up = _facing(r, truth)[r.valid]
    assert min(up.mean(), 1 - up.mean()) < 0.002, up.mean()


def test_joined_parts_keep_their_outward_vote():
    """Closed parts apart still face outward, and a far cluster of 30 points does not
    flip the surface it is joined to (the group's vote is the sum of its parts')."""
    a, b = shapes.sphere(3000, radius=1.0, seed=1), shapes.sphere(1500, radius=0.5, seed=2)
    for offset in (2.5, 1e6):
        r = core.estimate(np.vstack([a.points, b.points + [offset, 0, 0]]), k=15)
        assert _facing(r, np.vstack([a.normals, b.normals])).all(), offset
    cluster = np.random.default_rng(0).normal(0.0, 0.05, (30, 3)) + [40.0, 0, 0]
    r = core.estimate(np.vstack([a.points, cluster]), k=15)
    assert _facing(r, np.vstack([a.normals, np.zeros((30, 3))]))[:3000].all()


def test_nested_closed_surfaces_are_oriented_as_one_solid():
    """A sphere inside another, 0.4 apart: the chords between them cross no surface, so
    they are read as the two skins of one hollow solid: the outer faces out, the inner
    faces its hollow (k = -1/r there), not two solids inside each other."""
    outer, inner = shapes.sphere(6000, radius=1.0, seed=0), shapes.sphere(2000, radius=0.6, seed=1)
    r = core.estimate(np.vstack([outer.points, inner.points]), k=15)
    assert _facing(r, np.vstack([outer.normals, -inner.normals])).all()
    assert np.median(r.mean[6000:]) == pytest.approx(-1 / 0.6, rel=0.1)
    assert np.median(r.mean[:6000]) == pytest.approx(1.0, rel=0.1)


def test_joins_do_not_depend_on_the_order_of_the_points():
    s = shapes_thin.stripe_scan(6000, ratio=16.0, seed=1)
    perm = np.random.default_rng(5).permutation(len(s.points))
    a = core.estimate(s.points, k=15)
    b = core.estimate(s.points[perm], k=15)
    np.testing.assert_array_equal(a.normals[perm], b.normals)


def test_join_parts_ties_pieces_by_their_evidence():
    """The unit: three coplanar pieces, the middle one's normals flipped; the pieces are
    one group, the middle one with parity -1. A part under JOIN_MIN points joins nothing."""
    x = np.linspace(0.0, 1.0, 40)
    piece = np.stack(np.meshgrid(x, x), axis=-1).reshape(-1, 2)
    pts = np.vstack([np.c_[piece + [dx, 0.0], np.zeros(len(piece))] for dx in (0.0, 1.5, 3.0)] + [[[9.0, 9.0, 0.0]]])
    normals = np.tile([0.0, 0.0, 1.0], (len(pts), 1))
    labels = np.repeat([0, 1, 2, 3], [len(piece)] * 3 + [1])
    normals[labels == 1] *= -1
    group, parity = join_parts(pts, normals, labels, np.zeros(len(pts)), np.arange(len(pts)), GATE)
    np.testing.assert_array_equal(group, [0, 0, 0, 3])
    np.testing.assert_array_equal(parity, [1, -1, 1, 1])


def test_only_the_largest_parts_are_joined():
    """Beyond JOIN_PARTS parts the smallest keep their own vote (the cost is bounded)."""
    n = JOIN_PARTS + 4
    pts = np.vstack([np.c_[np.random.default_rng(i).uniform(0, 1, (20 + i, 2)), np.zeros(20 + i)] + [2.0 * i, 0, 0]
                     for i in range(n)])
    labels = np.repeat(np.arange(n), [20 + i for i in range(n)])
    group, _ = join_parts(pts, np.tile([0.0, 0.0, 1.0], (len(pts), 1)), labels, np.zeros(len(pts)),
                          np.arange(len(pts)), GATE)
    assert np.all(group[:4] == np.arange(4)) and len(set(group[4:])) == 1


@pytest.mark.parametrize("clumps, size, k", [(200, 25, 15), (200, 25, "auto"), (300, 15, 15)])
def test_a_torus_sampled_in_hundreds_of_clumps_faces_out(clumps, size, k):
    """Hundreds of clumps, each its own part: every one is joined to its nearest, and the
    torus faces out. With only the 64 largest joined, 200 clumps of 25 had 9 % (k = 15) and
    24 % (auto) of the points facing in (the clumps around the hole, each turned away from the
    centre); with parts of 16 points or more joined, 300 clumps of 15 had 8 % (k = 15)."""
    t = shapes.torus(40000, seed=2)
    centres = np.random.default_rng(0).choice(len(t.points), clumps, replace=False)
    rows = np.unique(cKDTree(t.points).query(t.points[centres], size)[1])
    r = core.estimate(t.points[rows], k=k)
    assert _facing(r, t.normals[rows])[r.valid].all()
