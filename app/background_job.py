"""A job thread whose answers reach the GUI thread through a parentless relay of signals.

:class:`app.loader.CloudLoader`, :class:`app.exporter.ResultExporter` and
:class:`app.estimator.Estimator` run their jobs on an :class:`app.jobs.JobThread`, and the
jobs answer by emitting on a :class:`Relay` (the estimator's is its worker): a
parentless ``QObject`` of signals made on the GUI thread, wired to its owner's slots
(parentless: a job may emit after the owner is gone, :mod:`app.jobs`). :class:`RelayedJobs`
holds the pair and shuts it down in the one safe order: the relay's signals disconnected
first (a late answer reaches nobody), then the thread stopped and joined. The reads of
:mod:`app.big_result` use a :class:`Relay` alone: they are not queued but superseded, each
on a plain thread of its own.
"""

from __future__ import annotations

from PySide6.QtCore import QObject

from .jobs import JobThread

__all__ = ["Relay", "RelayedJobs"]


class Relay(QObject):
    """A parentless ``QObject`` a job thread emits its answers on. Subclasses declare the
    signals; ``slots`` (signal name -> GUI-thread slot) wires them to the owner's slots."""

    def __init__(self, **slots):
        super().__init__()  # parentless: may be emitted on after its owner is gone
        self._wired = tuple(slots)
        for name, slot in slots.items():
            getattr(self, name).connect(slot)

    def disconnect_all(self) -> None:
        """Disconnect the wired signals (safe twice): a late answer then reaches nobody."""
        for name in self._wired:
            try:
                getattr(self, name).disconnect()
            except (RuntimeError, TypeError):
                pass


class RelayedJobs:
    """A :class:`app.jobs.JobThread` named ``name`` (started with the first job if ``lazy``,
    else at once) whose jobs answer on ``relay``."""

    def __init__(self, name: str, relay: Relay, *, lazy: bool = False):
        self.name, self.relay = name, relay
        self._thread: JobThread | None = None if lazy else JobThread(name)

    def put(self, job) -> None:
        """Queue ``job`` (a callable, run on the job thread)."""
        if self._thread is None:
            self._thread = JobThread(self.name)
        self._thread.put(job)

    def shutdown(self, timeout: float) -> bool:
        """Disconnect the relay, then let the queued jobs end (up to ``timeout`` s); whether they did."""
        self.relay.disconnect_all()
        return self._thread is None or self._thread.stop(timeout)
