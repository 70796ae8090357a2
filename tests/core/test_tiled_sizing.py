"""Tile sizes from the halos measured on the cloud's sample (core.tiled.sizing)."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from core import noise, shapes
from core.tiled import engine, estimate_tiled, run, sizing


def _spec(k, n):
    spec, _ = run._spec(k, "nr", None, "auto", None, False, in_process=True)
    spec = dataclasses.replace(spec, n_points=n)
    return dataclasses.replace(spec, passes=run.auto_plan(spec).passes) if k == "auto" else spec


@pytest.fixture(scope="module")
def torus():
    return noise.add_noise(shapes.torus(40_000, seed=3).points, 0.1, seed=1)


def test_predicted_loads_are_what_the_tiles_load(tmp_path, torus, monkeypatch):
    """The sample's estimate of each tile's points with its halo is within 25 % of what the
    task loaded (k = 15, 8 tiles)."""
    seen = {}
    orig = engine.timed

    def timed(fn, root, tile, spec):
        stats = orig(fn, root, tile, spec)
        seen[tile] = stats["loaded"]
        return stats

    monkeypatch.setattr(engine, "timed", timed)
    estimate_tiled(torus, tmp_path / "out.ply", k=15, tile_points=5000, workers=0)
    k_max, chain = sizing.tile_chain(_spec(15, len(torus)))
    margin = sizing.margin_on_sample(torus, len(torus), k_max, max(r for r, _ in chain))
    predicted = sizing.loads(torus, len(torus), 8, margin)
    loaded = np.array([seen[t] for t in range(8)])
    assert loaded.sum() > 1.1 * len(torus)  # the halos are not negligible here
    np.testing.assert_allclose(np.sort(predicted), np.sort(loaded), rtol=0.25)


def test_tiles_fit_the_room_with_their_halos(torus):
    spec = _spec(15, len(torus))
    bpp = run.bytes_per_point(15)
    for room_points in (15_000, 30_000):
        tp = sizing.choose_tile_points(torus, len(torus), spec=spec, workers=2, room=room_points * bpp,
                                       bytes_per_point=bpp, least_tiles=-(-len(torus) // room_points))
        k_max, chain = sizing.tile_chain(spec)
        margin = sizing.margin_on_sample(torus, len(torus), k_max, max(r for r, _ in chain))
        held = sizing.loads(torus, len(torus), -(-len(torus) // tp), margin)
        assert held.max() <= room_points  # the old rule (tile x 1.5) gave tiles of room/1.5 without looking


def test_halos_wider_than_the_tiles_are_told(torus):
    """k="auto" on a small cloud: every tile's chain reaches most of the cloud, which the
    run says (HaloTooWide) rather than spending many times the in-memory work in silence."""
    spec = _spec("auto", len(torus))
    bpp = run.bytes_per_point(run._memory_k(spec))
    with pytest.warns(sizing.HaloTooWide, match="larger --memory"):
        sizing.choose_tile_points(torus, len(torus), spec=spec, workers=2, room=5000 * bpp, bytes_per_point=bpp,
                                  least_tiles=8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a budget holding the whole cloud: one tile, no halo, no warning
        tp = sizing.choose_tile_points(torus, len(torus), spec=spec, workers=2, room=len(torus) * bpp,
                                       bytes_per_point=bpp, least_tiles=1)
    assert tp == len(torus)


def test_a_budget_below_a_worker_is_refused_before_any_work(tmp_path, torus):
    """The sizing took the room of any budget (at least 1 byte); the refusal of a budget no
    worker fits in, which the old size rule made, came back with one shared check."""
    with pytest.raises(ValueError, match="memory '100MB' is too small for a tile worker"):
        estimate_tiled(torus, tmp_path / "out.ply", k=15, workers=0, memory="100MB")
    assert list(tmp_path.iterdir()) == []
