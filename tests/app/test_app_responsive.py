"""Issue 11 / 10 behaviours of the viewer: request, preview, cancel, close, names, settings, LOD."""

from __future__ import annotations

import gc
import os
import weakref

import numpy as np
import pytest
from app_testutils import hold_first_estimate, wait_result
from PySide6.QtCore import QCoreApplication, QEvent, QSettings

from app.source import make_shape


def test_request_is_built_from_the_state_keys():
    from app.request import ESTIMATE_KEYS, EstimateRequest
    from app.state import ViewerState

    assert ESTIMATE_KEYS == {"source", "k", "k_auto", "method", "passes", "noise", "use_input_normals",
                             "compare_method", "orientation"}
    assert ESTIMATE_KEYS <= set(ViewerState.FIELDS)
    torus = make_shape("torus", 300)
    state = ViewerState(source=torus, k=22, k_auto=False, method="ct", noise=5.0)
    req = EstimateRequest.from_state(state, gen=7)
    assert (req.gen, req.source, req.k, req.k_auto, req.method, req.noise) == (7, torus, 22, False, "ct", 5.0)
    assert req.k_for("ct") == 22 and req.k_needed(300) == 22
    auto = EstimateRequest.from_state(ViewerState(source=torus), gen=1)
    assert auto.k_for("nr") == "auto" and auto.k_for("ct") == auto.k and auto.k_needed(300) > 22
    with pytest.raises(Exception):
        req.k = 3  # frozen


def test_preview_comes_first_then_the_full_result(make_window, qtbot, monkeypatch):
    import app.preview

    monkeypatch.setattr(app.preview, "PREVIEW_POINTS", 800)
    monkeypatch.setattr(app.preview, "PREVIEW_AUTO_MIN", 800)
    cloud = make_shape("torus", 3000)
    window = make_window(cloud, timeout=60_000)
    seen = []
    window.preview_shown.connect(lambda out: seen.append(("preview", out, window.status_label.text())))
    window.result_shown.connect(lambda out: seen.append(("final", out, window.status_label.text())))
    with wait_result(qtbot, window, 60_000):
        window.state.set(passes=2)
    assert [s[0] for s in seen] == ["preview", "final"]
    preview, final = seen[0][1], seen[1][1]
    assert preview.preview == 800 and preview.gen == final.gen and final.preview == 0
    assert len(preview.fields["mean"]) == 3000 and np.isfinite(preview.fields["mean"]).mean() > 0.9
    assert "PREVIEW" in seen[0][2] and "PREVIEW" not in seen[1][2]
    # the preview is the paper's k = 15 pipeline; the full result is automatic k
    assert preview.result.k == 15 and final.result.k == "auto"
    # a torus of major radius 2, minor 1: H is near the truth even on the preview
    truth = 0.5 * (cloud.sample.k1 + cloud.sample.k2)
    assert np.nanmedian(np.abs(preview.fields["mean"] - truth)) < 0.15
    assert window.output is final and final.reused_neighbours  # passes only: neighbours kept
    # ... and the initial normals, their orientation and the chosen k (core.stage_cache)
    assert {"initial", "orientation", "scale"} <= set(final.reused_stages)
    assert "initial normals, orientation, chosen k re-used" in window.status_label.text()


def test_border_flags_are_computed_on_the_job_thread(make_window, qtbot, monkeypatch):
    """An integer k's border flags are computed on first use where its graph is narrower
    than the test's 60 (core.CurvatureResult.border: a search of their own, 0.26 s per 100k
    points; the viewer searches 32 at k = 15); the worker computes them, so the GUI thread
    that greys them does not wait."""
    import threading

    import core.result

    seen = []
    real = core.result.border_of_valid

    def recorded(*args):
        seen.append(threading.current_thread())
        return real(*args)

    monkeypatch.setattr(core.result, "border_of_valid", recorded)
    window = make_window(make_shape("torus", 2000), timeout=60_000, k_auto=False, k=15)  # a graph of 32: lazy
    assert window.output.result.k == 15 and seen
    assert threading.main_thread() not in seen


def test_cancel_idles_at_once_and_a_cancelled_first_estimate_stays_usable(make_window, qtbot, monkeypatch):
    release, held = hold_first_estimate(monkeypatch)
    big = make_shape("sphere", 20000)
    window = make_window(big, wait=False)
    qtbot.waitUntil(lambda: window.estimator.busy, timeout=10_000)
    qtbot.wait(300)
    qtbot.waitUntil(lambda: bool(held), timeout=10_000)  # inside the estimate
    window.progress.cancel.click()
    assert not window.estimator.busy and held == ["running"]  # idle without waiting for the job
    release.set()
    assert not window.progress.shown
    assert "not estimated" in window.status_label.text()
    assert window.output is None
    # usable: estimate again gives a result for the same cloud
    window.state.set(k_auto=False, k=12)
    with wait_result(qtbot, window, 60_000) as blocker:
        pass
    assert blocker.args[0].request.source is big


