"""Background work on daemon Python threads; results reach the GUI thread by queued signals.

A :class:`JobThread` runs callables one at a time, in order, on one daemon thread.
Daemon, not ``QThread``: a job stuck in a compiled kernel can neither keep the
process alive after the window closed nor abort it ("QThread: Destroyed while
thread is still running", issue 10). The objects a job emits signals from are
plain parentless ``QObject``\\ s created on the GUI thread, kept alive by the job's
own references, so a late emit after the window closed reaches nobody instead of
a deleted C++ object.

Every background thread runs :data:`BACKGROUND_NICE` steps nicer than the GUI thread, so
that a frame rendered while an estimate runs gets the cores first.
"""

from __future__ import annotations

import logging
import os
import queue
import sys
import threading
import time
import weakref

__all__ = ["JobThread", "join_job_threads", "live_job_threads", "lower_priority", "BACKGROUND_NICE"]

LOG = logging.getLogger(__name__)

_LIVE: "weakref.WeakSet[JobThread]" = weakref.WeakSet()
_STOP = object()

#: How much nicer than the GUI thread the background threads run (Linux, where nice is per
#: thread; numba's OpenMP workers, started from a job thread, inherit it). Software OpenGL
#: renders on the same two cores as a parallel estimate: beside a 200k-point estimate a bunny
#: frame took 1.45-1.8x its idle time with the estimate at the GUI's priority, 1.1-1.4x at
#: +5 and 1.2x at +10 (one run each, load average 17). +5, not more: the estimate still gets
#: its share beside other programs (weight 335 to their 1024), and all idle cores when alone.
BACKGROUND_NICE = 5


def lower_priority(step: int = BACKGROUND_NICE) -> None:
    """Make the calling thread ``step`` nicer (Linux; elsewhere nice is per process: nothing)."""
    if not sys.platform.startswith("linux"):
        return
    try:
        tid = threading.get_native_id()
        os.setpriority(os.PRIO_PROCESS, tid, min(os.getpriority(os.PRIO_PROCESS, tid) + step, 19))
    except OSError:  # not allowed here: stay at the process's priority
        LOG.debug("could not lower the priority of %s", threading.current_thread().name)


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
        lower_priority()  # before any numba call on this thread starts its OpenMP workers
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


def join_job_threads(timeout: float) -> list[str]:
    """Wait up to ``timeout`` s in all for the job threads to end (their windows told them to
    stop: a cancelled estimate ends at its next check, a kernel numba compiles when it is
    compiled); the names of those still running."""
    deadline = time.monotonic() + max(float(timeout), 0.0)
    for job in list(_LIVE):
        job._thread.join(max(deadline - time.monotonic(), 0.0))
    return live_job_threads()
