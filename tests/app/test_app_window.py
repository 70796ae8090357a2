"""The viewer window: estimate on the worker, sliders, picking, files, closing."""

from __future__ import annotations

import numpy as np
import pytest
from app_testutils import colour_stats, hold_first_estimate, image_array, wait_result
from PySide6.QtCore import QMimeData, QPoint, QPointF, Qt, QUrl
from PySide6.QtGui import QDropEvent
from PySide6.QtTest import QTest

from app.source import make_shape


def test_default_bunny_shows_mean_curvature_colormap(make_window, qtbot):
    """With no file the bundled scan opens and its mean curvature is shown at once."""
    window = make_window()
    with wait_result(qtbot, window, 120_000) as blocker:
        assert window.open_default()
    out = blocker.args[0]
    assert out.request.source.name == "bunny.ply"
    assert len(out.points) == 28088
    assert window.shown["field"] == "mean"
    assert window.shown["cmap"] == "RdBu_r"  # signed field: diverging, centred on 0
    lo, hi = window.shown["clim"]
    assert lo == pytest.approx(-hi) and hi > 0
    assert window.scene._bar.GetTitle() == "Mean curvature H"
    assert window.histogram.counts.sum() > 0.9 * 28088

    stats = colour_stats(image_array(window.plotter.grab().toImage()))
    assert stats["foreground"] > 0.08, stats  # not blank
    assert stats["unique"] > 150, stats  # not uniform
    assert stats["coloured"] > 0.2, stats  # the colormap shows (not all grey NaN)


def test_slider_reestimates_and_reuses_neighbours(make_window, qtbot, torus):
    window = make_window(torus, k_auto=False)
    first = window.output
    with wait_result(qtbot, window, 30_000) as blocker:
        window.k_slider.slider.setValue(20)
    out = blocker.args[0]
    assert out.request.k == 20 and out.result.k == 20
    assert out.gen > first.gen
    assert out.reused_neighbours  # k <= k_max: the neighbour graph is not rebuilt
    with wait_result(qtbot, window, 30_000) as blocker:
        window.method_combo.setCurrentIndex(window.method_combo.findData("ct"))
    assert blocker.args[0].result.method == "ct" and blocker.args[0].reused_neighbours
    assert not window.passes_slider.isEnabled()  # CT has no refinement passes


def test_burst_of_slider_moves_makes_one_request(make_window, qtbot, torus):
    window = make_window(torus, k_auto=False)
    gen = window.estimator.generation
    with wait_result(qtbot, window, 30_000) as blocker:
        for k in (16, 17, 18, 19, 21):
            window.k_slider.slider.setValue(k)
    assert window.estimator.generation == gen + 1  # debounced
    assert blocker.args[0].result.k == 21


def test_stale_result_is_dropped(make_window, qtbot, torus):
    window = make_window(torus)
    dropped, cancelled = [], []
    window.estimator.dropped.connect(dropped.append)
    window.estimator.cancelled.connect(cancelled.append)
    with wait_result(qtbot, window, 30_000) as blocker:
        old = window.estimator.submit(torus, k=10)
        new = window.estimator.submit(torus, k=12)  # k_auto is off in a bare request
    assert blocker.args[0].gen == new.gen and blocker.args[0].result.k == 12
    qtbot.waitUntil(lambda: not window.estimator.busy, timeout=30_000)
    assert old.gen in dropped + cancelled  # skipped, cancelled mid-run or dropped on arrival
    assert window.output.gen == new.gen

    # a result that arrives after a newer request was made is never shown
    stale = window.output
    newest = window.estimator.submit(torus, k=14)
    shown = []
    window.result_shown.connect(shown.append)
    window.estimator._on_finished(stale)  # what a late delivery looks like
    assert stale.gen in dropped and not shown
    qtbot.waitUntil(lambda: window.output.gen == newest.gen, timeout=30_000)


