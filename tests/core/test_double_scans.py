"""Two scans of one surface merged with a small registration offset face out together
(core.double_scan).

Two independent samplings of one closed surface, the second shifted by 2-3 of its own
spacings in a random direction: the chord test read the two copies as a thin solid's two
skins and turned one of them inward wherever the gap passed the noise gate (k="auto":
22-41 % of the points inward, confidence ~1, and H of the wrong sign there). Copies of a
curved surface cross where the shift is tangent to it, and the thin solid's reading leaves
a seam inside each copy there; the double scan's reading does not."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import core
from core import shapes
from core.double_scan import cross_edges, frustration


def _bumpy(n, seed, a=0.12, b=4.0):
    """A closed star-shaped surface with bumps: |p|^2 - 1 + a sum(sin(b p)) = 0."""
    rng = np.random.default_rng(seed)
    return shapes._implicit_sample(
        "bumpy", lambda p: (p * p).sum(1) - 1.0 + a * np.sin(b * p).sum(1),
        lambda p: 2 * p + a * b * np.cos(b * p),
        lambda p: np.einsum("mi,ij->mij", 2 - a * b * b * np.sin(b * p), np.eye(3)), n, rng, 1.6)


_SHAPES = {
    "sphere": lambda n, s: shapes.sphere(n, seed=s),
    "torus": lambda n, s: shapes.torus(n, seed=s),
    "ellipsoid": lambda n, s: shapes.ellipsoid(n, seed=s),
    "bumpy": _bumpy,
}


def _double_scan(name, n, offset, seed, noise=0.0):
    """Two samplings of ``n`` points each, the second shifted by ``offset`` of one scan's mean
    spacings in a random direction (and turned by a small angle about a random axis),
    shuffled together: (points, true outward normals, true H)."""
    rng = np.random.default_rng(seed)
    a, b = _SHAPES[name](n, 2 * seed), _SHAPES[name](n, 2 * seed + 1)
    spacing = float(cKDTree(a.points).query(a.points, k=2)[0][:, 1].mean())
    turn = core.shapes._unit(rng.normal(size=(1, 3)))[0] * 0.3 * spacing
    c, s = np.cos(np.linalg.norm(turn)), np.sin(np.linalg.norm(turn))
    axis = turn / np.linalg.norm(turn)
    rot = c * np.eye(3) + s * np.cross(np.eye(3), axis) + (1 - c) * np.outer(axis, axis)
    shift = core.shapes._unit(rng.normal(size=(1, 3)))[0] * offset * spacing
    pts = np.vstack([a.points, b.points @ rot.T + shift])
    pts += rng.normal(size=pts.shape) * noise * spacing
    order = rng.permutation(2 * n)
    truth = np.vstack([a.normals, b.normals @ rot.T])
    return pts[order], truth[order], np.concatenate([a.mean, b.mean])[order]


@pytest.mark.parametrize("name, offset, seed", [
    ("sphere", 2.0, 0), ("sphere", 3.0, 1), ("torus", 2.5, 2), ("torus", 3.0, 3),
    ("ellipsoid", 3.0, 4), ("bumpy", 2.5, 5),
])
def test_a_double_scan_faces_out(name, offset, seed):
    """Failed before: 59-84 % of the points outward."""
    pts, truth, mean = _double_scan(name, 10000, offset, seed)
    res = core.estimate(pts)
    outward = np.einsum("ij,ij->i", np.nan_to_num(res.normals), truth) > 0
    assert outward.mean() > 0.995
    h = 0.5 * (res.k1 + res.k2)
    read = res.valid & (np.abs(mean) > 0.2)
    assert np.mean(np.sign(h[read]) == np.sign(mean[read])) > 0.99


def test_a_noisy_double_scan_faces_out():
    """0.2 spacing of noise, 3 spacings apart: failed before (84 % outward)."""
    pts, truth, _ = _double_scan("torus", 10000, 3.0, 7, noise=0.2)
    res = core.estimate(pts)
    assert np.mean(np.einsum("ij,ij->i", np.nan_to_num(res.normals), truth) > 0) > 0.99


def test_cross_edges_read_parallel_sheets_with_a_chord_across():
    """Two parallel sheets 3 units apart: the edges across carry a chord term, those along
    a sheet none; normals at 90 degrees are no cross edge."""
    pts = np.array([[0.0, 0, 0], [1, 0, 0], [0, 0, 3], [1, 0, 3]])
    up = np.tile([0.0, 0, 1], (4, 1))
    graph = np.array([[0, 1, 2], [1, 0, 3], [2, 3, 0], [3, 2, 1]])
    term = cross_edges(pts, up, graph, np.zeros(4))
    assert term[0, 1] == 0 and term[0, 2] < -0.9
    side = up.copy()
    side[2] = [1.0, 0, 0]
    assert cross_edges(pts, side, graph, np.zeros(4))[0, 2] == 0


def test_frustration_sums_the_evidence_the_signs_leave_unsatisfied():
    ev = np.array([[0.0, 0.5], [0.0, 0.5], [0.0, -0.25]])
    graph = np.array([[0, 1], [1, 0], [2, 0]])
    assert frustration(ev, graph, np.array([0, 0, 0], dtype=np.int8)) == 0.25
    assert frustration(ev, graph, np.array([1, 0, 0], dtype=np.int8)) == 1.0


def test_the_double_reading_is_made_a_block_of_rows_at_a_time(monkeypatch):
    """The double scan's evidence (double_reading) is the whole graph's formula, bit for bit,
    made a block of rows at a time: made at once, its temporaries (~17 arrays of the graph's
    size) were 4.0 GB of a 1M-point torus at 0.5 spacing of noise."""
    import tracemalloc

    from core import double_scan

    pts, normals, _ = _double_scan("sphere", 6000, 2.0, 7)
    n, rng = len(pts), np.random.default_rng(7)
    graph = cKDTree(pts).query(pts, k=30)[1].astype(np.int32)
    spread, weight = rng.uniform(0, 0.01, n), rng.uniform(0.5, 1.0, n)
    evidence = rng.normal(size=graph.shape)
    whole = evidence - 2.0 * cross_edges(pts, normals, graph, spread) * weight[:, None] * weight[graph]
    monkeypatch.setattr(double_scan, "ROWS_AT_A_TIME", 500, raising=False)
    tracemalloc.start()
    try:
        alt = double_scan.double_reading(pts, normals, graph, evidence, (spread, weight), np.arange(n))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert alt is not None and np.array_equal(alt, whole)
    assert peak < 3 * evidence.nbytes  # the answer and one block's temporaries


def test_the_frustration_is_summed_over_blocks_of_rows_to_the_same_bits(monkeypatch):
    """frustration reads the graph a block of rows at a time (three arrays of the graph's size
    at once, ~0.7 GB at 1M points and 30 columns) and sums the unsatisfied evidence once, in
    the same order: the same float as the whole graph's sum."""
    import tracemalloc

    from core import double_scan

    rng = np.random.default_rng(8)
    ev = rng.normal(size=(12000, 30))
    graph = rng.integers(0, len(ev), size=ev.shape)
    flip = rng.integers(0, 2, len(ev)).astype(np.int8)
    sign = 1.0 - 2.0 * flip
    agree = ev * sign[:, None] * sign[graph]
    whole = float(-agree[agree < 0].sum())
    monkeypatch.setattr(double_scan, "ROWS_AT_A_TIME", 500, raising=False)
    tracemalloc.start()
    try:
        got = frustration(ev, graph, flip)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert got == whole
    assert peak < 1.5 * ev.nbytes  # the values below zero, and one block's temporaries
