"""The fits of :mod:`core.anchors` read at the points that follow anchors and averaged, in
one compiled loop (numpy reference: :func:`core.anchor_blend.blended_reference`)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from ._base import BLOCK, LEAF, OPTS
from .border import _sort_small
from .frame import _shape_operator, tangent_basis_of
from .kdtree import _distance


@njit(**OPTS, inline="always")
def _read(pts, p, a, q, coef, frame, h, project, out):
    """out[0:2] = mu, out[2:6] = W (row-major, units of 1/h): the cubic polynomials of anchor
    row q (point a) read at point p's offset in its frame, W projected onto eq. 22's plane
    when ``project``."""
    hq = h[q]
    d0, d1, d2 = (pts[p, 0] - pts[a, 0]) / hq, (pts[p, 1] - pts[a, 1]) / hq, (pts[p, 2] - pts[a, 2]) / hq
    u = d0 * frame[q, 0, 0] + d1 * frame[q, 0, 1] + d2 * frame[q, 0, 2]
    v = d0 * frame[q, 1, 0] + d1 * frame[q, 1, 1] + d2 * frame[q, 1, 2]
    uu, uv, vv = u * u, u * v, v * v
    for c in range(2):
        k = coef[q, c]
        out[c] = k[0] + k[1] * u + k[2] * v + k[3] * uu + k[4] * uv + k[5] * vv + k[6] * uu * u + k[7] * uu * v \
            + k[8] * u * vv + k[9] * vv * v
        out[2 + 2 * c] = (k[1] + 2.0 * k[3] * u + k[4] * v + 3.0 * k[6] * uu + 2.0 * k[7] * uv + k[8] * vv) / hq
        out[3 + 2 * c] = (k[2] + k[4] * u + 2.0 * k[5] * v + k[7] * uu + 2.0 * k[8] * uv + 3.0 * k[9] * vv) / hq
    if project:  # §4.4: the Euclidean projection onto g . w = 0, as the NF kernel does at a centre
        X, Y = out[0], out[1]
        g1, g2, g3, g4 = X * Y, -(1.0 - Y * Y), 1.0 - X * X, -X * Y
        t = (g1 * out[2] + g2 * out[3] + g3 * out[4] + g4 * out[5]) / (g1 * g1 + g2 * g2 + g3 * g3 + g4 * g4)
        out[2] -= t * g1
        out[3] -= t * g2
        out[4] -= t * g3
        out[5] -= t * g4


class AnchorFits(NamedTuple):
    """The anchors' fits (:class:`core.anchors.Kept`): ``row`` (N,) each point's row (-1: not
    an anchor), per row ``coef`` (., 2, 10), ``frame`` (., 3, 3) = (t1, t2, z), ``h``, ``ok``."""

    row: np.ndarray
    coef: np.ndarray
    frame: np.ndarray
    h: np.ndarray
    ok: np.ndarray


class Blended(NamedTuple):
    """What :func:`blend` writes per follower: ``normal``, ``k1`` >= ``k2``, ``e1``, ``e2``."""

    normal: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    e1: np.ndarray
    e2: np.ndarray


@njit(**LEAF)
def _offsets(pts, p, nrm, picked, m, x, y, d2):
    """The offsets from point p of its anchors ``picked[m]`` in its tangent plane (x, y) and
    squared distances d2; returns the number of anchors and the largest distance (1 without anchors)."""
    t1, t2 = tangent_basis_of(nrm[p, 0], nrm[p, 1], nrm[p, 2])
    count, far = 0, 0.0
    for b in range(picked.shape[1]):
        a = picked[m, b]
        if a < 0:
            continue
        count += 1
        e0, e1, e2 = pts[a, 0] - pts[p, 0], pts[a, 1] - pts[p, 1], pts[a, 2] - pts[p, 2]
        x[b] = e0 * t1[0] + e1 * t1[1] + e2 * t1[2]
        y[b] = e0 * t2[0] + e1 * t2[1] + e2 * t2[2]
        d2[b] = e0 * e0 + e1 * e1 + e2 * e2
        far = max(far, d2[b])
    return count, math.sqrt(far) if far > 0.0 else 1.0


@njit(**LEAF)
def _weights(pts, p, nrm, picked, m, w, floor, xyd):
    """w[0:B] = the affine weights of :func:`core.anchor_blend.affine_weights` for point p
    and its anchors ``picked[m]`` (none below ``-floor``, else inverse squared distances);
    ``xyd`` (3, B) scratch."""
    B = picked.shape[1]
    x, y, d2 = xyd[0], xyd[1], xyd[2]
    for b in range(B):
        x[b] = y[b] = d2[b] = 0.0
    count, s = _offsets(pts, p, nrm, picked, m, x, y, d2)
    m00 = m01 = m02 = m11 = m12 = m22 = 0.0
    for b in range(B):
        xb, yb, on = x[b] / s, y[b] / s, 1.0 if picked[m, b] >= 0 else 0.0
        m00 += on
        m01 += xb
        m02 += yb
        m11 += xb * xb
        m12 += xb * yb
        m22 += yb * yb
    c00, c01, c02 = m11 * m22 - m12 * m12, m02 * m12 - m01 * m22, m01 * m12 - m02 * m11  # first column of adj(M)
    det = m00 * c00 + m01 * c01 + m02 * c02
    affine = count >= 3 and abs(det) > 1e-6
    for b in range(B):
        w[b] = (c00 + c01 * x[b] / s + c02 * y[b] / s) / det if affine and picked[m, b] >= 0 else 0.0
        affine = affine and w[b] >= -floor
    if not affine:  # inverse squared distances, normalised (w.sum()'s order: the same bits)
        total = 0.0
        for b in range(B):
            w[b] = (1.0 / d2[b] if d2[b] > 0.0 else 1.0) if picked[m, b] >= 0 else 0.0
            total += w[b]
        for b in range(B):
            w[b] /= total


@njit(**LEAF)
def _accumulate(pts, nrm, p, picked, m, w, fits, project, max_tilt2, N, S, vecs):
    """N += w_b n_b, S += w_b (the shape operator in world coordinates) over the anchors
    ``picked[m]`` of point p, each turned to the side of p's own normal ``nrm[p]`` (the result
    keeps the sign p came with, as a fit of its own does); False if a fit read is not
    usable there. ``vecs`` (5, 6) scratch."""
    val, n, u1, u2 = vecs[0], vecs[1, :3], vecs[2, :3], vecs[3, :3]
    own0, own1, own2 = nrm[p, 0], nrm[p, 1], nrm[p, 2]
    for b in range(picked.shape[1]):
        a = picked[m, b]
        if a < 0:
            continue
        q = fits.row[a]
        _read(pts, p, a, q, fits.coef, fits.frame, fits.h, project, val)
        X, Y = val[0], val[1]
        tilt2 = X * X + Y * Y
        if not (fits.ok[q] and _finite(val) and tilt2 < max_tilt2):
            return False
        Z0 = math.sqrt(1.0 - tilt2)
        s11, s12, s22, b1, b2 = _shape_operator(X, Y, Z0, val[2], val[3], val[4], val[5])
        f = fits.frame[q]
        for i in range(3):
            n[i] = X * f[0, i] + Y * f[1, i] + Z0 * f[2, i]
            u1[i] = b1[0] * f[0, i] + b1[1] * f[1, i] + b1[2] * f[2, i]
            u2[i] = b2[0] * f[0, i] + b2[1] * f[1, i] + b2[2] * f[2, i]
        wb = w[b] if n[0] * own0 + n[1] * own1 + n[2] * own2 >= 0.0 else -w[b]
        for i in range(3):
            N[i] += wb * n[i]
            for j in range(3):
                S[i, j] += wb * (s11 * u1[i] * u1[j] + s12 * (u1[i] * u2[j] + u2[i] * u1[j]) + s22 * u2[i] * u2[j])
    return True


@njit(**OPTS, inline="always")
def _finite(a):
    """Whether every value of ``a`` is finite (np.isfinite(a).all() allocates)."""
    for i in range(len(a)):
        if not math.isfinite(a[i]):
            return False
    return True


@njit(**LEAF)
def _principal(N, S, out, m):
    """out's row m: the unit normal along N and the principal curvatures and directions of
    S in its tangent plane (e1 x e2 = normal); False where N vanishes."""
    length = math.sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2])
    if not length > 0.0:
        return False
    n0, n1, n2 = N[0] / length, N[1] / length, N[2] / length
    t1, t2 = tangent_basis_of(n0, n1, n2)
    a11 = a12 = a22 = 0.0
    for i in range(3):
        for j in range(3):
            a11 += t1[i] * S[i, j] * t1[j]
            a12 += t1[i] * S[i, j] * t2[j]
            a22 += t2[i] * S[i, j] * t2[j]
    mean, half = 0.5 * (a11 + a22), 0.5 * (a11 - a22)
    rad = math.hypot(half, a12)
    phi = 0.5 * math.atan2(a12, half)
    c, s = math.cos(phi), math.sin(phi)
    out.k1[m], out.k2[m] = mean + rad, mean - rad
    out.normal[m, 0], out.normal[m, 1], out.normal[m, 2] = n0, n1, n2
    for i in range(3):
        out.e1[m, i] = c * t1[i] + s * t2[i]
        out.e2[m, i] = -s * t1[i] + c * t2[i]
    return True


@njit(**OPTS, parallel=True)
def blend(pts, nrm, points, picked, fits, project, max_tilt2, floor, out, good):
    """Follower m (point ``points[m]``) from the :class:`AnchorFits` ``fits`` of its anchors
    ``picked[m]``: each read at its offset (:func:`_read`), turned into a normal and a shape
    operator in world coordinates (the augmented Darboux frame of :mod:`core.kernels.frame`),
    averaged with the affine weights (:func:`_weights`) and diagonalised in the averaged
    normal's tangent plane, into the :class:`Blended` ``out``; ``good[m]``: every anchor read
    usable. Scratch arrays are allocated once per block of followers (per follower, their
    eleven allocations cost more than the arithmetic) and handed to :func:`_blend_block`."""
    n_blocks = (len(points) + BLOCK - 1) // BLOCK
    for blk in prange(n_blocks):
        B = picked.shape[1]
        scratch = (np.empty(B), np.empty(3), np.empty((3, 3)), np.empty((3, B)), np.empty((5, 6)))
        _blend_block(pts, nrm, points, picked, fits, (project, max_tilt2, floor), out, good,
                     blk * BLOCK, min(len(points), (blk + 1) * BLOCK), scratch)


@njit(**LEAF)
def _blend_block(pts, nrm, points, picked, fits, settings, out, good, start, stop, scratch):
    """Followers start..stop-1 of :func:`blend` (``settings`` = its project, max_tilt2,
    floor), compiled without reference counting (:data:`~core.kernels._base.LEAF`: it and
    its helpers allocate nothing; each call of a helper otherwise counts every array and
    record it passes, per follower)."""
    project, max_tilt2, floor = settings
    w, N, S, xyd, vecs = scratch
    for m in range(start, stop):
        p = points[m]
        for i in range(3):
            N[i] = 0.0
            for j in range(3):
                S[i, j] = 0.0
        _weights(pts, p, nrm, picked, m, w, floor, xyd)
        fine = _accumulate(pts, nrm, p, picked, m, w, fits, project, max_tilt2, N, S, vecs)
        if fine:
            fine = _principal(N, S, out, m)
        good[m] = fine


@njit(**OPTS, parallel=True)
def anchors_among(near, prio, m, allowed, out):
    """``out[i]``: ``allowed[i]`` and point i's priority above those of its ``m[i]``
    nearest (``near[i, 1:m[i] + 1]``). Numpy reference: :func:`core.anchors.assign`'s rival
    test, ``prio > where(columns <= m, prio[near[:, 1:]], 0).max(1)``."""
    for i in prange(len(m)):
        top = np.uint64(0)
        for c in range(1, m[i] + 1):
            top = max(top, prio[near[i, c]])
        out[i] = allowed[i] and prio[i] > top


@njit(**OPTS, parallel=True)
def first_anchors(near, rows, is_anchor, kc, reach, picked):
    """``picked[r]``: the first ``picked.shape[1]`` anchors of the same k among the ``reach``
    nearest of point ``rows[r]`` (``near[rows[r], 1:reach + 1]``), in their order, -1 past the
    last. Numpy reference: a stable argsort of ~ok per row (1M points: 0.8 s)."""
    blend = picked.shape[1]
    for r in prange(len(rows)):
        i = rows[r]
        m = 0
        for c in range(1, reach + 1):
            if m == blend:
                break
            q = near[i, c]
            if is_anchor[q] and kc[q] == kc[i]:
                picked[r, m] = q
                m += 1
        for b in range(m, blend):
            picked[r, b] = -1


@njit(**OPTS, parallel=True)
def priorities(pts, near, ratios, salt, out):
    """:func:`core.anchors.priority`'s hash per point, in one pass over the rows (numpy over
    (N, RATIOS) arrays spent 0.4 s of a 1M-point estimate on its temporaries): the distances
    to ``near[i, 1:ratios + 1]`` as the search computes them (:func:`core.kernels.kdtree._distance`,
    numpy's norm sums the squares in the same order), sorted, divided by the largest, rounded
    to 2^-20 and mixed (splitmix64's finaliser, :func:`core.passes.mix64`) from ``salt``."""
    n = len(out)
    for blk in prange((n + BLOCK - 1) // BLOCK):
        d = np.empty(ratios)
        for i in range(blk * BLOCK, min(n, (blk + 1) * BLOCK)):
            for c in range(ratios):
                d[c] = _distance(pts, near[i, c + 1], i)
            _sort_small(d)
            top = d[ratios - 1] if d[ratios - 1] > 0.0 else 1.0
            h = np.uint64(salt)
            for c in range(ratios - 1):
                h = _mix64(h ^ np.uint64(np.rint(d[c] / top * 2.0**20)))
            out[i] = h | np.uint64(1)


@njit(**OPTS, inline="always")
def _mix64(x):
    """:func:`core.passes.mix64` of one uint64 (wrapping)."""
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))
