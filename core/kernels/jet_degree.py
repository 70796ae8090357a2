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

from ._base import BLOCK, LEAF, OPTS
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
    """Per-block scratch of the rule, whole arrays only (a row or a record taken inside the loop
    over sizes costs an atomic reference count, :mod:`core.kernels.jets`): the factor ``L`` and
    vectors ``d``, ``x`` of :func:`_fit_degree`; ``table`` (rows + 5, P5): per model (then per
    cubic size, rows n_models + c) its fit in columns :data:`FIT` (f_uu, f_uv, f_vv, their sd,
    residual variance per degree of freedom) and its first 6 coefficients in :data:`KEEP`, then
    (rows :data:`CHAIN` past them) the intersection of the richer models' intervals so far (lower,
    upper ends) and 3 rows of scratch; ``flags`` (rows + 1,): each row's ``ok``, then whether that
    intersection is not empty (:func:`grow` fits no model past the first that leaves it)."""

    L: np.ndarray
    d: np.ndarray
    x: np.ndarray
    table: np.ndarray
    flags: np.ndarray


#: columns of a model's row of ``DegreeScratch.table``: its fit, its first 6 coefficients
FIT, KEEP = 0, 7
#: rows of the table past the models' and sizes': the chain's ends (2), the fits' scratch (3)
CHAIN, TMP = 0, 2


@njit(**OPTS)
def degree_scratch(n_models, n_sizes):
    """A :class:`DegreeScratch` for ``n_models`` models and ``n_sizes`` cubic sizes."""
    rows = n_models + n_sizes
    return DegreeScratch(np.empty((P5, P5)), np.empty(P5), np.empty(P5), np.empty((rows + 5, P5)),
                         np.zeros(rows + 1, dtype=np.bool_))


@njit(**OPTS, inline="always")
def start_chain(table, flags):
    """Forget the previous centre's models: none fitted, the intersection everything."""
    rows = len(flags) - 1
    flags[:] = False
    for t in range(3):
        table[rows + CHAIN, t] = -math.inf
        table[rows + CHAIN + 1, t] = math.inf
    flags[rows] = True


@njit(**OPTS, inline="always")
def _narrow(table, ends, fit, gamma):
    """Intersect [lo, hi] (table rows ends, ends + 1) with row ``fit``'s Hessian interval (+-gamma
    sd); True if not empty."""
    meet = True
    for t in range(3):
        table[ends, t] = max(table[ends, t], table[fit, FIT + t] - gamma * table[fit, FIT + 3 + t])
        table[ends + 1, t] = min(table[ends + 1, t], table[fit, FIT + t] + gamma * table[fit, FIT + 3 + t])
        meet = meet and table[ends, t] <= table[ends + 1, t]
    return meet


@njit(**OPTS, inline="always")
def _fit_degree(G, b, acc, degree, rcond, sigma2, L, d, x, table, out):
    """Jet of ``degree`` from its sums (:func:`_sums`): row ``out`` of ``table`` gets (f_uu,
    f_uv, f_vv, their sd at noise sigma2, residual variance per degree of freedom) and the first
    6 coefficients; False if rank deficient. The coefficients stay in x, the first p of them
    used; (L, d, x, table) as :class:`DegreeScratch` holds them."""
    p = (degree + 1) * (degree + 2) // 2
    n = int(acc[1])
    fitted = n > p and cholesky(G, p, rcond, d, L)
    if fitted:
        chol_solve(L, d, p, b, x)
        _degree_out(L, d, x, b, acc[0], n, p, sigma2, table, out)
    for a in range(6):
        table[out, KEEP + a] = x[a]
    return fitted


@njit(**LEAF)
def _degree_out(L, d, x, b, ww, n, p, sigma2, table, out):
    """:func:`_fit_degree`'s row ``out`` of ``table`` from the factor (L, d) of p terms, the
    solution x, the sums b and ww = sum w^2 of n neighbours; the table's last 3 rows scratch."""
    tmp = len(table) - 5 + TMP
    rss = ww
    for a in range(p):
        rss -= x[a] * b[a]
    for t in range(3):  # the variances first: (G^-1)_ii = |L^-1 e_i|^2 / d_i^2, L^-1 e_i zero above i,
        table[out, FIT + 3 + t] = 0.0
    for a in range(3, p):  # three short forward passes (rows of tmp), interleaved: the same operations
        for t in range(3):
            i = 3 + t
            if a < i:
                continue
            acc_ = 1.0 if a == i else 0.0
            for c in range(i, a):
                acc_ -= L[a, c] * table[tmp + t, c]
            table[tmp + t, a] = acc_ / L[a, a]
            table[out, FIT + 3 + t] += table[tmp + t, a] * table[tmp + t, a]
    for t in range(3):
        table[out, FIT + 3 + t] = (2.0 if t != 1 else 1.0) * math.sqrt(table[out, FIT + 3 + t] * sigma2) / d[3 + t]
    table[out, FIT], table[out, FIT + 1], table[out, FIT + 2] = 2.0 * x[3], x[4], 2.0 * x[5]
    table[out, FIT + 6] = max(rss, 0.0) / (n - p)


