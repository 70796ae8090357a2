"""The test fixtures themselves: analytic shapes (truth and sampling), noise, metrics."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.integrate import quad

from core import metrics, noise, shapes

# ----------------------------------------------------------------------------- shapes


@pytest.mark.parametrize("name", list(shapes.SHAPES))
def test_sample_frames_are_orthonormal(name):
    s = shapes.SHAPES[name](3000, seed=4)
    assert s.name == name
    n = len(s.points)
    assert n == 3000
    for f in ("points", "normals", "e1", "e2"):
        assert getattr(s, f).shape == (n, 3) and np.isfinite(getattr(s, f)).all()
    for f in ("normals", "e1", "e2"):
        np.testing.assert_allclose(np.linalg.norm(getattr(s, f), axis=1), 1, atol=1e-12)
    for a, b in (("normals", "e1"), ("normals", "e2"), ("e1", "e2")):
        assert np.abs(np.einsum("ij,ij->i", getattr(s, a), getattr(s, b))).max() < 1e-12
    assert np.all(s.k1 >= s.k2)
    np.testing.assert_allclose(s.mean, (s.k1 + s.k2) / 2)
    np.testing.assert_allclose(s.gaussian, s.k1 * s.k2)
    assert s.interior.dtype == bool and s.interior.shape == (n,) and s.interior.mean() > 0.4


@pytest.mark.parametrize("name", list(shapes.SHAPES))
def test_samples_reproducible(name):
    a = shapes.SHAPES[name](500, seed=3)
    b = shapes.SHAPES[name](500, seed=3)
    c = shapes.SHAPES[name](500, seed=4)
    np.testing.assert_array_equal(a.points, b.points)
    assert not np.array_equal(a.points, c.points)


@pytest.mark.parametrize("R, r", [(2.0, 1.0), (3.0, 0.5)])
def test_torus_truth_matches_spec(R, r):
    s = shapes.torus(4000, R=R, r=r, seed=1)
    x, y, z = s.points.T
    rho = np.hypot(x, y)
    np.testing.assert_allclose((rho - R) ** 2 + z**2, r * r, rtol=1e-12)  # on the surface
    theta = np.arctan2(z, rho - R)
    phi = np.arctan2(y, x)
    ct, st, cp, sp = np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    np.testing.assert_allclose(s.normals, np.column_stack([ct * cp, ct * sp, st]), atol=1e-12)
    # k_tube = 1/r >= k_ring = cos(theta) / (R + r cos(theta)) everywhere
    np.testing.assert_allclose(s.k1, 1 / r, rtol=1e-12)
    np.testing.assert_allclose(s.k2, ct / (R + r * ct), atol=1e-12)
    tube = np.column_stack([-st * cp, -st * sp, ct])
    ring = np.column_stack([-sp, cp, np.zeros_like(sp)])
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", s.e1, tube)), 1, atol=1e-12)
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", s.e2, ring)), 1, atol=1e-12)
    np.testing.assert_allclose(s.gaussian, ct / (r * (R + r * ct)), atol=1e-12)


@pytest.mark.parametrize("R, r", [(2.0, 1.0), (3.0, 1.0)])
def test_torus_sampling_is_area_uniform(R, r):
    """Density in theta is (R + r cos theta) / (2 pi R), uniform in phi. Hence
    P(cos theta > 0) = (pi R + 2 r) / (2 pi R)  (0.659 for R=2, r=1; 0.606 for R=3, r=1;
    a theta-uniform sampler gives 0.5) and E[cos theta] = r / (2 R)."""
    n = 20000
    s = shapes.torus(n, R=R, r=r, seed=2)
    rho = np.hypot(s.points[:, 0], s.points[:, 1])
    cos_t = (rho - R) / r
    expected = (np.pi * R + 2 * r) / (2 * np.pi * R)
    se = np.sqrt(expected * (1 - expected) / n)  # 0.0034
    assert abs(np.mean(cos_t > 0) - expected) < 4 * se
    assert abs(np.mean(cos_t) - r / (2 * R)) < 0.02
    phi = np.arctan2(s.points[:, 1], s.points[:, 0])
    counts = np.histogram(phi, bins=8, range=(-np.pi, np.pi))[0]
    assert np.all(np.abs(counts / n - 1 / 8) < 0.012)


def test_implicit_sampling_is_area_uniform():
    """Prolate spheroid (1, 1, 2): the area fraction with |z| < 1 is 0.566 (by quadrature);
    sampling uniform directions instead would give 0.756."""
    a, c = 1.0, 2.0

    def ring_area(z):
        x = a * np.sqrt(1 - (z / c) ** 2)
        dx = -a * z / (c * c * np.sqrt(1 - (z / c) ** 2))
        return 2 * np.pi * x * np.sqrt(1 + dx * dx)

    frac = quad(ring_area, -1, 1)[0] / quad(ring_area, -c, c, points=[-c, c])[0]
    n = 20000
    s = shapes.ellipsoid(n, axes=(a, a, c), seed=1)
    se = np.sqrt(frac * (1 - frac) / n)
    assert abs(np.mean(np.abs(s.points[:, 2]) < 1) - frac) < 4 * se


def test_sphere_cylinder_plane_truth():
    s = shapes.sphere(1000, radius=2.5, seed=0)
    np.testing.assert_allclose(np.linalg.norm(s.points, axis=1), 2.5)
    np.testing.assert_allclose(s.normals, s.points / 2.5, atol=1e-12)
    np.testing.assert_allclose(s.k1, 0.4) and np.testing.assert_allclose(s.k2, 0.4)
    c = shapes.cylinder(1000, radius=0.7, height=3.0, seed=0)
    np.testing.assert_allclose(np.hypot(c.points[:, 0], c.points[:, 1]), 0.7)
    np.testing.assert_allclose(c.k1, 1 / 0.7) and np.testing.assert_allclose(c.k2, 0, atol=0)
    np.testing.assert_allclose(np.abs(c.e2[:, 2]), 1)
    np.testing.assert_allclose(c.normals[:, :2] * 0.7, c.points[:, :2], atol=1e-12)
    assert np.all(np.abs(c.points[c.interior, 2]) < 1.5) and not c.interior.all()
    p = shapes.plane(1000, size=2.0, seed=0)
    assert np.all(p.points[:, 2] == 0) and np.all(p.k1 == 0) and np.all(p.normals[:, 2] == 1)
    assert np.all(np.abs(p.points[p.interior, :2]) < 0.9)


def _implicit_truth(p, grad, hess):
    """K and H of F = 0 with the normal grad F / |grad F| (independent formulas):
    K = -det([[Hess, g], [g^T, 0]]) / |g|^4,  H = (|g|^2 tr Hess - g^T Hess g) / (2 |g|^3)."""
    g, Hs = grad(p), hess(p)
    m = len(p)
    B = np.zeros((m, 4, 4))
    B[:, :3, :3] = Hs
    B[:, :3, 3] = g
    B[:, 3, :3] = g
    gn = np.linalg.norm(g, axis=1)
    K = -np.linalg.det(B) / gn**4
    H = (gn**2 * np.trace(Hs, axis1=1, axis2=2) - np.einsum("mi,mij,mj->m", g, Hs, g)) / (2 * gn**3)
    return K, H


def test_ellipsoid_truth_closed_form():
    a, b, c = 1.5, 1.0, 0.75
    s = shapes.ellipsoid(3000, axes=(a, b, c), seed=2)
    x, y, z = s.points.T
    np.testing.assert_allclose(x**2 / a**2 + y**2 / b**2 + z**2 / c**2, 1, atol=1e-12)
    S = x**2 / a**4 + y**2 / b**4 + z**2 / c**4
    K = 1 / (a * b * c) ** 2 / S**2
    H = (a * a + b * b + c * c - (x * x + y * y + z * z)) / (2 * (a * b * c) ** 2 * S**1.5)
    np.testing.assert_allclose(s.gaussian, K, rtol=1e-10)
    np.testing.assert_allclose(s.mean, H, rtol=1e-10)
    assert np.all(np.einsum("ij,ij->i", s.normals, s.points) > 0)  # outward


def test_saddle_truth_matches_implicit_formulas():
    a, b = 1.0, 1.2
    s = shapes.saddle(3000, a=a, b=b, seed=2)
    p = s.points
    x, r2 = p[:, 0], (p * p).sum(1)
    # Cassini surface: (r2 + a^2)^2 - 4 a^2 x^2 = b^4, expanded independently of core
    np.testing.assert_allclose((r2 + a * a) ** 2 - 4 * a * a * x * x - b**4, 0, atol=1e-12)
    ex = np.array([1.0, 0, 0])

    def grad(q):
        rr = (q * q).sum(1)[:, None]
        return 4 * (rr + a * a) * q - 8 * a * a * q[:, :1] * ex

    def hess(q):
        rr = (q * q).sum(1)
        return (4 * (rr + a * a))[:, None, None] * np.eye(3) + 8 * np.einsum("mi,mj->mij", q, q) \
            - 8 * a * a * np.outer(ex, ex)

    K, H = _implicit_truth(p, grad, hess)
    np.testing.assert_allclose(s.gaussian, K, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(s.mean, H, rtol=1e-9, atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", s.normals, p) > 0)


@pytest.mark.parametrize("b", [1.1, 1.2, 1.35])
def test_saddle_shape_has_negative_gaussian_curvature(b):
    s = shapes.saddle(4000, b=b, seed=4)
    assert np.mean(s.gaussian < 0) > 0.05


def test_hyperbolic_paraboloid_helper_truth(hypar):
    """The tests' own saddle z = a(x^2 - y^2) (conftest.graph_truth) against the graph
    closed forms K = (fxx fyy - fxy^2) / g^4 = -4a^2 / g^4 and, with the upward normal and
    k = +1/R on a cap, H = -((1 + fy^2) fxx - 2 fx fy fxy + (1 + fx^2) fyy) / (2 g^3)."""
    a = hypar.params["a"]
    x, y, _ = hypar.points.T
    g2 = 1 + 4 * a * a * (x * x + y * y)
    np.testing.assert_allclose(hypar.gaussian, -4 * a * a / g2**2, rtol=1e-10)
    fx, fy = 2 * a * x, -2 * a * y
    H = -((1 + fy**2) * 2 * a + (1 + fx**2) * (-2 * a)) / (2 * g2**1.5)
    np.testing.assert_allclose(hypar.mean, H, atol=1e-12)
    assert np.all(hypar.normals[:, 2] > 0)


def test_shape_argument_validation():
    with pytest.raises(ValueError, match="n=5 is out of range"):
        shapes.sphere(5)
    with pytest.raises(ValueError, match=r"torus needs R > r > 0, got R=1.0, r=2.0"):
        shapes.torus(100, R=1.0, r=2.0)
    with pytest.raises(ValueError, match=r"saddle needs a < b < sqrt\(2\) a, got a=1.0, b=2.0"):
        shapes.saddle(100, b=2.0)


# ----------------------------------------------------------------------------- noise


@pytest.fixture(scope="module")
def grid():
    """A unit-spaced 40 x 40 grid: mean spacing exactly 1."""
    g = np.stack(np.meshgrid(np.arange(40.0), np.arange(40.0)), -1).reshape(-1, 2)
    return np.column_stack([g, np.zeros(len(g))])


def test_mean_spacing_known(grid):
    assert noise.mean_spacing(grid) == pytest.approx(1.0)
    assert noise.mean_spacing(grid * 3) == pytest.approx(3.0)
    with pytest.raises(ValueError, match="at least 2 points, got 1"):
        noise.mean_spacing(grid[:1])


def test_noise_reproducible_and_pure(grid):
    before = grid.copy()
    a = noise.add_noise(grid, 0.2, seed=5)
    b = noise.add_noise(grid, 0.2, seed=5)
    c = noise.add_noise(grid, 0.2, seed=6)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    np.testing.assert_array_equal(grid, before)
    np.testing.assert_array_equal(noise.add_noise(grid, 0.0), grid)


@pytest.mark.parametrize("scale", [1.0, 10.0, 0.01])
def test_relative_sigma_scales_with_spacing(scale, grid):
    pts = grid * scale
    d = noise.add_noise(pts, 0.2, seed=1) - pts
    # isotropic: every coordinate ~ N(0, (0.2 * spacing)^2); 3 x 1600 samples, se ~ 1.3%
    assert np.std(d) == pytest.approx(0.2 * scale, rel=0.05)
    assert abs(np.mean(d)) < 0.02 * scale
    assert np.std(d[:, 2]) == pytest.approx(0.2 * scale, rel=0.08)
    # absolute sigma ignores the spacing; an explicit spacing is used as given
    d_abs = noise.add_noise(pts, 0.2, relative=False, seed=1) - pts
    assert np.std(d_abs) == pytest.approx(0.2, rel=0.05)
    d_sp = noise.add_noise(pts, 0.2, spacing=5.0, seed=1) - pts
    assert np.std(d_sp) == pytest.approx(1.0, rel=0.05)


def test_noise_along_normals():
    s = shapes.sphere(3000, seed=2)
    d = noise.add_noise(s.points, 0.5, normals=s.normals, direction="normal", seed=3) - s.points
    along = np.einsum("ij,ij->i", d, s.normals)
    np.testing.assert_allclose(d, along[:, None] * s.normals, atol=1e-12)
    assert np.std(along) == pytest.approx(0.5 * noise.mean_spacing(s.points), rel=0.06)
    with pytest.raises(ValueError, match="needs normals"):
        noise.add_noise(s.points, 0.5, direction="normal")


@pytest.mark.parametrize(
    "kw, match",
    [(dict(sigma=-1), "sigma must be a finite number >= 0, got -1"),
     (dict(sigma=np.nan), "sigma must be a finite number >= 0"),
     (dict(sigma=0.1, direction="radial"), "direction 'radial' is invalid")],
)
def test_noise_bad_arguments(kw, match, grid):
    with pytest.raises(ValueError, match=match):
        noise.add_noise(grid, **kw)


@pytest.mark.parametrize("fraction", [0.0, 0.013, 0.25])
def test_outliers_count_mask_and_distance(fraction, grid):
    out, mask = noise.add_outliers(grid, fraction, distance=(5.0, 20.0), seed=2)
    assert mask.dtype == bool and mask.shape == (len(grid),)
    assert mask.sum() == round(fraction * len(grid))
    np.testing.assert_array_equal(out[~mask], grid[~mask])
    moved = np.linalg.norm(out[mask] - grid[mask], axis=1)
    assert np.all((moved >= 5.0 - 1e-9) & (moved <= 20.0 + 1e-9))  # spacing is 1
    again, mask2 = noise.add_outliers(grid, fraction, distance=(5.0, 20.0), seed=2)
    np.testing.assert_array_equal(again, out)
    np.testing.assert_array_equal(mask2, mask)


def test_outliers_bad_arguments(grid):
    with pytest.raises(ValueError, match=r"fraction must be in \[0, 1\), got 1.0"):
        noise.add_outliers(grid, 1.0)
    with pytest.raises(ValueError, match="distance must be"):
        noise.add_outliers(grid, 0.1, distance=(5.0, 1.0))


# ----------------------------------------------------------------------------- metrics


def _fake(sample, **over):
    """A result-like object holding the sample's exact frame (what metrics reads)."""
    f = dict(points=sample.points, normals=sample.normals, k1=sample.k1, k2=sample.k2,
             e1=sample.e1, e2=sample.e2, valid=np.ones(len(sample.points), bool))
    f.update(over)
    return SimpleNamespace(**f)


