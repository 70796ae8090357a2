"""``python -m core bench perf --noise``: the measured torus with noise of the given
fraction of the mean spacing (k="auto" fits far wider with noise than without)."""

from __future__ import annotations

import numpy as np

from core import shapes
from core.bench import perf
from core.spacing import mean_spacing


def test_the_noisy_torus_moves_its_points_by_the_asked_fraction_of_the_spacing():
    clean = shapes.torus(4000, seed=0).points
    np.testing.assert_array_equal(perf._torus(4000, 0, 0.0), clean)
    moved = perf._torus(4000, 0, 0.2) - clean
    rms = np.sqrt((moved ** 2).sum(axis=1).mean() / 3)  # per coordinate
    assert abs(rms / mean_spacing(clean) - 0.2) < 0.02


def test_the_option_reaches_the_run(monkeypatch):
    seen = {}
    monkeypatch.setattr(perf, "run", lambda sizes, **kw: seen.update(kw, sizes=sizes))
    assert perf.main(["--sizes", "1000", "--noise", "0.2"]) == 0
    assert seen["noise"] == 0.2 and seen["sizes"] == (1000,)
