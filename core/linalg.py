"""Small batched linear algebra: tangent bases, weighted least squares, 2x2 eigen-pairs."""

from __future__ import annotations

import numpy as np

from .tuning import RCOND


def tangent_basis(n: np.ndarray):
    """Orthonormal (t1, t2) with t1 x t2 = n for unit normals n of shape (M, 3)."""
    # Householder-free branchless basis (Duff et al. 2017, "Building an orthonormal basis, revisited").
    sign = np.where(n[:, 2] >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    t1 = np.stack([1.0 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
    t2 = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    return t1, t2


def weighted_lstsq(A: np.ndarray, y: np.ndarray, w: np.ndarray | None = None):
    """Solve ``min sum_i w_i (A_i x - y_i)^2`` for a batch of small problems.

    Parameters
    ----------
    A : (M, m, p) design matrices.
    y : (M, m) or (M, m, q) right-hand sides (q problems sharing one design).
    w : (M, m) non-negative row weights, optional.

    Returns
    -------
    x : (M, p) or (M, p, q) solutions (zeros where singular).
    ok : (M,) bool, False where the problem is rank deficient.
    """
    wa = A if w is None else A * w[:, :, None]
    G = np.einsum("mip,miq->mpq", wa, A)
    rhs = np.einsum("mip,mi...->mp...", wa, y)
    return solve_spd(G, rhs)


def solve_spd(G: np.ndarray, rhs: np.ndarray):
    """Solve batched symmetric positive (semi-)definite systems, flagging singular ones.

    The matrices are equilibrated (unit diagonal) before the conditioning test, so the
    test does not depend on the units of the unknowns.
    """
    d = np.sqrt(np.einsum("mii->mi", G))
    good_diag = d > 0
    d = np.where(good_diag, d, 1.0)
    Gs = G / (d[:, :, None] * d[:, None, :])
    eig = np.linalg.eigvalsh(Gs)
    ok = good_diag.all(axis=1) & (eig[:, 0] > RCOND * np.maximum(eig[:, -1], 1e-300))
    Gs[~ok] = np.eye(G.shape[1])
    vec = rhs.ndim == 2
    r = rhs[:, :, None] if vec else rhs
    xs = np.linalg.solve(Gs, r / d[:, :, None])
    x = xs / d[:, :, None]
    x[~ok] = 0.0
    return (x[:, :, 0] if vec else x), ok


def symmetric_eig2(a: np.ndarray, b: np.ndarray, c: np.ndarray):
    """Eigen-pairs of symmetric 2x2 matrices [[a, b], [b, c]].

    Returns ``(l1, l2, cos, sin)`` with l1 >= l2 and (cos, sin) the unit eigenvector of l1.
    """
    mean = 0.5 * (a + c)
    half = 0.5 * (a - c)
    rad = np.hypot(half, b)
    phi = 0.5 * np.arctan2(b, half)
    return mean + rad, mean - rad, np.cos(phi), np.sin(phi)