def test_metrics_zero_for_the_truth(torus):
    err = metrics.point_errors(_fake(torus), torus)
    for key in ("k1", "k2", "gaussian", "mean", "normal_deg"):
        assert np.nanmax(err[key]) < 1e-5, key  # normal_deg: arccos(1 - eps) ~ 1.5e-6 deg
    assert np.nanmax(err["direction_deg"]) < 1e-5
    summ = metrics.summary(_fake(torus), torus)
    for key in ("k1", "k2", "gaussian", "mean", "normal_deg", "direction_deg", "invalid_fraction", "flipped_fraction"):
        assert summ[key] < 1e-5, key


def test_metrics_flipped_truth_is_still_perfect(torus):
    """Flipped normals: k -> -k swapped, e1 <-> e2; metrics align to the sample's orientation."""
    r = _fake(torus, normals=-torus.normals, k1=-torus.k2, k2=-torus.k1, e1=torus.e2, e2=-torus.e1)
    s = metrics.summary(r, torus)
    assert s["flipped_fraction"] == 1.0
    for key in ("k1", "k2", "gaussian", "mean", "direction_deg"):
        assert s[key] < 1e-5


def test_metrics_known_errors(torus):
    r = _fake(torus, k1=torus.k1 + 0.1, e1=torus.e2, e2=torus.e1)
    err = metrics.point_errors(r, torus)
    np.testing.assert_allclose(err["k1"], 0.1, rtol=1e-9)
    np.testing.assert_allclose(err["k2"], 0, atol=1e-12)
    np.testing.assert_allclose(err["mean"], 0.05, rtol=1e-9)  # H = (k1 + k2) / 2
    np.testing.assert_allclose(err["gaussian"], 0.1 * np.abs(torus.k2), rtol=1e-9, atol=1e-12)
    # swapped directions are 90 degrees off (the torus has no umbilics)
    np.testing.assert_allclose(err["direction_deg"], 90.0, atol=1e-6)


