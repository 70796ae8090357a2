"""The docks' show/hide actions are held from Python (app.actions.DockToggle): what
QDockWidget.toggleViewAction() does, without fetching that action back through PySide6
(which once returned a stale wrapper of a deleted QSurface at the same address)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDockWidget, QLabel, QMainWindow

from app.actions import DockToggle


def test_the_action_shows_hides_and_follows_its_dock(qtbot):
    window = QMainWindow()
    qtbot.addWidget(window)
    front, back = QDockWidget("Front", window), QDockWidget("Back", window)
    for dock in (front, back):
        dock.setWidget(QLabel(dock.windowTitle()))
        window.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, dock)
    window.tabifyDockWidget(front, back)
    back.hide()
    show_front, show_back = DockToggle(front, window), DockToggle(back, window, "&Back panel")
    window.show()
    qtbot.waitExposed(window)
    assert show_front.text() == "Front" and show_back.text() == "&Back panel"
    assert show_front.isCheckable() and show_front.isChecked() and not show_back.isChecked()
    show_back.trigger()
    qtbot.waitUntil(back.isVisible)
    assert show_back.isChecked() and show_front.isChecked()
    front.raise_()  # back is now the tab behind: not hidden, still checked (as Qt's own action)
    qtbot.wait(50)
    assert show_back.isChecked() and not back.isHidden()
    show_back.trigger()
    assert back.isHidden() and not show_back.isChecked()
    front.close()  # closed by its own button: the action follows
    assert not show_front.isChecked()
