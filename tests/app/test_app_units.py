"""Pieces of the viewer that need no window: fields, glyphs, state, arguments."""

from __future__ import annotations

import numpy as np
import pytest

from app import glyphs
from app.fields import FIELDS, colormap_for, compute_fields, is_signed, resolve_field, robust_limits


@pytest.mark.parametrize("clip", [0.0, 2.0, 10.0])
def test_signed_limits_are_symmetric_and_robust(clip):
    values = np.r_[np.linspace(-1, 3, 1000), 1e6, np.nan]
    lo, hi = robust_limits(values, signed=True, clip=clip)
    assert lo == -hi and 0 < hi
    if clip:
        assert hi < 10  # the outlier is clipped away


def test_unsigned_limits_and_degenerate_cases():
    lo, hi = robust_limits(np.linspace(0, 1, 101), signed=False, clip=10)
    assert lo == pytest.approx(0.1) and hi == pytest.approx(0.9)
    assert robust_limits(np.full(10, 2.0), signed=False)[0] < 2.0 < robust_limits(np.full(10, 2.0), signed=False)[1]
    assert robust_limits(np.full(5, np.nan), signed=True) == (-1.0, 1.0)
    assert robust_limits(np.zeros(5), signed=True)[1] > 0


def test_field_names_and_colormaps():
    assert resolve_field("H") == "mean" and resolve_field("K") == "gaussian" and resolve_field("k1") == "k1"
    with pytest.raises(ValueError, match="valid fields"):
        resolve_field("banana")
    spec = FIELDS["err_mean"]
    assert not is_signed(spec, np.array([0.1, 0.2])) and colormap_for(spec, False) == "magma"
    assert colormap_for(FIELDS["mean"], True) == "RdBu_r"


def test_compute_fields_on_a_torus(torus):
    import core

    res = core.estimate(torus.points, torus.normals, k=15)
    fields = compute_fields(res, reference_normals=torus.normals, sample=torus.sample)
    assert set(FIELDS) <= set(fields)
    assert np.allclose(fields["mean"], 0.5 * (res.k1 + res.k2), equal_nan=True)
    assert np.nanmedian(fields["normal_dev"]) < 5.0
    assert fields["mean"] is not res.mean  # copies, never the result's own arrays


def test_glyph_segments_are_centred_and_skip_invalid():
    pts = np.zeros((4, 3))
    dirs = np.array([[1.0, 0, 0], [0, 2.0, 0], [np.nan, 0, 0], [0, 0, 1.0]])
    v, lines = glyphs.segments(pts, dirs, np.arange(4), 2.0)
    assert v.shape == (6, 3) and lines.tolist() == [2, 0, 1, 2, 2, 3, 2, 4, 5]
    assert np.allclose(v[0], [-1, 0, 0]) and np.allclose(v[3], [0, 1, 0])  # unit length either way


def test_glyph_subsample_is_stable():
    a, b = glyphs.subsample(1000, 0.1), glyphs.subsample(1000, 0.2)
    assert len(a) == 100 and len(b) == 200 and set(a) <= set(b)
    assert len(glyphs.subsample(1000, 0.0)) == 0


def test_state_emits_names_once_and_batches(qtbot):
    from app.state import ViewerState

    state = ViewerState()
    seen = []
    state.changed.connect(seen.append)
    state.k = 20
    state.set(k=20)  # unchanged: no signal
    with state.batch():
        state.set(noise=10, method="ct")
        state.set(noise=20)
    assert seen == ["k", "noise", "method"] and state.noise == 20.0
    state.set(compare_method="")
    assert state.compare_method is None
    with pytest.raises(AttributeError, match="valid"):
        state.set(banana=1)
    with pytest.raises(ValueError, match="finite"):
        state.set(clim=(0, np.inf))


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--method", "nope"], "valid methods"),
        (["--compare", "nope"], "valid methods"),
        (["--field", "nope"], "valid fields"),
        (["--shape", "nope"], "valid shapes"),
        (["--k", "1"], "at least 3"),
        (["--glyphs", "e3"], "valid: e1, e2, normals"),
    ],
)
def test_bad_arguments_exit_with_a_message(argv, message, capsys):
    from app.__main__ import main

    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_reference_guard_protects_the_singletons(qapp):
    import sys

    from app import _refguard

    info = _refguard.guard()
    assert set(info) >= {"none", "true", "applied"}
    if (info["none"] > 0.5 or info["true"] > 0.5) and sys.version_info < (3, 12):
        assert info["applied"]
        assert sys.getrefcount(None) > 1 << 39 and sys.getrefcount(True) > 1 << 39
    assert _refguard.guard() == info  # once per process


