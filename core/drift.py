"""Where a refinement pass drifts: the curvatures of the pass before (k="auto", issue 15).

NR's pass p + 1 refits the normal field to the normals of pass p. Where the field is
smooth over the fit's reach, a pass removes noise and the next one changes the curvature
by a share of that, with no relation to it (the noise left is smaller and unlike the
last); where the curvature varies within the reach (the tight rounded edges of a rounded
cube, a chirp's tightening ridges), every pass smooths the curvature profile again: the
crest's H falls and the flanks' rises pass after pass, so the next pass *repeats* the
change of this one. The pass-stop rule (:class:`core.passes.PassRule`) judges the whole
cloud by its mean turn of the normals and keeps the pass; here each point judges what the
pass did to its H, pooled over its :data:`DRIFT_POOL` nearest (a point's own changes are
noise): the share r = sum(dH_p dH_(p+1)) / sum(dH_p^2) that the undone pass p + 1
repeats. Where r > :data:`DRIFT_SHARE` the kept pass's change of H was drift too, and the
point reports the curvatures k1, k2 of the pass before; its normal and principal
directions stay the kept pass's (the drift spreads a curvature across an edge, which
changes its size more than its direction: the passes are what make e1 good, README).

Measured on 6000-point races (`python -m core bench holdout`, per-pass fits dumped): on
the rounded cube at 0.1-0.5 spacing the first fit's H is 0.88-0.95x the best peer's and the
kept pass's 1.11-1.32x; on the torus, paraboloid and saddle the pooled r is ~0.0-0.1 (a
pass after the kept one is noise there), on the cube 0.4-0.6, on the chirp ~0.35-0.7.
"""

from __future__ import annotations

import numpy as np

from .kernels import pool as pool_kernels
from .stages import Fit
from .tuning import DRIFT_POOL, DRIFT_SHARE


def _mean_curvature(fit: Fit, ref: np.ndarray) -> np.ndarray:
    """H of ``fit`` with the sign of the normals ``ref`` (NaN where not valid)."""
    with np.errstate(invalid="ignore"):
        turned = np.einsum("ij,ij->i", fit.normals, ref) < 0
    h = 0.5 * (fit.k1 + fit.k2)
    return np.where(fit.valid, np.where(turned, -h, h), np.nan)


def drifted(before: Fit, kept: Fit, after: Fit, idx: np.ndarray) -> np.ndarray:
    """(N,) bool: where the change of H from ``before`` to ``kept`` is repeated by the
    change to ``after`` (the undone pass) in more than DRIFT_SHARE of its size, pooled
    over the rows of ``idx`` (N, >= DRIFT_POOL) (see the module)."""
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
