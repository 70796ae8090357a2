"""Whether a point's neighbours' scatter has a small least eigenvalue: a surface seen
(:mod:`core.volumetric`)."""

from __future__ import annotations

from numba import njit, prange

from ._base import OPTS
from .algebra import add_outer


@njit(**OPTS, parallel=True)
def sees_surface(points, centres, idx, share, out):
    """``out[r]``: whether the smallest eigenvalue of the scatter C of the points ``idx[r]`` (the
    neighbours of ``centres[r]``) is below ``share`` x trace(C): whether C - share trace(C) I
    is not positive definite (its leading minors; no eigenvalues needed). One pass, the
    moments taken about the centre (their spread, not the coordinates' size, sets the rounding)."""
    k = idx.shape[1]
    for r in prange(len(centres)):
        i = centres[r]
        sx = sy = sz = c00 = c01 = c02 = c11 = c12 = c22 = 0.0
        for j in range(k):
            q = idx[r, j]
            dx, dy, dz = points[q, 0] - points[i, 0], points[q, 1] - points[i, 1], points[q, 2] - points[i, 2]
            sx, sy, sz = sx + dx, sy + dy, sz + dz
            c00, c01, c02, c11, c12, c22 = add_outer(c00, c01, c02, c11, c12, c22, 1.0, dx, dy, dz)
        sx, sy, sz = sx / k, sy / k, sz / k
        c00, c01, c02 = c00 / k - sx * sx, c01 / k - sx * sy, c02 / k - sx * sz
        c11, c12, c22 = c11 / k - sy * sy, c12 / k - sy * sz, c22 / k - sz * sz
        x = share * (c00 + c11 + c22)
        a00, a11, a22 = c00 - x, c11 - x, c22 - x
        minor2 = a00 * a11 - c01 * c01
        det = a00 * (a11 * a22 - c12 * c12) - c01 * (c01 * a22 - c12 * c02) + c02 * (c01 * c12 - a11 * c02)
        out[r] = not (a00 > 0.0 and minor2 > 0.0 and det > 0.0)
