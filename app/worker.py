"""Estimation off the GUI thread.

``EstimateRequest`` (frozen, with a generation id) -> :class:`EstimateWorker` running
in its own ``QThread`` -> :class:`EstimateOutput` (numpy arrays and frozen core
results only, no VTK) delivered to the GUI thread by a queued signal.

The :class:`Estimator` controller lives on the GUI thread. It numbers requests;
a result whose generation is not the latest is dropped, and a running job that
went stale is cancelled cooperatively: core calls our progress callback between
chunks and we answer ``False``, which makes ``core.estimate`` raise
``core.Cancelled``. The worker keeps the last noisy copy and the last neighbour
graph so that changing only the method, the passes or a k <= k_max re-uses them.
"""

from __future__ import annotations

import logging
import threading
import time
import traceback
import weakref
from dataclasses import dataclass, field

import numpy as np
from PySide6.QtCore import QObject, QThread, Signal, Slot

from core.spacing import mean_spacing

from .fields import compute_fields
from .source import CloudSource

__all__ = ["EstimateRequest", "EstimateOutput", "EstimateWorker", "Estimator", "K_MAX_HEADROOM"]

LOG = logging.getLogger(__name__)

#: Threads that outlived a shutdown timeout, kept referenced until they finish.
_ORPHANS: list = []

#: Neighbour graphs are built for at least this many neighbours, so moving the k
#: slider below it re-uses the graph instead of querying the KD-tree again.
K_MAX_HEADROOM = 32


@dataclass(frozen=True)
class EstimateRequest:
    """Everything one estimate needs; immutable so a worker can read it safely."""

    gen: int
    source: CloudSource
    k: int = 15
    k_auto: bool = False
    method: str = "nr"
    passes: int | None = None
    noise: float = 0.0  # sigma in % of mean spacing
    use_input_normals: bool = True
    orientation: str = "auto"
    compare_method: str | None = None
    seed: int = 0

    def k_for(self, method: str):
        """What core.estimate gets as k: "auto" where the method supports it."""
        return "auto" if self.k_auto and method in ("nf", "nr") else int(self.k)

    def k_needed(self, n_points: int) -> int:
        """Neighbours the request needs cached on ``n_points`` (the largest automatic k when auto)."""
        from core.scale import candidates

        need = max(int(self.k), candidates(n_points)[-1]) if self.k_auto else int(self.k)
        return min(need, n_points)

    @property
    def cloud_key(self) -> tuple:
        """Identifies the (possibly noisy) point set the neighbours belong to."""
        return (self.source.uid, round(float(self.noise), 6), self.seed)


@dataclass(frozen=True, eq=False)
class EstimateOutput:
    """What the worker hands back: numpy arrays and frozen core results only."""

    gen: int
    request: EstimateRequest
    points: np.ndarray  # the cloud the estimate ran on (noisy copy when noise > 0)
    result: object  # core.CurvatureResult
    fields: dict
    spacing: float  # mean distance to the nearest neighbour
    summary: dict | None = None  # core.metrics.summary against the truth
    compare: object | None = None  # core.CurvatureResult of request.compare_method
    compare_fields: dict | None = None
    compare_summary: dict | None = None
    elapsed: float = 0.0
    reused_neighbours: bool = False
    timings: dict = field(default_factory=dict)


