"""The fit/refine stage of :func:`core.estimate`: the first fit, NR's refinement passes
(§4.4) with k="auto"'s rules for when a pass is kept (:class:`core.passes.PassRule`) and
where a point keeps an earlier pass (:class:`_Held`), the jets merged in, and the signs
re-decided on the refined normals (:func:`settle_signs`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import anchors, drift, passes
from .frame import turned_over
from .orientation import resettle
from .passes import PassRule, few_fits
from .initial_normals import Initial
from .fits import CURVATURES, Fit, Fitter, empty_fit, invalid_at
from .stages import Scale
from .tuning import ANCHOR_REACH, DRIFT_POOL, HOLD_TURN, IRLS_LATER, PASS_DECAY, RESETTLE_K, ROWS_LATER
from .wide_rows import held_h, rows_at_least


class Refined(NamedTuple):
    """The fit kept by the refinement loop, the normals it was fitted to, and its pass."""

    fit: Fit
    input_normals: np.ndarray
    passes_run: int


def refine(pts, initial: Initial, outlier, nb, sc: Scale, plan, report) -> Refined:
    """Fit, then refine the normals (NR, §4.4) up to ``plan.passes`` times: stop below
    ``plan.tol``; with ``plan.adaptive`` undo a pass that turned the normals more than
    PASS_DECAY x the pass before (it smoothed the shape, not the noise). The adaptive rule
    judges each pass on :func:`core.passes.rule_sample` before the rest of the pass is
    fitted, so an undone pass costs only the sample. In robust mode the outliers leave
    their neighbours' fits after the first one. Where ``sc.on_jet`` the jet is the result
    (and its normal the neighbours' input); passes run only if NR fits at least
    PASS_MIN_SHARE of the points with noise (the pass rule judges by mean turns,
    meaningless on a handful of points). When the rule keeps one pass and undoes the 2nd,
    where the 2nd repeats the 1st's change of H the 1st drifted: those points report the
    first fit's curvatures (:func:`core.drift.step_back`; the 2nd pass is then fitted at
    every point)."""
    rule = PassRule(plan, few_fits(float((initial.has_normal & ~sc.quiet).mean()), plan))
    judged = passes.rule_sample(pts, plan.n_points) if plan.adaptive else None
    best = before = None
    for p, fit, nrm, complete in fit_passes(pts, initial, outlier, nb, sc, plan, report, n_fits=rule.n_fits,
                                            first=judged):
        seen = fit.valid if judged is None else fit.valid & judged
        change = passes.mean_turn_deg(fit.normals, nrm, seen) if rule.measures else None
        keep, more = rule.step(p, change)
        if keep:  # the first fit is kept aside for the drift rule (pass 2 undone) only: 107 MB at 1M points
            before, best = best if p == 1 else None, Refined(complete(), nrm, p)
        elif best.passes_run == 1:  # pass 2 undone, fitted everywhere: where it repeats pass 1's change, drift
            pool = nb.take(min(DRIFT_POOL, plan.k_search))[0]
            best = best._replace(fit=drift.step_back(before.fit, best.fit, complete(), pool))
        del fit, complete  # not held while the next pass is fitted (a fit is 106 MB at 1M points)
        if not more:
            break
    return finish(best, sc, outlier, plan)


def fit_passes(pts, initial: Initial, outlier, nb, sc: Scale, plan, report, *, n_fits, fitted=None, first=None):
    """Yield ``(p, fit, input normals, complete)`` for the first fit and each refinement
    pass, up to ``n_fits`` (the caller stops when it has enough); fits are never changed
    afterwards. ``complete()`` returns the fit to report for pass p: ``fit`` itself, or
    with k="auto" a copy where :class:`_Held` keeps earlier passes' fits (the next pass
    and the pass rule see ``fit``). ``fitted[p]`` (N,) bool, optional: fit only those points in fit p (a tile
    fits each pass only as far out as later passes use it; the others keep their input
    normals). With a mask ``first`` a pass is fitted there only (and at the anchors its
    points read, :mod:`core.anchors`), and ``complete()`` fits its other points (done
    before the next pass if the caller did not)."""
    kc = sc.k
    anchor = _anchors(pts, nb, kc, held_h(nb, kc), sc, outlier, plan)
    fits = ~sc.on_jet & sc.spans  # the points any pass fits: where the jet is the result, no rows are read
    idx, h = rows_at_least(nb, kc, fits if anchor is None else fits & ~anchors.followers(anchor))  # followers' on demand
    nrm, has_normal = initial.normals, initial.has_normal
    if sc.on_jet.any():  # the jets' normals are the neighbours' input where the jet is kept
        nrm = np.where(sc.on_jet[:, None], sc.jets[0], nrm)
    fitter = Fitter(pts, idx, kc, h, plan.method, dict(plan.options), anchor)
    share = 1.0 if first is None else float(first.mean())
    held = _Held(len(pts)) if plan.adaptive else None
    for p in range(n_fits):
        sub = report.sub(p / n_fits, (p + 1) / n_fits)
        fit = empty_fit(len(pts))
        centres = has_normal & ~sc.on_jet & sc.spans if fitted is None else has_normal & ~sc.on_jet & sc.spans & fitted[p]
        kept = fitter.into(fit, nrm, centres if first is None else centres & first, sub.sub(0.0, share))
        complete = _Rest(fitter, (fit, nrm, None if first is None else centres & ~first, sub.sub(share, 1.0), kept),
                         held)
        yield p, fit, nrm, complete
        complete()
        kept = complete = None  # the next pass builds its own (the anchors' fits: 54 MB at 1M points)
        if p == 0:
            fitter = _refining(fitter, plan)
        new = np.where(fit.valid[:, None], fit.normals, nrm)
        if plan.robust and p == 0:  # outliers leave their neighbours' fits (and are not estimated)
            has_normal = has_normal & ~outlier
            new[outlier] = np.nan
        nrm = new


def _anchors(pts, nb, kc, h, sc: Scale, outlier, plan):
    """The anchors whose fits each point reads (:func:`core.anchors.assign`) with k="auto",
    else None; anchors and followers are points fitted in every pass (outliers fit their own),
    ``h`` > 0 (:func:`core.wide_rows.held_h`: the rows of followers are not searched)."""
    if not anchors.in_use(plan):
        return None
    eligible = ~sc.on_jet & sc.spans & (h > 0) & ~outlier
    return anchors.assign(pts, nb.take_indices(min(ANCHOR_REACH + 1, plan.k_search)), kc, eligible, sc.priority)


def _refining(fitter: Fitter, plan) -> Fitter:
    """The fitter of the refinement passes: a robust fit reweights :data:`~core.tuning.IRLS_LATER`
    times (its input normals are the previous fit's, cleaned by that fit's weights); with
    k="auto" a neighbourhood of at least twice :data:`~core.tuning.ROWS_LATER` is thinned
    (the same reach, fewer rows: the input normals are already smooth)."""
    options = dict(fitter.options)
    if options.get("robust"):
        options["reweightings"] = IRLS_LATER
    if plan.auto:  # (NF and NR only: the methods k="auto" runs)
        options["rows"] = ROWS_LATER
    return fitter._replace(options=options)


def finish(best: Refined, sc: Scale, outlier, plan) -> Refined:
    """The kept fit with the jets merged in where they are the result, and in robust mode
    without the outliers (new arrays: the fits yielded by :func:`fit_passes` are kept)."""
    best = _with_jets(best, sc)
    return _drop_outliers(best, outlier) if plan.robust else best


def _with_jets(best: Refined, sc: Scale) -> Refined:
    """The jets' frames merged into the kept fit where the jet is the result."""
    if not sc.on_jet.any():
        return best
    on = sc.on_jet
    merged = [np.where(on.reshape((-1,) + (1,) * (a.ndim - 1)), j, a)
              for j, a in zip(sc.jets, best.fit[:6])]
    return best._replace(fit=best.fit._replace(**dict(zip(Fit._fields[:6], merged))))


