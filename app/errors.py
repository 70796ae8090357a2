"""One channel for everything the user must be told.

Worker failures, a file that cannot be read, and uncaught exceptions
(``sys.excepthook`` and ``threading.excepthook``, once :meth:`Notifier.install_hooks`
ran) all end up in :attr:`Notifier.notified`. The window shows them in its status
bar and, for errors, in a non-modal message box. Emitting from any thread is fine:
the signal is queued to the GUI thread.
"""

from __future__ import annotations

import logging
import sys
import threading
import traceback
from dataclasses import dataclass

from PySide6.QtCore import QObject, Signal

from .text import safe_text

__all__ = ["Notifier", "Notification"]

LOG = logging.getLogger("app")


@dataclass(frozen=True)
class Notification:
    level: str  # "info" | "warning" | "error"
    message: str
    detail: str = ""


class Notifier(QObject):
    """Collects notifications and re-emits them on the GUI thread."""

    notified = Signal(object)  # Notification

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        self.history: list[Notification] = []
        self._old_hooks = None

    def notify(self, level: str, message: str, detail: str = "") -> None:
        note = Notification(level, safe_text(message), safe_text(detail))
        self.history.append(note)
        getattr(LOG, "warning" if level == "warning" else ("error" if level == "error" else "info"))(
            "%s%s", message, ("\n" + detail) if detail else ""
        )
        self.notified.emit(note)

    def info(self, message: str) -> None:
        self.notify("info", message)

    def warning(self, message: str) -> None:
        self.notify("warning", message)

    def error(self, message: str, exc: BaseException | None = None) -> None:
        detail = "".join(traceback.format_exception(exc)) if exc is not None else ""
        self.notify("error", message, detail)

    @property
    def last(self) -> Notification | None:
        return self.history[-1] if self.history else None

    # uncaught exceptions --------------------------------------------------
    def install_hooks(self) -> None:
        """Route uncaught exceptions (any thread) here. Undo with :meth:`uninstall_hooks`."""
        if self._old_hooks is not None:
            return
        self._old_hooks = (sys.excepthook, threading.excepthook)

        def excepthook(etype, value, tb):
            if issubclass(etype, KeyboardInterrupt):
                return self._old_hooks[0](etype, value, tb)
            self.notify("error", f"Unexpected error: {value}", "".join(traceback.format_exception(etype, value, tb)))

        def thread_hook(args):
            if args.exc_type is SystemExit:
                return
            self.notify(
                "error",
                f"Unexpected error in thread {getattr(args.thread, 'name', '?')}: {args.exc_value}",
                "".join(traceback.format_exception(args.exc_type, args.exc_value, args.exc_traceback)),
            )

        sys.excepthook = excepthook
        threading.excepthook = thread_hook

    def uninstall_hooks(self) -> None:
        if self._old_hooks is not None:
            sys.excepthook, threading.excepthook = self._old_hooks
            self._old_hooks = None
