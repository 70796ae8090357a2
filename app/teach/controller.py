"""The Teach mode's controller (GUI thread): listens to the window's results and pick, the
teach settings, and draws the overlays, the plots and the words.

Heavy cloud-wide maths (lines of curvature, point types, Gauss-Bonnet) runs on
:class:`CloudMathsWorker`; the picked point's :func:`core.local_fit` is a few hundred
neighbours and runs here. Every VTK call is on the GUI thread.
"""

from __future__ import annotations

import logging

import numpy as np
from matplotlib import colormaps
from PySide6.QtCore import QEvent, QObject, Signal

import core

from .cloudwork import CloudMathsWorker
from .dock import TeachSettings
from .overlays import (
    TYPE_COLOURS,
    OverlayLayer,
    dupin_mesh,
    frame_meshes,
    lines_mesh,
    normal_fit_meshes,
    section_meshes,
    surface_mesh,
)
from .text import cloud_text, point_text

__all__ = ["TeachController"]

LOG = logging.getLogger(__name__)

_LOCAL = ("frame", "surface", "sections", "dupin", "normal_fit")


def _share(mask) -> str:
    share = float(np.mean(mask))
    return f"{share:.0%}" if share >= 0.01 else "< 1%"


class TeachController(QObject):
    """Teach mode of one window.

    Signals
    -------
    ready : the overlays of the current result are all drawn (screenshots wait on it).
    """

    ready = Signal()

    def __init__(self, window, panel, settings: TeachSettings):
        super().__init__(window)
        self.window = window
        self.panel = panel
        self.settings = settings
        self.layer = OverlayLayer(window.plotter)
        self.worker = CloudMathsWorker(self)
        self.maths = None
        self.failure = None  # why the current result's cloud-wide maths gave nothing
        self.fit = None
        self._result = None
        self._gen = 0
        self._closed = False
        self._legend = False
        self.worker.done.connect(self._on_maths)
        self.worker.failed.connect(self._on_failed)
        settings.changed.connect(self._on_setting)
        window.result_shown.connect(self._on_result)
        window.state.changed.connect(self._on_state)
        window.installEventFilter(self)
        panel.tabs.currentChanged.connect(lambda _i: None if self._closed else self._draw_gauss_map())

    # -- inputs ---------------------------------------------------------------
    def eventFilter(self, obj, event):  # noqa: N802 - Qt API
        if obj is self.window and event.type() == QEvent.Type.Close:
            self.shutdown()
        return False

    @property
    def result(self):
        out = getattr(self.window, "output", None)
        return None if out is None else out.result

    def _on_result(self, _out=None) -> None:
        if self._closed or not self.settings.enabled:
            return
        res = self.result
        if res is None:
            return
        if res is not self._result:
            self._result = res
            self.maths, self.failure = None, None
            self._gen = self.worker.submit(res)
        self._draw_local()
        self._draw_cloud()

    def _on_state(self, name: str) -> None:
        if name == "picked" and self.settings.enabled and not self._closed:
            self._draw_local()
            self._draw_gauss_map()
            self.window.render_all()
        elif name == "point_size" and self.settings.enabled and not self._closed:
            self._draw_cloud()  # the lines float over the sprites' tops: bigger sprites, higher lines
            self.window.render_all()
        elif name == "source":
            self._forget()

    def _on_setting(self, name: str) -> None:
        if self._closed:
            return
        if name == "enabled" and not self.settings.enabled:
            self.layer.clear()
            self._set_legend(False)
            self.window.render_all()
            return
        if name == "enabled":
            self._on_result()
        elif name == "theta":
            self._draw_theta()
        else:
            self._draw_local()
            self._draw_cloud()
        self.window.render_all()

    def _on_maths(self, gen: int, maths) -> None:
        if self._closed or gen != self._gen:
            return
        self.maths = maths
        self._draw_cloud()
        self._draw_local()
        self.window.render_all()
        self.ready.emit()

    def _on_failed(self, gen: int, message: str) -> None:
        if gen == self._gen and not self._closed:
            self.failure = message
            self.panel.cloud_label.setText(cloud_text(None, message))
            self.window.notifier.error(f"Teach: the cloud-wide maths failed: {message}")
            self.ready.emit()

    def _forget(self) -> None:
        """A new cloud: nothing of the previous one stays on screen or in the panel."""
        self._result, self.maths, self.failure, self.fit = None, None, None, None
        self.layer.clear()
        self._set_legend(False)
        self.panel.cloud_label.setText("")
        self.panel.point_label.setText(point_text(None, self.settings.theta, None, None))
        self.panel.euler.show_fit(None, self.settings.theta)
        self.panel.gauss_map.show_map(None, None)

    def is_ready(self) -> bool:
        """True when the current result's cloud-wide maths are drawn, or have failed."""
        return (self.maths is not None or self.failure is not None) and self._result is self.result

    # -- the picked point ---------------------------------------------------------
    def _fit(self):
        res, index = self.result, self.window.state.picked
        if res is None or index is None or not 0 <= index < len(res.points) or not res.valid[index]:
            return None
        scale = self.maths.scale if self.maths is not None else None
        try:
            return core.local_fit(res, int(index), scale=scale)
        except ValueError as exc:
            LOG.debug("no local fit: %s", exc)
            return None

    def _draw_local(self) -> None:
        self.fit = fit = self._fit()
        for name in list(self.layer.names):
            if name.split("-")[0] in ("frame", "tangent", "surface", "section", "circle", "dupin", "normals"):
                self.layer.remove(name)
        self.panel.point_label.setText(point_text(fit, self.settings.theta, self.result, self.window.state.picked))
        self.panel.euler.show_fit(fit, self.settings.theta)
        if fit is None:
            return
        on = self.settings.overlays
        meshes = {}
        if "frame" in on:
            meshes.update(frame_meshes(fit))
        if "surface" in on:
            meshes["surface"] = (surface_mesh(fit), dict(color="#fdae6b", opacity=0.45, lighting=True))
        if "sections" in on:
            meshes.update(section_meshes(fit, np.radians(self.settings.theta)))
        if "dupin" in on:
            meshes["dupin"] = (dupin_mesh(fit), dict(color="#e7298a", line_width=3))
        if "normal_fit" in on:
            meshes.update(normal_fit_meshes(fit, 0.35 * fit.radius))
        for name, (mesh, style) in meshes.items():
            self.layer.show(name, mesh, style)

    def _draw_theta(self) -> None:
        fit = self.fit
        self.panel.point_label.setText(point_text(fit, self.settings.theta, self.result, self.window.state.picked))
        self.panel.euler.show_fit(fit, self.settings.theta)
        if fit is None or "sections" not in self.settings.overlays:
            return
        for name, (mesh, style) in section_meshes(fit, np.radians(self.settings.theta)).items():
            if name.endswith("theta") or name == "section-plane":
                self.layer.show(name, mesh, style)

    def focus(self) -> bool:
        """Turn the camera to the picked point: seen from above its tangent plane and 50 degrees
        off both normal sections' planes (so both osculating circles show as open ellipses),
        its neighbourhood filling a third of the view (GUI thread). False without a fit."""
        fit = self.fit
        if fit is None or self._closed:
            return False
        cam = self.window.plotter.camera
        direction = 0.65 * fit.normal + 0.5 * fit.e1 + 0.57 * fit.e2
        direction /= np.linalg.norm(direction)
        distance = 3.2 * fit.radius / np.tan(np.radians(cam.view_angle / 2))
        cam.focal_point = tuple(fit.origin)
        cam.position = tuple(fit.origin + distance * direction)
        cam.up = tuple(fit.e2 - direction * np.dot(fit.e2, direction))
        self.window.plotter.reset_camera_clipping_range()
        self.window.render_all()
        return True

    # -- the whole cloud ----------------------------------------------------------
    def _draw_cloud(self) -> None:
        maths, res, on = self.maths, self.result, self.settings.overlays
        self.panel.cloud_label.setText(cloud_text(maths, self.failure))
        lift = self.window.scene.overlay_lift()
        for key in ("e1", "e2"):
            mesh = lines_mesh(maths.lifted(key, lift)) if maths is not None and "lines" in on else None
            style = dict(color=self._colour(key), line_width=2.5, render_lines_as_tubes=False)
            self.layer.show(f"lines-{key}", mesh, style)
        if maths is not None and maths.types is not None and "types" in on and res is not None:
            self._draw_types(res, maths.types)
        else:
            self.layer.remove("types")
            self._set_legend(False)
        self._draw_gauss_map()

    @staticmethod
    def _colour(key: str) -> str:
        from ..glyphs import FRAME_COLOURS

        return FRAME_COLOURS[key]

    def _draw_types(self, res, types) -> None:
        import pyvista as pv

        rgb = np.array([[int(c[i:i + 2], 16) for i in (1, 3, 5)] for c in (*TYPE_COLOURS, "#b0b0b0")], np.uint8)
        cloud = pv.PolyData(np.asarray(res.points, dtype=float))
        cloud["type"] = rgb[np.where(types < 0, len(TYPE_COLOURS), types)]
        scene = self.window.scene  # the layer covers the cloud's sprites as they follow the zoom
        scene.sprite_layers["teach-types"] = 1.08
        size = scene.sprite_size * 1.08
        self.layer.show("types", cloud, dict(scalars="type", rgb=True, point_size=size,
                                             render_points_as_spheres=True, lighting=True))
        self._set_legend(True, types)

    def _set_legend(self, on: bool, types=None) -> None:
        plotter = self.window.plotter
        if self._legend:
            plotter.remove_legend(render=False)
            self._legend = False
        if on and types is not None:
            present = [i for i in range(len(core.TYPE_NAMES)) if np.any(types == i)]
            labels = [[f"{core.TYPE_NAMES[i]} ({_share(types == i)})", TYPE_COLOURS[i]] for i in present]
            plotter.add_legend(labels, bcolor="white", border=True, size=(0.2, 0.04 * (len(labels) + 1)),
                               loc="upper right", face="circle")
            self._legend = True

    def _draw_gauss_map(self) -> None:
        if self.panel.tabs.currentWidget() is not self.panel.gauss_map or not self.settings.enabled:
            return  # drawn when its tab is shown (a scatter of thousands of normals)
        res = self.result
        if res is None:
            self.panel.gauss_map.show_map(None, None)
            return
        highlight = self.fit.neighbours if self.fit is not None else None
        self.panel.gauss_map.show_map(res.normals, self._field_colours(), highlight, self.window.state.picked)

    def _field_colours(self):
        """RGBA per point as the main view colours it (field, limits, colour map on screen)."""
        out, shown = self.window.output, getattr(self.window, "shown", {}) or {}
        name = shown.get("field")
        if out is None or name not in out.fields:
            return None
        lo, hi = shown.get("clim", (0.0, 1.0))
        values = np.asarray(out.fields[name], dtype=float)
        t = np.clip((values - lo) / ((hi - lo) or 1.0), 0, 1)
        colours = colormaps[shown.get("cmap", "viridis")](np.nan_to_num(t, nan=0.5))
        colours[~np.isfinite(values)] = (0.69, 0.69, 0.69, 1.0)
        return colours

    # -- closing ---------------------------------------------------------------------
    def shutdown(self) -> None:
        """Idempotent: wait for the worker, forget the plotter (GUI thread)."""
        if self._closed:
            return
        self._closed = True
        self.worker.shutdown()
        self.layer.close()
