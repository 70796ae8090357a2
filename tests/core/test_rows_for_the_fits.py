"""k="auto" keeps and copies wide rows only for the points whose fits read them (issue 15,
memory): where the cubic jet is the result (tiny noise) nothing is fitted, and the rows its
reruns searched were 1221 MB at the peak of a 1M estimate."""

import numpy as np
import pytest

from core import estimate, neighbour_budget, noise, refinement, scale, shapes, stages
from core.wide_neighbours import WidenableNeighbours, search_in_spatial_order

FIELDS = ("normals", "k1", "k2", "e1", "e2", "valid", "k_point", "degree_point", "crease", "border")


def _rotated(pts, seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return pts @ q.T


@pytest.mark.parametrize("seed, size, level, noisy_share", [(3, 1.0, 1e-3, 0.0), (5, 40.0, 1e-3, 0.3),
                                                             (7, 0.02, 3e-3, 0.0)])
def test_rows_are_kept_and_copied_for_fitted_points_only(seed, size, level, noisy_share, monkeypatch):
    """Tori in any pose and scale, tiny noise with a noisier part: the rows handed to the fits
    belong to points that are not on their jet, the wide rows built are the fitted points'
    only, and every result is the same bits as with the whole graph searched at once."""
    base = shapes.torus(6000, seed=seed).points
    noisy = noise.add_noise(base, 0.3, seed=seed + 1) if noisy_share else base
    pts = np.where((base[:, 0] > 2.5 - 5 * noisy_share)[:, None], noisy, noise.add_noise(base, level, seed=seed + 2))
    pts = _rotated(pts, seed) * size
    monkeypatch.setattr(neighbour_budget, "NEIGHBOUR_BUDGET", 60 * len(pts))  # as at 1M: no whole graph of 320
    with monkeypatch.context() as mp:
        mp.setattr(stages, "SEARCH_WIDTH", 10**9)
        reference = estimate(pts)
    monkeypatch.setattr(scale, "WIDEN_SHARE", 1.0)
    monkeypatch.setattr(stages, "SEARCH_WIDTH", 40)
    seen = []
    fit_passes, rows_at_least = refinement.fit_passes, refinement.rows_at_least

    def watched_passes(pts, initial, outlier, nb, sc, *args, **kw):
        seen.append({"on_jet": sc.on_jet, "fits": ~sc.on_jet & sc.spans})
        yield from fit_passes(pts, initial, outlier, nb, sc, *args, **kw)

    def watched_rows(nb, kc, fits=None):
        kept = [] if nb._kept is None else nb._kept[1]
        seen[-1]["kept"] = np.concatenate([c for c, _ in kept] or [np.empty(0, dtype=np.int64)])
        rows, h = rows_at_least(nb, kc, fits)
        seen[-1]["wide"] = rows.blocks[0][0] if hasattr(rows, "blocks") else None
        return rows, h

    monkeypatch.setattr(refinement, "fit_passes", watched_passes)
    monkeypatch.setattr(refinement, "rows_at_least", watched_rows)
    got = estimate(pts)
    for f in FIELDS:
        assert np.array_equal(np.asarray(getattr(got, f)), np.asarray(getattr(reference, f)), equal_nan=True), f
    (s,) = seen
    assert s["on_jet"].any() and "kept" in s
    assert not s["on_jet"][s["kept"]].any()  # a jet that is the result: its rerun's rows are not kept
    assert s["fits"][s["wide"]].all()  # wide rows for the fitted points only


def test_keep_only_drops_the_rows_left_out():
    """The graph keeps, of a block its search kept, only the rows asked for, none if none;
    other blocks and arrays it did not keep are left as they are."""
    pts = shapes.torus(800, seed=1).points
    nb, _ = search_in_spatial_order(pts, 60, width=12)
    assert isinstance(nb, WidenableNeighbours)
    nb.keep_rows(60)
    a, b, c = np.arange(0, 300, 3), np.arange(1, 200, 2), np.arange(5, 50)
    rows_a, rows_b, rows_c = (nb.rows(x, 60)[0] for x in (a, b, c))
    keep = a % 2 == 0
    nb.keep_only(rows_a, keep)
    nb.keep_only(rows_b, np.zeros(len(b), dtype=bool))
    nb.keep_only(rows_a.copy(), np.zeros(len(a), dtype=bool))  # not a kept array: nothing changes
    kept = nb.kept_rows(60)
    assert [len(x) for x, _ in kept] == [keep.sum(), len(c)]
    np.testing.assert_array_equal(kept[0][0], a[keep])
    np.testing.assert_array_equal(kept[0][1], rows_a[keep])
    assert kept[1][1] is rows_c
