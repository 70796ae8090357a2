"""A second 3D view beside the main one, showing another method on the same
cloud, with the camera shared (linked) with the main view."""

from __future__ import annotations

from PySide6.QtCore import QTimer
from PySide6.QtWidgets import QVBoxLayout, QWidget

from .. import _refguard
from ..scene import CloudScene, make_plotter


def _pose(camera) -> tuple:
    return (tuple(camera.GetPosition()), tuple(camera.GetFocalPoint()), tuple(camera.GetViewUp()),
            camera.GetViewAngle(), camera.GetParallelScale())


def _update(plotter) -> None:
    if not getattr(plotter, "_closed", False):  # (closed: its render window is gone)
        plotter.update()


class CameraLink:
    """Share one vtkCamera between two plotters and repaint the other one when
    either view moves (GUI thread; the repaint is deferred to the event loop, and
    only happens when the pose actually changed, so the two never ping-pong).

    The repaint is ``update()``, not ``render()``: a render draws the view twice (VTK's
    render, then the paint it schedules), and updates asked before the paint make one."""

    def __init__(self, main, other):
        self.main, self.other = main, other
        other.renderer.camera = main.renderer.camera
        self._pose = _pose(main.renderer.camera)
        self._tags = []
        for source, target in ((main, other), (other, main)):
            window = source.render_window
            tag = window.AddObserver("EndEvent", lambda *_a, t=target: self._changed(t))
            self._tags.append((window, tag))

    def _changed(self, target) -> None:
        pose = _pose(self.main.renderer.camera)
        if pose != self._pose:
            self._pose = pose
            QTimer.singleShot(0, lambda: _update(target))

    def unlink(self) -> None:
        for window, tag in self._tags:
            window.RemoveObserver(tag)
        self._tags = []


class CompareView(QWidget):
    """Owns its plotter: :meth:`close_view` closes it (the window calls it on close)."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.plotter = make_plotter(self)
        self.plotter.setAcceptDrops(False)  # drops go to the main window
        self.plotter.setMinimumSize(240, 240)  # (without, a small window's splitter left it 0 px wide)
        self.scene = CloudScene(self.plotter)
        self.link: CameraLink | None = None
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.plotter)

    def link_to(self, main_plotter) -> None:
        if self.link is None:
            self.link = CameraLink(main_plotter, self.plotter)

    def close_view(self) -> None:
        if self.link is not None:
            self.link.unlink()
            self.link = None
        self.scene.close()
        self.plotter.close()
        _refguard.forget_surface(self.plotter)
