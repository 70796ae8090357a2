"""The augmented Darboux frame of :func:`core.frame.darboux_frame` in two compiled loops
(numba, ``nogil``): the numpy version makes some 60 temporary arrays per chunk of points,
which cost as much as the normal fit itself at k = 15. Same operations in the same order,
so the same numbers."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._base import OPTS


@njit(**OPTS)
def _to_world(v0, v1, v2, t1, t2, z, m, out):
    """out[m] = v0 t1[m] + v1 t2[m] + v2 z[m] (local frame coordinates to world)."""
    for j in range(3):
        out[m, j] = v0 * t1[m, j] + v1 * t2[m, j] + v2 * z[m, j]


@njit(**OPTS)
def _shape_operator(X, Y, Z0, w11, w12, w21, w22):
    """(s11, sym, s22, b1, b2) of :func:`core.frame.darboux_frame`: S = P W P^-1 in the
    tangent basis b1 = r_u / |r_u|, b2 = n x b1, symmetrised (eq. 22)."""
    fu, fv = -X / Z0, -Y / Z0
    ru_len = np.sqrt(1.0 + fu * fu)
    b10, b11, b12 = 1.0 / ru_len, 0.0, fu / ru_len
    b20, b21, b22 = Y * b12 - Z0 * b11, Z0 * b10 - X * b12, X * b11 - Y * b10  # np.cross(n, b1)
    p11, p12, p22 = ru_len, b12 * fv, b21 + b22 * fv
    pw11 = p11 * w11 + p12 * w21
    pw12 = p11 * w12 + p12 * w22
    pw21 = p22 * w21
    pw22 = p22 * w22
    s11 = pw11 / p11
    s12 = (-pw11 * p12 / p11 + pw12) / p22
    s21 = pw21 / p11
    s22 = (-pw21 * p12 / p11 + pw22) / p22
    return s11, 0.5 * (s12 + s21), s22, (b10, b11, b12), (b20, b21, b22)


@njit(**OPTS)
def _tilt(mu, W, max_tilt2, m):
    """(X, Y, Z0, good): the fitted normal in the local frame, zeroed where not usable."""
    X, Y = mu[m, 0], mu[m, 1]
    tilt2 = X * X + Y * Y
    good = math.isfinite(tilt2) and tilt2 < max_tilt2
    for a in range(2):
        for b in range(2):
            good = good and math.isfinite(W[m, a, b])
    if not good:
        X, Y = 0.0, 0.0
    return X, Y, np.sqrt(1.0 - X * X - Y * Y), good


@njit(**OPTS, parallel=True)
def frame_curvatures(t1, t2, z, mu, W, max_tilt2, normal, k1, k2, yx, good):
    """Per point m, :func:`core.frame.darboux_frame` up to the principal directions:
    ``normal``, ``k1`` >= ``k2``, ``yx[m]`` = (y, x) whose arctan2 / 2 is the angle of e1
    from b1 in the tangent plane (numpy's arctan2, cos and sin may differ from libm's in
    the last bit: the caller takes them), and ``good`` (mu and W usable). Numpy
    reference: that function's code."""
    for m in prange(len(k1)):
        X, Y, Z0, ok = _tilt(mu, W, max_tilt2, m)
        if ok:
            w11, w12, w21, w22 = W[m, 0, 0], W[m, 0, 1], W[m, 1, 0], W[m, 1, 1]
        else:
            w11, w12, w21, w22 = 0.0, 0.0, 0.0, 0.0
        s11, s12, s22, b1, b2 = _shape_operator(X, Y, Z0, w11, w12, w21, w22)
        mean = 0.5 * (s11 + s22)
        half = 0.5 * (s11 - s22)
        rad = math.hypot(half, s12)
        k1[m], k2[m] = mean + rad, mean - rad
        yx[m, 0], yx[m, 1] = s12, half
        _to_world(X, Y, Z0, t1, t2, z, m, normal)
        good[m] = ok