def test_running_job_is_cancelled_through_core_callback(torus):
    """The worker answers False to core's progress callback once its job is stale."""
    from app.request import EstimateRequest
    from app.worker import EstimateWorker

    worker = EstimateWorker()
    req = EstimateRequest(gen=1, source=torus, k=12)
    worker.latest = 1
    events = []
    worker.cancelled.connect(lambda g: events.append(("cancelled", g)))
    worker.finished.connect(lambda o: events.append(("finished", o.gen)))
    worker.progress.connect(lambda g, f, s: setattr(worker, "latest", 2))  # a newer request came in
    worker.run(req)
    assert events == [("cancelled", 1)]
    worker.deleteLater()


def test_cancel_button_keeps_the_shown_result(make_window, qtbot, torus):
    window = make_window(torus)
    shown = window.output
    window.estimator.submit(torus, k=25)
    window.progress.cancel.click()
    qtbot.waitUntil(lambda: not window.estimator.busy, timeout=30_000)
    assert window.output is shown


def _click_point(window, qtbot, index):
    x, y = window.scene.display_coords(index)
    dpr = window.plotter.devicePixelRatioF()
    pos = QPoint(int(round(x[0] / dpr)), int(round(window.plotter.height() - 1 - y[0] / dpr)))
    QTest.mouseClick(window.plotter, Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, pos)
    return pos


def test_picking_fills_the_panel_and_highlights(make_window, qtbot, torus):
    window = make_window(torus)
    window.render_all()
    # a point the camera sees (front-most at its own pixel)
    x, y = window.scene.display_coords(np.arange(len(torus.points)))
    centre = np.array(window.plotter.render_window.GetSize()) / 2
    order = np.argsort((x - centre[0]) ** 2 + (y - centre[1]) ** 2)
    target = next(i for i in order[:400] if window.scene.pick(x[i], y[i]) == i)
    _click_point(window, qtbot, target)
    qtbot.waitUntil(lambda: window.state.picked is not None, timeout=5_000)
    assert window.state.picked == target
    values = window.inspector.values
    res = window.output.result
    assert values["index"] == f"{target:,}"
    assert values["k1"] == f"{res.k1[target]:+.5g}"
    for key in ("position", "normal", "e1", "e2", "gaussian", "mean", "shape_index", "true_k1"):
        assert key in values
    actors = window.plotter.actors
    assert {"pick-neighbours", "pick-point", "pick-frame-e1", "pick-frame-e2", "pick-frame-n"} <= set(actors)
    assert actors["pick-neighbours"].mapper.dataset.n_points == res.k_point[target]

    # a drag is a rotation, not a pick; Esc clears
    window.state.set(picked=None)
    assert window.inspector.values == {} and "pick-point" not in window.plotter.actors


def test_bad_file_shows_message_and_app_survives(make_window, qtbot, torus, tmp_path):
    window = make_window(torus)
    bad = tmp_path / "broken.ply"
    bad.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\nbanana\n")
    missing = tmp_path / "nope.xyz"
    unknown = tmp_path / "cloud.unknownext"
    unknown.write_text("1 2 3\n")
    for path in (bad, missing, unknown):
        before = len(window.notifier.history)
        assert window.open_file(path)  # read on the loader thread; the answer comes back as an error
        qtbot.waitUntil(lambda: len(window.notifier.history) > before, timeout=10_000)
        note = window.notifier.last
        assert len(window.notifier.history) == before + 1
        assert note.level == "error" and path.name in note.message
        assert path.name in window.status_bar.currentMessage()
        assert window.state.source is torus  # the current cloud stays loaded
    assert window.recent_menu.paths() == []
    # and the app keeps working
    with wait_result(qtbot, window, 30_000):
        window.k_slider.slider.setValue(18)


def test_estimate_failure_reaches_the_notifier(make_window, qtbot):
    tiny = make_shape("sphere", 40)
    window = make_window(tiny)
    shown = window.output
    with qtbot.waitSignal(window.estimator.failed, timeout=30_000):
        window.state.set(k=60, k_auto=False)  # more neighbours than points
    note = window.notifier.last
    assert note.level == "error" and "estimate failed" in note.message
    assert window.output is shown  # the last good result stays on screen
    with wait_result(qtbot, window, 30_000):
        window.state.set(k=12)


