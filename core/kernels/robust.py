"""Robust weights of the normal fit: IRLS with Huber or Tukey weights, MAD scale."""

from __future__ import annotations

import math

from numba import njit

from ._base import OPTS
from .algebra import n_terms
from .lstsq import CX, CY


@njit(**OPTS)
def select(a, lo, hi, kth):
    """Partially order a[lo:hi] in place so a[kth] is the value a full sort would put there."""
    while hi - lo > 1:
        pivot = a[(lo + hi) // 2]
        i, j = lo, hi - 1
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if kth <= j:
            hi = j + 1
        elif kth >= i:
            lo = i
        else:
            return
    return


@njit(**OPTS)
def median(a, m):
    """Median of a[:m] (reorders it), without the copy np.median makes."""
    select(a, 0, m, m // 2)
    upper = a[m // 2]
    if m % 2:
        return upper
    select(a, 0, m // 2, m // 2 - 1)
    return 0.5 * (upper + a[m // 2 - 1])


@njit(**OPTS)
def robust_weights(s, n, degree, kind):
    """IRLS weights ``s.wt`` of neighbours 0..n-1 from the residuals of the current fit in
    the :class:`~core.kernels.lstsq.Scratch` ``s``: Huber (kind 1, c = 1.345) or Tukey
    biweight (kind 2, c = 4.685) on the residual / (1.4826 x median absolute residual)."""
    R, X, Y, base, vec, wt, res, tmp = s.R, s.X, s.Y, s.base, s.vec, s.wt, s.res, s.tmp
    p = n_terms(degree)
    m = 0
    for j in range(n):
        rx = X[j]
        ry = Y[j]
        for a in range(p):
            rx -= vec[CX, a] * R[a, j]
            ry -= vec[CY, a] * R[a, j]
        res[j] = math.sqrt(rx * rx + ry * ry)
        if base[j] > 0.0:
            m += 1
    if m == 0:
        return
    c = 0
    for j in range(n):
        if base[j] > 0.0:
            tmp[c] = res[j]
            c += 1
    scale = max(1.4826 * median(tmp, m), 1e-4)
    for j in range(n):
        r = res[j] / scale
        if kind == 1:  # Huber
            f = 1.0 if r <= 1.345 else 1.345 / r
        else:  # Tukey biweight
            f = (1.0 - (r / 4.685) ** 2) ** 2 if r < 4.685 else 0.0
        wt[j] = base[j] * f
