"""Round 3: dragging the camera with the compare view on (item 1 of the brief).

The two views share one camera, so a drag in either repaints both; only the view dragged
switched to its level-of-detail stand-in (app/lod.py), the other drew a still frame of
spheres at every step. And the dragged view drew every step twice: pyvistaqt's widget
renders in its paint, and the interactor's render also scheduled that paint (app/plotter.py).
"""

from __future__ import annotations

import time

import numpy as np
from app_testutils import GuiBeat, full_frames_cpu, wait_result
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt, QTimer
from PySide6.QtGui import QMouseEvent, QWheelEvent
from PySide6.QtWidgets import QApplication

from app.source import make_shape


class _Drag:
    """A left-button drag across ``view``, one step every ``interval`` ms from a timer (as a
    user's mouse comes), with a heartbeat (:class:`GuiBeat`) and every frame of both views
    recorded as (view, seconds, main stand-in on, compare stand-in on)."""

    def __init__(self, window, view, steps: int = 24, interval: int = 30):
        self.window, self.view, self.steps, self.step = window, view, steps, 0
        self.frames, self.beat, self._started, self._tags = [], GuiBeat(), {}, []
        for name, plotter in (("main", window.plotter), ("compare", window.compare.plotter)):
            rw = plotter.render_window
            self._tags += [(rw, rw.AddObserver("StartEvent", lambda *_a, n=name: self._start(n))),
                           (rw, rw.AddObserver("EndEvent", lambda *_a, n=name: self._end(n)))]
        self.mover = QTimer()
        self.mover.setInterval(interval)
        self.mover.timeout.connect(self._move)
        self.centre = QPointF(view.width() / 2, view.height() / 2)

    def _start(self, name):
        self._started[name] = time.perf_counter()

    def _end(self, name):
        lods = (self.window.scene.lod.active, self.window.compare.scene.lod.active)
        self.frames.append((name, time.perf_counter() - self._started[name], *lods))

    def _send(self, kind, step, buttons):
        pos = QPointF(self.centre.x() + 5 * step, self.centre.y() + step)
        event = QMouseEvent(kind, pos, self.view.mapToGlobal(pos), Qt.MouseButton.LeftButton, buttons,
                            Qt.KeyboardModifier.NoModifier)
        QApplication.sendEvent(self.view, event)

    def _move(self):
        self.step += 1
        self._send(QEvent.Type.MouseMove, self.step, Qt.MouseButton.LeftButton)
        if self.step >= self.steps:
            self.mover.stop()

    def run(self, qtbot):
        self.beat.start()
        try:
            self._send(QEvent.Type.MouseButtonPress, 0, Qt.MouseButton.LeftButton)
            self.mover.start()
            qtbot.waitUntil(lambda: not self.mover.isActive(), timeout=60_000)
            qtbot.wait(100)  # the last step's frames
            self.moving = list(self.frames)
            self._send(QEvent.Type.MouseButtonRelease, self.step, Qt.MouseButton.NoButton)
            qtbot.wait(600)
        finally:
            self.beat.stop()
        for rw, tag in self._tags:
            rw.RemoveObserver(tag)
        return self

    def frame_times(self, name) -> np.ndarray:
        return np.array([f[1] for f in self.moving if f[0] == name])


def _compare_window(make_window, qtbot, n):
    window = make_window(size=(1440, 900), compare_method="ct", timeout=240_000)
    with wait_result(qtbot, window, 240_000):
        window.set_source(make_shape("torus", n))
    qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=20_000)
    qtbot.wait(500)
    assert window.compare.isVisible()
    return window


