"""Test helpers of the seventh input audit: perturbations and surfaces with exact truth.

Coordinates quantised to a world grid, mirrored and rescaled copies of a sample (the truth
moved along), noise that grows with range (sigma ~ distance^2 from a sensor) and heavy-tailed
noise (Student t), and parametrised surfaces with singular or awkward global shape: a cone and
a double cone (apex), a long thin ribbon, a Moebius band (non-orientable).
"""

from __future__ import annotations

import numpy as np

from core.shapes import Sample
from audit_shapes import join, parametric


def _with_points(sample, points, **params):
    return Sample(sample.name, points, sample.normals, sample.k1, sample.k2, sample.e1,
                  sample.e2, sample.interior, {**sample.params, **params})


def quantised(sample, step_spacings, *, seed=0):
    """The sample's points rounded to a world grid of ``step_spacings`` spacings (a LAS file's
    integer scale, a coarse depth sensor), the grid's origin drawn at random."""
    step = step_spacings * sample.params["spacing"]
    origin = np.random.default_rng(seed).uniform(0, step, 3)
    return _with_points(sample, np.round((sample.points - origin) / step) * step + origin,
                        step=step)


def mirrored(sample, axis=0):
    """The sample reflected in the plane through the origin normal to ``axis`` (left-handed):
    points, normals and directions mirrored; k1, k2 unchanged (the normals still face out)."""
    m = np.ones(3)
    m[axis] = -1.0
    return Sample(sample.name + "_mirrored", sample.points * m, sample.normals * m, sample.k1,
                  sample.k2, sample.e1 * m, sample.e2 * m, sample.interior, dict(sample.params))


def rescaled(sample, scale, offset=0.0):
    """The sample scaled by ``scale`` and moved by ``offset`` (curvatures / scale)."""
    return Sample(sample.name, sample.points * scale + offset, sample.normals, sample.k1 / scale,
                  sample.k2 / scale, sample.e1, sample.e2, sample.interior,
                  {**sample.params, "spacing": sample.params["spacing"] * scale})


def range_noise(sample, sigma_far, *, ratio=10.0, seed=0):
    """Noise along the ray from a sensor whose sigma grows with the squared distance, from
    ``sigma_far / ratio`` at the nearest point to ``sigma_far`` (spacings) at the farthest; the
    sensor stands on the -x side, far enough for the distances to span sqrt(ratio)."""
    p = sample.points
    centre = p.mean(axis=0)
    half = 0.5 * np.ptp(p[:, 0])
    q = np.sqrt(ratio)
    eye = centre - np.array([half * (q + 1) / (q - 1), 0.0, 0.0])
    ray = p - eye
    dist = np.linalg.norm(ray, axis=1)
    sigma = sigma_far * (dist / dist.max()) ** 2
    shift = np.random.default_rng(seed).normal(size=len(p)) * sigma * sample.params["spacing"]
    return _with_points(sample, p + (shift / dist)[:, None] * ray, sigma=sigma)


def student_noise(sample, scale, *, dof=2.0, seed=0):
    """Isotropic Student-t noise (``dof`` = 2: infinite variance) of ``scale`` spacings."""
    t = np.random.default_rng(seed).standard_t(dof, size=sample.points.shape)
    return _with_points(sample, sample.points + t * scale * sample.params["spacing"])


def _spaced(sample, area):
    return _with_points(sample, sample.points, spacing=float(np.sqrt(area / len(sample.points))))


def cone(n=8000, *, half_angle=np.pi / 6, length=1.0, seed=0, nappe=1.0):
    """A cone of ``half_angle`` about z, slant length ``length`` from its apex at the origin
    (on +z, or -z for ``nappe`` = -1): k around = 1 / (t tan a), 0 along. params["apex"] is
    each point's distance to the apex."""
    sa, ca = np.sin(half_angle), np.cos(half_angle)

    def X(u, v):
        return np.stack([v * sa * np.cos(u), v * sa * np.sin(u), nappe * v * ca], -1)
    s = parametric("cone", X, (0, 2 * np.pi), (1e-3, length), n, seed, flip=nappe < 0)
    s = _with_points(s, s.points, apex=np.linalg.norm(s.points, axis=1))
    interior = s.params["apex"] < 0.85 * length
    out = Sample(s.name, s.points, s.normals, s.k1, s.k2, s.e1, s.e2, interior, s.params)
    return _spaced(out, np.pi * sa * length ** 2)


def double_cone(n=8000, *, half_angle=np.pi / 6, length=1.0, seed=0):
    """Two nappes meeting at their apex (the origin), normals away from the axis."""
    a = cone(n // 2, half_angle=half_angle, length=length, seed=seed)
    b = cone(n - n // 2, half_angle=half_angle, length=length, seed=seed + 1, nappe=-1.0)
    out = join("double_cone", [a, b], spacing=a.params["spacing"])
    return _with_points(out, out.points, apex=np.linalg.norm(out.points, axis=1))


def ribbon(*, aspect=200.0, width_spacings=4.0, radius=1.0, seed=0):
    """A strip of a cylinder of ``radius`` (k1 = 1 / radius around, k2 = 0 along the axis),
    ``aspect`` times as long (around 0.9 of the circle) as it is wide, ``width_spacings`` wide
    (aspect x width_spacings^2 points)."""
    length = 0.9 * 2 * np.pi * radius
    width = length / aspect

    def X(u, v):
        return np.stack([radius * np.cos(u), radius * np.sin(u), v], -1)
    s = parametric("ribbon", X, (0, 0.9 * 2 * np.pi), (-width / 2, width / 2),
                   int(aspect * width_spacings ** 2), seed)
    return _spaced(s, length * width)


def moebius(n=8000, *, radius=1.0, half_width=0.4, seed=0):
    """A Moebius band (non-orientable): the normal returns reversed after one turn."""
    def X(u, v):
        r = radius + v * np.cos(u / 2)
        return np.stack([r * np.cos(u), r * np.sin(u), v * np.sin(u / 2)], -1)
    s = parametric("moebius", X, (0, 2 * np.pi), (-half_width, half_width), n, seed,
                   interior_margin=0.1)
    off_core = np.hypot(np.hypot(*s.points[:, :2].T) - radius, s.points[:, 2])  # |v|
    out = Sample(s.name, s.points, s.normals, s.k1, s.k2, s.e1, s.e2,
                 off_core < 0.8 * half_width, s.params)
    return _spaced(out, 2 * np.pi * radius * 2 * half_width)
