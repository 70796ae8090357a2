"""Every pyvista/VTK call of the viewer, for one 3D view.

All methods run on the GUI thread (VTK must never be touched from the worker:
rendering from another thread aborts the process). Arrays are updated in place
when the cloud keeps its size; actors are rebuilt only when it changes.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from . import framing, glyphs, legend
from .detail import VisibleDetail
from .geometry import CloudGeometry
from .lod import LevelOfDetail, paint
from .picking import Picking
from .plotter import MULTI_SAMPLES, make_plotter
from .theme import LIGHT, Theme

__all__ = ["CloudScene", "GLYPH_COLOURS", "FRAME_COLOURS", "MULTI_SAMPLES", "make_plotter"]

#: Colours of the ± glyphs and of the picked frame: the same everywhere (app/glyphs.py).
FRAME_COLOURS = glyphs.FRAME_COLOURS
GLYPH_COLOURS = {"e1": FRAME_COLOURS["e1"], "e2": FRAME_COLOURS["e2"], "normals": FRAME_COLOURS["n"]}
NAN_COLOUR = legend.NAN_DEFAULT
TEXT_COLOUR = "#222222"


def _camera_state(renderer) -> tuple:
    cam = renderer.GetActiveCamera()
    return cam.GetPosition(), cam.GetFocalPoint(), cam.GetViewUp(), cam.GetViewAngle()


class CloudScene(Picking):
    """One cloud, its colours, glyphs, picked-point highlight and title in a plotter.

    Parameters
    ----------
    plotter : pyvistaqt.QtInteractor (or any pyvista plotter)
        The scene does not own it; whoever created the plotter closes it.
    """

    def __init__(self, plotter):
        self.plotter = plotter
        self.points: np.ndarray | None = None
        self.geometry: CloudGeometry | None = None
        self.drawn: np.ndarray | None = None  # indices of the points a still frame draws
        self._visible = 0  # of them, the points in view when they were chosen
        self._values: np.ndarray | None = None  # the colours' values on every point
        self._rgb: np.ndarray | None = None  # or the file's own colours on every point, (N, 3) uint8
        self._note = None  # what stands for the colour bar when the file's colours are drawn
        self.spacing = 1.0
        self.point_size = 5.0  # the user's "Point size": the sprite size at the default density
        self.sprite_size = 5.0  # what is drawn: follows the point spacing on screen (app/framing.py)
        self._sprite_spacing, self._fit_sprite = 0.0, None  # spacing; sprite px the last fit gave
        self.fitted_by: CloudScene | None = None  # the scene whose fits frame this view (the compare view's: the main)
        #: actor name -> size factor: point layers drawn over the cloud, resized with its sprites
        self.sprite_layers = {"pick-neighbours": 1.6}
        self._fit_pending: tuple | None = None  # (window size, camera) the last fit left
        #: other plotters sharing this scene's camera (the compare view): the fit frames the narrowest
        self.linked: list = []
        self.view = "front"
        self._cloud: pv.PolyData | None = None
        self._actor = None
        self._lut = pv.LookupTable(cmap="RdBu_r")
        self._lut.nan_color = NAN_COLOUR
        self._lut.scalar_range = (-1.0, 1.0)
        self._bar = None
        self._bar_title = ""
        self._glyph_names: set[str] = set()
        self._legend_size = None  # the window size the glyph legend was placed for
        self._pick_callback = None
        self._press = None
        self._observers = []
        self.theme = LIGHT
        self._title_actor = None
        self.lod = LevelOfDetail(plotter, self._lut)
        self.detail = VisibleDetail(self, self._show_detail)
        self.lod.attach(after_end=self.detail.request)
        self._render_tag = plotter.renderer.AddObserver("StartEvent", self._before_render)
        plotter.set_background(self.theme.background)
        # pyvista's key bindings that would fight the viewer's own state (point size,
        # picking mode, a screenshot on "q"); r (reset camera) and v (isometric) stay
        for key in ("q", "b", "C", "plus", "minus"):
            try:
                plotter.clear_events_for_key(key)
            except (AttributeError, KeyError, ValueError):
                pass

    # -- cloud and colours ----------------------------------------------------
    def set_cloud(self, points: np.ndarray, values: np.ndarray | None = None, *, reset_camera: str | None = None,
                  geometry: CloudGeometry | None = None):
        """Show ``points`` (in place if the count did not change).

        ``geometry``: the cloud's :class:`app.geometry.CloudGeometry`, computed off the GUI
        thread (computed here if None). Above :data:`app.lod.STILL_POINTS` points a still
        frame draws that many (a random subset, sprites grown to cover): with software
        OpenGL every frame then costs the GUI thread at most ~0.1 s. Zoomed in, the budget
        goes to the points in view once the camera stops (:mod:`app.detail`).
        """
        points = np.asarray(points, dtype=float)
        if geometry is None or geometry.n_points != len(points):
            geometry = CloudGeometry.of(points)
        same = self._cloud is not None and self.geometry is geometry  # same cloud: keep what is drawn
        moved = not same or points is not self.points  # a new result on the same array: positions kept
        self.geometry, self.points = geometry, points
        self._values = None if values is None else np.asarray(values, dtype=float)
        self._rgb = None
        if same:
            self._draw(self.drawn, self._visible, moved=moved)
        else:
            if self._actor is not None:
                self.plotter.remove_actor(self._actor, render=False)
            drawn = geometry.subset(self.lod.budget)
            self._cloud = pv.PolyData(points[drawn])
            self._cloud.point_data["values"] = np.full(len(drawn), np.nan)
            self._actor = self.plotter.add_mesh(
                self._cloud, scalars="values", cmap=self._lut, clim=self._lut.scalar_range, render_points_as_spheres=True,
                point_size=self.point_size, show_scalar_bar=False, nan_color=NAN_COLOUR, pickable=False,
                name="cloud", reset_camera=False, render=False,
            )
            self._actor.mapper.SetUseLookupTableScalarRange(True)
            self._draw(drawn, geometry.n_points)
            self.lod.set_cloud(geometry, self._actor, self.point_size, NAN_COLOUR)
            self._add_bar()
        if moved:
            self.lod.set_points(points)
        self.lod.set_values(values)
        if reset_camera:
            self.reset_camera(reset_camera)
        elif not same:
            self.detail.request()  # a new cloud in a camera someone may have zoomed

    def _draw(self, drawn: np.ndarray, visible: int, *, moved: bool = True) -> None:
        """Draw the points ``drawn`` (indices) of the ``visible`` in view; sprites grow as the
        drawn points get sparser than the cloud (spacing ~ 1 / sqrt(density)). ``moved``
        False: the drawn points' positions are those on screen (only the values change)."""
        if self._cloud.n_points == len(drawn):
            if moved or drawn is not self.drawn:
                self._cloud.points = self.points[drawn]
        else:
            self._cloud = pv.PolyData(self.points[drawn])
            self._actor.mapper.SetInputData(self._cloud)
        paint(self._cloud, self._actor.mapper, values=None if self._values is None else self._values[drawn],
              rgb=None if self._rgb is None else self._rgb[drawn])
        self.drawn, self._visible = drawn, visible
        self._sprite_spacing = self.geometry.spacing * np.sqrt(max(visible, 1) / max(len(drawn), 1))

    def set_budget(self, budget: int) -> None:
        """Draw at most ``budget`` points in a still frame (zoomed in: those in view, app.detail)."""
        if budget != self.lod.budget:
            whole = self._cloud is not None and self.geometry.n_points <= min(budget, self.lod.budget)
            self.lod.budget = int(budget)
            if self._cloud is not None and not whole:  # (every point drawn under both budgets: nothing to redo)
                self._draw(self.geometry.subset(self.lod.budget), self.geometry.n_points)
                self.detail.request()

    def _show_detail(self, drawn: np.ndarray, visible: int) -> None:
        """The visible points the camera's stop selected (app/detail.py): draw them, painted in a
        later pass (a ``render()`` drew the view twice) unless the stand-in is on (its end renders)."""
        self._draw(drawn, visible)
        if not self.lod.active:
            self.plotter.update()

    def _add_bar(self) -> None:  # once per scene
        if self._bar is None:
            self._bar = legend.add_bar(self.plotter, self._lut, self._bar_title, self.theme.text, self.theme.background)

    def set_values(self, values: np.ndarray, *, title: str, cmap: str, clim: tuple[float, float], log: bool = False,
                   bands: int = 0):
        """Colour the cloud by ``values`` (NaN in a grey no colour of the map is), on a log scale if ``log``;
        ``bands`` colours, one an integer, with a label each (a categorical field), or a smooth map."""
        if self._cloud is None:
            return
        self._values, self._rgb = np.asarray(values, dtype=float), None
        paint(self._cloud, self._actor.mapper, values=self._values[self.drawn])
        self.lod.set_values(values)
        want = legend.band_map(cmap, bands) if bands else cmap
        if (self._lut.cmap is None or getattr(self._lut.cmap, "name", None) != getattr(want, "name", want)
                or self._lut.n_values != (bands or 256)):
            self._lut.n_values = bands or 256  # (before the map, which is sampled at that many values)
            self._lut.cmap = want
        self._lut.nan_color = legend.nan_colour(cmap)
        if self._bar is not None:
            legend.label_categories(self._bar, clim, bands)
        log = bool(log) and clim[0] > 0
        if not log:  # the scale before the range, or the range before the log scale: never a log
            self._lut.log_scale = False  # table over a range with 0 or below (a VTK warning)
        self._lut.scalar_range = (float(clim[0]), float(clim[1]))
        self._lut.log_scale = log
        self._bar_title = title
        self.show_bar(True)

    def set_colours(self, rgb: np.ndarray, *, note: str) -> None:
        """Draw the cloud in its own colours ((N, 3) uint8, as they are: no colour map);
        ``note`` (what the colours are) stands where the colour bar would."""
        if self._cloud is None:
            return
        self._values, self._rgb = None, np.asarray(rgb, dtype=np.uint8)
        paint(self._cloud, self._actor.mapper, rgb=self._rgb[self.drawn])
        self.lod.set_colours(self._rgb)
        self._bar_title = note
        self.show_bar(True)

    def show_bar(self, on: bool) -> None:
        """Show or hide the colour bar (hidden while a new cloud has no values yet), or its
        note when the cloud is drawn in its own colours."""
        rgb = self._rgb is not None
        if self._bar is not None:
            self._bar.SetTitle(self._bar_title or " ")
            self._bar.SetVisibility(bool(on) and not rgb)
        if on and rgb:
            self._note = self.plotter.add_text(self._bar_title, position=(framing.BAR_LEFT + 0.5 * framing.BAR_WIDTH,
                                                                          framing.BAR_BOTTOM), viewport=True,
                                               font_size=7, color=self.theme.text, name="colour-note", render=False)
            self._note.prop.font_size = 14  # the bar's title size, centred under the view as the bar's is
            self._note.prop.SetJustificationToCentered()
            legend.plate(self._note.prop, self.theme.background)
        elif self._note is not None:
            self.plotter.remove_actor(self._note, render=False)
            self._note = None

    def set_point_size(self, size: float):
        """The user's point size: the sprite size at the default density, a factor otherwise."""
        self.point_size = float(size)
        self._update_sprites()

    def _update_sprites(self) -> None:
        """Sprite size from the point spacing seen at the current camera distance."""
        if self._actor is None or self.points is None or not len(self.points):
            return
        size = framing.sprite_size(self.plotter.renderer, np.asarray(self._cloud.center), self._sprite_spacing,
                                   self.point_size, (self.fitted_by or self)._fit_sprite)
        self.sprite_size = self._actor.prop.point_size = size  # VTK ignores a set to the same value
        self.lod.set_point_size(max(size, 2.0))
        for name, factor in self.sprite_layers.items():
            if name in self.plotter.actors:
                self.plotter.actors[name].prop.point_size = size * factor

    def _before_render(self, *_args) -> None:
        """Every render: refit a camera nobody moved if the view was resized, then size sprites."""
        window = self.plotter.renderer.GetRenderWindow()
        if self._fit_pending is not None and window is not None and self._fit_pending[0] != tuple(window.GetSize()):
            if self._fit_pending[1] == _camera_state(self.plotter.renderer):  # nobody moved it since
                self._fit()
        if self._glyph_names and window is not None and self._legend_size != tuple(window.GetSize()):
            self._legend_size = legend.place_legend(self.plotter)
        self._update_sprites()

    # -- glyphs -------------------------------------------------------------------
    def set_glyphs(self, kind: str, directions: np.ndarray | None, *, density: float, length: float,
                   normals: np.ndarray | None = None):
        """± segments along ``directions`` at a ``density`` fraction of the glyph positions
        (at most :data:`app.glyphs.GLYPH_POINTS`, spread evenly: the cloud's
        ``geometry.glyph_order``), or remove them. ``length`` is in mean point spacings. With
        ``normals``, glyphs are lifted (:meth:`overlay_lift`) over the point sprites; the
        normals' own glyphs start there and point outward (centred, the sprite hid them).
        """
        name = f"glyph-{kind}"
        if directions is None or self.points is None or density <= 0:
            if name in self._glyph_names:
                self.plotter.remove_actor(name, render=False)
                self.plotter.remove_actor(f"{name}-halo", render=False)
                self._glyph_names.discard(name)
            self._glyph_legend()
            return
        index = glyphs.glyph_index(self.geometry.glyph_order, density)
        base = self.points[index]
        if normals is not None:
            base = base + np.nan_to_num(np.asarray(normals, dtype=float)[index]) * self.overlay_lift()
        vertices, lines = glyphs.segments(base, np.asarray(directions)[index], slice(None), length * self.spacing,
                                          centred=kind != "normals")
        if len(vertices) == 0:
            self.set_glyphs(kind, None, density=0, length=0)
            return
        mesh = pv.PolyData(vertices, lines=lines)
        width = glyphs.glyph_width(len(self.points))
        # a white halo under each glyph (drawn first; the glyph wins the depth tie) keeps
        # the dark e1 readable over the dark end of any colour map
        for suffix, colour, w in (("-halo", "white", width + 2.5), ("", GLYPH_COLOURS.get(kind, "black"), width)):
            self.plotter.add_mesh(mesh, color=colour, line_width=w, name=name + suffix, pickable=False,
                                  reset_camera=False, render=False, lighting=False)
        self._glyph_names.add(name)
        self._glyph_legend()

    def overlay_lift(self) -> float:
        """World distance along the normal that clears the point sprites (app/framing.py)."""
        return framing.overlay_lift(self._sprite_spacing or self.spacing, self.point_size)

    def _glyph_legend(self) -> None:
        """A legend of the glyphs shown, in the lower-left corner (app/legend.py)."""
        shown = [kind for kind in legend.KINDS if f"glyph-{kind}" in self._glyph_names]
        self._legend_size = legend.update_legend(self.plotter, shown, GLYPH_COLOURS)  # a light plate in both themes

    def radius(self) -> float:
        """Half the diagonal of the cloud's bounding box."""
        return self.geometry.radius if self.geometry is not None else 1.0

    # -- camera, text, render ------------------------------------------------------
    def set_title(self, text: str):
        """Caption in the top-left corner, at a fixed font size (a corner annotation
        would shrink it, or drop it, in a narrow view)."""
        actor = self.plotter.add_text(text, position=(0.012, 0.985), viewport=True, font_size=7,
                                      color=self.theme.text, name="title", render=False)
        actor.prop.font_size = 13
        actor.prop.SetVerticalJustificationToTop()
        actor.prop.SetLineSpacing(1.15)
        legend.plate(actor.prop, self.theme.background)
        self._title_actor = actor

    def set_theme(self, theme: Theme) -> None:
        """Background and text colours (light or dark palette)."""
        self.theme = theme
        self.plotter.set_background(theme.background)
        legend.restyle(self._bar, (self._title_actor, self._note), theme)
        self._glyph_legend()

    def set_eye_dome(self, on: bool) -> None:
        """Eye-dome lighting: depth-edge shading that shows the shape of flat-shaded scans."""
        if on:
            self.plotter.enable_eye_dome_lighting()
        else:
            self.plotter.disable_eye_dome_lighting()

    def fit_view(self) -> None:
        """Frame the whole cloud, keeping the viewing direction."""
        self.plotter.renderer.reset_camera(render=False)  # Plotter.reset_camera renders regardless
        self._fit()
        self.detail.request()

    def _fit(self) -> None:
        """Fill the view above the colour bar with the cloud's projection (app/framing.py)."""
        if self.points is None or not len(self.geometry.fit_index):  # (no drawable point)
            return
        renderer = framing.narrowest([self.plotter.renderer] + [p.renderer for p in self.linked if p.isVisible()])
        sample = self.points[self.geometry.fit_index]
        framing.fit_to_region(renderer, sample)
        # the sprites' size depends on the fit: fit again with half a sprite of room
        size = framing.sprite_size(renderer, sample.mean(axis=0), self._sprite_spacing, self.point_size)
        framing.fit_to_region(renderer, sample, framing.free_region(renderer, inset=0.5 * size), steps=3)
        self._fit_sprite = framing.sprite_size(renderer, sample.mean(axis=0), self._sprite_spacing, framing.DEFAULT_SIZE)
        window = self.plotter.renderer.GetRenderWindow()
        self._fit_pending = (tuple(window.GetSize()), _camera_state(renderer)) if window is not None else None

    def reset_camera(self, view: str = "front"):
        """Frame the cloud.

        ``"front"``: look down -z with y up (the convention of most scans, the
        Stanford models among them), turned a little for depth. ``"oblique"``:
        z up, seen from above at an angle (the synthetic shapes). ``"xy"``,
        ``"xz"``, ``"yz"``: axis-aligned.
        """
        if self.points is None or not len(self.points):
            return
        # pyvista's camera getter renders the whole scene once on a fresh renderer
        # (camera_set False): 6 s for 1M sprites with llvmpipe. We place it ourselves.
        self.plotter.renderer.camera_set = True
        framing.look_from(self.plotter.renderer, self.geometry.centre, self.geometry.radius, view)
        self.plotter.renderer.reset_camera(render=False)  # Plotter.reset_camera renders regardless
        self._fit()
        self.view = view
        self.detail.request()  # the whole cloud in view again: the uniform subset

    def render(self):
        self.plotter.render()

    def close(self):
        """Drop observers and references (the plotter itself is closed by its owner)."""
        iren = getattr(self.plotter, "iren", None)
        for tag in self._observers:
            if iren is not None:
                iren.remove_observer(tag)
                style = getattr(iren, "style", None)
                if style is not None:
                    style.RemoveObserver(tag)
        self._observers = []
        if self._render_tag is not None:
            self.plotter.renderer.RemoveObserver(self._render_tag)
            self._render_tag = None
        self.lod.close()
        self.detail.close()
        self._pick_callback = None
        self._cloud = None
        self._title_actor = self._note = None
        self._actor = None
        self._bar = None
