"""The estimate pipeline as the worker thread runs it (no Qt widgets, no VTK).

:class:`EstimateWorker` takes a frozen :class:`app.request.EstimateRequest` and emits
an :class:`EstimateOutput` (numpy arrays and frozen core results only). It re-uses
what a change does not touch: the noisy copy (same cloud, noise, seed) and the preview
subsample here; the neighbour graph (k within its head room ``K_MAX_HEADROOM``), the
outlier scores, initial normals, orientation and chosen k through one
:class:`core.stage_cache.StageCache` (and one for the preview), which searches the
neighbours on the points in spatial order as a fresh estimate does. A stale job is
cancelled cooperatively: core calls our progress callback between chunks and we answer
``False`` once a newer request exists (core then raises ``core.Cancelled``).
"""

from __future__ import annotations

import dataclasses
import logging
import time
import traceback
from dataclasses import dataclass, field

import numpy as np
from PySide6.QtCore import Signal

import core
import core.metrics
import core.noise
from core.spacing import mean_spacing
from core.stage_cache import StageCache

from .background_job import Relay
from .fields import compute_fields
from .preview import PREVIEW_K, make_subsample, spread, wants_preview
from .request import EstimateRequest

__all__ = ["EstimateOutput", "EstimateWorker", "K_MAX_HEADROOM"]

LOG = logging.getLogger(__name__)

#: Neighbour graphs are built for at least this many neighbours, so moving the k
#: slider below it re-uses the graph instead of querying the KD-tree again.
K_MAX_HEADROOM = 32
#: Progress signals at most this often (s). Every visible change of the bar repaints the
#: window, which Qt composes whole with OpenGL once it holds a 3D view (25 ms of GUI thread
#: for 1440x900 with llvmpipe, measured at load average 15): at 20 a second that was half a
#: core taken from the estimate; 4 a second still moves the bar smoothly enough.
_PROGRESS_EVERY = 0.25


@dataclass(frozen=True, eq=False)
class EstimateOutput:
    """What the worker hands back: numpy arrays and frozen core results only."""

    gen: int
    request: EstimateRequest
    points: np.ndarray  # the cloud the estimate ran on (noisy copy when noise > 0)
    result: object  # core.CurvatureResult (of the subsample for a preview)
    fields: dict  # name -> (N,) values on every point of ``points``
    spacing: float  # mean distance to the nearest neighbour
    summary: dict | None = None  # core.metrics.summary against the truth
    compare: object | None = None  # core.CurvatureResult of request.compare_method
    compare_fields: dict | None = None
    compare_summary: dict | None = None
    elapsed: float = 0.0
    reused_neighbours: bool = False
    reused_stages: tuple = ()  # stages of core.estimate re-used from the last run (core.stage_cache)
    timings: dict = field(default_factory=dict)
    preview: int = 0  # points of the preview subsample; 0 for the full result


