"""Library-API defects from the API sweep (a scientist's usage): each test failed before its fix."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import passes


def _turns(points, **kw):
    """The mean turn of the normals of each fit the pass rule saw."""
    seen = []
    orig = passes.PassRule.step

    def spy(self, p, change):
        seen.append(change)
        return orig(self, p, change)

    passes.PassRule.step = spy
    try:
        res = core.estimate(points, **kw)
    finally:
        passes.PassRule.step = orig
    return res, seen


def test_tol_stops_after_the_first_pass_that_turns_the_normals_less_than_tol():
    pts = core.shapes.torus(1500, seed=0).points
    _, turns = _turns(pts, k=15, passes=4, tol=1e-9)  # never converges: every fit's turn
    assert turns[1] < turns[0]
    tol = 0.5 * (turns[1] + min(turns[0], turns[1] * 4))  # above pass 1's turn, below the first fit's
    res, _ = _turns(pts, k=15, passes=4, tol=tol)
    assert res.params["passes_run"] == 1  # was 2: the rule looked at the previous pass
    np.testing.assert_array_equal(res.k1, core.estimate(pts, k=15, passes=1).k1)


def test_a_masked_array_s_masked_rows_are_not_used():
    s = core.shapes.sphere(1500, seed=0)
    pts = np.ma.masked_array(s.points.copy(), mask=False)
    pts[:20] = np.ma.masked
    pts.data[:20] = 5.0  # garbage under the mask
    with pytest.raises(ValueError, match="masked"):
        core.estimate(pts, k=15)
    res = core.estimate(pts, k=15, drop_nonfinite=True)
    assert res.params["dropped"] == 20
    np.testing.assert_array_equal(res.k1, core.estimate(s.points[20:], k=15).k1)
    normals = np.ma.masked_array(s.normals.copy(), mask=False)
    normals[5] = np.ma.masked
    normals.data[5] = -s.normals[5]  # inward, under the mask: repaired from the neighbours instead
    res = core.estimate(s.points, normals, k=15)
    assert res.params["normals_repaired"]["unusable"] == 1
    assert res.normals[5] @ s.normals[5] > 0.99


@pytest.mark.parametrize("answer", [False, np.False_, 0])
def test_a_false_answer_of_the_progress_callback_cancels(answer):
    pts = core.shapes.sphere(500, seed=0).points
    with pytest.raises(core.Cancelled):
        core.estimate(pts, k=15, progress=lambda f, s: answer)
    core.estimate(pts, k=15, progress=lambda f, s: None)  # None goes on


@pytest.mark.parametrize("value", [np.float32(0.1), np.float64(0.1), np.int64(1)])
def test_numpy_scalars_are_numbers_for_tol(value):
    res = core.estimate(core.shapes.sphere(500, seed=0).points, k=15, passes=2, tol=value)
    assert res.params["passes_run"] >= 1


def test_numpy_scalars_are_numbers_for_point_types():
    res = core.estimate(core.shapes.cylinder(1000, seed=0).points, k=15)
    np.testing.assert_array_equal(core.point_types(res, zero=np.float32(0.1)), core.point_types(res, zero=0.1))
    with pytest.raises(ValueError, match="zero"):
        core.point_types(res, zero=np.True_)


def test_a_numpy_integer_k_over_the_distinct_positions_gets_the_copies_message():
    pts = np.repeat(core.shapes.sphere(300, seed=0).points, 2, axis=0)
    for k in (301, np.int64(301)):
        with pytest.raises(ValueError, match="distinct positions"):
            core.estimate(pts, k=k)
