"""Analytic surfaces with exact normals, principal curvatures and directions.

Every sampler returns a :class:`Sample` with outward normals (k = +1/R on a sphere),
area-uniform random points and a reproducible ``seed``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._validate import check_int
from .linalg import symmetric_eig2


@dataclass(frozen=True, eq=False)
class Sample:
    """Points on an analytic surface with their exact differential geometry.

    ``interior`` marks points at least a few spacings away from a boundary (open
    surfaces: plane, cylinder); metrics are computed there.
    """

    name: str
    points: np.ndarray
    normals: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    interior: np.ndarray
    params: dict = field(default_factory=dict)

    @property
    def gaussian(self):
        return self.k1 * self.k2

    @property
    def mean(self):
        return 0.5 * (self.k1 + self.k2)


def _rng_n(n, seed):
    n = check_int(n, name="n", low=10)
    return n, np.random.default_rng(seed)


def _unit(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _ordered(n, ka, kb, ea, eb, points, name, interior=None, **params):
    """Build a Sample with k1 >= k2 whatever order the formulas gave."""
    swap = kb > ka
    k1, k2 = np.where(swap, kb, ka), np.where(swap, ka, kb)
    e1 = np.where(swap[:, None], eb, ea)
    e2 = np.where(swap[:, None], ea, eb)
    if interior is None:
        interior = np.ones(len(points), dtype=bool)
    return Sample(name, points, n, k1, k2, _unit(e1), _unit(e2), interior, params)


def plane(n=5000, *, size=2.0, seed=0):
    """The square [-size/2, size/2]^2 in z = 0, normal +z, k1 = k2 = 0."""
    n, rng = _rng_n(n, seed)
    xy = (rng.random((n, 2)) - 0.5) * size
    pts = np.column_stack([xy, np.zeros(n)])
    ones, zeros = np.ones(n), np.zeros(n)
    nrm = np.column_stack([zeros, zeros, ones])
    ex = np.column_stack([ones, zeros, zeros])
    ey = np.column_stack([zeros, ones, zeros])
    margin = 0.1 * size
    interior = (np.abs(xy) < size / 2 - margin).all(axis=1)
    return _ordered(nrm, zeros, zeros, ex, ey, pts, "plane", interior, size=size)


def sphere(n=5000, *, radius=1.0, seed=0):
    """Sphere of the given radius at the origin: k1 = k2 = 1/radius (umbilic everywhere)."""
    n, rng = _rng_n(n, seed)
    nrm = _unit(rng.normal(size=(n, 3)))
    pts = radius * nrm
    ea = _unit(np.cross(nrm, np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])))
    eb = np.cross(nrm, ea)
    k = np.full(n, 1.0 / radius)
    return _ordered(nrm, k, k, ea, eb, pts, "sphere", radius=radius)


def cylinder(n=5000, *, radius=1.0, height=4.0, seed=0):
    """Open cylinder around the z axis: k1 = 1/radius around it, k2 = 0 along the axis (e2 = z)."""
    n, rng = _rng_n(n, seed)
    phi = rng.random(n) * 2 * np.pi
    z = (rng.random(n) - 0.5) * height
    c, s = np.cos(phi), np.sin(phi)
    zeros, ones = np.zeros(n), np.ones(n)
    pts = np.column_stack([radius * c, radius * s, z])
    nrm = np.column_stack([c, s, zeros])
    around = np.column_stack([-s, c, zeros])
    axis = np.column_stack([zeros, zeros, ones])
    interior = np.abs(z) < height / 2 - 0.15 * height
    return _ordered(nrm, np.full(n, 1 / radius), zeros, around, axis, pts, "cylinder", interior,
                    radius=radius, height=height)


def torus(n=5000, *, R=2.0, r=1.0, seed=0):
    """The paper's torus (R = 2, r = 1), area-uniform (density ∝ R + r cos θ), SPEC ground truth."""
    n, rng = _rng_n(n, seed)
    if not (R > r > 0):
        raise ValueError(f"torus needs R > r > 0, got R={R}, r={r}")
    theta = np.empty(0)
    while len(theta) < n:  # rejection sampling of θ with density ∝ R + r cos θ
        t = rng.random(2 * n) * 2 * np.pi
        keep = rng.random(2 * n) * (R + r) < R + r * np.cos(t)
        theta = np.concatenate([theta, t[keep]])
    theta = theta[:n]
    phi = rng.random(n) * 2 * np.pi
    ct, st, cp, sp = np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    rho = R + r * ct
    pts = np.column_stack([rho * cp, rho * sp, r * st])
    nrm = np.column_stack([ct * cp, ct * sp, st])
    tube = np.column_stack([-st * cp, -st * sp, ct])
    ring = np.column_stack([-sp, cp, np.zeros(n)])
    return _ordered(nrm, np.full(n, 1.0 / r), ct / rho, tube, ring, pts, "torus", R=R, r=r)


