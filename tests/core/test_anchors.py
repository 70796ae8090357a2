"""Sparse centres of k="auto" (core.anchors): fits at anchors, read at the points that follow them."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import core
from core import anchor_blend, anchors, fits, noise, refinement, scale, shapes, wide_rows
from core._progress import Progress
from core.methods import METHODS
from core.fits import Fitter, empty_fit

CUBIC = dict(weights="uniform", constraint="project", robust=None, degree=3)


def _graph(pts, k):
    dist, idx = cKDTree(pts).query(pts, k)
    return np.ascontiguousarray(idx), dist[:, -1].copy()


def _fit(pts, nrm, k, anchor):
    idx, h = _graph(pts, k)
    out = empty_fit(len(pts))
    Fitter(pts, idx, np.full(len(pts), k), h, METHODS["nr"], dict(CUBIC), anchor).into(
        out, nrm, np.ones(len(pts), dtype=bool), Progress(None))
    return out


def _anchor(pts, k, rows, monkeypatch):
    monkeypatch.setattr(anchors, "ANCHOR_ROWS", rows)
    idx, _ = _graph(pts, k)
    return anchors.assign(pts, idx, np.full(len(pts), k), np.ones(len(pts), dtype=bool))


@pytest.mark.parametrize("constraint", ["project", "none"])
def test_the_compiled_blend_is_the_numpy_reference(constraint, monkeypatch):
    """Followers of a noisy torus read from up to 4 anchors each (some from 1-2: the
    inverse-distance weights): the compiled average equals numpy's."""
    pts = noise.add_noise(shapes.torus(4000, seed=7).points, 0.1, seed=8)
    anchor = _anchor(pts, 80, 20, monkeypatch)
    anchor[::7, 2:] = np.where(anchors.followers(anchor)[::7, None], -1, anchor[::7, 2:])  # a few with two anchors
    idx, h = _graph(pts, 80)
    nrm = core.estimate(pts, k=15).normals
    kept = anchors.Kept(anchor)
    fitter = Fitter(pts, idx, np.full(len(pts), 80), h, METHODS["nr"], dict(CUBIC, constraint=constraint), anchor)
    fitter._fit(empty_fit(len(pts)), nrm, np.isin(np.arange(len(pts)), kept.points), Progress(None), kept)
    points = np.flatnonzero(anchors.followers(anchor))
    picked = anchor[points]
    got, good, r = anchor_blend.blended(kept, pts, nrm, points, picked, constraint)
    ref = anchor_blend.blended_reference(kept, pts, nrm, points, picked, constraint)
    np.testing.assert_array_equal(good, ref[1])
    assert good.mean() > 0.99 and (picked[:, 1:] < 0).sum() > 100
    for name in ("normal", "k1", "k2"):
        np.testing.assert_allclose(getattr(got, name)[good], getattr(ref[0], name)[good], rtol=1e-9, atol=1e-9)
    for name in ("e1", "e2"):  # up to sign
        dot = np.abs(np.einsum("ij,ij->i", getattr(got, name), getattr(ref[0], name)))[good]
        assert dot.min() > 1 - 1e-9, name


def _priority_numpy(pts, near):
    """The anchors' draw as numpy computes it (the reference of the compiled loop)."""
    from core.passes import mix64

    d = np.linalg.norm(pts[near[:, 1:anchors.RATIOS + 1]] - pts[:, None], axis=2)
    d.sort(axis=1)
    q = np.rint(d[:, :-1] / np.where(d[:, -1:] > 0.0, d[:, -1:], 1.0) * 2.0**20).astype(np.uint64)
    h = np.full(len(q), anchors._SALT, dtype=np.uint64)
    for j in range(q.shape[1]):
        h = mix64(h ^ q[:, j])
    return h | np.uint64(1)


@pytest.mark.parametrize("cloud", ["noisy", "grid", "far"])
def test_the_compiled_draw_is_numpy_s_to_the_last_bit(cloud):
    """anchors.priority (a compiled loop) equals numpy's norms, sort, rounding and hash bit
    for bit: on a noisy torus, on a grid (ties at every distance, ratios on the rounding's
    half-steps) and far from the origin (distances of large coordinates), with the neighbour
    rows a strided view as the estimate passes them."""
    rng = np.random.default_rng(3)
    if cloud == "grid":
        g = np.stack(np.meshgrid(np.arange(40.0), np.arange(40.0)), -1).reshape(-1, 2)
        pts = np.c_[g, rng.integers(0, 2, len(g)) * 0.5]
    else:
        pts = noise.add_noise(shapes.torus(5000, seed=9).points, 0.2, seed=10)
        pts = pts + 1e6 if cloud == "far" else pts
    near = cKDTree(pts).query(pts, 16)[1][:, :anchors.RATIOS + 1]
    assert not near.flags.c_contiguous
    got = anchors.priority(pts, near)
    np.testing.assert_array_equal(got, _priority_numpy(pts, near))
    assert len(np.unique(got)) > (0.001 if cloud == "grid" else 0.99) * len(pts)


