"""Clouds sampled the way scanners sample, with exact normals and mean curvature: the cases
of ``python -m core bench scanlines`` (:mod:`core.bench.scanlines`).

Every generator returns a :class:`ScanCloud`. Spacings are in units of the along-line
spacing: ``ratio`` is how many times farther apart the lines are than the points on a line,
``noise`` the standard deviation of isotropic noise in the same unit (a LiDAR's is its range
noise in metres). ``use`` marks the points scored (away from the patch's cut edges).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import shapes
from ..shapes_thin import stripe_scan


class ScanCloud(NamedTuple):
    """points (N, 3); normals (N, 3) and mean curvature (N,) exact (sign-blind comparisons);
    use (N,) bool, the points scored; view: the scanner's position, or None."""

    points: np.ndarray
    normals: np.ndarray
    mean: np.ndarray
    use: np.ndarray
    view: tuple | None = None


def _unit(v):
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _jitter(points, scale, seed):
    return points + np.random.default_rng(seed).normal(scale=scale, size=points.shape) if scale else points


def sphere_parallels(ratio, noise, n_line=200, lines=20) -> ScanCloud:
    """A unit-sphere patch along ``lines`` parallels of ``n_line`` points (a line scanner's sweep)."""
    step = 1.0 / (n_line - 1)
    th, ph = (g.ravel() for g in np.meshgrid(np.arange(n_line) * step - 0.5,
                                             (np.arange(lines) - (lines - 1) / 2) * step * ratio))
    p = np.column_stack([np.cos(ph) * np.cos(th), np.cos(ph) * np.sin(th), np.sin(ph)])
    use = (np.abs(th) < 0.5 - 5 * step) & (np.abs(ph) < np.abs(ph).max() - 1.5 * step * ratio)
    return ScanCloud(_jitter(p, noise * step, 1), p.copy(), np.ones(len(p)), use)


def sphere_rings(noise, n_rings=30, n_ring=300) -> ScanCloud:
    """A unit sphere in ``n_rings`` rings of latitude (a turntable scan); ``noise`` in units of the radius."""
    th, ph = (g.ravel() for g in np.meshgrid(np.linspace(0, np.pi, n_rings)[1:-1],
                                             np.linspace(0, 2 * np.pi, n_ring, endpoint=False)))
    p = np.column_stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
    return ScanCloud(_jitter(p, noise, 2), p, np.ones(len(p)), np.ones(len(p), dtype=bool))


def cylinder_rings(ratio, noise, n_ring=300) -> ScanCloud:
    """An open unit cylinder (height 4) in rings ``ratio`` x their spacing apart; H = 1/2."""
    step = 2 * np.pi / n_ring
    a, z = (g.ravel() for g in np.meshgrid(np.arange(n_ring) * step, np.arange(0.0, 4.0, step * ratio)))
    a = a + np.random.default_rng(ratio).normal(scale=0.02 * step, size=a.shape)
    p = np.column_stack([np.cos(a), np.sin(a), z - 2.0])
    n = np.column_stack([p[:, 0], p[:, 1], 0 * z])
    return ScanCloud(_jitter(p, noise * step, 3), n, np.full(len(p), 0.5), np.abs(z - 2.0) < 1.6)


def torus_parallels(ratio, noise, n_line=400) -> ScanCloud:
    """The paper's torus (R = 2, r = 1) along parallels ``ratio`` x their outer spacing apart
    (on the inner equator the points are 3x closer: the ratio triples)."""
    R, r = 2.0, 1.0
    step = 2 * np.pi * (R + r) / n_line
    nth = int(2 * np.pi * r / (step * ratio))
    T, P = (g.ravel() for g in np.meshgrid(np.arange(nth) * 2 * np.pi / nth, np.arange(n_line) * 2 * np.pi / n_line))
    p = np.column_stack([(R + r * np.cos(T)) * np.cos(P), (R + r * np.cos(T)) * np.sin(P), r * np.sin(T)])
    n = np.column_stack([np.cos(T) * np.cos(P), np.cos(T) * np.sin(P), np.sin(T)])
    H = 0.5 * (1 / r + np.cos(T) / (R + r * np.cos(T)))
    return ScanCloud(_jitter(p, noise * step, 4), n, H, np.ones(len(p), dtype=bool))


def lidar_ground(near, far, noise=0.02) -> ScanCloud:
    """Flat ground seen by a rotating LiDAR 1.8 m up (24 beams from -30 to -3 degrees, 0.2
    degrees apart around), range noise ``noise`` m along the rays; scored ``near``-``far`` m out."""
    h = 1.8
    el, az = np.meshgrid(np.radians(np.linspace(-30, -3, 24)), np.radians(np.arange(0, 360, 0.2)), indexing="ij")
    rays = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1).reshape(-1, 3)
    p = np.array([0.0, 0.0, h]) + (-h / rays[:, 2] + np.random.default_rng(0).normal(scale=noise, size=len(rays)))[:, None] * rays
    p = p[np.hypot(p[:, 0], p[:, 1]) < 40]
    d = np.hypot(p[:, 0], p[:, 1])
    return ScanCloud(p, np.tile([0.0, 0.0, 1.0], (len(p), 1)), np.zeros(len(p)), (d >= near) & (d < far), (0.0, 0.0, h))