def cube(n=6000, *, size=2.0, seed=0):
    """The surface of an axis-aligned cube: flat faces (k1 = k2 = 0) meeting at sharp edges.

    ``interior`` marks points at least 10 % of the edge length away from every edge; the
    edges themselves have no curvature to compare with (a crease), only a flag to expect.
    """
    n, rng = _rng_n(n, seed)
    face = rng.integers(0, 6, n)
    axis, sign = face // 2, np.where(face % 2 == 0, 1.0, -1.0)
    pts = (rng.random((n, 3)) - 0.5) * size
    pts[np.arange(n), axis] = sign * size / 2
    nrm = np.zeros((n, 3))
    nrm[np.arange(n), axis] = sign
    ea = np.zeros((n, 3))
    ea[np.arange(n), (axis + 1) % 3] = 1.0
    eb = np.cross(nrm, ea)
    in_face = np.abs(pts) < size / 2 * (1 - 1e-12)
    edge_dist = np.where(in_face, size / 2 - np.abs(pts), np.inf).min(axis=1)
    zeros = np.zeros(n)
    return _ordered(nrm, zeros, zeros, ea, eb, pts, "cube", edge_dist > 0.1 * size, size=size)


# ----------------------------------------------------------------------------- implicit
def _implicit_sample(name, F, grad, hess, n, rng, r_max, **params):
    """Area-uniform samples of a star-shaped implicit surface F = 0 (F < 0 inside).

    Directions are drawn uniformly, the radius found by bisection along each ray, and
    samples kept with probability ∝ dA/dω = r^2 / (n . ω) (rejection sampling).
    Curvatures are exact: dn = P Hess(F) P / |grad F| on the tangent plane.
    """
    out = []
    total = 0
    while total < n:
        m = 4 * n
        w = _unit(rng.normal(size=(m, 3)))
        lo, hi = np.zeros(m), np.full(m, r_max)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            inside = F(mid[:, None] * w) < 0
            lo, hi = np.where(inside, mid, lo), np.where(inside, hi, mid)
        r = 0.5 * (lo + hi)
        p = r[:, None] * w
        nrm = _unit(grad(p))
        dens = r**2 / np.einsum("ij,ij->i", nrm, w)
        keep = rng.random(m) * (r_max**2 / np.min(np.einsum("ij,ij->i", nrm, w)) + 1e-12) < dens
        out.append(p[keep])
        total += int(keep.sum())
    pts = np.concatenate(out)[:n]
    g = grad(pts)
    gn = np.linalg.norm(g, axis=1)
    nrm = g / gn[:, None]
    t1 = _unit(np.cross(nrm, np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])))
    t2 = np.cross(nrm, t1)
    H = hess(pts) / gn[:, None, None]
    a = np.einsum("mi,mij,mj->m", t1, H, t1)
    b = np.einsum("mi,mij,mj->m", t1, H, t2)
    c = np.einsum("mi,mij,mj->m", t2, H, t2)
    k1, k2, cs, sn = symmetric_eig2(a, b, c)
    e1 = cs[:, None] * t1 + sn[:, None] * t2
    e2 = -sn[:, None] * t1 + cs[:, None] * t2
    return _ordered(nrm, k1, k2, e1, e2, pts, name, **params)


def ellipsoid(n=5000, *, axes=(1.5, 1.0, 0.75), seed=0):
    """Ellipsoid x²/a² + y²/b² + z²/c² = 1 (four umbilics when a > b > c)."""
    n, rng = _rng_n(n, seed)
    inv = 1.0 / np.asarray(axes, dtype=float) ** 2
    F = lambda p: (p * p) @ inv - 1.0  # noqa: E731
    grad = lambda p: 2 * p * inv  # noqa: E731
    hess = lambda p: np.broadcast_to(np.diag(2 * inv), (len(p), 3, 3))  # noqa: E731
    return _implicit_sample("ellipsoid", F, grad, hess, n, rng, 1.01 * max(axes), axes=tuple(axes))


def saddle(n=5000, *, a=1.0, b=1.2, seed=0):
    """A closed surface with saddles: the Cassini "peanut" |p - a x̂|^2 |p + a x̂|^2 = b^4.

    For a < b < sqrt(2) a it is one closed surface of revolution about the x axis: two
    convex lobes (K > 0) joined by a waist where it is saddle-shaped (K < 0). It stands
    in for Goldfeather & Interrante's test surface, which the paper does not define.
    """
    n, rng = _rng_n(n, seed)
    if not a < b < np.sqrt(2) * a:
        raise ValueError(f"saddle needs a < b < sqrt(2) a, got a={a}, b={b}")
    ex = np.array([a, 0.0, 0.0])

    def F(p):
        return ((p - ex) ** 2).sum(1) * ((p + ex) ** 2).sum(1) - b**4

    def grad(p):
        A, B = ((p - ex) ** 2).sum(1), ((p + ex) ** 2).sum(1)
        return 2 * (p - ex) * B[:, None] + 2 * (p + ex) * A[:, None]

    def hess(p):
        A, B = ((p - ex) ** 2).sum(1), ((p + ex) ** 2).sum(1)
        ga, gb = 2 * (p - ex), 2 * (p + ex)
        outer = np.einsum("mi,mj->mij", ga, gb)
        return outer + outer.transpose(0, 2, 1) + 2 * (A + B)[:, None, None] * np.eye(3)

    r_max = 1.05 * np.sqrt(a * a + b * b)
    return _implicit_sample("saddle", F, grad, hess, n, rng, r_max, a=a, b=b)


#: shape name -> sampler(n, *, seed)
SHAPES = {
    "torus": torus,
    "sphere": sphere,
    "cylinder": cylinder,
    "plane": plane,
    "saddle": saddle,
    "ellipsoid": ellipsoid,
    "cube": cube,
}
