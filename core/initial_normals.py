"""The initial normals of :func:`core.estimate` (a stage of :mod:`core.stages`): weighted
PCA (eqs. 13-14), with k="auto" refined by 2-jets on a neighbourhood that grows with the
measured noise, kept from lying across folds or reaching around bends (:mod:`core.reach`), and
widened where scan lines leave the nearest too few lines (:mod:`core.plane_spread`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import anchors, kernels, local_noise, parts, plane_spread, reach, scale, tuning
from .clump_surfaces import scatter_shapes
from .kernels.knn import unflagged_first
from .normals import jet_normals, pca_jet_at, pca_normals


class Initial(NamedTuple):
    """Initial normals: ``normals`` (N, 3), ``has_normal`` (N,) bool, and with k="auto"
    the measured (or given) ``noise`` ratio, the ``k`` it chose and the ``fold_typical``
    spread folds were judged against (:func:`unfolded`; None otherwise), and the share
    of points whose region's noise gave them another initial k (:mod:`core.local_noise`)
    or their part's size (``part_sizes``, :func:`core.parts.part_sizes`)."""

    normals: np.ndarray
    has_normal: np.ndarray
    noise: float | None = None
    k: int | None = None
    fold_typical: float | None = None
    local: float = 0.0
    part_sizes: np.ndarray | None = None


def initial_normals(pts, nb, plan, outlier, report, views=None) -> Initial:
    """PCA normals (eqs. 13-14), refined by a 2-jet if ``plan.initial == "jet"``, on the
    ``plan.k_initial`` nearest; with k="auto" on a neighbourhood that grows with the noise
    the 2-jets measure (:func:`core.scale.initial_k`, or ``plan.noise`` when given),
    without the known outliers in robust mode, and wider where it lies along one scan line
    (:func:`core.plane_spread.spanning_normals`; or where, with the scanner's viewpoint
    given, its plane holds the view ray: :func:`core.plane_spread.ray_sheets`) or two (where
    the 2-jet was refused: :func:`core.plane_spread.determined_normals`); ``views``: each
    point's viewpoint where the plan faces them (:data:`core.planning.PER_POINT`)."""
    init, refused = _initial_normals(pts, nb, plan, outlier, report)
    if not plan.auto:
        return init
    sheets, nrm, ok = plane_spread.ray_sheets(pts, init.normals, plan.mode(views)), init.normals, init.has_normal
    for members, k, ks in parts.groups(init.part_sizes, init.k, plan.candidates):  # each part as if alone
        nrm, _ = plane_spread.spanning_normals(pts, nrm, ok & members, nb, k, ks, sheets)
        left = refused & ok & members & (nrm == init.normals).all(axis=1)  # not widened as a line already
        nrm = plane_spread.determined_normals(pts, nrm, left, nb, k, ks)
    return init._replace(normals=nrm)


def _initial_normals(pts, nb, plan, outlier, report) -> tuple[Initial, np.ndarray]:
    """:func:`initial_normals` before the scan lines are looked after, and where the 2-jet
    the normals come from was refused ((N,) bool; none without k="auto")."""
    idx_p, dist_p = nb.take(plan.k_initial)
    nrm, ok = pca_normals(pts, idx_p, dist_p, progress=report.sub(0.3, 0.37))
    if not plan.auto:
        if plan.initial == "jet":
            nrm, _ = jet_normals(pts, nrm, ok, idx_p, dist_p, progress=report.sub(0.37, 0.43))
        return Initial(nrm, ok), np.zeros(len(pts), dtype=bool)
    jet = ratios = None
    noise = plan.noise
    if noise is None:
        jet, ratio, clean = noise_samples(pts, nrm, ok, idx_p, dist_p, outlier)
        noise = scale.noise_ratio(np.where(clean, ratio, np.nan) if clean.any() else ratio, 1.0)
        jet, ratios = (jet, ratio * dist_p[:, -1]), (ratio, clean)  # the small jets' heights in length units
    k_init = scale.initial_k(noise, plan.k_initial, plan.k_search, plan.n_points)
    if k_init > nb.width:  # noise this large grows most jets to k_search too: search them all once, unless
        del idx_p, dist_p  # only anchors walk on (core.anchors.shares_scale; views of the narrow graph would keep it alive)
        nb.widen(k_init if anchors.shares_scale(plan) else plan.k_search)
        idx_p, dist_p = nb.take(plan.k_initial)
    small, height = _small_normals(pts, nrm, ok, idx_p, dist_p, jet, plan)
    if ratios is None and plan.initial == "jet":  # the noise given: the small jets' heights measure the regions
        ratios = noise_ratios(height, idx_p, dist_p, outlier)
    levels = None if ratios is None else _levels(pts, nb, plan, (idx_p, dist_p), small, ratios, k_init)
    sizes = parts.part_sizes(pts, nb, plan.k_initial)  # no more than a share of the object a point lies on
    levels = parts.initial_levels(levels, k_init, sizes, plan.k_initial)
    init, refused = _at_cloud_scale(pts, nb, plan, outlier, report, (ok, idx_p, noise, k_init), (small, height))
    init = init._replace(part_sizes=sizes)
    if levels is None:
        return init, refused
    return _at_levels(pts, nb, plan, outlier, levels, init, refused, (small, height, idx_p, ok))


