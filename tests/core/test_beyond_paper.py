"""Automatic scale, robust fits, crease and outlier flags, early-stopping refinement."""

import numpy as np
import pytest

import core
from core import scale
from core.estimate import AUTO_PASSES


@pytest.fixture(scope="module")
def noisy_torus():
    s = core.shapes.torus(5000, seed=3)
    return s, core.noise.add_noise(s.points, 0.2, seed=4)


def test_auto_k_is_the_default_and_reported_per_point(noisy_torus):
    s, p = noisy_torus
    r = core.estimate(p)
    assert r.k == "auto" and r.params["k"] == "auto"
    assert r.k_point.shape == (len(p),)
    assert set(np.unique(r.k_point)) <= set(scale.AUTO_KS)
    assert r.params["initial"] == "jet"


def test_auto_k_beats_the_papers_k_on_a_noisy_torus(noisy_torus):
    s, p = noisy_torus
    auto = core.metrics.summary(core.estimate(p), s)
    fixed = core.metrics.summary(core.estimate(p, k=15), s)
    for key in ("mean", "gaussian", "direction_deg"):
        assert auto[key] < 0.6 * fixed[key], key
    assert auto["direction_deg"] < 5.0  # issue target at noise 0.2 of the spacing


def test_ici_kernel_matches_separate_fits():
    """The one-pass nested-sums kernel picks what separate NF fits at each k would, in the
    same frames (turning with the cloud: Chunk.turning). (k="auto" now chooses by the jet
    rule, tested in test_scale_jets; this is the NF rule.)"""
    s = core.shapes.saddle(3000, seed=2)
    p = core.noise.add_noise(s.points, 0.1, seed=1)
    nb = core.build_neighbours(p, scale.AUTO_KS[-1])
    chosen = scale.choose_k(p, s.normals, nb, np.ones(len(p), bool), scale.AUTO_KS, scale.AUTO_DEGREE,
                            lambda *a: None)
    idx, dist = nb.take(scale.AUTO_KS[-1])
    from core.methods import get_method
    from core.patch import Chunk

    m = get_method("nf")
    centres = np.arange(200)
    h = dist[centres, -1]
    lo, hi = np.full((200, 3), -np.inf), np.full((200, 3), np.inf)
    alive = np.ones(200, bool)
    pick = np.full(200, scale.AUTO_KS[0])
    for k in scale.AUTO_KS:
        chunk = Chunk.build(nb.points, s.normals, idx[centres], h, centres, np.full(200, k)).turning(scale.AUTO_KS[0])
        _, W, ok, diag = m.fit(chunk, weights="uniform", constraint="none", robust=None, degree=scale.AUTO_DEGREE)
        est = np.stack([W[:, 0, 0], 0.5 * (W[:, 0, 1] + W[:, 1, 0]), W[:, 1, 1]], axis=1)
        sd = np.sqrt(diag["var"])
        lo, hi = np.maximum(lo, est - scale.GAMMA * sd), np.minimum(hi, est + scale.GAMMA * sd)
        alive &= ok & (lo <= hi).all(axis=1)
        pick = np.where(alive, k, pick)
    np.testing.assert_array_equal(chosen[:200], pick)


def test_auto_k_only_for_normal_fitting():
    with pytest.raises(ValueError, match=r'k="auto" is available for methods nf and nr'):
        core.estimate(core.shapes.sphere(500).points, k="auto", method="ct")
    with pytest.raises(ValueError, match=r"k must be an integer or \"auto\", got 'big'"):
        core.estimate(core.shapes.sphere(500).points, k="big")
    with pytest.raises(ValueError, match=r"initial 'svd' is invalid"):
        core.estimate(core.shapes.sphere(500).points, initial="svd")


def test_jet_initial_normals_are_closer_than_pca():
    s = core.shapes.torus(4000, seed=1)
    pca = core.metrics.summary(core.estimate(s.points, k=15, initial="pca"), s)
    jet = core.metrics.summary(core.estimate(s.points, k=15, initial="jet"), s)
    assert jet["normal_deg"] < 0.8 * pca["normal_deg"]
    assert jet["mean"] < 0.5 * pca["mean"]


def test_robust_fit_keeps_inliers_accurate_with_outliers():
    s = core.shapes.torus(5000, seed=7)
    clean = core.noise.add_noise(s.points, 0.1, seed=8)
    dirty, is_out = core.noise.add_outliers(clean, 0.03, distance=(2.0, 8.0), seed=9)
    base = core.metrics.summary(core.estimate(clean), s)
    rob = core.estimate(dirty, options={"robust": "tukey"})
    got = core.metrics.summary(rob, s, mask=~is_out)
    for key in ("mean", "gaussian", "direction_deg"):
        assert got[key] < 1.25 * base[key], key  # issue target: < 25 % growth
    # outliers well off the surface are scored high and, in robust mode, left out
    # (flagged invalid, NaN curvature); a random displacement may run along the surface
    spacing = core.noise.mean_spacing(clean)
    off = np.abs(np.einsum("ij,ij->i", dirty - clean, s.normals)) / spacing
    assert np.mean(rob.outlier[is_out & (off > 4)]) > 0.8
    assert np.mean(rob.outlier[~is_out]) < 0.01
    assert not rob.valid[is_out & rob.outlier].any()
    assert np.isnan(rob.k1[is_out & rob.outlier]).all()


