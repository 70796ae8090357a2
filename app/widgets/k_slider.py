"""Slider for k, the number of neighbours of each point (bound to ``state.k``)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QVBoxLayout, QWidget
from superqt import QLabeledSlider

from ._bind import blocked, labelled

K_MIN, K_MAX = 6, 64


class KSlider(QWidget):
    """k (neighbours, the point itself included). Writes ``state.k`` on every move;
    the window debounces the re-estimate."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self._state = state
        self.slider = QLabeledSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(K_MIN, max(K_MAX, int(state.k)))
        self.slider.setValue(state.k)
        box, _ = labelled(
            "Neighbours k", self.slider, "Number of nearest neighbours used by the fit (the point itself included)."
        )
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(box)
        self.slider.valueChanged.connect(self._on_slider)
        state.changed.connect(self._on_state)

    def _on_slider(self, value: int) -> None:
        self._state.set(k=int(value))

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name == "k":
            with blocked(self.slider):
                self.slider.setValue(int(value))
