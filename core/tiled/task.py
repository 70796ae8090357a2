"""One tile: read it with its halo from the bins, estimate, keep its own points.

This is the function a Dask worker runs; it reads and writes only its work directory,
so nothing but the tile id and a few parameters travel through the scheduler.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
from .. import anchors
from ..duplicates import CopiesNeighbours, find_duplicates
from ..estimate import estimate
from ..kernels.sign_evidence import knn_components
from ..neighbours import build_neighbours
from ..normals import pca_normals
from ..orientation import ORIENT_K
from ..planning import EstimatePlan
from . import creases
from .halo import auto_chain, first_margin, gather, grown, nr_chain, shortfall
from .plan import TilePlan
from .store import TileStore

#: margin growths before a tile gives up (each grows by 1.5x the measured shortfall)
MAX_GROWTHS = 12

ROW_DTYPE = np.dtype([("index", "<i8"), ("xyz", "<f8", 3), ("n", "<f8", 3), ("k1", "<f8"), ("k2", "<f8"),
                      ("e1", "<f8", 3), ("e2", "<f8", 3), ("valid", "u1"), ("k", "<i4"), ("comp", "<i4"),
                      ("degree", "i1"), ("border", "u1"), ("orientation_confidence", "<f4"),
                      ("outlier_score", "<f4"), ("crease", "u1"), ("anisotropy", "<f4")])
#: the result's per-point flags a tile keeps (row field -> CurvatureResult attribute); the border
#: and the anisotropy are judged on the tile's points and its halo (>= 2 k-th-neighbour
#: distances wide, first margin 3.75: the border's 30 neighbours reach ~1.4, the 60 a flagged
#: point is read again on ~2, the anisotropy's 15 + 4 nearest lie within the exact rings)
ROW_FLAGS = {"degree": "degree_point", "border": "border", "orientation_confidence": "orientation_confidence",
             "outlier_score": "outlier_score", "crease": "crease", "anisotropy": "anisotropy"}
#: a halo point near the tile: how this tile orients it (for sign agreement with its owner)
LINK_DTYPE = np.dtype([("index", "<i8"), ("owner", "<i4"), ("comp", "<i4"), ("n", "<f8", 3)])
#: one connected part of the tile's own points: what the final orientation needs
NODE_DTYPE = np.dtype([("comp", "<i4"), ("count", "<i8"), ("sum", "<f8", 3), ("top_z", "<f8"),
                       ("top_index", "<i8"), ("top_nz", "<f8")])


@dataclass(frozen=True)
class TileSpec:
    """What every tile runs: the estimate's parameters and the in-tile orientation."""

    k: object  # an int, or "auto" (then n_points and the whole-cloud quantities ``fixed`` matter)
    method: str
    passes: int
    orientation: object  # "propagate", "keep", "scanner" (each point's viewpoint) or a (3,) viewpoint tuple
    options: dict = field(default_factory=dict)
    normals_given: bool = False
    threads: int = 1
    n_points: int = 0  # of the whole cloud (k="auto" derives its candidates from it)
    fixed: tuple = ()  # (EstimatePlan field, whole-cloud value) pairs (core.tiled.wholecloud)


def auto_plan(spec: TileSpec, n_points: int | None = None) -> EstimatePlan:
    """The k="auto" plan of the whole cloud (candidates from its N, the whole-cloud
    quantities of ``spec.fixed``), for ``n_points`` points of one tile."""
    orientation = "keep" if spec.orientation == "scanner" else spec.orientation
    whole = EstimatePlan.build(spec.n_points, k="auto", method=spec.method, passes=spec.passes,
                               orientation=orientation, options=dict(spec.options) or None,
                               normals_given=spec.normals_given)
    return dataclasses.replace(whole, n_points=n_points or spec.n_points, **dict(spec.fixed))


