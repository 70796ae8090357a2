"""Where the first refinement pass drifts: the first fit's curvatures (k="auto", issue 15).

NR's pass p + 1 refits the normal field to the normals of pass p. Where the field is
smooth over the fit's reach, the 1st pass removes the first fit's noise and the 2nd
changes H by a share of that with no relation to it; where the curvature varies within
the reach (the tight rounded edges of a rounded cube, a chirp's tightening ridges), every
pass smooths the curvature profile again: the crest's H falls and the flanks' rises pass
after pass, so the 2nd pass *repeats* the change of the 1st. The pass-stop rule
(:class:`core.passes.PassRule`) judges the whole cloud by its mean turn of the normals;
when it keeps one pass and undoes the 2nd, each point here judges what the passes did to
its H, pooled over its :data:`DRIFT_POOL` nearest (a point's own changes are noise): the
share r = sum(dH_1 dH_2) / sum(dH_1^2) that the 2nd pass repeats. Where r >
:data:`DRIFT_SHARE` the 1st pass's change of H was drift, and the point reports the
curvatures k1, k2 of the first fit; its normal and principal directions stay the pass's
(the drift spreads a curvature across an edge, which changes its size more than its
direction, and the pass is what makes e1 good: README). Only the 1st pass is judged: the
noise a pass leaves is smooth over the fit, so later passes remove it in a repeating
pattern too (:data:`DRIFT_SHARE`).

Measured on the 6000-point races (`python -m core bench holdout`, per-pass fits dumped):
on the rounded cube at 0.1-0.5 spacing the first fit's H is 0.88-0.95x the best peer's and
the 1st pass's 1.11-1.32x; the pooled r is ~0.0-0.1 on the torus, paraboloid and saddle,
0.4-0.6 on the cube and 0.35-0.7 on the chirp.
"""

from __future__ import annotations

import numpy as np

from .kernels import pool as pool_kernels
from .fits import Fit
from .tuning import DRIFT_POOL, DRIFT_SHARE


def _mean_curvature(fit: Fit, ref: np.ndarray) -> np.ndarray:
    """H of ``fit`` with the sign of the normals ``ref`` (NaN where not valid)."""
    with np.errstate(invalid="ignore"):
        turned = np.einsum("ij,ij->i", fit.normals, ref) < 0
    h = 0.5 * (fit.k1 + fit.k2)
    return np.where(fit.valid, np.where(turned, -h, h), np.nan)


def drifted(before: Fit, kept: Fit, after: Fit, idx: np.ndarray) -> np.ndarray:
    """(N,) bool: where the change of H from ``before`` (the first fit) to ``kept`` (the
    1st pass) is repeated by the change to ``after`` (the undone 2nd pass) in more than
    DRIFT_SHARE of its size, pooled over the rows of ``idx`` (N, >= DRIFT_POOL)."""
    h0, h1, h2 = (_mean_curvature(f, kept.normals) for f in (before, kept, after))
    a, b = h1 - h0, h2 - h1
    pool = np.ascontiguousarray(idx[:, :DRIFT_POOL])
    both, square = np.empty(len(a)), np.empty(len(a))
    with np.errstate(invalid="ignore"):
        pool_kernels.pooled_nanmeans(np.ascontiguousarray(a * b), np.ascontiguousarray(a * a), pool, both, square)
        return kept.valid & before.valid & (both > DRIFT_SHARE * square)


def step_back(before: Fit, kept: Fit, after: Fit, idx: np.ndarray) -> Fit:
    """``kept`` with the curvatures of ``before`` (turned to ``kept``'s normals) where the
    refinement drifted (:func:`drifted`); new arrays, the fits are not changed."""
    back = drifted(before, kept, after, idx)
    if not back.any():
        return kept
    with np.errstate(invalid="ignore"):
        turned = np.einsum("ij,ij->i", before.normals, kept.normals) < 0
    k1 = np.where(turned, -before.k2, before.k1)
    k2 = np.where(turned, -before.k1, before.k2)
    return kept._replace(k1=np.where(back, k1, kept.k1), k2=np.where(back, k2, kept.k2))
