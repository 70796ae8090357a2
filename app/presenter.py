"""Draw a worker result with the current display settings (GUI thread).

:class:`ResultPresenter` turns one :class:`app.worker.EstimateOutput` plus the
display part of the state (field, colour limits, glyphs, picked point) into calls
on the scene(s) and the panels. It keeps the output on screen so that display
changes re-draw without a new estimate.
"""

from __future__ import annotations

import numpy as np

from .captions import (degenerate, method_title, orientation_text, preview_line, result_parameters, status_line,
                       summary_line, title, uses_passes)
from . import file_fields
from .fields import FIELDS, FILE_PREFIX, Colouring, colouring, curvature_floor, is_file_field

__all__ = ["ResultPresenter", "method_title", "uses_passes", "summary_line", "status_line", "preview_line",
           "point_info", "result_parameters", "orientation_text"]


class ResultPresenter:
    """Owns what is on screen; the window forwards display-state changes to it.

    Attributes
    ----------
    output : EstimateOutput or None
        The result on screen.
    shown : dict
        Field, colour limits, colormap and generation on screen (tests, status).
    compare_scene : CloudScene or None
        Set by the window while the compare view is visible.
    """

    def __init__(self, state, scene, *, field_panel, histogram, inspector, notify=None):
        self.state = state
        #: ``notify(message)``: tells the user the field asked for is not drawn (the window's
        #: ``notifier.warning``: status bar, and stderr for ``--screenshot``)
        self.notify = notify
        self._falling_back = False
        self.scene = scene
        self.compare_scene = None
        self.field_panel = field_panel
        self.histogram = histogram
        self.inspector = inspector
        self.output = None
        self.preview = None  # the preview on screen while its full result is computed
        self.shown: dict = {}

    def _pairs(self):
        """(scene, result, fields) for every view showing the current output."""
        out = self.output
        pairs = [(self.scene, out.result, out.fields)]
        if self.compare_scene is not None and out.compare is not None:
            pairs.append((self.compare_scene, out.compare, out.compare_fields))
        return pairs

    def clear(self) -> None:
        """A new cloud is loading: forget the old result."""
        self.output = self.preview = None
        self.shown = {}
        self.scene.set_highlight(None)
        for kind in ("e1", "e2", "normals"):
            self.scene.set_glyphs(kind, None, density=0, length=0)
        self.scene.show_bar(False)
        self.histogram.clear()
        self.inspector.clear()

    def _look(self, name: str, values, spec=None):
        """Colour limits and map of field ``name`` over ``values``, from the state's settings."""
        s = self.state
        manual = None if (s.clim_auto or s.clim is None) else s.clim
        return colouring(spec or FIELDS[name], values, clip=s.clip_percent,
                         floor=curvature_floor(name, self.scene.radius()), clim=manual)

    def show_source(self, source) -> None:
        """A new cloud is on screen, not estimated yet: the Field box lists its file's own
        fields (those that vary, :func:`app.file_fields.listed`), and the one chosen, if it is one of them, is drawn now (those do not wait for
        the estimate). A command line's "file:Intensity" becomes the file's "file:intensity"."""
        name = file_fields.find(self.state.field, source.field_specs) if is_file_field(self.state.field) else None
        self.field_panel.set_file_fields(file_fields.listed(source.field_specs, source.fields, keep=name))
        if name is not None and name != self.state.field:
            self.state.set(field=name)
        self._colour_source()

    def _colour_source(self) -> None:
        """No estimate on screen: a file's own field is drawn from the file, any other waits
        for the estimate (the cloud grey, no colour bar)."""
        source = self.state.source
        if source is None:
            return
        if self.state.field in source.field_specs:
            self._colour_file(self.state.field, source, gen=None)
        elif self.shown:  # a file field was drawn
            self.scene.set_cloud(source.points, geometry=source.geometry)
            self.scene.show_bar(False)
            self.field_panel.show_limits(*self.shown["clim"])  # (the limit boxes editable again)
            self.histogram.clear()
            self.shown = {}

    def _colour_file(self, name: str, source, *, gen) -> None:
        """Draw the file's own field ``name`` in every view showing the cloud: its colours as
        they are (the histogram: their luminance), or its values. The same in every view:
        they belong to the points (a noisy copy keeps their order), not to an estimate."""
        spec = source.field_specs[name]
        scenes = [self.scene] if self.output is None or self.preview is not None else [p[0] for p in self._pairs()]
        if spec.scale == "rgb":
            for scene in scenes:
                scene.set_colours(source.colours, note=spec.label)
            values, look, label = source.luminance, Colouring((0.0, 255.0), "gray"), "Luminance of the file colour"
        else:
            values, label = source.fields[name[len(FILE_PREFIX):]], spec.label
            look = self._look(name, values, spec)
            for scene in scenes:
                scene.set_values(values, title=spec.title, cmap=look.cmap, clim=look.clim, log=look.log,
                                 bands=look.bands)
        self.field_panel.show_limits(*look.clim, editable=spec.scale != "rgb")
        self.histogram.set_data(values, clim=look.clim, cmap=look.cmap, label=label, bands=look.bands)
        self.shown = {"field": name, "clim": look.clim, "cmap": look.cmap, "gen": gen, "file": True}

    def show_preview(self, out) -> None:
        """Colour the cloud by a preview (:mod:`app.preview`); glyphs and pick wait for the full result."""
        self.preview = out
        self.scene.set_cloud(out.points, geometry=out.request.source.geometry)
        self._colour_preview()
        self.scene.lod.hold(True)  # a big cloud shows its stand-in until the full result
        self.scene.set_title(f"{method_title(out.request.method)} — preview on {out.preview:,} points\n"
                             f"{out.request.source.name}\ncomputing the full result…")

    def _drawable_field(self, out) -> str:
        """The state's field if ``out`` has it; otherwise mean curvature H, and the state
        follows as if H had been chosen in the Field box (which thus names what is drawn),
        with a notice why. The recolour that change asks for is this one (no loop)."""
        name = self.state.field
        drawable = name in out.fields or name in out.request.source.field_specs
        if drawable or self._falling_back:
            return name if drawable else "mean"
        self._falling_back = True
        try:
            self.state.set(field="mean", clim_auto=True)
        finally:
            self._falling_back = False
        if self.notify is not None:
            self.notify(_unavailable_text(name, out.request.source))
        return "mean"

    def _colour_preview(self) -> None:
        """The preview's colours, colour bar, limit boxes and histogram for the current field."""
        out = self.preview
        name = self._drawable_field(out)
        if is_file_field(name):
            self._colour_file(name, out.request.source, gen=out.gen)
            self.shown["preview"] = True
            return
        spec = FIELDS[name]
        values = out.fields[name]
        look = self._look(name, values)
        clim, cmap = look.clim, look.cmap
        self.scene.set_values(values, title=spec.title, cmap=cmap, clim=clim, log=look.log)
        self.field_panel.show_limits(*clim)
        self.histogram.set_data(values, clim=clim, cmap=cmap, label=spec.label + " (preview)")
        self.shown = {"field": name, "clim": clim, "cmap": cmap, "gen": out.gen, "preview": True}

    def drop_preview(self) -> bool:
        """The full result of the preview on screen will not come (cancelled, failed): draw the
        kept result again, or grey the cloud if there is none. True if a preview was dropped."""
        out, self.preview = self.preview, None
        if out is None:
            return False
        if self.output is not None:
            self.show(self.output)
        else:
            self.clear()
            self.scene.set_cloud(out.request.source.points, geometry=out.request.source.geometry)
            self.scene.lod.hold(False)
            self._colour_source()
        return True

    def show(self, out) -> None:
        """Draw a new result in the main view (and the compare view if set)."""
        self.output, self.preview = out, None
        req = out.request
        self.scene.lod.hold(False)
        for scene, res, _fields in self._pairs():
            scene.spacing = out.spacing
            scene.set_cloud(out.points, geometry=req.source.geometry)
            method = req.method if res is out.result else req.compare_method
            summary = out.summary if res is out.result else out.compare_summary
            scene.set_title(title(out, method, res, summary))
        self.recolour()
        self.glyphs()
        self.pick()

    def recolour(self) -> None:
        if self._falling_back:  # the state's field set back to H by the recolour under way
            return
        if self.preview is not None:  # a field change during a preview colours the preview
            self._colour_preview()
            return
        out = self.output
        if out is None:
            self._colour_source()
            return
        self.field_panel.set_available(set(out.fields) | set(out.request.source.field_specs))
        name = self._drawable_field(out)
        if is_file_field(name):
            self._colour_file(name, out.request.source, gen=out.gen)
            return
        spec = FIELDS[name]
        pairs = self._pairs()
        # border points (scan rims, holes) are drawn grey and kept out of the colour limits
        both = np.concatenate([_off_border(fields[name], res) for _, res, fields in pairs if fields and name in fields])
        look = self._look(name, both)
        clim, cmap = look.clim, look.cmap
        for scene, res, fields in pairs:
            scene.set_values(_off_border(fields[name], res, keep_shape=True), title=spec.title, cmap=cmap, clim=clim,
                             log=look.log)
        self.field_panel.show_limits(*clim)
        self.histogram.set_data(out.fields[name], clim=clim, cmap=cmap, label=spec.label)
        self.shown = {"field": name, "clim": clim, "cmap": cmap, "gen": out.gen}

    def glyphs(self) -> None:
        if self.output is None:
            return
        s = self.state
        for scene, res, _fields in self._pairs():
            for kind, key, arr in (("e1", "show_e1", res.e1), ("e2", "show_e2", res.e2),
                                   ("normals", "show_normals", res.normals)):
                scene.set_glyphs(kind, arr if s.get(key) else None, density=s.glyph_density,
                                 length=s.glyph_length, normals=res.normals)

    def pick(self) -> None:
        out, index = self.output, self.state.picked
        if out is None or index is None or not 0 <= index < len(out.points):
            self.inspector.clear()
            for scene in (self.scene, self.compare_scene):
                if scene is not None:
                    scene.set_highlight(None)
            return
        for scene, res, _fields in self._pairs():
            scene.set_highlight(index, _neighbours_of(res, index),
                                {"e1": res.e1[index], "e2": res.e2[index], "n": res.normals[index]})
        self.inspector.show_point(point_info(out, index))

    def set_point_size(self, size: float) -> None:
        for scene in (self.scene, self.compare_scene):
            if scene is not None:
                scene.set_point_size(size)
        self.glyphs()  # they float over the sprites' tops: bigger sprites, higher glyphs
        self.pick()


