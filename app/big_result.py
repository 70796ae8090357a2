"""Results larger than memory: a level-of-detail preview of a LAS/LAZ result file.

A tiled estimate (:mod:`core.tiled`) writes LAS/LAZ with per-point fields (``nx ny nz
k1 k2 e1_* e2_* gaussian mean valid k``). The viewer neither reads such a file whole nor
estimates it again when it holds more than :data:`BUDGET` points: :class:`BigResultView`
reads an evenly spread subsample of at most ``budget`` points with their stored fields
(streamed in chunks, :func:`core.io.las_sample.sample_las`, on a daemon thread) and shows
it through the window's presenter (fields, histogram, glyphs, picking). When the camera
stops on a region the sample shows thinned, the points inside the view box are read
again, up to the budget (:meth:`BigResultView.refine`); zooming back out to the whole
cloud returns to the overview. Estimate parameters do not apply to a stored result: the
window asks :func:`is_stored` and sends no estimate while one is shown.
"""

from __future__ import annotations

import threading
import time
import traceback
from dataclasses import dataclass

import numpy as np
from PySide6.QtCore import QObject, QTimer, Signal, Slot

import core
from core.io.las_sample import sample_las
from core.io.las_stream import open_las

from . import framing
from .background_job import Relay
from .jobs import lower_priority
from .fields import compute_fields
from .request import EstimateRequest
from .source import CloudSource
from .text import display_name
from .worker import EstimateOutput

__all__ = ["BUDGET", "BigResultView", "StoredSource", "is_stored", "read_view", "view_of", "wants"]

#: points shown at once: the viewer draws 1M points at ~1 fps under software OpenGL and
#: its 60k-point stand-in while the camera moves (README, "The viewer"), and a 1M-point
#: sample with its fields holds ~0.2 GB
BUDGET = 1_000_000
#: a region is re-read when it would show at least this many times more points than now
REFINE_GAIN = 2.0
#: wait this long after the camera stops before reading (a burst of wheel steps reads once)
SETTLE_MS = 400
#: dimensions that make a LAS/LAZ a curvature result, and those read with the points
_NEEDS = ("nx", "ny", "nz", "k1", "k2")
_READ = ("nx", "ny", "nz", "k1", "k2", "e1_x", "e1_y", "e1_z", "e2_x", "e2_y", "e2_z", "valid", "k", "border")


@dataclass(frozen=True, eq=False)
class StoredSource(CloudSource):
    """The points on screen of a stored result: a subsample of ``file_points`` points,
    of the whole file or of the region ``box`` ((3,), (3,)) of it."""

    file_points: int = 0
    matched: int = 0  # file points in the box (all of them for the overview)
    box: tuple | None = None
    rows: np.ndarray | None = None  # the shown points' rows in the file


def is_stored(source) -> bool:
    """Whether ``source`` is a stored result on screen (no estimate applies to it)."""
    return isinstance(source, StoredSource)


def wants(path, budget: int | None = None) -> bool:
    """Whether ``path`` is a LAS/LAZ curvature result with more than ``budget`` points
    (header only; an unreadable file is left to the normal loader, which reports it)."""
    if not str(path).lower().endswith((".las", ".laz")):
        return False
    try:
        info = open_las(path)
    except (ValueError, OSError):
        return False
    return info.count > (BUDGET if budget is None else budget) and all(n in info.dims for n in _NEEDS)


def read_view(path, budget: int, box=None, progress=None) -> EstimateOutput:
    """Read the sample of ``path`` (in ``box``, if given) as an output the presenter shows."""
    t0 = time.perf_counter()
    info = open_las(path)
    sample = sample_las(path, budget, names=[n for n in _READ if n in info.dims], box=box, progress=progress)
    f = sample.fields
    name = display_name(path)
    part = "" if box is None else " (region)"
    src = StoredSource(name=f"{name}{part} — {len(sample.points):,} of {sample.matched:,} points",
                       points=sample.points, normals=_stack(f, "n"), path=path, file_points=info.count,
                       matched=sample.matched, box=None if box is None else tuple(map(tuple, box)),
                       rows=sample.rows)
    src.geometry  # box, spacing, drawing order: computed here, on the reading thread, not on the GUI's
    res = _result(sample.points, f)
    req = EstimateRequest(gen=0, source=src, k=int(np.median(res.k_point)) if len(res.k_point) else 0, method="stored")
    return EstimateOutput(gen=0, request=req, points=sample.points, result=res, fields=compute_fields(res),
                          spacing=_spacing(sample.points), elapsed=time.perf_counter() - t0, preview=0)