class EstimateWorker(Relay):
    """Runs requests one at a time on a job thread (:meth:`run`).

    :attr:`latest` is written by the GUI thread (a plain int read between chunks).
    The object is created on the GUI thread without a parent (a :class:`app.background_job.Relay`:
    ``slots`` wires its signals); its signals are queued to the GUI thread.
    """

    finished = Signal(object)  # EstimateOutput (full)
    previewed = Signal(object)  # EstimateOutput (preview)
    failed = Signal(int, str)  # gen, message
    cancelled = Signal(int)  # gen
    progress = Signal(int, float, str)  # gen, fraction, stage

    def __init__(self, **slots):
        super().__init__(**slots)
        self.latest = 0
        self._noisy_key = self._noisy = None
        self._sub_key = self._sub = None
        #: the stages of the full estimate (and of the preview): a change of the passes re-runs
        #: only the fit, of k only what follows the search (core.stage_cache); two kept per
        #: stage, so a compare run does not evict the main method's
        self._cache = StageCache(k_max=K_MAX_HEADROOM, keep=2)
        self._sub_cache = StageCache(k_max=K_MAX_HEADROOM)
        self._last_emit = 0.0

    # worker thread ---------------------------------------------------------
    def _callback(self, req: EstimateRequest):
        """Progress callback handed to core: False once the request is stale."""

        def callback(fraction: float, stage: str):
            if req.gen != self.latest:
                return False
            now = time.monotonic()
            if now - self._last_emit > _PROGRESS_EVERY or fraction >= 1.0:
                self._last_emit = now
                self.progress.emit(req.gen, float(fraction), str(stage))
            return None

        return callback

    def _points(self, req: EstimateRequest) -> np.ndarray:
        if self._noisy_key == req.cloud_key:
            return self._noisy
        src = req.source
        if req.noise > 0:
            pts = core.noise.add_noise(src.points, req.noise / 100.0, normals=src.normals, relative=True, seed=req.seed)
        else:
            pts = src.points
        pts = np.array(pts, dtype=float, copy=True)
        pts.flags.writeable = False
        self._noisy_key, self._noisy = req.cloud_key, pts
        self._cache.clear()  # another cloud: free the old one's stages
        self._sub_cache.clear()
        return pts

    def run(self, req: EstimateRequest) -> None:
        """Estimate one request (job thread): a preview first when it is slow, then the full result."""
        if req.gen != self.latest:
            self.cancelled.emit(req.gen)
            return
        callback = self._callback(req)
        try:
            points = self._points(req)
            heavy = req.heavy or bool(req.compare_method)
            if wants_preview(len(points), heavy):
                self.previewed.emit(self._preview(req, points, callback))
            out = self._full(req, points, callback)
        except core.Cancelled:
            self.cancelled.emit(req.gen)
            return
        except Exception as exc:  # noqa: BLE001 - every failure goes to the notifier
            LOG.debug("estimate failed:\n%s", traceback.format_exc())
            self.failed.emit(req.gen, str(exc) or type(exc).__name__)
            return
        if req.gen != self.latest:
            self.cancelled.emit(req.gen)
        else:
            self.finished.emit(out)

    def _preview(self, req: EstimateRequest, points: np.ndarray, callback) -> EstimateOutput:
        """The paper's pipeline (k = 15, or the fixed k) on a subsample, spread to all points."""
        t0 = time.perf_counter()
        callback(0.0, "preview")
        key = (req.source.uid, req.seed)
        if self._sub_key != key:
            self._sub, self._sub_key = make_subsample(req.source.points, seed=req.seed), key
        sub = self._sub
        pts = points[sub.index]
        k = min(PREVIEW_K if req.k_auto else int(req.k), len(pts) - 1)
        normals = req.source.normals[sub.index] if (req.use_input_normals and req.source.normals is not None) else None
        passes = None if req.k_auto else (req.passes if core.METHODS[req.method].uses_passes else None)
        res = core.estimate(pts, normals, k=max(k, 3), method=req.method, passes=passes,
                            orientation=orientation_of(req, normals, sub.index),
                            progress=_sub(callback, 0.0, 0.05, "preview"), cache=self._sub_cache)
        fields = spread(_fields_of(res, req.source, sub.index), sub)
        return EstimateOutput(gen=req.gen, request=req, points=points, result=res, fields=fields,
                              spacing=_spacing(res), elapsed=time.perf_counter() - t0, preview=len(pts))

    def _full(self, req: EstimateRequest, points: np.ndarray, callback) -> EstimateOutput:
        t0 = time.perf_counter()
        timings = {}
        results, kept = self._estimates(req, points, callback, timings)
        sample = req.source.sample
        reference = sample.normals if sample is not None else req.source.normals
        fields = [compute_fields(r, reference_normals=reference, sample=sample) for r in results]
        summaries = [core.metrics.summary(r, sample) if sample is not None else None for r in results]
        for r in results:
            _flags_drawn(r)
        two = len(results) > 1
        return EstimateOutput(
            gen=req.gen, request=req, points=points, result=results[0], fields=fields[0],
            spacing=_spacing(results[0]), summary=summaries[0],
            compare=results[1] if two else None, compare_fields=fields[1] if two else None,
            compare_summary=summaries[1] if two else None, elapsed=time.perf_counter() - t0,
            reused_neighbours="neighbours" in kept, reused_stages=kept, timings=timings,
        )

    def _estimates(self, req: EstimateRequest, points: np.ndarray, callback, timings: dict):
        """core.estimate of the method (and the compared one), through the stage cache;
        returns the results and the stages the main one re-used."""
        normals = req.source.normals if req.use_input_normals else None
        runs = [req.method] + ([req.compare_method] if req.compare_method else [])
        # one search serves both runs (and k slider moves within the head room)
        self._cache.k_max = max(K_MAX_HEADROOM, min(_k_needed(req, len(points)), len(points)))
        results, kept = [], ()
        for i, method in enumerate(runs):
            t, before = time.perf_counter(), dict(self._cache.reused)
            passes = req.passes if core.METHODS[method].uses_passes else None
            results.append(core.estimate(
                points, normals, k=req.k_for(method), method=method, passes=passes,
                orientation=orientation_of(req, normals),
                progress=_sub(callback, i / len(runs), (i + 1) / len(runs), method), cache=self._cache,
            ))
            timings[method] = time.perf_counter() - t
            if i == 0:
                kept = tuple(stage for stage, n in self._cache.reused.items() if n > before.get(stage, 0))
        return results, kept


