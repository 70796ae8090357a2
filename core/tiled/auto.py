"""k="auto" in tiles: one tile's estimate with every pass kept, and the whole-cloud pass choice.

In memory, k="auto" refines the normals pass after pass and stops (undoing the last pass)
once a pass turns the normals, on average over the whole cloud, by more than PASS_DECAY x
the pass before (:class:`core.stages.PassRule`). A tile cannot know that mean, so each
tile runs every pass (its halo holds the chain of all of them, :func:`core.tiled.halo.auto_chain`),
writes each pass's result for its own points and its share of each pass's mean turn;
:func:`kept_pass` then sums the shares and replays the in-memory rule, and the run
assembles the kept pass (:class:`PassView`). The whole-cloud quantities the front of the
estimate needs (the noise) are fixed beforehand by :mod:`core.tiled.wholecloud`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..estimate import _reported, _result as result_of, prepare  # the in-memory result's fields and flags
from ..planning import EstimatePlan
from ..passes import PassRule, few_fits, rule_sample, turn_angles
from .. import anchors, drift
from ..refinement import Refined, finish, fit_passes, settle_signs
from ..stages import flags
from .._progress import Progress
from ..tuning import DRIFT_POOL
from .halo import rings_from
from .plan import TilePlan
from .store import TileStore
from .task import auto_plan, LINK_DTYPE, NODE_DTYPE, ROW_DTYPE, _components, _face_viewpoints, _nodes, _rows, load_with_halo, tile_chain
from . import wholecloud


def run_auto_tile(root, tile: int, spec) -> dict:
    """Estimate tile ``tile`` with k="auto", every pass written (``.pass{p}`` results)."""
    store = TileStore(root)
    if store.finished(tile):
        return {"tile": tile, "skipped": True, "points": len(store.read_bin(tile))}
    plan = TilePlan.load(store.plan_path)
    whole = auto_plan(spec)
    if len(store.read_bin(tile)) == 0:
        _save(store, tile, [_empty()] * (whole.passes + 1), np.zeros((whole.passes + 2, 2)), {})
        return {"tile": tile, "skipped": False, "points": 0, "loaded": 0}
    anchored = anchors.shares_scale(whole)  # a fit or scale read at a follower: rings more (core.tiled.halo.auto_chain)
    rec, owner, nb, exact = load_with_halo(store, plan, tile, *tile_chain(spec))
    pts = np.ascontiguousarray(rec["xyz"])
    normals = np.ascontiguousarray(rec["n"]) if spec.normals_given else None
    tplan = dataclasses.replace(whole, n_points=len(pts))
    front = prepare(pts, normals, tplan, nb, Progress(None))
    own = owner == tile
    judged = own & rule_sample(pts, whole.n_points) if whole.adaptive else own  # as in memory (core.passes)
    outputs, stats = [], np.zeros((tplan.passes + 2, 2))  # per pass: sum of turns, count; then the noisy points
    # fit p where later fits use it, and one ring more: an own point's border flag counts its valid neighbours
    reach = [rings_from(own, nb.indices, (2 if anchored else 1) * (tplan.passes - p) + 1) for p in range(tplan.passes + 1)]
    fits, back = [], []  # the last three passes' fits; pass 1 stepped back where pass 2 drifts (core.drift)
    pool = front.fit_nb.take(min(DRIFT_POOL, tplan.k_search))[0]

    def output(fit, nrm, p):
        best = finish(Refined(fit, nrm, p), front.scale, front.outlier, tplan)
        best, confidence = settle_signs(pts, best, nb, tplan, front.confidence)
        marks = flags(best.fit, front.scores, tplan, front.reference, nb=nb, confidence=confidence)
        stages = _reported((front.init, best, front.scale, marks))
        res = result_of(pts, np.ones(len(pts), dtype=bool), tplan, stages=stages, neighbours=nb, repaired=front.repaired)
        return _outputs(rec, res, nb, own, owner, exact, spec, front.init.normals)

    for p, fit, nrm, complete in fit_passes(pts, front.init, front.outlier, front.fit_nb, front.scale, tplan, Progress(None),
                                         n_fits=tplan.passes + 1, fitted=reach):
        seen = fit.valid & judged
        stats[p] = math.fsum(turn_angles(fit.normals, nrm, seen)), int(seen.sum())
        fits = (fits + [(complete(), nrm)])[-3:]
        outputs.append(output(*fits[-1], p))
        if p == 2:
            (f0, _), (f1, n1), (f2, _) = fits
            back.append(output(drift.step_back(f0, f1, f2, pool), n1, 1))
    stats[-1, 0] = np.count_nonzero(front.init.has_normal & ~front.scale.quiet & own)
    _save(store, tile, outputs, stats, wholecloud.samples_after(front, tplan, own), back)
    return {"tile": tile, "skipped": False, "points": int(own.sum()), "loaded": len(pts)}


def _outputs(rec, res, nb, own, owner, exact, spec, initial):
    """(rows, links, nodes) of one pass, as :func:`core.tiled.task.run_tile` writes them."""
    comp = _components(nb.indices, np.isfinite(res.normals).all(axis=1), exact)
    rows = _rows(rec, res, comp, own)
    if spec.orientation == "scanner":
        _face_viewpoints(rows, initial[own], rec["view"][own])
    halo = exact & ~own & (comp >= 0)
    links = np.empty(int(halo.sum()), LINK_DTYPE)
    links["index"], links["owner"] = rec["index"][halo], owner[halo]
    links["comp"], links["n"] = comp[halo], res.normals[halo]
    return rows, links, _nodes(rows)


def _empty():
    return np.zeros(0, ROW_DTYPE), np.zeros(0, LINK_DTYPE), np.zeros(0, NODE_DTYPE)


def _save(store, tile, outputs, stats, samples, back=()) -> None:
    """Every pass's arrays (and pass 1's stepped back, ``back[0]``: ``.pass1b``), the tile's
    shares of the whole-cloud reductions, then the marker."""
    named = [(f".pass{p}", arrays) for p, arrays in enumerate(outputs)]
    named += [(f".pass{p}b", arrays) for p, arrays in enumerate(back, start=1)]
    for name, arrays in named:
        for part, arr in zip(("", ".links", ".nodes"), arrays):
            store.save_array(store.result_path(tile, f"{name}{part}"), arr)
    wholecloud.save_samples(store, tile, "after", samples)
    store.save_array(store.result_path(tile, ".stats"), stats)
    store.mark_finished(tile)


def kept_pass(store: TileStore, n_tiles: int, plan: EstimatePlan) -> int:
    """The pass the in-memory estimate keeps (:func:`pass_choice`)."""
    return pass_choice(store, n_tiles, plan)[0]


def pass_choice(store: TileStore, n_tiles: int, plan: EstimatePlan) -> tuple[int, bool]:
    """(the pass the in-memory estimate keeps, whether it steps back where the 2nd pass
    drifts: memory does when it keeps the 1st pass and undoes the 2nd,
    :func:`core.refinement.refine`): each pass's mean turn of the normals and the
    share of points NR fits with noise, summed over the tiles, through its :class:`PassRule`.

    The sums are exact (``math.fsum``) where memory sums pairwise, so a mean may differ in
    its last bit; the choice differs only if a mean lies within ~1e-15 of PASS_DECAY x the
    previous one (or of ``tol``).
    """
    stats = [np.load(store.result_path(t, ".stats")) for t in range(n_tiles)]
    noisy = sum(int(s[-1, 0]) for s in stats)
    sums, counts = zip(*[(math.fsum(s[p, 0] for s in stats), sum(int(s[p, 1]) for s in stats))
                         for p in range(plan.passes + 1)])
    rule = PassRule(plan, few_fits(noisy / plan.n_points, plan))
    kept, back = 0, False
    for p in range(rule.n_fits):
        change = (sums[p] / counts[p] if counts[p] else 0.0) if rule.measures else None
        keep, more = rule.step(p, change)
        kept, back = (p, False) if keep else (kept, kept == 1)
        if not more:
            break
    return kept, back


class PassView(TileStore):
    """The run's store seen through one pass: its results are the tiles' results (what
    :mod:`.signs` and :mod:`.assemble` read)."""

    def __init__(self, root, kept: int, back: bool = False):
        super().__init__(root)
        self.kept, self.back = kept, back

    def result_path(self, tile: int, part: str = ""):
        return super().result_path(tile, f".pass{self.kept}{'b' if self.back else ''}{part}")
