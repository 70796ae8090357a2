"""Compiled loops of the jet rule of the automatic scale (:mod:`core.scale`): nested
osculating 3-jets of the positions.

One pass over each centre's neighbours, nearest first: the least-squares sums of the
cubic height field w = sum c_ab u^a v^b (10 terms, lengths in units of the centre's
``h``) grow neighbour by neighbour and are solved at each candidate size ks[c]. The
centres travel as a :class:`~core.kernels.nf.Frames` record (its ``kc`` is unused), the
rule's settings as a :class:`~core.kernels.scale.ScaleRule` (``gamma``, ``rcond`` and
the fold test; its ``degree`` is unused: the jets are cubic).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS
from .algebra import chol_solve, cholesky, poly_row
from .scale import _folded, _local_reference

#: terms of the cubic jet
P3 = 10


@njit(**OPTS)
def _offsets(f, r, j0, j1, uvw):
    """Neighbours j0 <= j < j1 of centre r in its frame, lengths in units of f.h[r]; the
    height uvw[2, j] is NaN for a neighbour without a normal (a known outlier), which the
    sums leave out."""
    i = f.centres[r]
    for j in range(j0, j1):
        q = f.idx[r, j]
        if not math.isfinite(f.normals[q, 0]):
            uvw[2, j] = math.nan
            continue
        dx = (f.points[q, 0] - f.points[i, 0]) / f.h[r]
        dy = (f.points[q, 1] - f.points[i, 1]) / f.h[r]
        dz = (f.points[q, 2] - f.points[i, 2]) / f.h[r]
        uvw[0, j] = dx * f.t1[r, 0] + dy * f.t1[r, 1] + dz * f.t1[r, 2]
        uvw[1, j] = dx * f.t2[r, 0] + dy * f.t2[r, 1] + dz * f.t2[r, 2]
        uvw[2, j] = dx * f.z[r, 0] + dy * f.z[r, 1] + dz * f.z[r, 2]


@njit(**OPTS)
def _add(uvw, j0, j1, row, G, b, acc):
    """Sums of neighbours j0 <= j < j1 into G (lower triangle), b and acc[0] = sum w^2."""
    for j in range(j0, j1):
        w = uvw[2, j]
        if not math.isfinite(w):
            continue
        poly_row(uvw[0, j], uvw[1, j], 3, row)
        acc[0] += w * w
        for a in range(P3):
            b[a] += row[a] * w
            for c in range(a + 1):
                G[a, c] += row[a] * row[c]


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
    row, b, x, d, acc = np.empty(P3), np.empty(P3), np.empty(P3), np.empty(P3), np.empty(1)
    G, L = np.empty((P3, P3)), np.empty((P3, P3))
    for r in range(start, stop):
        _offsets(f, r, 0, kmax, uvw)
        G[:, :] = 0.0
        b[:] = 0.0
        acc[0] = 0.0
        prev = 0
        for c in range(len(ks)):
            _add(uvw, prev, ks[c], row, G, b, acc)
            prev = ks[c]
            if cholesky(G, P3, rcond, d, L):
                chol_solve(L, d, P3, b, x)
                rss[r, c] = _rss(b, x, acc)
            else:
                rss[r, c] = math.nan


@njit(**OPTS)
def _hessian_sd(L, d, e, x, sigma2, out):
    """Standard deviations of (2 c3, c4, 2 c5) = (f_uu, f_uv, f_vv) at noise sigma2."""
    for t in range(3):
        out[t] = (2.0 if t != 1 else 1.0) * math.sqrt(max(_inverse_diagonal(L, d, P3, 3 + t, x), 0.0) * sigma2)


@njit(**OPTS)
def _inverse_diagonal(L, d, p, i, x):
    """(G^-1)_ii with the factor of :func:`~core.kernels.algebra.cholesky`: entry i of
    ``chol_solve(L, d, p, e_i, x)``, bit for bit, without its dead work. Its forward pass
    leaves x[a] = +0.0 for a < i (0.0 / d[a], less exact zeros: L is finite once the
    factor succeeded), and subtracting L[a, e] * 0.0 from +0.0 or from 1 / d[i] changes
    nothing, so that pass starts at i; its backward pass reaches x[i] from x[i..p-1] alone."""
    for a in range(i, p):
        s = 1.0 / d[a] if a == i else 0.0
        for c in range(i, a):
            s -= L[a, c] * x[c]
        x[a] = s / L[a, a]
    for a in range(p - 1, i - 1, -1):
        s = x[a]
        for c in range(a + 1, p):
            s -= L[c, a] * x[c]
        x[a] = s / L[a, a]
    return x[i] / d[i]


@njit(**OPTS, parallel=True)
def jet_ici(f, ks, sigma2, rule, chosen, coef):
    """Intersection of confidence intervals of the jet's Hessian (f_uu, f_uv, f_vv).

    ``sigma2[r]``: the noise variance of the heights (units of h^2), known from outside
    (:func:`core.scale.noise_variance`), not from each fit's own residual, so a bias shows
    as a jump of the estimates rather than as a wider interval. ``chosen[r]`` gets the
    index into ``ks`` of the largest size whose interval (``rule.gamma`` deviations) still
    meets all smaller ones, ``coef[r]`` that fit's 10 coefficients; chosen = -1 if no fit
    was possible. k also stops where a ring of neighbours folds over and the next one too
    (as :func:`core.kernels.scale._fold_limit`, looking one ring ahead only as the size grows).
    """
    m = len(f.centres)
    for blk in prange((m + BLOCK - 1) // BLOCK):
        _ici_block(f, ks, sigma2, rule, chosen, coef, blk * BLOCK, min(m, (blk + 1) * BLOCK))


@njit(**OPTS)
def _ici_block(f, ks, sigma2, rule, chosen, coef, start, stop):
    """:func:`jet_ici` for centres start..stop-1, scratch arrays allocated once."""
    uvw = np.empty((3, ks[-1]))
    vecs = np.empty((7, P3))  # row, b, x, d, e, chosen coefficients, scratch
    G, L = np.empty((P3, P3)), np.empty((P3, P3))
    bounds, ref, acc = np.empty((4, 3)), np.empty(8), np.empty(1)  # lo, hi, est, sd
    for r in range(start, stop):
        _local_reference(f.points, f.normals, f.idx, r, ks[0], f.z, rule.fold_cos, ref)
        G[:, :] = 0.0
        vecs[1, :] = 0.0
        acc[0] = 0.0
        bounds[0, :] = -math.inf
        bounds[1, :] = math.inf
        chosen[r] = _ici_point(f, ks, sigma2[r], rule, r, uvw, vecs, G, L, bounds, ref, acc)
        coef[r, :] = vecs[5]
        if chosen[r] < 0:
            coef[r, :] = math.nan


@njit(**OPTS)
def _grows(f, ks, rule, r, c, fold_here, ref):
    """(stop, fold_next): a ring that folds, followed by another (or the last), ends the growth."""
    fold_next = c + 1 >= len(ks) or _folded(f.points, f.normals, f.idx, r, ks[c], ks[c + 1], rule, ref)
    if c == 1:
        fold_here = _folded(f.points, f.normals, f.idx, r, ks[0], ks[1], rule, ref)
    return fold_here and fold_next, fold_next


@njit(**OPTS)
def _ici_point(f, ks, sigma2, rule, r, uvw, vecs, G, L, bounds, ref, acc):
    """The chosen index for centre r (-1 if none); its coefficients in vecs[5]."""
    row, b, x, d, e = vecs[0], vecs[1], vecs[2], vecs[3], vecs[4]
    lo, hi, est, sd = bounds[0], bounds[1], bounds[2], bounds[3]
    chosen = -1
    prev = 0
    fold_here = False
    for c in range(len(ks)):
        if c > 0:
            stop, fold_here = _grows(f, ks, rule, r, c, fold_here, ref)
            if stop:
                break
        _offsets(f, r, prev, ks[c], uvw)
        _add(uvw, prev, ks[c], row, G, b, acc)
        prev = ks[c]
        if not cholesky(G, P3, rule.rcond, d, L):
            if chosen < 0:
                continue
            break
        chol_solve(L, d, P3, b, x)
        est[0], est[1], est[2] = 2.0 * x[3], x[4], 2.0 * x[5]
        _hessian_sd(L, d, e, vecs[6], sigma2, sd)
        meet = True
        for t in range(3):
            lo[t] = max(lo[t], est[t] - rule.gamma * sd[t])
            hi[t] = min(hi[t], est[t] + rule.gamma * sd[t])
            meet = meet and lo[t] <= hi[t]
        if not meet and chosen >= 0:
            break
        chosen = c
        vecs[5, :] = x
    return chosen


# ----------------------------------------------------------------------------- the degree (issue 15)
#: terms of the largest jet the degree rule fits (degree 5)
P5 = 21


@njit(**OPTS)
def _sums(uvw, j0, j1, degree, row, G, b, acc):
    """Least-squares sums of the jet of ``degree`` over neighbours j0 <= j < j1 (offsets in
    ``uvw``, NaN heights left out) added onto G (lower triangle), b, acc[0] = sum w^2 and
    acc[1] = their count. Sums of a lower degree are the leading block of these (the
    monomials come by total degree, each computed the same way at every degree)."""
    p = (degree + 1) * (degree + 2) // 2
    for j in range(j0, j1):
        w = uvw[2, j]
        if not math.isfinite(w):
            continue
        acc[1] += 1.0
        poly_row(uvw[0, j], uvw[1, j], degree, row)
        acc[0] += w * w
        for a in range(p):
            b[a] += row[a] * w
            for c in range(a + 1):
                G[a, c] += row[a] * row[c]


@njit(**OPTS)
def _fit_degree(G, b, acc, degree, rcond, sigma2, mats, vecs, out):
    """Jet of ``degree`` from its sums (:func:`_sums`): out = (f_uu, f_uv, f_vv, their sd
    at noise sigma2, residual variance per degree of freedom); False if rank deficient.
    The coefficients stay in vecs[2] (x), the first p of them used."""
    p = (degree + 1) * (degree + 2) // 2
    L = mats[1]
    x, d, tmp = vecs[2], vecs[3], vecs[5]
    ww, n = acc[0], int(acc[1])
    if n <= p or not cholesky(G, p, rcond, d, L):
        return False
    chol_solve(L, d, p, b, x)
    rss = ww
    for a in range(p):
        rss -= x[a] * b[a]
    for t in range(3):  # (G^-1)_ii = |L^-1 e_i|^2 / d_i^2, L^-1 e_i zero above i: a short forward pass
        i = 3 + t
        var = 0.0
        for a in range(i, p):
            acc_ = 1.0 if a == i else 0.0
            for c in range(i, a):
                acc_ -= L[a, c] * tmp[c]
            tmp[a] = acc_ / L[a, a]
            var += tmp[a] * tmp[a]
        out[3 + t] = (2.0 if t != 1 else 1.0) * math.sqrt(var * sigma2) / d[i]
    out[0], out[1], out[2] = 2.0 * x[3], x[4], 2.0 * x[5]
    out[6] = max(rss, 0.0) / (n - p)
    return True


@njit(**OPTS, parallel=True)
def jet_degrees(f, degrees, kd, k3, sigma2, rule, chosen, coef):
    """Per centre: the degree of its jet by intersection of confidence intervals.

    Models, from the least biased down: degree ``degrees[m]`` on ``kd[m]`` neighbours,
    then the cubic on ``k3[r]`` (the size :func:`jet_ici` chose). Walking down, a model is
    taken while its Hessian's interval (``rule.gamma`` sd at the outside noise
    ``sigma2[r]``) meets those of all the models before it; a higher-degree model must
    also leave a residual variance per degree of freedom no larger than the cubic's (if
    it fits its wider neighbourhood worse, that neighbourhood holds something no
    polynomial of the point's patch describes: an edge, a fold, an outlier). ``chosen[r]``
    gets the model index (len(degrees) for the cubic; -1: none), ``coef[r]`` its 6 terms
    up to degree 2.
    """
    m = len(f.centres)
    for blk in prange((m + BLOCK - 1) // BLOCK):
        _degrees_block(f, degrees, kd, k3, sigma2, rule, chosen, coef, blk * BLOCK, min(m, (blk + 1) * BLOCK))


@njit(**OPTS)
def _degrees_block(f, degrees, kd, k3, sigma2, rule, chosen, coef, start, stop):
    kmax = max(kd.max(), k3.max())
    uvw = np.empty((3, kmax))
    mats, vecs = np.empty((2, P5, P5)), np.empty((6, P5))
    nm = len(degrees) + 1
    fits, ok = np.empty((nm, 7)), np.empty(nm, dtype=np.bool_)
    keep, bounds = np.empty((nm, 6)), np.empty((2, 3))
    G3, b3, accs = np.empty((P3, P3)), np.empty(P3), np.empty((2, 2))  # accs: model 0's sums, the cubic's
    for r in range(start, stop):
        _offsets(f, r, 0, max(kd.max(), k3[r]), uvw)
        shared = nm > 1 and degrees[0] >= 3  # the cubic's sums come with those of model 0
        for mi in range(nm - 1):
            ok[mi] = _higher_fit(uvw, degrees[mi], kd[mi], k3[r] if mi == 0 and shared else 0, sigma2[r],
                                 rule.rcond, mats, vecs, accs, G3, b3, fits[mi])
            keep[mi, :] = vecs[2, :6]
        if not shared:  # the cubic's sums from nothing
            G3[:, :] = 0.0
            b3[:] = 0.0
            accs[1, :] = 0.0
            _sums(uvw, 0, k3[r], 3, vecs[0], G3, b3, accs[1])
        ok[nm - 1] = _fit_degree(G3, b3, accs[1], 3, rule.rcond, sigma2[r], mats, vecs, fits[nm - 1])
        keep[nm - 1, :] = vecs[2, :6]
        chosen[r] = _walk_down(fits, ok, rule.gamma, bounds)
        if chosen[r] >= 0:
            coef[r, :] = keep[chosen[r]]
        else:
            coef[r, :] = math.nan


@njit(**OPTS)
def _higher_fit(uvw, degree, k, k3, sigma2, rcond, mats, vecs, accs, G3, b3, out):
    """:func:`_fit_degree` of ``degree`` on k neighbours (its sum of w^2 and count in
    accs[0]); with k3 > 0 also the cubic's sums on k3 into G3, b3, accs[1], taken from the
    same pass: the leading block of these sums after min(k, k3) neighbours, then grown
    alone (each sum adds the same terms in the same order as a pass of its own)."""
    G, b, row, acc, acc3 = mats[0], vecs[1], vecs[0], accs[0], accs[1]
    p = (degree + 1) * (degree + 2) // 2
    G[:p, :p] = 0.0
    b[:p] = 0.0
    acc[:] = 0.0
    shared = min(k, k3)
    _sums(uvw, 0, shared, degree, row, G, b, acc)
    if k3 > 0:
        G3[:, :] = G[:P3, :P3]
        b3[:] = b[:P3]
        acc3[:] = acc
        _sums(uvw, shared, k3, 3, row, G3, b3, acc3)
    _sums(uvw, shared, k, degree, row, G, b, acc)
    return _fit_degree(G, b, acc, degree, rcond, sigma2, mats, vecs, out)


@njit(**OPTS)
def _walk_down(fits, ok, gamma, bounds):
    """The last model of the walk (see :func:`jet_degrees`), -1 if none fits; ``bounds``
    (2, 3) scratch for the intersection's lower and upper ends."""
    nm = len(ok)
    cubic_var = fits[nm - 1, 6] if ok[nm - 1] else math.inf
    lo, hi = bounds[0], bounds[1]
    lo[:] = -math.inf
    hi[:] = math.inf
    chosen = -1
    for mi in range(nm):
        if not ok[mi] or (mi < nm - 1 and fits[mi, 6] > cubic_var):
            continue
        meet = True
        for t in range(3):
            lo[t] = max(lo[t], fits[mi, t] - gamma * fits[mi, 3 + t])
            hi[t] = min(hi[t], fits[mi, t] + gamma * fits[mi, 3 + t])
            meet = meet and lo[t] <= hi[t]
        if not meet and chosen >= 0:
            break
        chosen = mi
    return chosen
