"""``estimate``: the pipeline neighbours -> initial normals -> orientation -> scale -> fit -> flags.

Arguments are checked once into a frozen :class:`core.planning.EstimatePlan`; each stage
is a function of :mod:`core.stages`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from . import degenerate, interop, one_sheet, stage_cache
from .plain_rows import PlainNeighbours
from ._progress import Progress
from ._validate import MIN_POINTS, as_normals, as_points, masked_as_nan, word
from .frame import signed_directions
from .duplicates import CopiesNeighbours, Merged, NearCopies, expand, find_duplicates, near_copies
from .planning import PER_POINT, EstimatePlan, per_point_views
from .result import CurvatureResult
from .spatial_order import SpatialOrder
from .refinement import refine, settle_signs, turned
from .initial_normals import initial_normals
from .stages import (choose_scale, crease_reference, flags, given_normals, off_volume, orient_signs,
                     outlier_scores, spatial_neighbours)
from .tuning import AUTO_PASSES, JET_DEGREE, MAX_PASSES, OUTLIER_SCORE, PASS_DECAY, PCA_K

__all__ = ["estimate", "AUTO_PASSES", "MAX_PASSES", "OUTLIER_SCORE", "PASS_DECAY", "PCA_K"]
_PLANNED = dict(k="auto", method="nr", passes=None, tol=None, initial="auto", orientation="auto", options=None)


def estimate(
    points,
    normals=None,
    *,
    k="auto",
    method="nr",
    passes=None,
    tol=None,
    initial="auto",
    orientation="auto",
    neighbours=None,
    options=None,
    drop_nonfinite=False,
    progress=None,
    plan=None,
    cache=None,
) -> CurvatureResult:
    """Estimate normals, principal curvatures and directions of a point cloud.

    Parameters
    ----------
    points : (N, 3) array_like of finite coordinates, or a point-cloud object of pyvista,
        Open3D, trimesh or laspy (or a :class:`core.io.Cloud`), whose normals, if it has
        any, are used unless ``normals`` is given (see :mod:`core.interop`).
    normals : (N, 3) array_like, optional. Used as the initial normals (their signs are
        kept); otherwise weighted PCA (eqs. 13–14) estimates them. Rows a file left
        zero, NaN or inf are estimated from their neighbours and rows of another length
        renormalised (``params["normals_repaired"]`` counts them). With k="auto", normals
        rougher than the estimator's own give only their signs
        (:mod:`core.given_normals_check`; ``params["normals_repaired"]["use"]``).
    k : "auto" (default) or int. Neighbourhood size including the point itself (the paper
        uses 15). "auto" (NF/NR only) chooses k per point by a bias–variance rule, see
        :mod:`core.scale`; the result's ``k_point`` holds the choice. Unless set in
        ``options``, "auto" also fits a cubic normal field (``degree=3``), Tukey-robust,
        and NR refines while it removes noise (see ``passes``).
    method : str, one of :data:`core.METHODS` ("nr", "nf", "ct", "qp", "qn", "cf", "cn", "jet").
    passes : int, optional. Normal refinement passes after the first fit (NR, §4.4);
        default: the method's (1 for "nr", 0 otherwise). With k="auto" it is a maximum
        (default 4): a pass is undone, and refinement stops, once it changes the normals by
        more than 0.7x the pass before (smoothing the shape rather than the noise;
        ``params["passes_run"]`` tells how many were kept). 0 gives plain NF.
    tol : float, optional. Stop refining early once the mean change of the normals in a
        pass is below ``tol`` degrees (``passes`` is then the maximum).
    initial : "auto", "pca" or "jet": how normals are estimated when none are given.
        "pca" is the paper's weighted PCA (eqs. 13–14); "jet" refines it with the normal
        of an osculating 2-jet (Cazals & Pouget), markedly closer on curved patches.
        "auto" is "pca" for an integer k (the paper's pipeline) and "jet" for k="auto".
        With k="auto" the initial neighbourhood grows as the square root of the noise,
        measured from the residuals of 2-jets on 15 neighbours (``params["noise"]``, in
        units of their radius; ``params["initial_k"]``; see :data:`core.scale.INITIAL_K0`),
        per region where the noise differs across the cloud (:mod:`core.local_noise`;
        ``params["initial_local"]``: the share of points whose region set theirs),
        and in robust mode leaves out the points flagged as outliers.
    orientation : "auto" (keep given normals; orient estimated ones outward, or toward
        the scanners of a cloud read from an E57 file), "propagate" (each component's
        highest point faces +z), "outward", "keep", a (3,) viewpoint, or an (N, 3) array
        of viewpoints, one per point (each scanner's position for the points it saw);
        signs follow the chord-aware spanning forest of :mod:`core.orientation`, which
        holds across thin parts (the result's ``orientation_confidence``), except toward
        viewpoints, where each normal faces its own.
    neighbours : :class:`core.Neighbours`, optional, from :func:`build_neighbours` on the
        same points with ``k_max >= k``; reused instead of a new search.
    options : dict, optional, method options (see ``core.METHODS[name].options``).
    drop_nonfinite : bool. If True rows with NaN/inf are dropped (and counted in
        ``params["dropped"]``) instead of raising.
    progress : callable(fraction, stage) -> None | False, optional. Returning False (or
        any false value but None: numpy's False_, 0) cancels: :class:`core.Cancelled` is raised.
    plan : :class:`core.EstimatePlan`, optional, from :func:`core.plan` for these points
        (after dropping non-finite rows), instead of ``k``, ``method``, ``passes``,
        ``tol``, ``initial``, ``orientation`` and ``options`` (leave those at their
        defaults). Through it the noise, the typical fold spread and the typical crease
        residual can be fixed rather than measured on this cloud (``params["noise"]``,
        ``params["fold_typical"]``, ``params["crease_typical"]`` report what was used).
    cache : :class:`core.stage_cache.StageCache`, optional. Passed to successive calls on
        the same cloud, it keeps the stages a change does not touch (neighbours to the
        chosen k when only ``passes`` or ``tol`` change); the result is bit-identical.

    Returns
    -------
    CurvatureResult

    Examples
    --------
    >>> from core import estimate, shapes
    >>> s = shapes.sphere(2000, radius=2.0, seed=1)
    >>> r = estimate(s.points)
    >>> bool(abs(np.median(r.mean) - 0.5) < 0.01)
    True
    """
    obj, (points, normals) = points, interop.unwrap(points, normals)  # harden: pyvista/Open3D/trimesh/laspy objects
    orientation, views = _per_point(orientation, obj, normals)  # an E57 or PTX cloud's own: its scanners'
    pts, kept = as_points(points, drop_nonfinite=drop_nonfinite)
    if len(pts) < MIN_POINTS:
        raise ValueError(f"points must hold at least {MIN_POINTS} points, got {len(pts)}")
    # "Auto", "NR", "Outward": keywords in any case (the result reports them in lower case)
    asked = dict(k=word(k), method=method, passes=passes, tol=tol, initial=word(initial),
                 orientation=word(orientation), options=options)
    # harden: every argument checked alike on every cloud, degenerate or not, before any work
    checked = degenerate.checked_plan(len(pts), asked, lambda n, ask: _plan(plan, n, ask, normals is not None),
                                      planned=plan is not None)
    given = None if normals is None else as_normals(_given_rows(normals, kept), len(pts), repair=True)
    report, cache, views = Progress(progress), stage_cache.checked(cache), _views(checked, views, kept)
    invalid = degenerate.invalid_if_degenerate(pts, kept, given, asked, checked, neighbours=neighbours)
    if invalid is not None:  # harden: valid=False, no crash
        return invalid
    merged = find_duplicates(pts, cache=cache)  # harden: copies of a point are estimated once, at their position
    args = dict(plan=plan, neighbours=neighbours, progress=progress, cache=cache, views=views)
    if merged is not None:
        return _on_distinct(merged, pts, kept, normals, asked, **args)
    plan = checked

    try:
        front = prepare(pts, given, plan, neighbours, report, cache=cache, near=True, sort_given=True, views=views,
                        consistent=True)
    except NearCopies as found:  # points on top of others (float rounding of one point written twice)
        if cache is not None:
            cache.remember(pts, found.merged)
        return _on_distinct(found.merged, pts, kept, normals, asked, **args)
    if not front.scale.on_jet.any():  # no jet is a result: their frames are not held while fitting
        front = front._replace(scale=front.scale._replace(jets=None))
    best = refine(front.pts, front.init, front.outlier, front.fit_nb, front.scale, plan,
                  report.sub(0.7 if plan.auto else 0.45, 1.0))
    front = front._replace(scale=front.scale._replace(jets=None))  # merged into best: 86 MiB less at 1M points
    if cache is None and isinstance(front.nb, PlainNeighbours):  # the fits are done: their graph made plain, read
        front = front._replace(nb=front.nb.release(), fit_nb=None)  # without copies (-141 MiB at 1M, two sheets)
    best = turned(best, front.turn)  # the caller's signs, where the fits read others (orient_signs)
    best, confidence = settle_signs(front.pts, best, front.nb, plan, front.confidence)
    marks = flags(best.fit, front.scores, plan, front.reference, nb=front.nb, confidence=confidence)
    stages = front.order.to_caller(_reported((front.init, best, front.scale, marks)))
    nb = neighbours if neighbours is not None else stage_cache.caller_neighbours(cache, front.order, front.nb, pts)
    report(1.0, "done")
    return _result(pts, kept, plan, stages=stages, neighbours=nb, repaired=front.repaired)


def _per_point(orientation, obj, normals):
    """``(orientation, views)``: an (N, 3) array of viewpoints is :data:`PER_POINT` with the
    array as ``views``; so is "auto" on a cloud ``obj`` that carries its scanners'
    positions (:func:`core.interop.facing`) with no ``normals`` in use; else as given, no views."""
    try:
        per_point = not isinstance(orientation, str) and np.ndim(orientation) == 2
    except ValueError:  # a ragged sequence: planning names it
        per_point = False
    if per_point:
        return PER_POINT, orientation
    faced = interop.facing(obj, normals, orientation)
    return (orientation, None) if faced is orientation else (PER_POINT, faced)


def _views(plan, views, kept):
    """The viewpoints of the points kept, checked against the caller's points, where the
    plan faces viewpoints of their own; None otherwise."""
    if plan.orientation != PER_POINT:
        return None
    if views is None:
        raise ValueError(f"orientation {PER_POINT!r} needs the viewpoints themselves: pass orientation=an "
                         f"({len(kept)}, 3) array, one viewpoint per point")
    return per_point_views(views, len(kept))[kept]


def _given_rows(normals, kept) -> np.ndarray:
    """The given normals' rows of the points kept (their shape checked against the caller's points)."""
    shape = np.shape(normals)
    if shape != (len(kept), 3):
        raise ValueError(f"normals must have shape ({len(kept)}, 3) to match points, got shape {shape}")
    return masked_as_nan(normals)[kept]


def _on_distinct(merged: Merged, pts, kept, normals, asked, *, plan, neighbours, progress, cache,
                 views) -> CurvatureResult:
    """:func:`estimate` of a cloud with duplicate points: its distinct positions estimated,
    every copy given its position's answer (:mod:`core.duplicates`), planned for the caller's
    count of points as the tiles of :mod:`core.tiled` are (the candidates with k="auto"),
    unless fewer places than the largest candidate leave only theirs. A graph passed back
    from such a result serves again; any other given graph was searched on the copies and
    is not used."""
    m, extra = len(merged.first), {"duplicates": merged.copies, "dropped": int(np.count_nonzero(~kept))}
    # m >= 3: one or two places are caught before, as identical or collinear points
    given = None if normals is None else _given_rows(normals, kept)[merged.first]
    if m < degenerate.min_k_asked(asked):  # fewer places than one fit needs: all invalid, as on so few points
        return expand(estimate(merged.points, given, **asked), merged, pts, extra)
    if isinstance(asked["k"], (int, np.integer)) and not isinstance(asked["k"], (bool, np.bool_)) and asked["k"] > m:
        raise ValueError(f"k={asked['k']} exceeds the {m} distinct positions of the cloud ({merged.copies} of its "
                         f"{len(pts)} points are copies of others)")
    given_plan, plan = plan, _plan(plan, len(pts), asked, normals is not None)  # the caller's count's candidates, as tiles
    if plan.k_search > m and given_plan is None:  # a small cloud: the candidates its places allow
        plan = _plan(None, m, asked, normals is not None)
    if plan.k_search > m:
        raise ValueError(f"plan searches {plan.k_search} neighbours but the cloud has only {m} distinct positions "
                         f"({merged.copies} of its {len(pts)} points are copies); make a plan for {m} points")
    reuse = neighbours._nb if isinstance(neighbours, CopiesNeighbours) and neighbours.matches(pts) else None
    res = estimate(merged.points, given, plan=replace(plan, n_points=m), neighbours=reuse, progress=progress,
                   cache=cache, orientation="auto" if views is None else views[merged.first])
    return expand(res, merged, pts, extra)


class Prepared(NamedTuple):
    """What the fits start from: the points ``pts`` in spatial ``order`` (the caller's
    order is ``order.to_caller``), neighbours ``nb``, outlier ``scores`` and flags
    ``outlier``, oriented initial normals ``init`` (and the counts of their ``repaired``
    rows when given, the orientation ``confidence``), the linear ``reference`` fit creases
    are judged by (k="auto") and the ``scale`` per point; ``fit_nb`` is ``nb`` as the
    normals are fitted on it (each point's own sheet first, :mod:`core.one_sheet`), the
    orientation and the result read ``nb``; ``turn``: where the fits read the other sign
    than the caller decided (:func:`core.stages.orient_signs`), None: nowhere."""

    pts: np.ndarray
    nb: object
    scores: np.ndarray
    outlier: np.ndarray
    init: object
    repaired: dict | None
    confidence: np.ndarray
    reference: object
    scale: object
    order: SpatialOrder
    fit_nb: object
    turn: np.ndarray | None = None


def prepare(pts, normals, plan, neighbours, report, *, cache=None, near=False, sort_given=False,
            views=None, consistent=False) -> Prepared:
    """The stages before the fits: neighbours -> outlier scores -> initial normals ->
    orientation -> scale choice (shared by :func:`estimate` and the tiles of
    :mod:`core.tiled`, which run the fits' passes themselves). They run on the points in
    spatial order (:mod:`core.spatial_order`; given ``neighbours``: in the caller's unless
    ``sort_given``), each one run or re-used through ``cache`` (:mod:`core.stage_cache`);
    ``views``: each point's viewpoint where the plan faces them (:data:`core.planning.PER_POINT`);
    ``consistent``: the scale rule and fits may read consistent signs where the caller's are
    mixed (``Prepared.turn``; the tiles, which face their viewpoints afterwards, do not)."""
    run = stage_cache.memo(cache, pts, normals, plan, views)  # each stage: run, or re-used from the cache
    nb, order = run.neighbours(lambda k: spatial_neighbours(pts, plan, neighbours, report.sub(0.0, 0.3), k=k,
                                                            sort_given=sort_given), neighbours)
    if near:  # places of points on top of others, for estimate() to merge (core.duplicates.near_copies)
        _near_copies(pts, nb, order, plan)
    pts, normals, views = nb.points, order.to_sorted(normals), order.to_sorted(views)  # the stages run in spatial order
    # the initial graph is taken afresh at each use: a view held across the stages would keep
    # the narrow search alive after a noisy cloud widens it (+480 MB at 1M points)
    scores = run("scores", lambda: outlier_scores(pts, nb.take(plan.k_initial)[0]))
    outlier = scores > OUTLIER_SCORE
    fit_nb = nb  # with k="auto", each point's own sheet first (core.one_sheet): what the normals are fitted on
    if plan.auto and normals is None:
        sheets = run("sheets", lambda: one_sheet.graphs(pts, nb, plan.k_initial))
        if sheets is not None:  # the plain nearest are then served from the fits' graph (core.plain_rows)
            fit_nb, nb = sheets
    if normals is None:
        init, repaired = run("initial", lambda: initial_normals(pts, fit_nb, plan, outlier, report, views)), None
    else:
        init, repaired = run("initial", lambda: given_normals(pts, normals, nb, plan, outlier))
    init, confidence, turn = run("orientation", lambda: orient_signs(pts, init, nb.take_indices(plan.k_initial), plan,
                                                                      rank=order.order, views=views, consistent=consistent))
    report(0.45, "orientation")

    reference = None
    if plan.auto:
        reference = run("reference", lambda: crease_reference(pts, init.normals, init.has_normal, fit_nb, plan,
                                                                report.sub(0.45, 0.47)))
    inliers = init.has_normal & ~outlier if plan.robust else init.has_normal  # outliers sit out the choice of k
    kc = run("scale", lambda: choose_scale(pts, init.normals, fit_nb, inliers, plan, report.sub(0.47, 0.7),
                                           scores=scores, k_initial=init.k, part_sizes=init.part_sizes))
    return Prepared(pts, nb, scores, outlier, init, repaired, confidence, reference, kc, order, fit_nb, turn)


def _near_copies(pts, nb, order: SpatialOrder, plan) -> None:
    """Raise :class:`core.duplicates.NearCopies` (places in the caller's rows of ``pts``)
    if the graph ``nb`` (on the points in ``order``) shows points on top of others."""
    idx, dist = nb.take(plan.k_initial)
    found = near_copies(idx, dist, nb.points, rank=order.order, spatial=order.order is not None)
    if found is None:
        return
    if order.order is not None:  # rows of the sorted points -> the caller's (a place: its copies' mean, core.clumps)
        inverse = np.empty_like(found.inverse)
        inverse[order.order] = found.inverse
        found = Merged(found.points, order.order[found.first], inverse)
    raise NearCopies(found)


def _plan(plan, n, asked, normals_given) -> EstimatePlan:
    if plan is None:
        return EstimatePlan.build(n, normals_given=normals_given, **asked)
    if not isinstance(plan, EstimatePlan):
        raise ValueError(f"plan must be a core.EstimatePlan (from core.plan) or None, got {type(plan).__name__}")
    if plan.n_points != n:
        raise ValueError(f"plan was made for {plan.n_points} points, these are {n}; make a new plan")
    if plan.orientation_label == "auto" and (plan.orientation == "keep") != normals_given:
        raise ValueError(f"plan was made with normals_given={not normals_given} (orientation 'auto' resolved to "
                         f"{plan.orientation!r}); make it with normals_given={normals_given}")
    changed = sorted(name for name, value in asked.items() if value is not _PLANNED[name] and value != _PLANNED[name]
                     and not (name == "orientation" and value == plan.orientation == PER_POINT))
    if changed:
        raise ValueError(f"pass either plan or {', '.join(changed)}, not both")
    return plan


def _reported(stages):
    """The stages' outputs (initial normals, refined fit, k per point, flags) cut to the
    arrays :func:`_result` reads, the points on no surface made invalid (:func:`core.stages.off_volume`)
    and the result's normals chosen (a fit's where valid, else its input's): only these go
    back to the caller's order (the initial normals, the fit's residuals, its input normals
    and the scale's ``k`` and ``quiet`` were moved there too and dropped)."""
    init, best, kc, marks = stages
    fit = off_volume(best.fit, marks.volumetric)
    chosen = np.where(fit.valid[:, None], fit.normals, best.input_normals)
    best = best._replace(fit=fit._replace(normals=chosen, rms=None, spread=None), input_normals=None)
    return init._replace(normals=None, has_normal=None), best, kc._replace(k=None, quiet=None, jets=None), marks


def _result(pts, kept, plan, *, stages, neighbours, repaired) -> CurvatureResult:
    """The result and its params from the stages' outputs as :func:`_reported` cut them
    (initial normals, refined fit with the result's normals, k per point, flags);
    ``repaired``: the counts of the given normals' repair, or None when no normals were
    given."""
    init, best, kc, marks = stages
    normals_given = repaired is not None
    fit = best.fit
    params = dict(
        method=plan.method.name, k=plan.k, passes=plan.passes, passes_run=best.passes_run, tol=plan.tol,
        orientation=plan.orientation_label, options=dict(plan.options), n_points=len(pts),
        dropped=int(np.count_nonzero(~kept)), normals_given=normals_given,
        initial=None if normals_given else plan.initial, initial_k=init.k, noise=init.noise,
        fold_typical=init.fold_typical, initial_local=init.local, crease_typical=marks.crease_typical,
        normals_repaired=repaired,
        jet_fraction=float(kc.on_jet.mean()),
    )
    if marks.volumetric is not None:  # k="auto": points on no surface at any scale, made invalid (core.volumetric)
        params["volumetric"] = int(np.count_nonzero(marks.volumetric))
    fitted = np.where(fit.degree > 0, fit.degree.astype(np.int64), plan.options.get("degree", -1))  # a fit may fall a degree
    degree = np.where(kc.on_jet, JET_DEGREE if kc.jet_degree is None else kc.jet_degree, fitted)
    e1, e2 = signed_directions(fit.e1, fit.e2)
    return CurvatureResult(
        points=pts, normals=fit.normals, k1=fit.k1, k2=fit.k2, e1=e1, e2=e2, valid=fit.valid, k_point=kc.k_point, degree_point=degree, outlier_score=marks.outlier_score,
        crease=marks.crease, _border=marks.border, orientation_confidence=marks.orientation_confidence,
        _crease_residual=marks.crease_residual,
        method=plan.method.name, k=plan.k, passes=plan.passes, params=params, neighbours=neighbours,
    )
