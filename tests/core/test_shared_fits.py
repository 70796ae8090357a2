"""Wide normal fits shared between nearby points (core.shared_fits): a satellite takes its
centre's cubic normal field at its own offset. Known answers: the field and its derivatives
of a known polynomial; a noisy sphere's curvature with and without sharing; the same result
on 1 and 2 threads; no satellite across a thin plate; noise-free clouds never share."""

from __future__ import annotations

import numba
import numpy as np
import pytest

import core
from core import noise, refinement, shapes, shapes_thin, shared_fits, tuning


def test_the_field_and_its_slopes_are_the_polynomials_at_the_offset():
    rng = np.random.default_rng(0)
    coef = rng.normal(size=(5, 2, 10))
    u, v = rng.uniform(-0.3, 0.3, 5), rng.uniform(-0.3, 0.3, 5)
    mu, W = shared_fits.field_at(coef, u, v, 3)

    def poly(c, a, b):
        return c[0] + c[1] * a + c[2] * b + c[3] * a * a + c[4] * a * b + c[5] * b * b + c[6] * a ** 3 \
            + c[7] * a * a * b + c[8] * a * b * b + c[9] * b ** 3

    e = 1e-6
    for m in range(5):
        for comp in range(2):
            c = coef[m, comp]
            assert mu[m, comp] == pytest.approx(poly(c, u[m], v[m]), abs=1e-12)
            assert W[m, comp, 0] == pytest.approx((poly(c, u[m] + e, v[m]) - poly(c, u[m] - e, v[m])) / (2 * e), abs=1e-7)
            assert W[m, comp, 1] == pytest.approx((poly(c, u[m], v[m] + e) - poly(c, u[m], v[m] - e)) / (2 * e), abs=1e-7)
    flat = shared_fits.field_at(coef[:, :, :3], u, v, 1)  # degree 1: constant slopes
    np.testing.assert_allclose(flat[1], coef[:, :, 1:3])


def test_the_projection_meets_the_symmetry_constraint():
    rng = np.random.default_rng(1)
    mu, W = rng.uniform(-0.3, 0.3, (6, 2)), rng.normal(size=(6, 2, 2))
    P = shared_fits.projected(mu, W)
    m1, m2 = mu[:, 0], mu[:, 1]
    g = np.stack([m1 * m2, -(1 - m2 * m2), 1 - m1 * m1, -m1 * m2], axis=1)
    np.testing.assert_allclose(np.einsum("mi,mi->m", g, P.reshape(6, 4)), 0.0, atol=1e-12)  # eq. 22


def _spy(monkeypatch):
    """Record the centre_of arrays the estimate uses (on its points in spatial order)."""
    seen = []
    original = refinement.satellites

    def spy(nb, nrm, kc, h, eligible):
        c = original(nb, nrm, kc, h, eligible)
        seen.append((nb.points, c))
        return c

    monkeypatch.setattr(refinement, "satellites", spy)
    return seen


@pytest.fixture(scope="module")
def noisy_sphere():
    s = shapes.sphere(12000, radius=1.0, seed=4)
    return noise.add_noise(s.points, 0.2, seed=5)


def test_a_noisy_sphere_shared_is_close_to_unshared_and_to_the_truth(noisy_sphere, monkeypatch):
    seen = _spy(monkeypatch)
    shared = core.estimate(noisy_sphere)
    share = (seen[-1][1] >= 0).mean()
    assert share > 0.5  # most points take a centre's fit
    monkeypatch.setattr(tuning, "SHARE_REACH", 0.0)
    own = core.estimate(noisy_sphere)
    assert seen[-1][1] is None
    H_shared, H_own = 0.5 * (shared.k1 + shared.k2), 0.5 * (own.k1 + own.k2)
    err_shared, err_own = (np.sqrt(np.nanmean((H - 1.0) ** 2)) for H in (H_shared, H_own))
    assert err_shared < 1.08 * err_own  # measured 1.02x
    assert err_shared < 0.03
    assert np.sqrt(np.nanmean((H_shared - H_own) ** 2)) < 0.5 * err_own  # close to the unshared estimate
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", shared.normals, own.normals), -1, 1))).max() < 2.0
    assert shared.valid.mean() == own.valid.mean() == 1.0


def test_one_and_two_threads_give_the_same_result(noisy_sphere):
    before = numba.get_num_threads()
    try:
        runs = []
        for threads in (1, min(2, numba.config.NUMBA_NUM_THREADS)):
            numba.set_num_threads(threads)
            runs.append(core.estimate(noisy_sphere[:6000]))
    finally:
        numba.set_num_threads(before)
    for name in ("normals", "k1", "k2", "e1", "valid", "k_point"):
        np.testing.assert_array_equal(getattr(runs[0], name), getattr(runs[1], name), err_msg=name)


def test_no_satellite_crosses_a_thin_plate(monkeypatch):
    s = shapes_thin.thin_plate(12000, thickness_spacings=3.0, seed=0)
    pts = shapes_thin.noisy(s, 0.5, seed=1)
    seen = _spy(monkeypatch)
    core.estimate(pts)
    sorted_pts, centre_of = seen[-1]
    assert centre_of is not None
    sat = np.flatnonzero(centre_of >= 0)
    sides = np.sign(sorted_pts[:, 2])
    face = np.abs(sorted_pts[:, 2]) > 0.25 * s.params["spacing"] * 3.0  # off the rim's middle
    both = sat[face[sat] & face[centre_of[sat]]]
    assert len(both) > 1000
    assert np.all(sides[both] == sides[centre_of[both]])


def test_a_noise_free_cloud_shares_nothing(monkeypatch):
    seen = _spy(monkeypatch)
    pts = shapes.torus(8000, seed=2).points
    a = core.estimate(pts)
    assert all(c is None for _, c in seen)
    monkeypatch.setattr(tuning, "SHARE_REACH", 0.0)
    b = core.estimate(pts)
    for name in ("normals", "k1", "k2", "e1", "valid"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
