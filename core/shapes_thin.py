"""Thin parts and scan-like samples: the shapes on which orientation and borders are tested.

Each sampler returns a :class:`core.shapes.Sample` whose size is set in units of the
sampling ``spacing`` (sqrt(area / n), stored in ``params["spacing"]``), because what makes
a part "thin" is its thickness against the spacing, not in absolute units. Normals are
the outward normals of the solid (k = +1/R on a convex part). ``params["parts"]``, where
present, labels separate surfaces (their relative sign is a convention, not a fact);
``params["faces"]`` labels the faces of one closed surface (their signs are facts).

At a sharp edge (the plate's rim, the bowl's lip) the surface has no single normal but a
cone of them, and an estimate there is a blend that may lie almost across the face's own
normal: :func:`cone_normals` gives the outward side of that cone to judge orientation by.
"""

from __future__ import annotations

import numpy as np

from .neighbours import build_neighbours
from .noise import add_noise
from .shapes import Sample, _ordered, _rng_n, _unit, torus


def thin_tube(n=20000, *, radius_spacings=2.0, R=1.0, seed=0):
    """A closed ring-shaped tube (torus) whose tube radius is ``radius_spacings`` spacings.

    Area 4 pi^2 R r with r = c s and s^2 = area / n gives s = 4 pi^2 R c / n.
    """
    n, _ = _rng_n(n, seed)
    spacing = 4 * np.pi**2 * R * radius_spacings / n
    s = torus(n, R=R, r=radius_spacings * spacing, seed=seed)
    return Sample("thin_tube", s.points, s.normals, s.k1, s.k2, s.e1, s.e2, s.interior,
                  {**s.params, "spacing": spacing})


def thin_plate(n=20000, *, thickness_spacings=3.0, size=1.0, seed=0):
    """A closed square slab ``size`` x ``size`` x (``thickness_spacings`` spacings), all six
    faces sampled: two sides a few spacings apart joined by a narrow rim of sharp edges.

    ``interior`` marks points at least 2 spacings from every edge (the two big faces).
    """
    n, rng = _rng_n(n, seed)
    c = thickness_spacings
    # n s^2 = 2 size^2 + 4 size c s  ->  the positive root
    spacing = (4 * size * c + np.sqrt(16 * size**2 * c**2 + 8 * n * size**2)) / (2 * n)
    half = np.array([size, size, c * spacing]) / 2
    area = 4 * np.array([half[1] * half[2], half[0] * half[2], half[0] * half[1]])  # one face per axis
    axis = rng.choice(3, size=n, p=area / area.sum())
    sign = np.where(rng.random(n) < 0.5, 1.0, -1.0)
    rows = np.arange(n)
    pts = (rng.random((n, 3)) * 2 - 1) * half
    pts[rows, axis] = sign * half[axis]
    nrm = np.zeros((n, 3))
    nrm[rows, axis] = sign
    ea = np.zeros((n, 3))
    ea[rows, (axis + 1) % 3] = 1.0
    in_face = np.abs(pts) < half * (1 - 1e-12)
    edge_dist = np.where(in_face, half - np.abs(pts), np.inf).min(axis=1)
    zeros = np.zeros(n)
    return _ordered(nrm, zeros, zeros, ea, np.cross(nrm, ea), pts, "thin_plate", edge_dist > 2 * spacing,
                    spacing=spacing, size=size)


