"""k="auto" near a junction of sheets does not depend on the pose: not at exactly 30 deg, nor far
from the origin.

The own-sheet rule (:mod:`core.one_sheet`) takes a neighbour for another sheet only if its
normal is parallel to the point's within 30 deg: sheets that meet at exactly that angle gave
cosines within rounding of the threshold, so the rounding of each pose decided which rows
held another sheet, and k with them (12000 points, a turned, shifted or scaled copy of the
same array: k_point moved at 0.5-2 % of the points, |H| by more than 0.1 at 3-9 %, all within
10 spacings of the line). The poses here keep both sheets within 45 deg of level, so the
floors-up convention (:func:`core.orientation.floors_up`, tied to the world's z on purpose)
gives every part the same side in both. (Left open: a turn about z can give a half-sheet of
the X the other side, whose signed normals the fold test then reads as folded; README,
"Pose does not move the flags".)
"""

import numpy as np
import pytest

import core
import test_shallow_creases as shallow

#: a share of the points allowed to move: near-ties that are really ties (a robust fit on two
#: sheets that may settle on either) may move a few points; the old rule moved 0.5-2 % (k)
#: and 3-9 % (|H| by > 0.1)
K_SHARE = 0.001
H_SHARE = 0.005


def _levelled_pose(pts, seed, scale, shift):
    """``pts`` tilted by 2-10 deg about a random horizontal axis (both sheets stay within 45 deg
    of level), scaled by ``scale`` and shifted by ``shift``."""
    rng = np.random.default_rng(seed)
    a, tilt = rng.uniform(0, 2 * np.pi), np.radians(rng.uniform(2, 10))
    axis = np.array([np.cos(a), np.sin(a), 0.0])
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    turn = np.eye(3) + np.sin(tilt) * cross + (1 - np.cos(tilt)) * cross @ cross  # Rodrigues
    return scale * pts @ turn.T + shift


@pytest.mark.parametrize("kind, seed, scale, shift", [("T", 0, 1.0, [3.0, -7.0, 11.0]), ("T", 1, 10.0, [0.0, 0.0, 0.0]),
                                                      ("X", 0, 0.1, [300.0, -70.0, 0.0]), ("X", 1, 1.0, [0.5, 0.25, -2.0])])
def test_thirty_degree_junction_is_pose_invariant(kind, seed, scale, shift):
    """The same array estimated in two poses: k_point and |H| (in the array's units) agree."""
    pts, _, _ = shallow._junction(kind, seed)
    plain = core.estimate(pts)
    posed = core.estimate(_levelled_pose(pts, seed + 5, scale, shift))
    assert np.mean(plain.k_point != posed.k_point) < K_SHARE
    moved = np.abs(np.abs(plain.mean) - scale * np.abs(posed.mean)) > 0.1
    assert np.mean(moved) < H_SHARE
    assert np.array_equal(plain.valid, posed.valid)


@pytest.mark.parametrize("kind, seed, degrees, scale, shift", [("X", 0, 60, 0.1, 300.0), ("T", 1, 45, 1.0, 3000.0),
                                                               ("X", 0, 60, 1.0, 3000.0)])
def test_junction_far_from_the_origin_keeps_k(kind, seed, degrees, scale, shift):
    """A junction moved thousands of spacings from the origin: its exactly planar sheets measure
    no noise, and the jets' noise floor was 1e-12 of the 15th neighbour's distance, below the
    rounding of coordinates that large (k_point moved at 0.3-1 % of the points: a 60 deg X
    scaled 0.1 and moved 300 away, 115 of 12000); the floor now grows with the coordinates."""
    pts, _, _ = shallow._junction(kind, seed, np.radians(degrees))
    plain = core.estimate(pts)
    moved = core.estimate(scale * pts + shift * np.array([1.0, -0.5, 0.25]))
    assert np.mean(plain.k_point != moved.k_point) < K_SHARE
    assert np.array_equal(plain.valid, moved.valid)
