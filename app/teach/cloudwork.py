"""The cloud-wide teaching maths of one result, computed off the GUI thread.

:class:`CloudMathsWorker` runs :func:`cloud_maths` (lines of curvature, point types,
Gauss-Bonnet) on a Python thread and delivers the numpy-only :class:`CloudMaths` to the GUI
thread through a queued signal; a result of an older request is dropped.
"""

from __future__ import annotations

import logging
import threading
from dataclasses import dataclass, field

import numpy as np
from PySide6.QtCore import QObject, Signal
from scipy.spatial import cKDTree

import core
from core.curvature_lines import SEED_SPACING
from core.duplicates import find_duplicates
from core.gauss_bonnet import VORONOI_NEIGHBOURS

from ..estimator import SHUTDOWN_WAIT_S

__all__ = ["CloudMaths", "cloud_maths", "CloudMathsWorker"]

LOG = logging.getLogger(__name__)

@dataclass(frozen=True)
class CloudMaths:
    """What the teaching overlays need about the whole cloud (numpy only): the lines of
    curvature on the surface, with the normal of each vertex's nearest point to lift them
    over the point sprites when drawn (their size is the view's: app/framing.overlay_lift).
    A part that could not be computed is None (``lines``: empty) and ``notes[part]`` says why
    (parts: "types", "gauss_bonnet", "lines")."""

    scale: float
    types: np.ndarray | None
    lines: dict  # "e1" / "e2" -> list of (m, 3) polylines
    gauss_bonnet: core.GaussBonnet | None
    line_normals: dict  # "e1" / "e2" -> list of (m, 3) unit normals, one per vertex
    notes: dict = field(default_factory=dict)

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
    ``progress``: :func:`core.curvature_lines`'s (returning False cancels the tracing). A
    part that fails is left out with a note; the others are kept."""
    if separation is None:
        separation = max(SEED_SPACING, float(np.sqrt(len(res.points) / LINE_SEEDS)))
    notes = {}
    scale = core.curvature_scale(res)
    types = _attempt(notes, "types", lambda: core.point_types(res, scale=scale if np.isfinite(scale) else None))
    gb = _gauss_bonnet(res, notes, progress)
    lines, normals = {}, {}
    for direction in ("e1", "e2"):
        traced = _attempt(notes, "lines", lambda d=direction: _lines(res, d, separation, progress))
        lines[direction], normals[direction] = traced or ([], [])
    return CloudMaths(scale=scale, types=types, lines=lines, gauss_bonnet=gb, line_normals=normals, notes=notes)


def _attempt(notes: dict, part: str, compute):
    """``compute()``, or None with ``notes[part]`` saying why it failed (a cancel propagates)."""
    try:
        return compute()
    except core.Cancelled:
        raise
    except Exception as exc:  # noqa: BLE001 - told in the panel; the other parts still show
        LOG.warning("teach: %s failed", part, exc_info=True)
        notes.setdefault(part, f"{type(exc).__name__}: {exc}")
        return None


def _gauss_bonnet(res, notes: dict, progress):
    """Gauss-Bonnet, or None with a note: its Voronoi cells need more than
    VORONOI_NEIGHBOURS distinct points."""
    merged = find_duplicates(np.ascontiguousarray(res.points, dtype=np.float64))
    distinct = len(res.points) if merged is None else len(merged.first)
    if distinct <= VORONOI_NEIGHBOURS:
        notes["gauss_bonnet"] = (f"unavailable for so few points: its per-point areas need more than "
                                 f"{VORONOI_NEIGHBOURS} distinct points, this cloud has {distinct}")
        return None
    return _attempt(notes, "gauss_bonnet", lambda: core.gauss_bonnet(res, progress=progress))


def _lines(res, direction: str, separation: float, progress):
    """One family of lines of curvature and their vertices' normals (none without a valid point)."""
    if not (res.valid & np.isfinite(res.k1) & np.isfinite(res.k2)).any():
        return [], []
    lines = core.curvature_lines(res, direction=direction, separation=separation, progress=progress)
    return lines, _vertex_normals(lines, res)


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
