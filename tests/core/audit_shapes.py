"""Test helpers of the fifth input audit: surfaces and perturbations with exact truth.

Minimal surfaces (catenoid, helicoid) sampled area-uniformly from their parametrisations, with
the truth read from the first and second fundamental forms; clouds of small spheres a few
spacings in radius; a small sphere beside a large plane; holes punched into a sample; noise whose
level or direction varies (heteroscedastic, along the normal, tangential, along a world axis).
"""

from __future__ import annotations

import numpy as np

from core.noise import add_noise
from core.shapes import Sample, _ordered, _unit, plane, sphere

_H = 1e-4  # finite-difference step of the parametrisations' derivatives (4th order)


def _derivs(X, u, v):
    """X, X_u, X_v, X_uu, X_uv, X_vv of a vectorised parametrisation (4th-order differences)."""
    def d1(f, a, b, axis):
        da = _H if axis == 0 else 0.0
        db = 0.0 if axis == 0 else _H
        return (-f(a + 2 * da, b + 2 * db) + 8 * f(a + da, b + db) - 8 * f(a - da, b - db)
                + f(a - 2 * da, b - 2 * db)) / (12 * _H)
    xu = d1(X, u, v, 0)
    xv = d1(X, u, v, 1)
    xuu = d1(lambda a, b: d1(X, a, b, 0), u, v, 0)
    xuv = d1(lambda a, b: d1(X, a, b, 0), u, v, 1)
    xvv = d1(lambda a, b: d1(X, a, b, 1), u, v, 1)
    return X(u, v), xu, xv, xuu, xuv, xvv


def parametric(name, X, u_range, v_range, n, seed, *, flip=False, interior_margin=0.0, **params):
    """Area-uniform sample of X(u, v) with exact normals (X_u x X_v, or its opposite), k1 >= k2
    and directions (the eigenpairs of the shape operator, k = +1/R on an outward sphere)."""
    rng = np.random.default_rng(seed)
    cu = rng.uniform(*u_range, 20 * n)
    cv = rng.uniform(*v_range, 20 * n)
    _, xu, xv, *_ = _derivs(X, cu, cv)
    dA = np.linalg.norm(np.cross(xu, xv), axis=1)
    keep = rng.random(len(cu)) * dA.max() < dA
    u, v = cu[keep][:n], cv[keep][:n]
    if len(u) < n:
        raise ValueError("rejection sampling fell short")
    area = dA.mean() * (u_range[1] - u_range[0]) * (v_range[1] - v_range[0])
    p, xu, xv, xuu, xuv, xvv = _derivs(X, u, v)
    nrm = _unit(np.cross(xu, xv)) * (-1.0 if flip else 1.0)
    E, F, G = (np.einsum("ij,ij->i", a, b) for a, b in ((xu, xu), (xu, xv), (xv, xv)))
    L, M, N = (np.einsum("ij,ij->i", a, nrm) for a in (xuu, xuv, xvv))
    first = np.stack([np.stack([E, F], -1), np.stack([F, G], -1)], -2)
    second = np.stack([np.stack([L, M], -1), np.stack([M, N], -1)], -2)
    shape = -np.linalg.solve(first, second)  # dn = -I^-1 II in the (X_u, X_v) basis
    vals, vecs = np.linalg.eig(shape)
    vals, vecs = vals.real, vecs.real
    dirs = [_unit(vecs[:, 0, i, None] * xu + vecs[:, 1, i, None] * xv) for i in range(2)]
    margin_u = interior_margin * (u_range[1] - u_range[0])
    margin_v = interior_margin * (v_range[1] - v_range[0])
    interior = ((u > u_range[0] + margin_u) & (u < u_range[1] - margin_u)
                & (v > v_range[0] + margin_v) & (v < v_range[1] - margin_v))
    spacing = float(np.sqrt(area / n))
    return _ordered(nrm, vals[:, 0], vals[:, 1], dirs[0], dirs[1], p, name, interior,
                    spacing=spacing, **params)


def catenoid(n=12000, *, c=1.0, height=1.2, seed=0):
    """Catenoid r = c cosh(z / c), |z| <= height: H = 0, K = -1 / (c^2 cosh^4)."""
    def X(u, v):
        r = c * np.cosh(v / c)
        return np.stack([r * np.cos(u), r * np.sin(u), v], -1)
    # X_z x X_angle faces the axis: flipped outward
    return parametric("catenoid", lambda u, v: X(v, u), (-height, height), (0, 2 * np.pi), n,
                      seed, flip=True, interior_margin=0.1, c=c)


def helicoid(n=12000, *, c=0.5, radius=1.5, turns=1.0, seed=0):
    """Helicoid (v cos u, v sin u, c u), |v| <= radius: H = 0, K = -c^2 / (c^2 + v^2)^2."""
    def X(u, v):
        return np.stack([v * np.cos(u), v * np.sin(u), c * u], -1)
    return parametric("helicoid", X, (0, 2 * np.pi * turns), (-radius, radius), n, seed,
                      interior_margin=0.1, c=c)


def monkey_saddle(n=12000, *, a=0.6, size=2.0, seed=0):
    """z = a (x^3 - 3 x y^2): an umbilic (flat point, k1 = k2 = 0) at the origin."""
    def X(u, v):
        return np.stack([u, v, a * (u ** 3 - 3 * u * v ** 2)], -1)
    h = size / 2
    return parametric("monkey_saddle", X, (-h, h), (-h, h), n, seed, interior_margin=0.1)


