"""The halo of a tile: every point its own points' answers depend on, proven complete.

With an integer k the answer at p depends on a chain of neighbourhoods (paper §4.2-4.4):
the fit at p uses the normals of its k neighbours; in an NR pass those are themselves
fits over *their* neighbours; the first fit uses the PCA normals (eqs. 13-14) of points
one ring further, and each PCA normal needs that point's own k nearest neighbours. So
with ``passes`` refinement passes the points up to ``passes + 1`` kNN rings away from the
tile must see exactly their global k nearest neighbours (:func:`chain_rings`). With
k="auto" the chain is longer and has two widths (:func:`auto_chain`).

A point's neighbours within the loaded box are its global ones when its k-th neighbour
is closer than the box's boundary (every point beyond the boundary is farther). The box
is the tile grown by a margin; :func:`check_halo` says by how much the margin falls
short, and the task grows it until nothing does, so the halo is derived from the data
(a sparse region or an outlier grows it) rather than guessed.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from ..one_sheet import sheet_width

#: own points whose k-th neighbour distance sets the first margin (a subsample suffices)
_PROBE = 20_000
#: the first margin is this many times (rings x the 99th percentile of the k-th distance)
_MARGIN_SAFETY = 1.25
_GROWTH = 1.5
#: kNN rings beyond a point whose ``k_initial`` nearest its outlier flag reads: its own row,
#: its neighbours' planes and their neighbours' scales (:func:`core.off_surface.off_surface`)
FLAG_RINGS = 2


def chain_rings(passes: int) -> int:
    """kNN rings beyond a tile whose neighbourhoods must be exact: one per fit (passes + 1)."""
    return passes + 1


def nr_chain(passes: int, k: int, k_initial: int, robust: bool) -> tuple:
    """The dependency chain (as :func:`auto_chain`'s) of an integer k: the fits' k nearest
    to :func:`chain_rings`, and the outlier flags' ``k_initial`` nearest
    :data:`FLAG_RINGS` further out from the points whose flags are read: the own points'
    (reported), and in robust mode those of the initial normals' neighbours, a ring beyond
    the fits' (outliers are left out of both)."""
    flags = chain_rings(passes) + 1 if robust else 0
    return ((chain_rings(passes), k), (flags + FLAG_RINGS, k_initial))


def auto_chain(passes: int, k_search: int, k_initial: int, anchored: bool = False) -> tuple:
    """The dependency chain of k="auto" as ``((rings, k), ...)``: points within ``rings``
    kNN hops of the tile (over the ``k_search`` lists) need their ``k`` nearest exact.

    The output at p is the last of ``passes + 1`` fits (the tiles compute all of them: the
    pass that is kept is a whole-cloud decision, :mod:`core.tiled.auto`). Fit j at a point
    uses its neighbours' normals of fit j - 1, so fit 0 is needed ``passes`` rings out and
    every point up to there needs its exact ``k_search`` list (the fit's k, and the scale
    choice's candidates up to k_search). Fit 0 and the scale choice at ring ``passes`` use
    the initial normals of ring ``passes + 1`` (the fold test, the noise pooled over 20
    neighbours, the jets' normals) and their k_init-NN PCA and 2-jet, which in robust mode
    skip outliers over the whole ``k_search`` list (``Neighbours.take_without``): exact
    ``k_search`` lists to ring ``passes + 1``. The outlier flags of those lists' points,
    ring ``passes + 2``, need only the ``k_initial`` nearest of the points up to
    :data:`FLAG_RINGS` further (the outlier scores). Each
    point's own-sheet order (:mod:`core.one_sheet`) reads its neighbours' normals, from their
    own-sheet rows in turn: the first :func:`core.one_sheet.sheet_width` one ring further,
    and the ``k_initial`` nearest two. With ``anchored`` fits (:mod:`core.anchors`) a point's
    fit is that of an anchor among its nearest, whose neighbours are a ring further: fit 0
    is needed ``2 passes + 1`` rings out, and at the anchors of that ring, whose scale may
    be that of an anchor of the scale rule a ring further (:func:`core.anchors.shared_scale`).
    """
    hops = 2 * passes + 2 if anchored else passes
    return ((hops + 1, k_search), (hops + 2, sheet_width(k_search)), (hops + 2 + FLAG_RINGS, k_initial))


def shortfall(nb, own, chain, lo, hi) -> tuple[float, np.ndarray]:
    """(:func:`check_halo`'s largest shortfall over the ``chain`` levels, the points whose
    ``nb`` lists are exact to their end: the first level's)."""
    worst, exact = -np.inf, None
    for rings, k in chain:
        needed = rings_from(own, nb.indices, rings)
        worst = max(worst, check_halo(nb.points, nb.distances[:, k - 1], needed, lo, hi))
        exact = needed if exact is None else exact
    return worst, exact


def first_margin(own_xyz: np.ndarray, k: int, rings: int, *, share: float = 1.0, probe: int = _PROBE) -> float:
    """A margin that usually suffices: (rings + 1) k-th neighbour distances, plus a safety.
    ``own_xyz`` may be a sample holding ``share`` of the cloud's points (:mod:`.sizing`): the
    cloud's k-th neighbour is then about the (k share)-th of the sample, whose distance is
    scaled as on a surface (by the square root of the neighbour counts); ``probe`` points
    are measured."""
    tree = cKDTree(own_xyz)
    probes = own_xyz[:: max(1, len(own_xyz) // probe)]
    j = k * share
    kk = min(max(1, math.ceil(j)), len(own_xyz))
    d, _ = tree.query(probes, k=kk)
    r = float(np.quantile(np.reshape(d, (len(probes), kk))[:, -1], 0.99))
    return _MARGIN_SAFETY * (rings + 1) * r * math.sqrt(min(j, len(own_xyz)) / kk)  # 1 on a tile's own points


def gather(store, plan, tile: int, margin: float):
    """The points in the tile's box grown by ``margin``, sorted by input row.

    Returns ``(binned records, owner tile of each, lo, hi)`` with lo/hi the grown box.
    """
    lo, hi = plan.lo[tile] - margin, plan.hi[tile] + margin
    parts, owners = [], []
    for t in plan.touching(lo, hi):
        rec = store.read_bin(int(t))
        if t != tile:
            xyz = rec["xyz"]
            rec = rec[((xyz >= lo) & (xyz <= hi)).all(axis=1)]
        parts.append(np.asarray(rec))
        owners.append(np.full(len(rec), t, dtype=np.int32))
    rec = np.concatenate(parts) if parts else np.zeros(0, store.bin_dtype)
    owner = np.concatenate(owners) if owners else np.zeros(0, np.int32)
    order = np.argsort(rec["index"], kind="stable")
    return rec[order], owner[order], lo, hi


def rings_from(start: np.ndarray, idx: np.ndarray, rings: int) -> np.ndarray:
    """Points within ``rings`` hops of ``start`` (bool mask) along kNN rows ``idx``."""
    reached = start.copy()
    frontier = np.flatnonzero(start)
    for _ in range(rings):  # marking a mask: 20x faster than np.unique of the rows (measured)
        hit = np.zeros(len(reached), dtype=bool)
        hit[idx[frontier].ravel()] = True
        hit &= ~reached
        reached |= hit
        frontier = np.flatnonzero(hit)
    return reached


def check_halo(xyz, dist_k, needed, lo, hi) -> float:
    """How far the box falls short of holding every needed point's k-neighbour ball.

    Negative when every point in ``needed`` has its k-th neighbour (at ``dist_k``)
    strictly closer than every finite face of the box [lo, hi] (the halo is complete);
    otherwise the largest shortfall (>= 0).
    """
    q, r = xyz[needed], dist_k[needed]
    with np.errstate(invalid="ignore"):  # inf - inf on the infinite faces
        room = np.minimum(np.where(np.isfinite(lo), q - lo, np.inf), np.where(np.isfinite(hi), hi - q, np.inf))
    short = r - room.min(axis=1)
    return float(short.max()) if len(short) else -np.inf


def grown(margin: float, shortfall: float, scale: float) -> float:
    """The next margin after a shortfall (grow by more than needed: new points bring new needs)."""
    return margin + _GROWTH * shortfall + 1e-9 * max(scale, 1.0)
