"""The main window: composition of the state, the widgets, the scene and the workers.

Everything here runs on the GUI thread. Data flow::

    widget --set--> ViewerState --changed--> MainWindow._on_state
        estimate keys  -> debounce (QTimer) -> EstimateRequest.from_state -> Estimator
        display keys   -> recolour / glyphs / highlight in the scene, right away
    CloudLoader.loaded  -> set_source (files are read on the loader thread)
    Estimator.preview   -> a fast first picture (app.preview), then
    Estimator.result    -> the full result (latest generation only) -> scene + panels

Menus, dialogs, export and drag-and-drop are in :class:`app.actions.WindowActions`; the
status line and the notifications over it in :class:`app.status.WindowStatus`.
"""

from __future__ import annotations

import logging

from PySide6.QtCore import QSettings, Qt, QTimer, Signal
from PySide6.QtGui import QIcon
from PySide6.QtWidgets import QLabel, QMainWindow, QMessageBox, QSplitter, QStatusBar

from . import ICON, _refguard
from .actions import WindowActions
from .big_result import is_stored
from .compiling import COMPILE_MESSAGE, CompileWatch
from .errors import Notifier
from .estimator import Estimator
from .layout import build_controls
from .loader import CloudLoader
from .persist import save_layout, save_state
from .presenter import ResultPresenter, preview_line
from .request import ESTIMATE_KEYS, EstimateRequest
from .scanners import show_scanners
from .scene import CloudScene, make_plotter
from .source import CloudSource
from .state import ViewerState
from .status import WindowStatus
from .views import WindowViews
from .teach import install_teach
from .theme import current_theme
from .widgets import CompareView, ElidedLabel, EstimateProgress
from .worker import EstimateOutput

__all__ = ["MainWindow", "DEBOUNCE_MS"]

LOG = logging.getLogger(__name__)

#: Slider moves within this many ms make one estimate (superqt's qdebounced uses 100).
DEBOUNCE_MS = 120

_DISPLAY_KEYS = {"field", "clim_auto", "clim", "clip_percent"}
_GLYPH_KEYS = {"show_e1", "show_e2", "show_normals", "glyph_density", "glyph_length"}


