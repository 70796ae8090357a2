"""Meshes of the teaching overlays, built from a :class:`core.LocalFit` (numpy + pyvista data
objects only: any thread may build them; only :class:`OverlayLayer` touches the plotter).

Colours follow :data:`app.glyphs.FRAME_COLOURS`: e1 near-black, e2 green, n purple; the
swept direction theta is orange everywhere (3D view and Euler plot).
"""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkRenderer

from ..glyphs import FRAME_COLOURS, polylines

__all__ = ["THETA_COLOUR", "TYPE_COLOURS", "frame_meshes", "surface_mesh", "section_meshes", "dupin_mesh",
           "normal_fit_meshes", "lines_mesh", "OverlayLayer"]

THETA_COLOUR = "#ff7f00"
#: osculating circles are drawn within this many neighbourhood radii of the point: a
#: flat direction's circle (radius 1/k2 = 4.5 at the torus' outer equator) dwarfs the cloud
CIRCLE_REACH = 2.5
MEASURED_COLOUR = "#4d4d4d"
#: point types (core.TYPE_NAMES order): red K > 0, blue K < 0, light orange K = 0 (not the
#: yellow of the picked neighbourhood), grey planar, magenta umbilic
TYPE_COLOURS = ("#d7301f", "#2b8cbe", "#fdae61", "#d9d9d9", "#ae017e")


def _size(fit) -> float:
    return max(fit.radius, 1e-12)


def frame_meshes(fit) -> dict:
    """Arrows e1, e2, n from the point (length 0.9 x the neighbourhood radius) and a
    translucent tangent disc of that radius."""
    r = _size(fit)
    out = {}
    for key, vec in (("e1", fit.e1), ("e2", fit.e2), ("n", fit.normal)):
        arrow = pv.Arrow(start=fit.origin, direction=vec, scale=0.9 * r, tip_length=0.18, tip_radius=0.06,
                         shaft_radius=0.022)
        out[f"frame-{key}"] = (arrow, dict(color=FRAME_COLOURS[key], lighting=True, on_top=True))
    disc = pv.Disc(center=fit.origin, inner=0.0, outer=r, normal=fit.normal, c_res=64)
    out["tangent-disc"] = (disc, dict(color="#9ecae1", opacity=0.35, lighting=False))
    labels = pv.PolyData(np.array([fit.origin + 1.0 * r * v for v in (fit.e1, fit.e2, fit.normal)]))
    labels["label"] = np.array(["e1", "e2", "n"])
    out["frame-labels"] = (labels, dict(labels="label"))
    return out


def surface_mesh(fit, n: int = 31):
    """The fitted local surface (osculating paraboloid) over the neighbourhood's disc."""
    r = _size(fit)
    u, v = np.meshgrid(np.linspace(-r, r, n), np.linspace(-r, r, n))
    grid = pv.StructuredGrid(*np.moveaxis(fit.to_world(np.stack([u, v, fit.height(u, v)], axis=-1)), -1, 0))
    grid["inside"] = (np.hypot(u, v) <= r).ravel(order="F").astype(float)
    return grid.threshold(0.5, scalars="inside")


def _section_curve(fit, theta):
    s, w = fit.section(theta)
    d = np.array([np.cos(theta), np.sin(theta)])
    return fit.to_world(np.column_stack([s * d[0], s * d[1], w]))


def section_meshes(fit, theta: float) -> dict:
    """Normal sections along e1, e2 and theta: the neighbours near each normal plane joined in
    order, and the osculating circle (a straight line where k_n ~ 0); the theta plane itself."""
    r = _size(fit)
    out = {}
    for key, angle, colour in (("e1", 0.0, FRAME_COLOURS["e1"]), ("e2", 0.5 * np.pi, FRAME_COLOURS["e2"]),
                               ("theta", theta, THETA_COLOUR)):
        curve = _section_curve(fit, angle)
        if len(curve) >= 2:
            verts, cells = polylines([curve])
            out[f"section-{key}"] = (pv.PolyData(verts, lines=cells), dict(color=colour, line_width=2))
        circle = fit.osculating_circle(angle, reach=CIRCLE_REACH * r)
        verts, cells = polylines([circle])
        out[f"circle-{key}"] = (pv.PolyData(verts, lines=cells), dict(color=colour, line_width=4))
    d = np.cos(theta) * fit.e1 + np.sin(theta) * fit.e2
    plane = pv.Plane(center=fit.origin, direction=np.cross(d, fit.normal), i_size=2.4 * r, j_size=2.4 * r)
    out["section-plane"] = (plane, dict(color=THETA_COLOUR, opacity=0.18, lighting=False))
    return out


