"""Compiled loop of :func:`core.orientation.resettle`: flipped patches re-decided by their seam."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._base import OPTS as _OPTS
from .union_find import mask_roots


@njit(**_OPTS)
def _same_face(points, normals, sign, i, j, min_cos, max_tilt):
    """Whether i and j lie on one smooth face with the same sign: their signed normals
    within acos(``min_cos``) and the chord between them within ``max_tilt`` (sine) of both
    tangent planes (so a chain of such pairs does not turn round a rim)."""
    nn = sign[i] * sign[j] * (normals[i, 0] * normals[j, 0] + normals[i, 1] * normals[j, 1]
                              + normals[i, 2] * normals[j, 2])
    if nn <= min_cos:
        return False
    cx, cy, cz = points[j, 0] - points[i, 0], points[j, 1] - points[i, 1], points[j, 2] - points[i, 2]
    reach = max_tilt * np.sqrt(cx * cx + cy * cy + cz * cz)
    ti = abs(normals[i, 0] * cx + normals[i, 1] * cy + normals[i, 2] * cz)
    tj = abs(normals[j, 0] * cx + normals[j, 1] * cy + normals[j, 2] * cz)
    return ti <= reach and tj <= reach


@njit(**_OPTS, parallel=True)
def _patches(points, normals, idx, ok, sign, min_cos, max_tilt):
    """Each point's patch (the lowest index in it): :func:`_same_face` pairs of the graph
    ``idx`` joined transitively, and the number of ``ok`` points in each. The pairs are tested
    and joined in parallel (:func:`core.kernels.union_find.mask_roots`: the same parts and roots
    on any number of threads)."""
    n, k = idx.shape
    face = np.zeros((n, k), dtype=np.bool_)
    for i in prange(n):
        if ok[i]:
            for m in range(k):
                j = idx[i, m]
                face[i, m] = j != i and ok[j] and _same_face(points, normals, sign, i, j, min_cos, max_tilt)
    parent = mask_roots(idx, face)
    size = np.zeros(n, dtype=np.int64)
    for i in range(n):
        size[parent[i]] += ok[i]
    return parent, size


@njit(**_OPTS)
def flip_patches(points, normals, idx, ok, sign, evidence, min_cos, max_tilt, max_size):
    """Split the points into patches (:func:`_patches`), sum each patch's ``evidence`` over
    the edges that leave it (signed by ``sign``), and flip (in ``sign``) every patch of at
    most ``max_size`` points whose sum is negative: its seam with the rest disagrees with
    it. Returns how many points flipped."""
    n, k = idx.shape
    patch, size = _patches(points, normals, idx, ok, sign, min_cos, max_tilt)
    seam = np.zeros(n)
    for i in range(n):
        if ok[i] and size[patch[i]] <= max_size:  # a larger patch stays as it is: its seam is not read
            for m in range(k):
                j = idx[i, m]
                if patch[j] != patch[i]:
                    seam[patch[i]] += sign[i] * sign[j] * evidence[i, m]
    flipped = 0
    for i in range(n):
        if ok[i] and size[patch[i]] <= max_size and seam[patch[i]] < 0.0:
            sign[i] = -sign[i]
            flipped += 1
    return flipped
