"""The jet scale rule of issue 15 (core.scale.choose_jets): noise level, bias, sizes chosen."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import kernels, metrics, neighbour_budget, noise, scale, shapes, tuning
from core.kernels import jets
from core.linalg import tangent_basis
from core.neighbours import build_neighbours


def _choose(sample, level, seed=1):
    pts = noise.add_noise(sample.points, level, seed=seed) if level else sample.points
    ks = scale.jet_candidates(len(pts))
    nb = build_neighbours(pts, ks[-1])
    k, frame, _, _ = scale.choose_jets(pts, sample.normals, nb, np.ones(len(pts), bool), ks, lambda *a: None)
    return pts, k, frame


def _noise_sd(sample, level):
    """The rule's noise estimate (median over points) for noise along the normals."""
    pts = sample.points
    if level:
        pts = noise.add_noise(pts, level, seed=1, direction="normal", normals=sample.normals)
    idx, dist = build_neighbours(pts, 28).take(28)
    t1, t2 = tangent_basis(sample.normals)
    s = dist[:, 14].copy()
    rss = np.empty((len(pts), 2))
    n = len(pts)
    f = kernels.Frames(pts, sample.normals, np.ascontiguousarray(idx), np.zeros(n, dtype=np.int64), s, np.arange(n),
                       t1, t2, sample.normals.copy())
    jets.jet_residuals(f, np.array(scale.NOISE_KS), 1e-10, rss)
    return np.sqrt(np.median(scale.noise_variance(rss[:, 0], rss[:, 1], s, idx)[0]))


@pytest.mark.parametrize("level", [0.1, 0.3, 1.0])
def test_noise_variance_recovers_sigma(level):
    s = shapes.plane(3000, seed=3)
    sd = _noise_sd(s, level)
    assert abs(sd / (level * noise.mean_spacing(s.points)) - 1) < 0.1


def test_noise_variance_is_not_fooled_by_curvature():
    """Noise-free, a cubic's residual on a curved patch is bias, not noise: ~0."""
    s = shapes.torus(4000, R=1.0, r=0.4, seed=2)
    assert _noise_sd(s, 0.0) < 0.01 * noise.mean_spacing(s.points)


def test_noise_free_ends_small_where_it_bends_noisy_wide_where_flat():
    torus = shapes.torus(4000, seed=2)
    _, k, _ = _choose(torus, 0.0)
    # the cubic stops at its smallest size; the degree rule then takes the quartic on its own smallest size
    assert np.median(k) == min(kd for _, kd in tuning.JET_DEGREES)
    plane = shapes.plane(4000, seed=2)
    _, k_plane, _ = _choose(plane, 0.3)
    assert np.median(k_plane[plane.interior]) == scale.JET_KS[-1]
    small = shapes.torus(4000, R=1.0, r=0.35, seed=2)  # strongly curved: bias caps k
    _, k_small, _ = _choose(small, 0.3)
    assert np.median(k_small) < scale.JET_KS[-1]


def test_noise_free_jets_as_accurate_as_the_best_fixed_jet():
    s = shapes.chirp(4000, seed=4)
    pts, k, (nrm, k1, k2, e1, e2, ok) = _choose(s, 0.0)
    assert ok[s.interior].mean() > 0.99
    res = core.estimate(pts, s.normals, k=15, method="jet", options={"degree": 3})
    ours = np.abs(0.5 * (k1 + k2) - s.mean)[s.interior & ok].mean()
    fixed = metrics.summary(res, s)["mean"]
    assert ours < 1.2 * fixed


def test_candidates_respect_the_budget():
    top = scale.jet_candidates(1_000_000)[-1]
    assert 1_000_000 * neighbour_budget.entries(top) <= tuning.NEIGHBOUR_BUDGET
    assert scale.jet_candidates(5000) == scale.JET_KS
    assert scale.jet_candidates(100)[-1] <= 100


def test_default_keeps_the_jet_noise_free_and_nr_with_noise():
    s = shapes.chirp(4000, seed=5)
    r = core.estimate(s.points)
    assert r.params["jet_fraction"] > 0.9 and np.median(r.k_point) <= max(kd for _, kd in tuning.JET_DEGREES)
    assert np.isin(r.degree_point[r.valid], (1, 2, 3, 4, 5)).all()  # the jets' degrees, or NR's field (up to cubic)
    assert np.median(r.degree_point[r.valid]) > scale.JET_DEGREE  # noise-free: the bias of a cubic is left
    jet = core.estimate(s.points, k=15, method="jet", options={"degree": 3})
    for key in ("mean", "gaussian"):
        assert metrics.summary(r, s)[key] < 1.2 * metrics.summary(jet, s)[key], key
    noisy = core.estimate(noise.add_noise(s.points, 0.3, seed=6))
    assert noisy.params["jet_fraction"] < 0.01 and np.median(noisy.k_point) >= 113
    paper = core.estimate(s.points, k=15)
    assert (paper.degree_point == 1).all() and paper.params["passes_run"] == 1


