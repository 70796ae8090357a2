"""The status bar of the main window: the status line of what is on screen, and the
notifications shown over it (a mixin of MainWindow; GUI thread).

A notification is a temporary message of the status bar (it hides the status line until it
times out). It is about the cloud or the estimate of the moment it was posted, so a new
cloud, or the result of a later request, takes it down again; it stays in
``notifier.history``.
"""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMessageBox

from .presenter import preview_line, status_line, summary_line

__all__ = ["WindowStatus"]


class WindowStatus:
    """Status line, cancelled and failed estimates, notifications."""

    #: Estimate generation a shown notification is about: a result of a later one clears it.
    _message_gen = 0
    #: The error the open error box shows, and how many times in a row it came.
    _box_message, _box_repeats = "", 0

    def _show_status(self) -> None:
        """The status line for what is on screen (the result or its preview, the estimate
        under way, or why there is none)."""
        out, source, preview = self.output, self.state.source, self.presenter.preview
        if preview is not None and preview.request.source is source and self.estimator.busy:
            self.status_label.setText(preview_line(preview))
        elif out is not None and out.request.source is source:
            self.status_label.setText(status_line(out))
            self.summary_label.setText(summary_line(out.summary, out.request.method))
        elif source is not None and not self.estimator.busy:
            self.status_label.setText(f"{source.name}: {source.n_points:,} points — not estimated "
                                      "(cancelled or failed; change a parameter or press F5)")
            self.scene.set_title(f"{source.name}\nnot estimated")
            self.scene.lod.hold(False)
            self.render_all()
        elif source is None:
            self.status_label.setText("No cloud")
        else:  # estimating, nothing of it shown yet
            self.status_label.setText(f"{source.name}: {source.n_points:,} points — estimating…")

    def _on_failed(self, message: str) -> None:
        self.notifier.error(f"The estimate failed: {message}")
        if self.presenter.drop_preview():  # its full result will not come
            self.render_all()
        self._show_status()

    def _on_cancelled(self, gen: int) -> None:
        """The latest estimate was cancelled (Cancel, or a file opened): a preview of it on
        screen gives way to the kept result, or to the grey cloud if there is none."""
        if gen != self.estimator.generation or self.estimator.busy:
            return
        dropped = self.presenter.drop_preview()
        self._show_status()
        # the label, not showMessage(): a temporary message hides the status widgets,
        # re-lays out the window and re-renders the whole cloud (seconds at 1M points)
        if self.output is not None:
            self.status_label.setText("Estimate cancelled; showing the previous result: " + self.status_label.text())
        elif dropped:
            self.status_label.setText("Estimate cancelled; its preview was cleared. " + self.status_label.text())
        if dropped:
            self.render_all()

    # -- notifications ------------------------------------------------------------------
    def _show_notification(self, note) -> None:
        if self._closed:
            return
        colour = {"error": "#b2182b", "warning": "#b35806"}.get(note.level, "")
        self.status_bar.setStyleSheet(f"QStatusBar {{ color: {colour}; }}" if colour else "")
        self.status_bar.showMessage(note.message, 15000 if note.level == "error" else 6000)
        self._message_gen = self.estimator.generation
        if note.level == "error" and self.dialogs:
            self._error_box(note)

    def _error_box(self, note) -> None:
        """Show an error in the one error box: opened if none is, otherwise its text becomes
        this error's, with the count of repeats when it is the same one again (dragging a
        slider on a cloud the estimate refuses must not stack boxes). Every error stays in
        ``notifier.history``."""
        box = next((b for b in self._boxes if b.isVisible()), None)
        if box is not None and note.message == self._box_message:
            self._box_repeats += 1
        else:
            self._box_message, self._box_repeats = note.message, 1
        if box is None:
            box = QMessageBox(QMessageBox.Icon.Critical, "Darboux", note.message, QMessageBox.StandardButton.Ok, self)
            box.setModal(False)
            box.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
            box.finished.connect(self._forget_boxes)
            self._boxes.append(box)
        repeats = f"\n\n(this error {self._box_repeats} times)" if self._box_repeats > 1 else ""
        box.setText(note.message + repeats)
        box.setDetailedText(note.detail)
        box.show()

    def _clear_message(self, gen: int | None = None) -> None:
        """Take down a notification about something older: any for a new cloud (``gen`` None),
        one posted before the request of the result ``gen`` otherwise."""
        bar = self.status_bar
        if bar.currentMessage() and (gen is None or gen > self._message_gen):
            bar.clearMessage()
            bar.setStyleSheet("")

    def _forget_boxes(self, *_args) -> None:
        self._boxes = [b for b in self._boxes if b.isVisible()]
