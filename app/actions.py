"""What the user does through menus, dialogs and drag-and-drop (a mixin of MainWindow).

GUI thread. Files are read and shapes generated on the loader's job thread
(:mod:`app.loader`); :meth:`WindowActions.open_file` returns at once with a ticket
and the cloud is swapped in when it arrives.
"""

from __future__ import annotations

import re
from pathlib import Path

from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QFileDialog, QMenu, QMenuBar, QMessageBox
from pyvistaqt import QtInteractor

import core.io
import core.shapes
from core.io.atomic import refuse_input_as_output

from . import DEFAULT_CLOUD, big_result
from .exporter import ResultExporter
from .presenter import result_parameters
from .text import safe_text
from .widgets import RecentFilesMenu, ShapeDialog

__all__ = ["DockToggle", "WindowActions", "read_filter", "write_filter", "with_default_suffix"]

#: what a screenshot and an export are written as when their name has no suffix
SCREENSHOT_SUFFIX, EXPORT_SUFFIX = ".png", ".ply"


class DockToggle(QAction):
    """A checkable action that shows and hides ``dock``, held from Python: what
    ``dock.toggleViewAction()`` gives, but that getter once returned a stale wrapper of
    another, deleted object (a QSurface) at the same address (PySide6; a newcomer run:
    ``QMenu.addAction(QSurface)``, and every later window test erred), as ``combo.model()``
    did before (:class:`app.widgets.field_panel.FieldPanel`). Checked while the dock is not
    hidden (a tab behind another stays checked); shown, it is raised."""

    def __init__(self, dock, parent, text=None):
        super().__init__(dock.windowTitle() if text is None else text, parent)
        self._dock = dock
        self.setCheckable(True)
        self.setChecked(not dock.isHidden())
        self.triggered.connect(self._show)
        dock.visibilityChanged.connect(self._follow)  # a bound slot: disconnected with this action

    def _show(self, on: bool) -> None:
        self._dock.setVisible(on)
        if on:
            self._dock.raise_()

    def _follow(self, _visible: bool) -> None:
        self.setChecked(not self._dock.isHidden())


def write_filter() -> str:
    return ";;".join(f"{desc} (*{ext if ext.startswith('.') else '.' + ext})"
                     for ext, desc in core.io.WRITE_FORMATS.items())


def with_default_suffix(path, suffix: str) -> Path:
    """``path`` with ``suffix`` added when its name has none (as Qt applications do); an
    existing directory is left as it is (its error names it)."""
    path = Path(path)
    return path if path.suffix or path.is_dir() else path.with_name(path.name + suffix)


def filter_suffix(name_filter: str, default: str) -> str:
    """The first suffix of a dialog's name filter, "PNG (*.png)" -> ".png"."""
    found = re.search(r"\(\*(\.\w+)", name_filter or "")
    return found.group(1) if found else default


def read_filter() -> str:
    exts, described = [], []
    for ext, desc in core.io.READ_FORMATS.items():
        ext = ext if ext.startswith(".") else f".{ext}"
        exts.append(f"*{ext}")
        described.append(f"{desc} (*{ext})")
    return ";;".join([f"Point clouds ({' '.join(exts)})", *described, "All files (*)"])