def thin_wedge(n=20000, *, thickness_spacings=(2.0, 5.0), size=1.0, seed=0):
    """A closed slab ``size`` x ``size`` whose thickness grows linearly along x from
    ``thickness_spacings[0]`` to ``[1]`` spacings: a plate whose rim is thinner on one side
    than :func:`thin_plate`'s and thicker on the other, its faces slightly tilted. All six
    faces sampled by area; ``interior`` marks points of the two big faces at least 2
    spacings from every edge. Flat: k1 = k2 = 0.
    """
    n, rng = _rng_n(n, seed)
    c0, c1 = thickness_spacings
    a = size / 2
    # n s^2 = 2 size^2 (the big faces, tilt ~1e-4 left out) + 2 size s (c0 + c1) (the four sides)
    spacing = (2 * size * (c0 + c1) + np.sqrt(4 * size**2 * (c0 + c1) ** 2 + 8 * n * size**2)) / (2 * n)
    slope = spacing * (c1 - c0) / size  # d(thickness)/dx

    def thick(x):
        return spacing * (c0 + (c1 - c0) * (x + a) / size)

    area = np.array([size**2, size**2, size * thick(-a), size * thick(a), size * thick(0.0), size * thick(0.0)])
    face = rng.choice(6, size=n, p=area / area.sum())  # top, bottom, x-, x+, y-, y+
    x, y, u = (rng.random(n) * 2 - 1) * a, (rng.random(n) * 2 - 1) * a, rng.random(n) - 0.5
    pending = face >= 4  # the trapezoids' x by rejection: density ~ thickness
    while pending.any():
        pending[pending] = rng.random(int(pending.sum())) * thick(a) > thick(x[pending])
        x[pending] = (rng.random(int(pending.sum())) * 2 - 1) * a
    x = np.select([face == 2, face == 3], [-a, a], x)
    y = np.select([face == 4, face == 5], [-a, a], y)
    z = np.where(face == 0, thick(x) / 2, np.where(face == 1, -thick(x) / 2, u * thick(x)))
    top = np.array([-slope / 2, 0.0, 1.0]) / np.hypot(slope / 2, 1.0)
    table = np.array([top, top * [1, 1, -1], [-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0]])
    nrm = table[face]
    ea = _unit(np.cross(nrm, np.where(np.abs(nrm[:, 1:2]) < 0.9, [[0, 1.0, 0]], [[1.0, 0, 0]])))
    interior = (face <= 1) & (np.minimum(a - np.abs(x), a - np.abs(y)) > 2 * spacing)
    zeros = np.zeros(n)
    return _ordered(nrm, zeros, zeros, ea, np.cross(nrm, ea), np.column_stack([x, y, z]), "thin_wedge", interior,
                    spacing=spacing, size=size, faces=face)


def two_sheets(n=20000, *, gap_spacings=4.0, radius=1.0, angle=np.pi / 2, seed=0):
    """Two concentric open cylinder patches (height ``radius``, ``angle`` wide) a few
    spacings apart, like the two layers of a bent sheet. Normals point away from the gap
    (outer: away from the axis, k1 = 1/r; inner: towards it, k2 = -1/r); ``params["parts"]``
    is 0 for the outer sheet and 1 for the inner one.
    """
    n, rng = _rng_n(n, seed)
    spacing = np.sqrt(2 * radius * angle * radius / n)  # approx: both sheets ~ radius x angle
    r_in = radius - gap_spacings * spacing
    part = (rng.random(n) < r_in / (radius + r_in)).astype(np.int64)  # area-proportional
    r = np.where(part == 1, r_in, radius)
    phi = (rng.random(n) - 0.5) * angle
    z = (rng.random(n) - 0.5) * radius
    c, s, zeros, ones = np.cos(phi), np.sin(phi), np.zeros(n), np.ones(n)
    pts = np.column_stack([r * c, r * s, z])
    out = np.where(part == 1, -1.0, 1.0)
    nrm = out[:, None] * np.column_stack([c, s, zeros])
    around = np.column_stack([-s, c, zeros])
    axis = np.column_stack([zeros, zeros, ones])
    edge = np.minimum(np.abs(np.abs(phi) - angle / 2) * r, np.abs(np.abs(z) - radius / 2))
    return _ordered(nrm, out / r, zeros, around, axis, pts, "two_sheets", edge > 3 * spacing,
                    spacing=spacing, parts=part)