@pytest.mark.parametrize("n", [16, 21, 27])
def test_clouds_too_small_to_measure_the_noise_fall_back_to_nr(n):
    """Fewer neighbours than NOISE_KS[-1]: no jets (they would read past the neighbours)."""
    s = shapes.sphere(n, seed=4)
    r = core.estimate(s.points)
    assert r.params["jet_fraction"] == 0.0 and r.valid.any()


@pytest.mark.parametrize("n", [30, 1000, 10_000, 400_000])
def test_the_plan_searches_as_far_as_the_largest_jet(n):
    p = core.plan(n, k="auto")
    jks = [k for k in scale.jet_candidates(n) if k <= p.candidates[-1]]
    assert jks and max(jks) <= p.k_search and p.k_search == p.candidates[-1]


def _ripple(x, y, a=0.057, w=17.5):
    """z = a sin(wx) sin(wy): at 8000 points a wavelength of 32 spacings and slopes up to 1,
    curvature changing sign every 8 spacings (the sweep's fast ripple)."""
    sx, cx, sy, cy = np.sin(w * x), np.cos(w * x), np.sin(w * y), np.cos(w * y)
    return (a * sx * sy, a * w * cx * sy, a * w * sx * cy, -a * w * w * sx * sy, a * w * w * cx * cy,
            -a * w * w * sx * sy)


@pytest.mark.xfail(strict=True, reason="open: quiet points whose jet is refused take the NF rule's wide k")
def test_quiet_points_off_the_jet_stay_small_where_the_surface_ripples():
    """Noise-free, a point whose jet is not kept (its 15 nearest reach 0.4 of a radius of
    curvature, or its jet leans off a blurred initial normal) is fitted by NR on the NF rule's
    k: on a ripple 80-226 neighbours, whose normal field is off by 7.6 degrees (median), 31 %
    of the normals by more than 10. Capping it at the jet's k met this (1.5 %, H 0.093) but
    broke the floor under a scanner (test_scan_lines) and the pose invariance of the scale."""
    s = shapes._graph_sample("ripple", _ripple, 8000, np.random.default_rng(0))
    res = core.estimate(s.points)
    use = s.interior & res.valid
    off = np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", res.normals, s.normals)), 0, 1)))[use]
    assert np.mean(off > 10) < 0.05  # 0.31; 0.015 with the cap
    assert np.percentile(res.k_point[use], 90) <= 40  # 226
    h = 0.5 * (s.k1 + s.k2)
    scale_h = np.sqrt(np.mean(h[use] ** 2))
    # 0.130; 0.093 with the cap; the paper's k = 15: 0.19; a cubic jet on 15: 0.105
    assert np.median(np.abs(res.mean - h)[use]) < 0.11 * scale_h


def test_ring_sums_are_the_cubic_least_squares_sums():
    """The jets' cubic sums are added a ring at a time by moments (jet_sums.ring_sums,
    vectorised): over rings of the jet rule's sizes they are numpy's R^T R, R^T w and w.w of
    the neighbours so far, to rounding, neighbours without a height (NaN) left out, G's
    whole lower triangle filled and nothing past the cubic's block touched."""
    from core.kernels.algebra import poly_row
    from core.kernels.jet_sums import P3, P5, ring_sums

    rng = np.random.default_rng(7)
    ks = [0, 15, 20, 28, 40, 56, 80, 113, 160, 226, 320]
    uvw = rng.normal(size=(3, 320)) * [[2.0], [1.5], [0.2]]
    uvw[2, [3, 17, 18, 200]] = np.nan
    rows = np.empty((320, P3))
    for j, (u, v) in enumerate(uvw[:2].T):
        poly_row.py_func(u, v, 3, rows[j])
    G, b, acc = np.zeros((P5, P5)), np.zeros(P5), np.zeros(2)
    packed, R = (np.empty(320), np.empty(320), np.empty(320)), np.empty((P3, 320))
    lower = np.tril_indices(P3)
    for lo, hi in zip(ks, ks[1:]):
        ring_sums(uvw, lo, hi, G, b, acc, *packed, R)
        has = np.isfinite(uvw[2, :hi])
        M, w = rows[:hi][has], uvw[2, :hi][has]
        np.testing.assert_allclose(G[lower], (M.T @ M)[lower], rtol=1e-12, atol=1e-13 * np.abs(M.T @ M).max())
        np.testing.assert_allclose(b[:P3], M.T @ w, rtol=1e-12, atol=1e-13 * np.abs(M.T @ w).max())
        np.testing.assert_allclose(acc, [w @ w, 0.0], rtol=1e-13)
    assert (G[P3:] == 0).all() and (G[:, P3:] == 0).all() and (b[P3:] == 0).all()
