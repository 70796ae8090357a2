"""The off-surface score (core.off_surface, core.kernels.off_planes): points a few
spacings off a surface are outliers even when other outliers, a coarse curved surface or a
border hide them from their neighbours' least-squares plane; edges, rims and noise are not."""

import numpy as np
import pytest

import core
from core import noise, shapes, shapes_thin
from core.bench.accuracy.cases import _make_cases, _errors
from core.kernels.off_planes import off_planes, pooled_units, robust_planes
from core.neighbours import build_neighbours
from core.off_surface import QUANTILE, REWEIGHTINGS, STANDOUT, off_surface
from core.stages import outlier_scores
from core.tuning import OUTLIER_FLOOR, OUTLIER_SCORE

TUKEY = 4.685


def _rows(points, k=15):
    return np.ascontiguousarray(build_neighbours(points, k).take(k)[0])


def _reference(points, idx, floor=OUTLIER_FLOOR, reweightings=REWEIGHTINGS, standout=STANDOUT, quantile=QUANTILE):
    """numpy: each row's Tukey-reweighted plane of its neighbours (kept least squares where none
    stands out), the neighbours' median scale, the quantile of the distances to the row planes."""
    nb = points[idx[:, 1:]]
    w = np.ones(nb.shape[:2])
    iterate = np.ones(len(points), dtype=bool)
    for it in range(reweightings + 1):
        c = (w[..., None] * nb).sum(1) / w.sum(1)[:, None]
        d = nb - c[:, None]
        n = np.linalg.eigh(np.einsum("nm,nmi,nmj->nij", w, d, d))[1][:, :, 0]
        r = np.einsum("nmi,ni->nm", d, n)
        scale = 1.4826 * np.median(np.abs(r), axis=1)
        term = floor * np.linalg.norm(d, axis=2).mean(1)
        if it == 0:
            planes = [c, n, scale, term]
            iterate &= np.abs(r).max(1) > standout * (scale + term)
        else:
            for a, b in zip(planes, (c, n, scale, term)):
                a[iterate] = b[iterate]
        u = r / (TUKEY * (scale + term))[:, None]
        w = np.where(np.abs(u) < 1, (1 - u * u) ** 2, 0.0)
    c, n, scale, term = planes
    unit = np.median(scale[idx[:, 1:]], axis=1) + term
    dist = np.abs(np.einsum("nmi,nmi->nm", points[:, None, :] - c[idx], n[idx])) / unit[idx]
    return np.quantile(dist, quantile, axis=1)


def _with_outliers(sample, level, seed, distance=(5.0, 20.0)):
    pts = noise.add_noise(sample.points, level, relative=True, seed=seed) if level else sample.points
    return noise.add_outliers(pts, 0.03, distance=distance, seed=seed + 1)


def test_the_kernels_are_their_numpy_reference():
    s = shapes.saddle(3000, seed=0)
    pts, _ = _with_outliers(s, 0.1, 1)
    idx = _rows(pts)
    got = off_surface(pts, idx)
    np.testing.assert_allclose(got, _reference(pts, idx), rtol=1e-9)
    planes, units, out = np.empty((len(pts), 8)), np.empty(len(pts)), np.empty(len(pts))
    robust_planes(pts, idx, OUTLIER_FLOOR, 0, np.inf, planes)  # no reweighting: least squares
    pooled_units(idx, planes, units)
    off_planes(pts, idx, planes, units, 0.0, out)  # the nearest plane
    np.testing.assert_allclose(out, _reference(pts, idx, reweightings=0, quantile=0.0), rtol=1e-9)


def test_degenerate_rows_give_nan_not_garbage():
    stack = np.zeros((20, 3))  # no plane anywhere
    assert np.isnan(off_surface(stack, _rows(stack))).all()
    flat = np.column_stack([np.repeat(np.arange(6.0), 6), np.tile(np.arange(6.0), 6), np.zeros(36)])
    assert (off_surface(flat, _rows(flat)) == 0).all()  # on their planes (a unit of 0 only if there)
    line = np.column_stack([np.arange(40.0), np.zeros(40), np.zeros(40)])
    assert (off_surface(line, _rows(line)) == 0).all()  # every plane through the line holds it


def test_points_off_a_coarse_saddle_are_flagged_where_the_plane_score_missed_them():
    """3 % of the points moved 1-6 spacings in random directions, scattered so that other
    outliers are among their neighbours: of those more than 2 spacings off the surface the
    least-squares plane missed 4-9 %, the off-surface score misses none (three seeds)."""
    plane_hits, hits, clean = [], [], []
    for seed in (1, 2, 3):
        s = shapes.saddle(5000, seed=seed)
        pts, moved = _with_outliers(s, 0.1, seed, distance=(1.0, 6.0))
        far = moved & (np.abs(np.einsum("ij,ij->i", pts - s.points, s.normals)) > 2 * noise.mean_spacing(s.points))
        idx = _rows(pts)
        plane = np.full(len(pts), np.nan)
        core.kernels.outlier_scores(pts, idx, OUTLIER_FLOOR, plane)
        both = outlier_scores(pts, idx)
        plane_hits += list(plane[far] > OUTLIER_SCORE)
        hits += list(both[far] > OUTLIER_SCORE)
        clean += list(both[~moved] > OUTLIER_SCORE)
    assert np.mean(plane_hits) < 0.97 and np.mean(hits) >= 0.99 and not any(clean)