def test_anchors_are_the_same_whatever_the_order_pose_or_scale(monkeypatch, helpers):
    pts = noise.add_noise(shapes.torus(6000, seed=2).points, 0.2, seed=3)
    anchor = _anchor(pts, 160, 40, monkeypatch)  # m = 3: an anchor's priority beats its 3 nearest
    n = len(pts)
    follows = anchors.followers(anchor)
    own = np.unique(anchor[follows][anchor[follows] >= 0])
    assert 0.2 < len(own) / n < 0.3 and follows.mean() > 0.7  # ~1 in 4 fitted
    assert not follows[own].any()  # an anchor fits its own
    idx, _ = _graph(pts, 25)
    read = anchor[follows]
    among = (idx[follows][:, :, None] == read[:, None, :]).any(axis=1)
    assert among[read >= 0].all() and (read[:, 1:] >= 0).mean() > 0.9  # among its 24 nearest, mostly 4
    perm = np.random.default_rng(1).permutation(n)
    moved = _anchor(pts[perm], 160, 40, monkeypatch)
    np.testing.assert_array_equal(np.where(moved >= 0, perm[moved], -1), anchor[perm])  # the same anchors
    turned = (pts @ helpers.random_orthogonal(3, proper=False).T) * 7.3 + [1e3, -2.0, 5.0]
    np.testing.assert_array_equal(_anchor(turned, 160, 40, monkeypatch), anchor)
    assert _anchor(pts, 40, 40, monkeypatch) is None  # k < 1.5 x ANCHOR_ROWS: every point fits its own


def test_a_follower_reads_a_spheres_curvature_exactly(monkeypatch):
    """A sphere's normal field is linear in the offsets of any tangent frame: the anchor's
    cubic holds it exactly, and a follower's value and slopes are exact too."""
    s = shapes.sphere(3000, radius=2.0, seed=1)
    anchor = _anchor(s.points, 40, 10, monkeypatch)
    out = _fit(s.points, s.normals, 40, anchor)
    follows = anchors.followers(anchor)
    assert follows.mean() > 0.6 and out.valid.all()
    np.testing.assert_allclose(out.k1[follows], 0.5, atol=1e-9)
    np.testing.assert_allclose(out.k2[follows], 0.5, atol=1e-9)
    assert np.abs(out.normals - s.normals).max() < 1e-9


def test_a_follower_keeps_its_own_sign_among_anchors_of_either(monkeypatch):
    """Normals whose signs are mixed (a file's, kept; or each point facing its own scanner):
    a follower's result faces its own normal, as a fit of its own does, whatever the signs
    of its anchors (the first anchor's sign had decided it), with the curvatures of that
    side: +1/R facing out, -1/R facing in."""
    s = shapes.sphere(3000, radius=2.0, seed=1)
    sign = np.where(np.random.default_rng(3).random(len(s.points)) < 0.5, -1.0, 1.0)
    anchor = _anchor(s.points, 40, 10, monkeypatch)
    out = _fit(s.points, s.normals * sign[:, None], 40, anchor)
    follows = anchors.followers(anchor)
    mixed = follows & (np.ptp(sign[np.where(anchor >= 0, anchor, np.arange(len(sign))[:, None])], axis=1) > 0)
    assert mixed.sum() > 300 and out.valid.all()
    np.testing.assert_allclose(out.normals, s.normals * sign[:, None], atol=1e-9)
    np.testing.assert_allclose(out.k1, 0.5 * sign, atol=1e-9)
    np.testing.assert_allclose(out.k2, 0.5 * sign, atol=1e-9)


def test_a_follower_is_nearly_as_accurate_as_its_own_fit(monkeypatch):
    """On a torus (a normal field no polynomial holds), k = 80: the curvatures and normals
    read at the followers' offsets are nearly as close to the truth as fits at the followers
    (measured: mean |H error| 1.25x, normals' 99th percentile 1.4x)."""
    s = shapes.torus(6000, seed=4)
    anchor = _anchor(s.points, 80, 20, monkeypatch)
    follows = anchors.followers(anchor)
    errors = []
    for fit in (_fit(s.points, s.normals, 80, anchor), _fit(s.points, s.normals, 80, None)):
        h = np.abs(0.5 * (fit.k1 + fit.k2) - 0.5 * (s.k1 + s.k2))[follows]
        turn = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", fit.normals, s.normals), -1, 1)))[follows]
        errors.append((h.mean(), np.percentile(turn, 99)))
    (h_read, n_read), (h_own, n_own) = errors
    assert h_read < 1.5 * h_own and n_read < 2.0 * n_own, errors


