"""The cloud-wide teaching maths of one result, computed off the GUI thread.

:class:`CloudMathsWorker` runs :func:`cloud_maths` (lines of curvature, point types,
Gauss-Bonnet) on a Python thread and delivers the numpy-only :class:`CloudMaths` to the GUI
thread through a queued signal; a result of an older request is dropped.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass

import numpy as np
from PySide6.QtCore import QObject, Signal
from scipy.spatial import cKDTree

import core
from core.curvature_lines import SEED_SPACING

from ..estimator import SHUTDOWN_WAIT_S

__all__ = ["CloudMaths", "cloud_maths", "CloudMathsWorker"]

@dataclass(frozen=True)
class CloudMaths:
    """What the teaching overlays need about the whole cloud (numpy only): the lines of
    curvature on the surface, with the normal of each vertex's nearest point to lift them
    over the point sprites when drawn (their size is the view's: app/framing.overlay_lift)."""

    scale: float
    types: np.ndarray
    lines: dict  # "e1" / "e2" -> list of (m, 3) polylines
    gauss_bonnet: core.GaussBonnet
    line_normals: dict  # "e1" / "e2" -> list of (m, 3) unit normals, one per vertex

    def lifted(self, key: str, lift: float) -> list:
        """The lines of ``key`` moved ``lift`` (world units) along their vertices' normals."""
        return [line + lift * n for line, n in zip(self.lines[key], self.line_normals[key])]


def _vertex_normals(lines, res) -> list:
    """The normal of each vertex's nearest valid point."""
    if not lines:
        return []
    ok = res.valid & np.isfinite(res.normals).all(axis=1)
    _, idx = cKDTree(res.points[ok]).query(np.concatenate(lines))
    normals = res.normals[ok][idx]
    return np.split(normals, np.cumsum([len(line) for line in lines])[:-1])


#: about this many seeds per family of lines: enough to cover a shape, few enough to read
#: and to trace in seconds on a million points (the seed separation grows as sqrt(N))
LINE_SEEDS = 200


def cloud_maths(res, *, separation: float | None = None, progress=None) -> CloudMaths:
    """Point types, lines of curvature (both families) and Gauss-Bonnet of one result (any
    thread). ``separation``: seed separation in spacings (default: about LINE_SEEDS seeds);
    ``progress``: :func:`core.curvature_lines`'s (returning False cancels the tracing)."""
    if separation is None:
        separation = max(SEED_SPACING, float(np.sqrt(len(res.points) / LINE_SEEDS)))
    scale = core.curvature_scale(res)
    types = core.point_types(res, scale=scale if np.isfinite(scale) else None)  # NaN: no valid point
    gb = core.gauss_bonnet(res, progress=progress)
    lines, normals = {}, {}
    for direction in ("e1", "e2"):
        try:
            lines[direction] = core.curvature_lines(res, direction=direction, separation=separation, progress=progress)
        except ValueError:  # no valid point
            lines[direction] = []
        normals[direction] = _vertex_normals(lines[direction], res)
    return CloudMaths(scale=scale, types=types, lines=lines, gauss_bonnet=gb, line_normals=normals)


class CloudMathsWorker(QObject):
    """One job at a time on a Python thread; :meth:`shutdown` stops it (GUI thread API).

    Signals
    -------
    done(int, object) : generation and :class:`CloudMaths` (queued to the GUI thread).
    failed(int, str) : generation and the error message.
    """

    done = Signal(int, object)
    failed = Signal(int, str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.generation = 0
        self._thread: threading.Thread | None = None
        self._pending = None
        self._lock = threading.Lock()
        self._closed = False

    def submit(self, res) -> int:
        """Compute for ``res``; a newer submit supersedes a pending one (GUI thread)."""
        self.generation += 1
        with self._lock:
            self._pending = (self.generation, res)
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(target=self._run, name="teach-maths", daemon=True)
                self._thread.start()
        return self.generation

    def _run(self):  # worker thread
        while True:
            with self._lock:
                job, self._pending = self._pending, None
                if job is None:
                    return
            gen, res = job
            try:
                maths = cloud_maths(res, progress=lambda _f, _s, g=gen: not self._stale(g))
            except core.Cancelled:  # closed, or a newer result came: its job follows
                continue
            except Exception as exc:  # noqa: BLE001 - reported to the GUI
                self._emit(self.failed, gen, f"{type(exc).__name__}: {exc}")
                continue
            self._emit(self.done, gen, maths)

    def _stale(self, gen: int) -> bool:
        """The job ``gen`` is no longer wanted: shut down, or a newer one is waiting."""
        with self._lock:
            return self._closed or (self._pending is not None and self._pending[0] != gen)

    def _emit(self, signal, *args) -> None:
        """Deliver unless shut down (the window may be gone: its signals with it)."""
        with self._lock:
            if self._closed:
                return
        try:
            signal.emit(*args)
        except RuntimeError:  # the QObject was deleted after the check
            pass

    def busy(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def shutdown(self, timeout: float = SHUTDOWN_WAIT_S) -> bool:
        """Drop pending work, disconnect, and wait up to ``timeout`` s for the running job
        (GUI thread): the lines of curvature of a 1M-point cloud take minutes and cannot be
        interrupted, and closing the window waited for them. A job still running after
        ``timeout`` finishes on its daemon thread and is dropped. True if it had stopped."""
        with self._lock:
            self._pending = None
            self._closed = True
        for signal in (self.done, self.failed):
            try:
                signal.disconnect()
            except (RuntimeError, TypeError):  # nothing connected
                pass
        if self._thread is not None:
            self._thread.join(timeout)
            if self._thread.is_alive():
                return False
            self._thread = None
        return True