def dupin_mesh(fit):
    """The Dupin indicatrix in the tangent plane (None for a planar point)."""
    pieces = fit.dupin()
    if not pieces:
        return None
    lift = 0.02 * _size(fit) * fit.normal
    verts, cells = polylines([p + lift for p in pieces])
    return pv.PolyData(verts, lines=cells)


def normal_fit_meshes(fit, length: float) -> dict:
    """Two sets of arrows at the neighbours: their normals (what NF fits, grey) and the fitted
    linear normal field (orange, eqs. 15-21)."""
    pts = fit.to_world(fit.local)
    R = np.stack([fit.e1, fit.e2, fit.normal])
    out = {}
    for key, vecs, colour in (("measured", fit.local_normals @ R, MEASURED_COLOUR),
                              ("fitted", fit.fitted_normals() @ R, THETA_COLOUR)):
        cloud = pv.PolyData(pts)
        cloud["v"] = vecs
        arrows = cloud.glyph(orient="v", scale=False, factor=length,
                             geom=pv.Arrow(tip_length=0.3, tip_radius=0.12, shaft_radius=0.04))
        out[f"normals-{key}"] = (arrows, dict(color=colour))
    return out


def lines_mesh(lines):
    """One PolyData of polylines (None when there are none)."""
    verts, cells = polylines(lines)
    return pv.PolyData(verts, lines=cells) if len(verts) else None


class OverlayLayer:
    """The overlay actors of one plotter, by name (GUI thread only).

    Every actor is named ``teach-<name>``; :meth:`show` replaces one, :meth:`clear` removes
    the ones not listed in ``keep``. A style with ``on_top=True`` draws the mesh in a second
    renderer layer that shares the camera, over the cloud and its highlighted neighbours.
    """

    def __init__(self, plotter):
        self.plotter = plotter
        self.names: set[str] = set()
        self._top = None
        self._top_actors: dict = {}

    def _top_renderer(self):
        if self._top is None:
            main = self.plotter.renderer
            top = vtkRenderer()
            top.SetLayer(1)
            top.InteractiveOff()
            top.SetActiveCamera(main.GetActiveCamera())
            top.SetViewport(main.GetViewport())
            window = self.plotter.ren_win
            window.SetNumberOfLayers(max(2, window.GetNumberOfLayers()))
            window.AddRenderer(top)
            self._top = top
        return self._top

    def _show_on_top(self, name, mesh, style):
        self.remove(name)
        actor = pv.Actor(mapper=pv.DataSetMapper(mesh))
        actor.mapper.scalar_visibility = False
        actor.prop.color = style.get("color", "black")
        actor.prop.lighting = style.get("lighting", True)
        self._top_renderer().AddActor(actor)
        self._top_actors[name] = actor
        self.names.add(name)
        return actor

    def show(self, name: str, mesh, style: dict | None = None) -> None:
        style = dict(style or {})
        full = f"teach-{name}"
        if mesh is None:
            self.remove(name)
            return
        if style.pop("on_top", False):
            return self._show_on_top(name, mesh, style)
        if "labels" in style:
            actor = self.plotter.add_point_labels(
                mesh, style["labels"], name=full, font_size=18, bold=True, text_color="#222222",
                shape_opacity=0.0, show_points=False, always_visible=True, render=False, reset_camera=False)
        else:
            style.setdefault("lighting", False)
            actor = self.plotter.add_mesh(mesh, name=full, pickable=False, reset_camera=False, render=False,
                                          **style)
        self.names.add(name)
        return actor

    def remove(self, name: str) -> None:
        if name in self._top_actors:
            self._top.RemoveActor(self._top_actors.pop(name))
        elif name in self.names:
            self.plotter.remove_actor(f"teach-{name}", render=False)
        self.names.discard(name)

    def clear(self, keep=()) -> None:
        for name in sorted(self.names - set(keep)):
            self.remove(name)

    def close(self) -> None:
        """Drop every actor and the top layer (before the plotter closes)."""
        self.clear()
        if self._top is not None:
            self.plotter.ren_win.RemoveRenderer(self._top)
            self._top = None