@njit(**OPTS, parallel=True)
def frame_directions(t1, t2, z, mu, good, c, s, e1, e2):
    """The principal directions e1 = c b1 + s b2, e2 = -s b1 + c b2 in world coordinates,
    (c, s) = (cos, sin) of the angle of :func:`frame_curvatures`."""
    for m in prange(len(c)):
        X, Y = (mu[m, 0], mu[m, 1]) if good[m] else (0.0, 0.0)
        _, _, _, b1, b2 = _shape_operator(X, Y, np.sqrt(1.0 - X * X - Y * Y), 0.0, 0.0, 0.0, 0.0)
        cm, sm = c[m], s[m]
        _to_world(cm * b1[0] + sm * b2[0], cm * b1[1] + sm * b2[1], cm * b1[2] + sm * b2[2], t1, t2, z, m, e1)
        _to_world(-sm * b1[0] + cm * b2[0], -sm * b1[1] + cm * b2[1], -sm * b1[2] + cm * b2[2], t1, t2, z, m, e2)


@njit(**OPTS)
def tangent_basis_of(n0, n1, n2):
    """(t1, t2) of :func:`core.linalg.tangent_basis` (Duff et al. 2017) for the unit normal
    (n0, n1, n2), the same operations in the same order."""
    sign = 1.0 if n2 >= 0.0 else -1.0
    a = -1.0 / (sign + n2)
    b = n0 * n1 * a
    return (1.0 + sign * (n0 * n0) * a, sign * b, -sign * n0), (b, sign + (n1 * n1) * a, -n1)


@njit(**OPTS)
def local_frames(normals, centres, z, t1, t2):
    """z = normals[centres] and the orthonormal (t1, t2) of :func:`core.linalg.tangent_basis`
    (Duff et al. 2017) in one loop, the same operations in the same order (numpy reference:
    that function), instead of some 20 temporary arrays per chunk."""
    for m in range(len(centres)):
        i = centres[m]
        n0, n1, n2 = normals[i, 0], normals[i, 1], normals[i, 2]
        z[m, 0], z[m, 1], z[m, 2] = n0, n1, n2
        (t1[m, 0], t1[m, 1], t1[m, 2]), (t2[m, 0], t2[m, 1], t2[m, 2]) = tangent_basis_of(n0, n1, n2)


@njit(**OPTS, parallel=True)
def intrinsic_frames(points, centres, z, idx, t1, t2):
    """Turn row r's (t1, t2) about its normal z[r] so that t1 points along the sum of the
    offsets from point ``centres[r]`` to its neighbours (row r of ``idx``, the point first)
    projected on its tangent plane, t2 = z x t1: a frame that turns with the cloud, where
    :func:`local_frames` is fixed to the world's axes. Rows whose projected sum vanishes
    against the offsets' own length (a symmetric neighbourhood) keep the frame given."""
    for r in prange(len(centres)):
        i = centres[r]
        n0, n1, n2 = z[r, 0], z[r, 1], z[r, 2]
        sx = sy = sz = total = 0.0
        for j in range(1, idx.shape[1]):
            q = idx[r, j]
            dx, dy, dz = points[q, 0] - points[i, 0], points[q, 1] - points[i, 1], points[q, 2] - points[i, 2]
            sx += dx
            sy += dy
            sz += dz
            total += math.sqrt(dx * dx + dy * dy + dz * dz)
        d = sx * n0 + sy * n1 + sz * n2
        sx, sy, sz = sx - d * n0, sy - d * n1, sz - d * n2
        length = math.sqrt(sx * sx + sy * sy + sz * sz)
        if not length > 1e-9 * total:
            continue
        a0, a1, a2 = sx / length, sy / length, sz / length
        t1[r, 0], t1[r, 1], t1[r, 2] = a0, a1, a2
        t2[r, 0], t2[r, 1], t2[r, 2] = n1 * a2 - n2 * a1, n2 * a0 - n0 * a2, n0 * a1 - n1 * a0