def _stack(f, prefix) -> np.ndarray | None:
    names = ["nx", "ny", "nz"] if prefix == "n" else [f"{prefix}_{c}" for c in "xyz"]
    if not all(n in f for n in names):
        return None
    return np.column_stack([np.asarray(f[n], dtype=float) for n in names])


def _result(points, f) -> core.CurvatureResult:
    """A CurvatureResult of the stored fields (NaN where the file has none), with the
    sample's own neighbours for picking."""
    n = len(points)
    nan3 = np.full((n, 3), np.nan)
    k1, k2 = np.asarray(f["k1"], dtype=float), np.asarray(f["k2"], dtype=float)
    valid = np.asarray(f["valid"]).astype(bool) if "valid" in f else np.isfinite(k1) & np.isfinite(k2)
    k_point = np.asarray(f["k"], dtype=np.int64) if "k" in f else np.full(n, -1)
    e1, e2 = _stack(f, "e1"), _stack(f, "e2")
    border = np.asarray(f["border"]).astype(bool) if "border" in f else np.zeros(n, dtype=bool)
    nb = core.build_neighbours(points, int(min(16, n - 1))) if n > 3 else None
    return core.CurvatureResult(points=points, normals=_stack(f, "n"), k1=k1, k2=k2,
                                e1=nan3 if e1 is None else e1, e2=nan3 if e2 is None else e2, valid=valid,
                                method="stored", k=int(np.median(k_point)) if n else 0, passes=None,
                                neighbours=nb, k_point=k_point, _border=border)


def _spacing(points) -> float:
    if len(points) < 2:
        return 1.0
    from core.spacing import mean_spacing

    return float(mean_spacing(points))


class _Relay(Relay):
    done = Signal(int, object)  # generation, EstimateOutput
    failed = Signal(int, str)


def view_of(window) -> "BigResultView":
    """The window's BigResultView (made on first use)."""
    view = getattr(window, "_big_result_view", None)
    if view is None:
        view = window._big_result_view = BigResultView(window)
    return view


