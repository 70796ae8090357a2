"""The 3D views of the main window: the compare view shown and hidden, repaints scheduled
one view a turn of the event loop (a mixin of MainWindow; GUI thread).

A frame of 100k point sprites costs the GUI thread ~0.1-0.3 s with llvmpipe. Qt paints
every widget that is due in one pass, so two views repainted together, or relaid out
together, made one stall of both frames (0.5-0.75 s at 200k points when the compare
view came on, with up to 9 frames: each view painted by the relayout, again by its
render, by the camera link's ``render()``, and after the refit). Now: the relayout
paints nothing (updates held), the main view paints in one turn, the compare view in the
next, and with two views each draws half the still-frame budget (each has half the
pixels; a frame's cost is linear in the points drawn).
"""

from __future__ import annotations

from PySide6.QtCore import QCoreApplication, QEvent, QTimer

from .lod import STILL_POINTS
from .theme import current_theme
from .widgets import CompareView

__all__ = ["WindowViews"]


class WindowViews:
    """Compare view, camera fits and the staged repaint of the 3D views."""

    _frame_due = _compare_due = _refit_due = False

    def _sync_compare(self, shown: bool) -> None:
        """Show the compare view (``shown``: the result has a compared method) or hide it."""
        if shown:
            self._show_compare()
        elif self.compare is not None and self.compare.isVisible():
            self.plotter.setUpdatesEnabled(False)  # widened: painted once, by _repaint
            self.compare.hide()
            QCoreApplication.sendPostedEvents(None, QEvent.Type.LayoutRequest)
            self.presenter.compare_scene = None
            self.scene.linked = []
            self.scene.set_budget(STILL_POINTS)

    def _show_compare(self) -> None:
        """Create (once) and show the second view beside the main one."""
        if self.compare is None:
            self.compare = CompareView(self)
            self.compare.scene.point_size = self.state.point_size
            self.compare.scene.set_theme(self.scene.theme)
            self.compare.hide()
            self.splitter.addWidget(self.compare)
            self.compare.link_to(self.plotter)
            _share_camera(self.scene, self.compare.scene)
            self.compare.plotter.render_window.AddObserver("EndEvent", self._compare_frame_done)
        self.presenter.compare_scene = self.compare.scene
        self.scene.linked = [self.compare.plotter]  # fits frame the narrower of the two views
        if not self.compare.isVisible():
            for view in (self.plotter, self.compare.plotter):  # no paint in the relayout: Qt would paint
                view.setUpdatesEnabled(False)  # both views in one pass; _repaint paints one a turn
            self.compare.show()
            # laid out now, held: a layout settled in a later pass resized (and so painted) the views again
            QCoreApplication.sendPostedEvents(None, QEvent.Type.LayoutRequest)
            half = max(self.splitter.width() // 2, 200)
            self.splitter.setSizes([half, half])
            for scene in (self.scene, self.compare.scene):
                scene.set_budget(STILL_POINTS // 2)
            self._refit_due = True  # the views got narrower: refit once the result is in them (:meth:`_refit`)

    def _refit(self) -> None:
        """After the presenter showed a result: the fit the compare view's arrival asked for,
        before the frame it schedules (fitted before the result was in the scene, the views
        drew nothing: the zoom detail chose no points of the new cloud)."""
        if self._refit_due:
            self._refit_due = False
            self.scene.fit_view()

    def changeEvent(self, event) -> None:  # noqa: N802
        """The desktop switched between a light and a dark palette: the 3D views and the
        histogram follow, as the Qt widgets do by themselves (they stayed white in a dark
        window until the viewer was started again)."""
        if (event.type() in (QEvent.Type.PaletteChange, QEvent.Type.ApplicationPaletteChange)
                and not self._closed and current_theme() != self.scene.theme):
            self.apply_theme()
            self.render_all()
        super().changeEvent(event)

    def fit_view(self) -> None:
        """F: frame the whole cloud, keeping the direction."""
        if not self._closed:
            self.scene.fit_view()
            self.render_all()

    def reset_view(self) -> None:
        """R: back to the preset direction of this cloud."""
        if not self._closed:
            self.scene.reset_camera(self.scene.view)
            self.render_all()

    def render_all(self) -> None:
        """Schedule one repaint of the 3D view(s), after the current pass of the event loop.

        Deferred (a 0 ms timer): the step that asked (a new result swapped in, ~10-70 ms
        of GUI thread at 1M points) and the frame (~50-100 ms with llvmpipe) are then two
        turns of the event loop, with input and timers served between them, instead of
        one stall of their sum. Requests before it make one repaint.
        """
        if not self._closed:
            self._frame_due = True
            self._render_timer.start()

    def _repaint(self) -> None:
        """``update()``, not ``render()``: the interactor widget renders VTK in its own
        ``paintGL``, and a ``render()`` schedules that paint as well, so each explicit
        render drew the whole cloud twice (0.4 s each for the bunny with llvmpipe).
        Qt also merges several updates before the next paint into one. The compare view
        follows the main view's frame (:meth:`_frame_done`).
        """
        if self._closed:
            return
        self._compare_due = self.compare is not None and self.compare.isVisible()
        _paint(self.plotter)

    def _frame_done(self, *_args) -> None:
        """The main view rendered: the compare view's frame next, in a turn of its own."""
        if self._compare_due:
            self._compare_due = False
            QTimer.singleShot(0, self._repaint_compare)
            return
        self._frame_due = False
        self.histogram.after_frame()

    def _repaint_compare(self) -> None:
        if not self._closed and self.compare is not None and self.compare.isVisible():
            _paint(self.compare.plotter)  # its EndEvent: _compare_frame_done
        else:
            self._compare_frame_done()

    def _compare_frame_done(self, *_args) -> None:
        if not self._compare_due:  # (else a main frame is on its way: the compare's follows it)
            self._frame_due = False
            self.histogram.after_frame()


def _share_camera(main, compare) -> None:
    """The two views share a camera: a drag in either shows both stand-ins (app/lod.py), and
    its end asks both zoom details; the main view's fit caps the sprites of both (zoomed in
    past it, the compare view's grew to twice the main's: it never fits, so had no cap)."""
    main.lod.follow(compare.plotter, after_end=main.detail.request)
    compare.lod.follow(main.plotter, after_end=compare.detail.request)
    compare.fitted_by = main


def _paint(view) -> None:
    """A paint of ``view`` in a later pass; its updates enabled again if held (which asks for
    the paint: an ``update()`` besides made Qt paint it twice in one pass)."""
    if view.updatesEnabled():
        view.update()
    else:
        view.setUpdatesEnabled(True)