def _unavailable_text(name: str, source) -> str:
    """Why field ``name`` is not drawn for ``source``, and what is."""
    spec = FIELDS.get(name)
    own = ", ".join(getattr(source, "field_specs", None) or ()) or "none"
    why = {"truth": "it has no ground truth (only the synthetic shapes have one)",
           "reference": "it has no reference normals (the file has none)"}.get(getattr(spec, "needs", None),
                                                                            "the result has no such field")
    if is_file_field(name):
        why = f"it has no such field of its own (its own: {own})"
    label = spec.label if spec is not None else file_fields.RGB_LABEL if name == "rgb" else repr(name)
    name = getattr(source, "name", "this cloud")
    return f"{label} is not available for {name}: {why}; showing {FIELDS['mean'].label}."


def _neighbours_of(res, index: int):
    """Indices of the neighbours point ``index`` was fitted with (None: no estimate there)."""
    graph = getattr(res, "neighbours", None)  # None: a degenerate cloud has no neighbourhoods
    k = min(int(res.k_point[index]), graph.k_max) if graph is not None else 0  # a tiled result carries 16
    if k <= 0:
        return None
    return np.asarray(graph.rows(np.array([index]), k)[0][0])  # a lazy graph: one row searched


def _off_border(values, res, *, keep_shape=False):
    """``values`` without the result's border points (NaN there with ``keep_shape``)."""
    border = getattr(res, "border", None)
    if border is None or not np.any(border) or np.ndim(values) != 1:
        return values
    return np.where(border, np.nan, values) if keep_shape else np.asarray(values)[~border]


def point_info(out, index: int) -> dict:
    """Everything the inspector shows about one point."""
    res = out.result
    info = {
        "index": int(index),
        "position": out.points[index],
        "normal": res.normals[index],
        "k1": res.k1[index],
        "k2": res.k2[index],
        "e1": res.e1[index],
        "e2": res.e2[index],
        "gaussian": out.fields["gaussian"][index],
        "mean": out.fields["mean"][index],
        "shape_index": out.fields["shape_index"][index],
        "curvedness": out.fields["curvedness"][index],
        "valid": bool(np.asarray(res.valid)[index]),
    }
    if degenerate(res):
        info["no_estimate"] = degenerate(res)
    sample = out.request.source.sample
    if sample is not None:
        k1, k2 = float(sample.k1[index]), float(sample.k2[index])
        info.update(true_k1=k1, true_k2=k2, true_mean=0.5 * (k1 + k2), true_gaussian=k1 * k2)
    if out.request.source.fields:
        info["file"] = file_fields.point_values(out.request.source.fields, index)
    return info