def _drop_outliers(best: Refined, outlier) -> Refined:
    """Outliers are not estimated in robust mode (a kept first fit still estimated them)."""
    if not best.fit.valid[outlier].any():
        return best
    return best._replace(fit=invalid_at(best.fit, outlier, ("normals", *CURVATURES)))


class _Held:
    """What k="auto" reports pass by pass, point by point: where a pass turns a point's
    normal by more than HOLD_TURN degrees and by more than PASS_DECAY x the turn the pass
    before gave it, the pass is not averaging noise there (its turns decay) but carrying
    the normal across a sharp edge (on a 3-spacing plate at noise 0.2 spacing the side
    strip's turns went 10, 7, 6 degrees pass after pass, the faces' 4, 1.5, 0.9, and 8 %
    of the strip's normals ended more than 90 degrees off, from 5 % after the first fit):
    that point reports the fit of the pass before, at this pass and the later ones.
    :class:`core.passes.PassRule` undoes a pass that does so on the whole cloud; this is
    the same rule where only some points drift. The passes themselves, and the rule's
    mean turns, are left as they were (the next pass fits to the unheld normals), and the
    rule is each point's own, so a tile holds the same points as the whole cloud."""

    def __init__(self, n):
        self.held, self.turn, self.last = np.zeros(n, dtype=bool), np.zeros(n), None

    def report(self, fit: Fit, nrm) -> Fit:
        """The fit to report for the pass that fitted ``fit`` to ``nrm`` (call once a pass, in order)."""
        rows = np.flatnonzero(fit.valid)
        turn = np.zeros(len(nrm))
        turn[rows] = passes.turn_angles(fit.normals[rows], nrm[rows], slice(None))
        if self.last is not None:
            self.held = self.last.valid & (self.held | ((turn > HOLD_TURN) & (turn > PASS_DECAY * self.turn)))
            if self.held.any():
                fit = Fit(*(np.where(self.held.reshape((-1,) + (1,) * (a.ndim - 1)), b, a) for a, b in zip(fit, self.last)))
        self.turn, self.last = turn, fit
        return fit


