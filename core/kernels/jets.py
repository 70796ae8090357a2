"""Compiled loops of the jet rule of the automatic scale (:mod:`core.scale`): nested
osculating 3-jets of the positions.

One pass over each centre's neighbours, nearest first: the least-squares sums of the
cubic height field w = sum c_ab u^a v^b (10 terms, lengths in units of the centre's
``h``) grow neighbour by neighbour and are solved at each candidate size ks[c]. The
centres travel as a :class:`~core.kernels.nf.Frames` record (its ``kc`` is unused), the
rule's settings as a :class:`~core.kernels.scale.ScaleRule` (``gamma``, ``rcond`` and
the fold test; its ``degree`` is unused: the intervals are the cubic's). Where the data are
quiet the intervals also run the degree rule (:mod:`core.kernels.jet_degree`) on their own
sums: one pass over the neighbours, not two (the degree rule alone cost 0.40 CPU s of a
100k torus, one thread; fused, the intervals went 0.29 -> 0.59 s; the same bits).

The helpers called once per size (:func:`_grows`, :func:`_meet`, :func:`_ici_point` and
:mod:`~core.kernels.jet_degree`'s ``grow``, ``stash_cubic``, ``_fit_degree``, ``_narrow``) are
inlined by numba and take whole arrays and row indices only. The loop over centres
(:func:`_ici_points`) and the helpers it calls are compiled without numba's reference counting
(:data:`~core.kernels._base.LEAF`; the block allocates their scratch): a call otherwise
increments and decrements the count of each array it receives, an atomic instruction each, and
so does each record field or row view taken in the loop (they cost ~13 % of it after the
inlining; see docs/performance-log.md). The scratch is unpacked once a point, the degree rule's
packed into one float table and one bool array (:class:`~core.kernels.jet_degree.DegreeScratch`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import BLOCK, LEAF, OPTS
from .algebra import chol_solve, cholesky
from .jet_degree import KEEP, DegreeRule, degree_scratch, grow, jet_degrees, start_chain, stash_cubic, walk
from .jet_sums import P3, P5, _offsets, ring_sums
from .scale import _folded, _local_reference

__all__ = ["P3", "DegreeRule", "jet_residuals", "jet_ici", "jet_degrees"]


@njit(**OPTS)
def _rss(b, x, acc):
    rss = acc[0]
    for a in range(P3):
        rss -= x[a] * b[a]
    return max(rss, 0.0)


@njit(**OPTS, parallel=True)
def jet_residuals(f, ks, rcond, rss):
    """rss[r, c] = residual sum of squares (units of h^2) of the cubic jet on ks[c]
    neighbours (those with a finite normal), NaN where the fit is rank deficient."""
    m = len(f.centres)
    for blk in prange((m + BLOCK - 1) // BLOCK):
        _residuals_block(f, ks, rcond, rss, blk * BLOCK, min(m, (blk + 1) * BLOCK))


@njit(**OPTS)
def _residuals_block(f, ks, rcond, rss, start, stop):
    kmax = ks[-1]
    uvw = np.empty((3, kmax))
    b, x, d, acc = np.empty(P3), np.empty(P3), np.empty(P3), np.empty(1)
    G, L = np.empty((P3, P3)), np.empty((P3, P3))
    pu, pv, pw, R = np.empty(kmax), np.empty(kmax), np.empty(kmax), np.empty((P3, kmax))
    for r in range(start, stop):
        _offsets(f, r, 0, kmax, uvw)
        G[:, :] = 0.0
        b[:] = 0.0
        acc[0] = 0.0
        prev = 0
        for c in range(len(ks)):
            ring_sums(uvw, prev, ks[c], G, b, acc, pu, pv, pw, R)
            prev = ks[c]
            if cholesky(G, P3, rcond, d, L):
                chol_solve(L, d, P3, b, x)
                rss[r, c] = _rss(b, x, acc)
            else:
                rss[r, c] = math.nan


@njit(**LEAF)
def _hessian_sd(L, d, x3, sigma2, bounds):
    """bounds[3] = the standard deviations of (2 c3, c4, 2 c5) = (f_uu, f_uv, f_vv) at noise sigma2, from
    (G^-1)_ii, i = 3, 4, 5, with the factor of :func:`~core.kernels.algebra.cholesky`: entry i
    of ``chol_solve(L, d, p, e_i, x)``, bit for bit, without its dead work. Its forward pass
    leaves x[a] = +0.0 for a < i (0.0 / d[a], less exact zeros: L is finite once the
    factor succeeded), and subtracting L[a, e] * 0.0 from +0.0 or from 1 / d[i] changes
    nothing, so that pass starts at i; its backward pass reaches x[i] from x[i..p-1] alone.
    The three solves (rows of the scratch x3) are interleaved, each the same operations in
    the same order: their chains of divisions overlap (0.42 -> 0.16 us per size)."""
    for a in range(3, P3):
        for t in range(3):
            i = 3 + t
            if a < i:
                continue
            s = 1.0 / d[a] if a == i else 0.0
            for c in range(i, a):
                s -= L[a, c] * x3[t, c]
            x3[t, a] = s / L[a, a]
    for a in range(P3 - 1, 2, -1):
        for t in range(3):
            if a < 3 + t:
                continue
            s = x3[t, a]
            for c in range(a + 1, P3):
                s -= L[c, a] * x3[t, c]
            x3[t, a] = s / L[a, a]
    for t in range(3):
        bounds[3, t] = (2.0 if t != 1 else 1.0) * math.sqrt(max(x3[t, 3 + t] / d[3 + t], 0.0) * sigma2)


@njit(**OPTS, parallel=True)
def jet_ici(f, ks, sigma2, rule, deg, chosen, coef, walked):
    """Intersection of confidence intervals of the jet's Hessian (f_uu, f_uv, f_vv), and
    where the data are quiet the degree rule on the same sums.

    ``sigma2[r]``: the noise variance of the heights (units of h^2), known from outside
    (:func:`core.scale.noise_variance`), not from each fit's own residual, so a bias shows
    as a jump of the estimates rather than as a wider interval. ``chosen[r]`` gets the
    index into ``ks`` of the largest size whose interval (``rule.gamma`` deviations) still
    meets all smaller ones, ``coef[r]`` that fit's 10 coefficients; chosen = -1 if no fit
    was possible. k also stops where a ring of neighbours folds over and the next one too
    (as :func:`core.kernels.scale._fold_limit`, looking one ring ahead only as the size grows).
    Where ``deg.quiet[r]`` and the cubic stopped within ``deg.reach`` neighbours,
    ``walked[r]`` gets the answer of :func:`core.kernels.jet_degree.jet_degrees` for that
    cubic (a model index, len(deg.kd) for the cubic, -1 none; -1 also where it does not
    run; -2 where the richer models still agree at ``ks[-1]`` short of ``deg.kmax``: run it again
    on more neighbours; past the first only where the cubic reached its size, as there) and
    ``coef[r, :6]`` the chosen richer model's: the sums are of the richest degree up to its size,
    the cubic's their leading block (:func:`core.kernels.jet_degree.grow`).
    """
    m = len(f.centres)
    for blk in prange((m + BLOCK - 1) // BLOCK):
        _ici_block(f, ks, sigma2, rule, deg, chosen, coef, walked, blk * BLOCK, min(m, (blk + 1) * BLOCK))


@njit(**OPTS)
def _ici_block(f, ks, sigma2, rule, deg, chosen, coef, walked, start, stop):
    """:func:`jet_ici` for centres start..stop-1, scratch arrays allocated once, whole arrays
    all (rows of them by index)."""
    kmax = ks[-1]
    uvw = np.empty((3, kmax))
    sums = (np.empty(P5), np.empty((P5, P5)), np.empty(P5), np.empty(2))  # row, G, b, (sum w^2, count)
    bounds, ref = np.empty((4, 3)), np.empty(8)  # the intervals' lo, hi, est, sd; _local_reference's
    cubic = (np.empty((P3, P3)), np.empty(P3), np.empty(P3), np.empty((3, P3)), bounds, ref)  # L, d, x, x3
    ring = (np.empty(kmax), np.empty(kmax), np.empty(kmax), np.empty((P3, kmax)))  # u, v, w packed, monomials
    ds = degree_scratch(len(deg.kd), len(ks))
    _ici_points(f, ks, sigma2, rule, deg, (chosen, coef, walked), start, stop, (uvw, sums, cubic, ring, ds))


@njit(**LEAF)
def _ici_points(f, ks, sigma2, rule, deg, out, start, stop, scratch):
    """:func:`_ici_block`'s loop over its centres; ``out`` = (chosen, coef, walked), ``scratch`` =
    (uvw, sums, cubic, ring, ds) as the block allocated them. Compiled without reference counting,
    as are the helpers it calls (:data:`~core.kernels._base.LEAF`): it allocates nothing."""
    chosen, coef, walked = out
    uvw, sums, cubic, ring, ds = scratch
    bounds, ref = cubic[4], cubic[5]
    table, flags = ds.table, ds.flags
    for r in range(start, stop):
        _local_reference(f.points, f.normals, f.idx, r, ks[0], f.z, rule.fold_cos, ref)
        _start_point(sums, deg.quiet[r], deg.dmax, bounds, table, flags)
        chosen[r], prev = _ici_point(f, ks, sigma2[r], rule, deg, r, uvw, sums, cubic, ring, ds, coef)
        walked[r] = -1
        if chosen[r] < 0:
            coef[r, :] = math.nan
        elif deg.quiet[r] and len(deg.kd) > 0 and ks[chosen[r]] <= deg.reach:
            top = min(deg.kmax, ks[-1])  # the neighbours held
            alive = flags[len(flags) - 1]
            if prev < top and alive and ks[chosen[r]] >= deg.kd[deg.by_k[0]]:  # see jet_degree.jet_degrees
                _offsets(f, r, prev, top, uvw)
                grow(uvw, prev, top, deg, sums, sigma2[r], rule.rcond, ds.L, ds.d, ds.x, table, flags)
            alive = flags[len(flags) - 1]
            final = top == deg.kmax or not alive or ks[chosen[r]] < deg.kd[deg.by_k[0]]
            walked[r] = walk(table, flags, deg, chosen[r]) if final else -2
            if 0 <= walked[r] < len(deg.kd):
                for a in range(6):
                    coef[r, a] = table[walked[r], KEEP + a]


@njit(**OPTS, inline="always")
def _start_point(sums, quiet, dmax, bounds, table, flags):
    """Empty sums (of degree dmax where ``quiet``, else the cubic's), intervals and models."""
    row, G, b, acc = sums
    p = (dmax + 1) * (dmax + 2) // 2 if quiet else P3
    G[:p, :p] = 0.0
    b[:p] = 0.0
    acc[:] = 0.0
    bounds[0, :] = -math.inf
    bounds[1, :] = math.inf
    start_chain(table, flags)


@njit(**OPTS, inline="always")
def _grows(points, normals, idx, ks, rule, r, c, fold_here, ref):
    """(stop, fold_next): a ring that folds, followed by another (or the last), ends the growth."""
    fold_next = c + 1 >= len(ks) or _folded(points, normals, idx, r, ks[c], ks[c + 1], rule, ref)
    if c == 1:
        fold_here = _folded(points, normals, idx, r, ks[0], ks[1], rule, ref)
    return fold_here and fold_next, fold_next


@njit(**OPTS, inline="always")
def _ici_point(f, ks, sigma2, rule, deg, r, uvw, sums, cubic, ring, ds, coef):
    """(the chosen index for centre r, -1 if none; the neighbours summed); its coefficients in
    coef[r]. ``sums`` = (row, G, b, acc), ``cubic`` = (L, d, x, x3, bounds, ref) the cubic's
    factor, solution, intervals and fold reference, ``ring`` = the rings' scratch of
    :func:`~core.kernels.jet_sums.ring_sums`, ``ds`` the degree rule's :class:`DegreeScratch`;
    all unpacked here, once a point, and handed on whole."""
    row, G, b, acc = sums
    L, d, x, x3, bounds, ref = cubic
    pu, pv, pw, R = ring
    L5, d5, x5, table, flags = ds
    points, normals, idx = f.points, f.normals, f.idx
    quiet = deg.quiet[r]
    n_models = len(deg.kd)
    chosen = -1
    prev = 0
    fold_here = False
    for c in range(len(ks)):
        if c > 0:
            stop, fold_here = _grows(points, normals, idx, ks, rule, r, c, fold_here, ref)
            if stop:
                break
        _offsets(f, r, prev, ks[c], uvw)
        if quiet:
            grow(uvw, prev, ks[c], deg, sums, sigma2, rule.rcond, L5, d5, x5, table, flags)
        else:
            ring_sums(uvw, prev, ks[c], G, b, acc, pu, pv, pw, R)
        prev = ks[c]
        if not cholesky(G, P3, rule.rcond, d, L):
            if chosen < 0:
                continue
            break
        chol_solve(L, d, P3, b, x)
        if quiet and ks[c] <= deg.reach:
            stash_cubic(L, d, x, b, acc, sigma2, n_models + c, table, flags)
        _hessian_sd(L, d, x3, sigma2, bounds)
        if not _meet(bounds, x, rule.gamma) and chosen >= 0:
            break
        chosen = c
        for a in range(P3):
            coef[r, a] = x[a]
    return chosen, prev


@njit(**OPTS, inline="always")
def _meet(bounds, x, gamma):
    """Narrow the intervals (bounds rows lo, hi) by this size's estimate (2 x3, x4, 2 x5, kept in
    the row est) +- gamma sd (row sd); True if they still meet."""
    bounds[2, 0], bounds[2, 1], bounds[2, 2] = 2.0 * x[3], x[4], 2.0 * x[5]
    meet = True
    for t in range(3):
        bounds[0, t] = max(bounds[0, t], bounds[2, t] - gamma * bounds[3, t])
        bounds[1, t] = min(bounds[1, t], bounds[2, t] + gamma * bounds[3, t])
        meet = meet and bounds[0, t] <= bounds[1, t]
    return meet
