"""Whole-cloud quantities of a tiled run: medians over every point, computed exactly.

An estimate measures a few quantities on the whole cloud: k="auto" grows its initial
neighbourhoods with the cloud's noise (a median of 2-jet residuals), creases are judged
against the cloud's median fit residual. They are :class:`core.planning.EstimatePlan`
fields that can be fixed from outside; a tiled run fixes them to the whole cloud's value:
each tile writes its own points' samples (sorted, to its work directory), and the run
selects the median exactly from the sorted files (:func:`median_of`), so no tile and no
scheduler ever holds the whole cloud's values.

A quantity is one :class:`Quantity` line in :data:`QUANTITIES`: the plan field, when it
is needed ("before" the fits, in a pre-pass round of tile tasks; "initial", in a second
pre-pass round, for what depends on a "before" value: the fold test's typical spread is
taken over the neighbourhoods the noise chose; or "after", sampled by the main tile
tasks and reported), its samples per tile and its reduction.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..normals import pca_normals
from ..one_sheet import fit_graph, sheet_width
from ..scale import initial_k
from ..initial_normals import _small_normals, fold_spreads, initial_rows, noise_samples
from ..stages import outlier_scores
from ..tuning import OUTLIER_SCORE
from .plan import TilePlan
from .store import TileStore
from .halo import FLAG_RINGS
from .task import auto_plan, load_with_halo

#: below this many values left, the selection reads them and partitions in memory
_GATHER = 1 << 20


@dataclass(frozen=True)
class Quantity:
    """One whole-cloud quantity: ``field`` of the EstimatePlan; ``when`` "before" (fixed
    before the fits) or "after" (sampled by the fits' tiles); ``samples(ctx)`` -> (groups
    of finite values, counts) of a tile's own points; ``reduce(median_of, counts)`` -> value."""

    field: str
    when: str
    samples: Callable
    reduce: Callable
    wanted: Callable = lambda plan: True


#: what a pre-pass round's tiles load: (k_max, dependency chain) of the plan, see
#: :func:`core.tiled.halo.shortfall`
_LOADS = {
    # own rows to the initial k, on their own sheet (core.one_sheet: two more rings), and their
    # points' outlier flags (core.tiled.halo.FLAG_RINGS further)
    "before": lambda plan: (sheet_width(plan), ((1, sheet_width(plan)), (1 + FLAG_RINGS, plan.k_initial))),
    # own rows to the initial k, their points' small normals and outlier flags, on their sheets
    "initial": lambda plan: (max(_k_init(plan), sheet_width(plan)),
                             ((0, max(_k_init(plan), sheet_width(plan))), (1, sheet_width(plan)),
                              (1 + FLAG_RINGS, plan.k_initial))),
}


def _initial_graph(ctx):
    """The tile's outlier flags (on the plain nearest) and the graph its initial normals are
    found on, as in memory (:func:`core.estimate.prepare`): each point's own sheet first."""
    pts, nb, plan = ctx.pts, ctx.nb, ctx.plan
    outlier = outlier_scores(pts, nb.take(plan.k_initial)[0]) > OUTLIER_SCORE
    return outlier, fit_graph(pts, nb, plan.k_initial) or nb


def _noise_samples(ctx):
    """The noise ratios (:func:`core.initial_normals.noise_samples`) of the tile's own points,
    apart for those with an outlier among their neighbours."""
    pts, plan, own = ctx.pts, ctx.plan, ctx.own
    outlier, nb = _initial_graph(ctx)
    idx_p, dist_p = nb.take(plan.k_initial)
    nrm, ok = pca_normals(pts, idx_p, dist_p)
    _, ratio, clean = noise_samples(pts, nrm, ok, idx_p, dist_p, outlier)
    finite = np.isfinite(ratio)
    return ({"clean": ratio[own & clean & finite], "other": ratio[own & ~clean & finite]},
            {"clean": int(np.count_nonzero(own & clean))})


def _fold_samples(ctx):
    """The fold test's spreads (:func:`core.initial_normals.fold_spreads`) of the tile's own points,
    at the initial scale the whole cloud's noise chose, apart for those with an outlier
    among those neighbours (their robust rows reach further than the tile loads: exact only
    where the cloud has clean points, which the median then takes alone)."""
    pts, plan, own = ctx.pts, ctx.plan, ctx.own
    outlier, nb = _initial_graph(ctx)
    idx_p, dist_p = nb.take(plan.k_initial)
    nrm, ok = pca_normals(pts, idx_p, dist_p)
    small, _ = _small_normals(pts, nrm, ok, idx_p, dist_p, None, plan)
    idx, _ = initial_rows(nb, _k_init(plan), outlier, plan)
    spread, clean = fold_spreads(small, idx, nb, _k_init(plan), outlier, plan)
    finite = np.isfinite(spread)
    return ({"clean": spread[own & clean & finite], "other": spread[own & ~clean & finite]},
            {"clean": int(np.count_nonzero(own & clean))})


def _k_init(plan) -> int:
    return initial_k(plan.noise, plan.k_initial, plan.k_search, plan.n_points)


def _folds_tested(plan) -> bool:
    """Whether :func:`core.initial_normals.initial_normals` tests folds: the noise grew the initial scale."""
    return plan.auto and plan.fold_typical is None and plan.noise is not None and _k_init(plan) > plan.k_initial


def _clean_median(median, counts):
    """:func:`core.scale.noise_ratio` (or :func:`core.initial_normals.typical_spread`) over the
    clean points if any, else over all."""
    return median(["clean"] if counts["clean"] else ["clean", "other"])


