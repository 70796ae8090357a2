"""Whether a normal fit of degree 2-3 is determined does not depend on the tangent axes:
its pivots were those of the equilibrated normal matrix in axes fixed to the world, so a
turned cloud fitted other degrees at other points (a unit sphere, NF of degree 3 at k = 20:
81 points, H off by up to 0.57; the default on a noisy open patch: H off by up to 0.09
where |H| <= 0.1)."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.kernels.algebra import determined, n_terms, poly_row


def _turn(seed=1):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _normal_matrix(u, v, degree):
    p = n_terms(degree)
    rows = np.empty((len(u), p))
    for j in range(len(u)):
        poly_row(u[j], v[j], degree, rows[j])
    return rows.T @ rows


def _scaled_smallest_eigenvalue(G, degree):
    binomial = np.array([1, 1, 1, 1, 2, 1, 1, 3, 3, 1.0])[:len(G)]
    block = np.repeat(np.arange(degree + 1), np.arange(1, degree + 2))
    mean = np.array([np.sum((binomial * np.diag(G))[block == e]) / (e + 1) for e in range(degree + 1)])
    d = np.sqrt(binomial / mean[block])
    return np.linalg.eigvalsh(G * np.outer(d, d))[0]


@pytest.mark.parametrize("degree", [2, 3])
def test_the_determinacy_test_is_the_scaled_smallest_eigenvalue_in_any_axes(degree):
    rng = np.random.default_rng(degree)
    d, L = np.empty(10), np.empty((10, 10))
    for trial in range(40):
        u, v = rng.normal(size=(2, 25)) * rng.uniform(0.05, 3.0, size=(2, 1))  # anisotropic discs
        if trial % 4 == 0:
            v = np.round(v * 2) / 2  # rows: a dependence among the monomials
        G = _normal_matrix(u, v, degree)
        lam = _scaled_smallest_eigenvalue(G, degree)
        a = rng.uniform(0, 2 * np.pi)
        turned = _normal_matrix(np.cos(a) * u - np.sin(a) * v, np.sin(a) * u + np.cos(a) * v, degree)
        assert _scaled_smallest_eigenvalue(turned, degree) == pytest.approx(lam, rel=1e-6, abs=1e-12)
        for tau in (0.5 * lam, 2.0 * lam):
            if tau > 1e-9:
                assert determined(G, degree, tau, d, L) == (lam > tau)
                assert determined(turned, degree, tau, d, L) == (lam > tau)


@pytest.mark.parametrize("method", ["nf", "nr"])
def test_a_fit_of_degree_three_falls_alike_in_any_pose(method):
    rng = np.random.default_rng(0)
    sphere = rng.normal(size=(6000, 3))
    sphere /= np.linalg.norm(sphere, axis=1)[:, None]
    q = _turn()
    a = core.estimate(sphere, k=20, method=method, options={"degree": 3})
    b = core.estimate(sphere @ q.T, k=20, method=method, options={"degree": 3})
    np.testing.assert_array_equal(a.degree_point, b.degree_point)
    np.testing.assert_allclose(a.mean, b.mean, atol=1e-9)


def test_the_default_on_a_noisy_open_patch_is_the_same_in_any_pose():
    rng = np.random.default_rng(2)
    xy = rng.uniform(-1, 1, (8000, 2))
    patch = core.noise.add_noise(np.c_[xy, 0.3 * xy[:, 0] ** 2 - 0.2 * xy[:, 1] ** 2], 0.3)
    q = _turn()
    a, b = core.estimate(patch), core.estimate(patch @ q.T)
    np.testing.assert_array_equal(a.degree_point, b.degree_point)
    sign = np.sign(np.sum(a.normals * (b.normals @ q), axis=1))  # the sheet may face the other way
    both = a.valid & b.valid
    np.testing.assert_allclose(a.mean[both], sign[both] * b.mean[both], atol=1e-8)