def test_dragging_either_view_shows_both_stand_ins_and_draws_each_step_once(make_window, qtbot):
    """200k points, compare on. Old code: the compare view drew a still frame of 50k spheres
    at every step (median 0.045-0.07 s against 0.02-0.03 s for the stand-in, this 2-core VM
    under load 4) and the dragged view rendered each step twice. Nothing but frames holds the
    GUI thread: no turn of the event loop, the release's two full frames included, takes
    more of its CPU than three full frames of both views measured after the drag and 0.05 s
    (a turn's own work, whatever the GL driver leaves on the thread); a wall-time bound of
    0.6 s failed at load 5-7 on a 2-core machine. Measured: 0.022-0.028 s against frames of
    0.018 s; a 0.1 s CPU block at each step: 0.129 s."""
    window = _compare_window(make_window, qtbot, 200_000)
    for view in (window.plotter, window.compare.plotter):
        drag = _Drag(window, view).run(qtbot)
        assert drag.moving, "no frame while dragging"
        # every frame while the camera moves draws the stand-ins, in both views
        assert all(main and compare for _name, _t, main, compare in drag.moving), drag.moving
        counts = {name: sum(f[0] == name for f in drag.moving) for name in ("main", "compare")}
        assert 0 < counts["main"] <= drag.steps + 1 and 0 < counts["compare"] <= drag.steps + 1, counts
        print(f"\ndrag in the {'main' if view is window.plotter else 'compare'} view: {drag.steps} steps, "
              f"frames {counts}, median main {np.median(drag.frame_times('main')):.3f} s, "
              f"compare {np.median(drag.frame_times('compare')):.3f} s")
        # released: both views back to their full clouds
        assert not window.scene.lod.active and not window.compare.scene.lod.active
        frames = full_frames_cpu((window.plotter, window.compare.plotter))
        print(f"longest block {drag.beat.longest_block():.3f} s CPU, full frames {frames:.3f} s CPU")
        assert drag.beat.longest_block() < 3 * frames + 0.05, (drag.beat.longest_block(), frames)
        assert window.scene._actor.GetVisibility() and window.compare.scene._actor.GetVisibility()


def test_the_compare_view_stand_in_follows_a_drag_without_leaking_observers(make_window, qtbot):
    """The stand-ins follow each other's interactor style; closing the compare view's scene
    removes its observers from the main view's style (and the other way round)."""
    window = _compare_window(make_window, qtbot, 3000)
    for scene in (window.scene, window.compare.scene):
        scene.lod.limit = 500
    window.set_source(make_shape("sphere", 3000))
    qtbot.waitUntil(lambda: window.output is not None and window.output.request.source.name.startswith("sphere")
                    and not window.estimator.busy, timeout=60_000)
    qtbot.waitUntil(lambda: not window.scene.lod.held, timeout=10_000)
    main_style = window.plotter.iren.interactor.GetInteractorStyle()
    compare_style = window.compare.plotter.iren.interactor.GetInteractorStyle()
    for style in (main_style, compare_style):
        style.InvokeEvent("StartInteractionEvent")
        assert window.scene.lod.active and window.compare.scene.lod.active
        assert not window.compare.scene._actor.GetVisibility()
        style.InvokeEvent("EndInteractionEvent")
        assert not window.scene.lod.active and not window.compare.scene.lod.active
        assert window.compare.scene._actor.GetVisibility()
    window.compare.scene.lod.close()
    main_style.InvokeEvent("StartInteractionEvent")  # nothing of the closed stand-in answers
    main_style.InvokeEvent("EndInteractionEvent")


def test_a_zoom_in_the_compare_view_details_both_views_alike(make_window, qtbot):
    """Wheel zoom in the compare view. Old code: the main view kept its uniform subset of the
    whole cloud (its zoom detail never ran: 1 point in 4 of the region in view drawn) and its
    sprites were half the compare view's (the compare view never fits, so its sprites had no
    cap): the two halves of the figure looked unlike (screenshot /tmp/v/wheel_compare_old.png)."""
    window = _compare_window(make_window, qtbot, 20_000)
    scenes = (window.scene, window.compare.scene)
    for scene in scenes:
        scene.set_budget(5_000)  # (the real budget is 50k a view; a small cloud keeps the test fast)
    view = window.compare.plotter
    pos = QPointF(view.width() / 2, view.height() / 2)
    for _ in range(6):
        QApplication.sendEvent(view, QWheelEvent(pos, view.mapToGlobal(pos), QPoint(0, 0), QPoint(0, 120),
                                                 Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier,
                                                 Qt.ScrollPhase.NoScrollPhase, False))
        qtbot.wait(30)
    qtbot.waitUntil(lambda: all(scene._visible < 20_000 for scene in scenes), timeout=10_000)
    qtbot.waitUntil(lambda: not window._frame_due, timeout=10_000)
    qtbot.wait(300)
    for plotter in (window.plotter, view):
        plotter.render()
    visible = [scene._visible for scene in scenes]
    assert abs(visible[0] - visible[1]) < 0.05 * max(visible), visible
    sizes = [scene.sprite_size for scene in scenes]
    assert abs(sizes[0] - sizes[1]) < 0.05 * max(sizes), sizes