def thin_shell(n=20000, *, thickness_spacings=3.0, radius=1.0, seed=0):
    """A bowl: the closed solid between two concentric hemispheres (z <= 0) a few spacings
    apart, with its flat rim. Outward normals: away from the centre outside (k = 1/R),
    towards it inside (k = -1/r), +z on the rim (k = 0).
    """
    n, rng = _rng_n(n, seed)
    spacing = np.sqrt(4 * np.pi * radius**2 / n)
    for _ in range(20):  # fixed point: the inner radius depends on the spacing
        r_in = radius - thickness_spacings * spacing
        area = np.array([2 * np.pi * radius**2, 2 * np.pi * r_in**2, np.pi * (radius**2 - r_in**2)])
        spacing = np.sqrt(area.sum() / n)
    part = rng.choice(3, size=n, p=area / area.sum())
    d = _unit(rng.normal(size=(n, 3)))
    d[:, 2] = -np.abs(d[:, 2])
    rim_r = np.sqrt(rng.random(n) * (radius**2 - r_in**2) + r_in**2)
    rim_phi = rng.random(n) * 2 * np.pi
    rim = np.column_stack([rim_r * np.cos(rim_phi), rim_r * np.sin(rim_phi), np.zeros(n)])
    r = np.where(part == 0, radius, r_in)[:, None]
    pts = np.where((part == 2)[:, None], rim, r * d)
    nrm = np.where((part == 2)[:, None], [[0.0, 0.0, 1.0]], np.where((part == 1)[:, None], -d, d))
    k = np.select([part == 0, part == 1], [1 / radius, -1 / r_in], 0.0)
    ea = _unit(np.cross(nrm, np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])))
    interior = (part != 2) & (pts[:, 2] < -2 * spacing)
    return _ordered(nrm, k, k, ea, np.cross(nrm, ea), pts, "thin_shell", interior, spacing=spacing,
                    faces=part)


def range_scan(n=20000, *, radius=1.0, seed=0):
    """A single-view range scan of a sphere: an orthographic pixel grid from +z hits the
    visible hemisphere, so samples thin out towards the silhouette (grazing rays) and the
    patch ends there. ``interior`` marks points whose normal is within 60 degrees of the
    view; k1 = k2 = 1/radius everywhere.
    """
    n, rng = _rng_n(n, seed)
    pixel = radius * np.sqrt(np.pi / n)  # n pixels on the disc
    g = np.arange(-radius, radius + pixel, pixel)
    x, y = (a.ravel() for a in np.meshgrid(g, g))
    x = x + rng.normal(scale=1e-3 * pixel, size=x.shape)  # sub-pixel jitter: no exact ties
    y = y + rng.normal(scale=1e-3 * pixel, size=y.shape)
    hit = x * x + y * y < radius**2
    x, y = x[hit], y[hit]
    pts = np.column_stack([x, y, np.sqrt(radius**2 - x * x - y * y)])
    nrm = pts / radius
    ea = _unit(np.cross(nrm, np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])))
    k = np.full(len(pts), 1 / radius)
    return _ordered(nrm, k, k, ea, np.cross(nrm, ea), pts, "range_scan", nrm[:, 2] > 0.5,
                    spacing=pixel, radius=radius)


def stripe_scan(n=20000, *, ratio=3.0, size=1.0, amplitude=0.1, seed=0):
    """A line scanner's sample of a gently waved square: scan lines ``ratio`` times farther
    apart than the samples along each line (``ratio=1``: a square grid), with 5 % jitter.
    The surface z = amplitude sin(3x) cos(2y) is smooth: any stripe its estimate shows is
    the sampling's. ``params["spacing"]`` is the along-line spacing.
    """
    _, rng = _rng_n(n, seed)
    along = size * np.sqrt(1.0 / (n * ratio))
    x, y = (a.ravel() for a in np.meshgrid(np.arange(0, size, along), np.arange(0, size, ratio * along)))
    x = x + rng.normal(scale=0.05 * along, size=x.shape)
    y = y + rng.normal(scale=0.05 * along, size=y.shape)
    pts, nrm, k, e = _monge(x, y, amplitude)
    edge = np.minimum(np.minimum(x, size - x), np.minimum(y, size - y))
    return _ordered(nrm, k[:, 0], k[:, 1], e[:, 0], e[:, 1], pts, "stripe_scan", edge > 3 * ratio * along,
                    spacing=along, ratio=ratio)