def test_refinement_passes_reweight_fewer_times_than_the_first_fit(monkeypatch):
    """The first robust fit reweights IRLS_ITERATIONS times, each refinement pass IRLS_LATER
    times (its input normals are already cleaned); the accuracy with outliers is kept."""
    from core import kernels, refinement, tuning

    seen = []
    real = kernels.Settings

    def spy(*args):  # the NF kernel's settings: args[3] robust code, args[4] reweightings
        if args[3]:
            seen.append(args[4])
        return real(*args)

    monkeypatch.setattr(kernels, "Settings", spy)
    s = core.shapes.torus(4000, seed=7)
    dirty, is_out = core.noise.add_outliers(core.noise.add_noise(s.points, 0.2, seed=8), 0.03, seed=9)
    res = core.estimate(dirty, k=40, passes=3, method="nr", options={"robust": "tukey", "degree": 3})
    assert res.params["passes_run"] >= 2
    assert seen[0] == tuning.IRLS_ITERATIONS and set(seen[1:]) == {tuning.IRLS_LATER}
    assert tuning.IRLS_LATER < tuning.IRLS_ITERATIONS
    monkeypatch.setattr(kernels, "Settings", real)
    errors = {}
    for later in (tuning.IRLS_ITERATIONS, tuning.IRLS_LATER):
        monkeypatch.setattr(refinement, "IRLS_LATER", later)
        r = core.estimate(dirty, k=40, passes=3, method="nr", options={"robust": "tukey", "degree": 3})
        errors[later] = core.metrics.summary(r, s, mask=~is_out)
    for key in ("mean", "gaussian", "direction_deg"):
        assert errors[tuning.IRLS_LATER][key] < 1.05 * errors[tuning.IRLS_ITERATIONS][key], key


@pytest.mark.parametrize("k, caught", [(15, 0.4), ("auto", 0.8)])
def test_crease_flags_cube_edges_not_faces_or_smooth_shapes(k, caught):
    cube = core.shapes.cube(20000, seed=1)
    r = core.estimate(cube.points, k=k)
    d = np.where(np.abs(cube.points) < 1 - 1e-9, 1 - np.abs(cube.points), np.inf).min(axis=1)
    spacing = core.noise.mean_spacing(cube.points)
    assert r.crease[d < 2 * spacing].mean() > caught
    assert r.crease[d > 8 * spacing].mean() < 0.01
    for shape in ("torus", "saddle", "ellipsoid"):
        s = core.shapes.SHAPES[shape](4000, seed=2)
        assert core.estimate(s.points).crease.mean() < 0.01, shape


def test_tolerance_stops_refinement_early():
    s = core.shapes.sphere(3000, seed=1)
    p = core.noise.add_noise(s.points, 0.05, seed=2)
    r = core.estimate(p, k=15, passes=10, tol=0.5)
    assert 1 <= r.params["passes_run"] < 10
    full = core.estimate(p, k=15, passes=10)
    assert full.params["passes_run"] == 10
    with pytest.raises(ValueError, match="tol must be a positive number"):
        core.estimate(p, k=15, tol=-1)


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_polynomial_normal_fit_matches_numpy_least_squares(degree):
    """The compiled NF of any degree solves the same least squares as numpy's lstsq."""
    from core.methods import get_method
    from core.patch import Chunk

    s = core.shapes.ellipsoid(2000, seed=5)
    p = core.noise.add_noise(s.points, 0.1, seed=6)
    nb = core.build_neighbours(p, 40)
    idx, dist = nb.take(40)
    centres = np.arange(50)
    chunk = Chunk.build(p, s.normals, idx[centres], dist[centres, -1], centres)
    mu, W, ok, _ = get_method("nf").fit(chunk, constraint="none", degree=degree)
    pa = chunk.patch
    u, v = pa.u, pa.v
    cols = [np.ones_like(u), u, v] + ([u * u, u * v, v * v] if degree > 1 else [])
    if degree == 3:
        cols += [u**3, u * u * v, u * v * v, v**3]
    A = np.stack(cols, axis=2)
    assert ok.all()
    for r in range(len(centres)):
        cx = np.linalg.lstsq(A[r], pa.X[r], rcond=None)[0]
        cy = np.linalg.lstsq(A[r], pa.Y[r], rcond=None)[0]
        np.testing.assert_allclose(mu[r], [cx[0], cy[0]], atol=1e-9)
        np.testing.assert_allclose(W[r], [[cx[1], cx[2]], [cy[1], cy[2]]], atol=1e-7)