def _at_cloud_scale(pts, nb, plan, outlier, report, cloud, smalls) -> tuple[Initial, np.ndarray]:
    """:func:`_initial_normals` at the cloud's initial k: ``cloud`` = (ok, the small rows,
    the noise, that k), ``smalls`` = the small normals and their jets' heights."""
    ok, idx_p, noise, k_init = cloud
    small, height = smalls
    if k_init == plan.k_initial and not (plan.robust and outlier.any()):
        return Initial(small, ok, noise, k_init), _refused(ok, height, plan)
    idx, dist = initial_rows(nb, k_init, outlier, plan)
    nrm, ok = pca_normals(pts, idx, dist, progress=report.sub(0.37, 0.4))
    wide = np.zeros(len(pts))
    if plan.initial == "jet":
        nrm, wide = jet_normals(pts, nrm, ok, idx, dist, progress=report.sub(0.4, 0.43))
    if k_init == plan.k_initial:  # only outliers left out: no wide plane to lie across a fold
        return Initial(nrm, ok, noise, k_init), _refused(ok, wide, plan)
    nrm, typical, folded = unfolded(nrm, small, *fold_spreads(small, idx, nb, k_init, outlier, plan),
                                    plan.fold_typical, pts=pts, small_rows=idx_p)
    wide = np.where(folded, height, wide)
    if plan.initial == "jet":  # nor around a bend (core.reach)
        nrm, ok, wide = _within_reach(pts, nb, plan, outlier, (nrm, ok, wide), (small, height, idx_p), k_init, ~folded)
    return Initial(nrm, ok, noise, k_init, typical), _refused(ok, wide, plan)


def _within_reach(pts, nb, plan, outlier, fitted, smalls, k_init, open_, *, centres=None):
    """``fitted`` = (normals, ok, their 2-jets' heights) of the ``centres`` (M,) (default: every
    point) on ``k_init`` neighbours, re-fitted where the wide 2-jet reaches around a bend
    (:func:`core.reach.overreaching`, among the ``open_`` (M,) ones) on a smaller size
    (:func:`core.reach.narrowed`), or the ``smalls`` (small normals, their heights, their rows,
    (N, ...)) where none fits."""
    nrm, ok, wide = fitted
    small, height, idx_p = smalls
    c = np.arange(len(nrm)) if centres is None else centres
    noise = reach.pooled_height(height, idx_p[c])
    over = np.flatnonzero(reach.overreaching(wide, noise, idx_p, c) & open_ & ok)
    if not len(over):
        return fitted
    nrm, ok, wide = nrm.copy(), ok.copy(), wide.copy()
    n_c, ok_c, h_c, left = reach.narrowed(pts, nrm[over], ok[over], c[over], noise[over],
                                          reach.sizes_below(k_init, plan.k_initial),
                                          lambda at, k: _level_rows(nb, at, k, outlier, plan)[:2])
    n_c[left], h_c[left] = small[c[over[left]]], height[c[over[left]]]
    nrm[over], ok[over], wide[over] = n_c, ok_c, h_c
    return nrm, ok, wide


