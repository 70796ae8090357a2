"""Round 2: turning the compare view on must not stall the GUI thread (issue 1 of the brief).

The stall was up to 9 frames of 100k point sprites in 2-3 turns of the event loop (0.5-0.75 s
a gap at 200k points): Qt painted both views in the relayout, the camera link re-rendered
the other view with ``render()`` (VTK's render, then the paint it schedules: two frames), a
zoom-detail selection computed on another view's clipping range was applied with another
``render()``, and both views were repainted together after the refit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from app_testutils import wait_result
from PySide6.QtCore import QTimer

from app.source import make_shape

BUNNY = Path(__file__).resolve().parents[2] / "resources" / "bunny.ply"


class _Frames:
    """Every frame of the main and compare views, with the turn of the event loop it came in
    (a 0 ms timer counts the turns)."""

    def __init__(self, window):
        self.turn, self.frames = 0, []
        self.timer = QTimer()
        self.timer.setInterval(0)
        self.timer.timeout.connect(self._beat)
        self.window = window
        self.tags = [(window.plotter.render_window,
                      window.plotter.render_window.AddObserver("EndEvent", lambda *_a: self._frame("main")))]

    def _beat(self):
        self.turn += 1

    def _frame(self, view):
        self.frames.append((view, self.turn))

    def watch_compare(self):
        rw = self.window.compare.plotter.render_window
        self.tags.append((rw, rw.AddObserver("EndEvent", lambda *_a: self._frame("compare"))))

    def stop(self):
        self.timer.stop()
        for rw, tag in self.tags:
            rw.RemoveObserver(tag)


def _toggle_compare(window, qtbot, watch: _Frames, method="ct"):
    window.result_shown.connect(lambda _out: watch.watch_compare() if len(watch.tags) == 1 else None)
    watch.timer.start()
    with wait_result(qtbot, window, 120_000):
        window.compare_combo.setCurrentIndex(window.compare_combo.findData(method))
    qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=20_000)
    qtbot.wait(400)  # nothing else on its way
    watch.stop()


def test_compare_view_paints_one_view_a_turn_and_each_once(make_window, qtbot):
    """After the compare result is swapped in, each view renders once, never two frames in
    one turn of the event loop (old code: 4-7 frames, main and compare in the same turns)."""
    window = make_window(make_shape("torus", 3000), size=(1440, 900))
    qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=10_000)
    qtbot.wait(200)
    watch = _Frames(window)
    at_result = []
    window.result_shown.connect(lambda _out: at_result.append(len(watch.frames)))
    _toggle_compare(window, qtbot, watch)
    after = watch.frames[at_result[-1]:]
    turns = [turn for _view, turn in after]
    assert len(turns) == len(set(turns)), after  # one frame a turn
    assert sorted(view for view, _ in after) == ["compare", "main"], after  # each view once
    assert window.compare.isVisible()


def test_compare_view_with_200k_points_keeps_the_gui_responsive(make_window, qtbot):
    """The compare view comes on at 200k points one frame a turn of the event loop, each of
    half the still budget. Before: 2-3 turns held 9 frames of 100k sprites (a heartbeat gap
    of 0.69-1.76 s on this 2-core VM, 0.17-0.33 s after; a bound on that wall time failed
    on a loaded machine, the frames a turn do not depend on its load)."""
    window = make_window(make_shape("torus", 200_000), size=(1440, 900), timeout=240_000)
    qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=20_000)
    qtbot.wait(500)
    watch = _Frames(window)
    _toggle_compare(window, qtbot, watch)
    turns = [turn for _view, turn in watch.frames]
    assert turns and len(turns) == len(set(turns)), watch.frames  # one frame a turn
    from app.lod import STILL_POINTS

    assert {len(window.scene.drawn), len(window.compare.scene.drawn)} == {STILL_POINTS // 2}
    # and back: the one view draws the whole budget again
    with wait_result(qtbot, window, 120_000):
        window.compare_combo.setCurrentIndex(0)
    assert not window.compare.isVisible() and len(window.scene.drawn) == STILL_POINTS


def test_zoom_detail_reads_the_clipping_range_a_render_would_set(make_window, qtbot, torus):
    """The camera is shared with the compare view, whose renders reset its clipping range to
    their own props; a selection of the points in view made then saw 87k of 200k points in
    the frustum and drew only those (parts of the cloud left out until the camera moved)."""
    from app.detail import _clip_matrix, visible_subset

    window = make_window(torus)
    renderer = window.plotter.renderer
    renderer.GetActiveCamera().SetClippingRange(1e-3, 2e-3)  # another view's, or stale
    points, order = window.scene.points, window.scene.geometry.order
    _, n_visible = visible_subset(points, _clip_matrix(renderer), order, len(points))
    assert n_visible == len(points)


def test_compare_view_off_paints_the_widened_main_view_once(make_window, qtbot):
    """Hiding the compare view widens the main view: one frame after the result (old code: a
    frame in the relayout, with the old colours, and another for the new result)."""
    window = make_window(size=(1440, 900), compare_method="ct")
    with wait_result(qtbot, window, 120_000):
        window.open_file(BUNNY)
    qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=10_000)
    assert window.compare.isVisible()
    frames, at_result = [], []
    tag = window.plotter.render_window.AddObserver("EndEvent", lambda *_a: frames.append(1))
    window.result_shown.connect(lambda _out: at_result.append(len(frames)))  # (a preview's frame may come first)
    try:
        with wait_result(qtbot, window, 60_000):
            window.compare_combo.setCurrentIndex(0)
        qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=10_000)
        qtbot.wait(300)
    finally:
        window.plotter.render_window.RemoveObserver(tag)
    assert not window.compare.isVisible() and len(frames) - at_result[-1] == 1, (len(frames), at_result)


def test_both_views_draw_the_cloud_when_the_first_result_has_a_comparison(make_window, qtbot):
    """``darboux --compare ct``: the refit for the narrower views runs once the result is in
    the scenes. Fitted before (on no cloud), both views stayed empty: the zoom detail chose
    none of the new cloud's points (the screenshot with --compare was blank)."""
    window = make_window(size=(1440, 900), compare_method="ct")
    with wait_result(qtbot, window, 120_000):
        window.open_file(BUNNY)
    qtbot.waitUntil(lambda: not window._frame_due and not window.histogram.draw_pending, timeout=10_000)
    qtbot.wait(400)
    assert window.compare is not None and window.compare.isVisible()
    for view in (window.plotter, window.compare.plotter):
        img = np.asarray(view.screenshot(return_img=True), dtype=int)
        drawn = (np.abs(img - img[2, 2]).sum(axis=2) > 60).mean()  # pixels unlike the background
        assert drawn > 0.1, drawn