def test_noise_is_a_reproducible_copy(make_window, qtbot, torus):
    window = make_window(torus)
    with wait_result(qtbot, window, 30_000) as b1:
        window.noise_slider.slider.setValue(30)
    noisy = b1.args[0].points
    assert not np.allclose(noisy, torus.points)
    assert np.array_equal(torus.points, torus.sample.points)  # original untouched
    with wait_result(qtbot, window, 30_000) as b2:
        window.noise_slider.slider.setValue(0)
    assert np.array_equal(b2.args[0].points, torus.points)
    with wait_result(qtbot, window, 30_000) as b3:
        window.noise_slider.slider.setValue(30)
    assert np.array_equal(b3.args[0].points, noisy)  # same level, same cloud


def test_fields_errors_and_glyphs(make_window, qtbot, torus):
    window = make_window(torus)
    assert "err_mean" in window.output.fields
    window.field_panel.combo.setCurrentIndex(window.field_panel.combo.findData("err_gaussian"))
    assert window.shown["field"] == "err_gaussian"
    assert window.scene._bar.GetTitle() == "Error of K"
    assert "mean abs. error" in window.summary_label.text()
    # manual limits, then back to robust ones
    window.field_panel.hi.setValue(0.05)
    assert not window.state.clim_auto and window.shown["clim"][1] == pytest.approx(0.05)
    window.field_panel.auto.setChecked(True)
    assert window.shown["clim"][1] != pytest.approx(0.05)

    window.state.set(show_e1=True, show_normals=True, glyph_density=0.1)
    actors = window.plotter.actors
    assert "glyph-e1" in actors and "glyph-normals" in actors and "glyph-e2" not in actors
    lines = actors["glyph-e1"].mapper.dataset
    assert lines.n_cells == round(0.1 * len(torus.points))
    seg = lines.points[1] - lines.points[0]
    assert np.linalg.norm(seg) == pytest.approx(window.state.glyph_length * window.output.spacing, rel=1e-6)
    window.state.set(show_e1=False)
    assert "glyph-e1" not in window.plotter.actors


def test_compare_two_methods_with_linked_cameras(make_window, qtbot, torus):
    window = make_window(torus)
    with wait_result(qtbot, window, 30_000) as blocker:
        window.compare_combo.setCurrentIndex(window.compare_combo.findData("ct"))
    out = blocker.args[0]
    assert out.compare is not None and out.compare.method == "ct" and out.result.method == "nr"
    assert window.compare.isVisible()
    main_cam = window.plotter.renderer.GetActiveCamera()
    assert window.compare.plotter.renderer.GetActiveCamera() is main_cam
    main_cam.Azimuth(30)
    window.plotter.render()
    qtbot.wait(50)
    assert window.compare.plotter.renderer.GetActiveCamera().GetPosition() == main_cam.GetPosition()
    with wait_result(qtbot, window, 30_000):
        window.compare_combo.setCurrentIndex(0)  # Off
    assert not window.compare.isVisible()


def test_drop_recent_and_export(make_window, qtbot, torus, tmp_path):
    import core.io

    window = make_window(torus)
    exported = window.export_result(tmp_path / "torus.ply")
    assert exported is not None and exported.exists()
    csv = window.export_result(tmp_path / "torus.csv")
    assert csv is not None and csv.exists()
    again = core.io.read_cloud(exported)
    assert len(again.points) == len(torus.points)

    mime = QMimeData()
    mime.setUrls([QUrl.fromLocalFile(str(exported))])
    event = QDropEvent(QPointF(20, 20), Qt.DropAction.CopyAction, mime, Qt.MouseButton.LeftButton,
                       Qt.KeyboardModifier.NoModifier)
    with wait_result(qtbot, window, 30_000) as blocker:
        window.dropEvent(event)
    assert blocker.args[0].request.source.name == "torus.ply"
    assert window.recent_menu.paths()[0].endswith("torus.ply")

    shot = tmp_path / "view.png"
    assert window.save_screenshot(shot) and shot.stat().st_size > 1000


