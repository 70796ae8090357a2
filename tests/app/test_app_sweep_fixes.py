"""Viewer defects from the app sweep (/work/sweep_app/FINDINGS.md), each driven through the real window."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from app_testutils import on_next_preview, wait_result
from PySide6.QtCore import Qt

import core.shapes
from app.source import CloudSource, load_file, make_shape


def _identical():
    return CloudSource(name="identical", points=np.ones((200, 3)))


def _caption(window) -> str:
    return window.scene._title_actor.GetInput()


# -- 1 ---------------------------------------------------------------------------------
def test_picking_a_point_of_a_degenerate_cloud_says_it_has_no_estimate(make_window, qtbot):
    window = make_window(_identical(), k_auto=False, k=12)
    why = window.output.result.params["degenerate"]
    window.state.set(picked=5)
    values = window.inspector.values
    assert values["index"] == "5" and why in values["no_estimate"]
    assert "no estimate" in window.inspector.header.text()
    assert "pick-point" in window.plotter.actors and "pick-neighbours" not in window.plotter.actors
    window.state.set(point_size=9.0)  # set_point_size re-picks
    with wait_result(qtbot, window, 30_000) as blocker:  # the next estimate of the pick's cloud draws
        window.state.set(k=20)
    assert blocker.args[0].request.k == 20 and "NR k=20" in window.status_label.text()
    assert window.inspector.values["index"] == "5"


# -- 2 ---------------------------------------------------------------------------------
def _looks_like(window, out, values):
    """What is drawn is ``out`` (its colours ``values``): points, colours, caption, histogram and limit boxes."""
    assert np.array_equal(window.scene.points, out.points)
    assert window.shown["gen"] == out.gen and "preview" not in window.shown
    assert np.array_equal(window.scene._values, values, equal_nan=True)
    assert "preview" not in _caption(window) and "computing" not in _caption(window)
    assert "(preview)" not in window.histogram.ax.get_title()
    lo, hi = window.shown["clim"]
    assert window.scene._lut.scalar_range == pytest.approx((lo, hi))
    assert (window.field_panel.lo.value(), window.field_panel.hi.value()) == pytest.approx((lo, hi))


def test_cancel_during_a_preview_draws_the_kept_result_again(make_window, qtbot, previewing, tmp_path):
    window = make_window(previewing)
    kept, values = window.output, window.scene._values.copy()
    seen = on_next_preview(window, lambda out: (window.shown["clim"],
                                                 (window.field_panel.lo.value(), window.field_panel.hi.value())))
    window.state.set(noise=50.0)
    qtbot.waitUntil(lambda: bool(seen), timeout=60_000)
    preview_clim, boxes = seen[0]
    assert boxes == pytest.approx(preview_clim)  # show_preview updates the limit boxes
    window.cancel()
    assert window.output is kept and not window.estimator.busy
    _looks_like(window, kept, values)
    assert "showing the previous result" in window.status_label.text()

    # a failed load leaves the estimate under way alone (test_app_view_sweep.py): its result comes
    seen = on_next_preview(window, lambda out: window.open_file(tmp_path / "missing.xyz"))
    with wait_result(qtbot, window, 60_000) as blocker:
        window.state.set(noise=30.0)
    qtbot.waitUntil(lambda: bool(seen) and window.loader.pending is None, timeout=10_000)
    assert any("missing.xyz" in note.message for note in window.notifier.history)
    _looks_like(window, blocker.args[0], window.scene._values)
    assert blocker.args[0].request.noise == 30.0


def test_cancel_during_the_first_preview_clears_it(make_window, qtbot, previewing):
    window = make_window()
    late = []  # the job thread's own word that it stopped comes after cancel() announced it
    window.estimator._worker.cancelled.connect(late.append, Qt.ConnectionType.DirectConnection)
    seen = on_next_preview(window, lambda out: window.cancel())
    window.set_source(previewing)
    qtbot.waitUntil(lambda: bool(seen) and bool(late), timeout=60_000)
    qtbot.wait(50)  # its queued signal reaches the GUI thread
    assert window.output is None
    assert np.isnan(window.scene._values).all() if window.scene._values is not None else True
    assert not window.scene._bar.GetVisibility() and window.histogram.counts.sum() == 0
    assert "preview was cleared" in window.status_label.text()
    assert "not estimated" in _caption(window)


# -- 3 ---------------------------------------------------------------------------------
def test_export_during_a_preview_says_which_result_it_wrote(make_window, qtbot, previewing, tmp_path):
    import core.io

    window = make_window(previewing)
    kept = window.output
    seen = on_next_preview(window, lambda out: window.export_result(tmp_path / "x.ply"))
    window.state.set(noise=50.0)
    qtbot.waitUntil(lambda: bool(seen), timeout=60_000)
    note = window.notifier.last
    assert "the preview on screen is not exported" in note.message
    assert "exported the last full result" in note.message and "noise" not in note.message.split("result:")[1]
    assert "NR" in note.message.split("result:")[1]
    assert np.array_equal(core.io.read_cloud(seen[0]).points, kept.points)
    window.cancel()


# -- 4 ---------------------------------------------------------------------------------
def test_a_new_cloud_or_result_clears_an_older_message(make_window, qtbot, torus):
    window = make_window(torus, k_auto=False)
    window.notifier.error("The estimate failed: something about the old cloud")
    assert "old cloud" in window.status_bar.currentMessage()
    with wait_result(qtbot, window, 30_000):
        window.set_source(make_shape("sphere", 500))
    assert window.status_bar.currentMessage() == "" and window.status_label.isVisible()
    assert "old cloud" in window.notifier.history[-1].message  # kept in the history
    window.notifier.warning("about the previous estimate")
    with wait_result(qtbot, window, 30_000):
        window.state.set(k=14)
    assert window.status_bar.currentMessage() == ""


# -- 5 ---------------------------------------------------------------------------------
def test_a_cloud_that_was_not_estimated_says_so(make_window, qtbot):
    window = make_window(_identical())
    why = window.output.result.params["degenerate"]
    text = window.status_label.text()
    assert f"no estimate: {why}" in text
    assert "median" not in text and "passes" not in text and "-1" not in text
    caption = _caption(window)
    assert "no estimate" in caption and "passes" not in caption
    window.field_panel.combo.setCurrentIndex(window.field_panel.combo.findData("k_point"))
    assert window.shown["field"] == "k_point" and min(window.shown["clim"]) >= 0
    assert np.isnan(window.scene._values).all()


# -- 6 ---------------------------------------------------------------------------------
@pytest.mark.parametrize("scale, typed", [(1e-6, -1e8), (1e5, -1e-8)])
def test_limit_boxes_hold_any_finite_limit(make_window, qtbot, scale, typed):
    s = core.shapes.sphere(1500, seed=0)
    src = CloudSource(name="sphere", points=np.array(s.points) * scale, normals=np.array(s.normals))
    window = make_window(src)
    panel = window.field_panel
    panel.combo.setCurrentIndex(panel.combo.findData("gaussian"))
    lo, hi = window.shown["clim"]
    assert panel.lo.value() == pytest.approx(lo, rel=1e-9) and panel.hi.value() == pytest.approx(hi, rel=1e-9)
    assert float(panel.hi.text()) == pytest.approx(hi, rel=1e-4)  # displayed, not rounded to 0 or clamped
    panel.lo.setValue(typed)
    assert window.shown["clim"] == pytest.approx((typed, hi), rel=1e-9)
    panel.lo.lineEdit().setText(f"{2 * typed:g}")
    panel.lo.interpretText()
    assert window.shown["clim"] == pytest.approx((2 * typed, hi), rel=1e-9)
    panel.hi.interpretText()  # leaving the other box untouched does not round its value
    assert window.shown["clim"][1] == hi


# -- 7 ---------------------------------------------------------------------------------
def test_a_huge_coordinate_frames_the_ordinary_points(make_window, qtbot):
    rng = np.random.default_rng(0)
    p = rng.normal(size=(500, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    p[0] = [1e300, 0, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        geometry = CloudSource(name="huge", points=p).geometry
    assert np.isfinite(geometry.radius) and np.all(np.isfinite(geometry.centre)) and 0 not in geometry.order
    window = make_window(CloudSource(name="huge", points=p))
    window.render_all()
    qtbot.wait(100)
    cam = window.plotter.renderer.GetActiveCamera()
    assert np.isfinite(cam.GetPosition()).all() and np.isfinite(cam.GetFocalPoint()).all()
    x, y = window.scene.display_coords(np.arange(1, 500))
    width, height = window.plotter.render_window.GetSize()
    inside = np.isfinite(x) & np.isfinite(y) & (x >= 0) & (x < width) & (y >= 0) & (y < height)
    assert inside.sum() > 450
    assert "no estimate" in window.status_label.text()


# -- 8 ---------------------------------------------------------------------------------
def _nan_file(tmp_path):
    rng = np.random.default_rng(0)
    p = rng.normal(size=(500, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    p[::7] = np.nan
    path = tmp_path / "scan_with_gaps.xyz"
    np.savetxt(path, p)
    return path


def test_a_file_with_nan_rows_loads_without_them_and_says_so(make_window, qtbot, tmp_path):
    path = _nan_file(tmp_path)
    window = make_window()
    with wait_result(qtbot, window, 60_000) as blocker:
        window.open_file(path)
    assert blocker.args[0].request.source.n_points == 500 - 72
    assert any("dropped 72 of 500" in n.message and n.level == "warning" for n in window.notifier.history)
    assert "dropped 72 of 500" in window.status_bar.currentMessage()  # not hidden by the cloud's first result


def test_load_file_keeps_only_the_file_s_warnings(tmp_path, monkeypatch):
    import core.io

    path = _nan_file(tmp_path)
    read = core.io.read_cloud

    def noisy(p, **kwargs):
        warnings.warn("something else entirely", UserWarning)
        return read(p, **kwargs)

    monkeypatch.setattr(core.io, "read_cloud", noisy)
    with pytest.warns(UserWarning, match="something else entirely"):
        src = load_file(path)
    assert len(src.notes) == 1 and "dropped 72 of 500" in src.notes[0]


# -- 10 / 11 -----------------------------------------------------------------------------
def _legend_boxes(window):
    ren = window.plotter.renderer
    boxes = {}
    for kind in ("e1", "e2", "normals"):
        actor = window.plotter.actors[f"glyph-legend-{kind}"]
        bb = [0.0] * 4
        actor.GetBoundingBox(ren, bb)
        ax, ay = actor.GetPositionCoordinate().GetComputedDisplayValue(ren)
        boxes[kind] = (ax + bb[0], ax + bb[1], ay + bb[2], ay + bb[3])
    return boxes


@pytest.mark.parametrize("size", [(1200, 800), (1800, 900)])
def test_glyph_legend_is_not_drawn_over_the_colour_bar(make_window, qtbot, torus, size):
    window = make_window(torus, size=size)
    window.state.set(show_e1=True, show_e2=True, show_normals=True)
    window.render_all()
    qtbot.wait(200)
    ren = window.plotter.renderer
    bx0 = window.scene._bar.GetPositionCoordinate().GetComputedDisplayValue(ren)
    bx1 = window.scene._bar.GetPosition2Coordinate().GetComputedDisplayValue(ren)
    title_top = bx1[1] + 24  # the bar's title sits above it
    for kind, (x0, x1, y0, y1) in _legend_boxes(window).items():
        assert not (x1 > bx0[0] and x0 < bx1[0] and y0 < title_top and y1 > bx0[1] - 14), (kind, size)


def test_switching_to_the_log_field_gives_no_vtk_warning(make_window, qtbot, torus):
    import pyvista as pv

    window = make_window(torus)
    assert window.shown["clim"][0] < 0
    with pv.VtkErrorCatcher(raise_errors=False, emit_warnings=False) as catcher:
        window.field_panel.combo.setCurrentIndex(window.field_panel.combo.findData("k_point"))
        window.field_panel.combo.setCurrentIndex(window.field_panel.combo.findData("mean"))
        window.field_panel.combo.setCurrentIndex(window.field_panel.combo.findData("k_point"))
        window.scene.render()
    assert not [e for e in catcher.events if "log scale" in str(e)]
    assert window.scene._lut.log_scale


def test_the_compare_view_shows_the_whole_cloud(make_window, qtbot):
    """The two views share one camera; the splitter leaves them different widths, and a fit
    computed in the wider one cut the cloud off in the narrower (13 % of a torus outside it)."""
    from app import framing

    window = make_window(make_shape("torus", 3000), size=(1200, 800))
    with wait_result(qtbot, window, 30_000):
        window.compare_combo.setCurrentIndex(window.compare_combo.findData("ct"))
    qtbot.wait(300)  # the refit after the layout (a 0 ms timer)
    window.plotter.render()
    window.compare.plotter.render()
    widths = []
    for plotter in (window.plotter, window.compare.plotter):
        x, y, _ = framing.projection(plotter.renderer, window.output.points)
        width, height = plotter.render_window.GetSize()
        widths.append(width)
        assert np.mean((x < 0) | (x >= width) | (y < 0) | (y >= height)) == 0.0
    assert widths[0] != widths[1]  # the case that failed: views of different widths


def test_a_long_status_line_ends_in_an_ellipsis_with_the_whole_line_as_tooltip(make_window, qtbot, torus):
    """At 900 px the status line was cut off mid-word, before the reason; it also must not
    widen the window."""
    window = make_window(torus, size=(900, 700))
    label = window.status_label
    label.setText(label.text() + " · " + "a long reason that does not fit in the status bar " * 4)
    qtbot.wait(50)
    shown = label.elided()
    assert shown.endswith("…") and len(shown) < len(label.text()), (shown, label.width())
    assert label.toolTip() == label.text()
    assert window.width() <= 900
