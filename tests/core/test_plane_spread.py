"""Neighbourhoods that do not span the tangent plane (core.plane_spread): points whose
neighbours lie along one line are not fitted (valid False, NaN) instead of reporting the
noise over their tiny lever arms as curvature; k="auto" widens NR's neighbourhood there."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import plane_spread, shapes, shapes_thin
from core.tuning import THIN_SPREAD


def _spreads(pts, k):
    res = core.estimate(pts, k=15)
    return plane_spread.spreads(pts, res.normals, core.build_neighbours(pts, k), k)


def test_spread_is_one_all_around_and_zero_on_a_line():
    t = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    ring = np.c_[np.cos(t), np.sin(t), 0 * t]
    pts = np.vstack([[0.0, 0.0, 0.0], ring, 2 * ring])
    nrm = np.tile([0.0, 0.0, 1.0], (len(pts), 1))
    nb = core.build_neighbours(pts, 9)
    assert plane_spread.spreads(pts, nrm, nb, 9, [0])[0] == pytest.approx(1.0)
    line = np.c_[np.linspace(-1, 1, 17), np.zeros(17), np.zeros(17)]
    line[9, 1] = 1e-3  # a neighbour a hair off the line
    nrm = np.tile([0.0, 0.0, 1.0], (17, 1))
    s = plane_spread.spreads(line, nrm, core.build_neighbours(line, 9), 9, [8])[0]
    assert 0 < s < 2e-3
    tilted = np.tile([0.0, 0.6, 0.8], (len(pts), 1))  # the moments are taken in the plane normal to the normal
    assert plane_spread.spreads(pts, tilted, nb, 9, [0])[0] == pytest.approx(0.8, rel=1e-12)
    assert np.isnan(plane_spread.spreads(pts, np.full_like(nrm[:1].repeat(len(pts), 0), np.nan), nb, 9, [0])[0])


@pytest.mark.parametrize("k", [10, 15])
def test_random_samplings_span_their_plane(k):
    t = shapes.torus(8000, seed=1)
    assert _spreads(t.points, k).min() > 1.5 * THIN_SPREAD  # measured: >= 0.31 at k = 15, 0.2 at 10
    res = core.estimate(t.points, k=k)
    assert res.valid.all()


def test_scan_lines_too_far_apart_for_k_are_not_fitted():
    """Lines 8 spacings apart: the 15 nearest of a point all lie on its own line."""
    s = shapes_thin.stripe_scan(6000, ratio=8.0, seed=0)
    assert np.median(_spreads(s.points, 15)) < THIN_SPREAD / 5
    for method in ("nr", "nf", "ct", "qp", "cf"):
        res = core.estimate(s.points, k=15, method=method)
        assert res.valid.mean() < 0.1, method  # before: every point valid, median |H error| 77 (|H| 0.18)
        assert np.isnan(res.mean[~res.valid]).all()
        err = np.abs(res.mean - s.mean)[res.valid & s.interior]
        assert len(err) == 0 or np.median(err) < 0.05, method
    near = core.estimate(s.points, k=15, method="nr")
    wide = core.estimate(shapes_thin.stripe_scan(6000, ratio=3.0, seed=0).points, k=15)
    assert wide.valid.all() and not near.valid.all()  # lines 3 apart: the 15 nearest reach the next lines


def test_a_helix_is_not_given_curvatures():
    t = np.linspace(0, 2 * np.pi, 3000, endpoint=False)
    helix = np.c_[np.cos(3 * t), np.sin(3 * t), 0.3 * t]
    for method in ("nr", "ct", "qp"):
        res = core.estimate(helix, k=15, method=method)
        assert not res.valid.any(), method  # before: every point valid, k1 made up


def test_auto_widens_nr_where_its_neighbours_do_not_span(monkeypatch):
    """With noise k="auto" fits NR; where its chosen neighbours lie on one scan line it
    takes the next candidate that reaches the neighbouring lines, never a thin one."""
    s = shapes_thin.stripe_scan(6000, ratio=8.0, seed=0)
    noisy = core.noise.add_noise(s.points, 0.2, seed=3)
    res = core.estimate(noisy)
    assert res.valid.mean() > 0.99
    assert np.all(_spreads_at(noisy, res) >= THIN_SPREAD)
    err = np.abs(res.mean - s.mean)[res.valid & s.interior]
    assert np.median(err) < 0.1


def _spreads_at(pts, res):
    nb = core.build_neighbours(pts, int(res.k_point.max()))
    fitted = res.valid & (res.degree_point == 3)  # NR's own fits (the jets judge their lever arms themselves)
    return plane_spread.spreads(pts, res.normals, nb, res.k_point[fitted], np.flatnonzero(fitted))


def test_widened_takes_the_smallest_spanning_candidate_or_none():
    s = shapes_thin.stripe_scan(6000, ratio=8.0, seed=0)
    res = core.estimate(s.points, k=15)
    nb = core.build_neighbours(s.points, 113)
    k = np.full(len(s.points), 15)
    wide = plane_spread.widened(s.points, s.normals, nb, k, (20, 28, 40, 56, 113))
    assert set(np.unique(wide)) <= {15, 20, 28, 40, 56, 113} and (wide == 20).mean() > 0.9  # 20 reach the next lines
    thin = plane_spread.spreads(s.points, s.normals, nb, 15) < THIN_SPREAD
    assert thin.mean() > 0.9 and (wide[~thin] == 15).all()
    for cand in (20, 28, 40):
        at = np.flatnonzero(wide == cand)
        assert (plane_spread.spreads(s.points, s.normals, nb, cand, at) >= THIN_SPREAD).all()
    line = np.c_[np.linspace(0, 1, 400), np.random.default_rng(0).normal(scale=1e-6, size=(400, 2))]
    nrm = np.tile([0.0, 0.0, 1.0], (400, 1))
    assert (plane_spread.widened(line, nrm, core.build_neighbours(line, 40), np.full(400, 15), (20, 28)) == 0).all()


def test_curve_share_is_small_along_one_curve_and_one_across_a_surface():
    """core.kernels.spread.curve_shares: the quartic across the widest axis of an arc (any
    pose, a quarter circle) leaves only its noise; two parallel arcs, a disc and a random
    patch leave about all of their spread across it. Checked against a numpy reference."""
    from core.kernels.spread import curve_shares

    rng = np.random.default_rng(0)
    t = np.linspace(0.0, np.pi / 2, 60)
    arc = np.c_[np.cos(t), np.sin(t), 0 * t] + rng.normal(scale=1e-3, size=(60, 3))
    twin = np.vstack([arc[::2], 1.2 * arc[1::2]])  # two arcs of a scan, 0.2 apart
    disc = np.c_[rng.uniform(-1, 1, (60, 2)), rng.normal(scale=1e-3, size=60)]
    q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    pts = np.vstack([arc, twin, disc]) @ q.T + 5.0
    rows = np.arange(180).reshape(3, 60)
    flat, curve = np.empty(3), np.empty(3)
    curve_shares(pts, rows, flat, curve)

    def reference(p):
        d = p - p.mean(0)
        _, vec = np.linalg.eigh(d.T @ d)
        u, v = d @ vec[:, 2], d @ vec[:, 1]
        a = np.vander(u / np.abs(u).max(), 5)
        return np.sqrt(np.mean((v - a @ np.linalg.lstsq(a, v, rcond=None)[0]) ** 2) / np.mean(v * v))

    assert curve == pytest.approx([reference(pts[r]) for r in rows], rel=1e-6)
    assert curve[0] < 0.05 and curve[1] > 0.5 and curve[2] > 0.8
    assert (flat < 0.05).all()


def _thin_shapes(pts, nrm, idx, dist):
    """core.kernels.spread.thin_shapes of every row: (spread, weighted, flat)."""
    from core.kernels.spread import thin_shapes
    from core.tuning import THETA_REACH

    out = np.empty((3, len(idx)))
    thin_shapes(pts, nrm, 0, np.ascontiguousarray(idx), np.ascontiguousarray(dist), THETA_REACH, out[0], out[1], out[2])
    return out


def test_weighted_spread_counts_neighbours_as_the_pca_weighs_them():
    """A line of 17 points and two points off it at the far end of the neighbourhood: they
    span the plane unweighted, but weigh ~1e-3 in the PCA (eq. 14), and the weighted spread
    is about that small; all around a point both are 1."""
    line = np.c_[np.linspace(-1, 1, 17), np.zeros(17), np.zeros(17)]
    pts = np.vstack([line, [[0.0, 1.05, 0.0], [0.0, -1.05, 0.0]]])
    nb = core.build_neighbours(pts, 19)
    nrm = np.tile([0.0, 0.0, 1.0], (len(pts), 1))
    spread, weighted, _ = _thin_shapes(pts, nrm, *nb.take(19))
    assert spread[8] == plane_spread.spreads(pts, nrm, nb, 19, [8])[0] > 0.5
    assert weighted[8] < 0.1
    t = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    ring = np.vstack([[0.0, 0.0, 0.0], np.c_[np.cos(t), np.sin(t), 0 * t]])
    nb = core.build_neighbours(ring, 9)
    assert _thin_shapes(ring, np.tile([0.0, 0.0, 1.0], (9, 1)), *nb.take(9))[1, 0] == pytest.approx(1.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_three_shapes_read_in_one_pass_are_those_of_their_own_kernels(seed):
    """thin_shapes' spread and flat are plane_spread's and scatter_shapes' bit for bit (noisy
    planes, lines and blobs at several scales, some normals NaN, rows of coincident points)."""
    from core.kernels.spread import scatter_shapes

    rng = np.random.default_rng(seed)
    pts = np.vstack([rng.normal(size=(300, 3)) * [1.0, 1.0, 0.01] * 10.0 ** (seed - 1),
                     np.c_[np.linspace(0, 1, 100), rng.normal(size=(100, 2)) * 1e-3], rng.normal(size=(200, 3)),
                     np.zeros((20, 3))])
    nrm = rng.normal(size=pts.shape)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    nrm[::17] = np.nan
    nb = core.build_neighbours(pts, 15)
    spread, weighted, flat = _thin_shapes(pts, nrm, *nb.take(15))
    assert np.array_equal(spread, plane_spread.spreads(pts, nrm, nb, 15), equal_nan=True)
    alone, line = np.empty(len(pts)), np.empty(len(pts))
    scatter_shapes(pts, np.ascontiguousarray(nb.take(15)[0]), alone, line)
    assert np.array_equal(flat, alone, equal_nan=True)
    assert np.isnan(weighted[::17]).all() and np.isnan(weighted[-20:]).all()  # no normal; h = 0
    assert np.isfinite(weighted[1:300]).any()


def test_widening_searches_twice_and_reads_the_rows_each_candidate_would():
    """plane_spread._CandidateRows: the rows of the centres still widened at each candidate
    are those a search at that width gives (ties included: a grid has many), though only the
    first candidate beyond the graph's held columns and then the widest are searched."""
    from core.wide_neighbours import search_in_spatial_order

    g = np.mgrid[0:60, 0:60].reshape(2, -1).T * 0.1  # a grid: equal distances everywhere
    pts = np.c_[g, 0.05 * np.sin(g[:, 0])]
    nb, _ = search_in_spatial_order(pts, 160, width=24)
    searched = []
    real_rows = nb.rows

    class Counting:
        width = nb.width

        def rows(self, centres, k):
            searched.append(k) if k > nb.width else None
            return real_rows(centres, k)

    rows = plane_spread._CandidateRows(Counting(), 160)
    centres = np.arange(0, len(pts), 3)
    rng = np.random.default_rng(0)
    for cand in (16, 40, 64, 100, 160):
        idx, dist = rows(centres, cand)
        want_idx, want_dist = real_rows(centres, cand)
        assert np.array_equal(idx, want_idx) and np.array_equal(dist, want_dist), cand
        assert idx.flags.c_contiguous and dist.flags.c_contiguous
        centres = np.sort(rng.choice(centres, len(centres) * 2 // 3, replace=False))
    assert searched == [40, 160]


def test_widening_with_no_candidate_beyond_k_keeps_the_normals():
    """Thin points and no candidate wider than k (a small cloud's plan): nothing to try."""
    s = shapes_thin.stripe_scan(3000, ratio=8.0, seed=0)
    nb = core.build_neighbours(s.points, 15)
    ok = np.ones(len(s.points), dtype=bool)
    assert (plane_spread.spreads(s.points, s.normals, nb, 15) < THIN_SPREAD).mean() > 0.5
    nrm, _ = plane_spread.spanning_normals(s.points, s.normals, ok, nb, 15, (10, 15))
    assert np.array_equal(nrm, s.normals)
