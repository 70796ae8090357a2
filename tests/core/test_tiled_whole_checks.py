"""What core.estimate decides on the whole cloud before any fit, a tiled run decides too
(core.tiled.wholechecks): a cloud no estimate can be made on is refused with the reason
core.estimate reports, before any tile runs; a cloud of copies is planned for its distinct
positions, so its tiles give core.estimate's answer."""

from __future__ import annotations

import re

import numpy as np
import pytest

import core
from core import shapes
from core.io import read_cloud
from core.tiled import estimate_tiled

_RNG = np.random.default_rng(4)
_DEGENERATE = {
    "three points": lambda: shapes.sphere(300, seed=1).points[:3],
    "one place": lambda: np.ones((500, 3)),
    "a line": lambda: np.c_[np.linspace(0.0, 1.0, 3000), np.zeros(3000), np.zeros(3000)],
    "huge coordinates": lambda: _RNG.normal(size=(3000, 3)) * 1e160,
    "a float32 grid": lambda: (np.float32(5e7) + _RNG.normal(size=(3000, 3)).astype(np.float32)).astype(np.float64),
}


@pytest.mark.parametrize("k", ["auto", 15])
@pytest.mark.parametrize("case", sorted(_DEGENERATE))
def test_a_cloud_no_estimate_can_be_made_on_is_refused_with_the_in_memory_reason(tmp_path, case, k):
    pts = _DEGENERATE[case]()
    why = core.estimate(pts, k=k).params["degenerate"]  # in memory: every point invalid, and why
    out = tmp_path / "out.ply"
    with pytest.raises(ValueError, match="no point can be estimated: " + re.escape(why)):
        estimate_tiled(pts, out, k=k, tile_points=100, workers=0)  # before: valid made-up values or a numpy error
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no output, no work directory


@pytest.mark.parametrize("k", ["auto", 15])
def test_a_cloud_of_copies_gets_the_in_memory_answer(tmp_path, k):
    half = shapes.sphere(300, seed=1).points
    pts = np.r_[half, half]  # 300 places: fewer than the 320 neighbours k="auto" plans for 600 points
    mem = core.estimate(pts, k=k)
    estimate_tiled(pts, tmp_path / "out.ply", k=k, tile_points=100, workers=0)
    f = read_cloud(tmp_path / "out.ply").fields
    np.testing.assert_array_equal(f["valid"].astype(bool), mem.valid)
    np.testing.assert_allclose(f["k1"], mem.k1, rtol=1e-6, atol=1e-9)  # the file's float32


def test_a_k_above_the_distinct_positions_is_refused_as_in_memory(tmp_path):
    half = shapes.sphere(300, seed=1).points
    pts = np.r_[half, half]
    with pytest.raises(ValueError) as mem:
        core.estimate(pts, k=301)
    with pytest.raises(ValueError, match=re.escape(str(mem.value))):
        estimate_tiled(pts, tmp_path / "out.ply", k=301, tile_points=100, workers=0)
