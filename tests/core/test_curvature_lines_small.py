"""Lines of curvature and Gauss-Bonnet on clouds whose points are stored twice (exactly, or
1e-6 apart): the spacing is between distinct places, and copies share one cell's area."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

import core
from core import shapes

_CACHE = {}


def _torus(jitter):
    """A 2000-point torus, every point twice (``jitter`` apart), and its plain estimate."""
    if jitter not in _CACHE:
        s = shapes.torus(2000, seed=0)
        pts = np.repeat(s.points, 2, axis=0)
        pts[1::2] += jitter * np.random.default_rng(0).standard_normal((len(s.points), 3))
        _CACHE[jitter] = core.estimate(pts, k=15), core.estimate(s.points, k=15)
    return _CACHE[jitter]


@pytest.mark.parametrize("jitter", [0.0, 1e-6])
def test_lines_of_a_cloud_stored_twice_are_the_plain_ones(jitter):
    doubled, plain = _torus(jitter)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # was: divide by zero, then ZeroDivisionError
        lines = core.curvature_lines(doubled, direction="e1")
    ref = core.curvature_lines(plain, direction="e1")
    assert abs(len(lines) - len(ref)) <= 0.2 * len(ref)  # 1e-6 apart: 3000 lines of 30 points
    assert np.median([len(x) for x in lines]) == pytest.approx(np.median([len(x) for x in ref]), rel=0.2)


def test_gauss_bonnet_of_a_cloud_stored_twice_counts_each_place_once():
    doubled, plain = _torus(0.0)
    gb, ref = core.gauss_bonnet(doubled), core.gauss_bonnet(plain)
    assert gb.area == pytest.approx(ref.area, rel=1e-9) and gb.chi == pytest.approx(ref.chi, abs=1e-9)
    s = shapes.sphere(30, seed=0)
    with pytest.raises(ValueError, match="more than k=40 distinct points, got 30"):
        core.point_areas(np.repeat(s.points, 2, axis=0), np.repeat(s.normals, 2, axis=0))


def test_a_single_place_has_no_lines():
    res = core.estimate(np.repeat(shapes.sphere(200, seed=0).points, 2, axis=0), k=15)
    one = res.valid.copy()
    one[2:] = False  # the two copies of point 0 only
    with pytest.raises(ValueError, match="distinct"):
        core.curvature_lines(replace(res, valid=one))
