"""The shape families that stress the automatic scale (issue 15): exact truth, density, views."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from core import shapes


def _graph_truth(s, h=1e-5):
    """H and K of a graph z = f(x, y) from the textbook formulas, f's derivatives by finite
    differences of the points' own heights (independent of the sampler's closed forms)."""
    terrain = {"chirp": None, "range_scan": shapes._bumps}[s.name]
    if terrain is None:
        a = s.params["amplitude"]

        def terrain(x, y):
            s_ = x + 1
            return (a * np.sin(2 * s_ + 1.75 * s_ * s_) * np.cos(3 * y),)
    f = lambda x, y: terrain(x, y)[0]  # noqa: E731
    x, y = s.points[:, 0], s.points[:, 1]
    fx = (f(x + h, y) - f(x - h, y)) / (2 * h)
    fy = (f(x, y + h) - f(x, y - h)) / (2 * h)
    g = 1e-3
    fxx = (f(x + g, y) - 2 * f(x, y) + f(x - g, y)) / g**2
    fyy = (f(x, y + g) - 2 * f(x, y) + f(x, y - g)) / g**2
    fxy = (f(x + g, y + g) - f(x + g, y - g) - f(x - g, y + g) + f(x - g, y - g)) / (4 * g * g)
    w2 = 1 + fx**2 + fy**2
    # upward normal, k > 0 where the graph bends down (a cap seen from above)
    H = -((1 + fy**2) * fxx - 2 * fx * fy * fxy + (1 + fx**2) * fyy) / (2 * w2**1.5)
    K = (fxx * fyy - fxy**2) / w2**2
    nrm = np.column_stack([-fx, -fy, np.ones_like(x)]) / np.sqrt(w2)[:, None]
    return f(x, y), nrm, H, K


@pytest.mark.parametrize("name", ["chirp", "range_scan"])
def test_graph_families_truth_matches_textbook_formulas(name):
    s = shapes.SHAPES[name](2000, seed=5)
    z, nrm, H, K = _graph_truth(s)
    np.testing.assert_allclose(s.points[:, 2], z, atol=1e-9)  # on the surface (noise-free scan)
    np.testing.assert_allclose(s.normals, nrm, atol=1e-7)
    np.testing.assert_allclose(s.mean, H, atol=1e-4 * max(1, np.abs(H).max()))
    np.testing.assert_allclose(s.gaussian, K, atol=1e-4 * max(1, np.abs(K).max()))
    # e1 is the direction of k1: II(e1, e1) = k1 with II = P Hess / w on the tangent plane
    assert np.abs(s.k1 - s.k2).max() > 1.0  # not umbilic: e1 means something


def test_chirp_curvature_grows_along_x():
    s = shapes.chirp(6000, seed=2)
    c = np.maximum(np.abs(s.k1), np.abs(s.k2))
    left, right = c[s.points[:, 0] < -0.5], c[s.points[:, 0] > 0.5]
    assert np.percentile(right, 90) > 4 * np.percentile(left, 90)


def test_graded_density_ratio():
    ratio = 10.0
    g = shapes.graded(8000, ratio=ratio, seed=3)
    u = shapes.saddle(8000, seed=3)  # area-uniform reference: same surface, same truth
    frac = lambda p, side: np.mean(side * p[:, 0] > 0.5)  # noqa: E731
    measured = (frac(g.points, 1) / frac(g.points, -1)) / (frac(u.points, 1) / frac(u.points, -1))
    assert 0.75 * ratio < measured < 1.3 * ratio
    # the truth is the saddle's: every point lies on the peanut with its normal and curvatures
    ex = np.array([1.0, 0, 0])
    F = ((g.points - ex) ** 2).sum(1) * ((g.points + ex) ** 2).sum(1) - 1.2**4
    np.testing.assert_allclose(F, 0, atol=1e-9)
    assert g.k2.min() < 0 < g.k1.min()
    with pytest.raises(ValueError, match="ratio"):
        shapes.graded(100, ratio=0.5)


def test_range_scan_is_one_view():
    s = shapes.range_scan(3000, seed=4)
    eye = np.asarray(s.params["view"])
    ray = s.points - eye
    rng_ = np.linalg.norm(ray, axis=1)
    # every point is the first hit along its ray: the segment from the eye stays above ground
    for t in np.linspace(0.05, 0.99, 40):
        p = eye + t * ray
        assert (p[:, 2] >= shapes._bumps(p[:, 0], p[:, 1])[0] - 1e-9).all()
    # facing the scanner, and sparser far away and at grazing angles
    cos_obl = -np.einsum("ij,ij->i", s.normals, ray) / rng_
    assert (cos_obl > 0).all()
    d = cKDTree(s.points).query(s.points, k=9)[0][:, -1]
    assert np.corrcoef(np.log(d), np.log(rng_**2 / cos_obl))[0, 1] > 0.3


def test_range_scan_noise_along_view_rays():
    clean = shapes.range_scan(2000, seed=6)
    noisy = shapes.range_scan(2000, noise=0.5, seed=6)
    eye = np.asarray(clean.params["view"])
    np.testing.assert_array_equal(clean.normals, noisy.normals)
    a, b = clean.points - eye, noisy.points - eye
    sin = np.linalg.norm(np.cross(a, b), axis=1) / np.linalg.norm(a, axis=1) / np.linalg.norm(b, axis=1)
    assert sin.max() < 1e-9
    shift = np.linalg.norm(noisy.points - clean.points, axis=1)
    spacing = cKDTree(clean.points).query(clean.points, k=2)[0][:, 1].mean()
    assert 0.3 * spacing < np.sqrt(np.mean(shift**2)) < 0.7 * spacing
    with pytest.raises(ValueError, match="view"):
        shapes.range_scan(100, view=(0, 0, 0.5))
