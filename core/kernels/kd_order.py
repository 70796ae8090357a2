"""The leaf order of a balanced kd-tree, on all cores (numba).

:func:`core.neighbours.search_in_spatial_order` runs on the points put in an order where
every range of consecutive indices is a compact piece of space, and a point's neighbours
in the order are its neighbours in space: each query starts from the previous point's
radius (:mod:`core.kernels.kdtree`), every later loop over the neighbours reads memory
already in cache. The order splits each range at its middle index, by the median of its
widest coordinate, down to :data:`core.tuning.ORDER_LEAF` points, on a copy of the points
moved along (sequential reads; the index permutation alone was 3x slower at 1M points).
Any order gives the same neighbours (ties follow the caller's index): this one only
decides how fast they are found.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._base import OPTS

#: ranges split one after another before the rest are split in parallel (a power of 2)
_TOP = 64


@njit(**OPTS)
def _widest(q, lo, hi):
    """The coordinate (0, 1, 2) along which the points q[lo:hi] spread the most."""
    mn0 = mn1 = mn2 = np.inf
    mx0 = mx1 = mx2 = -np.inf
    for j in range(lo, hi):
        a, b, c = q[j, 0], q[j, 1], q[j, 2]
        mn0, mx0 = min(mn0, a), max(mx0, a)
        mn1, mx1 = min(mn1, b), max(mx1, b)
        mn2, mx2 = min(mn2, c), max(mx2, c)
    s0, s1, s2 = mx0 - mn0, mx1 - mn1, mx2 - mn2
    if s0 >= s1 and s0 >= s2:
        return 0
    return 1 if s1 >= s2 else 2


@njit(**OPTS, inline="always")
def _swap(q, perm, i, j):
    """Exchange points i and j (their coordinates and their indices)."""
    perm[i], perm[j] = perm[j], perm[i]
    for d in range(3):
        q[i, d], q[j, d] = q[j, d], q[i, d]


@njit(**OPTS, inline="always")
def _draw(state, lo, hi):
    """(the next state of a 64-bit LCG, an index in [lo, hi) drawn from it)."""
    state = state * np.uint64(6364136223846793005) + np.uint64(1442695040888963407)
    return state, lo + np.int64(state >> np.uint64(33)) % (hi - lo)


@njit(**OPTS)
def _select(q, perm, lo, hi, kth, axis):
    """Reorder q[lo:hi] (and perm with it) so that no point before ``kth`` has a larger
    coordinate ``axis`` than point kth and none after it a smaller one (quickselect). The
    pivot is the median of 3 points drawn by a generator seeded with the range: linear
    time in expectation whatever the input's order (the median of the first, middle and
    last points took 111 s on a million points whose x rose then fell, as a scanner
    sweeping back and forth gives); values equal to the pivot are set apart, so repeated
    coordinates cannot make it quadratic; a NaN coordinate only ends its range's ordering early."""
    state = np.uint64(lo) * np.uint64(0x9E3779B97F4A7C15) + np.uint64(hi)
    while hi - lo > 1:
        state, a = _draw(state, lo, hi)
        state, b = _draw(state, lo, hi)
        state, c = _draw(state, lo, hi)
        x, y, z = q[a, axis], q[b, axis], q[c, axis]
        pivot = max(min(x, y), min(max(x, y), z))
        below = lo
        for i in range(lo, hi):
            if q[i, axis] < pivot:
                _swap(q, perm, i, below)
                below += 1
        upto = below
        for i in range(below, hi):
            if q[i, axis] == pivot:
                _swap(q, perm, i, upto)
                upto += 1
        if kth < below:
            hi = below
        elif kth < upto or upto == below:
            return
        else:
            lo = upto


@njit(**OPTS)
def _halve(q, perm, lo, hi):
    """Split q[lo:hi] at its middle index by the median of its widest coordinate; returns the middle."""
    mid = (lo + hi) // 2
    _select(q, perm, lo, hi, mid, _widest(q, lo, hi))
    return mid


@njit(**OPTS)
def _split_all(q, perm, lo, hi, leaf, stack):
    """Split q[lo:hi] down to ranges of at most ``leaf`` points, one after another."""
    stack[0], stack[1] = lo, hi
    top = 1
    while top > 0:
        top -= 1
        a, b = stack[2 * top], stack[2 * top + 1]
        if b - a <= leaf:
            continue
        mid = _halve(q, perm, a, b)
        stack[2 * top], stack[2 * top + 1] = a, mid
        stack[2 * top + 2], stack[2 * top + 3] = mid, b
        top += 2


@njit(**OPTS, parallel=True)
def kd_order(p, leaf):
    """``(order, q)``: the points ``p`` (N, 3) in the leaf order of a kd-tree that splits
    every range of more than ``leaf`` points at its middle index by the median of its
    widest coordinate (``order`` (N,) int64), and ``q = p[order]``. The same order whatever
    the number of threads: the top 6 levels are split in turn, then their 64 ranges each
    by one thread (each level's ranges split in parallel too: their slices are disjoint)."""
    n = p.shape[0]
    q = p.copy()
    perm = np.arange(n)
    los, his = np.zeros(_TOP, np.int64), np.zeros(_TOP, np.int64)
    his[0] = n
    count = 1
    while count < _TOP:  # breadth first: range i splits into 2i and 2i + 1 of the next level
        lo, hi = los.copy(), his.copy()  # read from the copies: range 0 writes the slot range 1 reads
        for i in prange(count):  # disjoint slices of q and perm: in parallel, the same splits
            a, b = lo[i], hi[i]
            mid = _halve(q, perm, a, b) if b - a > leaf else b
            los[2 * i], his[2 * i], los[2 * i + 1], his[2 * i + 1] = a, mid, mid, b
        count *= 2
    depth = 2 * int(np.log2(max(n, 2))) + 8
    for t in prange(_TOP):
        _split_all(q, perm, los[t], his[t], leaf, np.empty(2 * depth + 4, np.int64))
    return perm, q
