"""Compiled loops of the degree rule of the automatic scale (:mod:`core.scale`, issue 15):
where the data are quiet, jets of degree 4 (or 5) on a few more neighbours than the cubic
replace it while their confidence intervals show the cubic's bias.

:func:`jet_degrees` runs the rule on its own at given cubic sizes; the scale rule runs it
inside the cubic's intersection of intervals (:func:`core.kernels.jets.jet_ici`, through
:func:`grow`, :func:`stash_cubic` and :func:`walk`), on the same sums: the cubic's normal
equations are the leading block of a higher degree's (the monomials come by total degree),
so one pass over the neighbours serves both, and the cubic's factor at its chosen size is
the one the intervals already computed. The numbers are the same to the last bit."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS
from .algebra import chol_solve, cholesky
from ..tuning import JET_DEGREE_GAMMA, JET_MISFIT
from .jet_sums import P3, P5, _offsets, _sums


class DegreeRule(NamedTuple):
    """The richer models the rule tries (:data:`core.tuning.JET_DEGREES`): model m is a jet
    of degree ``degrees[m]`` on ``kd[m]`` neighbours (walked in that order), ``by_k`` the
    models by ascending ``kd``; ``quiet`` (M,) bool where a centre's noise lets the rule run,
    on cubics stopped at no more than ``reach`` neighbours; ``dmax``, ``kmax``: the highest
    degree and the widest model (the sums are of degree dmax up to kmax); ``misfit``, ``gamma``: as
    :func:`jet_degrees` takes them."""

    quiet: np.ndarray
    degrees: np.ndarray
    kd: np.ndarray
    by_k: np.ndarray
    reach: int
    dmax: int
    kmax: int
    misfit: float
    gamma: float


class DegreeScratch(NamedTuple):
    """Per-block scratch of the rule: the factor (mats[1]) and vectors of :func:`_fit_degree`,
    and per model (then per cubic size, rows len(kd) + c) its ``fits`` row (f_uu, f_uv,
    f_vv, their sd, residual variance per degree of freedom), first 6 coefficients and ``ok``;
    ``chain`` (2, 3) the intersection of the richer models' intervals so far, ``alive[0]`` while
    it is not empty (:func:`grow` fits no model past the first that leaves it)."""

    mats: np.ndarray
    vecs: np.ndarray
    fits: np.ndarray
    keep: np.ndarray
    ok: np.ndarray
    chain: np.ndarray
    alive: np.ndarray


@njit(**OPTS)
def degree_scratch(n_models, n_sizes):
    """A :class:`DegreeScratch` for ``n_models`` models and ``n_sizes`` cubic sizes."""
    rows = n_models + n_sizes
    return DegreeScratch(np.empty((2, P5, P5)), np.empty((8, P5)), np.empty((rows, 7)), np.empty((rows, 6)),
                         np.zeros(rows, dtype=np.bool_), np.empty((2, 3)), np.ones(1, dtype=np.bool_))


@njit(**OPTS, inline="always")
def start_chain(ds):
    """Forget the previous centre's models: none fitted, the intersection everything."""
    ds.ok[:] = False
    ds.chain[0, :] = -math.inf
    ds.chain[1, :] = math.inf
    ds.alive[0] = True


@njit(**OPTS, inline="always")
def _narrow(lo, hi, fit, gamma):
    """Intersect [lo, hi] (3,) with ``fit``'s Hessian interval (+-gamma sd); True if not empty."""
    meet = True
    for t in range(3):
        lo[t] = max(lo[t], fit[t] - gamma * fit[3 + t])
        hi[t] = min(hi[t], fit[t] + gamma * fit[3 + t])
        meet = meet and lo[t] <= hi[t]
    return meet


@njit(**OPTS, inline="always")
def _fit_degree(G, b, acc, degree, rcond, sigma2, mats, vecs, out):
    """Jet of ``degree`` from its sums (:func:`_sums`): out = (f_uu, f_uv, f_vv, their sd
    at noise sigma2, residual variance per degree of freedom); False if rank deficient.
    The coefficients stay in vecs[2] (x), the first p of them used."""
    p = (degree + 1) * (degree + 2) // 2
    L = mats[1]
    x, d = vecs[2], vecs[3]
    n = int(acc[1])
    if n <= p or not cholesky(G, p, rcond, d, L):
        return False
    chol_solve(L, d, p, b, x)
    _degree_out(L, d, x, b, acc[0], n, p, sigma2, vecs[5:8], out)
    return True


