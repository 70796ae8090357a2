"""Sparse centres of k="auto"'s wide fits: fit at some points, evaluate the fit at those around.

Where noise makes k="auto" choose a wide neighbourhood (k = 320 on a noisy torus), the
fits of neighbouring points are fits of nearly the same neighbours: two points a spacing
apart share ~95 % of 320 neighbours, and their fitted polynomials describe one normal
field. A cubic fit at a centre a describes the normal field over its whole disc, so the
normal and its derivatives at a point p a spacing or two away are the fitted polynomial's
value and slopes at p's offset (u, v) (eqs. 23-24 read at (u, v) instead of (0, 0)):

    X(u, v), Y(u, v)                                   the normal at p, in a's frame
    W = [[dX/du, dX/dv], [dY/du, dY/dv]]               dn at p in the basis (r_u, r_v)

(the graph parametrisation of :func:`core.frame.darboux_frame` holds at every (u, v),
not only at the centre), with the symmetry constraint of eq. 22 projected at p. So
about ``ANCHOR_ROWS / k`` of the points with such a k are *anchors* whose fits are
computed, and each other point *follows* the ``ANCHOR_BLEND`` nearest anchors among its
``ANCHOR_REACH`` nearest that chose the same k, their fits read at its offset and
averaged (:mod:`core.anchor_blend`): the fits cost what fits of ``ANCHOR_ROWS``
neighbours at every point would, over the same wide disc. Measured (2026-12-05, README
"Wide fits at sparse anchors"): the nearest anchor alone, 1 in 8 fitted (ANCHOR_ROWS 40):
hold-out race 8/84 cells lost, 3 over 1.10x; 4 anchors averaged: 6/84; ANCHOR_ROWS 80:
4/84, 2 over (fitting every point: 3/84, 2 over); noisy clouds' mean |H| error +3 to +5 % against a
fit at every point where the pass rule decides alike (+22 % where it undoes one pass more),
the default 10.8 -> ~6 s on a noisy 100k torus.

Which points are anchors is drawn by a hash of their distances to their nearest
(:func:`priority`), so it depends neither on the order of the points, the thread count
or the tile that holds them nor on the cloud's pose or scale; a point with no anchor near,
or where an anchor's fit fails, fits itself. An integer k never uses anchors.

The choice of k is shared the same way (:func:`shared_scale`, 2026-12-06): with noise the
jet rule of :mod:`core.scale` grows to the largest size nearly everywhere, so it runs at
the anchors of that size, and the other noisy points (and robust mode's suspects, which
sit the rule out) take their nearest anchor's size; a follower's own wide neighbours are
searched only if it fits after all (:func:`core.wide_rows.rows_at_least`). Noisy
100k torus 7.7 -> 5.2 s, races unchanged (README, "Wide fits at sparse anchors").
"""

from __future__ import annotations

import numpy as np

from .kernels.algebra import MAX_TERMS
from .kernels.anchors import anchors_among, first_anchors, priorities
from .tuning import ANCHOR_BLEND, ANCHOR_REACH, ANCHOR_ROWS

#: the hash's seed, and how many nearest distances it reads (:func:`priority`)
_SALT, RATIOS = 0x5A17C0DE, 8


def per_anchor(k):
    """Points per anchor at fits of ``k`` neighbours (scalar or array): round(k / ANCHOR_ROWS),
    the anchor and the m = that - 1 nearest it beats (:func:`assign`); shared from 2."""
    return np.rint(np.asarray(k) / ANCHOR_ROWS)


def shares_scale(plan) -> bool:
    """Whether the scale rule of ``plan`` runs at anchors, read by the other noisy points (:func:`shared_scale`):
    k="auto" with candidates of at least 1.5 x ANCHOR_ROWS (:func:`per_anchor` >= 2). Independent of
    the fit's options, so a cached choice of scale holds for any of them."""
    return bool(plan.auto and per_anchor(plan.k_search) >= 2)


def in_use(plan) -> bool:
    """Whether the fits of ``plan`` may read anchors: :func:`shares_scale`, and eq. 22
    projected (a follower's W is projected; "exact" solves at a centre)."""
    return shares_scale(plan) and plan.options.get("constraint") != "exact"


def assign(pts, near, kc, eligible, prio=None, lead=None) -> np.ndarray | None:
    """(N, ANCHOR_BLEND) int64: the anchors whose fits each point reads, nearest first and
    -1 past the last (column 0 is the point itself where it fits its own), or None when
    every point fits its own. ``near`` (N, >= ANCHOR_REACH + 1): each point's nearest
    (itself first) in the order its fit reads them; ``kc`` (N,) the k each point fits on;
    ``eligible`` (N,) bool: the points that may be anchors or follow them (fitted in every
    pass: not an outlier, a normal, a neighbourhood that spans). A point is an anchor when
    its :func:`priority` is above those of its m = round(k / ANCHOR_ROWS) - 1 nearest
    (about 1 in m + 1 points); ``prio``: :func:`priority`'s answer, if computed already;
    ``lead`` (N,) bool, optional: the eligible points that may be anchors (the others only follow)."""
    kc = np.ascontiguousarray(kc, dtype=np.int64)
    reach = min(ANCHOR_REACH, near.shape[1] - 1)
    m = np.clip(per_anchor(kc).astype(np.int64) - 1, 0, reach)
    prio = priority(pts, near) if prio is None else prio
    anchors = np.empty(len(kc), dtype=bool)
    anchors_among(near, prio, m, np.asarray(eligible if lead is None else eligible & lead, dtype=bool), anchors)
    rows = np.flatnonzero(eligible & ~anchors)
    if not len(rows):
        return None
    picked = np.empty((len(rows), ANCHOR_BLEND), dtype=np.int64)  # the first anchors of each row, in order
    first_anchors(near, rows, anchors, kc, reach, picked)
    found = picked[:, 0] >= 0
    anchor = np.full((len(kc), ANCHOR_BLEND), -1, dtype=np.int64)
    anchor[:, 0] = np.arange(len(kc))
    anchor[rows[found]] = picked[found]
    return anchor