def test_metrics_invalid_and_interior_and_umbilics(cylinder, torus):
    valid = np.ones(len(torus.points), bool)
    valid[:100] = False
    r = _fake(torus, k1=torus.k1 + 1.0, valid=valid)
    err = metrics.point_errors(r, torus)
    assert np.isnan(err["k1"][:100]).all() and np.all(err["k1"][100:] == pytest.approx(1.0))
    s = metrics.summary(r, torus)
    assert s["invalid_fraction"] == pytest.approx(100 / len(valid))
    assert s["k1"] == pytest.approx(1.0)
    # outside the interior is ignored
    bad = cylinder.k1.copy()
    bad[~cylinder.interior] += 5
    assert metrics.summary(_fake(cylinder, k1=bad), cylinder)["k1"] < 1e-12
    # directions are undefined at umbilics: NaN on a sphere
    sph = shapes.sphere(500, seed=0)
    assert np.isnan(metrics.point_errors(_fake(sph), sph)["direction_deg"]).all()
    with pytest.raises(ValueError, match="result has 500 points but sample has"):
        metrics.point_errors(_fake(sph), torus)


def test_metrics_mask(torus):
    r = _fake(torus, k1=torus.k1 + np.where(np.arange(len(torus.points)) < 10, 1.0, 0.0))
    mask = np.zeros(len(torus.points), bool)
    mask[:10] = True
    assert metrics.summary(r, torus, mask=mask)["k1"] == pytest.approx(1.0)
    assert metrics.summary(r, torus, mask=~mask)["k1"] == pytest.approx(0.0)