class EstimateWorker(QObject):
    """Runs requests one at a time. Lives in a worker QThread.

    :meth:`run` runs on the worker thread; :attr:`latest` is written by the GUI
    thread (a plain int, read between chunks through core's progress callback).
    """

    finished = Signal(object)  # EstimateOutput
    failed = Signal(int, str)  # gen, message
    cancelled = Signal(int)  # gen
    progress = Signal(int, float, str)  # gen, fraction, stage
    started = Signal(int)  # gen

    def __init__(self):
        super().__init__()
        self.latest = 0
        self._noisy_key = None
        self._noisy = None
        self._nb_key = None
        self._nb = None
        self._last_emit = 0.0

    # worker thread ---------------------------------------------------------
    def _check(self, req: EstimateRequest):
        """Progress callback handed to core (worker thread)."""

        def callback(fraction: float, stage: str):
            if req.gen != self.latest:
                return False
            now = time.monotonic()
            if now - self._last_emit > 0.05 or fraction >= 1.0:
                self._last_emit = now
                self.progress.emit(req.gen, float(fraction), str(stage))
            return None

        return callback

    def _points(self, req: EstimateRequest) -> np.ndarray:
        if self._noisy_key == req.cloud_key:
            return self._noisy
        if req.noise > 0:
            import core.noise

            pts = core.noise.add_noise(
                req.source.points, req.noise / 100.0, normals=req.source.normals, relative=True, seed=req.seed
            )
        else:
            pts = req.source.points
        pts = np.array(pts, dtype=float, copy=True)
        pts.flags.writeable = False
        self._noisy_key, self._noisy = req.cloud_key, pts
        self._nb_key = self._nb = None
        return pts

    @Slot(object)
    def run(self, req: EstimateRequest) -> None:
        """Estimate one request (worker thread). Skips it at once if already stale."""
        if req.gen != self.latest:
            self.cancelled.emit(req.gen)
            return
        import core

        t0 = time.perf_counter()
        callback = self._check(req)
        self.started.emit(req.gen)
        try:
            timings = {}
            points = self._points(req)
            normals = req.source.normals if req.use_input_normals else None
            need = req.k_needed(len(points))
            reused = self._nb is not None and self._nb_key == req.cloud_key and self._nb.k_max >= need
            if not reused:
                t = time.perf_counter()
                k_max = max(need, K_MAX_HEADROOM)
                k_max = min(k_max, len(points) - 1) if len(points) > need else need
                self._nb = core.build_neighbours(points, k_max, progress=_sub(callback, 0.0, 0.2, "neighbours"))
                self._nb_key = req.cloud_key
                timings["neighbours"] = time.perf_counter() - t
            runs = [req.method] + ([req.compare_method] if req.compare_method else [])
            results = []
            lo = 0.2 if not reused else 0.0
            span = (1.0 - lo) / len(runs)
            for i, method in enumerate(runs):
                t = time.perf_counter()
                passes = req.passes if core.METHODS[method].uses_passes else None
                res = core.estimate(
                    points,
                    normals,
                    k=req.k_for(method),
                    method=method,
                    passes=passes,
                    orientation=req.orientation,
                    neighbours=self._nb,
                    progress=_sub(callback, lo + i * span, lo + (i + 1) * span, method),
                )
                timings[method] = time.perf_counter() - t
                results.append(res)
            if req.gen != self.latest:
                self.cancelled.emit(req.gen)
                return
            sample = req.source.sample
            reference = sample.normals if sample is not None else req.source.normals
            fields = [compute_fields(r, reference_normals=reference, sample=sample) for r in results]
            summaries = [None] * len(results)
            if sample is not None:
                import core.metrics

                summaries = [core.metrics.summary(r, sample) for r in results]
            spacing = mean_spacing(points, neighbours=self._nb) if self._nb.k_max > 1 else 1.0
            out = EstimateOutput(
                gen=req.gen,
                request=req,
                points=points,
                result=results[0],
                fields=fields[0],
                spacing=spacing,
                summary=summaries[0],
                compare=results[1] if len(results) > 1 else None,
                compare_fields=fields[1] if len(results) > 1 else None,
                compare_summary=summaries[1] if len(results) > 1 else None,
                elapsed=time.perf_counter() - t0,
                reused_neighbours=reused,
                timings=timings,
            )
        except core.Cancelled:
            self.cancelled.emit(req.gen)
            return
        except Exception as exc:  # noqa: BLE001 - every failure goes to the notifier
            LOG.debug("estimate failed:\n%s", traceback.format_exc())
            self.failed.emit(req.gen, f"{type(exc).__name__}: {exc}" if not str(exc) else str(exc))
            return
        self.finished.emit(out)


def _sub(callback, start: float, stop: float, stage: str):
    """Map a 0..1 sub-job onto [start, stop] of the whole job."""

    def inner(fraction: float, stage_: str = stage):
        return callback(start + (stop - start) * min(max(float(fraction), 0.0), 1.0), stage_ or stage)

    return inner