class _Rest:
    """A pass's fit at the points outside the rule's sample, run once (:func:`fit_passes`);
    returns the fit to report (:class:`_Held`)."""

    def __init__(self, fitter, args, held=None):
        fit, nrm, mask, _, _ = args  # (fit, input normals, the points left, report, the anchors' fits kept)
        self.fitter, self.args = fitter, None if mask is None or not mask.any() else args
        self.fit, self.nrm, self.held, self.reported = fit, nrm, held, None

    def __call__(self) -> Fit:
        if self.args is not None:
            args, self.args = self.args, None
            self.fitter.into(*args)
        if self.reported is None:
            self.reported = self.fit if self.held is None else self.held.report(self.fit, self.nrm)
            self.fit = self.nrm = None  # what it was reported from is no longer needed here
        return self.reported


def settle_signs(pts, best: Refined, nb, plan, confidence):
    """The kept fit's signs re-decided on its own (refined) normals
    (:func:`core.orientation.resettle`) where the plan decides signs ("outward",
    "propagate"; on the neighbours of :func:`wider_ring`): the fits do not depend on the signs (each centre's neighbours are turned
    to its side), so a flip here is a flip of the result (:func:`core.frame.turned_over`).
    Returns ``(best, confidence)``, both new where
    anything changed."""
    if not plan.decides_signs:  # kept, or facing viewpoints
        return best, confidence
    fit = best.fit
    final = np.where(fit.valid[:, None], fit.normals, best.input_normals)
    sign, confidence = resettle(pts, final, wider_ring(nb, plan), plan.orientation, trust=plan.auto)
    return turned(best, sign < 0), confidence


def turned(best: Refined, flip) -> Refined:
    """``best`` turned over where ``flip`` (N,) bool (None: nowhere): normals negated, k1, k2
    negated and swapped, e1, e2 swapped (:func:`core.frame.turned_over`), its input normals
    negated; ``best`` itself where nothing turns."""
    if flip is None or not flip.any():
        return best
    fit = best.fit
    fit = fit._replace(**dict(zip(Fit._fields[:5], turned_over(*fit[:5], flip))))
    return best._replace(fit=fit, input_normals=np.where(flip[:, None], -best.input_normals, best.input_normals))


def wider_ring(nb, plan):
    """Each point's nearest whose evidence the re-decided signs read:
    :data:`core.tuning.RESETTLE_K` where the plan searches that many (k="auto"), else the
    ``plan.k_search`` it searches (15 with k=15: one more search of 30 cost NR k=15 on 100k
    points 1.3x its CPU time); set by the plan alone, so a cache's wider graph gives the
    same signs."""
    return nb.take_indices(min(RESETTLE_K, plan.k_search))  # k_search <= N, and >= ORIENT_K unless k is smaller
