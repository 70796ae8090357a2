"""Automatic scale: ``k="auto"`` picks, per point, the neighbourhood size and the model.

**The rule (issue 15).** Fit osculating cubic jets of the *positions* (Cazals & Pouget) on
nested neighbourhoods, 15, 20, 28, ... 226, 320 neighbours, in one pass per point (the normal
equations grow ring by ring, :mod:`core.kernels.jets`), and keep the largest size whose
Hessian (f_uu, f_uv, f_vv) still lies within +-5 sigma of every smaller one (intersection of
confidence intervals: Goldenshluger & Nemirovski 1997, Katkovnik 1999). What makes it see
bias is where sigma comes from: not from each fit's own residual (a biased fit has a large
residual, so its interval widens with its bias and the previous rule, on NF's normal fits,
went to 226 neighbours everywhere, noise-free included), but from the **noise level
measured apart** (:func:`noise_variance`): the residual variance of a cubic jet is the
noise (the same at every size) plus its bias, which grows as k^4; the variances at 15 and
28 neighbours, pooled over 20 neighbours, separate the two. Noise-free that is ~0, the
intervals are narrow and a curved patch stops at 15; with noise a flat patch goes to 320,
a bent one stops where the bias shows. Heights of points have independent noise, unlike
estimated normals, so the intervals need no correction for correlation.

**The degree.** Where the measured noise is below :data:`JET_QUIET` (nearly noise-free)
what remains of a cubic's error is the bias of the terms it lacks, and a richer model
removes it: a quartic on 20 neighbours (:data:`JET_DEGREES`) has 20-50x smaller H, K and
e1 errors than the cubic on 15 on the hold-out surfaces of ``python -m core bench
holdout``. The degree is chosen per point by the same intersection of confidence
intervals, walking *down* in bias: the quartic on 20, 28, ... 113 neighbours, then the
cubic at its chosen size; a model is kept while its Hessian's interval (sd from the noise
measured apart) meets those of all before it. Noise-free the quartic stays at 20; at noise
of 1e-4-3e-3 spacing it grows (on 20 it is too noisy); with more noise the walk ends at the cubic.
Only points whose cubic stopped within the quartic's reach take part; a richer model whose residual
variance per dof exceeds :data:`JET_MISFIT` times the cubic's ends the richer models (an edge, a
fold). (:mod:`core.kernels.jet_degree`, on the cubic's sums; ``res.degree_point``: the degree.)

**Shared at wide scales.** With noise nearly every jet grows to the largest size. Where
k="auto"'s wide fits are shared (:mod:`core.anchors`), the rule runs at the anchors drawn
for fits of that size (and at the quiet points), and every other noisy point takes its
nearest anchor's size (its fit reads the anchors' wide discs anyway): 1.8-2.3 s less of
a noisy 100k torus or ellipsoid, mean |H| error within 0.2 %.

**The model.** Where the measured noise is below :data:`JET_QUIET` (nearly noise-free) the
jet itself is the result: it inherits no error of estimated normals (on 7 stand-in
surfaces 2-30x better than NR at the same k). Elsewhere NR fits a cubic normal field on the
chosen k (at least the noise-set initial scale) and refines it: with noise it averages
better than the jet (1.2-1.8x). Quiet but sparse points, whose 15 neighbours reach over
0.4 of a radius of curvature (:data:`JET_REACH`), or whose jet tilts from the initial normal
(:data:`JET_TILT`: three grid lines do not determine a cubic; :data:`JET_THIN_TILT` where its
neighbours are a strip of one scan line), use NR with the NF rule below. ``res.k_point`` and
``res.degree_point`` hold the choice. (Values and reasons of the constants: :mod:`core.tuning`.)

**The principal direction with noise (measured; not solved).** With noise of 0.1-0.2 mean
spacing e1 is the quantity the default still loses (to a cubic jet on 240 neighbours on some
hold-out surfaces); four explanations were tested (k too small, the passes, e1 from the position
jet, a wider scale for the direction) and none holds across surfaces: README, "Why e1 still loses
with noise" (``python -m core bench holdout --probe``).

**The NF rule** (:func:`choose_k`, issue 4; now only for those sparse points): small
neighbourhoods give unbiased but noisy normal derivatives; large ones average the
noise away but the model of the normal field bends over a curved patch: the bias of W
is O(h) for the linear model of eq. 23 (O(h^2) on a symmetric neighbourhood) and O(h^3)
for the cubic one "auto" uses. Fit NF at increasing k, each giving the
Weingarten entries (W11, (W12 + W21)/2, W22) with their least-squares standard
deviations s_k. While the intervals [W_k - G s_k, W_k + G s_k] of all scales so far
still intersect, the larger k only removes noise; the first k whose interval leaves the
common intersection shows bias, and the previous k is kept. k also stops growing, in
both rules, where a ring of new neighbours folds over (see :mod:`core.kernels.scale`): past the far
side of a thin part the residuals explode and would hide the bias from the intervals.
A fold is judged against the smallest neighbourhood (its centroid, mean normal and noise
height), not the centre alone, and must persist into the next ring: with noise of a whole
spacing, a test on the centre's own noisy normal stopped a quarter of the points at 20."""

