"""Test helpers of the eighth input audit: one-dimensional structures in a scene, holes,
undersampled detail and a double sheet, with exact truth where a surface exists.

Every scene is a square ground plane (size 2, ``n`` points) plus the structure; params["part"]
names each point's piece (0: the ground) and params["curve"] marks points whose neighbourhood
is a curve (no surface normal: a wire, a line, a helix), where any valid estimate is garbage
unless its curvature is honest.
"""

from __future__ import annotations

import numpy as np

from core.shapes import Sample, _ordered, _unit, plane
from audit_shapes import join, parametric


def _marked(sample, curve):
    return Sample(sample.name, sample.points, sample.normals, sample.k1, sample.k2, sample.e1,
                  sample.e2, sample.interior, {**sample.params, "curve": curve})


def _tube(name, start, direction, length, radius, spacing, seed):
    """A cylinder of ``radius`` about the segment from ``start`` along ``direction``, sampled
    at the ground's density (at least one point per spacing along its axis): k1 = 1 / radius
    around, 0 along, normals radial."""
    d = _unit(np.asarray(direction, float)[None])[0]
    a = _unit(np.cross(d, [0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0])[None])[0]
    b = np.cross(d, a)
    n = max(int(2 * np.pi * radius * length / spacing ** 2), int(length / spacing))
    rng = np.random.default_rng(seed)
    t, phi = rng.uniform(0, length, n), rng.uniform(0, 2 * np.pi, n)
    radial = np.cos(phi)[:, None] * a + np.sin(phi)[:, None] * b
    pts = np.asarray(start, float) + t[:, None] * d + radius * radial
    along = np.broadcast_to(d, pts.shape).copy()
    around = np.cross(radial, along)
    return _ordered(radial, np.full(n, 1.0 / radius), np.zeros(n), around, along, pts, name,
                    np.ones(n, bool), spacing=spacing)


def _ground(n, seed):
    g = plane(n, size=2.0, seed=seed)
    return g, 2.0 / np.sqrt(n)


def wire_over_plane(n=8000, *, radius_spacings=1.0, height=0.3, seed=0, vertical=False):
    """A wire (``vertical``: a pole standing on the ground) of ``radius_spacings`` spacings
    beside a ground plane of ``n`` points; a radius under about 2 spacings is a curve."""
    g, s = _ground(n, seed)
    if vertical:
        w = _tube("pole", [0.3, -0.2, 0.0], [0, 0, 1], 0.6, radius_spacings * s, s, seed + 1)
    else:
        w = _tube("wire", [-0.9, 0.1, height], [1, 0.2, 0], 1.8, radius_spacings * s, s, seed + 1)
    out = join("pole" if vertical else "wire", [g, w], spacing=s)
    return _marked(out, (out.params["part"] == 1) & (radius_spacings < 2.5))


def line_over_plane(n=8000, *, height=0.3, step_spacings=0.5, jitter=0.1, seed=0):
    """A line of points (a power line, a railing) ``height`` above a ground of ``n`` points,
    one every ``step_spacings`` spacings, jittered by ``jitter`` spacings: no surface."""
    g, s = _ground(n, seed)
    m = int(1.8 / (step_spacings * s))
    rng = np.random.default_rng(seed + 1)
    t = np.linspace(-0.9, 0.9, m)
    pts = np.c_[t, 0.1 + 0.2 * t, np.full(m, height)] + rng.normal(size=(m, 3)) * jitter * s
    nan3 = np.full((m, 3), np.nan)
    line = Sample("line", pts, nan3, np.full(m, np.nan), np.full(m, np.nan), nan3, nan3,
                  np.zeros(m, bool), {"spacing": s})
    out = join("line", [g, line], spacing=s)
    return _marked(out, out.params["part"] == 1)


def helix(n=3000, *, radius=1.0, pitch=0.5, turns=3.0, thickness_spacings=0.2, seed=0):
    """A helix curve of ``n`` points with a little thickness (curvature r / (r^2 + c^2), c the
    pitch over 2 pi): no surface; params["spacing"] is its step along the curve."""
    c = pitch / (2 * np.pi)
    length = turns * 2 * np.pi * np.hypot(radius, c)
    s = length / n
    rng = np.random.default_rng(seed)
    u = np.sort(rng.uniform(0, turns * 2 * np.pi, n))
    pts = np.c_[radius * np.cos(u), radius * np.sin(u), c * u]
    pts = pts + rng.normal(size=pts.shape) * thickness_spacings * s
    nan3 = np.full((n, 3), np.nan)
    kappa = np.full(n, radius / (radius ** 2 + c ** 2))
    return Sample("helix", pts, nan3, kappa, np.full(n, np.nan), nan3, nan3, np.zeros(n, bool),
                  {"spacing": s, "curve": np.ones(n, bool)})


def sinusoid(n=8000, *, wavelength_spacings=5.0, amplitude_ratio=0.1, size=2.0, seed=0):
    """z = a sin(2 pi x / L) with L = ``wavelength_spacings`` spacings and a = ratio x L:
    curvature radius (L / 2 pi)^2 / a, 0.4-1.3 spacings at L = 3-8 spacings and ratio 0.1."""
    s = size / np.sqrt(n)
    wl = wavelength_spacings * s
    a = amplitude_ratio * wl

    def X(u, v):
        return np.stack([u, v, a * np.sin(2 * np.pi * u / wl)], -1)
    h = size / 2
    return parametric("sinusoid", X, (-h, h), (-h, h), n, seed, interior_margin=0.05,
                      wavelength=wl)


def double_sheet(sample, offset_spacings, *, seed=0):
    """Two scans of one surface misregistered along the normal: a random half of the sample's
    points (the second scan) moved ``offset_spacings`` spacings (of the joined cloud) along
    their true normal; the truth is the surface's; params["sheet"] is 0 / 1."""
    rng = np.random.default_rng(seed)
    second = rng.random(len(sample.points)) < 0.5
    pts = sample.points + (second * offset_spacings * sample.params["spacing"])[:, None] \
        * sample.normals
    return Sample(sample.name + "_double", pts, sample.normals, sample.k1, sample.k2, sample.e1,
                  sample.e2, sample.interior, {**sample.params, "sheet": second.astype(int)})
