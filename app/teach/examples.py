"""Guided examples: a synthetic shape, the overlays that make its point, where to look, and a
few lines of text for the class (registry; numpy only)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Example", "EXAMPLES", "OVERLAYS", "DEFAULT_OVERLAYS", "pick_for"]

#: overlay name -> menu / check-box text (drawn in this order)
OVERLAYS = {
    "frame": "Frame e1, e2, n and tangent plane",
    "surface": "Fitted local surface",
    "sections": "Normal sections and osculating circles",
    "dupin": "Dupin indicatrix",
    "normal_fit": "The normal fit (neighbours' normals, fitted field)",
    "lines": "Lines of curvature (e1 black, e2 green)",
    "types": "Point types (colours the cloud)",
}
DEFAULT_OVERLAYS = ("frame", "sections", "dupin")


@dataclass(frozen=True)
class Example:
    """One guided example.

    ``where`` picks the point to show: a function (points, normals) -> index.
    """

    title: str
    shape: str
    text: str
    overlays: tuple
    theta: float
    where: object


def _closest(target):
    return lambda pts, _n: int(np.argmin(np.linalg.norm(pts - np.asarray(target, dtype=float), axis=1)))


EXAMPLES = {
    "sphere": Example(
        "Sphere: every point is umbilic", "sphere",
        "On a sphere of radius R every normal section is a great circle: k_n(θ) = 1/R in every "
        "direction, so the Euler plot is flat, the Dupin indicatrix is a circle and e1, e2 are "
        "arbitrary. Lines of curvature are not defined (they stop at once). ∫K dA = 4π: χ = 2.",
        ("frame", "sections", "dupin", "lines"), 30.0, _closest([0.6, -0.6, 0.53])),
    "cylinder": Example(
        "Cylinder: parabolic, one straight line of curvature", "cylinder",
        "Around the axis the section is the cylinder's circle (k1 = 1/R); along the axis it is a "
        "straight line (k2 = 0): K = 0 everywhere, every point is parabolic and the Dupin "
        "indicatrix is a pair of parallel lines. The e2 lines of curvature are the straight rulings.",
        ("frame", "sections", "dupin", "lines"), 45.0, _closest([1.0, 0.0, 0.0])),
    "torus": Example(
        "Torus: elliptic, hyperbolic and parabolic points", "torus",
        "Outside, the torus bends away from its normal in every direction (elliptic, K > 0); "
        "inside it is a saddle (hyperbolic, K < 0); the top and bottom circles, where the two "
        "regions meet, are parabolic. The lines of curvature are the meridians and the "
        "parallels. Positive and negative curvature cancel: ∫K dA = 0, χ = 0.",
        ("frame", "dupin", "lines", "types"), 30.0, _closest([0.0, 1.0, 0.0])),  # the far inner wall, seen through the hole
    "saddle": Example(
        "Saddle: hyperbolic points", "saddle",
        "At the waist of this peanut-shaped surface the normal sections bend towards the normal "
        "in one direction and away from it in the other: k1 > 0 > k2. The Euler curve crosses "
        "zero at the asymptotic directions, where the Dupin hyperbolas have their asymptotes.",
        ("frame", "sections", "dupin"), 40.0, _closest([0.0, -0.96, 0.72])),  # the waist, towards the oblique view
}


def pick_for(example: Example, points, normals) -> int:
    """The point an example looks at."""
    return example.where(np.asarray(points, dtype=float), normals)