def test_higher_degree_removes_the_bias_of_wide_neighbourhoods():
    """Noise-free torus, exact normals, k = 80: the linear normal model (eq. 23) bends
    over the patch; a cubic one follows it."""
    s = core.shapes.torus(5000, seed=11)
    err = {d: core.metrics.summary(core.estimate(s.points, s.normals, k=80, method="nf", options={"degree": d}), s)
           for d in (1, 3)}
    for key in ("mean", "gaussian", "direction_deg"):
        assert err[3][key] < 0.3 * err[1][key], key


def test_degree_options_are_validated():
    pts = core.shapes.sphere(500, seed=1).points
    with pytest.raises(ValueError, match=r"degree 4 is invalid; must be one of \[1, 2, 3\]"):
        core.estimate(pts, k=30, options={"degree": 4})
    with pytest.raises(ValueError, match=r"k=10 is out of range"):
        core.estimate(pts, k=10, options={"degree": 3})  # 10 monomials need 11 neighbours
    assert core.estimate(pts, k=11, options={"degree": 3}).valid.mean() > 0.95


def test_auto_uses_the_cubic_normal_fit_and_stays_close_to_exact_normals_without_noise():
    """Issue 4 target: noise-free, the default is within 1.5x of NF with exact normals."""
    s = core.shapes.torus(5000, seed=12)
    r = core.estimate(s.points)
    assert r.params["options"]["degree"] == scale.AUTO_DEGREE and r.params["passes"] == AUTO_PASSES
    assert r.params["passes_run"] <= 1  # no noise to average: refinement would only smooth the shape
    auto = core.metrics.summary(r, s)
    nfe = core.metrics.summary(core.estimate(s.points, s.normals, k=15, method="nf"), s)
    for key in ("mean", "gaussian", "direction_deg"):
        assert auto[key] < 1.5 * nfe[key], key


def test_auto_on_a_tiny_cloud_falls_back_to_the_linear_fit():
    """Too small for the first candidate: half of itself, at least 8 (core.scale.candidates)."""
    pts = core.shapes.sphere(12, seed=2).points
    r = core.estimate(pts)
    assert r.params["options"]["degree"] == 1 and set(np.unique(r.k_point)) == {8}


def test_auto_k_stops_before_the_neighbourhood_wraps_around_a_sparse_tube():
    """1000 points on a torus (r = 1, spacing ~0.3): 160 neighbours would reach the far
    side of the tube, where the residuals explode and ICI alone sees no bias. The fold
    test stops k first, so auto stays better than the paper's k = 15."""
    s = core.shapes.torus(1000, seed=1)
    r = core.estimate(s.points)
    assert np.median(r.k_point) < 160  # without the fold test: 160
    auto = core.metrics.summary(r, s)
    paper = core.metrics.summary(core.estimate(s.points, k=15), s)
    for key in ("mean", "gaussian", "direction_deg"):
        assert auto[key] < 0.5 * paper[key], key


@pytest.mark.parametrize("seed", [1, 2])
def test_auto_k_is_not_stopped_by_noise_of_a_whole_spacing(seed):
    """Noise of one spacing (dense scans) turns some initial normals far off and lifts
    neighbours off the plane. Judged against the centre alone, 24 % of the points took
    that for a fold and kept 20 neighbours: a cubic fit there gave |H| errors up to 20
    on a unit sphere (mean 0.95). Judged against the neighbourhood, with noise margins
    and a fold confirmed by the next ring, nearly all points keep growing."""
    s = core.shapes.sphere(6000, seed=seed)
    p = core.noise.add_noise(s.points, 1.0, relative=True, seed=seed + 10)
    r = core.estimate(p)
    assert np.mean(r.k_point == core.scale.candidates(len(p))[0]) < 0.02
    auto = core.metrics.summary(r, s)["mean"]
    assert auto < 0.2
    assert auto < 0.15 * core.metrics.summary(core.estimate(p, k=15), s)["mean"]


@pytest.mark.parametrize("shape", ["torus", "sphere", "ellipsoid"])
def test_noise_alone_is_not_flagged_as_creases(shape):
    """At half a spacing of noise the linear fit explains little of the noisy initial
    normals anywhere; without comparing with the cloud's typical residual 45-70 % of a
    smooth shape was flagged."""
    s = core.shapes.SHAPES[shape](6000, seed=3)
    p = core.noise.add_noise(s.points, 0.5, relative=True, seed=4)
    assert core.estimate(p).crease.mean() < 0.05


def test_auto_refines_while_the_passes_remove_noise(noisy_torus):
    """With noise each pass changes the normals much less than the one before (noise
    averaged away) until it only drifts; the drifting pass is undone."""
    s, p = noisy_torus
    r = core.estimate(p)
    assert 2 <= r.params["passes_run"] < AUTO_PASSES
    capped = {n: core.metrics.summary(core.estimate(p, passes=n), s)["mean"] for n in range(AUTO_PASSES + 1)}
    assert core.metrics.summary(r, s)["mean"] <= 1.05 * min(capped.values())