def _monge(x, y, a):
    """z = a sin(3x) cos(2y): points, upward normals, principal curvatures (N, 2) and
    directions (N, 2, 3) from the fundamental forms (k = -eigenvalues of I^-1 II with n up,
    so that a cap under an upward normal has k > 0, as a sphere's outside)."""
    s3, c3, s2, c2 = np.sin(3 * x), np.cos(3 * x), np.sin(2 * y), np.cos(2 * y)
    fx, fy = 3 * a * c3 * c2, -2 * a * s3 * s2
    fxx, fxy, fyy = -9 * a * s3 * c2, -6 * a * c3 * s2, -4 * a * s3 * c2
    w = np.sqrt(1 + fx**2 + fy**2)
    first = np.stack([np.stack([1 + fx**2, fx * fy], -1), np.stack([fx * fy, 1 + fy**2], -1)], -2)
    second = np.stack([np.stack([fxx, fxy], -1), np.stack([fxy, fyy], -1)], -2) / w[:, None, None]
    lam, vec = np.linalg.eig(np.linalg.solve(first, second))
    lam, vec = lam.real, vec.real
    tangents = np.stack([np.column_stack([np.ones_like(x), 0 * x, fx]), np.column_stack([0 * x, np.ones_like(x), fy])], 1)
    e = _unit(np.einsum("nij,nik->njk", vec, tangents).reshape(-1, 3)).reshape(-1, 2, 3)
    nrm = np.column_stack([-fx, -fy, np.ones_like(x)]) / w[:, None]
    return np.column_stack([x, y, a * s3 * c2]), nrm, -lam, e


def orientation_agreement(normals, truth, parts=None):
    """Fraction of rows whose normal points the same way as ``truth`` (NaN rows count as
    wrong). With ``parts``, each part may be flipped as a whole (its sign is a convention).
    """
    dots = np.einsum("ij,ij->i", np.nan_to_num(normals), truth)
    if parts is None:
        return float(np.mean(dots > 0))
    good = 0
    for p in np.unique(parts):
        d = dots[parts == p]
        good += max(np.count_nonzero(d > 0), np.count_nonzero(d < 0))
    return good / len(dots)


def sign_agreement(normals, sample, *, min_cos=0.5):
    """How an oriented estimate is judged on a thin shape, as ``(clear, face, off)``:
    ``clear``, the share facing the same side as the truth (its face's own normal; per part
    where ``params["parts"]`` makes a part's sign a convention) among the points whose
    normal is within acos(``min_cos``) = 60 degrees of the truth's line, the points where a
    sign means something; ``face``, the same over all points (NaN rows wrong); ``off``, the
    share left out of ``clear``: normals more than 60 degrees off, blends across a sharp
    rim or a thin gap, whose sign is a coin toss whatever the orientation does."""
    dots = np.einsum("ij,ij->i", np.nan_to_num(normals), sample.normals)
    parts = sample.params.get("parts")
    if parts is not None:
        for p in np.unique(parts):
            rows = parts == p
            if np.count_nonzero(dots[rows] < 0) > np.count_nonzero(dots[rows] > 0):
                dots[rows] *= -1.0
    clear = np.abs(dots) >= min_cos
    agree = float(np.mean(dots[clear] > 0)) if clear.any() else 0.0
    return agree, float(np.mean(dots > 0)), float(np.mean(~clear))


def noisy(sample, sigma_spacings, seed):
    """The sample's points with isotropic Gaussian noise of ``sigma_spacings`` x its
    ``params["spacing"]`` (in the points' units, not :func:`core.noise.add_noise`'s
    relative unit, the mean nearest-neighbour distance, about half the spacing)."""
    if not sigma_spacings:
        return sample.points
    return add_noise(sample.points, sigma_spacings * sample.params["spacing"], relative=False, seed=seed)


def cone_normals(sample, k=15):
    """The true normals averaged over each point's ``k`` nearest sample points: the
    outward direction of the normal cone at a sharp edge (the mean of the faces' normals
    met there), the normal itself on a smooth part (up to O(spacing^2 k) on a curved one).
    An oriented estimate on the right side faces it (dot > 0) even where its blended
    normal is across the face's own one."""
    idx = build_neighbours(sample.points, k).take(k)[0]
    return _unit(sample.normals[idx].sum(axis=1))


