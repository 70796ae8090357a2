"""GUI-thread controller of the estimate worker: numbering, dropping, cancelling.

Slider -> debounce -> :meth:`Estimator.submit` (a frozen request with a generation id)
-> :class:`app.worker.EstimateWorker` (a :class:`app.background_job.Relay`) on the job
thread of a :class:`app.background_job.RelayedJobs` -> queued signals back here -> only
the latest generation is passed on (napari's layer slicer, mne-qt-browser's
superseded-run check). Cancel makes the GUI idle at once:
the stale job is abandoned, stops at its next chunk and its answer is dropped.
"""

from __future__ import annotations

from PySide6.QtCore import QObject, Signal, Slot

from .background_job import RelayedJobs
from .jobs import live_job_threads
from .request import EstimateRequest
from .source import CloudSource
from .worker import EstimateOutput, EstimateWorker

__all__ = ["Estimator", "SHUTDOWN_WAIT_S"]

#: Closing waits this long for a running job to reach its next cancel check; longer
#: jobs are abandoned (daemon thread), so a close always ends within ~1 s.
SHUTDOWN_WAIT_S = 0.5


class Estimator(QObject):
    """GUI-thread controller owning the worker and its job thread.

    Signals (all on the GUI thread)
    -------------------------------
    result(EstimateOutput)      the latest request's full result
    preview(EstimateOutput)     a fast first picture of the latest request
    failed(str)                 the latest request failed (message for the user)
    progress(float, str)        progress of the latest request
    busy_changed(int)           1 while the latest request is pending, then 0
    dropped(int)                a stale answer (result, failure, late cancel) was dropped
    cancelled(int)              the estimate under way was cancelled (once per request)
    """

    result = Signal(object)
    preview = Signal(object)
    failed = Signal(str)
    progress = Signal(float, str)
    busy_changed = Signal(int)  # not bool: see ViewerState.changed about True through signals
    dropped = Signal(int)
    cancelled = Signal(int)

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        self._gen = 0
        self._busy = False
        self._worker = EstimateWorker(finished=self._on_finished, previewed=self._on_preview, failed=self._on_failed,
                                      cancelled=self._on_cancelled, progress=self._on_progress)  # parentless
        self._jobs = RelayedJobs("darboux-estimate", self._worker)

    # GUI thread -------------------------------------------------------------
    @property
    def generation(self) -> int:
        return self._gen

    @property
    def busy(self) -> bool:
        return self._busy

    def next_gen(self) -> int:
        self._gen += 1
        return self._gen

    def submit(self, source: CloudSource, **params) -> EstimateRequest:
        """Queue a new estimate from parameters; any older one goes stale."""
        return self.submit_request(EstimateRequest(gen=self.next_gen(), source=source, **params))

    def submit_request(self, req: EstimateRequest) -> EstimateRequest:
        """Queue ``req`` (its ``gen`` from :meth:`next_gen`); any older one goes stale."""
        self._gen = max(self._gen, req.gen)
        self._worker.latest = req.gen  # stale jobs see this at their next chunk
        self._set_busy(True)
        worker = self._worker
        self._jobs.put(lambda: worker.run(req))
        return req

    def cancel(self) -> None:
        """Abandon whatever is queued or running; idle at once (the shown result stays)."""
        self._worker.latest = -1
        if self._busy:
            self._set_busy(False)
            self.cancelled.emit(self._gen)

    def abandon(self) -> None:
        """The cloud being estimated is replaced: drop whatever is queued or running, idle
        at once, without a ``cancelled`` signal (nothing of it is to be restored on screen);
        its late answers, a cancel included, are of an older generation and dropped."""
        self.next_gen()
        self._worker.latest = -1
        self._set_busy(False)

    def shutdown(self, timeout: float = SHUTDOWN_WAIT_S) -> bool:
        """Cancel, idle, then disconnect the worker's answers and stop the job thread, waiting
        up to ``timeout`` s (:meth:`app.background_job.RelayedJobs.shutdown`). Safe to call twice."""
        self._worker.latest = -1
        self._set_busy(False)
        return self._jobs.shutdown(timeout)

    @staticmethod
    def running_threads() -> list[str]:
        """Job threads still running (tests check this is empty after close)."""
        return live_job_threads()

    def _latest(self, gen: int) -> bool:
        return gen == self._gen and self._worker.latest == gen

    def _set_busy(self, busy: bool) -> None:
        if busy != self._busy:
            self._busy = busy
            self.busy_changed.emit(1 if busy else 0)

    @Slot(object)
    def _on_finished(self, out: EstimateOutput) -> None:
        if not self._latest(out.gen):
            self.dropped.emit(out.gen)
            return
        self._set_busy(False)
        self.result.emit(out)

    @Slot(object)
    def _on_preview(self, out: EstimateOutput) -> None:
        if self._latest(out.gen):
            self.preview.emit(out)

    @Slot(int, str)
    def _on_failed(self, gen: int, message: str) -> None:
        if self._latest(gen):
            self._set_busy(False)
            self.failed.emit(message)
        else:
            self.dropped.emit(gen)

    @Slot(int)
    def _on_cancelled(self, gen: int) -> None:
        """The job thread gave up ``gen``. Announced as ``cancelled`` only if it is the
        estimate under way; after :meth:`cancel` (which announced it already) or for a stale
        job it is a ``dropped`` answer, so the window does not redo its cancel twice."""
        if gen == self._gen and self._busy:
            self._set_busy(False)
            self.cancelled.emit(gen)
        else:
            self.dropped.emit(gen)

    @Slot(int, float, str)
    def _on_progress(self, gen: int, fraction: float, stage: str) -> None:
        if self._latest(gen):
            self.progress.emit(fraction, stage)
