"""File normals repaired per row (core.normal_repair)."""

from __future__ import annotations

import warnings

import numpy as np

from core import build_neighbours, shapes
from core.normal_repair import repair_normals, split_normals


def test_split_renormalises_and_marks_unusable():
    given = np.array([[0, 0, 2.0], [0, 0, 0], [np.nan, 0, 1], [0, 1.0, 0], [1e-9, 0, 0], [np.inf, 0, 0]])
    before = given.copy()
    unit, usable, counts = split_normals(given)
    np.testing.assert_array_equal(given, before)
    np.testing.assert_array_equal(usable, [True, False, False, True, False, False])
    np.testing.assert_allclose(unit[[0, 3]], [[0, 0, 1.0], [0, 1.0, 0]])
    assert np.isnan(unit[~usable]).all()
    assert counts == {"unusable": 4, "renormalised": 1}


def test_normals_near_the_float_limit_are_unscaled_not_unusable():
    unit = shapes.sphere(300, seed=1).normals
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the median of two lengths near 1e308 overflowed (a warning) to inf
        got, usable, counts = split_normals(unit * 1e308)
    assert usable.all() and counts == {"unusable": 0, "renormalised": 300}  # was: all unusable, re-estimated
    np.testing.assert_allclose(got, unit, atol=1e-15)


def test_repair_estimates_unusable_rows_with_the_neighbours_sign():
    """A sphere's file normals, inward, with 10 % zeroed and 5 % NaN and the rest scaled by 3:
    every repaired normal is unit and inward like its neighbours (error < 5 degrees)."""
    s = shapes.sphere(4000, seed=5)
    rng = np.random.default_rng(0)
    given = -3.0 * s.normals
    bad = rng.random(4000)
    given[bad < 0.10] = 0.0
    given[(bad >= 0.10) & (bad < 0.15)] = np.nan
    nb = build_neighbours(s.points, 15)
    fixed, counts = repair_normals(s.points, given, *nb.take(15))
    assert counts["unusable"] == int(np.count_nonzero(bad < 0.15))
    assert counts["estimated"] == counts["unusable"]
    assert counts["renormalised"] == 4000 - counts["unusable"]
    np.testing.assert_allclose(np.linalg.norm(fixed, axis=1), 1.0)
    assert np.all(np.einsum("ij,ij->i", fixed, -s.normals) > np.cos(np.radians(5)))
