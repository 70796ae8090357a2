"""Level of detail: a decimated cloud drawn while the camera moves (GUI thread).

Software OpenGL draws 1M point sprites in ~1 s and 5M in ~5 s (notes/perf), far too
slow to turn the camera. While the user drags, the full cloud is hidden and a fixed
random subset of :data:`LOD_POINTS` points, drawn as flat squares, is shown instead;
when the drag ends the full cloud comes back (MeshLab and CloudCompare do the same).
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

__all__ = ["LevelOfDetail", "LOD_POINTS", "STILL_POINTS", "paint"]

#: Points drawn while the camera moves. Measured with llvmpipe on this 2-core VM under
#: a load average of 8 (1100x850 view): 150k flat points 0.72 s per frame, 28k 0.15 s,
#: roughly linear; 60k keeps a frame near 0.2 s even on the loaded machine.
LOD_POINTS = 60_000
#: Points a still frame draws at most (spheres; a random subset above it, sprites grown by
#: sqrt(N / budget) to cover). Measured on this VM with llvmpipe, 1100x850, quiet machine:
#: a frame costs ~45 ms plus ~0.45 us a sphere (1M: 0.49 s, 200k: 0.19 s), so 100k keeps a
#: still frame, and with it any GUI-thread step that renders, near the 0.1 s target.
STILL_POINTS = 100_000


def paint(mesh: pv.PolyData, mapper, *, values: np.ndarray | None = None, rgb: np.ndarray | None = None) -> None:
    """Colour ``mesh`` (drawn by the pyvista ``mapper``): by ``rgb``, (n, 3) uint8 colours
    drawn as they are (array "rgb"), or else by ``values`` through the lookup table (array
    "values"; None: NaN, grey)."""
    if rgb is not None:
        name, other, array = "rgb", "values", np.asarray(rgb, dtype=np.uint8)
    else:
        name, other = "values", "rgb"
        array = np.full(mesh.n_points, np.nan) if values is None else values
    mesh.point_data[name] = array
    if other in mesh.point_data:
        mesh.point_data.remove(other)
    mesh.set_active_scalars(name)
    if mapper.GetArrayName() != name:
        mapper.set_active_scalars(name)  # and in the mapper's active-scalars filter (pyvista's)
    if rgb is not None:
        mapper.SetColorModeToDirectScalars()
    else:
        mapper.SetColorModeToMapScalars()


class LevelOfDetail:
    """The decimated stand-in of one scene's cloud.

    Parameters
    ----------
    plotter : pyvista plotter the scene draws in.
    lut : pyvista.LookupTable shared with the full cloud (same colours).
    limit : clouds with more points than this get a stand-in.
    budget : a still frame draws at most this many points (read by the scene).
    """

    def __init__(self, plotter, lut, limit: int = LOD_POINTS, budget: int = STILL_POINTS):
        self.plotter = plotter
        self.lut = lut
        self.limit = int(limit)
        self.budget = int(budget)
        self.index: np.ndarray | None = None
        self._mesh: pv.PolyData | None = None
        self._actor = None
        self._full = None
        self.active = False
        self.held = False
        self._tags: list = []

    def set_cloud(self, geometry, full_actor, point_size: float, nan_colour: str) -> None:
        """Build (or drop) the stand-in for a new cloud (:class:`app.geometry.CloudGeometry`:
        the stand-in is a prefix of its random drawing order). Its points and values
        follow with :meth:`set_points` and :meth:`set_values`."""
        self._remove()
        self._full = full_actor
        if geometry.n_points <= self.limit:
            return
        self.index = geometry.subset(self.limit)
        self._mesh = pv.PolyData(np.zeros((len(self.index), 3)))
        self._mesh.point_data["values"] = np.full(len(self.index), np.nan)
        self._actor = self.plotter.add_mesh(
            self._mesh, scalars="values", cmap=self.lut, clim=self.lut.scalar_range, point_size=max(point_size, 2.0),
            render_points_as_spheres=False, show_scalar_bar=False, nan_color=nan_colour, pickable=False,
            name="cloud-lod", reset_camera=False, render=False,
        )
        self._actor.mapper.SetUseLookupTableScalarRange(True)
        self._actor.SetVisibility(False)

    def set_point_size(self, size: float) -> None:
        """The full cloud's sprite size, grown for the subset's wider spacing (sqrt of the
        density ratio on a surface) so the stand-in has no more holes than the cloud."""
        if self._actor is not None and self._full is not None:
            n_full = self._full.GetMapper().GetInput().GetNumberOfPoints()
            self._actor.prop.point_size = min(float(size) * np.sqrt(max(n_full, 1) / self.limit), 48.0)

    def set_values(self, values: np.ndarray | None) -> None:
        """Values of the whole cloud (None: not estimated yet, drawn grey)."""
        if self._mesh is not None:
            paint(self._mesh, self._actor.mapper,
                  values=None if values is None else np.asarray(values, dtype=float)[self.index])

    def set_colours(self, rgb: np.ndarray) -> None:
        """Colours of the whole cloud ((N, 3) uint8, drawn as they are)."""
        if self._mesh is not None:
            paint(self._mesh, self._actor.mapper, rgb=rgb[self.index])

    def set_points(self, points: np.ndarray) -> None:
        if self._mesh is not None:
            self._mesh.points = np.asarray(points[self.index], dtype=float)

    def begin(self, *_args) -> None:
        """The camera starts moving: show the stand-in."""
        if self._actor is not None and self._full is not None and not self.active:
            self.active = True
            self._full.SetVisibility(False)
            self._actor.SetVisibility(True)

    def hold(self, on: bool) -> None:
        """Keep the stand-in on screen until released (a new cloud or a preview on a big
        cloud: one full render of 1M sprites costs ~1 s of GUI time, paid once, for the final result)."""
        self.held = bool(on)
        if on:
            self.begin()
        else:
            self.end(render=False)

    def end(self, *_args, render: bool = True) -> None:
        """The camera stopped: back to the full cloud unless held."""
        if self.active and not self.held:
            self.active = False
            self._actor.SetVisibility(False)
            self._full.SetVisibility(True)
            if render:
                self.plotter.render()

    def attach(self, after_end=None) -> None:
        """Follow the interactor style's start/end of interaction (drag, zoom, pan);
        ``after_end()`` is called when an interaction ends (the scene's zoom detail)."""
        self._observe(self.plotter, after_end)

    def follow(self, plotter, after_end=None) -> None:
        """Also stand in while the camera moves in ``plotter``, a view sharing this one's
        camera (the compare view): each step of its drag repaints this view too, so a
        full frame here made every step cost a still frame (0.05-0.14 s at 200k points)."""
        self._observe(plotter, after_end)

    def _end_and_paint(self, *_args) -> None:
        """An interaction ended: the full cloud, painted in a later pass. Not rendered here:
        the style renders right after (``StopState``; a paint too, app/plotter.py), and the
        render this made besides drew the full cloud once more in the same turn (0.07-0.2 s
        at 200k points); the paints asked before the next one make one."""
        if self.active and not self.held:
            self.end(render=False)
            self.plotter.update()

    def _observe(self, plotter, after_end) -> None:
        iren = getattr(plotter, "iren", None)
        style = iren.interactor.GetInteractorStyle() if iren is not None else None
        if style is None:
            return
        self._tags += [(style, style.AddObserver("StartInteractionEvent", self.begin)),
                       (style, style.AddObserver("EndInteractionEvent", self._end_and_paint))]
        if after_end is not None:
            self._tags.append((style, style.AddObserver("EndInteractionEvent", lambda *_args: after_end())))

    def close(self) -> None:
        for style, tag in self._tags:
            style.RemoveObserver(tag)
        self._tags = []
        self._mesh = self._actor = self._full = None

    def _remove(self) -> None:
        if self._actor is not None:
            self.plotter.remove_actor(self._actor, render=False)
        self._mesh = self._actor = self.index = None
        self.active = self.held = False