class BigResultView(QObject):
    """Shows a stored result in ``window`` as a level-of-detail sample, refined on zoom.

    Signals: ``shown(EstimateOutput)`` after a sample (overview or region) is on screen.
    """

    shown = Signal(object)

    def __init__(self, window, budget: int | None = None):
        super().__init__(window)
        self.window, self.budget = window, int(BUDGET if budget is None else budget)
        self.path = None
        self.overview: EstimateOutput | None = None
        self.thread: threading.Thread | None = None  # the read under way (or the last one)
        self._gen = 0
        # parentless (app.background_job): a late answer after the window closed reaches nobody
        self._relay = _Relay(done=self._on_read, failed=self._on_failed)
        self._settle = QTimer(self)
        self._settle.setSingleShot(True)
        self._settle.setInterval(SETTLE_MS)
        self._settle.timeout.connect(self.check_view)
        window.state.changed.connect(self._on_state)
        iren = getattr(window.plotter, "iren", None)
        style = iren.interactor.GetInteractorStyle() if iren is not None else None
        if style is not None:
            style.AddObserver("EndInteractionEvent", lambda *_: self._settle.start())

    @property
    def active(self) -> bool:
        """Whether this view's result is on screen."""
        return is_stored(self.window.state.source) and self.window.state.source.path == self.path

    def open(self, path, *, remember: bool = False):
        """Read the overview of ``path`` (returns at once; :attr:`shown` follows);
        ``remember`` lists it in File > Open recent. The cloud on screen, and its estimate,
        stay until the overview arrives (a file that cannot be read leaves them as they were)."""
        if remember:
            self.window.recent_menu.add(path)
        self.path, self.overview = path, None
        self.window.status_label.setText(f"reading a {self.budget:,}-point preview of {display_name(path)}…")
        self.window.progress.set_progress(-1.0, "reading…")
        self._read(None)

    def refine(self, lo, hi) -> None:
        """Read the points inside the box [lo, hi] (up to the budget) and show them."""
        self.window.status_label.setText(f"reading the region of {display_name(self.path)} in view…")
        self._read((np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)))

    def check_view(self) -> None:
        """The camera stopped: refine to the region in view, or go back to the overview."""
        if not self.active or self.overview is None:
            return
        box, seen = self.view_box()
        src = self.window.state.source
        if box is None:
            return
        if seen == len(src.points) and src.box is not None:  # everything shown is in view: zoomed out
            self._show(self.overview)
        elif seen * REFINE_GAIN <= self.budget and src.matched > len(src.points):  # a thinned region
            self.refine(*box)

    def view_box(self):
        """(lo, hi) box of the shown points inside the view (padded by 5 %), and their count."""
        pts = self.window.state.source.points
        x, y, depth = framing.projection(self.window.plotter.renderer, pts)
        x0, y0, x1, y1 = framing.free_region(self.window.plotter.renderer)
        seen = (x >= x0) & (x <= x1) & (y >= y0) & (y <= y1) & (np.abs(depth) <= 1.0)
        if not seen.any():
            return None, 0
        lo, hi = pts[seen].min(axis=0), pts[seen].max(axis=0)
        pad = 0.05 * (hi - lo) + 1e-9 * (1.0 + np.abs(hi))
        return (lo - pad, hi + pad), int(seen.sum())

    def _read(self, box) -> None:
        self._gen += 1
        gen, path, budget, relay, window = self._gen, self.path, self.budget, self._relay, self.window

        def still_wanted(_fraction, _stage):
            return gen == self._gen and not window._closed  # a newer read, another cloud or closing stops it

        def job():
            lower_priority()
            try:
                relay.done.emit(gen, read_view(path, budget, box, progress=still_wanted))
            except core.Cancelled:
                return
            except (ValueError, OSError) as exc:
                relay.failed.emit(gen, str(exc))
            except Exception as exc:  # noqa: BLE001 - a reader bug must not take the app down
                relay.failed.emit(gen, f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}")

        self.thread = threading.Thread(target=job, name="darboux-big-result", daemon=True)
        self.thread.start()

    @Slot(int, object)
    def _on_read(self, gen, out) -> None:
        if gen != self._gen or self.window._closed:
            return
        if out.request.source.box is None:
            self.overview = out
        self._show(out)

    def _show(self, out) -> None:
        """Put a sample on screen: the window's source (set quietly: no estimate, the camera
        stays, except for a new file) and the presenter's output."""
        w, src = self.window, out.request.source
        first = not self.active
        w.state.set(picked=None)
        w.state.blockSignals(True)
        try:
            w.state.set(source=src)
        finally:
            w.state.blockSignals(False)
        if first:
            w.estimator.abandon()  # the estimate of the cloud this one replaces
            w.presenter.clear()
            w.scene.set_cloud(out.points, reset_camera="front", geometry=src.geometry)  # (from the reading thread)
            w.setWindowTitle(f"Darboux — {display_name(src.path)}")
        w.presenter.show(out)
        region = " in the region in view" if src.box is not None else ""
        w.scene.set_title(f"stored result: {len(src.points):,} of {src.matched:,} points{region}\n"
                          f"{display_name(src.path)} (zoom in for detail)")
        w.status_label.setText(f"{display_name(src.path)}: {src.file_points:,} points stored, showing "
                               f"{len(src.points):,} of the {src.matched:,}{region or ' in the file'}")
        w.progress.set_busy(False)
        w.render_all()
        self.shown.emit(out)
        w.result_shown.emit(out)

    @Slot(int, str)
    def _on_failed(self, gen, message) -> None:
        if gen != self._gen or self.window._closed:
            return
        w = self.window
        w.progress.set_busy(w.estimator.busy or w.loader.pending is not None)
        w.notifier.notify("error", f"Could not read the result. {message.splitlines()[0]}", message)
        if not self.active:  # the cloud on screen stays, estimate and all: its status line again
            w._show_status()

    def _on_state(self, name) -> None:
        if name == "source" and not is_stored(self.window.state.source):
            self._gen += 1  # another cloud: drop (and stop) reads under way