def _levels(pts, nb, plan, small_rows, small, ratios, k_init):
    """Each point's initial k where its region's noise asks for more than the cloud's
    ``k_init`` (:func:`core.local_noise.local_k`) from ``ratios`` (:func:`noise_ratios`),
    without the suspects whose residual is a bias (their jets on wider rows, in the frames
    of the ``small`` normals); None where none does."""
    idx_p, dist_p = small_rows
    ratio, clean = ratios
    width = min(nb.width, local_noise.POOL)
    suspect = np.flatnonzero(local_noise.suspects(ratio, k_init) & np.isfinite(small[:, 0]))
    if len(suspect) and width > plan.k_initial:  # no bias in the pools: where a wider jet's residual grows
        idx, dist = nb.rows(suspect, width)
        _, wide = jet_normals(pts, small[suspect], np.ones(len(suspect), dtype=bool), np.ascontiguousarray(idx),
                              np.ascontiguousarray(dist), centres=suspect)
        ratio = ratio.copy()
        ratio[suspect[local_noise.biased(ratio[suspect] * dist_p[suspect, -1], wide)]] = np.nan
    return local_noise.local_k(ratio, clean, nb.take_indices(width), k_init, plan.k_initial, plan.k_search,
                               plan.n_points)


def _at_levels(pts, nb, plan, outlier, levels, init, refused, smalls) -> tuple[Initial, np.ndarray]:
    """``init`` and ``refused`` with the points whose region asks for another initial k
    (``levels`` (N,), :func:`_levels`, or whose part caps it, :mod:`core.parts`) fitted on it,
    each level's fold test against the typical agreement of its own points; ``smalls`` = (the
    small normals, their jets' heights, their rows, where they have a normal)."""
    small, height, idx_p, small_ok = smalls
    nrm, ok, refused = init.normals.copy(), init.has_normal.copy(), refused.copy()
    for k in np.unique(levels[levels != init.k]):  # above the cloud's (core.local_noise) or below (core.parts)
        c = np.flatnonzero(levels == k)
        if k == plan.k_initial and not (plan.robust and outlier.any()):  # the small normals, as on the part alone
            nrm[c], ok[c], refused[c] = small[c], small_ok[c], _refused(small_ok[c], height[c], plan)
            continue
        idx, dist, clean = _level_rows(nb, c, int(k), outlier, plan)
        n_c, ok_c, wide = pca_jet_at(pts, c, idx, dist, jet=plan.initial == "jet")
        spread = np.empty(len(c))
        kernels.normal_spread(small, idx, spread)
        n_c, _, folded = unfolded(n_c, small[c], spread, clean, pts=pts, small_rows=idx_p[c])
        wide = np.where(folded, height[c], wide)
        if plan.initial == "jet":  # nor around a bend (core.reach)
            n_c, ok_c, wide = _within_reach(pts, nb, plan, outlier, (n_c, ok_c, wide), smalls[:3], int(k), ~folded,
                                            centres=c)
        nrm[c], ok[c], refused[c] = n_c, ok_c, _refused(ok_c, wide, plan)
    return init._replace(normals=nrm, has_normal=ok, local=float(np.mean(levels != init.k))), refused


def _level_rows(nb, centres, k, outlier, plan):
    """The ``k`` nearest of ``centres`` (without the known outliers in robust mode, as
    :func:`initial_rows`) and whether their plain k nearest hold no outlier (as :func:`fold_spreads`)."""
    robust = plan.robust and outlier.any()
    idx, dist = nb.rows(centres, min(nb.k_max, 2 * k) if robust else k)
    if not robust:
        return np.ascontiguousarray(idx), np.ascontiguousarray(dist), np.ones(len(centres), dtype=bool)
    clean = ~outlier[idx[:, :k]].any(axis=1)
    out_i, out_d = np.empty((len(centres), k), dtype=idx.dtype), np.empty((len(centres), k))
    unflagged_first(np.ascontiguousarray(idx), np.ascontiguousarray(dist), np.ascontiguousarray(outlier, dtype=np.bool_),
                    out_i, out_d, np.empty(len(centres), dtype=np.int64))
    return out_i, out_d, clean


def _refused(ok, height, plan) -> np.ndarray:
    """(N,) bool: where a point with a normal has no 2-jet (``height`` NaN: refused)."""
    return ok & np.isnan(height) if plan.initial == "jet" else np.zeros(len(ok), dtype=bool)


