"""The choice of k per point (see :mod:`core.scale`): intersection of confidence
intervals over nested neighbourhoods, stopped where a ring of neighbours folds over."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ._base import BLOCK, LEAF, OPTS
from .lstsq import CX, CY, accumulate, fit_scratch, monomials, reset, slope_variances, solve_determined
from .nf import gather


class ScaleRule(NamedTuple):
    """The choice rule's settings (values and reasons in :mod:`core.tuning`): the
    ``degree`` of the normal fit, the intervals' width ``gamma`` in standard deviations,
    the singularity threshold ``rcond``, and the fold test: ``fold_fraction`` (share of a
    ring allowed off the graph), ``fold_cos`` (a normal turned beyond this cosine is off
    it), ``fold_noise`` (heights within this many noise heights are not a fold) and
    ``fold_min_bad`` (fewest off-graph neighbours that make a fold); ``pivot``: a normal
    fit of degree 2-3 whose Cholesky pivots do not all exceed it falls a degree
    (:func:`~core.kernels.lstsq.solve_determined`)."""

    degree: int
    gamma: float
    rcond: float
    fold_fraction: float
    fold_cos: float
    fold_noise: float
    fold_min_bad: int
    pivot: float


@njit(**LEAF)
def _local_reference(points, normals, idx, r, n, z, fold_cos, ref):
    """What a fold of centre r is judged against, from its neighbours 0..n-1 (the
    smallest neighbourhood): ``ref`` gets their centroid (0:3) and mean normal (3:6,
    sign-aligned with z), which unlike the centre's own point and normal are not thrown
    far off by noise, the RMS height of the neighbours over that plane (6: the scale of
    the position noise, plus a little curvature) and the share of them whose normals
    turn more than ``fold_cos`` from the mean (7: what the normal noise alone does)."""
    c0, c1, c2 = z[r, 0], z[r, 1], z[r, 2]
    ref[:] = 0.0
    seen = 0
    for j in range(n):
        q = idx[r, j]
        nx, ny, nz = normals[q, 0], normals[q, 1], normals[q, 2]
        if not math.isfinite(nx):
            continue
        sgn = 1.0 if nx * c0 + ny * c1 + nz * c2 >= 0.0 else -1.0
        for a in range(3):
            ref[a] += points[q, a]
            ref[3 + a] += sgn * normals[q, a]
        seen += 1
    norm = math.sqrt(ref[3] ** 2 + ref[4] ** 2 + ref[5] ** 2)
    if seen == 0 or norm == 0.0:
        for a in range(3):
            ref[a] = points[idx[r, 0], a]
        ref[3], ref[4], ref[5] = c0, c1, c2
        ref[6] = ref[7] = 0.0
        return
    for a in range(3):
        ref[a] /= seen
        ref[3 + a] /= norm
    height2 = 0.0
    turned = 0
    for j in range(n):
        q = idx[r, j]
        if not math.isfinite(normals[q, 0]):
            continue
        w = 0.0
        facing = 0.0
        for a in range(3):
            w += (points[q, a] - ref[a]) * ref[3 + a]
            facing += normals[q, a] * ref[3 + a]
        height2 += w * w
        if facing < fold_cos:
            turned += 1
    ref[6] = math.sqrt(height2 / seen)
    ref[7] = turned / seen


@njit(**LEAF)
def _folded(points, normals, idx, r, j0, j1, rule, ref):
    """Whether the ring of neighbours j0..j1-1 of centre r has left the graph of a
    function over the local plane ``ref`` (see :func:`_local_reference`): more of it
    than ``fold_fraction`` (plus the share of the smallest neighbourhood) seen more than 45
    degrees above or below the plane (beyond ``fold_noise`` x the noise height), or with
    normals turned more than 70 degrees: the far side of a thin part, another sheet, a
    crease. No model of the normal field fits there, and the residual variance such a
    ring adds would hide the bias from the ICI test. Judged against the neighbourhood,
    not the centre alone, so a noisy centre is not taken for a fold."""
    margin = rule.fold_noise * ref[6]
    bad = 0
    seen = 0
    for j in range(j0, j1):
        q = idx[r, j]
        if not math.isfinite(normals[q, 0]):  # no normal (or a known outlier): not counted
            continue
        seen += 1
        w = 0.0
        d2 = 0.0
        facing = 0.0
        for a in range(3):
            d = points[q, a] - ref[a]
            w += d * ref[3 + a]
            d2 += d * d
            facing += normals[q, a] * ref[3 + a]
        lift = max(abs(w) - margin, 0.0)
        if 2.0 * lift * lift > d2 or facing < rule.fold_cos:
            bad += 1
    return bad >= rule.fold_min_bad and bad > (rule.fold_fraction + ref[7]) * seen


@njit(**OPTS)
def _fold_limit(points, normals, idx, r, ks, rule, ref):
    """How many of the candidate sizes ``ks`` stay on the graph: the first ring that folds
    ends them, if the next ring folds too (a fold persists as the neighbourhood grows;
    a ring that noise alone makes look folded is seldom followed by another). The last
    ring has no ring beyond it and ends them on its own."""
    before = False
    for c in range(1, len(ks)):
        folded = _folded(points, normals, idx, r, ks[c - 1], ks[c], rule, ref)
        if before and folded:
            return c - 1
        before = folded
    return len(ks) - 1 if before else len(ks)


@njit(**OPTS, parallel=True)
def fold_limits(f, ks, rule, out):
    """``out[r]``: how many of the sizes ``ks`` stay on the graph at centre r of ``f``
    (:func:`_fold_limit`), for a size chosen by another rule (the noise floor of NR's fits)."""
    m = len(f.centres)
    for blk in prange((m + BLOCK - 1) // BLOCK):
        ref = np.empty(8)
        for r in range(blk * BLOCK, min(m, (blk + 1) * BLOCK)):
            _local_reference(f.points, f.normals, f.idx, r, ks[0], f.z, rule.fold_cos, ref)
            out[r] = _fold_limit(f.points, f.normals, f.idx, r, ks, rule, ref)


@njit(**OPTS, parallel=True)
def choose_scales(f, ks, rule, chosen):
    """Intersection of confidence intervals over nested neighbourhoods (see core.scale).

    One pass over each centre's ks[-1] neighbours (``f`` a
    :class:`~core.kernels.nf.Frames`, ``rule`` a :class:`ScaleRule`): the NF sums
    (polynomial of ``rule.degree``) grow neighbour by neighbour and are solved at each
    candidate size ks[c] (uniform weights, no constraint, lengths in units of h = the
    distance to the largest neighbourhood). ``chosen`` gets the largest k whose interval
    [W - gamma s, W + gamma s] (gamma = ``rule.gamma``) still meets all previous ones.
    """
    m = len(f.centres)
    n_blocks = (m + BLOCK - 1) // BLOCK
    for blk in prange(n_blocks):
        _choose_block(f, ks, rule, chosen, blk * BLOCK, min(m, (blk + 1) * BLOCK))


@njit(**OPTS)
def _choose_block(f, ks, rule, chosen, start, stop):
    """:func:`choose_scales` for centres start..stop-1, with scratch arrays allocated once
    (a per-point allocation would cost more than the fits)."""
    kmax = ks[-1]
    s = fit_scratch(kmax)
    bounds = np.empty((2, 3))
    ref = np.empty(8)
    for r in range(start, stop):
        gather(f, r, r, kmax, 0, 1.0, s)
        monomials(s.u, s.v, kmax, rule.degree, s.R)
        reset(rule.degree, s.vec, s.G, s.acc)
        _local_reference(f.points, f.normals, f.idx, r, ks[0], f.z, rule.fold_cos, ref)
        stop_c = _fold_limit(f.points, f.normals, f.idx, r, ks, rule, ref)
        chosen[r] = _ici(s, ks, stop_c, rule, bounds)


@njit(**OPTS)
def _ici(s, ks, stop, rule, bounds):
    """The largest of ks[:stop] whose confidence interval of (W11, (W12 + W21)/2, W22)
    meets those of all smaller sizes (``bounds``: scratch for the running intersection).
    Each size fits the highest degree up to ``rule.degree`` that it determines."""
    vec, acc, degree, gamma = s.vec, s.acc, rule.degree, rule.gamma
    lo, hi = bounds[0], bounds[1]
    lo[:] = -math.inf
    hi[:] = math.inf
    pick = ks[0]
    prev = 0
    for c in range(stop):
        accumulate(s.R, s.X, s.Y, s.base, prev, ks[c], degree, vec, s.G, acc, s.WR)
        prev = ks[c]
        fitted = solve_determined(degree, rule.rcond, rule.pivot, vec, s.G, s.L, acc, True)
        if fitted == 0:
            if c == 0:
                continue
            break
        v0, v1, v2 = slope_variances(fitted, ks[c], vec, acc)
        est0 = vec[CX, 1]
        est1 = 0.5 * (vec[CX, 2] + vec[CY, 1])
        est2 = vec[CY, 2]
        lo[0] = max(lo[0], est0 - gamma * math.sqrt(v0))
        hi[0] = min(hi[0], est0 + gamma * math.sqrt(v0))
        lo[1] = max(lo[1], est1 - gamma * math.sqrt(v1))
        hi[1] = min(hi[1], est1 + gamma * math.sqrt(v1))
        lo[2] = max(lo[2], est2 - gamma * math.sqrt(v2))
        hi[2] = min(hi[2], est2 + gamma * math.sqrt(v2))
        if lo[0] > hi[0] or lo[1] > hi[1] or lo[2] > hi[2]:
            break
        pick = ks[c]
    return pick
