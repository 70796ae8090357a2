"""k="auto" in tiles: every point gets the in-memory choice of k, model and fit, from the
whole cloud's candidates, medians and pass decision; the halo holds the derived chain."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import anchors, neighbour_budget, noise, passes, shapes, shapes_thin
from core.frame import signed_directions
from core.io import read_cloud
from core.tiled import auto, estimate_tiled, halo, task, wholecloud


def _same(path, mem):
    """Assert that the PLY result at ``path`` is ``mem`` point for point (normal signs aligned)."""
    c = read_cloud(path)
    f = c.fields
    valid = f["valid"].astype(bool)
    np.testing.assert_array_equal(valid, mem.valid)
    same = np.einsum("ij,ij->i", c.normals, mem.normals) > 0
    assert same[valid].mean() >= 0.999
    s = np.where(same, 1.0, -1.0)
    k1, k2 = np.where(same, f["k1"], -f["k2"]), np.where(same, f["k2"], -f["k1"])
    e1, _ = signed_directions(*(np.column_stack([np.where(same, f[f"{a}_{x}"], f[f"{b}_{x}"]) for x in "xyz"])
                                for a, b in (("e1", "e2"), ("e2", "e1"))))
    v = mem.valid
    assert np.abs(c.normals * s[:, None] - mem.normals)[v].max() < 1e-9
    assert max(np.abs(k1 - mem.k1)[v].max(), np.abs(k2 - mem.k2)[v].max()) < 1e-9
    assert np.abs(e1 - mem.e1)[v].max() < 1e-9  # signs too
    np.testing.assert_array_equal(f["border"].astype(bool), mem.border)  # reads the neighbours' final normals


@pytest.fixture
def small_candidates(monkeypatch):
    """Candidates (20, 28) and jets (15, 20, 28) for 4000-8000 points, as a cloud of 2 million
    gets them (core.scale.candidates): a short chain, so 16 tiles need only small halos."""
    monkeypatch.setattr(neighbour_budget, "NEIGHBOUR_BUDGET", 240_000)


def _noisy_torus(n=8000):
    """Noise on half of a torus (NR, refined, at the noise's k there; jets elsewhere), and outliers."""
    t = shapes.torus(n, seed=3).points
    pts = np.where(t[:, :1] > 0.5, noise.add_noise(t, 0.1, seed=1), t)
    return np.concatenate([pts, [[0.0, 0.0, 2.5], [3.2, 0.4, 0.0]]])  # two outliers: robust mode at work


def test_auto_in_16_tiles_is_the_in_memory_estimate(tmp_path, small_candidates, monkeypatch):
    sample = passes.rule_sample  # the pass rule judged on ~1000 of the points, in memory and in the tiles
    monkeypatch.setattr(passes, "rule_sample", lambda pts, n=None: sample(pts, n, size=1000))
    monkeypatch.setattr(auto, "rule_sample", passes.rule_sample)
    pts = _noisy_torus(6000)
    mem = core.estimate(pts, passes=2)
    assert mem.params["passes_run"] >= 1 and len(np.unique(mem.k_point)) > 1
    run = estimate_tiled(pts, tmp_path / "out.ply", tile_points=375, workers=0, passes=2,
                         workdir=tmp_path / "work", keep_workdir=True)
    assert run.n_tiles >= 16
    _same(tmp_path / "out.ply", mem)
    kept = auto.PassView(tmp_path / "work", run.params["passes_run"])
    rows = np.concatenate([kept.load_result(t) for t in range(run.n_tiles)])
    rows = rows[np.argsort(rows["index"])]
    np.testing.assert_array_equal(rows["k"], mem.k_point)  # the same k per point
    for field, name in (("degree", "degree_point"), ("border", "border"), ("crease", "crease")):  # and flags
        np.testing.assert_array_equal(rows[field], getattr(mem, name), err_msg=field)
    ref = (tmp_path / "out.ply").read_bytes()  # a tile killed before its marker: redone, the same file
    (tmp_path / "work" / "results" / "tile_000003.done").unlink()
    kept.result_path(3).write_bytes(b"garbage")
    rerun = estimate_tiled(pts, tmp_path / "out.ply", tile_points=375, workers=0, passes=2, workdir=tmp_path / "work")
    assert rerun.tiles_skipped == run.n_tiles - 1 and rerun.params == run.params
    assert (tmp_path / "out.ply").read_bytes() == ref
    for name in ("noise", "crease_typical", "passes_run"):  # the whole cloud's, exactly
        assert run.params[name] == mem.params[name]


def test_anchored_fits_in_tiles_are_the_in_memory_estimate(tmp_path, small_candidates, monkeypatch):
    """Where a point reads its fit from anchors among its nearest (core.anchors; here from
    k > 8, so that the small candidates use them) each pass depends on one ring more, and its
    scale on an anchor's, which the halo's chain and each pass's reach hold (core.tiled.halo.auto_chain).
    (As in the test below, that one ring fewer is wrong is not asserted: the halo's growth overshoots.)"""
    monkeypatch.setattr(anchors, "ANCHOR_ROWS", 8)
    drawn, assign, shared, scale_of = [], anchors.assign, [], anchors.shared_scale
    monkeypatch.setattr(anchors, "assign", lambda *args: drawn.append(assign(*args)) or drawn[-1])
    monkeypatch.setattr(anchors, "shared_scale", lambda *args: shared.append(scale_of(*args)) or shared[-1])
    pts = _noisy_torus(4000)
    mem = core.estimate(pts, passes=2)
    assert mem.params["passes_run"] >= 1 and anchors.followers(drawn[-1]).mean() > 0.3
    assert len(shared[-1][0]) > 1000  # and the scale of most noisy points is an anchor's
    monkeypatch.setattr(task, "first_margin", lambda *args: 0.0)  # the halo only what the chain demands
    run = estimate_tiled(pts, tmp_path / "out.ply", tile_points=375, workers=0, passes=2)
    assert run.n_tiles >= 8
    _same(tmp_path / "out.ply", mem)


def test_a_thin_rims_fold_test_is_the_whole_clouds(tmp_path, small_candidates):
    """The fold test (core.initial_normals.unfolded) compares a point's spread with the whole cloud's
    median, which a second pre-pass fixes (it depends on the noise the first one fixes):
    with each tile's own median, a noisy wedge's tiles judge folds against other values."""
    s = shapes_thin.THIN_SHAPES["thin_wedge"](6000, seed=0)
    pts = np.concatenate([shapes_thin.noisy(s, 0.2, 1), [[0.5, 0.5, 0.3], [0.2, 0.9, -0.4]]])  # robust rows
    mem = core.estimate(pts, passes=1)
    assert mem.params["fold_typical"] is not None and mem.outlier.sum() >= 2
    run = estimate_tiled(pts, tmp_path / "out.ply", tile_points=375, workers=0, passes=1,
                         workdir=tmp_path / "work")
    for name in ("noise", "fold_typical", "crease_typical", "passes_run"):
        assert run.params[name] == mem.params[name], name
    _same(tmp_path / "out.ply", mem)


def test_tiles_step_back_where_memory_does(tmp_path):
    """The chirp at 0.1 spacing of noise keeps one pass and undoes the 2nd, which repeats the
    1st's change of H on its tightening ridges: memory reports the first fit's curvatures
    there (core.drift); the tiles write pass 1 stepped back and the run reads it."""
    pts = noise.add_noise(shapes.chirp(6000, seed=0).points, 0.1, seed=17)
    mem = core.estimate(pts)
    assert mem.params["passes_run"] == 1
    run = estimate_tiled(pts, tmp_path / "out.ply", tile_points=1500, workers=0, workdir=tmp_path / "work",
                         keep_workdir=True)
    assert run.n_tiles >= 4
    plan = task.auto_plan(task.TileSpec(k="auto", method="nr", passes=4, orientation="propagate", n_points=len(pts)))
    assert auto.pass_choice(auto.TileStore(tmp_path / "work"), run.n_tiles, plan) == (1, True)
    _same(tmp_path / "out.ply", mem)


def test_the_candidates_come_from_the_whole_cloud(small_candidates):
    spec = task.TileSpec(k="auto", method="nr", passes=4, orientation="propagate", n_points=8000)
    assert task.auto_plan(spec, 500).candidates == core.plan(8000).candidates == (20, 28)
    assert core.plan(500).candidates != (20, 28)  # what a tile alone would have chosen


def test_a_noise_free_cloud_keeps_the_jets_and_one_fit(tmp_path, small_candidates):
    """Quiet: the jets are the result and no refinement pass runs; signs by a viewpoint."""
    pts = shapes.ellipsoid(4000, seed=2).points
    view = (0.1, -0.2, 0.3)  # inside: every normal inward
    mem = core.estimate(pts, orientation=view)
    assert mem.params["passes_run"] == 0 and mem.params["jet_fraction"] > 0.5
    run = estimate_tiled(pts, tmp_path / "out.ply", tile_points=250, workers=0, orientation=view)
    assert run.n_tiles >= 16 and run.params["passes_run"] == 0
    _same(tmp_path / "out.ply", mem)


def test_the_derived_auto_chain_is_enough(tmp_path, monkeypatch, small_candidates):
    """With no head start (a zero first margin) the halo is only what the chain demands
    (grown in steps until it is covered): the derived chain reproduces memory. (That one
    ring fewer is wrong is not asserted: the halo's growth steps overshoot, so on a cloud
    this small it can come out the same.)"""
    pts = _noisy_torus(4000)
    mem = core.estimate(pts, passes=1)
    monkeypatch.setattr(task, "first_margin", lambda *args: 0.0)
    estimate_tiled(pts, tmp_path / "out.ply", tile_points=250, workers=0, passes=1)
    _same(tmp_path / "out.ply", mem)


def test_the_auto_chain_covers_every_pass():
    # own-sheet rows a ring more (core.one_sheet); the flags of that ring read two more (halo.FLAG_RINGS)
    assert halo.auto_chain(4, 226, 15) == ((5, 226), (6, 40), (8, 15))
    assert halo.auto_chain(0, 20, 15) == ((1, 20), (2, 20), (4, 15))
    assert halo.auto_chain(2, 226, 15, anchored=True) == ((7, 226), (8, 40), (10, 15))  # a ring more per pass, one for the scale
    assert halo.nr_chain(1, 15, 15, robust=False) == ((2, 15), (2, 15))  # the own points' flags (reported)
    assert halo.nr_chain(1, 30, 15, robust=True) == ((2, 30), (5, 15))  # the flags the initial normals read


@pytest.mark.parametrize("sizes", [[0], [1], [5, 0, 3], [4, 4], [3000, 1, 2500, 0, 7], [1_200_000, 900_001]])
def test_the_median_of_sorted_files_is_numpys(monkeypatch, sizes):
    monkeypatch.setattr(wholecloud, "_GATHER", 64)  # the narrowing, not only the final partition
    rng = np.random.default_rng(len(sizes))
    arrays = [np.sort(np.round(rng.normal(size=n), 2)) for n in sizes]  # ties across arrays
    joined = np.concatenate(arrays)
    assert wholecloud.median_of(arrays) == (float(np.median(joined)) if len(joined) else 0.0)
    for k in (0, len(joined) // 3, len(joined) - 1) if len(joined) else ():
        assert wholecloud.kth_smallest(arrays, k) == np.sort(joined)[k]


def test_the_pass_rule_is_replayed_on_whole_cloud_means(tmp_path):
    """Tiles' sums of turns: a pass that turns more than PASS_DECAY x the previous is undone."""
    store = auto.TileStore(tmp_path)
    (tmp_path / "results").mkdir()
    plan = core.plan(1000, k="auto")
    share = [[10.0, 1.0, 0.9, 0.8, 0.7], [100.0, 10.0, 6.0, 5.9, 1.0]]  # per tile: sum of turns per pass
    for t, sums in enumerate(share):
        stats = np.zeros((plan.passes + 2, 2))
        stats[:-1, 0], stats[:-1, 1] = sums, 500
        stats[-1, 0] = 500  # points NR fits with noise
        store.save_array(store.result_path(t, ".stats"), stats)
    assert auto.kept_pass(store, 2, plan) == 2  # means 0.11, 0.011, 0.0069, 0.0067 (> 0.7 x 0.0069): undone


def test_a_work_directory_of_other_auto_rules_is_not_resumed(monkeypatch):
    """The candidates (a library's rule, not an argument) are part of the run's manifest."""
    from core.tiled import run

    spec = task.TileSpec(k="auto", method="nr", passes=4, orientation="propagate", n_points=8000)
    before = run._auto_rules(spec)
    monkeypatch.setattr(neighbour_budget, "NEIGHBOUR_BUDGET", 240_000)
    assert run._auto_rules(spec) != before
    assert run._auto_rules(task.TileSpec(k=15, method="nr", passes=1, orientation="propagate")) is None


@pytest.mark.parametrize("share", [1.0, 0.25])
def test_copies_in_tiles_are_the_in_memory_estimates_places(tmp_path, small_candidates, share):
    """core.estimate estimates copies of a point once, at their place (core.duplicates); the
    tiles' halos hold the distinct places' neighbours, which reach farther than the copies'."""
    base = _noisy_torus(4000)
    rng = np.random.default_rng(7)
    pts = np.concatenate([base, base[rng.random(len(base)) < share]])
    pts = pts[rng.permutation(len(pts))]
    mem = core.estimate(pts)
    assert mem.params["duplicates"] > 900
    run = estimate_tiled(pts, tmp_path / "out.ply", tile_points=400, workers=0)
    assert run.n_tiles >= 8
    _same(tmp_path / "out.ply", mem)
