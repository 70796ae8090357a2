"""Clicking a point of the 3D view (a mixin of :class:`app.scene.CloudScene`, GUI thread)."""

from __future__ import annotations

import numpy as np

from . import framing

__all__ = ["Picking"]


class Picking:
    """Display coordinates, the point under a click, and the click observers.

    Expects ``plotter``, ``points``, ``drawn``, ``sprite_size``, ``_pick_callback``,
    ``_press`` and ``_observers`` on the scene.
    """

    # -- picking ---------------------------------------------------------------------
    def display_coords(self, index) -> tuple[np.ndarray, np.ndarray]:
        """Display (x, y) pixel coordinates of cloud points (origin bottom-left)."""
        x, y, _ = framing.projection(self.plotter.renderer, self.points[np.atleast_1d(index)])
        return x, y

    def pick(self, x: float, y: float, radius: float | None = None) -> int | None:
        """Index of the front-most drawn cloud point within ``radius`` px of display (x, y)
        (a still frame of a big cloud draws a subset: the pick is among what is seen)."""
        if self.points is None or not len(self.points):
            return None
        drawn = self.drawn if self.drawn is not None else np.arange(len(self.points))
        px, py, depth = framing.projection(self.plotter.renderer, self.points[drawn])
        r = radius if radius is not None else max(4.0, 0.5 * self.sprite_size)
        d2 = (px - x) ** 2 + (py - y) ** 2
        near = np.flatnonzero((d2 <= r * r) & np.isfinite(depth) & (np.abs(depth) <= 1.0))
        if not len(near):
            return None
        # front-most first; among points at about the same depth, the closest to the click
        front = depth[near]
        keep = near[front <= front.min() + 1e-3 * (1.0 + abs(front.min()))]
        return int(drawn[keep[np.argmin(d2[keep])] if len(keep) else near[np.argmin(front)]])

    def enable_picking(self, callback) -> None:
        """Call ``callback(index)`` when the user clicks (press and release, no drag) a point."""
        iren = getattr(self.plotter, "iren", None)
        if iren is None:
            return
        self._pick_callback = callback
        vtk_iren = iren.interactor

        def on_press(*_args):
            self._press = vtk_iren.GetEventPosition()

        def on_release(*_args):
            start, self._press = self._press, None
            if start is None or self._pick_callback is None:
                return
            x, y = vtk_iren.GetEventPosition()
            if abs(x - start[0]) + abs(y - start[1]) > 3:
                return  # that was a drag (rotate), not a click
            index = self.pick(x, y)
            if index is not None:
                self._pick_callback(index)

        # pyvista registers release observers on the interactor style: the
        # interactor swallows release events (pyvista issue #4976)
        self._observers = [
            iren.add_observer("LeftButtonPressEvent", on_press),
            iren.add_observer("LeftButtonReleaseEvent", on_release),
        ]