from __future__ import annotations

import warnings

import numpy as np

from . import anchors, kernels, neighbour_budget, plane_spread, wide_rows
from .frame import jet_frames, turned_over
from .kernels import jets as jet_kernels, pool as pool_kernels
from .kernels.frame import intrinsic_frames
from .linalg import tangent_basis
from .patch import Chunk
from .tuning import (ANCHOR_REACH, AUTO_DEGREE, AUTO_KS, DEGREE_PIVOT, FOLD_COS, FOLD_FRACTION, FOLD_MIN_BAD, FOLD_NOISE,
                     GAMMA, INITIAL_K0, INITIAL_SHARE, JET_DEGREE, JET_GAMMA, JET_DEGREES, JET_KS, JET_QUIET, JET_REACH,
                     JET_DEGREE_GAMMA, JET_MISFIT, JET_SCORE, NOISE_KS, NOISE_POOL, RCOND, JET_RCOND, JET_THIN_TILT,
                     JET_TILT, ROUNDING_NOISE, WIDEN_SHARE, COORD_ROUNDING)

__all__ = ["AUTO_DEGREE", "AUTO_KS", "GAMMA", "INITIAL_K0", "JET_KS", "JET_DEGREE", "JET_SCORE",
           "candidates", "choose_k", "noise_ratio", "initial_k", "jet_candidates", "noise_variance", "choose_jets",
           "aligned_jets", "choose_model"]

_CHUNK = 32_768


def candidates(n_points: int) -> tuple[int, ...]:
    """The candidate k that a cloud of ``n_points`` allows (and the memory budget, :mod:`core.neighbour_budget`),
    none above half the cloud (a 30-point sphere took 20 and gave H 1.7; k = 15: 1.00), else half of it (>= 8)."""
    half = n_points // 2
    ks = neighbour_budget.affordable(tuple(k for k in AUTO_KS if k <= half), n_points, AUTO_KS[0])
    return ks or (min(n_points, max(half, 8)),)


def choose_k(points, normals, nb, has_normal, ks, degree, report):
    """Per-point k by ICI over ``ks`` (ascending); returns (N,) int (ks[0] where no normal)."""
    n = len(points)
    chosen = np.full(n, ks[0], dtype=np.int64)
    usable = np.flatnonzero(has_normal)  # and whose ks[-1]-th neighbour is not at distance 0 (else ks[0])
    chosen[usable] = _per_centre(kernels.choose_scales, points, normals, nb, usable, ks, _nf_rule(degree), report,
                                 flat=ks[0])
    return chosen


