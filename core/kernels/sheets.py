"""Compiled loops of :mod:`core.one_sheet` (numba, ``nogil``): which of a point's held
neighbours lie on another sheet, and the order that puts its own sheet first."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._base import BLOCK, OPTS


@njit(**OPTS, inline="always")
def _side(points, normals, ok, scales, i, q, rule):
    """+1 / -1 if neighbour q of point i lies on another sheet above / below i's plane,
    else 0: its normal parallel to i's (either sign) within ``rule[0]`` (a cosine), and its
    offset from i's plane, less the sagitta the turn between their normals explains
    (chord x sin(turn / 2)), beyond ``rule[1]`` x i's noise spread ``scales[i, 0]`` and
    beyond ``scales[i, 1]`` (a length)."""
    if not ok[q]:
        return 0
    cos_par, gate = rule[0], rule[1]
    par = abs(normals[i, 0] * normals[q, 0] + normals[i, 1] * normals[q, 1] + normals[i, 2] * normals[q, 2])
    if par < cos_par:
        return 0
    cx, cy, cz = points[q, 0] - points[i, 0], points[q, 1] - points[i, 1], points[q, 2] - points[i, 2]
    off = normals[i, 0] * cx + normals[i, 1] * cy + normals[i, 2] * cz
    sagitta = np.sqrt(cx * cx + cy * cy + cz * cz) * np.sqrt(max(0.0, 0.5 * (1.0 - min(par, 1.0))))
    if abs(off) - sagitta > max(gate * scales[i, 0], scales[i, 1]):
        return 1 if off > 0.0 else -1
    return 0


@njit(**OPTS, inline="always")
def _sides(points, normals, ok, scales, idx, row, i, rule):
    """(above, below): which sides of point i's plane hold another sheet among its
    neighbours ``idx[row, 1:]``: at least ``rule[2]`` of them there, and ``rule[3]`` times as
    many as on the other side (a sheet lies on one side; noise's tails on both), and at
    least ``rule[4]`` left on the point's own (a part a spacing or two across, the far side
    of a coarse thin tube, is not a sheet to fit alone)."""
    up = down = 0
    if ok[i]:
        for m in range(1, idx.shape[1]):
            s = _side(points, normals, ok, scales, i, idx[row, m], rule)
            up += s > 0
            down += s < 0
    least, ratio = rule[2], rule[3]
    above, below = up >= least and up >= ratio * down, down >= least and down >= ratio * up
    if idx.shape[1] - 1 - above * up - below * down < rule[4]:  # too few left to fit the point's own sheet on
        return False, False
    return above, below


@njit(**OPTS, parallel=True)
def count_other(points, normals, ok, scales, idx, rule, out):
    """``out[i]``: how many sides of point i's plane (0-2) hold another sheet (:func:`_sides`)."""
    for i in prange(idx.shape[0]):
        up, down = _sides(points, normals, ok, scales, idx, i, i, rule)
        out[i] = up + down


@njit(**OPTS, parallel=True)
def own_sheet_first(points, normals, ok, scales, rows, centres, rule, perm):
    """``perm[r]`` (int64): the columns of ``rows[r]`` (the neighbour row of point
    ``centres[r]``) in the order that puts its own sheet first (the point itself, then the
    neighbours not on a sheet of :func:`_sides`, then those that are, each in the row's
    order). The flags are scratch of each block of rows (an allocation per row cost more
    than the tests)."""
    w = rows.shape[1]
    for blk in prange((len(centres) + BLOCK - 1) // BLOCK):
        other = np.zeros(w, dtype=np.bool_)
        for r in range(blk * BLOCK, min(len(centres), (blk + 1) * BLOCK)):
            _sheet_order(points, normals, ok, scales, rows, centres[r], r, rule, other, perm)


@njit(**OPTS)
def _sheet_order(points, normals, ok, scales, rows, i, r, rule, other, perm):
    """:func:`own_sheet_first` at row r (point i), with ``other`` (w,) scratch."""
    w = rows.shape[1]
    up, down = _sides(points, normals, ok, scales, rows, r, i, rule)
    n_other = 0
    for m in range(1, w):
        s = _side(points, normals, ok, scales, i, rows[r, m], rule)
        other[m] = (s > 0 and up) or (s < 0 and down)
        n_other += other[m]
    front, back = 0, w - 1 - n_other  # own sheet from the start, the others after it
    for m in range(w):
        if other[m]:
            back += 1
            perm[r, back] = m
        else:
            perm[r, front] = m
            front += 1