def join(name, samples, **params):
    """One Sample of several; params["part"] is each point's sample index."""
    cat = {f: np.concatenate([getattr(s, f) for s in samples]) for f in
           ("points", "normals", "k1", "k2", "e1", "e2", "interior")}
    part = np.concatenate([np.full(len(s.points), i) for i, s in enumerate(samples)])
    return Sample(name, cat["points"], cat["normals"], cat["k1"], cat["k2"], cat["e1"], cat["e2"],
                  cat["interior"], {**params, "part": part})


def moved(sample, offset):
    """The sample translated by ``offset``."""
    return Sample(sample.name, sample.points + np.asarray(offset, float), sample.normals,
                  sample.k1, sample.k2, sample.e1, sample.e2, sample.interior, dict(sample.params))


def subset(sample, keep, name=None):
    """The sample's points where ``keep``."""
    params = {k: (v[keep] if isinstance(v, np.ndarray) and len(v) == len(keep) else v)
              for k, v in sample.params.items()}
    return Sample(name or sample.name, sample.points[keep], sample.normals[keep], sample.k1[keep],
                  sample.k2[keep], sample.e1[keep], sample.e2[keep], sample.interior[keep], params)


def small_spheres(n=12000, *, radius_spacings=3.0, seed=0):
    """Well separated spheres of ``radius_spacings`` spacings (ball bearings): each holds
    4 pi c^2 points at spacing 1 (113 at c = 3); radius 1 each, centres 6 radii apart."""
    per = max(int(round(4 * np.pi * radius_spacings ** 2)), 12)
    count = max(n // per, 1)
    rng = np.random.default_rng(seed)
    side = int(np.ceil(count ** (1 / 3)))
    parts = []
    for i in range(count):
        centre = 6.0 * np.array(np.unravel_index(i, (side,) * 3), float) + rng.uniform(-1, 1, 3)
        parts.append(moved(sphere(per, radius=1.0, seed=seed * 1000 + i), centre))
    return join("small_spheres", parts, spacing=1.0 / radius_spacings)


def plane_and_sphere(n=12000, *, radius_spacings=3.0, size=2.0, seed=0):
    """A large square plane and a small sphere of ``radius_spacings`` spacings hovering a
    diameter above its middle (one cloud, two scales)."""
    flat = plane(n, size=size, seed=seed)
    spacing = size / np.sqrt(n)
    r = radius_spacings * spacing
    per = max(int(round(4 * np.pi * radius_spacings ** 2)), 12)
    ball = moved(sphere(per, radius=r, seed=seed + 7), [0.0, 0.0, 3 * r])
    return join("plane_and_sphere", [flat, ball], spacing=spacing, radius=r)


def with_holes(sample, *, holes=8, radius_spacings=(3.0, 8.0), seed=0):
    """Remove discs (balls) of 3-8 spacings around random points; params["rim"] marks the
    points within 3 spacings of a removed ball."""
    rng = np.random.default_rng(seed)
    s = sample.params["spacing"]
    centres = sample.points[rng.choice(len(sample.points), holes, replace=False)]
    radii = rng.uniform(*radius_spacings, holes) * s
    d = np.linalg.norm(sample.points[:, None, :] - centres[None], axis=2) - radii[None]
    keep = (d > 0).all(axis=1)
    rim = (d < 3 * s).any(axis=1)
    out = subset(sample, keep, sample.name + "_holes")
    return Sample(out.name, out.points, out.normals, out.k1, out.k2, out.e1, out.e2, out.interior,
                  {**out.params, "rim": rim[keep], "kept": keep})


def hetero_noise(sample, low, high, *, axis=0, seed=0):
    """Isotropic noise whose sigma (in spacings) grows geometrically from ``low`` to ``high``
    along a world axis; params["sigma"] is each point's sigma in spacings."""
    x = sample.points[:, axis]
    t = (x - x.min()) / np.ptp(x)
    sigma = low * (high / low) ** t
    rng = np.random.default_rng(seed)
    pts = sample.points + rng.normal(size=sample.points.shape) * (sigma * sample.params["spacing"])[:, None]
    return pts, sigma


def directional_noise(sample, sigma, kind, *, seed=0):
    """Noise of ``sigma`` spacings: "normal" (along the true normal), "tangent" (isotropic in
    the tangent plane, sigma per axis), "z" (along the world z axis), or "iso"."""
    rng = np.random.default_rng(seed)
    s = sigma * sample.params["spacing"]
    n = len(sample.points)
    if kind == "iso":
        return add_noise(sample.points, s, relative=False, seed=seed)
    if kind == "normal":
        return sample.points + rng.normal(size=(n, 1)) * s * sample.normals
    if kind == "z":
        return sample.points + rng.normal(size=(n, 1)) * s * np.array([[0.0, 0.0, 1.0]])
    if kind == "tangent":
        g = rng.normal(size=(n, 2)) * s
        return sample.points + g[:, :1] * sample.e1 + g[:, 1:] * sample.e2
    raise ValueError(kind)


def spaced(sample, area):
    """The sample with params["spacing"] = sqrt(area / n)."""
    return Sample(sample.name, sample.points, sample.normals, sample.k1, sample.k2, sample.e1,
                  sample.e2, sample.interior,
                  {**sample.params, "spacing": float(np.sqrt(area / len(sample.points)))})
