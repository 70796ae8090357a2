"""Sampling anisotropy: scanner stripes told apart from surface structure.

A line scanner samples densely along each scan line and sparsely across the lines; the
estimate's neighbourhoods then reach far along a line and little across it, and the
stripe pattern shows in H. The neighbourhood's own shape does not
show it (the k nearest reach across to the next lines and look round again); the
directions to each point's *nearest* neighbours do: on a stripe scan they all run along
the lines. For each point, the unit directions from its :data:`ANISO_K` neighbours to their
first and second nearest neighbours, projected on its tangent plane, give the tensor
T = sum u u^T; the **anisotropy** is 1 - lambda_min / lambda_max of T: near 0 where
nearest neighbours lie in every direction (a random sampling), near 1 where they lie
along one line (scan lines, or any sampling much denser one way than the other).
Structure does not move it: a ridge sampled evenly has nearest neighbours all around.
"""

from __future__ import annotations

import numpy as np

from .duplicates import find_duplicates
from .kernels import anisotropy as kern
from .neighbours import build_neighbours

#: neighbours per point (the point itself included) whose nearest-neighbour directions are
#: pooled: 2 x 15 directions keep a random sampling's tensor near isotropic
ANISO_K = 15
#: nearest neighbours per point whose directions count, weighted by how nearly they tie
#: with the nearest (TIE: relative distance at which the weight falls to 1/e)
NEAREST = 4
TIE = 0.2
#: a point is "striped" when its anisotropy exceeds this. Measured (20k points, k = 15,
#: tests/core/test_anisotropy.py): uniform random samplings of a plane, sphere and cylinder,
#: noise-free and at 0.2 spacing: median 0.33, 99th percentile 0.67-0.68, 0.02-0.07 % above;
#: scan lines 1.5x / 2x / 3x wider apart than the along-line spacing: 89 % / 100 % / 100 %
#: above (96 % for 3x at noise 0.2 spacing, 37 % for 1.2x); a square grid with 5 % jitter
#: (near ties between its four nearest): 7 % above
STRIPED = 0.8


def anisotropy(points, normals, idx):
    """Per-point sampling anisotropy in [0, 1] (see the module doc).

    Parameters
    ----------
    points : (N, 3) float array.
    normals : (N, 3) unit normals (sign irrelevant); NaN rows give NaN.
    idx : (N, K) int neighbour indices sorted by distance, the point first (K > NEAREST); the
        first :data:`ANISO_K` are pooled.

    Returns
    -------
    (N,) float array, NaN where there is no normal.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    nrm = np.ascontiguousarray(normals, dtype=np.float64)
    idx = np.asarray(idx)
    if idx.ndim != 2 or idx.shape[1] < NEAREST + 1:
        raise ValueError(f"idx must hold at least {NEAREST + 1} neighbours per point (the point first), "
                         f"got shape {idx.shape}")
    nearest = _nearest_directions(pts, idx)
    out = np.empty(len(pts))
    kern.direction_anisotropy(nearest, nrm, np.ascontiguousarray(idx[:, :ANISO_K]), out)
    return out


def _nearest_directions(pts, idx):
    """(N, NEAREST, 3): each point's directions to its NEAREST nearest neighbours, each
    scaled by the square root of its tie weight exp(-((d / d_1 - 1) / TIE)^2) (so that the
    tensor counts the weight once): on a square grid the four equally near neighbours
    count alike, on scan lines the across-line ones, farther, hardly count."""
    out = np.empty((len(pts), NEAREST, 3))
    kern.nearest_directions(pts, np.ascontiguousarray(idx), TIE, out)
    return out


def striped(values):
    """Points whose anisotropy exceeds :data:`STRIPED` (False where it is NaN)."""
    return np.nan_to_num(np.asarray(values, dtype=float), nan=0.0) > STRIPED


def anisotropy_of(points, normals, nb):
    """:func:`anisotropy` with :data:`ANISO_K` neighbours from ``nb`` (a
    :class:`core.Neighbours`), or from a search of their own when it holds fewer (or is None)."""
    k = min(ANISO_K, len(points))
    if k < NEAREST + 1 or not np.isfinite(normals).any():  # no normal (a degenerate cloud): all NaN, and
        return np.full(len(points), np.nan)  # no search (coordinates of 1e300 overflow the kd-tree)
    if nb is not None and nb.k_max >= k:
        return anisotropy(points, normals, nb.take(k)[0])
    merged = find_duplicates(np.ascontiguousarray(points, dtype=np.float64))
    if merged is not None:  # copies are one place (core.duplicates), sampled once
        return anisotropy_of(merged.points, np.asarray(normals)[merged.first], None)[merged.inverse]
    return anisotropy(points, normals, build_neighbours(points, k).take(k)[0])
