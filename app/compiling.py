"""Tell the user when numba compiles kernels (a first run without a warm cache).

:class:`CompileWatch` listens to numba's ``numba:compile`` event, which fires only
when a kernel is really compiled (not when it is loaded from the on-disk cache),
and emits :attr:`CompileWatch.started` once per burst of compilations. The
listener runs on whichever thread compiles (the job thread); the signal is queued
to the GUI thread.
"""

from __future__ import annotations

import threading

from numba.core import event
from PySide6.QtCore import QObject, Signal

__all__ = ["CompileWatch", "COMPILE_MESSAGE"]

COMPILE_MESSAGE = "compiling kernels (first run only)…"


class _Listener(event.Listener):
    def __init__(self, watch: "CompileWatch"):
        self.watch = watch
        self.depth = 0
        self.lock = threading.Lock()

    def on_start(self, _event) -> None:
        with self.lock:
            self.depth += 1
            first = self.depth == 1
        if first:
            self.watch.started.emit()

    def on_end(self, _event) -> None:
        with self.lock:
            self.depth = max(self.depth - 1, 0)


class CompileWatch(QObject):
    """Emits :attr:`started` when numba starts compiling; :meth:`close` stops listening."""

    started = Signal()

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        self._listener = _Listener(self)
        event.register("numba:compile", self._listener)

    def close(self) -> None:
        if self._listener is not None:
            event.unregister("numba:compile", self._listener)
            self._listener = None
