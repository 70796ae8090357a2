"""Slider for the Gaussian noise level (bound to ``state.noise``)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QVBoxLayout, QWidget
from superqt import QLabeledSlider

from ._bind import blocked, labelled

NOISE_MAX = 100  # percent of the mean point spacing


class NoiseSlider(QWidget):
    """σ of isotropic Gaussian noise, in % of the mean point spacing.

    Noise is applied by the worker to a copy of the cloud with a fixed seed, so the
    same level always gives the same cloud and 0 gives back the original.
    """

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self._state = state
        self.slider = QLabeledSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(0, NOISE_MAX)
        self.slider.setValue(int(round(state.noise)))
        box, _ = labelled(
            "Noise σ (% of point spacing)",
            self.slider,
            "Gaussian noise added to a copy of the cloud (fixed seed); 0 = the original cloud.",
        )
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(box)
        self.slider.valueChanged.connect(self._on_slider)
        state.changed.connect(self._on_state)

    def _on_slider(self, value: int) -> None:
        self._state.set(noise=float(value))

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name == "noise":
            with blocked(self.slider):
                self.slider.setValue(int(round(value)))