def test_closing_while_estimating_leaves_nothing_behind(make_window, qtbot, monkeypatch):
    """Closing does not wait for a job that reaches no cancel check: it returns with the job
    still running (abandoned on its thread, which the fixture sees end once let go)."""
    release, held = hold_first_estimate(monkeypatch)
    big = make_shape("sphere", 20000)
    window = make_window(big, wait=False)
    qtbot.waitUntil(lambda: window.estimator.busy and bool(held), timeout=10_000)
    window.close()  # the fixture checks threads and plotters
    assert held == ["running"]
    release.set()
    assert window.plotter._closed


def test_open_close_twenty_times(make_window, qtbot):
    tiny = make_shape("torus", 400)
    for i in range(20):
        window = make_window(tiny, wait=i % 2 == 0, timeout=30_000, size=(640, 480))
        window.close()
        assert window.plotter._closed


def test_toggling_controls_keeps_true_and_none_alive(make_window, qtbot, torus):
    """The PySide6 build in use drops a reference to True for every Python signal
    emitting True, and to None for every invalid QVariant read back (e.g. a None
    item datum): enough toggles and the interpreter aborts (bool_dealloc /
    none_dealloc). The viewer sends names, not values, through its signals and
    keeps None out of item data; this checks that a few hundred user actions do
    not bleed either singleton."""
    import sys

    window = make_window(torus, size=(640, 480))
    boxes = list(window.glyph_controls.boxes.values()) + [window.field_panel.auto]
    true_before, none_before = sys.getrefcount(True), sys.getrefcount(None)
    for _ in range(25):
        for box in boxes:
            box.setChecked(not box.isChecked())
        window.compare_combo.setCurrentIndex(1)
        window.compare_combo.setCurrentIndex(0)
    window._debounce.stop()
    qtbot.waitUntil(lambda: not window.estimator.busy, timeout=30_000)
    assert sys.getrefcount(True) > true_before - 25
    assert sys.getrefcount(None) > none_before - 25


def test_gui_stays_responsive_while_estimating(make_window, qtbot, monkeypatch):
    """The estimate runs on the worker: the GUI thread keeps serving timers."""
    import threading
    import time

    import app.worker

    from PySide6.QtCore import QTimer

    real, on = app.worker.core.estimate, []

    def recorded(*args, **kwargs):
        on.append(threading.current_thread())
        return real(*args, **kwargs)

    monkeypatch.setattr(app.worker.core, "estimate", recorded)
    big = make_shape("sphere", 30000)
    window = make_window(size=(640, 480))
    ticks = []
    timer = QTimer()
    timer.setInterval(20)
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start()
    try:
        with wait_result(qtbot, window, 120_000):
            window.set_source(big)
    finally:
        timer.stop()
    assert len(ticks) > 5 and on
    assert threading.main_thread() not in on


def test_automatic_k_is_the_default_and_can_be_turned_off(make_window, qtbot, torus):
    window = make_window(torus)
    assert window.state.k_auto and window.k_slider.slider.isEnabled()
    out = window.output
    assert out.result.k == "auto" and out.request.k_auto
    assert set(np.unique(out.result.k_point)) <= set(__import__("core").scale.JET_KS)  # candidates of the jet rule
    with wait_result(qtbot, window, 30_000) as blocker:
        window.k_slider.auto.setChecked(False)
    assert blocker.args[0].result.k == window.state.k and window.k_slider.slider.isEnabled()
    # moving the k slider while automatic k is on picks that fixed k
    window.state.set(k_auto=True)
    with wait_result(qtbot, window, 30_000) as blocker:
        window.k_slider.slider.setValue(21)
    assert not window.state.k_auto and blocker.args[0].result.k == 21