class WindowActions:
    """Menus, file and shape loading, export, screenshots, drag-and-drop."""

    def _build_menus(self) -> None:
        """The menu bar, its menus and actions, all created and held here (see :class:`DockToggle`)."""
        self.menu_bar = QMenuBar(self)
        self.setMenuBar(self.menu_bar)
        menu = self.add_menu("&File")
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

        menu = self.shapes_menu = self.add_menu("&Shapes")
        for name in core.shapes.SHAPES:
            self._action(menu, name.capitalize(), lambda _=False, n=name: self.load_shape(n))
        menu.addSeparator()
        self._action(menu, "&Generate…", self.shape_dialog)

        menu = self.add_menu("&View")
        self._action(menu, "&Fit view", self.fit_view, "F")
        self._action(menu, "&Reset camera", self.reset_view, "R")
        self._action(menu, "&Clear picked point", lambda: self.state.set(picked=None), "Esc")
        self._action(menu, "Estimate &again", self.request_estimate, "F5")
        self.eye_dome_action = self._action(menu, "&Eye-dome lighting (scans)",
                                            lambda: self.state.set(eye_dome=self.eye_dome_action.isChecked()), "E")
        self.eye_dome_action.setCheckable(True)
        self.scanners_action = self._action(menu, "Scanner &positions (E57, PTX)",
                                            lambda: self.state.set(scanners=self.scanners_action.isChecked()))
        self.scanners_action.setCheckable(True)
        self.scanners_action.setEnabled(False)  # until a cloud with scanner positions is shown
        menu.addSeparator()
        for dock in (self.controls_dock, self.histogram_dock, self.inspector_dock):
            menu.addAction(DockToggle(dock, self))

        menu = self.add_menu("&Help")
        self._action(menu, "&About Darboux", self._about)

    def add_menu(self, title) -> QMenu:
        """A menu of the menu bar, held from Python (see :class:`DockToggle`)."""
        menu = QMenu(title, self)
        self.menu_bar.addMenu(menu)
        return menu

    def _action(self, menu, text, slot, shortcut=None) -> QAction:
        action = QAction(text, self)
        if shortcut is not None:
            action.setShortcut(QKeySequence(shortcut))
        action.triggered.connect(lambda *_: slot())
        menu.addAction(action)
        return action

    # -- loading (answers arrive in _on_loaded / _on_load_failed) -------------------
    def open_file(self, path, *, remember: bool = True):
        """Read a file on the loader thread; the current cloud, and its estimate, stay until
        it arrives (a file that cannot be read leaves them as they were)."""
        if big_result.wants(path):  # a stored result larger than the budget: a level-of-detail view
            return big_result.view_of(self).open(path, remember=remember)
        ticket = self.loader.open_file(path, remember=remember)
        self.status_label.setText(f"reading {ticket.label}…")
        self.progress.set_progress(-1.0, "reading…")
        return ticket

    def open_default(self):
        """Open the bundled real scan (the Stanford bunny)."""
        return self.open_file(DEFAULT_CLOUD, remember=False)

    def load_shape(self, name: str, n: int | None = None):
        """Generate a shape on the loader thread; the current cloud and its estimate stay until it arrives."""
        self.shape_count = n = int(n or self.shape_count)
        ticket = self.loader.make_shape(name, n)
        self.status_label.setText(f"generating {ticket.label}…")
        self.progress.set_progress(-1.0, "generating…")
        return ticket

    def _on_loaded(self, ticket, source) -> None:
        if self._closed:
            return
        if ticket.remember and ticket.path is not None and safe_text(ticket.path) == ticket.path:
            # (a name that is not valid UTF-8 cannot round-trip through QSettings: not remembered)
            path = Path(ticket.path)
            self.recent_menu.add(path)
            self.settings.setValue("last_dir", safe_text(path.resolve().parent))
        self.estimator.abandon()  # the cloud it estimates is replaced now, not at the open (a read may fail)
        self.set_source(source)
        for note in source.notes:  # what the reader warned about (e.g. columns not taken for normals)
            self.notifier.warning(note)
        if source.notes:  # about the cloud itself: it stays over the cloud's first result
            self._message_gen = self.estimator.generation + 1

    def _on_load_failed(self, ticket, message: str, detail: str) -> None:
        """The current cloud stays, with its estimate (running or done) and preview."""
        if self._closed:
            return
        self.notifier.notify("error", f"Could not open the file. {message}", detail)
        self._show_status()

    def open_dialog(self) -> None:
        start = self.settings.value("last_dir", str(Path.home()))
        path, _ = QFileDialog.getOpenFileName(self, "Open point cloud", str(start), read_filter())
        if path:
            self.open_file(path)

    def shape_dialog(self) -> None:
        dialog = ShapeDialog(list(core.shapes.SHAPES), count=self.shape_count, parent=self)
        if dialog.exec():
            self.load_shape(dialog.shape, dialog.count)

    # -- export ---------------------------------------------------------------------
    def export_result(self, path, default_suffix: str = EXPORT_SUFFIX, *, background: bool = False) -> Path | None:
        """Write the last full result to ``path`` (File > Export), ``default_suffix`` added to
        a name without one; the path written, or None (refused or failed: the user is told).

        While a preview is on screen (its full result still computing) the preview is not
        written: it is an approximation on a subsample, like a display-only state in
        CloudCompare, which saves the entities as they are. The last full result is written
        and the notification says so, with that result's parameters.

        ``background`` (the dialog's): written on the exporter's job thread (:mod:`app.exporter`;
        a 1M-point CSV took 19 s of GUI thread); the path is returned at once, the
        notification comes once the file is written.
        """
        out = self.output
        if out is None:
            self.notifier.warning("Nothing to export yet: wait for the estimate to finish"
                                  + (" (a preview is not exported)." if self.presenter.preview is not None else "."))
            return None
        source = self.state.source
        path = with_default_suffix(path, default_suffix)
        asked = (path, out, self.presenter.preview is not None)
        try:  # never over the file the cloud came from (a symlink or hard link to it included), as the CLI
            refuse_input_as_output([source.path] if source is not None and source.path is not None else [], path)
            if background:
                self._result_exporter().write(path, out.result, tag=asked)
                self.notifier.info(f"Exporting {len(out.points):,} points to {path}…")
                return path
            written = core.io.write_result(path, out.result)
        except Exception as exc:  # noqa: BLE001
            self._export_failed(asked, exc)
            return None
        self._exported(asked, Path(written))
        return Path(written)

    _exporter = None

    def _result_exporter(self) -> ResultExporter:
        if self._exporter is None:
            self._exporter = ResultExporter()
            self._exporter.written.connect(self._exported)
            self._exporter.failed.connect(self._export_failed)
        return self._exporter

    def _exported(self, asked, written: Path) -> None:
        _path, out, preview = asked
        if preview:
            self.notifier.warning(f"Exported to {written}: the preview on screen is not exported; exported the last "
                                  f"full result: {result_parameters(out)}")
        else:
            self.notifier.info(f"Exported the result to {written}")

    def _export_failed(self, asked, exc, _detail: str = "") -> None:
        path = asked[0]
        text = str(exc) if str(path) in str(exc) else f"{path}: {exc}"  # core's messages name the file
        self.notifier.error(f"Could not export to {text}", exc)

    def export_dialog(self) -> None:
        start = Path(self.settings.value("last_dir", str(Path.home())))
        stem = Path(self.state.source.name).stem.split(" ")[0] if self.state.source else "result"
        path, chosen = QFileDialog.getSaveFileName(self, "Export result", str(start / f"{stem}-curvature.ply"),
                                                   write_filter())
        if path:
            self.export_result(path, filter_suffix(chosen, EXPORT_SUFFIX), background=True)

    def save_screenshot(self, path, *, whole_window: bool = False) -> bool:
        """Save a PNG of the 3D view(s), or of the whole window (``grab`` renders the 3D views);
        a name without a suffix gets ".png"."""
        path = with_default_suffix(path, SCREENSHOT_SUFFIX)
        self.histogram.flush()  # a draw still waiting for its own turn (app/widgets/histogram.py)
        widget = self if whole_window else self.splitter
        for view in self.splitter.findChildren(QtInteractor):  # (a repaint held by the compare's relayout)
            view.setUpdatesEnabled(True)
        ok = widget.grab().save(str(path))
        if not ok:
            self.notifier.error(f"Could not write the screenshot {path}")
        return ok

    def screenshot_dialog(self) -> None:
        start = Path(self.settings.value("last_dir", str(Path.home())))
        path, _ = QFileDialog.getSaveFileName(self, "Save screenshot", str(start / "darboux.png"), "PNG (*.png)")
        if path:
            self.save_screenshot(path)

    def _about(self) -> None:
        QMessageBox.about(
            self, "About Darboux",
            "<b>Darboux</b> — differential geometry of unorganized point clouds.<br>"
            "Normal fitting and refinement after Cheng &amp; Zhang (2009).<br><br>"
            "Bundled data: the Stanford Bunny, Stanford 3D Scanning Repository.",
        )

    # -- drag and drop ----------------------------------------------------------------
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