@njit(**OPTS)
def _degree_out(L, d, x, b, ww, n, p, sigma2, tmp, out):
    """:func:`_fit_degree`'s ``out`` from the factor (L, d) of p terms, the solution x, the
    sums b and ww = sum w^2 of n neighbours; ``tmp`` (3, p) scratch."""
    rss = ww
    for a in range(p):
        rss -= x[a] * b[a]
    out[3:6] = 0.0  # the variances first: (G^-1)_ii = |L^-1 e_i|^2 / d_i^2, L^-1 e_i zero above i,
    for a in range(3, p):  # three short forward passes (rows of tmp), interleaved: the same operations
        for t in range(3):
            i = 3 + t
            if a < i:
                continue
            acc_ = 1.0 if a == i else 0.0
            for c in range(i, a):
                acc_ -= L[a, c] * tmp[t, c]
            tmp[t, a] = acc_ / L[a, a]
            out[3 + t] += tmp[t, a] * tmp[t, a]
    for t in range(3):
        out[3 + t] = (2.0 if t != 1 else 1.0) * math.sqrt(out[3 + t] * sigma2) / d[3 + t]
    out[0], out[1], out[2] = 2.0 * x[3], x[4], 2.0 * x[5]
    out[6] = max(rss, 0.0) / (n - p)


@njit(**OPTS, inline="always")
def grow(uvw, j0, j1, deg, row, G, b, acc, sigma2, rcond, ds):
    """Sums of neighbours j0 <= j < j1 (offsets in ``uvw``) added onto G, b, acc (with the
    count in acc[1]): of degree ``deg.dmax`` up to ``deg.kmax``, cubic after, and each model
    of ``deg`` fitted (into ``ds``) when they reach its ``kd``, until one's interval (``deg.gamma``
    sd) leaves those before it (the walk ends there: the wider ones are not needed). Every entry
    adds the same products in the same order as a pass of its own."""
    j = j0
    for t in range(len(deg.by_k)):
        mi = deg.by_k[t]
        k = deg.kd[mi]
        if ds.alive[0] and j0 < k <= j1:
            _sums(uvw, j, k, deg.dmax, row, G, b, acc)
            j = k
            ds.ok[mi] = _fit_degree(G, b, acc, deg.degrees[mi], rcond, sigma2, ds.mats, ds.vecs, ds.fits[mi])
            ds.keep[mi, :] = ds.vecs[2, :6]
            if ds.ok[mi]:
                ds.alive[0] = _narrow(ds.chain[0], ds.chain[1], ds.fits[mi], deg.gamma)
    top = min(j1, deg.kmax) if ds.alive[0] else j
    if j < top:
        _sums(uvw, j, top, deg.dmax, row, G, b, acc)
        j = top
    _sums(uvw, j, j1, 3, row, G, b, acc)


@njit(**OPTS, inline="always")
def stash_cubic(L, d, x, b, acc, sigma2, row, ds):
    """Keep, as ``ds``'s row ``row``, what :func:`_fit_degree` gives the cubic whose factor
    (L, d) and solution x the intervals computed on the sums b, acc (the same factor:
    the same sums and the same :func:`cholesky`)."""
    n = int(acc[1])
    ds.ok[row] = n > P3
    if n > P3:
        _degree_out(L, d, x, b, acc[0], n, P3, sigma2, ds.vecs[5:8], ds.fits[row])
    ds.keep[row, :] = x[:6]


@njit(**OPTS, inline="always")
def walk(ds, deg, c, bounds):
    """:func:`_walk_down` over the models of ``deg`` and the cubic at its size index c (kept by
    :func:`stash_cubic` in row n_models + c)."""
    n_models = len(deg.kd)
    top = n_models + c
    ds.fits[n_models, :] = ds.fits[top]
    ds.keep[n_models, :] = ds.keep[top]
    ds.ok[n_models] = ds.ok[top]
    return _walk_down(ds.fits[:n_models + 1], ds.ok[:n_models + 1], deg.gamma, bounds, deg.misfit)


