"""Peak memory of k="auto" at 1M points (issue 15): the stages that peaked hold no more
than they need, with the same numbers (``python -m core.bench.perf_identity`` proves the
whole estimate bit-identical; these pin each cut)."""

from __future__ import annotations

import importlib
import tracemalloc
import weakref

import numpy as np

import core
from core import initial_normals, noise, orientation, shapes, stages
from core._progress import Progress
from core.frame import darboux_frame, height_field_derivatives, jet_frames
from core.linalg import tangent_basis
from core.tuning import RESETTLE_K, SEARCH_WIDTH


def _peak_bytes(fn):
    """(result, peak bytes numpy allocated while ``fn`` ran: numpy reports to tracemalloc)."""
    tracemalloc.start()
    try:
        out = fn()
        return out, tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_resettle_reads_the_graph_in_place():
    """The held graph is (N, 56) int32; an int64 copy of its first RESETTLE_K columns was
    as large as the evidence itself (~13.6 MB at 20k points before, ~7.2 MB now)."""
    s = shapes.torus(20_000, seed=0)
    nb = core.build_neighbours(s.points, SEARCH_WIDTH)
    idx = nb.indices.astype(np.int32)
    evidence_bytes = len(idx) * RESETTLE_K * 8
    orientation.resettle(s.points[:100], s.normals[:100], np.clip(idx[:100], 0, 99), "outward")  # compiled
    (sign, conf), peak = _peak_bytes(lambda: orientation.resettle(s.points, s.normals, idx, "outward"))
    wide = orientation.resettle(s.points, s.normals, np.ascontiguousarray(idx[:, :RESETTLE_K], dtype=np.int64),
                                "outward")
    assert peak < 1.7 * evidence_bytes
    np.testing.assert_array_equal(sign, wide[0])
    np.testing.assert_array_equal(conf, wide[1])


def test_jet_frames_by_chunks_are_the_frames_at_once():
    """Row by row the same numbers as darboux_frame over all rows at once, NaN rows included."""
    rng = np.random.default_rng(3)
    n = 1000
    coef = rng.normal(size=(n, 10))
    coef[::17] = np.nan
    z = rng.normal(size=(n, 3))
    z /= np.linalg.norm(z, axis=1)[:, None]
    t1, t2 = tangent_basis(z)
    s = rng.uniform(0.5, 2.0, n)
    mu, W = height_field_derivatives(coef[:, 1], coef[:, 2], 2 * coef[:, 3], coef[:, 4], 2 * coef[:, 5])
    with np.errstate(invalid="ignore", divide="ignore"):
        whole = darboux_frame(t1, t2, z, np.nan_to_num(mu), np.nan_to_num(W) / s[:, None, None])
    for a, b in zip(jet_frames(coef, t1, t2, z, s, rows=96), whole):  # chunks of 96 rows: 11, the last one short
        np.testing.assert_array_equal(a, b)


def test_the_crease_reference_keeps_only_what_flags_read():
    """Residuals (valid, rms, spread): its frames were 84 MiB at 1M points, read by nobody;
    the creases are those of the full fit."""
    pts = noise.add_noise(shapes.torus(5000, seed=1).points, 0.2, seed=2)
    plan = core.plan(len(pts), k="auto")
    nb, _ = stages.spatial_neighbours(pts, plan, None, Progress(None))
    init = initial_normals.initial_normals(nb.points, nb, plan, np.zeros(len(pts), dtype=bool), Progress(None))
    ref = stages.crease_reference(nb.points, init.normals, init.has_normal, nb, plan, Progress(None))
    assert type(ref) is stages.Residuals
    idx, dist = nb.take(plan.k_initial)
    full = stages.fit_all(nb.points, init.normals, idx, np.full(len(pts), idx.shape[1]), dist[:, -1],
                          init.has_normal, method=plan.method, options={**plan.options, "degree": 1, "robust": None},
                          report=Progress(None))
    for name in stages.Residuals._fields:
        np.testing.assert_array_equal(getattr(ref, name), getattr(full, name))
    np.testing.assert_array_equal(stages._creases(ref.valid, ref.rms, ref.spread)[0],
                                  stages._creases(full.valid, full.rms, full.spread)[0])


def test_a_refinement_pass_holds_one_pass_of_anchor_fits_and_no_unused_jets(monkeypatch):
    """While a pass fits, the previous pass's anchors' fits (core.anchors.Kept, 54 MB at 1M
    points) are gone, and where no point keeps its jet the jets' frames (86 MB) are not
    held through the refinement (a 1M sphere at 1 spacing of noise peaked at 2.42 GB)."""
    from core import anchors, refinement

    pts = noise.add_noise(shapes.torus(6000, seed=5).points, 0.2, seed=6)
    alive, jets_seen = [], []
    build = anchors.Kept.__init__

    def watched(self, anchor):
        assert not [ref for ref in alive if ref() is not None]  # the earlier passes' are freed
        build(self, anchor)
        alive.append(weakref.ref(self.coef))

    refine = refinement.refine

    def seen(pts, initial, outlier, nb, sc, *args):
        jets_seen.append((sc.jets, bool(sc.on_jet.any())))
        return refine(pts, initial, outlier, nb, sc, *args)

    monkeypatch.setattr(anchors.Kept, "__init__", watched)
    monkeypatch.setattr(importlib.import_module("core.estimate"), "refine", seen)
    res = core.estimate(pts)
    assert len(alive) >= 3 and res.valid.mean() > 0.99  # a first fit and passes, at anchors
    assert jets_seen == [(None, False)]
