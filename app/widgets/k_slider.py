"""Slider for k, the number of neighbours of each point (bound to ``state.k``)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QCheckBox, QVBoxLayout, QWidget
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
        self.auto = QCheckBox("automatic k per point (NF/NR)")
        self.auto.setToolTip(
            "Choose k per point from the data (bias-variance rule, core.scale); the slider's k is used "
            "for the other methods. Show the choice with the field 'Neighbourhood size k'."
        )
        self.auto.setChecked(bool(state.k_auto))
        self.slider.setEnabled(not state.k_auto)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(box)
        layout.addWidget(self.auto)
        self.slider.valueChanged.connect(self._on_slider)
        self.auto.toggled.connect(self._on_auto)
        state.changed.connect(self._on_state)

    def _on_auto(self, checked: bool) -> None:
        self._state.set(k_auto=bool(checked))

    def _on_slider(self, value: int) -> None:
        self._state.set(k=int(value))

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name == "k":
            with blocked(self.slider):
                self.slider.setValue(int(value))
        elif name == "k_auto":
            with blocked(self.auto):
                self.auto.setChecked(bool(value))
            self.slider.setEnabled(not value)
