"""Full detail where the camera looks: a still frame's point budget spent on the visible points.

A still frame of a cloud above :data:`app.lod.STILL_POINTS` draws a random subset of
that many points (:meth:`app.scene.CloudScene.set_cloud`). Zoomed in, most of that
subset is off screen: when the camera stops, a job thread projects the whole cloud
(~50-100 ms of numpy at 1M points, off the GUI thread), keeps the points inside the view
frustum and, if they are more than the budget, the first of them in the cloud's random
drawing order (so zooming out again gives back the same uniform subset). The GUI thread
swaps the drawn points in only if the camera has not moved since (Potree and
CloudCompare spend their point budgets the same way, per visible node).
"""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QObject, Signal

from .jobs import JobThread

__all__ = ["VisibleDetail", "visible_subset"]


def visible_subset(points: np.ndarray, matrix: np.ndarray, order: np.ndarray, budget: int) -> tuple[np.ndarray, int]:
    """Sorted indices of at most ``budget`` points inside the view frustum of the 4x4
    ``matrix`` (world -> clip coordinates), the earliest in ``order``; and how many
    points are visible in all."""
    visible = np.ones(len(points), dtype=bool)
    w = points @ matrix[3, :3] + matrix[3, 3]
    visible &= w > 0
    for row in range(3):  # -w <= clip <= w on each axis
        c = points @ matrix[row, :3] + matrix[row, 3]
        visible &= np.abs(c) <= w
    index = np.flatnonzero(visible)
    if len(index) <= budget:
        return index, len(index)
    rank = np.empty(len(points), dtype=np.intp)
    rank[order] = np.arange(len(order))
    rank_visible = rank[index]
    keep = index[np.argpartition(rank_visible, budget - 1)[:budget]]
    return np.sort(keep), len(index)


def _clip_matrix(renderer) -> np.ndarray:
    # the range a render would set: the one left may be another view's (a linked camera
    # reset by the compare view's props) or a moved camera's, whose planes cut the cloud
    renderer.ResetCameraClippingRange()
    cam = renderer.GetActiveCamera()
    vtk_m = cam.GetCompositeProjectionTransformMatrix(renderer.GetTiledAspectRatio(), -1.0, 1.0)
    return np.array([[vtk_m.GetElement(i, j) for j in range(4)] for i in range(4)])


def _camera(renderer) -> tuple:
    cam = renderer.GetActiveCamera()
    return cam.GetPosition(), cam.GetFocalPoint(), cam.GetViewUp(), cam.GetViewAngle(), cam.GetParallelScale()


class VisibleDetail(QObject):
    """Spends one scene's still-frame budget on what the camera sees (GUI-thread object).

    :meth:`request` (camera stopped, new cloud) queues a selection on a job thread;
    the answer comes back through the queued :attr:`ready` signal and is applied by
    ``apply(indices, n_visible)`` (the scene's) unless the cloud or camera changed since.
    """

    ready = Signal(int, object, int)  # token, indices, visible count

    def __init__(self, scene, apply):
        super().__init__()
        self.scene = scene
        self._apply = apply
        self._token = 0
        self._asked: tuple | None = None
        self._jobs: JobThread | None = None
        self.ready.connect(self._on_ready)

    def request(self) -> None:
        """Select the visible points for the current camera (no-op within the budget)."""
        scene = self.scene
        geometry, points = scene.geometry, scene.points
        if geometry is None or points is None or len(geometry.order) <= scene.lod.budget:
            return
        renderer = scene.plotter.renderer
        if renderer.GetRenderWindow() is None:
            return
        self._token += 1
        token, matrix, budget = self._token, _clip_matrix(renderer), scene.lod.budget
        self._asked = (token, points, _camera(renderer))
        if self._jobs is None:
            self._jobs = JobThread("darboux-detail")
        ready = self.ready
        self._jobs.put(lambda: ready.emit(token, *visible_subset(points, matrix, geometry.order, budget)))

    def _on_ready(self, token: int, indices, n_visible: int) -> None:
        asked = self._asked
        if asked is None or asked[0] != token or asked[1] is not self.scene.points:
            return  # a newer request, or another cloud
        if asked[2] != _camera(self.scene.plotter.renderer):
            return  # the camera moved on; its own stop asks again
        if self.scene.drawn is not None and np.array_equal(indices, self.scene.drawn):
            return  # already drawn (the whole cloud in view: the uniform subset)
        self._apply(indices, n_visible)

    def close(self) -> None:
        self._asked = None
        try:
            self.ready.disconnect()
        except (RuntimeError, TypeError):
            pass
        if self._jobs is not None:
            self._jobs.stop(0.0)
            self._jobs = None
