"""Method selector over ``core.METHODS`` (bound to ``state.method`` or
``state.compare_method``)."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QComboBox

import core

from ._bind import blocked

OFF = "Off"


class MethodCombo(QComboBox):
    """One entry per registered method: its short title, its description as tooltip.

    With ``key="compare_method"`` a first entry "Off" stands for no comparison.
    Every item carries a string as data: reading back a None item datum through
    PySide6 (as in use here) drops a reference to ``None``.
    """

    def __init__(self, state, key: str = "method", parent=None):
        super().__init__(parent)
        self._state = state
        self._key = key
        if key == "compare_method":
            self.addItem(OFF, "")  # never None as item data: see _data()
        for name, method in core.METHODS.items():
            self.addItem(getattr(method, "title", name), name)
            self.setItemData(self.count() - 1, getattr(method, "description", ""), Qt.ItemDataRole.ToolTipRole)
        self._select(state.get(key))
        self.currentIndexChanged.connect(self._on_index)
        state.changed.connect(self._on_state)

    def _select(self, name) -> None:
        index = self.findData(name or "")
        with blocked(self):
            self.setCurrentIndex(max(index, 0))

    def _on_index(self, index: int) -> None:
        self._state.set(**{self._key: self.itemData(index) or None})

    def _on_state(self, name: str) -> None:
        value = self._state.get(name)
        if name == self._key:
            self._select(value)