def test_the_default_with_anchors_is_as_accurate_as_without(monkeypatch):
    """A noisy torus, k="auto" (k = 320 almost everywhere): reading the fits at 1 in 8 of the
    points costs no accuracy against fitting at every point."""
    s = shapes.torus(6000, seed=5)
    pts = noise.add_noise(s.points, 0.2, seed=6)
    with_anchors = core.estimate(pts)
    monkeypatch.setattr(anchors, "ANCHOR_ROWS", 10**6)
    without = core.estimate(pts)
    assert with_anchors.params["passes_run"] == without.params["passes_run"]
    for name, truth in (("mean", 0.5 * (s.k1 + s.k2)), ("gaussian", s.k1 * s.k2)):
        a, b = (np.nanmean(np.abs(getattr(r, name) - truth)) for r in (with_anchors, without))
        assert a < 1.1 * b, (name, a, b)


def test_a_noisy_point_takes_the_scale_of_an_anchor_among_its_nearest(monkeypatch):
    """With noise the jet rule grows to the largest size nearly everywhere; only anchors (as
    for fits of that size) run it, the other noisy points take their nearest anchor's size
    (core.anchors.shared_scale), at nearly no cost in accuracy against running it everywhere;
    so do the points that sit out the rule (outlier scores above JET_SCORE), never anchors."""
    s = shapes.torus(6000, seed=5)
    pts = noise.add_noise(s.points, 0.2, seed=6)
    seen, shared, choose = [], anchors.shared_scale, scale.choose_jets
    monkeypatch.setattr(anchors, "shared_scale", lambda *a: seen.append((a, shared(*a))) or seen[-1][1])
    monkeypatch.setattr(scale, "choose_jets", lambda *a, **kw: seen.append(choose(*a, **kw)) or seen[-1])
    res = core.estimate(pts)
    ((_, near, noisy, k_top, _, sat_out), (follow, lead)), (k, jets, *_) = seen
    assert k_top == 320 and (noisy | sat_out).mean() > 0.95 and 0.6 < len(follow) / noisy.sum() < 0.8
    assert noisy[lead].all() and not np.isin(lead, follow).any()  # anchors run the rule themselves
    assert sat_out[follow].sum() > 100 and (k[sat_out] > 0).mean() > 0.95  # robust mode's suspects follow too
    assert (near[follow, 1:anchors.ANCHOR_REACH + 1] == lead[:, None]).any(axis=1).all()
    np.testing.assert_array_equal(k[follow], k[lead])
    assert not jets[-1][follow].any() and jets[-1][lead].mean() > 0.99  # no jet of the size at a follower
    monkeypatch.setattr(anchors, "shared_scale", lambda *a: (np.empty(0, dtype=np.int64),) * 2)
    own = core.estimate(pts)
    assert (own.k_point != res.k_point).any()
    for name, truth in (("mean", 0.5 * (s.k1 + s.k2)), ("gaussian", s.k1 * s.k2)):
        a, b = (np.nanmean(np.abs(getattr(r, name) - truth)) for r in (res, own))
        assert a < 1.05 * b, (name, a, b)


def test_a_follower_whose_anchor_fails_fits_its_own_on_rows_searched_then(monkeypatch):
    """A follower's wide rows are not searched up front (core.wide_rows.rows_at_least);
    where its anchor's fit fails it fits its own on rows searched then: the same numbers as
    with every row searched first."""
    pts = noise.add_noise(shapes.torus(6000, seed=5).points, 0.2, seed=6)
    real, failed = fits.blended, []

    def failing(kept, pts_, nrm, points, picked, constraint):
        frame, good, r = real(kept, pts_, nrm, points, picked, constraint)
        failed.append(int((good & (points % 7 == 0)).sum()))
        return frame, good & (points % 7 != 0), r

    monkeypatch.setattr(fits, "blended", failing)
    lazy = core.estimate(pts)
    assert min(failed) > 100
    monkeypatch.setattr(refinement, "rows_at_least", lambda nb, kc, fits=None: wide_rows.rows_at_least(nb, kc))
    full = core.estimate(pts)
    for name in ("normals", "k1", "k2", "e1", "valid", "k_point"):
        np.testing.assert_array_equal(getattr(lazy, name), getattr(full, name), err_msg=name)