def initial_rows(nb, k_init, outlier, plan):
    """The ``k_init`` nearest a point's initial normal is fitted on, without the known
    outliers in robust mode."""
    return nb.take_without(k_init, outlier) if plan.robust and outlier.any() else nb.take(k_init)


def _small_normals(pts, nrm, ok, idx_p, dist_p, jet, plan):
    """The ``plan.k_initial`` normals a fold falls back to, and their 2-jets' residual
    heights (NaN where refused; zeros without jets): the 2-jet's where the plan asks for
    jets, computed here when the noise was given (tiles, cached stages) rather than
    measured by :func:`noise_samples` (``jet``: its normals and ratios), so both paths
    fall back to the same normals."""
    if plan.initial != "jet":
        return nrm, np.zeros(len(nrm))
    return jet if jet is not None else jet_normals(pts, nrm, ok, idx_p, dist_p)


def fold_spreads(small, idx, nb, k_init, outlier, plan) -> tuple[np.ndarray, np.ndarray]:
    """``(spread, clean)`` per point: how well the ``small`` normals of its ``idx``
    neighbours agree (the largest eigenvalue of their unsigned scatter,
    :func:`core.kernels.normal_spread`), and whether it counts towards the typical spread
    (:func:`typical_spread`): in robust mode, no known outlier among its ``k_init``
    nearest (its robust row reaches past them, and an outlier spoils the small normals
    around it); every point otherwise. A tiled run samples the same pair."""
    spread = np.empty(len(idx))
    kernels.normal_spread(small, idx, spread)
    if plan.robust and outlier.any():
        return spread, ~outlier[nb.take(k_init)[0]].any(axis=1)
    return spread, np.ones(len(idx), dtype=bool)


def typical_spread(spread, clean) -> float:
    """The median spread over the ``clean`` points, or over all points if none is clean
    (0.0 if none is finite)."""
    if clean.any():
        spread = spread[clean]
    return float(np.nanmedian(spread)) if np.isfinite(spread).any() else 0.0


def unfolded(wide, small, spread, clean, typical=None, *, pts=None, small_rows=None):
    """(``wide`` normals, but ``small``'s (the ``plan.k_initial`` neighbours') where the
    small normals of a point's wide neighbours disagree with each other well beyond what
    the cloud's noise makes them do (``spread``, :func:`fold_spreads`, below
    :data:`core.tuning.FOLD_SPREAD` x ``typical``, by default :func:`typical_spread` of
    this cloud; a tiled run fixes the whole cloud's): a fold, the rim of a part a few
    spacings thick, where a wide PCA plane lies across both faces and the side between
    them; the ``typical`` spread used; where the small ones were taken). Given the
    points ``pts`` and the small normals' neighbours ``small_rows``, not where those are a
    noisy scan line, as wide both ways across the line (:data:`core.tuning.FOLD_FLAT`) as
    they are narrow along it (:data:`core.plane_spread.LINE_SPREAD`): there the small
    normals disagree by the line's noise."""
    if typical is None:
        typical = typical_spread(spread, clean)
    folded = (spread < tuning.FOLD_SPREAD * typical) & np.isfinite(small[:, 0])
    if folded.any() and pts is not None:
        flat, line = scatter_shapes(pts, small_rows[folded])
        folded[folded] = ~((flat > tuning.FOLD_FLAT) & (line < plane_spread.LINE_SPREAD))
    if not folded.any():
        return wide, typical, folded
    out = wide.copy()
    out[folded] = small[folded]
    return out, typical, folded


def noise_samples(pts, nrm, ok, idx_p, dist_p, outlier):
    """What the cloud's noise ratio is the median of (:func:`core.scale.noise_ratio`):
    ``(jet normals, ratio, clean)`` per point, ratio = 2-jet residual height over the
    radius of the ``idx_p`` neighbours, clean = no outlier among them (an outlier inflates
    the residuals around it; the median is taken over the clean points if any). A tiled
    run gathers these over the whole cloud and fixes ``plan.noise``."""
    jet, height = jet_normals(pts, nrm, ok, idx_p, dist_p)
    return (jet, *noise_ratios(height, idx_p, dist_p, outlier))


def noise_ratios(height, idx_p, dist_p, outlier):
    """``(ratio, clean)`` per point (:func:`noise_samples`) from its 2-jet's ``height``."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return height / dist_p[:, -1], ~outlier[idx_p].any(axis=1)
