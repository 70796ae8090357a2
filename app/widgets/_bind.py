"""Helpers shared by the widgets (GUI thread)."""

from __future__ import annotations

import contextlib

from PySide6.QtCore import QSignalBlocker
from PySide6.QtWidgets import QHBoxLayout, QLabel, QVBoxLayout, QWidget


@contextlib.contextmanager
def blocked(*objects):
    """Block the signals of ``objects`` while updating them from the state."""
    blockers = [QSignalBlocker(o) for o in objects]
    try:
        yield
    finally:
        for b in blockers:
            b.unblock()


def labelled(title: str, widget: QWidget, tooltip: str = "", *, vertical: bool = True) -> tuple[QWidget, QLabel]:
    """``widget`` under (or beside) a caption, as one widget."""
    box = QWidget()
    layout = QVBoxLayout(box) if vertical else QHBoxLayout(box)
    layout.setContentsMargins(0, 0, 0, 0)
    layout.setSpacing(2)
    label = QLabel(title)
    layout.addWidget(label)
    layout.addWidget(widget)
    if tooltip:
        box.setToolTip(tooltip)
        widget.setToolTip(tooltip)
    return box, label
