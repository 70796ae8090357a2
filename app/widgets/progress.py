"""Status-bar progress of the running job, with a Cancel button."""

from __future__ import annotations

from PySide6.QtCore import Signal
from PySide6.QtWidgets import QHBoxLayout, QLabel, QProgressBar, QStackedLayout, QToolButton, QWidget


class EstimateProgress(QWidget):
    """Shows ``idle`` (blank by default: the window puts the result's summary there) while
    idle. Emits :attr:`cancel_requested` when Cancel is clicked.

    The widget itself always stays visible at a fixed size and only its pages (:attr:`inner`
    or ``idle``) are switched: showing or hiding a status-bar widget re-lays out the main
    window, which repaints the 3D view, and every repaint re-renders the whole cloud
    (0.25-0.8 s for the bunny with llvmpipe). One slot for both, not two side by side: a
    900 px window had no room left for the status line.
    """

    cancel_requested = Signal()

    def __init__(self, parent=None, idle: QWidget | None = None):
        super().__init__(parent)
        self.inner = QWidget(self)
        self.stage = QLabel()
        self.stage.setMinimumWidth(170)
        self.bar = QProgressBar()
        self.bar.setRange(0, 1000)
        self.bar.setFixedWidth(160)
        self.bar.setTextVisible(False)
        self.cancel = QToolButton()
        self.cancel.setText("Cancel")
        self.cancel.setToolTip("Cancel the running job (the current result stays)")
        self.cancel.clicked.connect(self.cancel_requested)
        layout = QHBoxLayout(self.inner)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.stage)
        layout.addWidget(self.bar)
        layout.addWidget(self.cancel)
        self.idle = idle if idle is not None else QWidget()
        self._pages = QStackedLayout(self)
        self._pages.setContentsMargins(0, 0, 0, 0)
        self._pages.addWidget(self.idle)
        self._pages.addWidget(self.inner)
        self.setFixedSize(self.inner.sizeHint())
        self._show(False)

    def _show(self, busy: bool) -> None:
        self._pages.setCurrentWidget(self.inner if busy else self.idle)

    @property
    def shown(self) -> bool:
        """Whether the progress (and Cancel) is on screen."""
        return self._pages.currentWidget() is self.inner

    def set_busy(self, busy) -> None:
        busy = bool(busy)
        if busy:
            self.bar.setRange(0, 1000)
            self.bar.setValue(0)
            self.stage.setText("working…")
        self._show(busy)

    def set_progress(self, fraction: float, stage: str) -> None:
        """Show ``stage``; a negative ``fraction`` means "no measure" (reading a file,
        compiling kernels): the bar turns into a busy indicator until the next fraction."""
        if fraction >= 0:
            if self.bar.maximum() == 0:
                self.bar.setRange(0, 1000)
            self.bar.setValue(int(round(1000 * min(fraction, 1.0))))
        else:
            self.bar.setRange(0, 0)
            self._show(True)
        if stage != self.stage.text():  # each repaint composes the whole window (app/worker.py)
            self.stage.setText(stage)
