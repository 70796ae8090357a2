"""Border flag (core.border): rims and holes flagged, interiors not, noise-free and noisy."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.bench import scan_clouds
from core import border, build_neighbours, shapes, shapes_thin

SIZE, N = 2.0, 20000


def _plane_with_hole(seed, radius=4):
    """A square with a round hole of ``radius`` spacings; distance to the nearest border."""
    s = shapes.plane(N, size=SIZE, seed=seed)
    spacing = SIZE / np.sqrt(N)
    radius = radius * spacing
    rho = np.hypot(s.points[:, 0] - 0.3, s.points[:, 1] + 0.2)
    keep = rho > radius
    to_rim = (SIZE / 2 - np.abs(s.points[:, :2])).min(axis=1)
    dist = np.minimum(to_rim, rho - radius)[keep] / spacing
    return s.points[keep], spacing, dist


@pytest.mark.parametrize("sigma", [0.0, 0.2])
def test_rim_and_hole_flagged_interior_not(sigma):
    """measured (seed 3): 99.7-100 % of the points within 1 spacing of a rim flagged,
    0.5-0.8 % of those beyond 3 spacings (the 30 neighbours' reach) flagged."""
    pts, spacing, dist = _plane_with_hole(3)
    pts = pts + np.random.default_rng(2).normal(scale=sigma * spacing, size=pts.shape)
    nb = build_neighbours(pts, 30)
    normals = core.estimate(pts, k=15, method="nf", neighbours=nb).normals
    flag, gap, reach = border.border_flags(pts, normals, nb.take(30)[0])
    near, inner = dist <= 1.0, dist > 3.0
    assert flag[near].mean() >= 0.95
    assert flag[inner].mean() <= 0.01
    assert np.nanmedian(gap[near]) > np.nanmedian(gap[inner])


def test_closed_surface_has_no_border():
    s = shapes.sphere(5000, seed=1)
    nb = build_neighbours(s.points, 30)
    flag, _, _ = border.border_flags(s.points, s.normals, nb.take(30)[0])
    assert flag.mean() < 0.01


@pytest.mark.parametrize("make", [shapes.torus, shapes.sphere, shapes.ellipsoid])
def test_voids_of_random_sampling_are_not_borders(make):
    """The 30-neighbour test alone flags 0.5 % of a clean random closed surface (its voids);
    read again on 60, 0.02-0.05 %. A round hole of radius 8 spacings keeps its rim."""
    s = make(20000, seed=1)
    assert border.border_of(s.points, s.normals, None).mean() < 0.001
    pts, spacing, dist = _plane_with_hole(4, radius=8)
    assert border.border_of(pts, np.tile([0.0, 0.0, 1.0], (len(pts), 1)), None)[dist <= 1.0].mean() >= 0.97


def test_no_normal_no_flag():
    s = shapes.sphere(2000, seed=2)
    nrm = s.normals.copy()
    nrm[::7] = np.nan
    nb = build_neighbours(s.points, 30)
    flag, gap, reach = border.border_flags(s.points, nrm, nb.take(30)[0])
    assert not flag[::7].any() and np.isnan(gap[::7]).all() and np.isnan(reach[::7]).all()


@pytest.mark.parametrize("sigma", [0.0, 0.2])
def test_range_scan_no_wild_curvature_unless_flagged(sigma):
    """A single-view scan: no valid, unflagged point has |H| > 10x the 99th percentile."""
    s = shapes_thin.range_scan(20000, seed=1)
    pts = s.points + np.random.default_rng(4).normal(scale=sigma * s.params["spacing"], size=s.points.shape)
    r = core.estimate(pts, k=15)
    nb = build_neighbours(pts, 30)
    flag, _, _ = border.border_flags(pts, r.normals, nb.take(30)[0])
    h = np.abs(r.mean)
    p99 = np.nanpercentile(h[r.valid], 99)
    wild = r.valid & (h > 10 * p99) & ~flag & ~r.crease & ~r.outlier
    assert not wild.any()
    assert flag[s.normals[:, 2] < 0.05].all()  # the outermost ring, seen edge-on


def test_border_of_searches_more_neighbours_when_needed():
    s = shapes.plane(3000, seed=5)
    few = build_neighbours(s.points, 15)
    many = build_neighbours(s.points, 40)
    a = border.border_of(s.points, s.normals, few)
    b = border.border_of(s.points, s.normals, many)
    np.testing.assert_array_equal(a, b)
    tiny = shapes.plane(12, seed=1)
    assert border.border_of(tiny.points, tiny.normals, build_neighbours(tiny.points, 5)).shape == (12,)


@pytest.mark.parametrize("k", ["auto", 15])
def test_estimate_result_carries_the_border_flag(k):
    """The result's ``border``: rims of an open patch flagged, a closed surface not."""
    pts, spacing, dist = _plane_with_hole(6)
    r = core.estimate(pts, k=k)
    assert r.border.dtype == bool and r.border.shape == (len(pts),)
    assert r.border[dist <= 1.0].mean() >= 0.95
    assert r.border[dist > 3.0].mean() <= 0.01
    assert not r.border[~r.valid].any()
    closed = core.estimate(shapes.sphere(3000, seed=2).points, k=k)
    assert closed.border.mean() <= 0.01


@pytest.mark.parametrize("make, interior", [
    (lambda: scan_clouds.stripes(24, 0.1), None),  # lines 24 x their spacing apart
    (lambda: scan_clouds.lidar_ground(5, 20), (5.0, 20.0)),  # a rotating LiDAR's rings, 15-50 x apart
])
def test_scan_lines_far_apart_are_not_all_border(make, interior):
    """The 30 nearest of a point on such lines lie on its own line, one side empty: every
    point was flagged (stripes 100 %, LiDAR ground 5-20 m 98-99 %). The flag is read again on
    neighbourhoods wide enough to reach across the lines; the outer lines stay flagged."""
    c = make()
    r = core.estimate(c.points) if c.view is None else core.estimate(c.points, orientation=c.view)
    if interior is None:
        y = c.points[:, 1]
        assert r.border[c.use].mean() < 0.01
        assert r.border[np.abs(y - y.min()) < 1e-2].mean() > 0.95 and r.border[np.abs(y - y.max()) < 1e-2].mean() > 0.95
    else:
        d = np.hypot(c.points[:, 0], c.points[:, 1])
        assert r.border[(d > interior[0]) & (d < interior[1])].mean() < 0.05
        assert r.border[d < 3.2].mean() > 0.7  # the innermost ring: nothing inside it
