"""The principal directions' signs follow one world rule (core.frame.signed_directions), so
that the same surface gives the same e1 in memory and in tiles, after any number of passes."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import noise, shapes
from core.frame import DIRECTION_SIGN, signed_directions


@pytest.mark.parametrize("kwargs", [dict(), dict(k=15), dict(k=15, passes=3), dict(k=12, method="ct"),
                                    dict(k=15, method="qp")])
def test_every_result_keeps_the_rule_and_a_right_handed_frame(kwargs):
    pts = noise.add_noise(shapes.saddle(3000, seed=2).points, 0.1, seed=4)
    res = core.estimate(pts, **kwargs)
    v = res.valid
    assert v.mean() > 0.9
    assert (res.e1[v] @ DIRECTION_SIGN >= 0).all()
    hand = np.einsum("ij,ij->i", np.cross(res.e1, res.e2), res.normals)[v]
    np.testing.assert_allclose(hand, 1.0, atol=1e-9)


def test_rule_leaves_nan_rows_and_ties_alone():
    e1 = np.array([[np.nan] * 3, [-1.0, 0, 0], [1.0, 0, 0]])
    e2 = np.array([[np.nan] * 3, [0, -1.0, 0], [0, 1.0, 0]])
    a, b = signed_directions(e1, e2)
    assert np.isnan(a[0]).all() and np.isnan(b[0]).all()
    np.testing.assert_array_equal(a[1:], [[1.0, 0, 0], [1.0, 0, 0]])
    np.testing.assert_array_equal(b[1:], [[0, 1.0, 0], [0, 1.0, 0]])