def test_dialog_pieces(qtbot):
    import core.io
    import core.shapes

    from app.widgets import ShapeDialog
    from app.actions import read_filter as _read_filter, write_filter as _write_filter

    dialog = ShapeDialog(list(core.shapes.SHAPES), shape="saddle", count=1234)
    qtbot.addWidget(dialog)
    assert dialog.shape == "saddle" and dialog.count == 1234
    filt = _read_filter()
    for ext in core.io.READ_FORMATS:
        assert f"*{ext}" in filt
    assert "*.ply" in _write_filter() and "*.csv" in _write_filter()


def test_histogram_and_limits_of_many_values_use_a_random_subset_scaled_to_the_whole(qapp, monkeypatch):
    import app.fields
    import app.widgets.histogram as hist

    monkeypatch.setattr(hist, "SAMPLE", 10_000)
    h = hist.Histogram()
    v = np.random.default_rng(0).normal(size=100_000)
    v[::10] = np.nan  # a period that a strided subset would alias with
    h.set_data(v, clim=(-2.0, 2.0), cmap="RdBu_r", label="H")
    assert abs(h.counts.sum() - 90_000) < 900 and "90,000 pts, 10,000 nan" in h.ax.get_title()
    exact, _ = np.histogram(np.clip(v[np.isfinite(v)], -2.4, 2.4), bins=h.bins, range=(-2.4, 2.4))
    assert np.abs(h.counts - exact).max() < 0.25 * exact.max()  # the same shape
    monkeypatch.setattr(app.fields, "LIMIT_SAMPLE", 2000)
    look = app.fields.colouring(app.fields.FIELDS["mean"], v, clip=2.0)
    truth = np.percentile(np.abs(v[np.isfinite(v)]), 98.0)
    assert look.clim[1] == pytest.approx(truth, rel=0.1) and look.clim[0] == -look.clim[1]


def test_histogram_puts_infinite_outlier_scores_in_the_top_bar_not_with_nan(qapp):
    """A lone point's outlier score is inf (core.kernels.isolated_groups): an outlier, not a missing value."""
    import app.widgets.histogram as hist

    h = hist.Histogram()
    v = np.r_[np.linspace(0.0, 3.0, 100), [np.inf] * 7, [np.nan] * 2]
    h.set_data(v, clim=(0.0, 8.0), cmap="RdBu_r", label="Outlier score")
    assert h.counts.sum() == 107 and h.counts[-1] == 7
    assert "107 pts, 2 nan" in h.ax.get_title()


