"""k="auto" within the part a point lies on: many small objects far apart (README "Small objects").

The scale rule's caps are shares of the cloud: the initial normals hold at most 1 /
:data:`core.tuning.INITIAL_SHARE` of it (:func:`core.scale.initial_k`), the chosen fits at
most half (:func:`core.scale.candidates`). A small object far from the rest is a cloud of its
own to the neighbours (none reach across the gap), but was capped by the size of the whole:
27 spheres of 113 points in a grid, 4 radii apart, took 42-59 initial neighbours (15 alone) and
chose 28-40; spheres of 50 points reached into the next sphere. Here a part is a connected
component of the :data:`core.tuning.SEARCH_WIDTH`-nearest graph cut where a neighbour lies more
than :data:`GAP` x the point's ``k_initial``-th nearest away, and a point's initial and chosen
neighbourhoods are capped as if its part were the whole cloud. A cloud of one part (any
ordinary surface), parts of fewer than :data:`MIN_PART` points (specks of outliers) and parts
that are curves or flat as a whole (scan lines or rings farther apart than the graph reaches:
the end rings of a sphere scanned in rings, the rings of a LiDAR's ground; also a coin or a
leaf) keep the cloud's caps.
"""

from __future__ import annotations

import numpy as np

from .clump_surfaces import SURFACE_NEAREST, SURFACE_WIDE, bent, scatter_shapes
from .kernels.parts import gap_components
from .tuning import INITIAL_SHARE, SEARCH_WIDTH

#: a neighbour farther than this many times the point's k_initial-th nearest is across a gap
#: (on a surface the 40th nearest lies ~1.6x as far as the 15th; scan lines 20 spacings
#: apart stay one part)
GAP = 3.0
#: parts smaller than this keep the cloud's caps (a speck of outliers is no object)
MIN_PART = 30
#: ... and so do parts flat as a whole, their smallest covariance eigenvalue below this share of
#: the middle one (a ring of a scan: ~1e-3; a torus of tube radius 0.45 of its ring's 0.18,
#: an ellipsoid 1.5 x 1 x 0.75 0.56, a sphere or a box ~1)
PART_THICK = 0.05


def part_sizes(pts, nb, k_min: int) -> np.ndarray | None:
    """(N,) the number of points of the part each point lies on (the cloud's size on parts
    under :data:`MIN_PART` and on curves, :func:`_curves`), or None where one part holds every
    point of an object."""
    idx, dist = nb.take(min(nb.width, SEARCH_WIDTH))
    roots = gap_components(idx, dist, k_min, GAP)
    size = np.bincount(roots)[roots]
    n = len(size)
    size = np.where(size < MIN_PART, n, size)
    if (size == n).all():
        return None
    size[_curves(pts, idx, roots, size < n)] = n
    rows = np.flatnonzero(size < n)
    if len(rows):  # and flat as a whole: a ring of a scan, noisy enough to span planes locally
        ids, group = np.unique(roots[rows], return_inverse=True)
        size[rows[~bent(pts[rows], group.ravel(), len(ids), flat=PART_THICK)[group.ravel()]]] = n
    return None if (size == n).all() else size


def _curves(pts, idx, roots, tested) -> np.ndarray:
    """(N,) bool: the ``tested`` points whose part is a curve, most of its points' nearest
    (:data:`core.clump_surfaces.SURFACE_NEAREST`) along a line (their covariance's middle
    eigenvalue below SURFACE_WIDE of the largest): a scan line or a ring farther from the next
    than the graph reaches is no object (the lines are one surface, :mod:`core.plane_spread`)."""
    rows = np.flatnonzero(tested)
    _, wide = scatter_shapes(pts, idx[rows, :SURFACE_NEAREST])
    line = np.zeros(len(pts))
    line[rows] = ~(wide > np.sqrt(SURFACE_WIDE))  # lambda2 <= SURFACE_WIDE lambda1, or all on one spot
    share = np.bincount(roots, weights=line) / np.maximum(np.bincount(roots), 1)
    return tested & (share[roots] > 0.5)


