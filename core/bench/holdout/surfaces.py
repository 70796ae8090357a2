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


# ----------------------------------------------------------------------------- a third, private check set
def _waves(x, y):
    a, b, u, v = 0.15, 0.08, 3.0, 5.0  # two crossed waves of different wavelength and height
    s, c, t, d = np.sin(u * x + 1.0), np.cos(u * x + 1.0), np.cos(v * y), np.sin(v * y)
    return (a * s + b * t, a * u * c, -b * v * d, -a * u * u * s, 0 * x, -b * v * v * t)


def _swell(x, y):
    a, b = 0.3, 0.2  # a skewed product of sines plus a twist: directions rotate across the patch
    s, c, t, d = np.sin(2 * x), np.cos(2 * x), np.sin(1.5 * y), np.cos(1.5 * y)
    return (a * s * t + b * x * y, 2 * a * c * t + b * y, 1.5 * a * s * d + b * x, -4 * a * s * t,
            3 * a * c * d + b, -2.25 * a * s * t)


def _dimple(x, y):
    a = 0.6  # a saddle damped by a Gaussian: curvature and anisotropy both fade outwards
    g = np.exp(-(x * x + y * y))
    q = x * x - y * y
    fx, fy = a * g * (2 * x - 2 * x * q), a * g * (-2 * y - 2 * y * q)
    fxx = a * g * (2 - 2 * q - 4 * x * x - 2 * x * (2 * x - 2 * x * q))
    fyy = a * g * (-2 - 2 * q + 4 * y * y - 2 * y * (-2 * y - 2 * y * q))
    fxy = a * g * (4 * x * y - 2 * y * (2 * x - 2 * x * q))
    return a * g * q, fx, fy, fxx, fxy, fyy


def wobble(n, seed):
    """x^2 + y^2 + z^2 + 0.9 xyz = 1: a sphere pushed out into four lobes and in at four others."""
    a = 0.9
    F = lambda p: (p * p).sum(1) + a * p[:, 0] * p[:, 1] * p[:, 2] - 1.0  # noqa: E731

    def grad(p):
        x, y, z = p.T
        return 2 * p + a * np.column_stack([y * z, x * z, x * y])

    def hess(p):
        x, y, z = p.T
        h = np.zeros((len(p), 3, 3))
        h[:, 0, 0] = h[:, 1, 1] = h[:, 2, 2] = 2.0
        h[:, 0, 1] = h[:, 1, 0] = a * z
        h[:, 0, 2] = h[:, 2, 0] = a * y
        h[:, 1, 2] = h[:, 2, 1] = a * x
        return h

    return _implicit_sample("wobble", F, grad, hess, n, np.random.default_rng(seed), 1.6)


#: name -> sampler(n, seed): a private check of a mechanism before it meets the hold-out set
#: (neither tuned on nor part of the issue's score)
PRIVATE = {
    "waves": _graph("waves", _waves),
    "swell": _graph("swell", _swell),
    "dimple": _graph("dimple", _dimple),
    "wobble": wobble,
}
SETS = {"holdout": HOLDOUT, "tuning": TUNING, "private": PRIVATE}
