"""``python -m core bench perf``'s stage rows run the estimate's own stages: their result is
the estimate's, bit for bit, so the rows add up to the end-to-end figure (the rows before
left out the outlier scores, the re-decided signs and the flags)."""

from __future__ import annotations

import time

import numpy as np

import core
from core import shapes_thin
from core.bench import perf_stages


def _timed(fn):
    t0 = time.perf_counter()
    return fn(), time.perf_counter() - t0, None


def test_the_stage_rows_give_the_estimates_normals():
    """On a noisy thin wedge the re-decided signs flip points (without them the normals
    differ), so the rows must hold every stage to give the estimate's normals."""
    pts = shapes_thin.noisy(shapes_thin.thin_wedge(6000, seed=1), 0.2, 1)
    kept = {}
    rows = perf_stages.stage_rows(pts, 15, _timed, kept=kept)
    names = [name for name, _, _ in rows]
    assert any("re-decided" in name for name in names) and any("outlier" in name for name in names)
    np.testing.assert_array_equal(kept["normals"], core.estimate(pts, k=15, method="nr").normals)


def test_the_remainder_row_is_the_end_to_end_figure_minus_the_stages():
    rows = [("a", 1.0, type("S", (), {"cpu": 0.5})()), ("b", 2.0, type("S", (), {"cpu": 1.5})())]
    (_, wall, total), (_, rest, left) = perf_stages.summed(rows, 3.5, 2.5)
    assert (wall, total.cpu, rest, left.cpu) == (3.0, 2.0, 0.5, 0.5)
