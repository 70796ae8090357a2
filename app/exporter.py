"""File > Export written off the GUI thread.

Writing a result is long for a big cloud (1M points on this 2-core VM with core.io: PLY
2.3 s, XYZ 21 s, CSV 19 s) and the dialog's export wrote it on the GUI thread: the window
froze that long, saying nothing. :class:`ResultExporter` writes on a job thread of its own,
one file after the other; the window says what is being written and, once it is, where.
A closing window waits for a write under way (the user's file: a half-written one is
worse than a wait). :meth:`app.actions.WindowActions.export_result` stays synchronous
(scripts and tests read the file back at once).
"""

from __future__ import annotations

import traceback
from pathlib import Path

from PySide6.QtCore import QObject, Signal, Slot

import core.io

from .background_job import Relay, RelayedJobs

__all__ = ["ResultExporter", "EXPORT_WAIT_S"]

#: How long a closing window waits for a write under way, s (then the file is abandoned).
EXPORT_WAIT_S = 300.0


class _Relay(Relay):
    written = Signal(object, object)  # tag, the path written
    failed = Signal(object, object, str)  # tag, exception, traceback


class ResultExporter(QObject):
    """Signals (GUI thread): ``written(tag, path)``, ``failed(tag, exc, detail)``; ``tag`` is
    what :meth:`write` was given (the caller's note of what it asked)."""

    written = Signal(object, object)
    failed = Signal(object, object, str)

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        relay = _Relay(written=self._on_written, failed=self._on_failed)
        self._jobs = RelayedJobs("darboux-export", relay, lazy=True)  # the thread starts with the first write
        self.pending = 0  # writes asked and not yet answered

    @property
    def busy(self) -> bool:
        return self.pending > 0

    def write(self, path: Path, result, tag=None) -> None:
        """Write ``result`` (a frozen core result) to ``path`` on the job thread."""
        self.pending += 1
        relay = self._jobs.relay

        def job():
            try:
                written = core.io.write_result(path, result)
            except Exception as exc:  # noqa: BLE001 - reported to the user, the app goes on
                relay.failed.emit(tag, exc, traceback.format_exc())
            else:
                relay.written.emit(tag, Path(written))

        self._jobs.put(job)

    @Slot(object, object)
    def _on_written(self, tag, path) -> None:
        self.pending -= 1
        self.written.emit(tag, path)

    @Slot(object, object, str)
    def _on_failed(self, tag, exc, detail) -> None:
        self.pending -= 1
        self.failed.emit(tag, exc, detail)

    def shutdown(self, timeout: float = EXPORT_WAIT_S) -> bool:
        """Let the writes asked end (up to ``timeout`` s); whether they did."""
        return self._jobs.shutdown(timeout)
