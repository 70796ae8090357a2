"""File > Open Recent, kept in QSettings."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import QSettings, Signal
from PySide6.QtWidgets import QMenu

KEY = "recent_files"
MAX_RECENT = 8


class RecentFilesMenu(QMenu):
    """Most recent first; files that no longer exist are still listed (opening them
    shows the usual error) until they fall off the end."""

    open_requested = Signal(str)

    def __init__(self, settings: QSettings, parent=None):
        super().__init__("Open &Recent", parent)
        self._settings = settings
        self._rebuild()

    def paths(self) -> list[str]:
        value = self._settings.value(KEY, [])
        if isinstance(value, str):
            value = [value]
        return [str(v) for v in (value or [])]

    def add(self, path) -> None:
        path = str(Path(path).resolve())
        items = [p for p in self.paths() if p != path]
        self._settings.setValue(KEY, [path, *items][:MAX_RECENT])
        self._settings.sync()
        self._rebuild()

    def clear_all(self) -> None:
        self._settings.setValue(KEY, [])
        self._rebuild()

    def _rebuild(self) -> None:
        self.clear()
        paths = self.paths()
        for i, path in enumerate(paths, 1):
            action = self.addAction(f"&{i} {Path(path).name}")
            action.setToolTip(path)
            action.setStatusTip(path)
            action.triggered.connect(lambda _=False, p=path: self.open_requested.emit(p))
        if paths:
            self.addSeparator()
            self.addAction("Clear list", self.clear_all)
        self.setEnabled(bool(paths))