@njit(**OPTS, parallel=True)
def jet_degrees(f, degrees, kd, k3, sigma2, rule, chosen, coef, misfit=JET_MISFIT, gamma=JET_DEGREE_GAMMA):
    """Per centre: the degree of its jet by intersection of confidence intervals (the rule
    alone; the scale rule runs it inside :func:`core.kernels.jets.jet_ici`).

    Models, from the least biased down: degree ``degrees[m]`` on ``kd[m]`` neighbours,
    then the cubic on ``k3[r]`` (the size :func:`jet_ici` chose). Walking down, a model is
    taken while its Hessian's interval (``gamma`` sd at the outside noise
    ``sigma2[r]``) meets those of all the models before it; a higher-degree model whose
    residual variance per degree of freedom exceeds ``misfit`` times the cubic's ends the
    richer models (the walk goes on to the cubic): its wider neighbourhood holds something
    no polynomial of the point's patch describes (an edge, a fold, an outlier). Models after the first are fitted
    only where the cubic reached the first's size (``k3[r] >= kd[0]``): where it stopped short, its bias shows above
    the noise and the first is precise (noise-free, most points; a 100k torus took 27 % longer without). ``chosen[r]``
    gets the model index (len(degrees) for the cubic; -1: none), ``coef[r]`` its 6 terms
    up to degree 2.
    """
    m = len(f.centres)
    for blk in prange((m + BLOCK - 1) // BLOCK):
        _degrees_block(f, degrees, kd, k3, sigma2, (rule.rcond, misfit, gamma), chosen, coef, blk * BLOCK,
                       min(m, (blk + 1) * BLOCK))


@njit(**OPTS)
def _degrees_block(f, degrees, kd, k3, sigma2, rule, chosen, coef, start, stop):
    """:func:`jet_degrees` for centres start..stop-1; ``rule`` = (rcond, misfit, gamma). A model wider than the
    neighbours held is not fitted."""
    rcond, misfit, gamma = rule
    kmax = min(max(kd.max(), k3.max()), f.idx.shape[1])
    uvw = np.empty((3, kmax))
    mats, vecs = np.empty((2, P5, P5)), np.empty((8, P5))
    nm = len(degrees) + 1
    fits, ok = np.empty((nm, 7)), np.empty(nm, dtype=np.bool_)
    keep, bounds = np.empty((nm, 6)), np.empty((2, 3))
    G3, b3, accs = np.empty((P3, P3)), np.empty(P3), np.empty((2, 2))  # accs: model 0's sums, the cubic's
    for r in range(start, stop):
        _offsets(f, r, 0, min(max(kd.max(), k3[r]), kmax), uvw)
        shared = nm > 1 and degrees[0] >= 3 and kd[0] <= kmax  # the cubic's sums come with those of model 0
        for mi in range(nm - 1):
            grows = mi == 0 or k3[r] >= kd[0]  # past the first model only where the cubic reached it
            ok[mi] = kd[mi] <= kmax and grows and _higher_fit(uvw, degrees[mi], kd[mi], k3[r] if mi == 0 and shared
                                                              else 0, sigma2[r], rcond, mats, vecs, accs, G3, b3,
                                                              fits[mi])
            keep[mi, :] = vecs[2, :6]
        if not shared:  # the cubic's sums from nothing
            G3[:, :] = 0.0
            b3[:] = 0.0
            accs[1, :] = 0.0
            _sums(uvw, 0, k3[r], 3, vecs[0], G3, b3, accs[1])
        ok[nm - 1] = _fit_degree(G3, b3, accs[1], 3, rcond, sigma2[r], mats, vecs, fits[nm - 1])
        keep[nm - 1, :] = vecs[2, :6]
        chosen[r] = _walk_down(fits, ok, gamma, bounds, misfit)
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
def _walk_down(fits, ok, gamma, bounds, misfit):
    """The last model of the walk (see :func:`jet_degrees`), -1 if none fits; ``bounds``
    (2, 3) scratch for the intersection's lower and upper ends."""
    nm = len(ok)
    cubic_var = fits[nm - 1, 6] if ok[nm - 1] else math.inf
    lo, hi = bounds[0], bounds[1]
    lo[:] = -math.inf
    hi[:] = math.inf
    chosen = -1
    mi = 0
    while mi < nm:
        if ok[mi] and mi < nm - 1 and fits[mi, 6] > misfit * cubic_var:
            mi = nm - 1  # an edge or a fold in its neighbourhood: no wider richer model, the cubic next
            continue
        if ok[mi]:
            if not _narrow(lo, hi, fits[mi], gamma) and chosen >= 0:
                break
            chosen = mi
        mi += 1
    return chosen