@njit(**OPTS, inline="always")
def grow(uvw, j0, j1, deg, sums, sigma2, rcond, L, d, x, table, flags):
    """Sums of neighbours j0 <= j < j1 (offsets in ``uvw``) added onto ``sums`` = (row, G, b,
    acc) (with the count in acc[1]): of degree ``deg.dmax`` up to ``deg.kmax``, cubic after, and
    each model of ``deg`` fitted (into the :class:`DegreeScratch` arrays L, d, x, table, flags)
    when they reach its ``kd``, until one's interval (``deg.gamma`` sd) leaves those before it
    (the walk ends there: the wider ones are not needed). Every entry adds the same products in
    the same order as a pass of its own."""
    row, G, b, acc = sums
    alive = len(flags) - 1
    ends = alive + CHAIN
    j = j0
    for t in range(len(deg.by_k)):
        mi = deg.by_k[t]
        k = deg.kd[mi]
        if flags[alive] and j0 < k <= j1:
            _sums(uvw, j, k, deg.dmax, row, G, b, acc)
            j = k
            flags[mi] = _fit_degree(G, b, acc, deg.degrees[mi], rcond, sigma2, L, d, x, table, mi)
            if flags[mi]:
                flags[alive] = _narrow(table, ends, mi, deg.gamma)
    top = min(j1, deg.kmax) if flags[alive] else j
    if j < top:
        _sums(uvw, j, top, deg.dmax, row, G, b, acc)
        j = top
    _sums(uvw, j, j1, 3, row, G, b, acc)


@njit(**OPTS, inline="always")
def stash_cubic(L, d, x, b, acc, sigma2, row, table, flags):
    """Keep, as row ``row`` of a :class:`DegreeScratch`'s ``table`` and ``flags``, what
    :func:`_fit_degree` gives the cubic whose factor (L, d) and solution x the intervals
    computed on the sums b, acc (the same factor: the same sums and the same :func:`cholesky`)."""
    n = int(acc[1])
    flags[row] = n > P3
    if n > P3:
        _degree_out(L, d, x, b, acc[0], n, P3, sigma2, table, row)
    for a in range(6):
        table[row, KEEP + a] = x[a]


@njit(**LEAF)
def walk(table, flags, deg, c):
    """:func:`_walk_down` over the models of ``deg`` and the cubic at its size index c (kept by
    :func:`stash_cubic` in row n_models + c) of a :class:`DegreeScratch`'s table and flags."""
    n_models = len(deg.kd)
    top = n_models + c
    for a in range(table.shape[1]):  # a row copied by hand: numba's row copy needs reference counting
        table[n_models, a] = table[top, a]
    flags[n_models] = flags[top]
    return _walk_down(table, flags, n_models + 1, deg.gamma, deg.misfit)


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
    nm = len(degrees) + 1
    L, d, x, table, ok = degree_scratch(nm - 1, 1)
    G, row, b = np.empty((P5, P5)), np.empty(P5), np.empty(P5)
    G3, b3, accs = np.empty((P3, P3)), np.empty(P3), np.empty((2, 2))  # accs: model 0's sums, the cubic's
    for r in range(start, stop):
        _offsets(f, r, 0, min(max(kd.max(), k3[r]), kmax), uvw)
        shared = nm > 1 and degrees[0] >= 3 and kd[0] <= kmax  # the cubic's sums come with those of model 0
        for mi in range(nm - 1):
            grows = mi == 0 or k3[r] >= kd[0]  # past the first model only where the cubic reached it
            ok[mi] = False
            if kd[mi] <= kmax and grows:
                _higher_sums(uvw, degrees[mi], kd[mi], k3[r] if mi == 0 and shared else 0, (row, G, b, accs[0]),
                             G3, b3, accs[1])
                ok[mi] = _fit_degree(G, b, accs[0], degrees[mi], rcond, sigma2[r], L, d, x, table, mi)
        if not shared:  # the cubic's sums from nothing
            G3[:, :] = 0.0
            b3[:] = 0.0
            accs[1, :] = 0.0
            _sums(uvw, 0, k3[r], 3, row, G3, b3, accs[1])
        ok[nm - 1] = _fit_degree(G3, b3, accs[1], 3, rcond, sigma2[r], L, d, x, table, nm - 1)
        chosen[r] = _walk_down(table, ok, nm, gamma, misfit)
        for a in range(6):
            coef[r, a] = table[chosen[r], KEEP + a] if chosen[r] >= 0 else math.nan


@njit(**OPTS)
def _higher_sums(uvw, degree, k, k3, sums, G3, b3, acc3):
    """The sums (:func:`_sums`) of ``degree`` on k neighbours into ``sums`` = (row, G, b, acc);
    with k3 > 0 also the cubic's sums on k3 into G3, b3, acc3, taken from the same pass: the
    leading block of these sums after min(k, k3) neighbours, then grown alone (each sum adds
    the same terms in the same order as a pass of its own)."""
    row, G, b, acc = sums
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


@njit(**LEAF)
def _walk_down(table, ok, nm, gamma, misfit):
    """The last of the nm models of the walk (see :func:`jet_degrees`; rows of a
    :class:`DegreeScratch`'s table and ok), -1 if none fits; the table's chain rows hold the
    intersection's lower and upper ends."""
    cubic_var = table[nm - 1, FIT + 6] if ok[nm - 1] else math.inf
    ends = len(ok) - 1 + CHAIN
    for t in range(3):
        table[ends, t] = -math.inf
        table[ends + 1, t] = math.inf
    chosen = -1
    mi = 0
    while mi < nm:
        if ok[mi] and mi < nm - 1 and table[mi, FIT + 6] > misfit * cubic_var:
            mi = nm - 1  # an edge or a fold in its neighbourhood: no wider richer model, the cubic next
            continue
        if ok[mi]:
            if not _narrow(table, ends, mi, gamma) and chosen >= 0:
                break
            chosen = mi
        mi += 1
    return chosen