def initial_levels(levels, k_init: int, sizes, k_min: int):
    """Each point's initial k (``levels`` (N,) or, None, the cloud's ``k_init``) at most 1 /
    INITIAL_SHARE of its part (``sizes``, :func:`part_sizes`), at least ``k_min``; unchanged
    (None stays None) where no part caps it."""
    if sizes is None:
        return levels
    current = np.full(len(sizes), k_init, dtype=np.int64) if levels is None else levels
    capped = np.minimum(current, np.maximum(k_min, sizes // INITIAL_SHARE))
    return levels if (capped == current).all() else capped


def chosen_cap(sizes, ks) -> np.ndarray:
    """(N,) the largest of the candidates ``ks`` within half of each point's part (the
    candidates a cloud of that size allows, :func:`core.scale.candidates`), at least ``ks[0]``."""
    ks = np.asarray(ks, dtype=np.int64)
    at = np.searchsorted(ks, sizes // 2, side="right") - 1
    return ks[np.clip(at, 0, len(ks) - 1)]


def initial_ks(sizes, k_init: int, k_min: int, n: int) -> np.ndarray:
    """(``n``,) each point's initial k: the cloud's ``k_init`` capped by its part (:func:`initial_levels`)."""
    levels = initial_levels(None, k_init, sizes, k_min)
    return np.full(n, k_init) if levels is None else levels


def choose_within(choose, ks, sizes, usable):
    """``choose(sizes, usable)`` -> (k, on_jet, quiet, jets, degree) (:func:`core.scale.choose_model`)
    run on each group of the ``usable`` (N,) points whose parts allow the same candidates
    (:func:`chosen_cap`) with only those, the answers put together; one run on ``ks`` without parts."""
    top = None if sizes is None else chosen_cap(sizes, ks)
    if top is None or not usable.any():
        return choose(ks, usable)
    out = None
    for cap in np.unique(top[usable]):
        group = usable & (top == cap)
        got = choose(tuple(k for k in ks if k <= cap), group)
        out = got if out is None else _merged(out, got, group)
    return out


def _merged(old, new, group):
    """The answers of :func:`choose_within`: ``new`` at the ``group`` (N,) points, ``old`` elsewhere."""
    def pick(a, b):
        return np.where(group.reshape(-1, *([1] * (a.ndim - 1))), b, a)

    k, on_jet, quiet, degree = (pick(a, b) for a, b in zip(old[:3] + old[4:], new[:3] + new[4:]))
    ja, jb = old[3], new[3]
    if ja is None or jb is None:  # no jets on one side: the other's frames, not valid there
        jets = ja if jb is None else jb
        if jets is not None:
            jets = (*jets[:-1], jets[-1] & (group if ja is None else ~group))
    else:
        jets = tuple(pick(a, b) for a, b in zip(ja, jb))
    return k, on_jet, quiet, jets, degree


def capped(sizes, ks, kc, on_jet, fit_k):
    """(on_jet, fit_k) with no fit wider than its part allows (:func:`chosen_cap`): a jet
    chosen wider is left to NR (unchanged without ``sizes``)."""
    if sizes is None:
        return on_jet, fit_k
    top = chosen_cap(sizes, ks)
    return on_jet & (kc <= top), np.minimum(fit_k, top)


def groups(sizes, k_init: int, ks):
    """Yield ``(members (N,) bool, initial k, candidates)``: the points whose parts allow the
    same initial k (:func:`initial_levels`, at least ``ks[0]``) and candidates (:func:`chosen_cap`);
    without parts every point, ``k_init`` and ``ks``."""
    if sizes is None:
        yield True, k_init, ks
        return
    level = initial_ks(sizes, k_init, ks[0], len(sizes))
    top = chosen_cap(sizes, ks)
    for k, cap in sorted(set(zip(level.tolist(), top.tolist()))):
        yield (level == k) & (top == cap), int(k), tuple(c for c in ks if c <= cap)
