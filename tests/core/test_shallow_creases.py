"""Creases where two planes meet or cross at a shallow angle (30 deg), in any pose and scale.

The initial normals blend the two sheets near the line, so its 15 nearest spread little
(0.04-0.08 RMS) although a line explains less than a quarter of their turning: the crease
test's spread threshold (core.tuning.CREASE_SPREAD) must let such a line through.
"""

import numpy as np
import pytest

import core

N = 12000


def _junction(kind, seed, angle=np.pi / 6):
    """A unit plane z = 0 and a sheet rising from the line x = z = 0 at ``angle`` (30 deg): a
    half-plane ("T") or a whole plane ("X"). Returns (points, distance to the line, spacing)."""
    rng = np.random.default_rng(seed)
    slope = np.array([np.cos(angle), 0.0, np.sin(angle)])
    if kind == "T":
        m = 2 * N // 3
        flat = np.column_stack([rng.uniform(-1, 1, (m, 2)), np.zeros(m)])
        t, y = rng.uniform(0, 1, N - m), rng.uniform(-1, 1, N - m)
        spacing = np.sqrt(6.0 / N)
    else:
        m = N // 2
        flat = np.column_stack([rng.uniform(-1, 1, (m, 2)), np.zeros(m)])
        t, y = rng.uniform(-1, 1, N - m), rng.uniform(-1, 1, N - m)
        spacing = np.sqrt(8.0 / N)
    rising = t[:, None] * slope + y[:, None] * [0.0, 1.0, 0.0]
    pts = np.vstack([flat, rising])
    line = np.r_[np.abs(flat[:, 0]), np.abs(t)]
    inside = (np.abs(pts[:, 1]) < 0.8) & (np.r_[np.abs(flat[:, 0]), np.abs(t)] < 0.8)
    return pts, np.where(inside, line, np.nan), spacing


def _pose(pts, seed, scale):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return scale * pts @ (q * np.sign(np.linalg.det(q))).T + [3.0, -7.0, 11.0]


@pytest.mark.parametrize("kind, seed, scale", [("T", 0, 1.0), ("T", 1, 10.0), ("X", 0, 0.1), ("X", 1, 1.0)])
def test_shallow_junction_lines_are_creases(kind, seed, scale):
    """Within 3 spacings of a 30 deg junction line most points are flagged (the old
    threshold 0.15 flagged 21-49 %), none 10 spacings or more from it."""
    pts, line, spacing = _junction(kind, seed)
    crease = core.estimate(_pose(pts, seed + 1, scale)).crease
    assert crease[line < 3 * spacing].mean() > 0.6
    assert crease[line > 10 * spacing].mean() < 0.01
