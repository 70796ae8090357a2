"""The stages of :func:`core.estimate`, each a function of a few named inputs returning
a small named result: neighbours -> outlier scores -> initial normals -> orientation ->
scale choice -> fit/refine (:mod:`core.refinement`) -> flags. A tiled engine runs them with quantities fixed on
the whole cloud through the :class:`core.planning.EstimatePlan`."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import anchors, kernels, parts, plane_spread, scale
from .border import border_of_valid, served_by
from .neighbours import Neighbours, search_neighbours
from .normal_repair import repair_normals
from .given_normals_check import max_roughness, roughness, signed_like
from .initial_normals import Initial, initial_normals, initial_rows
from .orientation import orient
from ._progress import Progress
from .spatial_order import SpatialOrder, given_in_spatial_order
from .wide_neighbours import search_in_spatial_order
from .fits import Fit, fit_all, invalid_at
from .creases import crease_residuals, judge_creases as _creases
from .off_surface import off_surface
from .volumetric import volumetric
from .tuning import JET_SCORE, OUTLIER_FLOOR, OUTLIER_SCORE, SEARCH_WIDTH


class Flags(NamedTuple):
    """Per-point flags of the result (another flag is one more field here and one more
    line in :func:`flags`): ``outlier_score`` (N,), ``crease`` (N,) bool, the typical
    residual the creases were judged against, ``border`` (N,) bool (see
    :mod:`core.border`) and the ``orientation_confidence`` (N,) of :func:`core.orientation.orient`
    (re-judged on the refined normals by :func:`settle_signs` where it re-decided the signs)."""

    outlier_score: np.ndarray
    crease: np.ndarray
    crease_typical: float
    border: np.ndarray | None = None
    orientation_confidence: np.ndarray | None = None
    crease_residual: np.ndarray | None = None  # see :func:`crease_residuals`
    volumetric: np.ndarray | None = None  # (N,) bool, on no surface at any scale: :mod:`core.volumetric`


def find_neighbours(pts, plan, neighbours, report) -> Neighbours:
    """The ``plan.k_search`` nearest neighbours: searched, or the given ones checked."""
    if neighbours is None:
        return search_neighbours(pts, plan.k_search, progress=report)
    if not isinstance(neighbours, Neighbours):
        raise ValueError(f"neighbours must be a core.Neighbours, got {type(neighbours).__name__}")
    if neighbours.k_max < plan.k_search:
        raise ValueError(f"neighbours were built with k_max={neighbours.k_max} < k={plan.k_search}; rebuild them")
    if not neighbours.matches(pts):
        raise ValueError("neighbours were built on different points; rebuild them")
    return neighbours


def spatial_neighbours(pts, plan, neighbours, report, *, k=None, sort_given=False) -> tuple[Neighbours, SpatialOrder]:
    """:func:`find_neighbours`, searched on the points in spatial order (the stages then run
    on ``nb.points``, :mod:`core.spatial_order`); given neighbours are used as they are,
    or put in spatial order too if ``sort_given`` (:func:`core.spatial_order.given_in_spatial_order`).
    ``k``: search that many (>= ``plan.k_search``, a cache's head room) instead."""
    if neighbours is not None:
        given = find_neighbours(pts, plan, neighbours, report)
        return given_in_spatial_order(pts, given) if sort_given else (given, SpatialOrder(None))
    nb, order = search_in_spatial_order(pts, plan.k_search if k is None else k, progress=report,
                                        width=search_width(plan))
    return nb, SpatialOrder(order)


def search_width(plan) -> int | None:
    """Neighbours searched per point at first (:class:`core.wide_neighbours.WidenableNeighbours`
    serves the rest): with k="auto" :data:`core.tuning.SEARCH_WIDTH`; with an integer k all
    (None), a cache's head room included (a viewer's k slider moves within it unsearched)."""
    return min(SEARCH_WIDTH, plan.n_points) if plan.auto else None


def outlier_scores(pts, idx) -> np.ndarray:
    """Distance of each point from its neighbours' plane in units of their spread, raised
    to the off-surface score where that alone flags the point (:mod:`core.off_surface`:
    the robust planes of its own and its neighbours' rows, which outliers among the
    neighbours or a curved surface's sag do not hide it from); inf for the points of a
    group smaller than a neighbourhood, apart from the rest
    (:func:`core.kernels.isolated_groups`: a clump floating off the surface, whose own
    points made up its neighbours' plane). Below the flag the plane's score is kept: it
    also sets which points sit out the jets (:data:`core.tuning.JET_SCORE`)."""
    idx = np.ascontiguousarray(idx)
    scores = np.full(len(pts), np.nan)
    kernels.outlier_scores(pts, idx, OUTLIER_FLOOR, scores)
    off = off_surface(pts, idx)
    raised = off > OUTLIER_SCORE
    scores[raised] = np.fmax(scores[raised], off[raised])
    apart = np.zeros(len(pts), dtype=bool)
    kernels.isolated_groups(pts, idx, apart)
    scores[apart] = np.inf
    return scores


def given_normals(pts, normals, nb, plan, outlier) -> tuple[Initial, dict]:
    """The caller's (or file's) normals with unusable rows (zero, NaN, inf) estimated from
    their neighbours and unscaled ones renormalised (:mod:`core.normal_repair`), the rows no
    file normal decides (all, when none is usable) oriented "outward" as estimated ones are:
    whatever the orientation, which this cached stage does not depend on (:mod:`core.stage_cache`;
    the other modes re-orient every row). The counts go to ``params["normals_repaired"]``."""
    fixed, counts = repair_normals(pts, normals, *nb.take(plan.k_initial), orientation="outward", trust=plan.auto)
    init = Initial(fixed, np.isfinite(fixed).all(axis=1))
    return judged_given(pts, init, nb, plan, outlier, counts) if plan.auto else (init, counts)


def judged_given(pts, given: Initial, nb, plan, outlier, counts) -> tuple[Initial, dict]:
    """With k="auto", the estimator's own initial normals (:func:`core.initial_normals.initial_normals`)
    turned to the ``given`` ones' sides where the given ones are rougher than they
    (:mod:`core.given_normals_check`), else ``given``; ``counts`` gains the verdict,
    ``"use"``: "initial" or "signs", and the ``"roughness"`` it was read from."""
    own = initial_normals(pts, nb, plan, outlier, Progress(None))
    rough = roughness(pts, given.normals, own.normals, own.has_normal, *initial_rows(nb, own.k, outlier, plan))
    use = "signs" if rough > max_roughness(own.k, plan.k_initial) else "initial"
    counts = {**counts, "use": use, "roughness": round(rough, 3)}
    if use == "initial":
        return given, counts
    normals, has_normal = signed_like(own.normals, own.has_normal, given.normals, nb.take_indices(plan.k_initial))
    return own._replace(normals=normals, has_normal=has_normal), counts


#: k="auto" with the caller's signs (kept, or facing viewpoints): beyond this share of points whose
#: sign most neighbours lack (orientation confidence < 0.5), the scale rule, which compares signed
#: normals, and the fits read consistent signs (:func:`orient_signs`; README, "mixed signs")
MIXED_SIGNS = 0.001


def orient_signs(pts, init: Initial, idx, plan, *, rank=None, views=None,
                 consistent=False) -> tuple[Initial, np.ndarray, np.ndarray | None]:
    """Signs made consistent (:func:`core.orientation.orient`), their confidence, and where
    the normals returned carry the other sign than asked (None: nowhere); ``rank``: the
    points' indices in the caller's order if they are in another; ``views``: each point's
    viewpoint, in the points' order, where the plan asks for them
    (:data:`core.planning.PER_POINT`). With ``consistent`` and k="auto", signs the caller
    decides (kept, or facing viewpoints) that disagree among neighbours at more than
    :data:`MIXED_SIGNS` of the points are returned as the spanning forest makes
    them consistent ("outward"): the scale rule reads signed normals."""
    out = orient(pts, init.normals, idx, plan.mode(views), ok=init.has_normal, rank=rank, trust=plan.auto)
    if not (consistent and plan.auto and not plan.decides_signs) \
            or np.count_nonzero(out.confidence[init.has_normal] < 0.5) <= MIXED_SIGNS * len(pts):
        return init._replace(normals=out.normals), out.confidence, None
    inner = orient(pts, out.normals, idx, "outward", ok=init.has_normal, rank=rank, trust=plan.auto)
    flip = np.einsum("ij,ij->i", np.nan_to_num(inner.normals), np.nan_to_num(out.normals)) < 0
    return init._replace(normals=inner.normals), out.confidence, flip


class Residuals(NamedTuple):
    """What creases are judged by (:func:`flags`): a fit's ``valid``, ``rms`` and ``spread``."""

    valid: np.ndarray
    rms: np.ndarray
    spread: np.ndarray


def crease_reference(pts, nrm, has_normal, nb, plan, report) -> Residuals:
    """The paper's linear fit at the initial scale, which creases are judged by with
    k="auto": a cubic over a wide neighbourhood explains half of a step, so its
    residuals do not show it. Only its residuals are kept (its frames were 84 MiB at 1M points)."""
    k = plan.k_initial
    idx_p, dist_p = nb.take(max(k, nb.width) if nb.served_in_place else k)  # the fit reads the first k
    # (in place: a copy of 100k rows was ~5 ms of the crease reference's 47)
    linear = {**plan.options, "degree": 1, "robust": None}
    fit = fit_all(pts, nrm, idx_p, np.full(len(pts), k), dist_p[:, k - 1], has_normal, method=plan.method,
                  options=linear, report=report, frames=False)
    return Residuals(fit.valid, fit.rms, fit.spread)


class Scale(NamedTuple):
    """The choice of scale and model per point: ``k`` (N,) the neighbours NR fits on,
    ``k_point`` (N,) the size reported (the jet's where the jet is kept), ``on_jet`` (N,)
    where the cubic position jet is the result, ``quiet`` (N,) where the measured noise is
    nil (NF rule or jet), ``jets`` the jets' frames (None without k="auto") and
    ``jet_degree`` (N,) their polynomial degree where kept (-1 elsewhere); ``spans`` (N,)
    False where NR's neighbours do not span the tangent plane (:mod:`core.plane_spread`:
    not fitted, invalid); ``priority`` (N,) the anchors' draw where wide fits are shared
    (:func:`core.anchors.priority`, else None)."""

    k: np.ndarray
    k_point: np.ndarray
    on_jet: np.ndarray
    quiet: np.ndarray
    jets: tuple | None = None
    jet_degree: np.ndarray | None = None
    spans: np.ndarray | None = None
    priority: np.ndarray | None = None


def choose_scale(pts, nrm, nb, inliers, plan, report, *, scores=None, k_initial=None, part_sizes=None) -> Scale:
    """Neighbourhood size and model per point: with k="auto" by :func:`core.scale.choose_model`
    (only ``inliers`` take part, in robust mode not those whose ``scores`` exceed :data:`core.tuning.JET_SCORE`), else ``plan.k``.
    NR's own fits are at least ``plan.candidates[0]`` wide, and with noise at least the
    candidate >= ``k_initial``: a jet stopped early by a noise tail or an outlier is no
    reason to fit fewer points; a fold is (:func:`core.scale.fold_capped`: the far side
    of a thin part). Where the scale is shared (:func:`core.anchors.shares_scale`) the
    suspects take their nearest anchor's size (it was the floor: k = 40 amid 320). Where
    NR's neighbours do not span the tangent plane, k="auto" takes the smallest candidate
    whose neighbours do (:mod:`core.plane_spread`; the jets judge their own lever arms,
    through the variance of their Hessian); ``Scale.spans`` tells where none does. With
    ``part_sizes`` (:func:`core.parts.part_sizes`) no fit holds more than its part allows
    (:func:`core.parts.chosen_cap`), nor is lifted past the part's initial k."""
    n = len(pts)
    if not plan.auto:
        kc, none = np.full(n, plan.k, dtype=np.int64), np.zeros(n, dtype=bool)
        return Scale(kc, kc, none, none, spans=plane_spread.spans_plane(pts, nrm, nb, kc))
    ks = plan.candidates
    suspect = scores > JET_SCORE if plan.robust and scores is not None else np.zeros(n, dtype=bool)
    steady = inliers & ~suspect  # the jets are least squares: suspects sit out the choice of k
    masked = np.where(steady[:, None], nrm, np.nan)
    prio = anchors.priority(pts, nb.take_indices(anchors.RATIOS + 1)) if anchors.shares_scale(plan) else None
    if hasattr(nb, "keep_rows"):  # the fits read rows the jets search (anchors' of 320, the degree rule's of 113)
        nb.keep_rows(nb.width + 1)
    kc, on_jet, quiet, jets, degree = parts.choose_within(
        lambda sizes, usable: scale.choose_model(pts, masked, nb, usable, sizes, report, priority=prio,
                                                 sat_out=inliers & suspect), ks, part_sizes, steady)
    k0 = parts.initial_ks(part_sizes, k_initial or 0, ks[0], n)
    floor = np.asarray(ks)[np.minimum(np.searchsorted(ks, k0), len(ks) - 1)]  # a candidate >= k_initial
    lifted = np.flatnonzero(steady & ~quiet & (kc < floor))
    if len(lifted):  # but not across a fold (the far side of a thin part)
        capped_at = scale.fold_capped(pts, masked, nb, lifted, ks, int(floor[lifted].max()))
        floor[lifted] = np.minimum(floor[lifted], capped_at)
    fit_k = np.maximum(kc, np.where(quiet, ks[0], floor))
    wide = plane_spread.widened(pts, nrm, nb, fit_k, ks, noisy=~quiet)
    fit_k = np.where(wide > 0, wide, fit_k)
    on_jet, fit_k = parts.capped(part_sizes, ks, kc, on_jet, fit_k)  # within the part a point lies on
    return Scale(fit_k, np.where(on_jet, kc, fit_k), on_jet, quiet, jets, np.where(on_jet, degree, -1),
                 spans=on_jet | (wide > 0), priority=prio)


def flags(fit: Fit, scores, plan, reference: Residuals | None, *, nb=None, confidence=None) -> Flags:
    """Per-point flags: the outlier scores, with k="auto" and the neighbours ``nb`` the points on
    no surface at any scale (:func:`core.volumetric.volumetric`; the result makes them invalid:
    :func:`off_volume`), creases judged on ``reference`` (the linear fit at the initial scale,
    k="auto") or on the fit itself, and, given ``nb``, the border points among the valid ones
    (on the refined normals); the creases and the border count the valid points off the volume.
    An integer k runs the paper's pipeline, whose wider searches the volume test would add
    (+73 % at k = 15 on a cloud with noise of one spacing)."""
    volume = volumetric(nb.points, nb) if plan.auto and nb is not None else None
    valid = fit.valid if volume is None else fit.valid & ~volume
    judged = Residuals(valid, fit.rms, fit.spread) if reference is None else reference
    crease, typical = _creases(judged.valid, judged.rms, judged.spread, plan.crease_typical)
    border = None  # without enough cached neighbours: computed on first use (CurvatureResult.border)
    if served_by(nb, len(valid)):
        border = border_of_valid(nb.points, fit.normals, valid, nb)
    return Flags(outlier_score=scores, crease=valid & crease, crease_typical=typical, border=border,
                 orientation_confidence=confidence, crease_residual=crease_residuals(judged), volumetric=volume)


def off_volume(fit: Fit, volume) -> Fit:
    """``fit`` with the points on no surface at any scale (``volume``, :attr:`Flags.volumetric`;
    None: none) invalid: ``valid`` False and NaN curvatures and directions there, as at any
    invalid point (new arrays: the fits a tile keeps for its next pass are not changed)."""
    if volume is None or not volume.any():
        return fit
    return invalid_at(fit, volume)