def test_a_new_result_renders_the_3d_view_once_in_a_turn_of_its_own(make_window, qtbot, torus):
    """Swapping a result in, rendering it and drawing its histogram are three turns of the
    event loop, and the 3D view renders once (issue 11, GUI stall)."""
    window = make_window(torus, k_auto=False)
    qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=10_000)
    frames, at_result = [], []
    tag = window.plotter.render_window.AddObserver(
        "EndEvent", lambda *_a: frames.append(window.histogram.draw_pending))
    window.result_shown.connect(lambda _out: at_result.append(len(frames)))
    try:
        with wait_result(qtbot, window):
            window.state.set(k=18)
        qtbot.waitUntil(lambda: bool(frames) and not window.histogram.draw_pending, timeout=10_000)
        qtbot.wait(300)  # nothing else is on its way
    finally:
        window.plotter.render_window.RemoveObserver(tag)
    assert at_result == [0]  # the result is swapped in; the frame is a later turn
    assert frames == [True]  # one frame, rendered before the histogram's draw


def test_new_cloud_clears_the_old_histogram_and_colour_bar(make_window, qtbot, torus):
    window = make_window(torus)
    assert window.histogram.counts.sum() > 0 and window.scene._bar.GetVisibility()
    window.set_source(make_shape("sphere", 20000))
    assert window.histogram.counts.sum() == 0 and not window.scene._bar.GetVisibility()
    window.estimator.cancel()


def test_file_name_that_is_not_utf8(make_window, qtbot, tmp_path):
    raw = os.fsencode(str(tmp_path)) + b"/caf\xe9-\xff.xyz"
    with open(raw, "wb") as f:
        np.savetxt(f, make_shape("sphere", 300).points)
    window = make_window()
    with wait_result(qtbot, window, 60_000) as blocker:
        window.open_file(raw)
    name = blocker.args[0].request.source.name
    assert name == "caf\ufffd-\ufffd.xyz"
    assert name in window.windowTitle() and name in window.status_label.text()
    name.encode("utf-8")  # no lone surrogates anywhere near Qt or VTK
    with wait_result(qtbot, window, 60_000):
        window.open_file(os.fsdecode(raw))  # the str form (surrogate escapes) too


def test_settings_round_trip(make_window, qtbot, torus, settings):
    from app.persist import restore_layout, restore_state
    from app.state import ViewerState

    window = make_window(torus, size=(900, 600))
    window.state.set(method="ct", field="gaussian", k=23, k_auto=False, passes=2)
    window.histogram_dock.hide()
    window.close()
    state = ViewerState()
    applied = restore_state(state, settings)
    assert applied == {"method": "ct", "field": "gaussian", "k": 23, "k_auto": False, "passes": 2}
    assert (state.method, state.field, state.k, state.k_auto, state.passes) == ("ct", "gaussian", 23, False, 2)
    assert restore_state(ViewerState(), settings, skip={"method"}).keys() == applied.keys() - {"method"}
    again = make_window(size=(900, 600))
    assert restore_layout(again, settings) and again.histogram_dock.isHidden()
    # a corrupt entry is ignored, not applied
    settings.setValue("viewer/k", "banana")
    settings.setValue("viewer/method", "nope")
    assert "k" not in restore_state(ViewerState(), settings) and "method" not in restore_state(ViewerState(), settings)


def test_level_of_detail_while_the_camera_moves(make_window, qtbot, torus):
    window = make_window(size=(640, 480))
    scene = window.scene
    scene.lod.limit = 500  # the real limit is LOD_POINTS; a small cloud keeps the test fast
    with wait_result(qtbot, window, 60_000):
        window.set_source(torus)
        # a new big cloud shows its stand-in (cheap to draw) until the result is in
        assert scene.lod.active and scene.lod.held and not scene._actor.GetVisibility()
    assert len(scene.lod.index) == 500 and not scene.lod.active and scene._actor.GetVisibility()
    lod_values = scene.lod._mesh.point_data["values"]
    shown = np.where(window.output.result.border, np.nan, window.output.fields["mean"])  # border points are grey
    assert np.allclose(lod_values, shown[scene.lod.index], equal_nan=True)
    style = window.plotter.iren.interactor.GetInteractorStyle()
    style.InvokeEvent("StartInteractionEvent")  # what a drag starts with
    assert scene.lod.active and not scene._actor.GetVisibility() and scene.lod._actor.GetVisibility()
    style.InvokeEvent("EndInteractionEvent")
    assert not scene.lod.active and scene._actor.GetVisibility() and not scene.lod._actor.GetVisibility()


