"""The compiled pieces of the robust normal fit against plain numpy: the monomials of the
neighbours, the median of the reweighting, and the whole Huber/Tukey IRLS of NF at degrees 1-3."""

import numpy as np
import pytest

import core
from core.kernels.algebra import MAX_TERMS, n_terms, poly_row
from core.kernels.lstsq import monomials
from core.kernels.robust import HUBER_C, MAD_SIGMA, MIN_SCALE, TUKEY_C, root_median, select
from core.methods import get_method
from core.patch import Chunk
from core.tuning import IRLS_ITERATIONS


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_monomials_row_by_row_are_poly_row_per_neighbour_to_the_last_bit(degree):
    """The NF kernel computes the monomials a row at a time (vectorised); the anchors' and
    the jets' readers evaluate poly_row's order of products: they must agree bit for bit,
    and leave the columns past n and the rows past the degree alone."""
    rng = np.random.default_rng(degree)
    n, width = 37, 40
    u, v = rng.normal(size=width) * 1.7, rng.normal(size=width) * 0.3
    R = np.full((MAX_TERMS, width), -7.0)
    monomials(u, v, n, degree, R)
    p = n_terms.py_func(degree)
    want = np.empty(MAX_TERMS)
    for j in range(n):
        poly_row.py_func(u[j], v[j], degree, want)
        assert np.array_equal(R[:p, j], want[:p])
    assert (R[p:] == -7.0).all() and (R[:, n:] == -7.0).all()


@pytest.mark.parametrize("size", [1, 2, 3, 7, 8, 15, 226, 227])
@pytest.mark.parametrize("kind", ["distinct", "repeated", "constant", "sorted", "reversed"])
def test_root_median_is_the_median_of_the_roots(size, kind):
    rng = np.random.default_rng(size)
    a = {"distinct": rng.random(size), "repeated": rng.integers(0, 3, size).astype(float),
         "constant": np.full(size, 0.25), "sorted": np.sort(rng.random(size)),
         "reversed": np.sort(rng.random(size))[::-1].copy()}[kind]
    want = np.median(np.sqrt(a))
    work = a.copy()
    assert root_median(work, size) == pytest.approx(want, rel=1e-15, abs=1e-300)
    assert np.array_equal(np.sort(work), np.sort(a))  # reordered, nothing lost or invented


@pytest.mark.parametrize("kth", [0, 1, 50, 98, 99])
def test_select_puts_the_kth_value_in_place(kth):
    a = np.random.default_rng(kth).integers(0, 10, 100).astype(float)  # many ties
    work = a.copy()
    select(work, 0, len(work), kth)
    assert work[kth] == np.sort(a)[kth]
    assert (work[:kth] <= work[kth]).all() and (work[kth + 1:] >= work[kth]).all()


def _numpy_irls(A, X, Y, base, robust):
    """The reweighting of core.kernels.robust, written from its formulas."""
    w = base.copy()
    for it in range(IRLS_ITERATIONS + 1):
        if it:
            r = np.hypot(X - A @ cx, Y - A @ cy)
            scale = max(MAD_SIGMA * np.median(r[base > 0]), MIN_SCALE)
            t = r / scale
            f = np.where(t <= HUBER_C, 1.0, HUBER_C / t) if robust == "huber" else \
                np.where(t < TUKEY_C, (1 - (t / TUKEY_C) ** 2) ** 2, 0.0)
            w = base * f
        sw = np.sqrt(w)
        cx = np.linalg.lstsq(A * sw[:, None], X * sw, rcond=None)[0]
        cy = np.linalg.lstsq(A * sw[:, None], Y * sw, rcond=None)[0]
    return cx, cy


@pytest.mark.parametrize("robust", ["huber", "tukey"])
@pytest.mark.parametrize("degree", [1, 2, 3])
def test_robust_normal_fit_matches_numpy_irls(robust, degree):
    """Noisy ellipsoid with a few normals flipped sideways (outlying residuals), 60 neighbours."""
    s = core.shapes.ellipsoid(2000, seed=5)
    p = core.noise.add_noise(s.points, 0.2, seed=6)
    nrm = s.normals.copy()
    bad = np.random.default_rng(7).random(len(p)) < 0.05
    nrm[bad] = np.cross(nrm[bad], [0.0, 0.0, 1.0]) + 0.3 * nrm[bad]
    nrm[bad] /= np.linalg.norm(nrm[bad], axis=1, keepdims=True)
    nrm[3] = np.nan  # a neighbour without a normal has weight 0 and no say in the median
    nb = core.build_neighbours(p, 60)
    idx, dist = nb.take(60)
    centres = np.arange(4, 40)
    chunk = Chunk.build(p, nrm, idx[centres], dist[centres, -1], centres)
    mu, W, ok, diag = get_method("nf").fit(chunk, constraint="none", degree=degree, robust=robust)
    pa = chunk.patch
    u, v = pa.u, pa.v
    cols = [np.ones_like(u), u, v, u * u, u * v, v * v, u**3, u * u * v, u * v * v, v**3]
    assert ok.all()
    # a fit its neighbours do not determine falls a degree (measured: 1 of the 36 cubics, pivot 5e-3)
    assert (diag["degree"] <= degree).all() and np.mean(diag["degree"] == degree) > 0.9
    for r in range(len(centres)):
        d = diag["degree"][r]
        A = np.stack(cols[:(d + 1) * (d + 2) // 2], axis=2)
        cx, cy = _numpy_irls(A[r], pa.X[r], pa.Y[r], pa.weight[r], robust)
        np.testing.assert_allclose(mu[r], [cx[0], cy[0]], atol=1e-9)
        np.testing.assert_allclose(W[r], [[cx[1], cx[2]], [cy[1], cy[2]]], atol=1e-7)
