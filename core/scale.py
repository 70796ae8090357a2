"""Automatic neighbourhood size: ``k="auto"`` picks k per point by a bias–variance rule.

Small neighbourhoods give unbiased but noisy normal derivatives; large ones average the
noise away but the model of the normal field bends over a curved patch: the bias of W
is O(h) for the linear model of eq. 23 (O(h^2) on a symmetric neighbourhood) and O(h^3)
for the cubic one "auto" uses, which is why "auto" can go up to 226 neighbours. The
rule is the *intersection of confidence intervals* (ICI; Goldenshluger & Nemirovski 1997, Katkovnik 1999): fit NF at increasing k, each giving the
Weingarten entries (W11, (W12 + W21)/2, W22) with their least-squares standard
deviations s_k. While the intervals [W_k - G s_k, W_k + G s_k] of all scales so far
still intersect, the larger k only removes noise; the first k whose interval leaves the
common intersection shows bias, and the previous k is kept. Noise sets s_k, curvature
sets the bias, and both are read from the data: nothing is tuned per shape. k also stops
growing where a ring of new neighbours folds over (see :mod:`core.kernels.scale`): past the far
side of a thin part the residuals explode and would hide the bias from the intervals.
A fold is judged against the smallest neighbourhood (its centroid, mean normal and noise
height), not the centre alone, and must persist into the next ring: with noise of a whole
spacing, a test on the centre's own noisy normal stopped a quarter of the points at 20."""

from __future__ import annotations

import numpy as np

from . import kernels
from .patch import Chunk
from .tuning import (AUTO_DEGREE, AUTO_KS, FOLD_COS, FOLD_FRACTION, FOLD_MIN_BAD, FOLD_NOISE, GAMMA,
                     INITIAL_K0, NEIGHBOUR_BUDGET, RCOND)

__all__ = ["AUTO_DEGREE", "AUTO_KS", "GAMMA", "INITIAL_K0", "NEIGHBOUR_BUDGET", "candidates", "choose_k",
           "noise_ratio", "initial_k"]

_CHUNK = 32_768


def candidates(n_points: int) -> tuple[int, ...]:
    """The candidate k that a cloud of ``n_points`` allows (and the memory budget)."""
    cap = min(n_points, max(AUTO_KS[0], NEIGHBOUR_BUDGET // max(n_points, 1)))
    ks = tuple(k for k in AUTO_KS if k <= cap)
    return ks or (n_points,)


def choose_k(points, normals, nb, has_normal, ks, degree, report):
    """Per-point k by ICI over ``ks`` (ascending); returns (N,) int (ks[0] where no normal)."""
    n = len(points)
    idx_all, dist_all = nb.take(ks[-1])
    chosen = np.full(n, ks[0], dtype=np.int64)
    usable = np.flatnonzero(has_normal & (dist_all[:, -1] > 0))
    ks_arr = np.asarray(ks, dtype=np.int64)
    rule = kernels.ScaleRule(degree, GAMMA, RCOND, FOLD_FRACTION, FOLD_COS, FOLD_NOISE, FOLD_MIN_BAD)
    for start in range(0, len(usable), _CHUNK):
        centres = usable[start:start + _CHUNK]
        chunk = Chunk.build(points, normals, idx_all[centres], dist_all[centres, -1], centres)
        out = np.empty(len(centres), dtype=np.int64)
        kernels.choose_scales(chunk.frames(), ks_arr, rule, out)
        chosen[centres] = out
        report(min(len(usable), start + _CHUNK) / max(len(usable), 1), "choosing k")
    return chosen


def noise_ratio(height, h) -> float:
    """The cloud's noise as a fraction of the neighbourhood radius: median of
    ``height / h`` (jet residual over the radius of its neighbours), NaN-free."""
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = height / h
    ratio = ratio[np.isfinite(ratio)]
    return float(np.median(ratio)) if len(ratio) else 0.0


def initial_k(noise: float, k_min: int, k_max: int) -> int:
    """Neighbours for the initial normals at a measured ``noise_ratio`` (see :data:`core.tuning.INITIAL_K0`)."""
    k = int(round(INITIAL_K0 * np.sqrt(max(noise, 0.0))))
    return int(min(max(k, k_min), max(k_max, k_min)))