class Estimator(QObject):
    """GUI-thread controller owning the worker thread.

    Signals (all on the GUI thread)
    -------------------------------
    result(EstimateOutput)      the latest request's result
    failed(str)                 the latest request failed (message for the user)
    progress(float, str)        progress of the latest request
    busy_changed(int)           1 while requests are queued or running, then 0
    dropped(int)                a result came back stale and was dropped
    cancelled(int)              a request was cancelled or skipped
    """

    result = Signal(object)
    failed = Signal(str)
    progress = Signal(float, str)
    busy_changed = Signal(int)  # not bool: see ViewerState.changed about True through signals
    dropped = Signal(int)
    cancelled = Signal(int)
    _submit = Signal(object)

    _live_threads: "weakref.WeakSet[QThread]" = weakref.WeakSet()

    def __init__(self, parent: QObject | None = None):
        super().__init__(parent)
        self._gen = 0
        self._busy = False
        self._pending: set[int] = set()
        self._thread = QThread()
        self._thread.setObjectName("darboux-estimate")
        self._worker = EstimateWorker()
        self._worker.moveToThread(self._thread)
        self._submit.connect(self._worker.run)
        self._worker.finished.connect(self._on_finished)
        self._worker.failed.connect(self._on_failed)
        self._worker.cancelled.connect(self._on_cancelled)
        self._worker.progress.connect(self._on_progress)
        self._thread.finished.connect(self._worker.deleteLater)
        self._thread.start()
        Estimator._live_threads.add(self._thread)

    # GUI thread -------------------------------------------------------------
    @property
    def generation(self) -> int:
        return self._gen

    @property
    def busy(self) -> bool:
        return self._busy

    def submit(self, source: CloudSource, **params) -> EstimateRequest:
        """Queue a new estimate; any older one still queued or running goes stale."""
        if not self._thread.isRunning():
            raise RuntimeError("the estimator has been shut down")
        self._gen += 1
        req = EstimateRequest(gen=self._gen, source=source, **params)
        self._worker.latest = req.gen  # stale jobs see this at their next chunk
        self._pending.add(req.gen)
        self._set_busy(True)
        self._submit.emit(req)
        return req

    def cancel(self) -> None:
        """Cancel whatever is queued or running (the shown result stays)."""
        self._worker.latest = -1

    def shutdown(self, timeout_ms: int = 15000) -> bool:
        """Cancel, stop the thread and wait for it (GUI thread). Safe to call twice.

        Core checks for cancellation between chunks; if a chunk outlasts the
        timeout, the thread is kept alive in :data:`_ORPHANS` until it finishes,
        because destroying a running QThread aborts the process.
        """
        self._worker.latest = -1
        for signal in (self._worker.finished, self._worker.failed, self._worker.cancelled, self._worker.progress):
            try:
                signal.disconnect()
            except (RuntimeError, TypeError):
                pass
        if self._thread.isRunning():
            self._thread.quit()
            if not self._thread.wait(timeout_ms):
                LOG.error("estimate thread did not stop within %d ms; leaving it to finish", timeout_ms)
                thread, worker = self._thread, self._worker
                _ORPHANS.append((thread, worker))
                thread.finished.connect(lambda: _ORPHANS.remove((thread, worker)) if (thread, worker) in _ORPHANS else None)
                self._pending.clear()
                self._set_busy(False)
                return False
        self._pending.clear()
        self._set_busy(False)
        return True

    @classmethod
    def running_threads(cls) -> list[QThread]:
        """Estimator threads still running (tests check this is empty after close)."""
        out = []
        for t in list(cls._live_threads):
            try:
                if t.isRunning():
                    out.append(t)
            except RuntimeError:  # C++ object already deleted
                pass
        return out

    def _settle(self, gen: int) -> None:
        # the worker answers every request exactly once (finished, failed or cancelled)
        self._pending.discard(gen)
        if not self._pending:
            self._set_busy(False)

    def _set_busy(self, busy: bool) -> None:
        if busy != self._busy:
            self._busy = busy
            self.busy_changed.emit(1 if busy else 0)

    @Slot(object)
    def _on_finished(self, out: EstimateOutput) -> None:
        if out.gen != self._gen or self._worker.latest != out.gen:
            self.dropped.emit(out.gen)
            self._settle(out.gen)
            return
        self._settle(out.gen)
        self.result.emit(out)

    @Slot(int, str)
    def _on_failed(self, gen: int, message: str) -> None:
        self._settle(gen)
        if gen == self._gen:
            self.failed.emit(message)
        else:
            self.dropped.emit(gen)

    @Slot(int)
    def _on_cancelled(self, gen: int) -> None:
        self._settle(gen)
        self.cancelled.emit(gen)

    @Slot(int, float, str)
    def _on_progress(self, gen: int, fraction: float, stage: str) -> None:
        if gen == self._gen:
            self.progress.emit(fraction, stage)


def threads_alive() -> list[str]:
    """Names of non-daemon Python threads other than the main one (for tests)."""
    return [t.name for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
