"""The Teach mode of one window: its dock, menu, guided examples and figure export (GUI thread)."""

from __future__ import annotations

from html import escape
from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction
from PySide6.QtWidgets import QDockWidget, QFileDialog, QMenu

from ..actions import DockToggle
from .controller import TeachController
from .dock import TeachPanel, TeachSettings
from .examples import EXAMPLES, OVERLAYS, pick_for
from .plots import save_figure

__all__ = ["Teach", "OVERLAYS", "EXAMPLES"]


class Teach:
    """The Teach mode of one window: ``settings``, ``panel``, ``dock``, ``controller``."""

    def __init__(self, window):
        self.window = window
        self.settings = TeachSettings(window)
        self.panel = TeachPanel(self.settings)
        self.dock = QDockWidget("Teach", window)
        self.dock.setObjectName("teach")
        self.dock.setWidget(self.panel)
        window.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.dock)
        neighbour = getattr(window, "controls_dock", None)
        if neighbour is not None:  # a tab beside the controls: the whole column's height
            window.tabifyDockWidget(neighbour, self.dock)
        self.dock.hide()  # off by default
        self.controller = TeachController(window, self.panel, self.settings)
        self.dock.visibilityChanged.connect(self._on_visible)
        self.panel.export_requested.connect(self.export_dialog)
        self._pending_example = None
        self._focus = False
        window.result_shown.connect(self._on_result)
        self._build_menus()

    def _build_menus(self) -> None:
        menu = self.window.add_menu("&Teach")  # menus and actions held from Python (app.actions.DockToggle)
        self.toggle_action = DockToggle(self.dock, self.window, "&Teaching mode")
        self.toggle_action.setShortcut("Ctrl+T")
        menu.addAction(self.toggle_action)
        focus = QAction("&Zoom to the picked point", self.window)
        focus.setShortcut("Ctrl+F")
        focus.triggered.connect(self.controller.focus)
        menu.addAction(focus)
        menu.addSeparator()
        examples = QMenu("&Guided examples", self.window)
        menu.addMenu(examples)
        for key, example in EXAMPLES.items():
            action = QAction(example.title, self.window)
            action.triggered.connect(lambda _=False, k=key: self.run_example(k))
            examples.addAction(action)
        self.window.shapes_menu.addSeparator()
        self.window.shapes_menu.addMenu(examples)
        menu.addSeparator()
        export = QAction("&Export figures for slides…", self.window)
        export.triggered.connect(self.export_dialog)
        menu.addAction(export)

    def _on_visible(self, visible: bool) -> None:
        self.settings.set(enabled=visible)

    def configure(self, *, enabled: bool | None = None, overlays=None, theta: float | None = None,
                  focus: bool | None = None, example: str | None = None) -> None:
        """Set the mode from code or the command line (GUI thread): ``focus`` zooms to the
        picked point once the overlays are ready, ``example`` runs a guided example."""
        if focus is not None:
            self._focus = bool(focus)
        if example is not None:
            self.run_example(example)
        values = {k: v for k, v in (("overlays", overlays), ("theta", theta)) if v is not None}
        self.settings.set(**values)
        if enabled is not None:
            self.dock.setVisible(bool(enabled))
            if enabled:
                self.dock.raise_()
            self.settings.set(enabled=bool(enabled))

    def when_ready(self, callback) -> None:
        """Call ``callback()`` once the teaching overlays of the current result are drawn (at
        once when the mode is off); zoom to the picked point first if asked (GUI thread)."""
        controller = self.controller
        if not self.settings.enabled or controller.is_ready():
            if self._focus:
                controller.focus()
            callback()
            return

        def once():
            controller.ready.disconnect(once)
            self.when_ready(callback)

        controller.ready.connect(once)

    def run_example(self, key: str) -> None:
        """Load a guided example's shape, show its overlays and text, pick its point."""
        example = EXAMPLES[key]
        self.configure(enabled=True, overlays=example.overlays, theta=example.theta)
        self.panel.show_example(f"<b>{escape(example.title, quote=False)}</b><br>{escape(example.text, quote=False)}")  # "K < 0" is not a tag
        self._pending_example = example
        self.window.load_shape(example.shape)

    def _on_result(self, out) -> None:
        example, self._pending_example = self._pending_example, None
        if example is not None and out is not None:
            normals = out.result.normals
            self.window.state.set(picked=pick_for(example, out.points, normals))

    def export_figures(self, directory, stem: str = "darboux") -> list[Path]:
        """High-resolution PNG of the 3D view, Euler plot as SVG + PDF + PNG, Gauss map PNG."""
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        view = directory / f"{stem}-view.png"
        self.window.render_all()
        self.window.plotter.screenshot(str(view), scale=2, return_img=False)
        written = [view]
        for name, fig in (("euler", self.panel.euler.figure), ("gauss-map", self.panel.gauss_map.figure)):
            for suffix in ((".svg", ".pdf", ".png") if name == "euler" else (".png",)):
                written.append(save_figure(fig, directory / f"{stem}-{name}{suffix}"))
        return written

    def export_dialog(self) -> None:
        directory = QFileDialog.getExistingDirectory(self.window, "Export figures to")
        if directory:
            try:
                paths = self.export_figures(directory)
            except Exception as exc:  # noqa: BLE001
                self.window.notifier.error(f"Could not export the figures: {exc}", exc)
                return
            self.window.notifier.info(f"Saved {len(paths)} figures in {directory}")

    def shutdown(self) -> None:
        self.controller.shutdown()
