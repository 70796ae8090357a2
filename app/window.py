"""The main window: composition of the state, the widgets, the scene and the worker.

Everything here runs on the GUI thread. Data flow::

    widget --set--> ViewerState --changed--> MainWindow._on_state
        estimate keys  -> debounce (QTimer) -> Estimator.submit(frozen request, gen id)
        display keys   -> recolour / glyphs / highlight in the scene, right away
    Estimator.result (latest generation only) -> MainWindow._on_result -> scene + panels
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtGui import QAction, QIcon, QKeySequence
from PySide6.QtWidgets import (
    QDockWidget,
    QFileDialog,
    QGroupBox,
    QLabel,
    QMainWindow,
    QMessageBox,
    QScrollArea,
    QSplitter,
    QVBoxLayout,
    QWidget,
)
from pyvistaqt import QtInteractor

from . import DEFAULT_CLOUD, ICON, _refguard
from .errors import Notifier
from .presenter import ResultPresenter, status_line, summary_line
from .scene import CloudScene
from .source import CloudSource, load_file, make_shape
from .state import ESTIMATE_KEYS, ViewerState
from .teach import install_teach
from .widgets import (
    CompareView,
    EstimateProgress,
    FieldPanel,
    GlyphControls,
    Histogram,
    KSlider,
    MethodCombo,
    NoiseSlider,
    PassesSlider,
    PointInspector,
    RecentFilesMenu,
    ShapeDialog,
    StateCheckBox,
)
from .worker import Estimator, EstimateOutput

__all__ = ["MainWindow", "DEBOUNCE_MS"]

LOG = logging.getLogger(__name__)

#: Slider moves within this many ms make one estimate.
DEBOUNCE_MS = 120

_DISPLAY_KEYS = {"field", "clim_auto", "clim", "clip_percent"}
_GLYPH_KEYS = {"show_e1", "show_e2", "show_normals", "glyph_density", "glyph_length"}


def _group(title: str, *widgets) -> QGroupBox:
    box = QGroupBox(title)
    layout = QVBoxLayout(box)
    layout.setContentsMargins(6, 6, 6, 6)
    for w in widgets:
        layout.addWidget(w)
    return box


def _write_filter() -> str:
    import core.io

    return ";;".join(f"{desc} (*{ext if ext.startswith('.') else '.' + ext})"
                     for ext, desc in core.io.WRITE_FORMATS.items())


def _read_filter() -> str:
    import core.io

    exts = []
    described = []
    for ext, desc in core.io.READ_FORMATS.items():
        ext = ext if ext.startswith(".") else f".{ext}"
        exts.append(f"*{ext}")
        described.append(f"{desc} (*{ext})")
    return ";;".join([f"Point clouds ({' '.join(exts)})", *described, "All files (*)"])


class MainWindow(QMainWindow):
    """Darboux viewer window.

    Parameters
    ----------
    state : ViewerState, optional
        Parameters to start from (a fresh default state otherwise).
    settings : QSettings, optional
        Where recent files live (tests pass a throw-away ini file).
    dialogs : bool
        Show errors in a (non-modal) message box as well as in the status bar.

    Signals
    -------
    result_shown(EstimateOutput)
        After a result has been drawn (the screenshot mode and the tests wait on it).
    """

    result_shown = Signal(object)

    def __init__(self, *, state: ViewerState | None = None, settings: QSettings | None = None,
                 notifier: Notifier | None = None, dialogs: bool = True, parent=None):
        super().__init__(parent)
        guarded = _refguard.guard()  # PySide6 6.12 refcount bug: see app/_refguard.py
        LOG.debug("PySide6 reference guard: %s", guarded)
        self.setWindowTitle("Darboux — point-cloud curvature")
        if ICON.exists():
            self.setWindowIcon(QIcon(str(ICON)))
        self.resize(1440, 900)
        self.setAcceptDrops(True)
        self.state = state if state is not None else ViewerState()
        self.state.setParent(self)
        self.notifier = notifier if notifier is not None else Notifier(self)
        self.settings = settings if settings is not None else QSettings("Darboux", "darboux")
        self.dialogs = dialogs
        self.shape_count = 5000
        self._closed = False
        self._boxes: list[QMessageBox] = []

        self.estimator = Estimator(self)
        self._debounce = QTimer(self)
        self._debounce.setSingleShot(True)
        self._debounce.setInterval(DEBOUNCE_MS)
        self._debounce.timeout.connect(self.request_estimate)

        self._build_views()
        self._build_controls()
        self.presenter = ResultPresenter(self.state, self.scene, field_panel=self.field_panel,
                                         histogram=self.histogram, inspector=self.inspector)
        self._build_status()
        self._build_menus()

        self.state.changed.connect(self._on_state)
        self.estimator.result.connect(self._on_result)
        self.estimator.failed.connect(self._on_failed)
        self.estimator.progress.connect(self.progress.set_progress)
        self.estimator.busy_changed.connect(self.progress.set_busy)
        self.estimator.cancelled.connect(self._on_cancelled)
        self.progress.cancel_requested.connect(self.estimator.cancel)
        self.notifier.notified.connect(self._show_notification)
        self.teach = install_teach(self)
        if self.state.source is not None:
            self._on_source(self.state.source)
            self._debounce.start()

    # -- construction ---------------------------------------------------------
    def _build_views(self) -> None:
        self.plotter = QtInteractor(self, auto_update=False)
        self.plotter.setAcceptDrops(False)  # the window handles drops
        self.plotter.setMinimumSize(320, 240)
        self.scene = CloudScene(self.plotter)
        self.scene.point_size = self.state.point_size
        self.scene.enable_picking(self._on_pick)
        self.compare: CompareView | None = None
        self.splitter = QSplitter(Qt.Orientation.Horizontal)
        self.splitter.setChildrenCollapsible(False)
        self.splitter.addWidget(self.plotter)
        self.setCentralWidget(self.splitter)

    def _build_controls(self) -> None:
        s = self.state
        self.method_combo = MethodCombo(s)
        self.k_slider = KSlider(s)
        self.passes_slider = PassesSlider(s)
        self.noise_slider = NoiseSlider(s)
        self.normals_check = StateCheckBox(
            s, "use_input_normals", "Use the cloud's normals",
            "Start from the normals stored in the file (or the shape's exact normals) instead of estimating them",
        )
        self.compare_combo = MethodCombo(s, key="compare_method")
        self.compare_combo.setToolTip("Show a second method side by side (linked cameras)")
        self.field_panel = FieldPanel(s)
        self.histogram = Histogram()
        self.glyph_controls = GlyphControls(s)
        self.inspector = PointInspector()

        compare_row = QWidget()
        row = QVBoxLayout(compare_row)
        row.setContentsMargins(0, 0, 0, 0)
        row.addWidget(QLabel("Compare with"))
        row.addWidget(self.compare_combo)

        panel = QWidget()
        layout = QVBoxLayout(panel)
        layout.setContentsMargins(4, 4, 4, 4)
        layout.addWidget(_group("Estimate", self.method_combo, self.k_slider, self.passes_slider,
                                self.noise_slider, self.normals_check, compare_row))
        layout.addWidget(_group("Colour", self.field_panel))
        layout.addWidget(_group("Glyphs", self.glyph_controls))
        layout.addStretch(1)
        scroll = QScrollArea()
        scroll.setWidget(panel)
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        scroll.setMinimumWidth(panel.minimumSizeHint().width() + scroll.verticalScrollBar().sizeHint().width() + 4)
        self.controls_dock = QDockWidget("Controls", self)
        self.controls_dock.setObjectName("controls")
        self.controls_dock.setWidget(scroll)
        self.controls_dock.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetMovable
                                       | QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        self.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, self.controls_dock)
        self.histogram_dock = self._dock("Histogram", self.histogram, Qt.DockWidgetArea.LeftDockWidgetArea)
        self.inspector_dock = self._dock("Picked point", self.inspector, Qt.DockWidgetArea.LeftDockWidgetArea)
        self.resizeDocks([self.histogram_dock], [270], Qt.Orientation.Horizontal)
        self.resizeDocks([self.histogram_dock, self.inspector_dock], [260, 500], Qt.Orientation.Vertical)

    def _dock(self, title: str, widget: QWidget, area) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(title.lower().replace(" ", "_"))
        dock.setWidget(widget)
        dock.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetMovable
                         | QDockWidget.DockWidgetFeature.DockWidgetFloatable
                         | QDockWidget.DockWidgetFeature.DockWidgetClosable)
        self.addDockWidget(area, dock)
        return dock

    def _build_status(self) -> None:
        bar = self.statusBar()
        self.status_label = QLabel("No cloud")
        self.summary_label = QLabel("")
        self.summary_label.setStyleSheet("color: #5a3d8a;")
        self.progress = EstimateProgress()
        bar.addWidget(self.status_label, 1)
        bar.addPermanentWidget(self.summary_label)
        bar.addPermanentWidget(self.progress)

    def _build_menus(self) -> None:
        import core.shapes

        menu = self.menuBar().addMenu("&File")
        self._action(menu, "&Open…", self.open_dialog, QKeySequence.StandardKey.Open)
        self.recent_menu = RecentFilesMenu(self.settings, self)
        self.recent_menu.open_requested.connect(self.open_file)
        menu.addMenu(self.recent_menu)
        self._action(menu, "Open the &bundled bunny", self.open_default)
        menu.addSeparator()
        self._action(menu, "&Export result…", self.export_dialog, "Ctrl+E")
        self._action(menu, "Save &screenshot…", self.screenshot_dialog, "Ctrl+Shift+S")
        menu.addSeparator()
        self._action(menu, "&Quit", self.close, QKeySequence.StandardKey.Quit)

        menu = self.menuBar().addMenu("&Shapes")
        for name in core.shapes.SHAPES:
            self._action(menu, name.capitalize(), lambda _=False, n=name: self.load_shape(n))
        menu.addSeparator()
        self._action(menu, "&Generate…", self.shape_dialog)

        menu = self.menuBar().addMenu("&View")
        self._action(menu, "&Reset camera", lambda: (self.scene.reset_camera(self.scene.view), self.plotter.render()), "R")
        self._action(menu, "&Clear picked point", lambda: self.state.set(picked=None), "Esc")
        menu.addSeparator()
        for dock in (self.controls_dock, self.histogram_dock, self.inspector_dock):
            menu.addAction(dock.toggleViewAction())

        menu = self.menuBar().addMenu("&Help")
        self._action(menu, "&About Darboux", self._about)

    def _action(self, menu, text, slot, shortcut=None) -> QAction:
        action = QAction(text, self)
        if shortcut is not None:
            action.setShortcut(QKeySequence(shortcut))
        action.triggered.connect(lambda *_: slot())
        menu.addAction(action)
        return action

    # -- loading ------------------------------------------------------------------
    def set_source(self, source: CloudSource) -> None:
        """Show a new cloud and estimate it (GUI thread)."""
        self.state.set(source=source, picked=None)

    def open_file(self, path, *, remember: bool = True) -> bool:
        """Load a file; on failure the user is told and the current cloud stays."""
        import core.io

        path = Path(path)
        try:
            source = load_file(path)
        except (core.io.CloudFileError, OSError, ValueError) as exc:
            message = str(exc) if str(path.name) in str(exc) else f"{path}: {exc}"
            self.notifier.error(f"Could not open the file. {message}")
            return False
        except Exception as exc:  # noqa: BLE001 - a reader bug must not take the app down
            self.notifier.error(f"Could not open {path}: {type(exc).__name__}: {exc}", exc)
            return False
        if remember:
            self.recent_menu.add(path)
            self.settings.setValue("last_dir", str(path.resolve().parent))
        self.set_source(source)
        return True

    def open_default(self) -> bool:
        """Open the bundled real scan (the Stanford bunny)."""
        return self.open_file(DEFAULT_CLOUD, remember=False)

    def load_shape(self, name: str, n: int | None = None) -> None:
        n = int(n or self.shape_count)
        self.shape_count = n
        try:
            self.set_source(make_shape(name, n))
        except Exception as exc:  # noqa: BLE001
            self.notifier.error(f"Could not generate {name}: {exc}", exc)

    def open_dialog(self) -> None:
        start = self.settings.value("last_dir", str(Path.home()))
        path, _ = QFileDialog.getOpenFileName(self, "Open point cloud", str(start), _read_filter())
        if path:
            self.open_file(path)

    def shape_dialog(self) -> None:
        import core.shapes

        dialog = ShapeDialog(list(core.shapes.SHAPES), count=self.shape_count, parent=self)
        if dialog.exec():
            self.load_shape(dialog.shape, dialog.count)

    # -- export -------------------------------------------------------------------
    def export_result(self, path) -> Path | None:
        import core.io

        if self.output is None:
            self.notifier.warning("Nothing to export yet: wait for the estimate to finish.")
            return None
        try:
            written = core.io.write_result(path, self.output.result)
        except Exception as exc:  # noqa: BLE001
            self.notifier.error(f"Could not export to {path}: {exc}", exc)
            return None
        self.notifier.info(f"Exported the result to {written}")
        return Path(written)

    def export_dialog(self) -> None:
        start = Path(self.settings.value("last_dir", str(Path.home())))
        stem = Path(self.state.source.name).stem.split(" ")[0] if self.state.source else "result"
        path, _ = QFileDialog.getSaveFileName(self, "Export result", str(start / f"{stem}-curvature.ply"),
                                              _write_filter())
        if path:
            self.export_result(path)

    def save_screenshot(self, path, *, whole_window: bool = False) -> bool:
        """Save a PNG of the 3D view(s), or of the whole window."""
        self.render_all()
        widget = self if whole_window else self.splitter
        ok = widget.grab().save(str(path))
        if not ok:
            self.notifier.error(f"Could not write the screenshot {path}")
        return ok

    def screenshot_dialog(self) -> None:
        start = Path(self.settings.value("last_dir", str(Path.home())))
        path, _ = QFileDialog.getSaveFileName(self, "Save screenshot", str(start / "darboux.png"), "PNG (*.png)")
        if path:
            self.save_screenshot(path)

    # -- state -> work ----------------------------------------------------------------
    def _on_state(self, name: str) -> None:
        if self._closed:
            return
        if name == "source":
            self._on_source(self.state.source)
        if name in ESTIMATE_KEYS:
            self._debounce.start()  # restarts: a burst of changes makes one request
            return
        if name in _DISPLAY_KEYS:
            self.presenter.recolour()
        elif name in _GLYPH_KEYS:
            self.presenter.glyphs()
        elif name == "picked":
            self.presenter.pick()
        elif name == "point_size":
            self.presenter.set_point_size(self.state.point_size)
        else:
            return
        self.render_all()

    def request_estimate(self):
        """Send the current parameters to the worker (normally via the debounce timer)."""
        s = self.state
        if s.source is None or self._closed:
            return None
        return self.estimator.submit(
            s.source, k=s.k, k_auto=s.k_auto, method=s.method, passes=s.passes, noise=s.noise,
            use_input_normals=s.use_input_normals, compare_method=s.compare_method,
        )

    def _on_source(self, source: CloudSource) -> None:
        self.presenter.clear()
        self.scene.spacing = _rough_spacing(source.points)
        self.scene.set_cloud(source.points, reset_camera="oblique" if source.has_truth else "front")
        self.scene.set_title(f"{source.name}\nestimating…")
        self.setWindowTitle(f"Darboux — {source.name}")
        self.status_label.setText(f"{source.name}: {source.n_points:,} points — estimating…")
        self.summary_label.setText("")
        self.render_all()

    # -- results ------------------------------------------------------------------------
    @property
    def output(self):
        """The :class:`app.worker.EstimateOutput` on screen, or None."""
        return self.presenter.output

    @property
    def shown(self) -> dict:
        """Field, colour limits and colormap on screen."""
        return self.presenter.shown

    def _on_result(self, out: EstimateOutput) -> None:
        if self._closed or out.request.source is not self.state.source:
            return
        if out.compare is not None:
            self._show_compare()
        elif self.compare is not None and self.compare.isVisible():
            self.compare.hide()
            self.presenter.compare_scene = None
        self.presenter.show(out)
        self.status_label.setText(status_line(out))
        self.summary_label.setText(summary_line(out.summary, out.request.method))
        self.render_all()
        self.result_shown.emit(out)

    def _on_failed(self, message: str) -> None:
        self.notifier.error(f"The estimate failed: {message}")
        if self.output is None and self.state.source is not None:
            self.status_label.setText(f"{self.state.source.name}: estimate failed")

    def _on_cancelled(self, gen: int) -> None:
        if gen == self.estimator.generation and self.output is not None:
            self.statusBar().showMessage("Estimate cancelled; showing the previous result.", 5000)

    def _show_compare(self) -> None:
        """Create (once) and show the second view beside the main one."""
        if self.compare is None:
            self.compare = CompareView(self)
            self.compare.scene.point_size = self.state.point_size
            self.compare.hide()
            self.splitter.addWidget(self.compare)
            self.compare.link_to(self.plotter)
        self.presenter.compare_scene = self.compare.scene
        if not self.compare.isVisible():
            self.compare.show()
            half = max(self.splitter.width() // 2, 200)
            self.splitter.setSizes([half, half])
            QTimer.singleShot(0, self._refit_camera)  # the views got narrower: refit once laid out

    def _refit_camera(self) -> None:
        if not self._closed:
            self.scene.reset_camera(self.scene.view)
            self.render_all()

    def _on_pick(self, index: int) -> None:
        self.state.set(picked=int(index))

    def render_all(self) -> None:
        if self._closed:
            return
        self.plotter.render()
        if self.compare is not None and self.compare.isVisible():
            self.compare.plotter.render()

    # -- notifications ------------------------------------------------------------------
    def _show_notification(self, note) -> None:
        if self._closed:
            return
        colour = {"error": "#b2182b", "warning": "#b35806"}.get(note.level, "#333333")
        self.statusBar().setStyleSheet(f"QStatusBar {{ color: {colour}; }}")
        self.statusBar().showMessage(note.message, 15000 if note.level == "error" else 6000)
        QTimer.singleShot(15000, lambda: None if self._closed else self.statusBar().setStyleSheet(""))
        if note.level == "error" and self.dialogs:
            box = QMessageBox(QMessageBox.Icon.Critical, "Darboux", note.message, QMessageBox.StandardButton.Ok, self)
            if note.detail:
                box.setDetailedText(note.detail)
            box.setModal(False)
            box.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
            box.finished.connect(lambda _=0, b=box: self._boxes.remove(b) if b in self._boxes else None)
            self._boxes.append(box)
            box.show()

    def _about(self) -> None:
        QMessageBox.about(
            self, "About Darboux",
            "<b>Darboux</b> — differential geometry of unorganized point clouds.<br>"
            "Normal fitting and refinement after Cheng &amp; Zhang (2009).<br><br>"
            "Bundled data: the Stanford Bunny, Stanford 3D Scanning Repository.",
        )

    # -- drag and drop ----------------------------------------------------------------------
    def dragEnterEvent(self, event) -> None:  # noqa: N802
        urls = event.mimeData().urls() if event.mimeData().hasUrls() else []
        if any(u.isLocalFile() for u in urls):
            event.acceptProposedAction()
        else:
            event.ignore()

    def dropEvent(self, event) -> None:  # noqa: N802
        for url in event.mimeData().urls():
            if url.isLocalFile():
                event.acceptProposedAction()
                self.open_file(url.toLocalFile())
                return

    # -- closing --------------------------------------------------------------------------------
    def closeEvent(self, event) -> None:  # noqa: N802
        """Stop the worker and close every plotter before Qt tears the widgets down."""
        self.shutdown()
        super().closeEvent(event)

    def shutdown(self) -> None:
        """Idempotent: stop timers and the worker thread, close plotters and dialogs."""
        if self._closed:
            return
        self._closed = True
        self._debounce.stop()
        self.teach.shutdown()
        self.estimator.shutdown()
        for box in list(self._boxes):
            box.close()
        self._boxes.clear()
        if self.compare is not None:
            self.compare.close_view()
        self.scene.close()
        self.plotter.close()


def _rough_spacing(points: np.ndarray) -> float:
    """Mean nearest-neighbour distance from a sample (until the worker's exact value arrives)."""
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return 1.0
    sample = pts[np.random.default_rng(0).choice(len(pts), size=min(len(pts), 500), replace=False)]
    d, _ = cKDTree(pts).query(sample, k=2)
    return float(np.mean(d[:, 1])) or 1.0