class MainWindow(WindowActions, WindowStatus, WindowViews, QMainWindow):
    """Darboux viewer window.

    Parameters
    ----------
    state : ViewerState, optional
        Parameters to start from (a fresh default state otherwise).
    settings : QSettings, optional
        Recent files, remembered parameters and layout (tests pass a throw-away ini file).
    dialogs : bool
        Show errors in a (non-modal) message box as well as in the status bar.

    Signals
    -------
    result_shown(EstimateOutput)
        After a full result has been drawn (the screenshot mode and the tests wait on it).
    preview_shown(EstimateOutput)
        After a fast preview has been drawn (the full result follows).
    """

    result_shown = Signal(object)
    preview_shown = Signal(object)

    def __init__(self, *, state: ViewerState | None = None, settings: QSettings | None = None,
                 notifier: Notifier | None = None, dialogs: bool = True, parent=None):
        super().__init__(parent)
        LOG.debug("PySide6 reference guard: %s", _refguard.guard())  # see app/_refguard.py
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
        self.loader = CloudLoader(self)
        self.compile_watch = CompileWatch(self)
        self._debounce = QTimer(self)
        self._debounce.setSingleShot(True)
        self._debounce.setInterval(DEBOUNCE_MS)
        self._debounce.timeout.connect(self.request_estimate)
        self._render_timer = QTimer(self)  # render_all: one repaint, after the current pass of the event loop
        self._render_timer.setSingleShot(True)
        self._render_timer.setInterval(0)
        self._render_timer.timeout.connect(self._repaint)
        self._build_views()
        build_controls(self)
        self.presenter = ResultPresenter(self.state, self.scene, field_panel=self.field_panel,
                                         histogram=self.histogram, inspector=self.inspector,
                                         notify=self.notifier.warning)
        # a changed histogram draws in a pass of the event loop after the 3D frame, not with it
        self._frame_due = self._compare_due = False
        self.histogram.frame_due = lambda: self._frame_due
        self._frame_tag = self.plotter.render_window.AddObserver("EndEvent", self._frame_done)
        self._build_status()
        self._build_menus()
        self._connect()
        self.apply_theme()
        self.teach = install_teach(self)
        if self.state.source is not None:
            self._on_source(self.state.source)
            self._debounce.start()

    # -- construction ---------------------------------------------------------
    def _build_views(self) -> None:
        self.plotter = make_plotter(self)
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

    def _build_status(self) -> None:
        bar = self.status_bar = QStatusBar(self)  # held from Python, not fetched (app.actions.DockToggle)
        self.setStatusBar(bar)
        self.status_label = ElidedLabel("No cloud")
        self.summary_label = ElidedLabel("")
        self.summary_label.setStyleSheet("color: #5a3d8a;")
        self.progress = EstimateProgress(idle=self.summary_label)  # the summary while idle, the progress while busy
        bar.addWidget(self.status_label, 1)
        bar.addPermanentWidget(self.progress)

    def _connect(self) -> None:
        est, load = self.estimator, self.loader
        self.state.changed.connect(self._on_state)
        est.result.connect(self._on_result)
        est.preview.connect(self._on_preview)
        est.failed.connect(self._on_failed)
        est.progress.connect(self.progress.set_progress)
        est.busy_changed.connect(self._on_busy)
        est.cancelled.connect(self._on_cancelled)
        load.loaded.connect(self._on_loaded)
        load.failed.connect(self._on_load_failed)
        load.busy_changed.connect(self._on_busy)
        self.progress.cancel_requested.connect(self.cancel)
        self.compile_watch.started.connect(lambda: self.progress.set_progress(-1.0, COMPILE_MESSAGE))
        self.notifier.notified.connect(self._show_notification)

    def apply_theme(self) -> None:
        """Follow the application palette (dark or light) in the 3D view(s) and histogram."""
        theme = current_theme()
        for scene in (self.scene, self.compare.scene if self.compare is not None else None):
            if scene is not None:
                scene.set_theme(theme)
        self.histogram.set_theme(theme)

    # -- state -> work ----------------------------------------------------------------
    def set_source(self, source: CloudSource) -> None:
        """Show a new cloud and estimate it (GUI thread)."""
        self.state.set(source=source, picked=None)

    def _on_state(self, name: str) -> None:
        if self._closed:
            return
        if name == "source":
            self._on_source(self.state.source)
        if name in ESTIMATE_KEYS:
            self._debounce.start()  # restarts: a burst of changes makes one request
            return
        handlers = {"picked": self.presenter.pick, "eye_dome": self._eye_dome, "scanners": self._scanners,
                    "point_size": lambda: self.presenter.set_point_size(self.state.point_size)}
        handlers.update(dict.fromkeys(_DISPLAY_KEYS, self.presenter.recolour))
        handlers.update(dict.fromkeys(_GLYPH_KEYS, self.presenter.glyphs))
        if name in handlers:
            handlers[name]()
            self.render_all()

    def request_estimate(self) -> EstimateRequest | None:
        """Send the current parameters to the worker (normally via the debounce timer)."""
        if self.state.source is None or self._closed or is_stored(self.state.source):
            return None  # (a stored result, app.big_result, is shown as it is)
        self._debounce.stop()
        return self.estimator.submit_request(EstimateRequest.from_state(self.state, self.estimator.next_gen()))

    def cancel(self) -> None:
        """Cancel button: idle at once; the shown result (if any) stays."""
        self.loader.cancel()
        if self.estimator.busy:
            self.estimator.cancel()  # its cancelled signal updates the status line
        else:
            self._show_status()

    def _on_source(self, source: CloudSource) -> None:
        self._clear_message()  # a notification about the previous cloud
        self.presenter.clear()
        self.scene.spacing = 1.0
        self.scene.set_cloud(source.points, reset_camera="oblique" if source.has_truth else "front",
                             geometry=source.geometry)
        self.scene.lod.hold(True)  # a big cloud: its stand-in until there are colours to show
        self.scene.set_title(f"{source.name}\nestimating…")
        self.setWindowTitle(f"Darboux — {source.name}")
        self.status_label.setText(f"{source.name}: {source.n_points:,} points — estimating…")
        self.normals_check.setEnabled(source.normals is not None)  # nothing to use otherwise
        self.summary_label.setText("")
        self.presenter.show_source(source)  # the file's own fields: listed, and drawn if chosen
        self._scanners()
        self.render_all()

    def _scanners(self) -> None:
        """Markers at the cloud's scanner positions (View › Scanner positions), where it has any."""
        at = getattr(self.state.source, "scanners", None)  # (a stored result, app.big_result, has none)
        self.scanners_action.setEnabled(at is not None and len(at) > 0)
        self.scanners_action.setChecked(bool(self.state.scanners))
        show_scanners(self.scene.plotter, at if self.state.scanners else None, self.scene.radius())

    def _eye_dome(self) -> None:
        on = bool(self.state.eye_dome)
        self.eye_dome_action.setChecked(on)
        self.scene.set_eye_dome(on)

    # -- results ------------------------------------------------------------------------
    @property
    def output(self):
        """The :class:`app.worker.EstimateOutput` on screen (full results only), or None."""
        return self.presenter.output

    @property
    def shown(self) -> dict:
        """Field, colour limits and colormap on screen."""
        return self.presenter.shown

    def _on_result(self, out: EstimateOutput) -> None:
        if self._closed or out.request.source is not self.state.source:
            return
        self._sync_compare(out.compare is not None)
        self.presenter.show(out)
        self._refit()
        self._clear_message(out.gen)
        self._show_status()
        self.render_all()
        self.result_shown.emit(out)

    def _on_preview(self, out: EstimateOutput) -> None:
        if self._closed or out.request.source is not self.state.source:
            return
        self.presenter.show_preview(out)
        self.status_label.setText(preview_line(out))
        self.render_all()
        self.preview_shown.emit(out)

    def _on_busy(self, _busy: int) -> None:
        self.progress.set_busy(self.estimator.busy or self.loader.pending is not None)

    def _on_pick(self, index: int) -> None:
        self.state.set(picked=int(index))

    # -- closing --------------------------------------------------------------------------------
    def closeEvent(self, event) -> None:  # noqa: N802
        """Stop the workers and close every plotter before Qt tears the widgets down."""
        self.shutdown()
        super().closeEvent(event)

    def shutdown(self) -> None:
        """Idempotent: remember the settings, stop timers and workers, close plotters and dialogs.

        Takes at most ~0.8 s: a job that does not reach a cancel check in time is
        abandoned on its daemon thread (its answer goes nowhere).
        """
        if self._closed:
            return
        self._closed = True
        save_state(self.state, self.settings)
        save_layout(self, self.settings)
        self.settings.sync()  # on disk now: the process may end without destructors (app.__main__.run)
        self._debounce.stop()
        self.teach.shutdown()
        self._render_timer.stop()
        self.plotter.render_window.RemoveObserver(self._frame_tag)
        self.compile_watch.close()
        self.loader.shutdown()
        self.estimator.shutdown()
        if self._exporter is not None:
            self._exporter.shutdown()  # a file being written is finished first
        for box in list(self._boxes):
            box.close()
        self._boxes.clear()
        if self.compare is not None:
            self.compare.close_view()
        self.scene.close()
        self.plotter.close()
        _refguard.forget_surface(self.plotter)
        self._pinned = _refguard.pinned_children(self)  # Qt may now delete the widgets safely