def test_fit_view_eye_dome_and_dark_palette(make_window, qtbot, torus, qapp):
    from PySide6.QtGui import QColor, QPalette

    window = make_window(torus, size=(640, 480))
    cam = window.plotter.camera
    focal, fitted = np.array(cam.focal_point), np.array(cam.position)
    cam.position = tuple(focal + 20.0 * (fitted - focal))  # walked far away
    direction = (fitted - focal) / np.linalg.norm(fitted - focal)
    window.fit_view()  # F
    now = np.array(cam.position) - np.array(cam.focal_point)
    assert np.linalg.norm(now) < 2.0 * np.linalg.norm(fitted - focal)
    assert np.allclose(now / np.linalg.norm(now), direction, atol=1e-6)  # same direction
    window.state.set(eye_dome=True)
    assert window.eye_dome_action.isChecked() and window.plotter.renderer.GetPass() is not None
    window.state.set(eye_dome=False)
    assert window.plotter.renderer.GetPass() is None
    old = qapp.palette()
    dark = QPalette(old)
    dark.setColor(QPalette.ColorRole.Window, QColor("#202020"))
    qapp.setPalette(dark)
    try:
        window.apply_theme()
        assert np.mean(window.plotter.background_color.float_rgb) < 0.3
        assert np.mean(window.histogram.figure.get_facecolor()[:3]) < 0.3
    finally:
        qapp.setPalette(old)
    window.apply_theme()
    assert np.mean(window.plotter.background_color.float_rgb) > 0.9


def test_closed_windows_are_freed(qtbot, settings):
    """Open/close cycles free their windows (issue 10: 583 -> 2406 MB over 50 cycles)."""
    from app.estimator import Estimator
    from app.state import ViewerState
    from app.window import MainWindow

    tiny = make_shape("torus", 300)
    refs, rss = [], []
    for _ in range(4):
        window = MainWindow(state=ViewerState(), settings=settings, dialogs=False)
        window.resize(480, 360)
        window.show()
        with wait_result(qtbot, window, 60_000):
            window.set_source(tiny)
        window.close()
        window.deleteLater()
        refs.append(weakref.ref(window))
        del window
        for _ in range(3):
            QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
            QCoreApplication.processEvents()
        gc.collect()
        with open(f"/proc/{os.getpid()}/statm") as f:
            rss.append(int(f.read().split()[1]) * 4096 / 2**20)
    assert all(r() is None for r in refs), "a closed window is still referenced"
    assert rss[-1] - rss[1] < 40, rss  # MB over the last three cycles
    qtbot.waitUntil(lambda: not Estimator.running_threads(), timeout=10_000)


def test_a_closed_window_pins_the_wrappers_qt_will_delete(make_window):
    """Closing pins every wrapper created from Python under the window (app._refguard.pinned_children):
    PySide's own record of parents alone held the controls' group boxes, and Qt's deletion of the
    tree freed one inside Shiboken's destroy (a segfault in the tests' teardown)."""
    import shiboken6
    from PySide6.QtCore import QObject
    from PySide6.QtWidgets import QGroupBox

    window = make_window()
    assert {b.title() for b in window.findChildren(QGroupBox)} >= {"Estimate", "Colour", "Glyphs"}
    window.close()
    pinned = {id(o) for o in window._pinned}
    made = [o for o in window.findChildren(QObject) if shiboken6.createdByPython(o)]
    assert made and all(id(o) in pinned for o in made)


def test_compile_watch_reports_a_numba_compile(qtbot):
    """The status bar's "compiling kernels" comes from numba's compile event."""
    from numba import njit

    from app.compiling import CompileWatch

    watch = CompileWatch()
    try:
        @njit
        def fresh(x):  # never cached: compiled on its first call
            return x + 1

        with qtbot.waitSignal(watch.started, timeout=30_000):
            assert fresh(1) == 2
        fired = []
        watch.started.connect(lambda: fired.append(1))
        assert fresh(2) == 3  # compiled already: no event
        assert not fired
    finally:
        watch.close()
