"""Light or dark colours for the 3D view and the histogram, following the Qt palette.

GUI thread. A desktop with a dark palette (``QPalette.Window`` darker than mid-grey)
gets a dark 3D background and light text, so the viewer does not glare white
inside a dark window (issue 10).
"""

from __future__ import annotations

from typing import NamedTuple

from PySide6.QtGui import QPalette
from PySide6.QtWidgets import QApplication

__all__ = ["Theme", "LIGHT", "DARK", "current_theme"]


class Theme(NamedTuple):
    name: str
    background: str  # 3D view and histogram background
    text: str  # titles, scalar bar, tick labels
    axes: str  # histogram frame and limit lines


LIGHT = Theme("light", "#ffffff", "#222222", "#444444")
DARK = Theme("dark", "#1e1f22", "#e6e6e6", "#bbbbbb")

#: Palette window colours darker than this (HSL lightness 0-255) count as dark.
_DARK_BELOW = 128


def current_theme(app: QApplication | None = None) -> Theme:
    """The theme matching the application's palette (light without an application)."""
    app = app or QApplication.instance()
    if app is None:
        return LIGHT
    colour = app.palette().color(QPalette.ColorRole.Window)
    return DARK if colour.lightness() < _DARK_BELOW else LIGHT