def run_tile(root, tile: int, spec: TileSpec) -> dict:
    """Estimate tile ``tile`` of the run in ``root`` unless already done; returns a summary."""
    store = TileStore(root)
    if store.finished(tile):
        return {"tile": tile, "skipped": True, "points": len(store.load_result(tile))}
    _set_threads(spec.threads)
    plan = TilePlan.load(store.plan_path)
    own_n = len(store.read_bin(tile))
    if own_n == 0:
        creases.save(store, tile, np.zeros(0), np.zeros(0))
        store.save_result(tile, np.zeros(0, ROW_DTYPE), np.zeros(0, LINK_DTYPE), np.zeros(0, NODE_DTYPE))
        return {"tile": tile, "skipped": False, "points": 0, "loaded": 0}
    rec, owner, nb, needed = _load_with_halo(store, plan, tile, spec)
    pts = np.ascontiguousarray(rec["xyz"])
    normals = np.ascontiguousarray(rec["n"]) if spec.normals_given else None
    orientation = spec.orientation
    if isinstance(orientation, tuple):
        orientation = np.asarray(orientation)
    elif orientation == "scanner":  # faced after the fit, each point towards its own viewpoint
        orientation = "keep"
    res = estimate(pts, normals, k=spec.k, method=spec.method, passes=spec.passes, orientation=orientation,
                   options=dict(spec.options) or None, neighbours=nb)
    own = owner == tile
    comp = _components(nb.indices, np.isfinite(res.normals).all(axis=1), needed)
    rows = _rows(rec, res, comp, own)
    if spec.orientation == "scanner":
        initial, _ = pca_normals(nb.points, *nb.take(spec.k))  # as estimate() computed them
        _face_viewpoints(rows, initial[own], rec["view"][own])
    halo = needed & ~own & (comp >= 0)
    links = np.empty(int(halo.sum()), LINK_DTYPE)
    links["index"], links["owner"] = rec["index"][halo], owner[halo]
    links["comp"], links["n"] = comp[halo], res.normals[halo]
    loaded = len(pts)
    crease = creases.tile_parts(res, own, nb)  # re-judged against the whole cloud's typical residual
    del res, nb, rec, pts  # the tile's largest arrays: what is left needs only the rows (peak memory)
    creases.save(store, tile, *crease)
    store.save_result(tile, rows, links, _nodes(rows))
    return {"tile": tile, "skipped": False, "points": int(own.sum()), "loaded": loaded}


def tile_chain(spec):
    """(k_max, chain) a tile of the run loads with its halo (:mod:`.halo`): with k="auto" the whole
    cloud's plan's chain, else the paper's pipeline's (the outlier flags' k and mode as estimate()'s)."""
    if spec.k == "auto":
        whole = auto_plan(spec)
        return whole.k_search, auto_chain(whole.passes, whole.k_search, whole.k_initial, anchors.shares_scale(whole))
    nr = EstimatePlan.build(max(spec.k, 3), k=spec.k, method=spec.method, passes=spec.passes,
                            options=dict(spec.options) or None)
    return spec.k, nr_chain(nr.passes, spec.k, nr.k_initial, nr.robust)


def _load_with_halo(store, plan, tile, spec):
    return load_with_halo(store, plan, tile, *tile_chain(spec))


def load_with_halo(store, plan, tile, k_max, chain):
    """The tile and a halo grown until every point of the dependency ``chain`` (see
    :func:`core.tiled.halo.shortfall`) has its true neighbours; returns the records, their
    owner tiles, their ``k_max`` neighbours and the points whose lists are exact. Copies of
    a point are one place (:mod:`core.duplicates`, as :func:`core.estimate` merges them), so
    the halo must hold the distinct places' neighbours, which reach farther than the copies'."""
    own_xyz = np.asarray(store.read_bin(tile)["xyz"])
    margin = first_margin(own_xyz, k_max, max(rings for rings, _ in chain))
    scale = float(np.abs(plan.bounds).max())
    for _ in range(MAX_GROWTHS):
        rec, owner, lo, hi = gather(store, plan, tile, margin)
        nb, short, needed = _tile_graph(np.ascontiguousarray(rec["xyz"]), owner == tile, k_max, chain, lo, hi, tile)
        if short < 0:
            return rec, owner, nb, needed
        margin = grown(margin, short, scale)
    raise ValueError(f"tile {tile}: the halo did not cover the neighbourhoods after {MAX_GROWTHS} growths "
                     f"(margin {margin:.4g})")