def orientation_of(req: EstimateRequest, normals, rows=None):
    """What core.estimate gets as ``orientation``: the request's, except that "auto" on a
    cloud that came with its scanners' positions (an E57 file), with no normals in use,
    faces each point's scanner (its ``rows`` of them), as core does for the file's cloud."""
    faced = core.interop.facing(req.source, normals, req.orientation)
    return faced[rows] if rows is not None and faced is req.source.viewpoints else faced


def _flags_drawn(result) -> None:
    """Compute here, on the job thread, the flags the view draws that core computes on first
    use: the border points (grey; an integer k's result searches its own neighbours for
    them, 0.26 s per 100k points, which the GUI thread paid when it coloured the result).
    A preview's are never drawn (:meth:`app.presenter.Presenter._colour_preview`)."""
    result.border  # noqa: B018 - the property computes and keeps them


def _k_needed(req: EstimateRequest, n_points: int) -> int:
    """Neighbours to search for ``req``, or :data:`K_MAX_HEADROOM` when its plan refuses the
    cloud: core.estimate then answers itself, with the same plain reason as for automatic
    k (a 3-point cloud is "fewer than the 4 the method needs for one fit", not a fixed k
    that "must be at least 4 and at most 3"), or with its own error."""
    try:
        return req.k_needed(n_points)
    except ValueError:
        return K_MAX_HEADROOM


def _fields_of(result, source, index: np.ndarray) -> dict:
    """The fields of a result on the points ``index`` of ``source``: the same ones the full
    result has (the errors against the truth and the reference normals' deviation
    included), so the Field box keeps a field the preview shows as well."""
    sample, reference = source.sample, None if source.normals is None else source.normals[index]
    if sample is not None:
        sample = dataclasses.replace(sample, points=sample.points[index], normals=sample.normals[index],
                                     k1=sample.k1[index], k2=sample.k2[index], e1=sample.e1[index],
                                     e2=sample.e2[index], interior=sample.interior[index])
        reference = sample.normals
    return compute_fields(result, reference_normals=reference, sample=sample)


def _spacing(result) -> float:
    """Mean distance to the nearest neighbour, from the graph the result carries."""
    nb = result.neighbours
    return mean_spacing(nb.points, neighbours=nb) if nb is not None and nb.k_max > 1 else 1.0


def _sub(callback, start: float, stop: float, stage: str):
    """Map a 0..1 sub-job onto [start, stop] of the whole job."""

    def inner(fraction: float, stage_: str = stage):
        return callback(start + (stop - start) * min(max(float(fraction), 0.0), 1.0), stage_ or stage)

    return inner
