"""Robust weights of the normal fit: IRLS with Huber or Tukey weights, MAD scale.

The reweighting is a third of the robust cubic fit's time at k = 226, most of it in the
median; both loops here are free of data-dependent branches (a mispredicted branch per
neighbour cost more than the arithmetic), and the median is taken of the squared
residuals, so no square root is needed but the median's own.
"""

from __future__ import annotations

import math

from numba import njit

from ._base import LEAF
from .algebra import n_terms
from .lstsq import CX, CY

#: Huber's and Tukey's tuning constants (95 % efficiency under Gaussian residuals)
HUBER_C = 1.345
TUKEY_C = 4.685
#: MAD -> standard deviation of a Gaussian
MAD_SIGMA = 1.4826
#: the smallest residual scale (normal components are unitless): an exact fit gets weights 1
MIN_SCALE = 1e-4


@njit(**LEAF)
def _partition(a, lo, hi, pivot, strict):
    """Move the values of a[lo:hi] below ``pivot`` (at or below it unless ``strict``) to
    its front, without a branch per value; returns the end of that front part."""
    store = lo
    for i in range(lo, hi):
        x = a[i]
        a[i] = a[store]
        a[store] = x
        store += (x < pivot) if strict else (x <= pivot)
    return store


@njit(**LEAF)
def select(a, lo, hi, kth):
    """Partially order a[lo:hi] in place so a[kth] is the value a full sort would put
    there and no value before it is larger (quickselect, median-of-3 pivot; values equal
    to the pivot are set apart, so repeated values cannot make it quadratic)."""
    while hi - lo > 1:
        x, y, z = a[lo], a[(lo + hi) // 2], a[hi - 1]
        pivot = max(min(x, y), min(max(x, y), z))
        below = _partition(a, lo, hi, pivot, True)
        if kth < below:
            hi = below
            continue
        upto = _partition(a, below, hi, pivot, False)
        if kth < upto:
            return
        lo = upto


@njit(**LEAF)
def root_median(a, m):
    """Median of sqrt(a[:m]) for a[:m] >= 0 (reorders a), without the copy np.median makes:
    the square root is monotone, so only the one or two middle values need it."""
    select(a, 0, m, m // 2)
    return selected_root_median(a, m)


@njit(**LEAF)
def selected_root_median(a, m):
    """:func:`root_median` of a[:m] once it is selected at m // 2 (or sorted)."""
    upper = math.sqrt(a[m // 2])
    if m % 2:
        return upper
    lower = a[0]
    for j in range(1, m // 2):  # after select every value before m // 2 is <= the middle one
        lower = max(lower, a[j])
    return 0.5 * (upper + math.sqrt(lower))


@njit(**LEAF)
def _squared_residuals(s, n, degree):
    """s.res[j] = |(X, Y) - fit|^2 of neighbours 0..n-1 (monomials innermost: vectorised)."""
    R, res, tmp, vec = s.R, s.res, s.tmp, s.vec
    for j in range(n):
        res[j] = s.X[j]
        tmp[j] = s.Y[j]
    for a in range(n_terms(degree)):
        cx, cy = vec[CX, a], vec[CY, a]
        for j in range(n):
            res[j] -= cx * R[a, j]
            tmp[j] -= cy * R[a, j]
    for j in range(n):
        res[j] = res[j] * res[j] + tmp[j] * tmp[j]


@njit(**LEAF)
def robust_weights(s, n, degree, kind):
    """IRLS weights ``s.wt`` of neighbours 0..n-1 from the residuals of the current fit in
    the :class:`~core.kernels.lstsq.Scratch` ``s``: Huber (kind 1, c = 1.345) or Tukey
    biweight (kind 2, c = 4.685) on the residual / (1.4826 x median absolute residual of
    the neighbours with a normal)."""
    base, wt, res, tmp = s.base, s.wt, s.res, s.tmp
    _squared_residuals(s, n, degree)
    m = 0
    for j in range(n):  # the neighbours with a normal, packed into tmp
        tmp[m] = res[j]
        m += base[j] > 0.0
    if m == 0:
        return
    mad = root_median(tmp, m)
    scale = max(MAD_SIGMA * mad, MIN_SCALE)
    if kind == 1:  # Huber: 1 up to c scales, then c scale / r
        for j in range(n):
            r = math.sqrt(res[j]) / scale
            wt[j] = base[j] * (1.0 if r <= HUBER_C else HUBER_C / r)
        return
    inv = 1.0 / (TUKEY_C * scale) ** 2
    for j in range(n):  # Tukey biweight: (1 - (r / c scale)^2)^2 up to c scales, then 0
        t = 1.0 - res[j] * inv
        wt[j] = base[j] * (t * t if t > 0.0 else 0.0)
