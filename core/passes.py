"""The pass-stop rule of k="auto" (:func:`core.refinement.refine`), judged on a sample.

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

from .tuning import PASS_DECAY, PASS_MIN_SHARE, RULE_SAMPLE


def rule_sample(points, n_total=None, size=RULE_SAMPLE) -> np.ndarray:
    """(len(points),) bool: the points the pass-stop rule is judged on, about ``size`` of a
    cloud of ``n_total`` points (default: ``len(points)``); all of them when ``n_total <=
    size``, so a small cloud is judged exactly as before. A point is in the sample when a
    hash of its coordinates' bits falls below ``size / n_total`` of the hash range: the
    same point is in or out whatever the order of the points, the machine or the thread
    count, and whichever tile of a tiled run (:mod:`core.tiled.auto`) holds it; the
    sample is spread over the whole cloud like a random one."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    n_total = len(points) if n_total is None else int(n_total)
    if n_total <= size:
        return np.ones(len(points), dtype=bool)
    bits = (points + 0.0).view(np.uint64).reshape(len(points), 3)  # + 0.0: -0.0 hashes as 0.0
    h = mix64(bits[:, 0] ^ mix64(bits[:, 1] ^ mix64(bits[:, 2])))
    return h < np.uint64(int(size / n_total * 2.0**64))


def mix64(x: np.ndarray) -> np.ndarray:
    """splitmix64's finaliser: every input bit moves every output bit (wrapping uint64)."""
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def turn_angles(a, b, mask) -> np.ndarray:
    """Angles (degrees, sign-blind: a normal and its opposite have not turned) between the
    rows of unit vectors ``a`` and ``b`` where ``mask``; their mean is a pass's change (a
    tiled run sums them over its tiles)."""
    cos = np.abs(np.einsum("ij,ij->i", a[mask], b[mask]))
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


def mean_turn_deg(a, b, mask) -> float:
    """Mean of :func:`turn_angles` where ``mask``; 0 where the mask is empty."""
    if not mask.any():
        return 0.0
    return float(turn_angles(a, b, mask).mean())


class PassRule:
    """When :func:`core.refinement.refine` keeps a pass and stops, from each fit's mean turn of the
    normals (a whole-cloud mean: a tiled run reduces it over the tiles and replays this
    rule). ``n_fits``: fits at most (1 when NR fits too few points with noise)."""

    def __init__(self, plan, few: bool):
        self.plan, self.n_fits = plan, 1 if few else plan.passes + 1
        self.measures = plan.adaptive or plan.tol is not None
        self.last = None
        self.converged = False

    def step(self, p: int, change) -> tuple[bool, bool]:
        """(keep fit ``p``, compute another): undo and stop at a pass that smoothed the shape."""
        if self.plan.adaptive and self.last is not None and change > PASS_DECAY * self.last:
            return False, False
        self.last = change
        # converged: a refinement pass (not the first fit, which replaces the initial normals) moved less than tol
        self.converged = self.plan.tol is not None and p >= 1 and change < self.plan.tol
        return True, p + 1 < self.n_fits and not self.converged


def few_fits(share: float, plan) -> bool:
    """Whether NR fits too few points with noise for refinement passes: ``share`` of all
    points have a normal and noise (not ``Scale.quiet``), below PASS_MIN_SHARE."""
    return bool(plan.auto and share < PASS_MIN_SHARE)