def _tile_graph(xyz, own, k_max, chain, lo, hi, tile):
    """(graph, :func:`shortfall`, exact points) of a tile and its halo; with copies, the
    graph of the distinct places as neighbours of every copy."""
    merged = find_duplicates(xyz)
    places = xyz if merged is None else merged.points
    if len(places) < k_max:
        raise ValueError(f"tile {tile}: only {len(places)} points within reach, fewer than k={k_max}")
    nb = build_neighbours(places, k_max)
    if merged is None:
        return (nb, *shortfall(nb, own, chain, lo, hi))
    short, needed = shortfall(nb, own[merged.first], chain, lo, hi)  # a place's copies share its tile
    return CopiesNeighbours(nb, merged, xyz), short, needed[merged.inverse]


def _components(idx, ok, exact) -> np.ndarray:
    """Connected parts of the orientation graph (ORIENT_K nearest, as :func:`orient_normals`),
    using only edges from points whose neighbours are exact; -1 where a point has no normal.
    Labelled 0, 1, ... in order of each part's lowest index."""
    roots = knn_components(idx, ok & exact, ok, ORIENT_K)
    labels = np.full(len(idx), -1, dtype=np.int32)
    _, labels[ok] = np.unique(roots[ok], return_inverse=True)
    return labels


def _rows(rec, res, comp, own) -> np.ndarray:
    rows = np.empty(int(own.sum()), ROW_DTYPE)
    rows["index"], rows["xyz"], rows["n"] = rec["index"][own], rec["xyz"][own], res.normals[own]
    rows["k1"], rows["k2"], rows["e1"], rows["e2"] = res.k1[own], res.k2[own], res.e1[own], res.e2[own]
    rows["valid"], rows["k"], rows["comp"] = res.valid[own], res.k_point[own], comp[own]
    for name, attr in ROW_FLAGS.items():
        rows[name] = getattr(res, attr)[own]
    return rows


def _face_viewpoints(rows, initial, views) -> None:
    """Orient each row as if its initial normal had been turned towards its own viewpoint
    (what ``orientation=(x, y, z)`` does for one). The fits follow the sign of the initial
    normal (each fit's normal stays in the hemisphere of the one it refines), so flipping
    the result (n -> -n, k1, k2 -> -k2, -k1, e1 <-> e2) where the initial normal faced away
    is the same."""
    flip = np.einsum("ij,ij->i", initial, views - rows["xyz"]) < 0
    r = rows[flip]
    r["n"] *= -1
    r["k1"], r["k2"] = -rows["k2"][flip], -rows["k1"][flip]
    r["e1"], r["e2"] = rows["e2"][flip], rows["e1"][flip]
    rows[flip] = r


def _nodes(rows) -> np.ndarray:
    """Per connected part of the own points: count, coordinate sum and highest point."""
    have = np.flatnonzero(rows["comp"] >= 0)  # rows by index, not a copy of the records (peak memory)
    labels, inverse = np.unique(rows["comp"][have], return_inverse=True)
    nodes = np.zeros(len(labels), NODE_DTYPE)
    nodes["comp"] = labels
    nodes["count"] = np.bincount(inverse, minlength=len(labels))
    xyz = rows["xyz"][have]
    for j in range(3):
        nodes["sum"][:, j] = np.bincount(inverse, xyz[:, j], len(labels))
    # the highest point of each part (lowest input row among equals, as the in-memory seed)
    order = np.lexsort((rows["index"][have], -xyz[:, 2], inverse))
    first = have[order[np.searchsorted(inverse[order], np.arange(len(labels)))]]
    nodes["top_z"], nodes["top_index"], nodes["top_nz"] = rows["xyz"][first, 2], rows["index"][first], rows["n"][first, 2]
    return nodes


def _set_threads(threads: int) -> None:
    import numba

    numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
