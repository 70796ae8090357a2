"""Which points take a nearby centre's wide normal fit instead of their own
(:mod:`core.shared_fits`): a greedy pass in the points' (spatial) order."""

from __future__ import annotations

import math
from typing import NamedTuple

from numba import njit, prange

from ._base import OPTS

#: centre_of codes besides a centre's index
OWN, CENTRE = -1, -2


class Blend(NamedTuple):
    """How satellites' normals are blended (:func:`blend_normals`)."""

    reach: float
    k_ratio: float
    cos_min: float


@njit(**OPTS)
def assign_satellites(idx, dist, kc, h, eligible, nrm, reach, k_ratio, cos_min, centre_of):
    """Greedy, in index order: an ``eligible`` point not yet taken becomes a centre
    (``centre_of`` = CENTRE) and takes as satellites (``centre_of`` = its index) its
    neighbours in ``idx`` that are eligible, not yet taken, within ``reach`` x ``h`` of it,
    whose size ``kc`` is within a factor ``k_ratio`` of its own and whose normal ``nrm``
    agrees with its own (cosine >= ``cos_min``: not the far side of a fold). Points that
    are not eligible keep OWN. Sequential, so the result does not depend on threads."""
    n, m = idx.shape
    for i in range(n):
        if not eligible[i] or centre_of[i] != OWN:
            continue
        centre_of[i] = CENTRE
        lim = reach * h[i]
        for a in range(1, m):
            if dist[i, a] > lim:
                break
            j = idx[i, a]
            if not eligible[j] or centre_of[j] != OWN:
                continue
            if kc[j] * k_ratio < kc[i] or kc[j] > kc[i] * k_ratio:
                continue
            cos = nrm[i, 0] * nrm[j, 0] + nrm[i, 1] * nrm[j, 1] + nrm[i, 2] * nrm[j, 2]
            if cos >= cos_min:
                centre_of[j] = i


@njit(**OPTS, inline="always")
def _poly(c, t, u, v):
    """The polynomial with coefficients c[:t] at (u, v), monomials in
    :func:`core.kernels.algebra.poly_row`'s order (degree <= 3)."""
    s = c[0]
    if t > 1:
        s += c[1] * u + c[2] * v
    if t > 3:
        s += c[3] * u * u + c[4] * u * v + c[5] * v * v
    if t > 6:
        s += ((c[6] * u + c[7] * v) * u + c[8] * v * v) * u + c[9] * v * v * v
    return s


@njit(**OPTS, parallel=True)
def blend_normals(pts, idx, dist, kc, h, row, coef, frames, sats, ref, opt, out):
    """out[a] = the normal of satellite ``sats[a]`` blended from the fitted normal fields of
    every centre c among its neighbours ``idx`` (``row[c]`` >= 0: its ``coef`` and
    ``frames`` (t1, t2, z) rows) within ``opt.reach`` x h[c] of it, of a size within
    ``opt.k_ratio`` of its own and agreeing with its normal ``ref`` (cosine >=
    ``opt.cos_min``), weighted by (1 - (d / reach h[c])^2)^2; ``ref`` where none is."""
    t = coef.shape[2]
    for a in prange(len(sats)):
        j = sats[a]
        sx = sy = sz = 0.0
        for b in range(idx.shape[1]):
            c = idx[j, b]
            r = row[c]
            reach = opt.reach * h[c]
            if r < 0 or dist[j, b] >= reach or kc[j] * opt.k_ratio < kc[c] or kc[j] > kc[c] * opt.k_ratio:
                continue
            f = frames[r]
            dx, dy, dz = pts[j, 0] - pts[c, 0], pts[j, 1] - pts[c, 1], pts[j, 2] - pts[c, 2]
            u = (dx * f[0, 0] + dy * f[0, 1] + dz * f[0, 2]) / h[c]
            v = (dx * f[1, 0] + dy * f[1, 1] + dz * f[1, 2]) / h[c]
            X, Y = _poly(coef[r, 0], t, u, v), _poly(coef[r, 1], t, u, v)
            Z = math.sqrt(max(1.0 - X * X - Y * Y, 0.0))
            nx, ny, nz = X * f[0, 0] + Y * f[1, 0] + Z * f[2, 0], X * f[0, 1] + Y * f[1, 1] + Z * f[2, 1], \
                X * f[0, 2] + Y * f[1, 2] + Z * f[2, 2]
            if nx * ref[j, 0] + ny * ref[j, 1] + nz * ref[j, 2] < opt.cos_min:
                continue
            q = 1.0 - (dist[j, b] / reach) ** 2
            sx, sy, sz = sx + q * q * nx, sy + q * q * ny, sz + q * q * nz
        norm = math.sqrt(sx * sx + sy * sy + sz * sz)
        for e, s in enumerate((sx, sy, sz)):
            out[a, e] = s / norm if norm > 0.0 else ref[j, e]
