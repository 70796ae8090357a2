"""A check box bound to one boolean of the state (e.g. ``use_input_normals``)."""

from __future__ import annotations

from PySide6.QtWidgets import QCheckBox

from ._bind import blocked


class StateCheckBox(QCheckBox):
    def __init__(self, state, key: str, text: str, tooltip: str = "", parent=None):
        super().__init__(text, parent)
        self._state = state
        self._key = key
        self.setToolTip(tooltip)
        self.setChecked(bool(state.get(key)))
        self.toggled.connect(self._on_toggled)
        state.changed.connect(self._on_state)

    def _on_toggled(self, on: bool) -> None:
        self._state.set(**{self._key: bool(on)})

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name == self._key:
            with blocked(self):
                self.setChecked(bool(value))
