"""The hold-out surfaces: analytic, exact truth, and NOT in :mod:`core.shapes` (the automatic
scale is never tuned on them), plus the tuning set it may be tuned on.

Graphs z = f(x, y) over [-1, 1]^2 (each terrain returns f and its first and second
derivatives; borders within 0.15 of the square are left out of the metrics) and two closed
implicit surfaces (curvature from the Hessian of F, :func:`core.shapes._implicit_frame`).
"""

from __future__ import annotations

import numpy as np

from ... import shapes
from ...shapes import _graph_sample, _implicit_sample


def _monkey(x, y):
    a = 0.4
    return (a * (x**3 - 3 * x * y * y), a * (3 * x * x - 3 * y * y), a * (-6 * x * y), a * 6 * x, a * -6 * y,
            a * -6 * x)


def _bump(x, y):
    s2 = 0.25
    g = 0.6 * np.exp(-(x * x + y * y) / (2 * s2))
    gx, gy = -x / s2, -y / s2
    return g, g * gx, g * gy, g * (gx * gx - 1 / s2), g * gx * gy, g * (gy * gy - 1 / s2)


def _eggcrate(x, y):
    a, w = 0.12, 4.0
    sx, cx, sy, cy = np.sin(w * x), np.cos(w * x), np.sin(w * y), np.cos(w * y)
    return (a * sx * sy, a * w * cx * sy, a * w * sx * cy, -a * w * w * sx * sy, a * w * w * cx * cy,
            -a * w * w * sx * sy)


def _paraboloid(x, y):
    a, b, z = 0.8, 0.3, 0 * x
    return a * x * x + b * y * y, 2 * a * x, 2 * b * y, 2 * a + z, z, 2 * b + z


def _ridge(x, y):
    a, w, z = 0.4, 1.8, 0 * y
    return (a * np.cos(w * x) + z, -a * w * np.sin(w * x) + z, z, -a * w * w * np.cos(w * x) + z, z, z)


def _graph(name, terrain):
    return lambda n, seed: _graph_sample(name, terrain, n, np.random.default_rng(seed))


def roundcube(n, seed):
    """The superellipsoid x^4 + y^4 + z^4 = 1: flat faces, tight rounded edges and corners."""
    F = lambda p: (p**4).sum(1) - 1.0  # noqa: E731
    grad = lambda p: 4 * p**3  # noqa: E731
    hess = lambda p: np.einsum("mi,ij->mij", 12 * p * p, np.eye(3))  # noqa: E731
    return _implicit_sample("roundcube", F, grad, hess, n, np.random.default_rng(seed), 1.01 * 3**0.5)


def capsule(n, seed):
    """(x / 1.6)^4 + y^2 + z^2 = 1: a cylinder-like middle with rounded caps."""
    c = 1.6**4
    F = lambda p: p[:, 0] ** 4 / c + p[:, 1] ** 2 + p[:, 2] ** 2 - 1.0  # noqa: E731
    grad = lambda p: np.column_stack([4 * p[:, 0] ** 3 / c, 2 * p[:, 1], 2 * p[:, 2]])  # noqa: E731

    def hess(p):
        h = np.zeros((len(p), 3, 3))
        h[:, 0, 0], h[:, 1, 1], h[:, 2, 2] = 12 * p[:, 0] ** 2 / c, 2.0, 2.0
        return h

    return _implicit_sample("capsule", F, grad, hess, n, np.random.default_rng(seed), 1.7)


#: name -> sampler(n, seed): surfaces the rule is never tuned on
HOLDOUT = {
    "monkey": _graph("monkey", _monkey),
    "bump": _graph("bump", _bump),
    "eggcrate": _graph("eggcrate", _eggcrate),
    "paraboloid": _graph("paraboloid", _paraboloid),
    "ridge": _graph("ridge", _ridge),
    "roundcube": roundcube,
    "capsule": capsule,
}
#: name -> sampler(n, seed): the core.shapes families the rule may be tuned on
TUNING = {
    "torus": lambda n, seed: shapes.torus(n, seed=seed),
    "saddle": lambda n, seed: shapes.saddle(n, seed=seed),
    "ellipsoid": lambda n, seed: shapes.ellipsoid(n, seed=seed),
    "chirp": lambda n, seed: shapes.chirp(n, seed=seed),
    "graded": lambda n, seed: shapes.graded(n, seed=seed),
    "range_scan": lambda n, seed: shapes.range_scan(n, seed=seed),
}
SETS = {"holdout": HOLDOUT, "tuning": TUNING}
