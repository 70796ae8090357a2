"""The pass-stop rule of k="auto" (:func:`core.stages.refine`), judged on a sample.

NR's refinement passes average the noise of the normals further, and the turn a pass
gives them decays geometrically; a pass that turns them more than ``PASS_DECAY`` x the
pass before smooths the shape itself and is undone. The rule compares mean turns, so it
needs the pass only at a sample of the points: the pass is fitted there first, and at the
other points only if it is kept. An undone pass, which the rule computes on almost every
noisy cloud (measured: the 4th pass on 17 of 17 noisy tori, saddles and ellipsoids of
20k-1M points), then costs the sample rather than a whole fit.
"""

from __future__ import annotations

import numpy as np

from .tuning import RULE_SAMPLE


def rule_sample(n, size=RULE_SAMPLE) -> np.ndarray:
    """(n,) bool: the points the pass-stop rule is judged on, every (n / size)-th point
    (all of them when n <= size, so a small cloud is judged exactly as before). Evenly
    spread indices, not random ones: the same cloud gives the same sample on any machine
    and thread count, and a cloud in scan or spatial order is sampled all over."""
    mask = np.zeros(n, dtype=bool)
    m = min(n, size)
    if m:
        mask[np.arange(m) * n // m] = True
    return mask


def mean_turn_deg(a, b, mask) -> float:
    """Mean angle in degrees between the rows of unit vectors a and b where ``mask``
    (sign-free: a normal and its opposite have not turned); 0 where the mask is empty."""
    if not mask.any():
        return 0.0
    cos = np.abs(np.einsum("ij,ij->i", a[mask], b[mask]))
    return float(np.degrees(np.arccos(np.clip(cos, 0.0, 1.0))).mean())