def shared_scale(pts, near, noisy, k_top, prio=None, sat_out=None):
    """``(follow, lead)`` (F,) int64: the ``noisy`` points (N,) bool that take the scale
    chosen at an anchor, and that anchor (the nearest among their ``ANCHOR_REACH``
    nearest); anchors drawn as for fits of ``k_top`` neighbours (:func:`assign`). With
    noise the jets of the scale rule grow to ``k_top`` nearly everywhere, and the rule runs
    at the anchors alone: a follower would fit on nearly the same wide disc. ``prio``: as
    :func:`assign`'s; ``sat_out`` (N,) bool, optional: points that sit out the rule (robust
    mode's suspects) and follow an anchor too, never one themselves."""
    eligible = noisy if sat_out is None else noisy | sat_out
    anchor = assign(pts, near, np.full(len(pts), k_top, dtype=np.int64), eligible, prio, noisy)
    if anchor is None:
        return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
    follow = np.flatnonzero(followers(anchor))
    return follow, anchor[follow, 0]


def priority(pts, near) -> np.ndarray:
    """(N,) uint64 > 0: a hash of each point's distances to its ``RATIOS`` nearest (``near``
    (N, >= RATIOS + 1), itself first), sorted and divided by the largest, rounded to 2^-20
    (:func:`core.kernels.anchors.priorities`): a draw that depends on neither the order of
    the points, the thread count or the tile that holds them, nor the pose or scale of the
    cloud (a rotation moves the ratios by ~1e-16, far from the rounding's half-steps), so a
    turned cloud reads the same anchors. Points with equal ratios (an exact grid's) tie, and
    a tie is no anchor: such points fit their own."""
    prio = np.empty(len(pts), dtype=np.uint64)
    priorities(np.ascontiguousarray(pts, dtype=np.float64), near, RATIOS, _SALT, prio)
    return prio


def followers(anchor) -> np.ndarray:
    """(N,) bool: the points that read anchors' fits."""
    return anchor[:, 0] != np.arange(len(anchor))


def split(anchor, usable, kept: "Kept"):
    """``(fit_at, follow)`` (N,) bool: the points to fit (the usable ones that fit their
    own, and the anchors of the usable ones that follow them), less those ``kept`` has
    fitted in this pass already, and the usable followers."""
    follow = usable & followers(anchor)
    fit_at = usable & ~follow
    read = anchor[follow]
    fit_at[read[read >= 0]] = True
    fit_at[kept.points[kept.fitted]] = False
    return fit_at, follow


class Kept:
    """One pass's fits at the anchors (their polynomials, frames, length units and
    diagnostics), filled chunk by chunk as they are fitted (:meth:`take`): the rule's
    sample and the rest of a pass (:func:`core.refinement.fit_passes`) share them."""

    def __init__(self, anchor):
        n = len(anchor)
        read = anchor[followers(anchor)]
        some = np.zeros(n, dtype=bool)
        some[read[read >= 0]] = True
        self.points = np.flatnonzero(some)  # the anchors some point follows (np.unique sorted them: 0.36 s at 1M)
        m = len(self.points)
        self.row = np.full(n, -1, dtype=np.int64)
        self.row[self.points] = np.arange(m)
        self.coef, self.frame = np.zeros((m, 2, MAX_TERMS)), np.zeros((m, 3, 3))
        self.h, self.ok, self.fitted = np.ones(m), np.zeros(m, dtype=bool), np.zeros(m, dtype=bool)
        self.rms, self.spread, self.degree = np.full(m, np.nan), np.full(m, np.nan), np.zeros(m, dtype=np.int8)

    def take(self, chunk, diag, good) -> None:
        """Keep the chunk's fits at the anchors it holds (``good``: fit and frame usable)."""
        rows = self.row[chunk.centres]
        at = np.flatnonzero(rows >= 0)
        r = rows[at]
        self.coef[r] = diag["coef"][at]
        self.frame[r, 0], self.frame[r, 1], self.frame[r, 2] = chunk.t1[at], chunk.t2[at], chunk.z[at]
        self.h[r], self.ok[r], self.fitted[r] = chunk.h[at], good[at], True
        self.rms[r], self.spread[r], self.degree[r] = diag["rms"][at], diag["spread"][at], diag["degree"][at]
