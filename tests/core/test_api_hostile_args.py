"""Arguments of the wrong kind get an error that names the argument (not a bare
AttributeError deep inside), and a result with no valid point gets NaN scales and totals,
not a made-up number (cases from a hostile-input sweep)."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

import core
from core import shapes
from core.io import read_cloud, write_cloud, write_result

_POINTS = shapes.sphere(300, seed=1).points


@pytest.mark.parametrize("value", ["no", 1, 0, None, np.array([True])])
def test_drop_nonfinite_takes_true_or_false_only(tmp_path, value):
    pts = np.r_[_POINTS, [[np.nan] * 3]]
    with pytest.raises(ValueError, match=r"drop_nonfinite must be True or False"):
        core.estimate(pts, drop_nonfinite=value)  # "no" dropped the NaN row: any truthy value did
    path = write_cloud(tmp_path / "c.xyz", _POINTS)
    with pytest.raises(ValueError, match=r"drop_nonfinite must be True or False"):
        read_cloud(path, drop_nonfinite=value)


@pytest.mark.parametrize("fn", [core.point_types, core.curvature_scale, core.total_curvature, core.gauss_bonnet,
                                core.curvature_lines, lambda a: core.local_fit(a, 5)])
def test_the_teaching_functions_name_a_result_that_is_not_one(fn):
    with pytest.raises(TypeError, match=r"res must be a curvature result .*ndarray"):
        fn(_POINTS)


def test_file_paths_of_the_wrong_type_are_named(tmp_path):
    res = core.estimate(_POINTS, k=15)
    with pytest.raises(TypeError, match=r"path must be a file path .*NoneType"):
        read_cloud(None)
    with pytest.raises(TypeError, match=r"path must be a file path .*NoneType"):
        write_result(None, res)
    path = write_cloud(tmp_path / "c.xyz", _POINTS)
    assert len(read_cloud(bytes(path)).points) == len(_POINTS)  # a bytes path is a path


def test_a_result_without_a_valid_point_has_no_scale_and_no_total():
    res = core.estimate(np.ones((50, 3)), k=15)  # one place: every point invalid
    assert not res.valid.any()
    assert math.isnan(core.curvature_scale(res))  # was 1 / the smallest float, 4.5e307
    assert math.isnan(core.total_curvature(res))  # was 0.0, as if the integral were known
    assert (core.point_types(res) == -1).all()


def test_a_pipe_is_not_read_as_an_empty_file(tmp_path):
    fifo = tmp_path / "p.xyz"
    os.mkfifo(fifo)  # nothing writes into it: reading would block
    with pytest.raises(core.io.CloudFileError, match=r"p\.xyz.*not a regular file"):  # was "is empty (0 bytes)"
        read_cloud(fifo)
