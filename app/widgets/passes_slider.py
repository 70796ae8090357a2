"""Slider for the number of normal-refinement passes (bound to ``state.passes``)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QVBoxLayout, QWidget
from superqt import QLabeledSlider

from ._bind import blocked, labelled

PASSES_MAX = 5


def _uses_passes(method: str) -> bool:
    import core

    m = core.METHODS.get(method)
    return bool(getattr(m, "uses_passes", False))


class PassesSlider(QWidget):
    """NR refinement passes (0 = plain normal fitting, NF). Disabled for methods
    that do not use passes."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self._state = state
        self.slider = QLabeledSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, PASSES_MAX)
        self.slider.setValue(state.passes)
        box, self.label = labelled(
            "Refinement passes (0 = NF)",
            self.slider,
            "Normal-refinement passes: the fit is run again on the refined normals (the paper uses 1).",
        )
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(box)
        self.slider.valueChanged.connect(self._on_slider)
        state.changed.connect(self._on_state)
        self._sync_enabled(state.method)

    def _sync_enabled(self, method: str) -> None:
        self.setEnabled(_uses_passes(method))

    def _on_slider(self, value: int) -> None:
        self._state.set(passes=int(value))

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name == "passes":
            with blocked(self.slider):
                self.slider.setValue(int(value))
        elif name == "method":
            self._sync_enabled(value)
