"""Creases: points where the neighbours' normals turn a lot but not linearly (a step).

Judged on a fit's residuals (:class:`core.stages.Residuals`) by :func:`core.stages.flags`;
:func:`crease_residuals` keeps what the same test needs with another typical residual
(a tiled run judges every tile's points against the whole cloud's median).
"""

from __future__ import annotations

import numpy as np

from .tuning import CREASE_NOISE, CREASE_RATIO, CREASE_SPREAD


def judge_creases(valid, rms, spread, typical=None):
    """Points where the neighbours' normals turn a lot but not linearly (a step: a crease).

    On a smooth patch the linear model of eq. 23 explains the turning of the normals and
    the residual is a small part of it; across a sharp edge the normals jump and a line
    explains only part of the jump. Noise leaves residuals everywhere: a crease must also
    stand out against the cloud's typical residual (its median, unless ``typical`` is
    given: creases are a minority of the points), or a noisy scan would be flagged all
    over. Returns (crease (N,) bool, the typical residual used).
    """
    if typical is None:
        seen = rms[valid & np.isfinite(rms)]  # methods without a normal fit report no residual
        typical = float(np.median(seen)) if len(seen) else 0.0
    return _crease_shaped(valid, rms, spread) & (rms > CREASE_NOISE * typical), typical


def _crease_shaped(valid, rms, spread):
    """The tests of a crease that do not depend on the cloud's typical residual."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return valid & (spread > CREASE_SPREAD) & (rms / spread > CREASE_RATIO)


def crease_residuals(judged) -> np.ndarray:
    """Per point, what the crease test of another typical residual needs (a tiled run fixes
    the whole cloud's): the residual where ``judged`` (valid, rms, spread) is valid and finite (NaN elsewhere),
    negated where the other tests fail; ``crease = valid & (r > CREASE_NOISE * typical)``
    and the typical is the median of ``abs(r)`` over its finite values. A crease's residual
    is > 0 (its ratio to a spread > 0 exceeds CREASE_RATIO), so -0.0 never passes."""
    valid, rms = judged.valid & np.isfinite(judged.rms), judged.rms
    return np.where(valid, np.where(_crease_shaped(valid, rms, judged.spread), rms, -rms), np.nan)