def _nf_rule(degree):
    """The NF rule's :class:`core.kernels.ScaleRule` (ICI width, fold test) for ``degree``."""
    return kernels.ScaleRule(degree, GAMMA, RCOND, FOLD_FRACTION, FOLD_COS, FOLD_NOISE, FOLD_MIN_BAD, DEGREE_PIVOT)


def _per_centre(kernel, points, normals, nb, centres, ks, rule, report=None, *, flat=None):
    """``kernel(frames, ks, rule, out)`` over ``centres`` in chunks of :data:`_CHUNK`, each
    with its ``ks[-1]`` neighbours (``nb.rows``: searched for these centres only when the
    graph holds fewer); returns ``out`` (len(centres),) int. ``flat``: the answer, without
    the kernel, at centres whose ``ks[-1]``-th neighbour is at distance 0."""
    ks_arr = np.asarray(ks, dtype=np.int64)
    result = np.empty(len(centres), dtype=np.int64)
    for start in range(0, len(centres), _CHUNK):
        c = centres[start:start + _CHUNK]
        idx, dist = nb.rows(c, ks[-1])
        h = dist[:, -1]
        out = np.empty(len(c), dtype=np.int64)
        if flat is None:
            kernel(Chunk.build(points, normals, idx, h, c).turning(ks[0]).frames(), ks_arr, rule, out)
        else:
            far = np.flatnonzero(h > 0)
            out[:] = flat
            part = np.empty(len(far), dtype=np.int64)
            kernel(Chunk.build(points, normals, idx[far], h[far], c[far]).turning(ks[0]).frames(), ks_arr, rule, part)
            out[far] = part
        result[start:start + _CHUNK] = out
        if report is not None:
            report(min(len(centres), start + _CHUNK) / max(len(centres), 1), "choosing k")
    return result


def fold_capped(points, normals, nb, centres, ks, k_floor):
    """The largest of ``ks`` up to ``k_floor`` whose neighbourhood stays on the graph of a
    function (the fold test of :func:`core.kernels.scale._fold_limit`), per centre.

    The noise floor widens NR's fits to the initial scale where the jet rule stopped
    early; across a thin part it must not reach the far side: on a plate 3 spacings thick
    at 0.2 spacing of noise the floor (80 neighbours, a third of them on the other face)
    turned 5.6 % of the normals more than 60 degrees.
    """
    limits = _per_centre(kernels.fold_limits, points, normals, nb, centres, ks, _nf_rule(AUTO_DEGREE))
    top = int(np.searchsorted(ks, k_floor, side="right"))  # sizes <= k_floor
    return np.asarray(ks, dtype=np.int64)[np.clip(np.minimum(limits, top), 1, None) - 1]


def noise_ratio(height, h) -> float:
    """The cloud's noise as a fraction of the neighbourhood radius: median of
    ``height / h`` (jet residual over the radius of its neighbours), NaN-free."""
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = height / h
    ratio = ratio[np.isfinite(ratio)]
    return float(np.median(ratio)) if len(ratio) else 0.0


