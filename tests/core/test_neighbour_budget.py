"""k="auto"'s candidate sizes from the memory its neighbour lists hold (core.neighbour_budget)."""

from __future__ import annotations

import numpy as np
import pytest

from core import anchors, neighbour_budget, scale, shapes, tuning
from core.wide_neighbours import search_in_spatial_order
from core.wide_rows import rows_at_least


@pytest.mark.parametrize("n", [1000, 100_000, 300_000, 1_000_000, 1_100_000, 2_000_000, 10_000_000])
def test_candidates_fit_the_budget(n):
    ks = scale.candidates(n)
    assert ks == tuning.AUTO_KS[:len(ks)]  # a prefix: the rules step through sizes ~1.4x apart
    whole = neighbour_budget.whole_cap(n, tuning.AUTO_KS[0])
    for k in ks:
        assert k <= whole or n * neighbour_budget.entries(k) <= tuning.NEIGHBOUR_BUDGET
    if ks[-1] > whole:  # past the whole graph only to sizes whose fits are shared at anchors
        assert anchors.per_anchor(ks[-1]) >= 2
    if len(ks) < len(tuning.AUTO_KS):  # stopped by the budget: the next size does not fit it, or
        nxt = tuning.AUTO_KS[len(ks)]  # it and those after it that fit are every point's own
        assert nxt > whole
        fit = [k for k in tuning.AUTO_KS[len(ks):] if n * neighbour_budget.entries(k) <= tuning.NEIGHBOUR_BUDGET]
        assert all(anchors.per_anchor(k) < 2 for k in fit[:1]) or not fit


def test_a_million_points_reach_the_shared_sizes():
    """Every row whole, 1M points could hold 80; fits shared at anchors hold ~ANCHOR_ROWS
    indices per point whatever k (0.21 -> 0.022 mean |H| error on a noisy 1M torus)."""
    assert neighbour_budget.whole_cap(1_000_000, 20) < 113
    assert scale.candidates(1_000_000)[-1] == scale.jet_candidates(1_000_000)[-1] == 320
    assert anchors.shares_scale(_Plan(auto=True, k_search=320))
    assert scale.candidates(5_000_000) == (20,)  # the floor: a whole graph of 20
    assert scale.candidates(1_100_000)[-1] == 56  # 80 fits the budget, but as every point's own index rows
    per_point = [neighbour_budget.entries(k) for k in (160, 226, 320)]
    assert max(per_point) < 40 + tuning.ANCHOR_ROWS / 2  # the held columns and a third of ~ANCHOR_ROWS rows


def test_initial_normals_stay_within_the_whole_graph(monkeypatch):
    """Every point fits an initial normal: its k stays within what all may hold whole."""
    beside = neighbour_budget.entries(320) - tuning.SEARCH_WIDTH  # the anchors' rows
    assert scale.initial_k(1.0, 15, 320, 1_000_000) == int(tuning.NEIGHBOUR_BUDGET / 1e6 - beside) == 53
    assert scale.initial_k(1.0, 15, 320, 100_000) == round(tuning.INITIAL_K0)


def test_rows_beyond_the_whole_graph_are_held_as_indices(monkeypatch):
    """Most points fit wider than held but the budget cannot widen every row: their rows
    are searched (indices only), the same rows and h as a full search, the graph not widened."""
    pts = shapes.torus(3000, seed=5).points
    narrow, _ = search_in_spatial_order(pts, 120, width=24)
    full, _ = search_in_spatial_order(pts, 120)
    n = len(pts)
    kc = np.where(np.arange(n) % 5 == 0, 20, 100)
    monkeypatch.setattr(neighbour_budget, "NEIGHBOUR_BUDGET", 60 * n)
    rows, h = rows_at_least(narrow, kc)
    assert narrow.width == 24 and not isinstance(rows, np.ndarray)
    np.testing.assert_array_equal(h, full.distances[np.arange(n), kc - 1])
    c = np.arange(0, n, 7)
    for i, row in zip(c, rows[c]):
        np.testing.assert_array_equal(row[:kc[i]], full.indices[i, :kc[i]])
    monkeypatch.setattr(neighbour_budget, "NEIGHBOUR_BUDGET", 100 * n)
    rows, h2 = rows_at_least(narrow, kc)  # within the budget: the graph widens, the same numbers
    assert narrow.width == 100 and isinstance(rows, np.ndarray)
    np.testing.assert_array_equal(h2, h)


class _Plan:
    def __init__(self, **kw):
        self.__dict__.update(kw)
