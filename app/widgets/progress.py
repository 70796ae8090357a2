"""Status-bar progress of the running estimate, with a Cancel button."""

from __future__ import annotations

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QHBoxLayout, QLabel, QProgressBar, QToolButton, QWidget


class EstimateProgress(QWidget):
    """Hidden while idle. Emits :attr:`cancel_requested` when Cancel is clicked."""

    cancel_requested = Signal()

    def __init__(self, parent=None):
        super().__init__(parent)
        self.stage = QLabel()
        self.bar = QProgressBar()
        self.bar.setRange(0, 1000)
        self.bar.setFixedWidth(160)
        self.bar.setTextVisible(False)
        self.cancel = QToolButton()
        self.cancel.setText("Cancel")
        self.cancel.setToolTip("Cancel the running estimate (the current result stays)")
        self.cancel.clicked.connect(self.cancel_requested)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.stage)
        layout.addWidget(self.bar)
        layout.addWidget(self.cancel)
        self.setVisible(False)

    def set_busy(self, busy) -> None:
        busy = bool(busy)
        if busy:
            self.bar.setValue(0)
            self.stage.setText("working…")
        self.setVisible(busy)

    def set_progress(self, fraction: float, stage: str) -> None:
        """Show ``stage``; a negative ``fraction`` changes only the text (e.g. compiling)."""
        if fraction >= 0:
            self.bar.setValue(int(round(1000 * min(fraction, 1.0))))
        self.stage.setText(stage)
        if fraction < 0:
            self.setVisible(True)