def initial_k(noise, k_min: int, k_max: int, n_points: int):
    """Initial normals' neighbours at a ``noise_ratio`` (tuning.INITIAL_K0), at most n_points / INITIAL_SHARE
    and what every point may hold (:func:`core.neighbour_budget.whole_cap`: the initial normals fit at every point);
    an int, or an int64 array for an array of (finite) noise ratios (:mod:`core.local_noise`)."""
    k = np.rint(INITIAL_K0 * np.sqrt(np.maximum(noise, 0.0)))  # half to even, as round()
    k_max = min(k_max, n_points // INITIAL_SHARE, neighbour_budget.whole_cap(n_points, k_min, k_max))
    k = np.clip(k, k_min, max(k_max, k_min))
    return int(k) if np.ndim(k) == 0 else k.astype(np.int64)


# ----------------------------------------------------------------------------- jets (issue 15)
def jet_candidates(n_points: int) -> tuple[int, ...]:
    """The sizes of :data:`JET_KS` that a cloud of ``n_points`` allows within the budget."""
    return neighbour_budget.affordable(JET_KS, n_points, JET_KS[1])


def noise_variance(rss_a, rss_b, s, idx, ka=NOISE_KS[0], kb=NOISE_KS[1], size=0.0):
    """Per-point variance of the position noise along the normal (length units squared).

    The residual variance of a cubic jet on k neighbours is sigma^2 (noise, the same at
    every k) plus the model's bias, whose quartic terms grow as h^8, i.e. as k^4 on a
    surface (h^2 ~ k). With the variances a at ka and b at kb, pooled over the point's
    :data:`NOISE_POOL` nearest neighbours, sigma^2 = (rho a - b) / (rho - 1), rho =
    (kb / ka)^4, at least :data:`ROUNDING_NOISE` x s and :data:`COORD_ROUNDING` x ``size`` (N,), the point's
    largest coordinate. Noise-free this is ~0 (all bias), so the intervals of :func:`choose_jets` are narrow
    and the smallest wins; the plain residual variance would let a biased fit pass for noise. Returns (sigma^2, a).
    """
    s2 = s * s
    with np.errstate(invalid="ignore"):
        va = rss_a * s2 / (ka - 10)
        vb = rss_b * s2 / (kb - 10)
    pool = idx[:, :min(NOISE_POOL, idx.shape[1])]
    if pool.shape[1] <= pool_kernels.MAX_POOL:  # np.nanmean(va[pool], axis=1) without its (N, 20) copies
        a, b = np.empty(len(pool)), np.empty(len(pool))
        pool_kernels.pooled_nanmeans(np.ascontiguousarray(va, dtype=np.float64),
                                     np.ascontiguousarray(vb, dtype=np.float64), pool, a, b)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN pools (rank-deficient fits)
            a = np.nanmean(va[pool], axis=1)
            b = np.nanmean(vb[pool], axis=1)
    rho = (kb / ka) ** 4
    sigma2 = np.maximum((rho * a - b) / (rho - 1.0), np.maximum(ROUNDING_NOISE * s, COORD_ROUNDING * size) ** 2)
    return np.nan_to_num(sigma2, nan=0.0), np.nan_to_num(a, nan=np.inf)


def _at(a, centres):
    """``a[centres]``: a view for a run of consecutive centres (every point of a clean
    cloud, chunk by chunk), else a copy."""
    if len(centres) and centres[-1] - centres[0] == len(centres) - 1:  # sorted, distinct: a run
        return a[centres[0]:centres[-1] + 1]
    return a[centres]


def _rows(idx, centres, width):
    """The first ``width`` neighbours of ``centres`` in the graph ``idx`` (N, w): a view
    for a run, else a contiguous copy of those columns only (:func:`_at`)."""
    return _at(idx[:, :width], centres)


def _jet_frames(points, normals, rows, centres, s, t1, t2):
    """The kernels' record of ``centres`` with their neighbours ``rows`` (M, w) (frame z =
    their normal, lengths in units of s)."""
    return kernels.Frames(points, normals, rows, np.zeros(len(centres), dtype=np.int64), _at(s, centres), centres,
                          _at(t1, centres), _at(t2, centres), _at(normals, centres))


def _jet_rule():
    return kernels.ScaleRule(JET_DEGREE, JET_GAMMA, JET_RCOND, FOLD_FRACTION, FOLD_COS, FOLD_NOISE, FOLD_MIN_BAD, JET_RCOND)


def choose_jets(points, normals, nb, has_normal, ks, report, *, priority=None, sat_out=None):
    """Per point: the size of a cubic jet by ICI with an outside noise level (see module);
    ``priority`` (N,), optional: the anchors' draw (:func:`core.anchors.priority`) where
    k="auto"'s wide fits are shared: a noisy point that follows an anchor takes its size
    (:func:`core.anchors.shared_scale`; its jet's frame is not valid), and so do the
    points ``sat_out`` (N,) bool, which run no jet of their own (robust mode's suspects).

    Returns ``(k, jet, noise, degree)``: k (N,) int (0 where no fit), the chosen jets'
    frames ``(normal, k1, k2, e1, e2, ok)`` as :func:`core.frame.darboux_frame` gives them,
    the noise over s: the larger of sigma and half the plain residual RMS at 15 (an
    outlier makes the separation of :func:`noise_variance` fail, not the residual), and
    the jets' degree (N,) int: 3, or where the noise is below :data:`JET_QUIET` the
    degree rule's (see the module; -1 where no fit).
    """
    n = len(points)
    if nb.width < max(NOISE_KS[1], NOISE_POOL, ks[0]):
        nb.widen(ks[-1])
    idx_all, dist_all = nb.take(min(nb.width, ks[-1]))  # the columns held: the rows that need more are searched
    s = dist_all[:, ks[0] - 1].copy()
    usable = np.flatnonzero(has_normal & (s > 0))
    base = np.where(has_normal[:, None], normals, [0.0, 0.0, 1.0])
    t1, t2 = tangent_basis(base)  # turned with the cloud: the rules compare the Hessian entry by entry
    intrinsic_frames(points, np.arange(n), base, np.ascontiguousarray(idx_all[:, :ks[0]]), t1, t2)
    sigma2, plain = _measured_noise(points, normals, idx_all, usable, s, t1, t2)
    with np.errstate(invalid="ignore", divide="ignore"):
        noise = np.where(s > 0, np.maximum(np.sqrt(sigma2), 0.5 * np.sqrt(plain)) / s, np.inf)
    if (priority is None and nb.width < ks[-1] <= neighbour_budget.whole_cap(n, ks[0])
            and np.count_nonzero(noise[usable] > JET_QUIET) > WIDEN_SHARE * len(usable)):
        idx_all, dist_all = nb.take(ks[-1])  # noisy: most jets grow past the columns held, search all at once
    report(0.2, "choosing k")
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma2_h = sigma2 / s ** 2  # the noise in units of h^2, as the kernels take it

    def frames(rows, c):
        return _jet_frames(points, normals, rows, c, s, t1, t2)

    deg = _degree_rule(ks, noise <= JET_QUIET)
    lead = None
    if priority is not None and idx_all.shape[1] > ANCHOR_REACH:  # its nearest, to find their anchors among
        lead = lambda noisy: anchors.shared_scale(points, idx_all, noisy, ks[-1], priority, sat_out)  # noqa: E731
    chosen, coef, walked = _jet_ici(nb, idx_all, usable, ks, frames, sigma2_h, deg, report, lead=lead)
    ks_arr = np.asarray(ks, dtype=np.int64)
    fitted = chosen >= 0
    k = np.where(fitted, ks_arr[np.maximum(chosen, 0)], 0)
    degree = np.where(fitted, JET_DEGREE, -1)
    higher = np.flatnonzero((walked >= 0) & (walked < len(deg.kd)))  # a richer model than the cubic
    k[higher], degree[higher] = deg.kd[walked[higher]], deg.degrees[walked[higher]]
    frame = jet_frames(coef, t1, t2, np.where(has_normal[:, None], normals, [0.0, 0.0, 1.0]), s)
    return k, (*frame[:-1], frame[-1] & fitted & ~np.isnan(coef[:, 0])), noise, degree  # followers: no jet


def _measured_noise(points, normals, idx, usable, s, t1, t2):
    """:func:`noise_variance` from the cubic jets at :data:`NOISE_KS` of the ``usable``
    centres on their neighbours ``idx`` (N, w); returns (sigma^2, a) (N,)."""
    rss = np.full((len(points), 2), np.nan)
    out = np.empty((len(usable), 2))
    f = _jet_frames(points, normals, _rows(idx, usable, NOISE_KS[1]), usable, s, t1, t2)
    jet_kernels.jet_residuals(f, np.asarray(NOISE_KS, dtype=np.int64), RCOND, out)
    rss[usable] = out
    return noise_variance(rss[:, 0], rss[:, 1], s, idx, size=np.abs(points).max(axis=1))


def _jet_ici(nb, idx, usable, ks, frames, sigma2_h, deg, report, *, lead=None):
    """(chosen index into ``ks`` (N,), -1 where no fit; coefficients (N, 10), NaN where not
    fitted; the degree rule's answer (N,)) of :func:`core.kernels.jets.jet_ici` at the
    ``usable`` centres, on their neighbours ``idx`` (N, w) (the columns ``nb`` holds);
    ``frames(rows, centres)`` the kernels' record, ``sigma2_h`` (N,) the noise in units of
    h^2, ``deg`` the degree rule (:func:`_degree_rule`, ``quiet`` for all N points).

    With w < ks[-1] the rule runs on the sizes up to w first. It looks one ring ahead
    (at size c it tests the ring ks[c]..ks[c + 1] for a fold) and ends at the last size,
    so it takes the same steps as on all sizes up to the next-to-last size held: a centre
    that stopped before (chosen <= m - 3 of m sizes) has the full rule's answer, the others
    (and those without a fit) are run again on their ``ks[-1]`` neighbours (``nb.rows``).
    With ``lead`` (noisy (N,) bool -> (followers, their anchors), :func:`core.anchors.shared_scale`)
    the noisy centres that follow an anchor take its answer (those whose anchor's fails, their own).
    """
    n = len(idx)
    out = (np.full(n, -1, dtype=np.int64), np.full((n, jet_kernels.P3), np.nan), np.full(n, -1, dtype=np.int64))
    rule = _jet_rule()
    m = int(np.searchsorted(ks, idx.shape[1], side="right"))  # sizes held
    if m < 3 < len(ks):  # too few to tell anything: all of them
        idx, m = nb.take(ks[-1])[0], len(ks)

    def run(c, rows, sizes):  # rows >= ks[2] = 28 wide: the richer models' (20) included
        got = np.empty(len(c), dtype=np.int64), np.empty((len(c), jet_kernels.P3)), np.empty_like(c)
        jet_kernels.jet_ici(frames(rows, c), np.asarray(sizes, dtype=np.int64), sigma2_h[c], rule,
                            deg._replace(quiet=deg.quiet[c]), *got)
        for dst, src in zip(out, got):
            dst[c] = src

    follow = lead_of = usable[:0]
    noisy = np.zeros(n, dtype=bool)
    if lead is not None:
        noisy[usable[~deg.quiet[usable]]] = True
        follow, lead_of = lead(noisy)
        usable = np.setdiff1d(usable, follow, assume_unique=True)
    for start in range(0, len(usable), _CHUNK):
        c = usable[start:start + _CHUNK]
        run(c, _rows(idx, c, ks[m - 1]), ks[:m])
        report(0.2 + 0.8 * min(len(usable), start + _CHUNK) / max(len(usable), 1), "choosing k")
    chosen = out[0]
    if m < len(ks):
        again = (chosen[usable] < 0) | (chosen[usable] >= m - 2)
        richer = usable[~again & (out[2][usable] == -2)], ks[:int(np.searchsorted(ks, deg.kmax, side="right"))]
        for redo, sizes in ((usable[again], ks), richer):  # the cubic final, the quartic still growing: to its widest
            for start in range(0, len(redo), _CHUNK):
                run(c := redo[start:start + _CHUNK], rows := nb.rows(c, sizes[-1])[0], sizes)
                wide_rows.keep_only(nb, rows, ~deg.quiet[c])  # a quiet point's jet is nearly always the result
    chosen[follow] = chosen[lead_of]
    alone = follow[(chosen[follow] < 0) & noisy[follow]]  # their anchor's rule failed: their own (not the sat-out)
    if len(alone):
        run(alone, nb.rows(alone, ks[-1])[0], ks)
    return out


def _degree_rule(ks, quiet):
    """The degree rule's :class:`core.kernels.jets.DegreeRule` for the cubic's sizes ``ks``:
    the models of :data:`JET_DEGREES` within reach of them, tried where ``quiet`` (N,) and
    the cubic stopped within their reach (where it grew wider, noise, not bias, limits it)."""
    reach = min(max(kd for _, kd in JET_DEGREES), ks[-1])
    models = [(d, k) for d, k in JET_DEGREES if k <= max(reach, ks[0])]
    degrees = np.array([d for d, _ in models], dtype=np.int64)
    kd = np.array([k for _, k in models], dtype=np.int64)
    return jet_kernels.DegreeRule(np.ascontiguousarray(quiet, dtype=np.bool_), degrees, kd,
                                  np.argsort(kd, kind="stable").astype(np.int64), int(reach),
                                  int(max([JET_DEGREE, *degrees])), int(max([0, *kd])), float(JET_MISFIT),
                                  float(JET_DEGREE_GAMMA))


def aligned_jets(jets, normals):
    """The jets' frames with their normals turned to agree with ``normals`` (k1, k2 change
    sign and swap, and so do e1, e2: the SPEC conventions)."""
    nrm, k1, k2, e1, e2, ok = jets
    with np.errstate(invalid="ignore"):
        flip = np.einsum("ij,ij->i", nrm, np.nan_to_num(normals)) < 0
    return (*turned_over(nrm, k1, k2, e1, e2, flip), ok)


def choose_model(points, normals, nb, has_normal, ks, report, *, priority=None, sat_out=None):
    """k per point by :func:`choose_jets`, and where the cubic jet itself is the result.

    Returns ``(k, on_jet, quiet, jets, degree)``: jets (aligned with ``normals``, of ``degree`` per point, see
    :func:`choose_jets`) are kept where the noise is below :data:`JET_QUIET`, the jet does not reach too far
    (:data:`JET_REACH`) and its normal is within :data:`JET_TILT` (:data:`JET_THIN_TILT`) of ``normals``;
    elsewhere NR fits on k neighbours, k by the NF rule (:func:`choose_k`) where the data are quiet but too
    sparse for the jet. A cloud too small for a cubic jet or for the noise measurement (fewer than
    ``NOISE_KS[-1]`` neighbours) keeps NR on ``ks[0]`` everywhere."""
    n = len(points)
    jks = tuple(k for k in jet_candidates(n) if k <= ks[-1])
    if not jks or ks[-1] < NOISE_KS[-1]:
        none = np.zeros(n, dtype=bool)
        return np.full(n, ks[0], dtype=np.int64), none, none, None, np.full(n, -1)
    k, jets, noise, degree = choose_jets(points, normals, nb, has_normal, jks, report, priority=priority, sat_out=sat_out)
    quiet = jets[-1] & (noise <= JET_QUIET)
    reach = nb.take(jks[0])[1][:, -1] * np.maximum(np.abs(jets[1]), np.abs(jets[2]))
    tilt = np.abs(np.einsum("ij,ij->i", jets[0], np.nan_to_num(normals)))  # cos to the initial normal (NaN: no jet)
    limit = np.full(n, JET_TILT)
    doubt = np.flatnonzero(quiet & (reach <= JET_REACH) & (tilt < np.cos(np.radians(JET_THIN_TILT))))  # where it matters
    limit[doubt[~plane_spread.spans_plane(points, normals, nb, np.maximum(k[doubt], jks[0]), centres=doubt)]] = JET_THIN_TILT
    on_jet = quiet & (reach <= JET_REACH) & (tilt >= np.cos(np.radians(limit)))
    nf_rule = quiet & ~on_jet
    if nf_rule.any():  # too few points per radius of curvature for a position jet: NF's own rule
        k_nf = choose_k(points, normals, nb, nf_rule, ks, AUTO_DEGREE, lambda *a: None)
        k = np.where(nf_rule, k_nf, k)
    return k, on_jet, quiet, aligned_jets(jets, normals), degree
