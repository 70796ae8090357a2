"""The border test's verdict without the angles (core.border._border_flags): the widest gap
between neighbour directions is taken only where a quarter turn around the point is empty;
elsewhere it is bounded, and the flags are those of border_flags, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core import border, build_neighbours, shapes
from core.kernels import border as kern


def test_sectors_follow_the_circle():
    """Each direction falls in the 22.5-degree sector its angle lies in (counter-clockwise from +x)."""
    angles = np.random.default_rng(0).uniform(0.0, 2 * np.pi, 20000)
    width = 2 * np.pi / kern.SECTORS
    clear = np.abs(angles / width - np.round(angles / width)) > 1e-9  # off the edges
    got = np.array([kern._sector(math.cos(a), math.sin(a)) for a in angles[clear]])
    assert np.array_equal(got, np.floor(angles[clear] / width).astype(int))
    assert kern._sector(1.0, 0.0) == 0 and kern._sector(-1.0, -0.0) == 7 and kern._sector(0.0, -1.0) == 12


def _clouds():
    rng = np.random.default_rng(3)
    for trial in range(8):
        pts = rng.normal(size=(6000, 3)) * [1.0, 1.0, rng.uniform(0.0, 0.3)]
        if trial % 4 == 1:  # a straight rim
            pts = pts[pts[:, 0] + 0.3 * pts[:, 1] > rng.uniform(-1, 1)]
        if trial % 4 == 2:  # quantised: repeated directions, offsets on the sectors' edges
            pts = np.round(pts * rng.uniform(2, 20)) / 10
        if trial % 4 == 3:  # holes
            pts = pts[np.hypot(*(pts[:, :2] % 1.0 - 0.5).T) > 0.2]
        nrm = np.tile([0.0, 0.0, 1.0], (len(pts), 1)) + rng.normal(scale=0.3 * (trial % 2), size=(len(pts), 3))
        nrm[::17] = np.nan
        yield pts, nrm / np.linalg.norm(nrm, axis=1)[:, None]
    s = shapes.torus(20000, seed=1)
    yield s.points, s.normals


@pytest.mark.parametrize("cloud", list(_clouds()), ids=lambda c: str(len(c[0])))
def test_bounded_gap_gives_the_same_flags(cloud):
    pts, nrm = cloud
    idx = build_neighbours(pts, 30).take(30)[0].astype(np.int64)
    flag, gap, reach = border.border_flags(pts, nrm, idx)
    bounded, bounded_reach = np.empty(len(pts)), np.empty(len(pts))
    kern.tangent_extent(pts, nrm, idx, border.N_DIRS, bounded, bounded_reach, 0, True)
    assert np.array_equal(reach, bounded_reach, equal_nan=True)
    at_bound = bounded == kern.GAP_BOUND
    assert at_bound.any()
    if len(pts) == 20000:  # a closed surface: nearly every point skips the angles
        assert at_bound.mean() > 0.9
    assert np.array_equal(np.degrees(bounded[~at_bound]), gap[~at_bound], equal_nan=True)  # measured: as before
    assert (np.radians(gap[at_bound]) <= kern.GAP_BOUND + 1e-12).all()
    assert np.degrees(kern.GAP_BOUND) < border.GAP
    assert np.array_equal(border._border_flags(pts, nrm, idx), flag)