def test_histogram_draws_in_a_turn_of_its_own_after_the_3d_frame(qtbot, monkeypatch):
    """A changed histogram is drawn later, never while a 3D frame is still due: the two
    heavy GUI steps of one change are two turns of the event loop (issue 11, GUI stall)."""
    import app.widgets.histogram as hist

    monkeypatch.setattr(hist, "MAX_WAITS", 10**6)  # this test does not time out the wait
    h = hist.Histogram()
    qtbot.addWidget(h)
    drawn, due = [], [True]
    monkeypatch.setattr(h, "draw", lambda: drawn.append(h.ax.get_title()))
    h.frame_due = lambda: due[0]
    h.set_data(np.linspace(-1.0, 1.0, 500), clim=(-1.0, 1.0), cmap="RdBu_r", label="H")
    h.set_data(np.linspace(-2.0, 2.0, 700), clim=(-2.0, 2.0), cmap="RdBu_r", label="K")
    assert h.draw_pending and drawn == [] and h.counts.sum() == 700  # data now, the draw later
    qtbot.wait(4 * hist.DRAW_DELAY_MS)
    assert drawn == [] and h.draw_pending  # the 3D frame first
    due[0] = False
    h.after_frame()
    qtbot.waitUntil(lambda: len(drawn) == 1, timeout=5000)
    assert "K" in drawn[0] and not h.draw_pending  # two changes, one draw, of the last one
    monkeypatch.setattr(hist, "MAX_WAITS", 2)
    due[0] = True  # a 3D view that never renders (hidden) does not hold the histogram for good
    h.clear()
    qtbot.waitUntil(lambda: len(drawn) == 2, timeout=5000)
    h.set_data(np.zeros(10), clim=(-1.0, 1.0), cmap="RdBu_r", label="H")
    h.flush()  # a screenshot draws a pending change at once
    assert len(drawn) == 3 and not h.draw_pending


def test_the_worker_searches_the_neighbours_once_and_matches_a_fresh_estimate(qapp):
    """Slider moves re-use one neighbour graph, the stage cache's (searched in spatial order,
    with head room for k), and every result is bit-identical to core.estimate of the same
    request (issue 11: one neighbour cache)."""
    import core
    from app.request import EstimateRequest
    from app.source import make_shape
    from app.worker import EstimateWorker

    source = make_shape("torus", 1500, seed=2)
    worker, got = EstimateWorker(), []
    worker.finished.connect(got.append)
    worker.failed.connect(lambda gen, message: pytest.fail(message))
    steps = [dict(k_auto=True, passes=4), dict(k_auto=True, passes=2), dict(k=20), dict(k=12),
             dict(k=12, method="ct", compare_method="nr"), dict(k=12, noise=5.0)]
    for gen, step in enumerate(steps, start=1):
        worker.latest = gen
        worker.run(EstimateRequest(gen=gen, source=source, **step))
    assert [out.gen for out in got] == list(range(1, len(steps) + 1))
    assert [out.reused_neighbours for out in got] == [False, True, True, True, True, False]  # noise: new points
    assert worker._cache.computed["neighbours"] == 2  # the clean cloud once, the noisy copy once
    for out in got:
        req = out.request
        runs = [(req.method, out.result)] + ([(req.compare_method, out.compare)] if req.compare_method else [])
        for method, res in runs:
            passes = req.passes if core.METHODS[method].uses_passes else None
            fresh = core.estimate(out.points, source.normals, k=req.k_for(method), method=method, passes=passes)
            for name in ("normals", "k1", "k2", "e1", "e2", "valid", "k_point", "outlier_score", "crease",
                         "border", "orientation_confidence"):
                assert np.asarray(getattr(res, name)).tobytes() == np.asarray(getattr(fresh, name)).tobytes(), name
            assert res.params == fresh.params
    assert got[1].spacing == pytest.approx(core.spacing.mean_spacing(source.points))


def test_reader_warnings_reach_the_loaded_source(tmp_path):
    """A headerless x y z r g b file: the reader keeps the colours as fields and warns; the
    warning rides with the source for the window to show (not lost on the loader thread)."""
    from app.source import load_file

    path = tmp_path / "scan.xyz"
    rng = np.random.default_rng(0)
    np.savetxt(path, np.column_stack([rng.random((50, 3)), rng.integers(0, 256, (50, 3))]))
    source = load_file(path)
    assert source.normals is None
    assert len(source.notes) == 1 and "no normals" in source.notes[0]
    np.savetxt(path, rng.random((50, 3)))
    assert load_file(path).notes == ()
