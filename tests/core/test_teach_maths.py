"""Known answers for the teaching mathematics: Gauss-Bonnet, lines of curvature, point types,
the local picture at one point."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import noise, shapes

_CACHE = {}


def _estimate(name, sigma):
    """Default estimate of a 5000-point shape at noise sigma (spacings), cached per session."""
    key = (name, sigma)
    if key not in _CACHE:
        s = getattr(shapes, name)(5000, seed=0)
        pts = noise.add_noise(s.points, sigma, seed=1) if sigma else s.points
        _CACHE[key] = (s, core.estimate(pts))
    return _CACHE[key]


# --------------------------------------------------------------------------- Gauss-Bonnet


@pytest.mark.parametrize("sigma", [0.0, 0.1])
@pytest.mark.parametrize("name, chi", [("sphere", 2), ("ellipsoid", 2), ("torus", 0)])
def test_gauss_bonnet_chi_within_3_percent(name, chi, sigma):
    _, res = _estimate(name, sigma)
    gb = core.gauss_bonnet(res)
    assert gb.closed and gb.n_invalid == 0
    assert abs(gb.chi - chi) < 0.03 * 2  # 3 % of a sphere's chi; the torus' truth is 0
    assert gb.total == pytest.approx(core.total_curvature(res))
    assert isinstance(core.total_curvature(res), float)


def test_point_areas_sum_to_the_surface_area():
    s = shapes.sphere(5000, seed=0)
    areas, boundary = core.point_areas(s.points, s.normals)
    assert not boundary.any()
    assert areas.sum() == pytest.approx(4 * np.pi, rel=0.005)
    assert (areas > 0).all()
    t = shapes.torus(5000, seed=0)
    assert core.point_areas(t.points, t.normals)[0].sum() == pytest.approx(8 * np.pi**2, rel=0.01)


def test_point_areas_flag_the_boundary_of_an_open_surface():
    s = shapes.plane(4000, seed=0)
    areas, boundary = core.point_areas(s.points, s.normals)
    edge = (np.abs(s.points[:, :2]) > 0.97).any(axis=1)
    assert boundary[edge].mean() > 0.5 and boundary[s.interior].mean() < 0.01
    assert areas.sum() == pytest.approx(4.0, rel=0.03)  # boundary cells take the local density
    assert not core.gauss_bonnet(core.estimate(s.points, s.normals, k=15)).closed


def test_point_areas_reject_bad_input():
    s = shapes.sphere(100, seed=0)
    with pytest.raises(ValueError, match="k=2"):
        core.point_areas(s.points, s.normals, k=2)
    with pytest.raises(ValueError, match="normals"):
        core.point_areas(s.points, s.normals[:5])
    with pytest.raises(ValueError, match="more than k"):
        core.point_areas(s.points[:10], s.normals[:10])


# --------------------------------------------------------------------------- lines of curvature


def _torus_normal(p):
    phi = np.arctan2(p[:, 1], p[:, 0])
    ring = np.column_stack([2.0 * np.cos(phi), 2.0 * np.sin(phi), np.zeros(len(p))])
    d = p - ring
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _tangent_error_deg(line, truth_dir):
    """Angle between each chord, in the true tangent plane (noisy points jitter the height),
    and the true direction at its midpoint (a chord is parallel to its midpoint tangent)."""
    mid = 0.5 * (line[:-1] + line[1:])
    t = np.diff(line, axis=0)
    n = _torus_normal(mid)
    t -= n * (t * n).sum(1, keepdims=True)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    true = truth_dir(mid)
    return np.degrees(np.arccos(np.clip(np.abs((t * true).sum(1)), 0, 1)))


def _meridian_dir(p):  # the tube direction at fixed phi: normal-to-phi-plane complement
    phi = np.arctan2(p[:, 1], p[:, 0])
    rho = np.hypot(p[:, 0], p[:, 1])
    th = np.arctan2(p[:, 2], rho - 2.0)
    return np.column_stack([-np.sin(th) * np.cos(phi), -np.sin(th) * np.sin(phi), np.cos(th)])


def _parallel_dir(p):
    phi = np.arctan2(p[:, 1], p[:, 0])
    return np.column_stack([-np.sin(phi), np.cos(phi), np.zeros(len(p))])


@pytest.mark.parametrize("sigma", [0.0, 0.1])
def test_torus_lines_of_curvature_are_meridians_and_parallels(sigma):
    _, res = _estimate("torus", sigma)
    for direction, truth, angle in (("e1", _meridian_dir, "phi"), ("e2", _parallel_dir, "theta")):
        lines = core.curvature_lines(res, direction=direction)
        assert len(lines) > 10
        spreads, errors = [], []
        for line in lines:
            rho = np.hypot(line[:, 0], line[:, 1])
            a = np.arctan2(line[:, 1], line[:, 0]) if angle == "phi" else np.arctan2(line[:, 2], rho - 2.0)
            spreads.append(np.degrees(np.ptp(np.unwrap(a))))  # drift off its meridian / parallel
            errors.append(_tangent_error_deg(line, truth))
        errors = np.concatenate(errors)
        assert np.median(errors) < 1.0 and np.percentile(errors, 95) < 2.0
        assert np.percentile(spreads, 95) < 2.0
        if sigma == 0:
            assert max(spreads) < 2.0
        # every line closes into a loop (no umbilic, no boundary on a torus)
        lengths = np.array([np.linalg.norm(np.diff(line, axis=0), axis=1).sum() for line in lines])
        assert np.median(lengths) > (2 * np.pi * 0.9 if direction == "e1" else 2 * np.pi * 1.0)


def test_cylinder_e2_lines_are_straight_and_axial():
    s = shapes.cylinder(4000, seed=0)
    res = core.estimate(s.points, s.normals, k=20)
    lines = core.curvature_lines(res, direction="e2")
    assert len(lines) > 10
    for line in lines:
        centred = line - line.mean(0)
        _, sv, vt = np.linalg.svd(centred, full_matrices=False)
        assert abs(vt[0, 2]) > np.cos(np.deg2rad(1.0))  # along the axis
        assert sv[1] / np.sqrt(len(line)) < 0.003  # RMS off a straight line, radius 1
    e1_lines = core.curvature_lines(res, direction="e1")  # circles around the axis
    z_spread = [np.ptp(line[:, 2]) for line in e1_lines]
    assert np.median(z_spread) < 0.01


def test_lines_stop_at_umbilics():
    _, res = _estimate("sphere", 0.0)  # every point umbilic: no direction to follow
    lines = core.curvature_lines(res, direction="e1")
    assert all(len(line) <= 3 for line in lines)


def test_curvature_lines_reject_bad_arguments():
    _, res = _estimate("sphere", 0.0)
    with pytest.raises(ValueError, match="direction"):
        core.curvature_lines(res, direction="e3")
    with pytest.raises(ValueError, match="step"):
        core.curvature_lines(res, step=0)
    with pytest.raises(ValueError, match="seeds"):
        core.curvature_lines(res, seeds=[len(res) + 5])


# --------------------------------------------------------------------------- point types


@pytest.mark.parametrize("name, kind, share, sigma", [
    ("sphere", core.UMBILIC, 0.99, 0.0), ("sphere", core.UMBILIC, 0.99, 0.1),
    ("cylinder", core.PARABOLIC, 0.99, 0.0), ("plane", core.PLANAR, 0.99, 0.0),
    ("ellipsoid", core.ELLIPTIC, 0.95, 0.0), ("ellipsoid", core.ELLIPTIC, 0.95, 0.1),
])
def test_point_types_of_simple_shapes(name, kind, share, sigma):
    s, res = _estimate(name, sigma)
    types = core.point_types(res)[s.interior]
    assert (types == kind).mean() >= share


def test_torus_has_all_three_types_where_the_truth_says():
    s, res = _estimate("torus", 0.0)
    types = core.point_types(res)
    rho = np.hypot(s.points[:, 0], s.points[:, 1])
    theta = np.arctan2(s.points[:, 2], rho - 2.0)
    outer, inner = np.cos(theta) > 0.3, np.cos(theta) < -0.3
    band = np.abs(np.cos(theta)) < 0.05
    assert (types[outer] == core.ELLIPTIC).mean() > 0.99
    assert (types[inner] == core.HYPERBOLIC).mean() > 0.99
    assert (types[band] == core.PARABOLIC).mean() > 0.95


def test_point_types_flag_invalid_and_check_arguments():
    _, res = _estimate("sphere", 0.0)
    with pytest.raises(ValueError, match="zero"):
        core.point_types(res, zero=2)
    with pytest.raises(ValueError, match="scale"):
        core.point_types(res, scale=-1.0)
    bad = core.CurvatureResult(res.points, res.normals, np.where(np.arange(len(res)) < 3, np.nan, res.k1),
                               res.k2, res.e1, res.e2, np.arange(len(res)) >= 3, "nr", 15, 1)
    assert (core.point_types(bad)[:3] == -1).all()
    # scale invariance: the same shape 1000 x bigger has the same types
    big = core.CurvatureResult(res.points * 1000, res.normals, res.k1 / 1000, res.k2 / 1000, res.e1,
                               res.e2, res.valid, "nr", 15, 1)
    assert np.array_equal(core.point_types(big), core.point_types(res))


# --------------------------------------------------------------------------- local fit


def test_local_fit_on_a_sphere():
    s, res = _estimate("sphere", 0.0)
    fit = core.local_fit(res, 7)
    assert fit.kind == "umbilic"
    assert np.allclose(np.cross(fit.e1, fit.e2), fit.normal, atol=1e-9)
    theta, k = fit.measured_curvatures()
    assert np.median(np.abs(k - 1.0)) < 0.02  # every neighbour sees 1/R
    assert np.allclose(fit.normal_curvature(theta), 1.0, atol=0.02)
    # neighbours sit on the osculating paraboloid (up to the quartic term u^4 / 8R^3)
    u, v, w = fit.local.T
    assert np.abs(w - fit.height(u, v)).max() < 0.2 * fit.radius**4 + 1e-3
    circle = fit.osculating_circle(0.3)
    assert np.allclose(np.linalg.norm(circle, axis=1), 1.0, atol=0.02)  # the great circle
    assert np.linalg.norm(circle - fit.origin, axis=1).max() > 1.95  # the whole circle
    arc = fit.osculating_circle(0.3, reach=0.5)
    assert np.linalg.norm(arc - fit.origin, axis=1).max() == pytest.approx(0.5, rel=0.02)
    pieces = fit.dupin()
    assert len(pieces) == 1
    r = np.linalg.norm(pieces[0] - fit.origin, axis=1)
    assert np.ptp(r) < 0.05 * r.mean()  # a circle
    assert np.allclose(fit.fitted_normals()[:, 2], fit.local_normals[:, 2], atol=1e-2)
    assert fit.gauss_map_ratio() == pytest.approx(1.0, rel=0.1)  # |K| = 1 on the unit sphere


def test_local_fit_euler_formula_at_a_torus_saddle_point():
    s, res = _estimate("torus", 0.0)
    rho = np.hypot(s.points[:, 0], s.points[:, 1])
    i = int(np.argmin(rho))  # innermost: k1 = 1, k2 = -1
    fit = core.local_fit(res, i)
    assert fit.kind == "hyperbolic"
    assert fit.k1 == pytest.approx(1.0, abs=0.05) and fit.k2 == pytest.approx(-1.0, abs=0.05)
    theta, k = fit.measured_curvatures()
    assert np.median(np.abs(k - fit.normal_curvature(theta))) < 0.05
    assert len(fit.dupin()) == 4  # two hyperbola pairs
    s_, w_ = fit.section(0.0)
    assert len(s_) >= 3 and np.all(np.diff(s_) >= 0)
    assert fit.gauss_map_ratio() == pytest.approx(abs(fit.k1 * fit.k2), rel=0.1)
    flat = core.local_fit(res, int(np.argmin(np.abs(s.points[:, 2] + 1))))  # bottom: parabolic
    assert flat.kind == "parabolic" and len(flat.dupin()) == 2
    assert len(flat.osculating_circle(np.pi / 2)) == 2  # k_n ~ 0 along e2: a straight segment


def test_local_fit_rejects_bad_index():
    _, res = _estimate("sphere", 0.0)
    for bad in (-1, len(res), 1.5, True):
        with pytest.raises(ValueError, match="index"):
            core.local_fit(res, bad)
