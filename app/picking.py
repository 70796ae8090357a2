"""Clicking a point of the 3D view and highlighting it (a mixin of :class:`app.scene.CloudScene`, GUI thread)."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from . import framing
from .glyphs import FRAME_COLOURS

__all__ = ["Picking", "HIGHLIGHT_COLOUR"]

HIGHLIGHT_COLOUR = "#ffd92f"


class Picking:
    """Display coordinates, the point under a click, and the click observers.

    Expects ``plotter``, ``points``, ``drawn``, ``sprite_size``, ``spacing``, ``radius()``,
    ``_pick_callback``, ``_press`` and ``_observers`` on the scene.
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

    # -- picked point ---------------------------------------------------------------
    def set_highlight(self, index: int | None, neighbours: np.ndarray | None = None, frame: dict | None = None):
        """Highlight a point's neighbourhood and draw its frame (``frame``: name -> unit vector)."""
        for name in ("pick-neighbours", "pick-point", *(f"pick-frame-{k}" for k in FRAME_COLOURS)):
            self.plotter.remove_actor(name, render=False)
        if index is None or self.points is None or index >= len(self.points):
            return
        if neighbours is not None and len(neighbours):
            nb = pv.PolyData(self.points[np.asarray(neighbours)])
            self.plotter.add_mesh(
                nb, color=HIGHLIGHT_COLOUR, point_size=self.sprite_size * 1.6, render_points_as_spheres=True,
                name="pick-neighbours", pickable=False, reset_camera=False, render=False,
            )
        centre = self.points[index]
        self.plotter.add_mesh(
            pv.PolyData(centre[None, :]), color="#e7298a", point_size=max(self.sprite_size * 1.8, 10.0),
            render_points_as_spheres=True, name="pick-point", pickable=False, reset_camera=False, render=False,
        )
        length = max(8.0 * self.spacing, 0.1 * self.radius())
        for key, vec in (frame or {}).items():
            vec = np.asarray(vec, dtype=float)
            if not np.isfinite(vec).all():
                continue
            seg = pv.Line(centre - 0.5 * length * vec, centre + 0.5 * length * vec)
            self.plotter.add_mesh(
                seg, color=FRAME_COLOURS.get(key, "black"), line_width=5, name=f"pick-frame-{key}",
                pickable=False, reset_camera=False, render=False, lighting=False,
            )
