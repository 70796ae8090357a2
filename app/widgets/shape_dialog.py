"""Shapes > Generate…: pick a synthetic shape and its point count."""

from __future__ import annotations

from PySide6.QtWidgets import QComboBox, QDialog, QDialogButtonBox, QFormLayout, QSpinBox


class ShapeDialog(QDialog):
    """Modal dialog; read :attr:`shape` and :attr:`count` after ``exec()``."""

    def __init__(self, shapes, *, shape: str = "torus", count: int = 5000, parent=None):
        super().__init__(parent)
        self.setWindowTitle("Generate a shape")
        self.combo = QComboBox()
        for name in shapes:
            self.combo.addItem(name)
        self.combo.setCurrentIndex(max(self.combo.findText(shape), 0))
        self.spin = QSpinBox()
        self.spin.setRange(100, 500_000)
        self.spin.setSingleStep(1000)
        self.spin.setGroupSeparatorShown(True)
        self.spin.setValue(int(count))
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Ok | QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        form = QFormLayout(self)
        form.addRow("Shape", self.combo)
        form.addRow("Points", self.spin)
        form.addRow(buttons)

    @property
    def shape(self) -> str:
        return self.combo.currentText()

    @property
    def count(self) -> int:
        return int(self.spin.value())
