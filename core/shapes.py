"""Analytic surfaces with exact normals, principal curvatures and directions.

Every sampler returns a :class:`Sample` with outward normals (k = +1/R on a sphere),
area-uniform random points and a reproducible ``seed``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

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
    return _implicit_frame(name, pts, grad, hess, **params)


def _implicit_frame(name, pts, grad, hess, **params):
    """Exact frame of points on F = 0 with normal grad F / |grad F|: dn = P Hess(F) P / |grad F|."""
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


# ----------------------------------------------------------------------------- graphs z = f(x, y)
def _graph_frame(name, xy, terrain, interior, **params):
    """Exact frame on the graph of ``terrain`` (upward normal; F = z - f, see _implicit_frame)."""
    f, fx, fy, fxx, fxy, fyy = terrain(xy[:, 0], xy[:, 1])
    zeros, ones = np.zeros(len(xy)), np.ones(len(xy))
    grad = lambda p: np.column_stack([-fx, -fy, ones])  # noqa: E731
    hess = lambda p: -np.stack([np.column_stack([fxx, fxy, zeros]), np.column_stack([fxy, fyy, zeros]),  # noqa: E731
                                np.zeros((len(p), 3))], axis=1)
    return _implicit_frame(name, np.column_stack([xy, f]), grad, hess, interior=interior, **params)


def _graph_sample(name, terrain, n, rng, margin=0.15, **params):
    """Area-uniform points on the graph over [-1, 1]^2 (rejection by sqrt(1 + |grad f|^2)).

    ``interior``: more than ``margin`` from the square's border (open-patch borders are
    left out of the metrics, as for the plane).
    """
    grid = np.linspace(-1, 1, 201)
    gx, gy = np.meshgrid(grid, grid)
    _, fx, fy, *_ = terrain(gx.ravel(), gy.ravel())
    top = 1.05 * np.sqrt(1 + fx**2 + fy**2).max()
    kept = np.empty((0, 2))
    while len(kept) < n:
        xy = rng.uniform(-1, 1, (4 * n, 2))
        _, fx, fy, *_ = terrain(xy[:, 0], xy[:, 1])
        kept = np.concatenate([kept, xy[rng.random(4 * n) * top < np.sqrt(1 + fx**2 + fy**2)]])
    xy = kept[:n]
    return _graph_frame(name, xy, terrain, (np.abs(xy) < 1 - margin).all(axis=1), **params)


def chirp(n=6000, *, amplitude=0.1, seed=0):
    """Fast-varying curvature: z = A sin(phi(x)) cos(3 y), phi(x) = 2 (x+1) + 1.75 (x+1)^2.

    The ridges tighten along x (wavelength ~3 at x = -1, ~0.7 at x = 1), so |k1| ranges
    from 0 to about 8 over a patch of side 2: no single neighbourhood size suits it.
    """
    n, rng = _rng_n(n, seed)

    def terrain(x, y):
        s = x + 1
        ph, d1, d2 = 2 * s + 1.75 * s * s, 2 + 3.5 * s, 3.5
        sp, cp, cy, sy = np.sin(ph), np.cos(ph), np.cos(3 * y), np.sin(3 * y)
        a = amplitude
        return (a * sp * cy, a * cp * d1 * cy, -3 * a * sp * sy,
                a * (cp * d2 - sp * d1 * d1) * cy, -3 * a * cp * d1 * sy, -9 * a * sp * cy)

    return _graph_sample("chirp", terrain, n, rng, amplitude=amplitude)


def graded(n=6000, *, ratio=10.0, width=0.1, seed=0):
    """The saddle (Cassini peanut) sampled ``ratio``:1 more densely on its x > 0 lobe.

    Density ∝ 1 + (ratio - 1) / (1 + exp(-x / width)) per unit area: a 10:1 change across
    a band of a few ``width`` around the waist, where the K < 0 region is. Truth as for
    :func:`saddle`; the k nearest neighbours of points in the sparse half next to the
    dense one are lopsided.
    """
    n, rng = _rng_n(n, seed)
    if not (ratio >= 1 and width > 0):
        raise ValueError(f"graded needs ratio >= 1 and width > 0, got ratio={ratio}, width={width}")
    m = 2 * n
    while True:
        base = saddle(m, seed=int(rng.integers(2**31)))
        w = 1 + (ratio - 1) / (1 + np.exp(-base.points[:, 0] / width))
        keep = np.flatnonzero(rng.random(m) * ratio < w)
        if len(keep) >= n:
            break
        m *= 2
    keep = np.sort(rng.choice(keep, n, replace=False))
    pick = {f: getattr(base, f)[keep] for f in ("points", "normals", "k1", "k2", "e1", "e2", "interior")}
    return Sample("graded", **pick, params=dict(base.params, ratio=ratio, width=width))


def _bumps(x, y):
    """Terrain of the range scan: three Gaussian bumps/dents on a gentle slope (f and derivatives)."""
    out = [0.1 * x + 0 * y, 0.1 + 0 * x, 0 * y, 0 * x, 0 * x, 0 * x]
    for a, cx, cy, s in ((0.35, -0.3, 0.2, 0.3), (-0.2, 0.4, -0.3, 0.22), (0.15, 0.35, 0.5, 0.15)):
        dx, dy = x - cx, y - cy
        g = a * np.exp(-(dx * dx + dy * dy) / (2 * s * s))
        gx, gy = -dx / s**2, -dy / s**2
        for i, v in enumerate((g, g * gx, g * gy, g * (gx * gx - 1 / s**2), g * gx * gy, g * (gy * gy - 1 / s**2))):
            out[i] = out[i] + v
    return tuple(out)


def range_scan(n=6000, *, view=(-2.5, 0.4, 1.6), noise=0.0, seed=0):
    """A single-view range scan of a bumpy terrain over [-1, 1]^2 from the point ``view``.

    Rays are drawn uniformly in azimuth and elevation (a scanner's angular grid, jittered)
    and stop at their first hit (occluded parts are missing), so the density falls with
    range squared and with the obliquity of the surface. ``noise`` (a fraction of the mean
    spacing) moves each point along its view ray; the truth is that of the hit point.
    """
    n, rng = _rng_n(n, seed)
    eye = np.asarray(view, dtype=float)
    if eye.shape != (3,) or not np.isfinite(eye).all() or eye[2] <= 1.0 or not (np.isfinite(noise) and noise >= 0):
        raise ValueError(f"range_scan needs a finite view (x, y, z > 1) and noise >= 0, got {view}, {noise}")
    corners = np.array([[x, y, 0.0] for x in (-1, 1) for y in (-1, 1)]) - eye
    az, el = np.arctan2(corners[:, 1], corners[:, 0]), np.arctan2(corners[:, 2], np.hypot(*corners[:, :2].T))
    hits = np.empty((0, 2))
    rays = np.empty((0, 3))
    while len(hits) < n:
        m = 3 * n
        a, e = rng.uniform(az.min(), az.max(), m), rng.uniform(el.min() - 0.1, el.max() + 0.05, m)
        d = np.column_stack([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
        t = _first_hit(eye, d)
        ok = np.isfinite(t)
        hits = np.concatenate([hits, eye[:2] + t[ok, None] * d[ok, :2]])
        rays = np.concatenate([rays, d[ok]])
    xy, rays = hits[:n], rays[:n]
    s = _graph_frame("range_scan", xy, _bumps, (np.abs(xy) < 0.85).all(axis=1), view=tuple(eye), noise=noise)
    shift = rng.normal(size=(n, 1)) * noise * _mean_nn(s.points)
    return Sample(s.name, s.points + shift * rays, s.normals, s.k1, s.k2, s.e1, s.e2, s.interior, s.params)


def _first_hit(eye, d, step=0.005, t_max=8.0):
    """Ray parameter of the first crossing of z = _bumps (extended beyond the square, so it
    also occludes), kept where it lies over [-1, 1]^2 (inf: a miss)."""
    t = np.full(len(d), np.inf)
    todo = np.arange(len(d))
    for t1 in np.arange(step, t_max, step):
        p = eye + t1 * d[todo]
        below = p[:, 2] < _bumps(p[:, 0], p[:, 1])[0]
        t[todo[below]] = t1
        todo = todo[~below & (p[:, 2] > -1.0)]
        if not len(todo):
            break
    hit = np.flatnonzero(np.isfinite(t))
    a, b = t[hit] - step, t[hit]
    for _ in range(40):  # bisection on the bracket [t - step, t]
        mid = 0.5 * (a + b)
        p = eye + mid[:, None] * d[hit]
        above = p[:, 2] > _bumps(p[:, 0], p[:, 1])[0]
        a, b = np.where(above, mid, a), np.where(above, b, mid)
    t[hit] = 0.5 * (a + b)
    p = eye + t[:, None] * d
    t[~(np.abs(p[:, :2]) <= 1).all(axis=1)] = np.inf
    return t


def _mean_nn(points):
    return float(cKDTree(points).query(points, k=2)[0][:, 1].mean())


#: shape name -> sampler(n, *, seed)
SHAPES = {
    "torus": torus,
    "sphere": sphere,
    "cylinder": cylinder,
    "plane": plane,
    "saddle": saddle,
    "ellipsoid": ellipsoid,
    "cube": cube,
    "chirp": chirp,
    "graded": graded,
    "range_scan": range_scan,
}