#: the L-bracket's outline in the x-z plane, counter-clockwise from the origin, in units of
#: (leg length, thickness): each row (x0, z0, x1, z1) as a + b t, the outward normal (x, z)
_BRACKET = np.array([  # (ax0, bx0, az0, bz0, ax1, bx1, az1, bz1, nx, nz)
    [0, 0, 0, 0, 1, 0, 0, 0, 0, -1],  # bottom of the horizontal leg
    [1, 0, 0, 0, 1, 0, 0, 1, 1, 0],  # its end
    [1, 0, 0, 1, 0, 1, 0, 1, 0, 1],  # its top, up to the inner (concave) corner
    [0, 1, 0, 1, 0, 1, 1, 0, 1, 0],  # the inner face of the vertical leg
    [0, 1, 1, 0, 0, 0, 1, 0, 0, 1],  # the vertical leg's end
    [0, 0, 1, 0, 0, 0, 0, 0, -1, 0],  # its back
], dtype=float)


def thin_bracket(n=20000, *, thickness_spacings=3.0, size=1.0, seed=0):
    """A closed L-shaped bracket: two legs ``size`` long and wide, ``thickness_spacings``
    spacings thick, meeting at 90 degrees (the outline of :data:`_BRACKET` in the x-z plane
    extruded along y, with its two L-shaped end caps). Convex rims like the plate's and one
    concave crease (the inner corner), where the solid lies on the far side of both faces.
    ``params["faces"]``: 0-5 the outline's strips, 6 and 7 the caps (y = 0, y = size);
    ``interior`` marks strip points at least 2 spacings from every edge. Flat: k1 = k2 = 0.
    """
    n, rng = _rng_n(n, seed)
    c, L = thickness_spacings, size
    # n s^2 = 4 L^2 (the strips) + 2 (2 L c s - c^2 s^2) (the caps)
    spacing = (4 * L * c + np.sqrt(16 * L**2 * c**2 + 16 * L**2 * (n + 2 * c**2))) / (2 * (n + 2 * c**2))
    t = c * spacing
    ends = _BRACKET[:, [0, 2, 4, 6]] * L + _BRACKET[:, [1, 3, 5, 7]] * t  # x0, z0, x1, z1
    length = np.hypot(ends[:, 2] - ends[:, 0], ends[:, 3] - ends[:, 1])
    cap = 2 * L * t - t * t
    area = np.r_[length * L, cap, cap]
    face = rng.choice(8, size=n, p=area / area.sum())
    u, y = rng.random(n), rng.random(n) * L
    strip = np.minimum(face, 5)
    x = ends[strip, 0] + u * (ends[strip, 2] - ends[strip, 0])
    z = ends[strip, 1] + u * (ends[strip, 3] - ends[strip, 1])
    on_cap = face >= 6
    leg = rng.random(n) < L * t / cap  # the cap's horizontal leg [0, L] x [0, t], else [0, t] x [t, L]
    cx, cz = np.where(leg, rng.random(n) * L, rng.random(n) * t), np.where(leg, rng.random(n) * t, t + rng.random(n) * (L - t))
    x, z = np.where(on_cap, cx, x), np.where(on_cap, cz, z)
    y = np.select([face == 6, face == 7], [0.0, L], y)
    nrm = np.zeros((n, 3))
    nrm[:, 0], nrm[:, 2] = _BRACKET[strip, 8], _BRACKET[strip, 9]
    nrm[on_cap] = 0.0
    nrm[on_cap, 1] = np.where(face[on_cap] == 6, -1.0, 1.0)
    ea = _unit(np.cross(nrm, np.where(np.abs(nrm[:, 1:2]) < 0.9, [[0, 1.0, 0]], [[1.0, 0, 0]])))
    interior = ~on_cap & (np.minimum(u, 1 - u) * length[strip] > 2 * spacing) & (np.minimum(y, L - y) > 2 * spacing)
    zeros = np.zeros(n)
    return _ordered(nrm, zeros, zeros, ea, np.cross(nrm, ea), np.column_stack([x, y, z]), "thin_bracket", interior,
                    spacing=spacing, size=size, faces=face)


#: thin-part shape name -> sampler(n, *, seed)
THIN_SHAPES = {
    "thin_tube": thin_tube,
    "thin_plate": thin_plate,
    "two_sheets": two_sheets,
    "thin_shell": thin_shell,
    "thin_wedge": thin_wedge,
    "thin_bracket": thin_bracket,
}