@pytest.mark.parametrize("make, level", [
    (lambda: shapes.cube(8000, seed=0), 0.0),  # edges and corners
    (lambda: shapes_thin.thin_plate(8000, seed=0), 0.0),  # rims
    (lambda: shapes_thin.thin_wedge(8000, seed=0), 0.0),  # a rim thinning to 2 spacings
    (lambda: shapes_thin.two_sheets(8000, seed=0), 0.1),
    (lambda: shapes.range_scan(8000, seed=0), 0.0),  # density falling with range
    (lambda: shapes.graded(8000, seed=0), 0.5),  # 10:1 density
    (lambda: shapes.torus(8000, seed=0), 1.0),  # heavy noise
])
def test_clean_clouds_get_no_new_flags(make, level):
    s = make()
    pts = noise.add_noise(s.points, level, relative=True, seed=3) if level else s.points
    score = off_surface(pts, _rows(pts))
    assert (score > OUTLIER_SCORE).mean() <= (0.0005 if level < 1 else 0.001)


def test_three_percent_outliers_barely_move_the_inliers_answers():
    """The accuracy race's outlier case on the saddle (3 % of the points 5-20 spacings off,
    noise 0.1 spacing), one refinement pass (more would let the pass rule, at 0.70 on this
    saddle, decide): with the plane's flags alone the inliers' K, H and e1 errors grew
    7, 10 and 16 % over three seeds; now 3, 3 and 4 %."""
    grow = []
    for seed in (0, 1, 2):
        c = _make_cases("saddle", 5000, 0.1, 1, seed, 2000, 240)[0]
        pts, moved = noise.add_outliers(c.points, 0.03, spacing=c.spacing, seed=seed + 7)
        clean = _errors(core.estimate(c.points, passes=1), c, ~moved)
        dirty = _errors(core.estimate(pts, passes=1), c, ~moved)
        grow.append([dirty[q] / clean[q] for q in ("gaussian", "mean", "direction_deg")])
    assert np.mean(grow, axis=0).max() < 1.07


def test_the_score_is_invariant_under_rotation_translation_and_scale():
    pts, _ = _with_outliers(shapes.torus(4000, seed=2), 0.1, 4, distance=(1.0, 8.0))
    idx = _rows(pts)  # the same rows: a similarity keeps every neighbour order
    base = off_surface(pts, idx)
    rot = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))[0]
    for moved in (pts + [5e5, 4e6, 100.0], 1e3 * pts @ rot.T, 1e-3 * pts):
        np.testing.assert_allclose(off_surface(moved, idx), base, rtol=1e-6, atol=1e-9)


def test_the_sorting_network_sorts_every_row_of_zeros_and_ones():
    """kernels.network.sorted_short sorts any m <= SHORT values: a network of compare-exchanges
    that sorts every 0/1 input sorts every input (Knuth's 0-1 principle), so all 2^m are tried."""
    from core.kernels.network import SHORT, sorted_short
    for m in range(SHORT + 1):
        rows = ((np.arange(2 ** m)[:, None] >> np.arange(m)) & 1).astype(float)
        for row in rows:
            sorted_short(row, m)
        assert (np.diff(rows, axis=1) >= 0).all(), m


def test_short_rows_give_the_quickselects_order_statistics_bit_for_bit():
    """The off-surface kernels' medians and quantiles of rows up to SHORT values (the network)
    and the orientation's spread (a median by the network, sign_evidence._median) are those of
    the quickselect (robust.root_median, pool.linear_quantile), with ties, zeros,
    inf and rows of every length, longer rows included (which keep the quickselect)."""
    from core.kernels.network import SHORT
    from core.kernels.off_planes import _quantile, _root_median
    from core.kernels.pool import linear_quantile
    from core.kernels.robust import root_median
    from core.kernels.sign_evidence import _median
    rng = np.random.default_rng(3)
    for m in range(1, SHORT + 6):
        for trial in range(200):
            row = np.full(m, np.nan)
            draw = rng.integers(0, 4, m) * 0.25 if trial % 2 else rng.random(m) ** 2 * 10.0 ** rng.integers(-8, 8)
            row[:m] = np.where(rng.random(m) < 0.05, np.inf, draw)
            assert np.float64(_root_median(row.copy(), m)).tobytes() == np.float64(root_median(row.copy(), m)).tobytes()
            for q in (0.0, 0.25, 0.5, 0.9, 1.0):  # NaN where inf meets a finite value in numpy's lerp: both
                got, want = _quantile(row.copy(), m, q), linear_quantile(row.copy(), m, q)
                assert np.float64(got).tobytes() == np.float64(want).tobytes()
            if np.isfinite(row).all():
                assert _median(row.copy()) == np.median(row)
