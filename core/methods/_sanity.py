"""When a baseline's fit is meaningless by its own numbers: flag the point, never report it.

QN, CN and CF fit the neighbours' normals as slopes, -X/Z and -Y/Z: a neighbour whose normal
lies near the tangent plane of p (the far side of a hemisphere at k = 1500 on a 3000-point
sphere, a cube's other face, a PCA normal of a noisy blob) gives a slope of hundreds and the
fitted curvature follows it (|H| 1e3-1e5 reported valid: sphere k = 1500, or k = 15 at 0.5
spacing of noise on the torus, saddle, chirp and cube). Two tests, both on the fit's own numbers:

- :func:`turns_too_fast`: the fitted curvature times the neighbourhood's reach h (W is in
  units of 1/h). A surface that is a graph over the tangent plane out to a distance h bends
  at most by about sqrt(2)/h (a sphere's cap is a graph up to its equator, sqrt(2) R from
  the pole); above :data:`MAX_REACH_CURVATURE` the neighbourhood is not such a graph, or the
  fit followed junk. Measured at k = 15 (torus, saddle, chirp, cube faces): noise-free
  max |k| h <= 0.6 for every method, 3.0 at 0.2 spacing of noise (CN; NF and CT never pass 3.8
  even at 1 spacing).
- :func:`slopes_disagree`: the weighted RMS residual of the normal rows, in slope units (the
  tangent of the angle between a neighbour's normal and the fitted one). Above
  :data:`MAX_SLOPE_RESIDUAL` the quadric or cubic does not describe the normals: some of
  them lie near the tangent plane. Noise-free k = 15 fits leave < 0.01; a single neighbour
  normal 87 degrees off among 15 leaves ~3.
"""

from __future__ import annotations

import numpy as np

#: largest |k1|, |k2| times h (the distance to the farthest neighbour) a baseline reports
MAX_REACH_CURVATURE = 4.0
#: largest weighted RMS residual of the normal rows (slope units: tan of the angle) QN/CN/CF report
MAX_SLOPE_RESIDUAL = 1.0


def turns_too_fast(W: np.ndarray) -> np.ndarray:
    """(M,) True where the symmetric part of W (M, 2, 2), in units of 1/h, has an
    eigenvalue beyond :data:`MAX_REACH_CURVATURE` in magnitude (or is not finite)."""
    a, c = W[:, 0, 0], W[:, 1, 1]
    b = 0.5 * (W[:, 0, 1] + W[:, 1, 0])
    with np.errstate(invalid="ignore", over="ignore"):
        top = np.abs(0.5 * (a + c)) + np.hypot(0.5 * (a - c), b)  # the largest |eigenvalue|
        return ~(top <= MAX_REACH_CURVATURE)


def slopes_disagree(A: np.ndarray, y: np.ndarray, wt: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(M,) True where the weighted RMS of ``A @ x - y`` over rows of weight > 0 (the normal
    rows: slope targets -X/Z, -Y/Z) exceeds :data:`MAX_SLOPE_RESIDUAL`, or is not finite."""
    with np.errstate(invalid="ignore", over="ignore"):
        r = np.einsum("mip,mp->mi", A, x) - y
        r = np.where(wt > 0, r, 0.0)
        total = np.maximum(np.einsum("mi->m", wt), 1e-300)
        rms = np.sqrt(np.einsum("mi,mi,mi->m", wt, r, r) / total)
        return ~(rms <= MAX_SLOPE_RESIDUAL)


def judged(ok: np.ndarray, W: np.ndarray, *residual_tests) -> np.ndarray:
    """``ok`` where no test says the fit is meaningless: :func:`turns_too_fast` on W and
    each ``(A, y, wt, x)`` of ``residual_tests`` by :func:`slopes_disagree`."""
    bad = turns_too_fast(W)
    for test in residual_tests:
        bad |= slopes_disagree(*test)
    return ok & ~bad
