"""Background work on daemon Python threads; results reach the GUI thread by queued signals.

A :class:`JobThread` runs callables one at a time, in order, on one daemon thread.
Daemon, not ``QThread``: a job stuck in a compiled kernel can neither keep the
process alive after the window closed nor abort it ("QThread: Destroyed while
thread is still running", issue 10). The objects a job emits signals from are
plain parentless ``QObject``\\ s created on the GUI thread, kept alive by the job's
own references, so a late emit after the window closed reaches nobody instead of
a deleted C++ object.
"""

from __future__ import annotations

import logging
import queue
import threading
import weakref

__all__ = ["JobThread", "live_job_threads"]

LOG = logging.getLogger(__name__)

_LIVE: "weakref.WeakSet[JobThread]" = weakref.WeakSet()
_STOP = object()


class JobThread:
    """One daemon thread serving a FIFO of callables.

    :meth:`put` and :meth:`stop` are called from the GUI thread; the jobs run on
    the worker thread. An exception escaping a job is logged, and the thread goes on.
    """

    def __init__(self, name: str):
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._loop, name=name, daemon=True)
        self._stopped = False
        self._thread.start()
        _LIVE.add(self)

    def put(self, job) -> None:
        if self._stopped:
            raise RuntimeError("this job thread has been stopped")
        self._queue.put(job)

    def is_alive(self) -> bool:
        return self._thread.is_alive()

    def stop(self, timeout: float = 1.0) -> bool:
        """Ask the thread to end after the queued jobs; wait up to ``timeout`` s.

        Returns whether it ended. A thread still inside a long job is left to finish
        on its own (daemon: it never delays the process exit).
        """
        if not self._stopped:
            self._stopped = True
            self._queue.put(_STOP)
        self._thread.join(max(float(timeout), 0.0))
        return not self._thread.is_alive()

    def _loop(self) -> None:
        while True:
            job = self._queue.get()
            if job is _STOP:
                return
            try:
                job()
            except Exception:  # noqa: BLE001 - a job's own handler failed; keep serving
                LOG.exception("background job failed")
            del job  # drop the job's references before blocking again


def live_job_threads() -> list[str]:
    """Names of job threads still running (tests check this after windows close)."""
    return [t._thread.name for t in list(_LIVE) if t.is_alive()]
