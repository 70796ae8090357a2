"""core.frame.darboux_frame runs in compiled loops (core.kernels.frame): it must give the
numpy code's numbers bit for bit (kept here as the reference), on valid and invalid rows."""

from __future__ import annotations

import numpy as np

from core.frame import darboux_frame, frame_valid
from core.linalg import symmetric_eig2, tangent_basis
from core.tuning import MAX_TILT2


def _numpy_frame(t1, t2, z, mu, W):
    """The numpy implementation the kernels replaced."""
    mu = np.asarray(mu, dtype=np.float64)
    X, Y = mu[:, 0], mu[:, 1]
    tilt2 = X * X + Y * Y
    ok = np.isfinite(tilt2) & (tilt2 < MAX_TILT2) & np.isfinite(W).all(axis=(1, 2))
    X = np.where(ok, X, 0.0)
    Y = np.where(ok, Y, 0.0)
    Z0 = np.sqrt(1.0 - X * X - Y * Y)
    Wc = np.where(ok[:, None, None], W, 0.0)

    # Local coordinates: n = (X, Y, Z0), r_u = (1, 0, fu), r_v = (0, 1, fv).
    fu, fv = -X / Z0, -Y / Z0
    ru_len = np.sqrt(1.0 + fu * fu)
    b1 = np.stack([1.0 / ru_len, np.zeros_like(X), fu / ru_len], axis=1)
    n_loc = np.stack([X, Y, Z0], axis=1)
    b2 = np.cross(n_loc, b1)
    # P = B^T [r_u r_v]: r_u . b2 = 0 by construction.
    p11 = ru_len
    p12 = b1[:, 2] * fv  # r_v . b1 = (0, 1, fv) . b1
    p22 = b2[:, 1] + b2[:, 2] * fv
    # S = P W P^-1 with P upper triangular.
    w11, w12, w21, w22 = Wc[:, 0, 0], Wc[:, 0, 1], Wc[:, 1, 0], Wc[:, 1, 1]
    pw11 = p11 * w11 + p12 * w21
    pw12 = p11 * w12 + p12 * w22
    pw21 = p22 * w21
    pw22 = p22 * w22
    # P^-1 = [[1/p11, -p12/(p11 p22)], [0, 1/p22]]
    s11 = pw11 / p11
    s12 = (-pw11 * p12 / p11 + pw12) / p22
    s21 = pw21 / p11
    s22 = (-pw21 * p12 / p11 + pw22) / p22
    k1, k2, c, s = symmetric_eig2(s11, 0.5 * (s12 + s21), s22)

    e1_loc = c[:, None] * b1 + s[:, None] * b2
    e2_loc = -s[:, None] * b1 + c[:, None] * b2
    to_world = np.stack([t1, t2, z], axis=1)  # (M, 3 local, 3 world)
    normal = np.einsum("mi,mij->mj", n_loc, to_world)
    e1 = np.einsum("mi,mij->mj", e1_loc, to_world)
    e2 = np.einsum("mi,mij->mj", e2_loc, to_world)
    ok &= np.isfinite(k1) & np.isfinite(k2)
    return normal, k1, k2, e1, e2, ok


def _awkward_rows(seed, m):
    """Frames' inputs with invalid rows: NaN and too tilted normals, infinite W, W over 12 decades."""
    rng = np.random.default_rng(seed)
    z = rng.normal(size=(m, 3))
    z /= np.linalg.norm(z, axis=1)[:, None]
    t1, t2 = tangent_basis(z)
    mu = rng.normal(scale=0.3, size=(m, 2))
    mu[::97], mu[::89] = np.nan, 2.0
    W = rng.normal(size=(m, 2, 2)) * rng.choice([1e-8, 1.0, 1e6], size=(m, 1, 1))
    W[::101, 0, 1] = np.inf
    return t1, t2, z, mu, W


def test_compiled_frame_is_the_numpy_frame_bit_for_bit():
    m = 20_000
    t1, t2, z, mu, W = _awkward_rows(4, m)  # and exact zeros (umbilics), symmetric rows
    W[::7, 0, 1] = W[::7, 1, 0]
    W[::13], mu[::13] = 0.0, 0.0
    got = darboux_frame(t1, t2, z, mu, W)
    ref = _numpy_frame(t1, t2, z, mu, W)
    assert got.ok.sum() > m // 2 and (~got.ok).sum() > m // 100
    for name, a, b in zip(("normal", "k1", "k2", "e1", "e2", "ok"), got, ref):
        np.testing.assert_array_equal(a, b, err_msg=name)
    assert (got.k1[got.ok] >= got.k2[got.ok]).all()


def test_frame_validity_alone_is_the_frames_own():
    """frame_valid (the crease reference's fits keep no frame) flags the rows darboux_frame does:
    NaN or too tilted normals, infinite W, and curvatures that overflow from a finite W."""
    m = 5000
    t1, t2, z, mu, W = _awkward_rows(7, m)
    W[::31] = 1e308  # finite, but k1 = inf
    with np.errstate(over="ignore", invalid="ignore"):
        ok = darboux_frame(t1, t2, z, mu, W).ok
        got = frame_valid(t1, t2, z, mu, W)
    assert ok.sum() > m // 2 and (~ok[::31]).all()
    np.testing.assert_array_equal(got, ok)


def test_frame_of_no_points():
    empty = np.empty((0, 3))
    out = darboux_frame(empty, empty, empty, np.empty((0, 2)), np.empty((0, 2, 2)))
    assert out.normal.shape == (0, 3) and out.ok.shape == (0,)
