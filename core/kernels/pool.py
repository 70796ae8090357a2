"""Means and quantiles over each point's neighbours of a per-point value (numba, ``nogil``):
the pooled residual variances of :func:`core.scale.noise_variance`, the local noise of
:mod:`core.local_noise`.

Numpy reference: ``np.nanmean(v[pool], axis=1)``, which gathers an (N, m) copy, a NaN
mask and a zero-filled copy before it sums (1.3 s of a 1M-point estimate for two
values). The sums here add in numpy's order for a contiguous row shorter than 128
(:func:`_row_sum`), so the means are bit-identical: they feed threshold decisions.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS
from .robust import select

#: the longest row whose sum :func:`_row_sum` adds in numpy's order (numpy's pairwise
#: block; longer rows are split in halves, which the kernel does not do)
MAX_POOL = 128


@njit(**OPTS, parallel=True)
def pooled_nanmeans(va, vb, pool, a, b):
    """a[r] = nanmean(va[pool[r]]), b[r] = nanmean(vb[pool[r]]) (NaN where every value of
    the row is NaN), for rows of at most :data:`MAX_POOL` neighbours."""
    n = pool.shape[0]
    for blk in prange((n + BLOCK - 1) // BLOCK):
        for r in range(blk * BLOCK, min(n, (blk + 1) * BLOCK)):
            a[r] = _row_nanmean(va, pool, r)
            b[r] = _row_nanmean(vb, pool, r)


@njit(**OPTS)
def _row_nanmean(v, pool, r):
    """Sum of the non-NaN v[pool[r, j]] over their count, as numpy's nanmean: NaN -> 0,
    the row summed by :func:`_row_sum` onto numpy's initial 0.0, then one division."""
    count = 0
    for j in range(pool.shape[1]):
        if not math.isnan(v[pool[r, j]]):
            count += 1
    return (0.0 + _row_sum(v, pool, r)) / count


@njit(**OPTS, inline="always")
def _at(v, pool, r, j):
    x = v[pool[r, j]]
    return 0.0 if math.isnan(x) else x


@njit(**OPTS)
def _row_sum(v, pool, r):
    """numpy's pairwise_sum of a row of m < 8 (one by one from 0.0) or 8 <= m <= 128
    values: eight running sums r_j of the values j, j + 8, ..., combined as
    ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7)), then the last m % 8 added one by one."""
    m = pool.shape[1]
    if m < 8:
        res = 0.0
        for j in range(m):
            res += _at(v, pool, r, j)
        return res
    r0, r1, r2, r3 = _at(v, pool, r, 0), _at(v, pool, r, 1), _at(v, pool, r, 2), _at(v, pool, r, 3)
    r4, r5, r6, r7 = _at(v, pool, r, 4), _at(v, pool, r, 5), _at(v, pool, r, 6), _at(v, pool, r, 7)
    i = 8
    while i < m - m % 8:
        r0 += _at(v, pool, r, i)
        r1 += _at(v, pool, r, i + 1)
        r2 += _at(v, pool, r, i + 2)
        r3 += _at(v, pool, r, i + 3)
        r4 += _at(v, pool, r, i + 4)
        r5 += _at(v, pool, r, i + 5)
        r6 += _at(v, pool, r, i + 6)
        r7 += _at(v, pool, r, i + 7)
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < m:
        res += _at(v, pool, r, i)
        i += 1
    return res


@njit(**OPTS)
def _row_quantile(v, pool, r, q, row):
    """The q-quantile of the finite v[pool[r, :]] (copied into ``row``; NaN if none), by
    :func:`linear_quantile`."""
    m = 0
    for j in range(pool.shape[1]):
        x = v[pool[r, j]]
        if math.isfinite(x):
            row[m] = x
            m += 1
    return linear_quantile(row, m, q) if m else math.nan


@njit(**OPTS)
def linear_quantile(a, m, q):
    """The q-quantile of a[:m] (m >= 1; a is reordered) by selection, as numpy's linear
    interpolation gives it, bit for bit."""
    select(a, 0, m, int(math.floor(q * (m - 1))))
    return selected_quantile(a, m, q)


@njit(**OPTS)
def selected_quantile(a, m, q):
    """:func:`linear_quantile` of a[:m] once it is selected at floor(q (m - 1)) (or sorted)."""
    at = q * (m - 1)
    lo = int(math.floor(at))
    low = a[lo]
    if lo + 1 >= m:
        return low
    high = a[lo + 1]
    for j in range(lo + 2, m):  # after the selection, what is above lo holds the larger values
        high = min(high, a[j])
    t = at - lo  # numpy's lerp: from the nearer end
    return high - (high - low) * (1.0 - t) if t >= 0.5 else low + (high - low) * t


@njit(**OPTS, parallel=True)
def pooled_above(v, pool, q, bound, out):
    """out[r] = np.nanquantile(v[pool[r]], q) (numpy's linear interpolation) where it exceeds
    ``bound``, else 0 (also where the row has no finite value): the local noise of
    :mod:`core.local_noise`. The quantile is selected only where a count of the row says it
    may exceed the bound: it is at most the (lo + 1)-th smallest value (lo = floor(q (m - 1)))."""
    n = pool.shape[0]
    for blk in prange((n + BLOCK - 1) // BLOCK):
        row = np.empty(pool.shape[1])
        for r in range(blk * BLOCK, min(n, (blk + 1) * BLOCK)):
            m = upto = 0
            for j in range(pool.shape[1]):
                x = v[pool[r, j]]
                if math.isfinite(x):
                    m += 1
                    upto += x <= bound
            out[r] = 0.0
            if m and upto < int(math.floor(q * (m - 1))) + 2:
                x = _row_quantile(v, pool, r, q, row)
                if x > bound:
                    out[r] = x
