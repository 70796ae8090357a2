"""Classify points by the sign pattern of their principal curvatures.

elliptic (K > 0), hyperbolic (K < 0), parabolic (one principal curvature zero), planar (both
zero) and umbilic (k1 = k2, not zero). "Zero" is relative to the cloud's curvature scale, so
that the same thresholds read a sphere of radius 1 mm and of 1 km alike.
"""

from __future__ import annotations

import math

import numpy as np

from ._validate import check_result

#: type codes, in the order of :data:`TYPE_NAMES`; -1 marks invalid points
ELLIPTIC, HYPERBOLIC, PARABOLIC, PLANAR, UMBILIC = range(5)
INVALID = -1
TYPE_NAMES = ("elliptic", "hyperbolic", "parabolic", "planar", "umbilic")
#: one line each, for legends and guided examples
TYPE_TEXT = {
    "elliptic": "K > 0: the surface bends the same way in every direction (a cap or a cup)",
    "hyperbolic": "K < 0: it bends up one way and down the other (a saddle)",
    "parabolic": "K = 0, H != 0: flat in one direction only (a cylinder)",
    "planar": "k1 = k2 = 0: flat in every direction",
    "umbilic": "k1 = k2 != 0: every direction is principal (a sphere)",
}
#: a principal curvature is "zero" below this fraction of the curvature scale. At 0.1, the
#: estimates of 5000-point shapes at noise 0 and 0.1 spacing read the sphere and the cylinder
#: as umbilic / parabolic at > 95 % of their points and the torus as three bands.
ZERO = 0.1
#: k1 and k2 are "equal" when they differ by less than this fraction of their magnitude
EQUAL = 0.1


def curvature_scale(res) -> float:
    """The cloud's curvature scale: the median curvedness of its valid points, but at least
    1 / (the cloud's bounding-box diagonal), so that a plane's noise is not its scale. NaN
    when no point is valid: there is no curvature to scale (a cloud of identical points
    gave 1 / the smallest float, 4.5e307)."""
    ok = check_result(res).valid & np.isfinite(res.k1) & np.isfinite(res.k2)
    if not ok.any():
        return math.nan
    extent = np.ptp(res.points, axis=0)
    floor = 1.0 / max(math.hypot(*extent), np.finfo(float).tiny)  # hypot: no overflow at 1e300
    return max(float(np.median(res.curvedness[ok])), floor)


def point_types(res, *, zero: float = ZERO, equal: float = EQUAL, scale: float | None = None):
    """The type of each point of a :class:`core.CurvatureResult`.

    Parameters
    ----------
    res : CurvatureResult.
    zero : float in (0, 1), a curvature below ``zero * scale`` counts as zero.
    equal : float in (0, 1), ``|k1 - k2| < equal * max(|k1|, |k2|)`` counts as umbilic.
    scale : float > 0, the curvature scale (default :func:`curvature_scale`).

    Returns
    -------
    (N,) int8 array of codes: indices into :data:`TYPE_NAMES`, ``-1`` for invalid points.

    Examples
    --------
    >>> import core
    >>> s = core.shapes.cylinder(2000, seed=0)
    >>> res = core.estimate(s.points, s.normals, k=20)
    >>> types = core.point_types(res)
    >>> float((types[s.interior] == core.PARABOLIC).mean()) > 0.95
    True
    """
    check_result(res)
    for name, value in (("zero", zero), ("equal", equal)):
        if not (isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, (bool, np.bool_))
                and 0 < value < 1):
            raise ValueError(f"{name}={value!r} is invalid; must be a number in (0, 1)")
    if scale is None:
        scale = curvature_scale(res)
    elif not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale={scale!r} is invalid; must be a finite number > 0")
    return classify(res.k1, res.k2, res.valid, scale=scale, zero=zero, equal=equal)


def classify(k1, k2, valid, *, scale: float, zero: float = ZERO, equal: float = EQUAL):
    """Type codes for principal curvature arrays (see :func:`point_types`, which checks)."""
    k1, k2 = np.atleast_1d(np.asarray(k1, float)), np.atleast_1d(np.asarray(k2, float))
    ok = np.atleast_1d(np.asarray(valid, bool)) & np.isfinite(k1) & np.isfinite(k2)
    a1, a2 = np.abs(k1), np.abs(k2)
    flat1, flat2 = a1 < zero * scale, a2 < zero * scale
    out = np.where(k1 * k2 > 0, ELLIPTIC, HYPERBOLIC).astype(np.int8)
    out[flat1 ^ flat2] = PARABOLIC
    out[(np.abs(k1 - k2) < equal * np.maximum(a1, a2)) & ~(flat1 & flat2)] = UMBILIC
    out[flat1 & flat2] = PLANAR
    out[~ok] = INVALID
    return out