def _crease_samples(ctx):
    """The linear reference fit's residuals where valid (:func:`core.stages.flags`)."""
    ref, own = ctx.front.reference, ctx.own
    return {"rms": ref.rms[own & ref.valid & np.isfinite(ref.rms)]}, {}


QUANTITIES = (
    Quantity("noise", "before", _noise_samples, _clean_median, wanted=lambda plan: plan.noise is None),
    Quantity("fold_typical", "initial", _fold_samples, _clean_median, wanted=_folds_tested),
    Quantity("crease_typical", "after", _crease_samples, lambda median, counts: median(["rms"]),
             wanted=lambda plan: plan.auto and plan.crease_typical is None),
)


def wanted(plan, when: str) -> tuple:
    return tuple(q for q in QUANTITIES if q.when == when and q.wanted(plan))


# ---------------------------------------------------------------------------------- tiles
def run_before(root, tile: int, spec) -> dict:
    """The first pre-pass task of tile ``tile``: the "before" quantities' samples of its
    points (their chain: the own points and one ring of ``k_initial`` neighbours)."""
    return _run_prepass(root, tile, spec, "before")


def run_initial(root, tile: int, spec) -> dict:
    """The second pre-pass task of tile ``tile`` (``spec`` holds the "before" values):
    the "initial" quantities' samples of its points."""
    return _run_prepass(root, tile, spec, "initial")


def _run_prepass(root, tile: int, spec, when: str) -> dict:
    store = TileStore(root)
    n_own = len(store.read_bin(tile))
    if sampled(store, tile, when):
        return {"tile": tile, "skipped": True, "points": n_own}
    plan = auto_plan(spec)
    quantities = wanted(plan, when)
    samples = {}
    if n_own and quantities:
        k_max, chain = _LOADS[when](plan)
        rec, owner, nb, _ = load_with_halo(store, TilePlan.load(store.plan_path), tile, k_max, chain)
        pts = nb.points
        ctx = _Context(pts, nb, dataclasses.replace(plan, n_points=len(pts)), owner == tile, None)
        samples = {q.field: q.samples(ctx) for q in quantities}
    save_samples(store, tile, when, samples)
    return {"tile": tile, "skipped": False, "points": n_own}


def sampled(store, tile: int, when: str) -> bool:
    """Whether tile ``tile`` has written its samples of ``when`` (the last file of them)."""
    return _path(store, tile, when).exists()


def samples_after(front, plan, own) -> dict:
    """The "after" quantities' samples of a main tile task."""
    ctx = _Context(front.pts, front.nb, plan, own, front)
    return {q.field: q.samples(ctx) for q in wanted(plan, "after")}


@dataclass(frozen=True)
class _Context:
    pts: np.ndarray
    nb: object
    plan: object
    own: np.ndarray
    front: object


def save_samples(store, tile: int, when: str, samples: dict) -> None:
    """Each group sorted into its own .npy (memory-mapped by the reduction), the counts last."""
    counts = {}
    for field, (groups, n) in samples.items():
        for name, values in groups.items():
            store.save_array(_path(store, tile, when, f"{field}.{name}"), np.sort(values))
        counts[field] = {"groups": sorted(groups), "counts": n}
    store._write_bytes(_path(store, tile, when), json.dumps(counts).encode())


def _path(store, tile, when, part=None):
    name = f"tile_{tile:06d}.{when}" + (f".{part}.npy" if part else ".json")
    return store.root / "results" / name


# ---------------------------------------------------------------------------- the reduction
def reduce(store, n_tiles: int, plan, when: str) -> dict:
    """The whole-cloud value of every wanted quantity of ``when`` from the tiles' samples."""
    index = [json.loads(_path(store, t, when).read_text()) for t in range(n_tiles)]
    out = {}
    for q in wanted(plan, when):
        counts = {}
        for entry in index:
            for name, c in entry.get(q.field, {}).get("counts", {}).items():
                counts[name] = counts.get(name, 0) + c

        def median(groups, field=q.field):
            return median_of([np.load(_path(store, t, when, f"{field}.{g}"), mmap_mode="r")
                              for t, entry in enumerate(index) if field in entry for g in groups])

        out[q.field] = float(q.reduce(median, counts))
    return out


def median_of(arrays) -> float:
    """``np.median`` of the concatenation of sorted, NaN-free ``arrays`` (0.0 if empty),
    exactly, without concatenating them."""
    n = sum(len(a) for a in arrays)
    if n == 0:
        return 0.0
    if n % 2:
        return float(kth_smallest(arrays, n // 2))
    return float(np.mean(np.array([kth_smallest(arrays, n // 2 - 1), kth_smallest(arrays, n // 2)])))


def kth_smallest(arrays, k: int):
    """The ``k``-th smallest (0-based) of sorted ``arrays`` taken together: narrow each
    array's window around a pivot (the middle of the widest window) by binary search."""
    lo = np.zeros(len(arrays), dtype=np.int64)
    hi = np.array([len(a) for a in arrays], dtype=np.int64)
    while True:
        width = hi - lo
        if width.sum() <= _GATHER:
            left = np.concatenate([np.asarray(a[l:h]) for a, l, h in zip(arrays, lo, hi)])
            return np.partition(left, k)[k]
        t = int(np.argmax(width))
        pivot = arrays[t][(lo[t] + hi[t]) // 2]
        below = np.array([l + np.searchsorted(a[l:h], pivot, "left") for a, l, h in zip(arrays, lo, hi)])
        upto = np.array([l + np.searchsorted(a[l:h], pivot, "right") for a, l, h in zip(arrays, lo, hi)])
        n_below, n_upto = int((below - lo).sum()), int((upto - lo).sum())
        if k < n_below:
            hi = below
        elif k < n_upto:
            return pivot
        else:
            k -= n_upto
            lo = upto
