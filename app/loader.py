"""Reading files and generating shapes off the GUI thread.

:class:`CloudLoader` runs :func:`app.source.load_file` / :func:`app.source.make_shape`
on its own :class:`app.jobs.JobThread` and delivers a :class:`app.source.CloudSource`
to the GUI thread. A load superseded by a newer one is dropped on arrival.
"""

from __future__ import annotations

import os
import traceback

from PySide6.QtCore import QObject, Signal, Slot

import core.io

from .background_job import Relay, RelayedJobs
from .fields import prepare_sampling
from .source import display_name, load_file, make_shape

__all__ = ["CloudLoader", "LoadTicket"]


class LoadTicket:
    """What was asked for (GUI thread reads it back with the answer)."""

    def __init__(self, gen: int, label: str, path=None, remember: bool = False):
        self.gen, self.label, self.path, self.remember = gen, label, path, remember


class _Relay(Relay):
    done = Signal(object, object)  # ticket, CloudSource
    failed = Signal(object, str, str)  # ticket, message, detail


class CloudLoader(QObject):
    """Signals (GUI thread): ``loaded(ticket, source)``, ``failed(ticket, message, detail)``,
    ``busy_changed(int)``."""

    loaded = Signal(object, object)
    failed = Signal(object, str, str)
    busy_changed = Signal(int)

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        self._gen = 0
        self._jobs = RelayedJobs("darboux-load", _Relay(done=self._on_done, failed=self._on_failed))
        self.pending: LoadTicket | None = None

    def open_file(self, path, *, remember: bool = True) -> LoadTicket:
        path = os.fsdecode(path)  # bytes names too (undecodable bytes as surrogate escapes)
        ticket = self._ticket(display_name(path), path, remember)
        relay = self._jobs.relay
        self._jobs.put(lambda: _run(relay, ticket, lambda: load_file(ticket.path), file=True))
        return ticket

    def make_shape(self, name: str, n: int) -> LoadTicket:
        ticket = self._ticket(f"{name} ({n:,} pts)")
        relay = self._jobs.relay
        self._jobs.put(lambda: _run(relay, ticket, lambda: make_shape(name, n)))
        return ticket

    def cancel(self) -> None:
        if self.pending is not None:
            self.pending = None
            self.busy_changed.emit(0)

    def shutdown(self, timeout: float = 0.3) -> bool:
        self.pending = None
        return self._jobs.shutdown(timeout)

    def _ticket(self, label, path=None, remember=False) -> LoadTicket:
        self._gen += 1
        self.pending = LoadTicket(self._gen, label, path, remember)
        self.busy_changed.emit(1)
        return self.pending

    @Slot(object, object)
    def _on_done(self, ticket, source) -> None:
        if self.pending is ticket:
            self.pending = None
            self.busy_changed.emit(0)
            self.loaded.emit(ticket, source)

    @Slot(object, str, str)
    def _on_failed(self, ticket, message, detail) -> None:
        if self.pending is ticket:
            self.pending = None
            self.busy_changed.emit(0)
            self.failed.emit(ticket, message, detail)


def _run(relay: _Relay, ticket: LoadTicket, make, *, file: bool = False) -> None:
    """Job thread: build the source, or report why not in one line."""
    try:
        source = make()
        source.geometry  # noqa: B018 - framing facts computed here, not on the GUI thread
        source.field_specs, source.colours  # noqa: B018 - and the file's own fields' looks and colours
        source.scanners  # noqa: B018 - and its distinct scanner positions
        prepare_sampling(source.n_points)  # and the colour limits' sample index
    except (core.io.CloudFileError, OSError, ValueError) as exc:
        text = str(exc)
        if file and ticket.label not in text:
            text = f"{ticket.label}: {text}"
        relay.failed.emit(ticket, text, "")
        return
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as exc:  # noqa: BLE001 - a reader bug, or a native library's panic (pyo3 raises a
        # BaseException), must not take the app down nor end the loader's thread with the load pending forever
        what = "not enough memory to load it" if isinstance(exc, MemoryError) else f"{type(exc).__name__}: {exc}"
        relay.failed.emit(ticket, f"{ticket.label}: {what}", traceback.format_exc())
        return
    relay.done.emit(ticket, source)
