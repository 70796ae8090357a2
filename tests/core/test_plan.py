"""The frozen plan of an estimate: defaults resolved once, bad options refused before any
compiled kernel runs, and the whole-cloud quantities a tiled run must fix."""

from __future__ import annotations

import dataclasses
import pickle
import re
import sys

import numpy as np
import pytest

import core
from core import scale, shapes


@pytest.fixture(scope="module")
def sample():
    return shapes.torus(1500, seed=3)


def test_plan_resolves_the_automatic_and_the_paper_pipelines():
    auto = core.plan(10_000)
    assert auto.auto and auto.candidates == scale.candidates(10_000) and auto.k_search == scale.AUTO_KS[-1]
    assert auto.options["robust"] == "tukey" and auto.options["degree"] == scale.AUTO_DEGREE
    assert auto.passes == core.estimate.__globals__["AUTO_PASSES"] and auto.adaptive and auto.initial == "jet"
    assert auto.orientation == "outward" and auto.k_initial == 15
    paper = core.plan(10_000, k=15, method="nr")
    assert not paper.auto and paper.k_search == 15 and paper.candidates == (15,) and paper.passes == 1
    assert paper.options["degree"] == 1 and paper.options["robust"] is None and paper.initial == "pca"
    assert core.plan(100, k=15, orientation="auto", normals_given=True).orientation == "keep"
    assert core.plan(100, k=15, orientation=[0, 0, 5]).orientation == (0.0, 0.0, 5.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        paper.k_search = 30
    with pytest.raises(TypeError):
        paper.options["degree"] = 2
    again = pickle.loads(pickle.dumps(auto))  # a plan can travel to a worker process
    assert again == auto and again.options == auto.options
    with pytest.raises(TypeError):
        again.options.update(degree=1)


@pytest.mark.parametrize("k", ["auto", 30])
@pytest.mark.parametrize("value", [7, 0, "3", 3.0, None, True, np.float64(2.0)])
def test_a_bad_degree_is_refused_before_any_kernel(k, value):
    with pytest.raises(ValueError, match=rf"degree {re.escape(repr(value))} is invalid; must be one of \[1, 2, 3\]"):
        core.plan(1000, k=k, options={"degree": value})


@pytest.mark.parametrize("option, value", [
    ("weights", "gauss"), ("weights", None), ("constraint", "strict"), ("constraint", 1),
    ("robust", "cauchy"), ("robust", False), ("robust", 0),
])
def test_every_normal_fit_option_is_checked(option, value):
    for k in ("auto", 15):
        with pytest.raises(ValueError, match=rf"{option} {re.escape(repr(value))} is invalid; must be one of"):
            core.plan(1000, k=k, options={option: value})


@pytest.mark.parametrize("value", [1, 4, 2.0, "2", True])
def test_jet_degree_is_checked(value):
    with pytest.raises(ValueError, match=rf"degree {re.escape(repr(value))} is invalid; must be 2 or 3"):
        core.plan(1000, k=20, method="jet", options={"degree": value})


@pytest.mark.parametrize("kwargs, match", [
    (dict(tol=True), "tol must be a positive number"),
    (dict(noise=-1.0), "noise must be a finite number >= 0"),
    (dict(crease_typical=float("nan")), "crease_typical must be a finite number >= 0"),
    (dict(initial=None), "initial None is invalid"),
    (dict(orientation="up"), "orientation 'up' is invalid"),
    (dict(orientation=(1, 2)), "viewpoint must be 3 finite numbers"),
    (dict(k="15"), 'k must be an integer or "auto"'),
    (dict(k="auto", method="qp"), 'k="auto" is available for methods nf and nr'),
])
def test_bad_plan_arguments_name_themselves(kwargs, match):
    with pytest.raises(ValueError, match=match):
        core.plan(1000, **kwargs)


def test_keywords_are_read_in_any_case_and_reported_in_lower_case(sample):
    """Users type "Auto", "NR", "Outward" (as in MeshLab's and CloudCompare's dialogs)."""
    assert core.plan(1000, k=" Auto ", method="NR", initial="JET", orientation="Outward",
                     options={"robust": "Huber", "weights": "THETA"}) == core.plan(
        1000, k="auto", method="nr", initial="jet", orientation="outward",
        options={"robust": "huber", "weights": "theta"})
    a = core.estimate(sample.points, k="AUTO", orientation="OUTWARD")
    b = core.estimate(sample.points)
    assert a.k == "auto" and a.params["orientation"] == "outward"
    np.testing.assert_array_equal(a.k1, b.k1)
    with pytest.raises(ValueError, match="robust 'cauchy' is invalid"):
        core.plan(1000, options={"robust": "Cauchy"})


def test_estimate_refuses_a_degree_7_with_automatic_k(sample):
    with pytest.raises(ValueError, match=r"degree 7 is invalid"):
        core.estimate(sample.points, options={"degree": 7})


def test_a_plan_runs_the_same_estimate(sample):
    p = core.plan(len(sample.points), k=15, method="nr", options={"robust": "huber"})
    a = core.estimate(sample.points, k=15, method="nr", options={"robust": "huber"})
    b = core.estimate(sample.points, plan=p)
    for name in ("normals", "k1", "k2", "valid", "crease", "outlier_score"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    with pytest.raises(ValueError, match="pass either plan or k, not both"):
        core.estimate(sample.points, k=20, plan=p)
    with pytest.raises(ValueError, match="plan was made for"):
        core.estimate(sample.points[:-1], plan=p)
    with pytest.raises(ValueError, match="plan was made with normals_given=False"):
        core.estimate(sample.points, sample.normals, plan=p)
    given = core.plan(len(sample.points), k=15, normals_given=True)
    r = core.estimate(sample.points, sample.normals, plan=given)
    np.testing.assert_array_equal(r.k1, core.estimate(sample.points, sample.normals, k=15).k1)


def test_fixing_the_measured_quantities_reproduces_the_run(sample):
    """What a tiled engine does: pass the noise and the typical crease residual the whole
    cloud measured, and every tile sees the same thresholds (here: the same cloud, so the
    same result, bit for bit); other values change the outcome."""
    ref = core.estimate(sample.points)
    fixed = core.plan(len(sample.points), noise=ref.params["noise"], crease_typical=ref.params["crease_typical"])
    r = core.estimate(sample.points, plan=fixed)
    for name in ("normals", "k1", "k2", "e1", "e2", "valid", "crease", "k_point", "outlier_score"):
        np.testing.assert_array_equal(getattr(r, name), getattr(ref, name))
    assert r.params["initial_k"] == ref.params["initial_k"]
    noisier = core.estimate(sample.points, plan=core.plan(len(sample.points), noise=0.2))
    assert noisier.params["noise"] == 0.2 and noisier.params["initial_k"] > ref.params["initial_k"]
    strict = core.estimate(sample.points, plan=core.plan(len(sample.points), crease_typical=0.0))
    assert strict.params["crease_typical"] == 0.0 and strict.crease.sum() >= ref.crease.sum()


@pytest.mark.parametrize("options, match", [
    ({"degree": 4}, r"degree 4 is invalid; must be one of \[1, 2, 3\]"),  # 4 exists only inside the jet rule
    ({"degree": 2.5}, r"degree 2.5 is invalid"),
    ({"degree": "cubic"}, r"degree 'cubic' is invalid"),
    ({"degree": 3, "bogus": 1}, r"option\(s\) \['bogus'\] do not apply to method 'nr'"),
])
@pytest.mark.parametrize("k", ["auto", 20])
def test_bad_options_are_refused_before_any_compiled_kernel_runs(monkeypatch, sample, options, match, k):
    """The refusal comes from the checks, not from a kernel: every step that would touch the
    points (the degenerate-cloud probe, the neighbour search, the stages) is made to fail."""
    import core.degenerate as degenerate
    est = sys.modules["core.estimate"]

    def ran(*args, **kwargs):
        raise AssertionError("a computation ran before the options were checked")

    monkeypatch.setattr(degenerate, "reason", ran)
    monkeypatch.setattr(est, "prepare", ran)
    with pytest.raises(ValueError, match=match):
        core.estimate(sample.points, k=k, options=options)


def test_auto_candidates_stay_within_half_a_small_cloud():
    """A neighbourhood wider than half a small closed object reaches round it: a 30-point
    sphere took k = 20 and gave H 1.7, a 20-point one a saddle at every point."""
    assert core.scale.candidates(30) == (15,) and core.scale.candidates(20) == (10,)
    assert core.scale.candidates(100) == (20, 28, 40) and core.scale.candidates(6000)[-1] == 320
    for n in (20, 30):
        i = np.arange(n) + 0.5
        phi, theta = np.arccos(1 - 2 * i / n), np.pi * (1 + 5 ** 0.5) * i
        sphere = np.c_[np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)]
        res = core.estimate(sphere)
        assert res.valid.all() and np.median(np.abs(np.abs(res.mean) - 1.0)) < 0.05