def tripod_floor(noise=0.002) -> ScanCloud:
    """A floor under a terrestrial scanner 1.5 m up (1-degree steps, elevations -85 to -20
    degrees): dense rings under the tripod, range noise ``noise`` m."""
    eye = np.array([0.0, 0.0, 1.5])
    az, el = np.meshgrid(np.radians(np.arange(0, 360, 1.0)), np.radians(np.arange(-85, -20, 1.13)), indexing="ij")
    rays = np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)], -1).reshape(-1, 3)
    reach = -eye[2] / rays[:, 2] + np.random.default_rng(1).normal(scale=noise, size=len(rays))
    p = eye + reach[:, None] * rays
    return ScanCloud(p, np.tile([0.0, 0.0, 1.0], (len(p), 1)), np.zeros(len(p)), np.ones(len(p), dtype=bool), tuple(eye))


def sphere_seen(noise, dist=3.0, n=120) -> ScanCloud:
    """The near cap of a unit sphere seen from ``dist`` on a square grid of rays, range noise
    ``noise`` x the ray spacing on the sphere."""
    eye = np.array([0.0, 0.0, dist])
    a = np.radians(np.linspace(-19, 19, n))
    ax, ay = (g.ravel() for g in np.meshgrid(a, a))
    d = _unit(np.column_stack([np.tan(ax), np.tan(ay), -np.ones_like(ax)]))
    b, c = d @ eye, eye @ eye - 1.0
    hit = b * b - c > 0
    p = eye + (-b[hit] - np.sqrt(b[hit] ** 2 - c))[:, None] * d[hit]
    p = p + np.random.default_rng(3).normal(scale=noise * np.radians(38 / n) * (dist - 1), size=(len(p), 1)) * d[hit]
    nrm = _unit(p)
    return ScanCloud(p, nrm, np.ones(len(p)), nrm[:, 2] > 0.5, tuple(eye))


def range_scan(noise, view=(-2.5, 0.4, 1.6)) -> ScanCloud:
    """:func:`core.shapes.range_scan` (bumps on a slope, noise along the view rays) with its viewpoint."""
    s = shapes.range_scan(6000, view=view, noise=noise)
    return ScanCloud(s.points, s.normals, s.mean, s.interior, tuple(view))


def stripes(ratio, noise, turned=False) -> ScanCloud:
    """:func:`core.shapes_thin.stripe_scan` (a waved square in lines ``ratio`` x apart), 20k
    points; ``turned``: rotated at random (the lines no longer follow an axis)."""
    s = stripe_scan(20000, ratio=ratio)
    q = _jitter(s.points, noise * s.params["spacing"], 6)
    if not turned:
        return ScanCloud(q, s.normals, s.mean, s.interior)
    rot = np.linalg.qr(np.random.default_rng(7).normal(size=(3, 3)))[0]
    return ScanCloud(q @ rot.T, s.normals @ rot.T, s.mean, s.interior)


def cases() -> dict:
    """{name: generator} of the bench's clouds, in the order of its table."""
    out = {}
    for r in (6, 8, 12, 16):
        for nz in (0, 0.05, 0.1):
            out[f"sphere parallels {r}x, noise {nz}"] = lambda r=r, nz=nz: sphere_parallels(r, nz)
    for nz in (0, 0.002, 0.005):
        out[f"sphere rings, noise {nz}"] = lambda nz=nz: sphere_rings(nz)
    for r in (8, 12):
        for nz in (0, 0.05):
            out[f"cylinder rings {r}x, noise {nz}"] = lambda r=r, nz=nz: cylinder_rings(r, nz)
    for r in (4, 8, 12):
        for nz in (0, 0.05):
            out[f"torus parallels {r}x, noise {nz}"] = lambda r=r, nz=nz: torus_parallels(r, nz)
    for r in (6, 10, 16, 24):
        for nz in (0, 0.1, 0.3):
            out[f"stripes {r}x, noise {nz}"] = lambda r=r, nz=nz: stripes(r, nz)
    out["stripes 10x, noise 0.1, turned"] = lambda: stripes(10, 0.1, True)
    for a, b in ((0, 5), (5, 10), (10, 20), (20, 40)):
        out[f"LiDAR ground {a}-{b} m"] = lambda a=a, b=b: lidar_ground(a, b)
    out["floor under a tripod"] = tripod_floor
    out["floor under a tripod, noise 1 cm"] = lambda: tripod_floor(0.01)
    for nz in (0, 0.5, 2.0):
        out[f"sphere seen from 3, noise {nz}"] = lambda nz=nz: sphere_seen(nz)
    for nz in (0, 0.1, 0.3, 1.0):
        out[f"range scan, noise {nz}"] = lambda nz=nz: range_scan(nz)
    return out
