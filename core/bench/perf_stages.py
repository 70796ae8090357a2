"""The stage rows of ``python -m core bench perf``: every stage of :func:`core.estimate` at an
integer k, run by the estimate's own functions in its order and on its (spatial) order of
the points, so that the rows add up to the end-to-end figure.

The rows before this module ran the orientation, the fits and the back-to-the-caller step by
hand and left out the outlier scores, the re-decided signs (:func:`core.refinement.settle_signs`:
a second chord-aware evidence on the refined normals, 0.6-1 CPU s of a 1M-point estimate) and
the flags; the table's orientation row then read 1.09 s against ~2.5 s of sign work in the
estimate. :func:`stage_rows` mirrors :func:`core.estimate.estimate` and
:func:`core.estimate.prepare` for an integer k without given normals or a stage cache.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .. import degenerate
from .._progress import Progress
from .._validate import as_points
from ..estimate import _plan, _reported
from ..refinement import refine, settle_signs
from ..initial_normals import initial_normals
from ..stages import choose_scale, flags, orient_signs, outlier_scores, spatial_neighbours
from ..stage_cache import caller_neighbours
from ..tuning import OUTLIER_SCORE


def stage_rows(points, k, timed, *, kept=None):
    """``[(name, wall seconds, sampler), ...]``, one row per stage of ``estimate(points, k=k,
    method="nr")``; ``timed(fn)`` returns ``(fn(), seconds, sampler)``. ``kept``: a dict that
    receives the result's ``normals`` in the caller's order (what the estimate returns)."""
    rows = []

    def stage(name, fn):
        out, dt, mem = timed(fn)
        rows.append((name, dt, mem))
        return out

    asked = dict(k=k, method="nr", passes=None, tol=None, initial="auto", orientation="auto", options=None)

    def checked():
        pts, kept = as_points(points)
        if degenerate.invalid_if_degenerate(pts, kept, None, asked) is not None:
            raise ValueError("a degenerate cloud has no stages to time")
        return pts, _plan(None, len(pts), asked, False)

    pts, plan = stage("checks + plan", checked)
    report = Progress()
    nb, order = stage("neighbours (kd-tree, spatial order)", lambda: spatial_neighbours(pts, plan, None, report))
    sp = nb.points
    idx_p, _ = nb.take(plan.k_initial)
    scores = stage("outlier scores", lambda: outlier_scores(sp, idx_p))
    outlier = scores > OUTLIER_SCORE
    init = stage("PCA normals (eqs. 13-14)", lambda: initial_normals(sp, nb, plan, outlier, report))
    init, confidence, _ = stage("orientation (orientation.orient)",
                             lambda: orient_signs(sp, init, idx_p, plan, rank=order.order))
    inliers = init.has_normal & ~outlier if plan.robust else init.has_normal
    kc = stage("scale (k per point)", lambda: choose_scale(sp, init.normals, nb, inliers, plan, report,
                                                          scores=scores, k_initial=init.k))
    best = stage(f"NF fits + frames, {plan.passes + 1} passes (NR)",
                 lambda: refine(sp, init, outlier, nb, kc, plan, report))
    best, confidence = stage("signs re-decided (orientation.resettle)",
                             lambda: settle_signs(sp, best, nb, plan, confidence))
    marks = stage("flags", lambda: flags(best.fit, scores, plan, None, nb=nb, confidence=confidence))
    back, _ = stage("back to the caller's order", lambda: (order.to_caller(_reported((init, best, kc, marks))),
                                                           caller_neighbours(None, order, nb, pts)))
    if kept is not None:
        kept["normals"] = back[1].fit.normals
    return rows


def summed(rows, t_all, cpu_all):
    """The sum of the stage rows and what the end-to-end wall ``t_all`` and CPU ``cpu_all``
    hold beyond them (Python between the stages, the result object; negative when the
    stages ran slower than the estimate they were compared with), as rows whose sampler
    carries only ``cpu`` (no memory)."""
    wall = float(np.sum([dt for _, dt, _ in rows]))
    cpu = float(np.sum([mem.cpu for _, _, mem in rows]))
    return [("sum of the stages above", wall, SimpleNamespace(cpu=cpu)),
            ("end to end minus that sum", t_all - wall, SimpleNamespace(cpu=cpu_all - cpu))]
