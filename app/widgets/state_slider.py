"""One slider class for every integer-valued parameter of the state (k, passes, noise).

A :class:`StateSlider` is bound both ways to one state key; the window debounces the
re-estimate. The three estimate sliders are built by :func:`k_slider`,
:func:`passes_slider` and :func:`noise_slider` from one table of captions and ranges.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QVBoxLayout, QWidget
from superqt import QLabeledSlider

import core

from ._bind import blocked, labelled
from .check_box import StateCheckBox

__all__ = ["StateSlider", "KSlider", "k_slider", "passes_slider", "noise_slider", "K_RANGE", "PASSES_MAX", "NOISE_MAX"]

K_RANGE = (6, 64)
PASSES_MAX = 5
NOISE_MAX = 100  # percent of the mean point spacing


class StateSlider(QWidget):
    """A labelled slider bound to ``state.<key>``.

    Parameters
    ----------
    also : dict, optional
        Extra state values set together with a user move (e.g. ``{"k_auto": False}``:
        moving the k slider picks that fixed k).
    enabled_by : (key, predicate), optional
        The slider is enabled while ``predicate(state.<key>)`` holds.
    """

    def __init__(self, state, key: str, title: str, tooltip: str, *, minimum: int, maximum: int,
                 also: dict | None = None, enabled_by=None, parent=None):
        super().__init__(parent)
        self._state, self._key, self._also = state, key, dict(also or {})
        self._enabled_by = enabled_by
        self.slider = QLabeledSlider(Qt.Orientation.Horizontal)
        self.slider.setRange(minimum, max(maximum, int(round(state.get(key)))))
        self.slider.setValue(int(round(state.get(key))))
        box, self.label = labelled(title, self.slider, tooltip)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(box)
        self.slider.valueChanged.connect(self._on_slider)
        state.changed.connect(self._on_state)
        self._sync_enabled()

    def _sync_enabled(self) -> None:
        if self._enabled_by is not None:
            key, predicate = self._enabled_by
            self.setEnabled(bool(predicate(self._state.get(key))))

    def _on_slider(self, value: int) -> None:
        with self._state.batch():
            self._state.set(**{self._key: value}, **self._also)

    def _on_state(self, name: str) -> None:
        if name == self._key:
            with blocked(self.slider):
                self.slider.setValue(int(round(self._state.get(name))))
        elif self._enabled_by is not None and name == self._enabled_by[0]:
            self._sync_enabled()


class KSlider(QWidget):
    """The k slider and the automatic-k check box. Moving the slider chooses that fixed k."""

    def __init__(self, state, parent=None):
        super().__init__(parent)
        self.control = StateSlider(
            state, "k", "Neighbours k",
            "Number of nearest neighbours used by the fit (the point itself included). "
            "Moving it turns automatic k off.",
            minimum=K_RANGE[0], maximum=K_RANGE[1], also={"k_auto": False},
        )
        self.slider = self.control.slider
        self.auto = StateCheckBox(
            state, "k_auto", "automatic k per point (NF/NR)",
            "Choose k per point from the data (bias-variance rule, core.scale); the slider's k is used "
            "for the other methods. Show the choice with the field 'Neighbourhood size k'.",
        )
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.control)
        layout.addWidget(self.auto)


def _uses_passes(method: str) -> bool:
    return bool(getattr(core.METHODS.get(method), "uses_passes", False))


def k_slider(state) -> KSlider:
    return KSlider(state)


def passes_slider(state) -> StateSlider:
    """NR refinement passes (0 = plain normal fitting, NF); disabled for methods without passes."""
    return StateSlider(
        state, "passes", "Refinement passes (0 = NF)",
        "Normal-refinement passes: the fit is run again on the refined normals (the paper uses 1).",
        minimum=0, maximum=PASSES_MAX, enabled_by=("method", _uses_passes),
    )


def noise_slider(state) -> StateSlider:
    """σ of Gaussian noise in % of the mean spacing, added by the worker to a copy (fixed seed)."""
    return StateSlider(
        state, "noise", "Noise σ (% of point spacing)",
        "Gaussian noise added to a copy of the cloud (fixed seed); 0 = the original cloud.",
        minimum=0, maximum=NOISE_MAX,
    )
