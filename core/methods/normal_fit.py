"""NF: linear fitting of the neighbours' normal components (Cheng & Zhang 2009, §4.3–4.4)."""

from __future__ import annotations

import numpy as np

from ..linalg import solve_spd

NF_DOC = (
    "Normal fitting (§4.3–4.4): in a frame at p, fit X ≈ μ1 + w11·u + w12·v and "
    "Y ≈ μ2 + w21·u + w22·v to the neighbours' normal components by least squares "
    "(eqs. 25–26), enforce the symmetry constraint (eq. 22) by projecting w onto its plane, "
    "and read the Weingarten matrix from w (eq. 21). The refined normal is (μ1, μ2, Z0)."
)
NR_DOC = NF_DOC + " NR repeats the fit with the refined normals of all points (§4.4 end; 1 pass by default)."

#: weights: "uniform" (paper eqs. 25–26) or "theta" (eq. 14's kernel on the distance);
#: constraint: "project" (paper §4.4), "exact" (Lagrange multiplier in the metric of the
#: normal equations) or "none".
DEFAULTS = {"weights": "uniform", "constraint": "project"}
_WEIGHTS = ("uniform", "theta")
_CONSTRAINTS = ("project", "exact", "none")
THETA_REACH = 1.1  # h of eq. 14 in units of the k-th neighbour distance


def theta(x):
    """Eq. 14 kernel: (1 - x^2)^4 for x < 1, else 0."""
    return np.where(x < 1.0, (1.0 - np.minimum(x, 1.0) ** 2) ** 4, 0.0)


def _constraint_vector(mu):
    """Normal g of the symmetry plane g . (w11, w12, w21, w22) = 0 (eq. 22)."""
    m1, m2 = mu[:, 0], mu[:, 1]
    return np.stack([m1 * m2, -(1.0 - m2 * m2), 1.0 - m1 * m1, -m1 * m2], axis=1)


def fit(patch, *, weights="uniform", constraint="project"):
    """Fit (mu, W) per point; see :data:`NF_DOC`."""
    if weights not in _WEIGHTS:
        raise ValueError(f"weights {weights!r} is invalid; must be one of {list(_WEIGHTS)}")
    if constraint not in _CONSTRAINTS:
        raise ValueError(f"constraint {constraint!r} is invalid; must be one of {list(_CONSTRAINTS)}")
    wt = patch.weight
    if weights == "theta":
        wt = wt * theta(patch.dist / THETA_REACH)
    ones = np.ones_like(patch.u)
    A = np.stack([ones, patch.u, patch.v], axis=2)  # (M, k, 3): design of eqs. 25–26
    wa = A * wt[:, :, None]
    G = np.einsum("mip,miq->mpq", wa, A)
    rhs = np.einsum("mip,miq->mpq", wa, np.stack([patch.X, patch.Y], axis=2))
    coef, ok = solve_spd(G, rhs)  # (M, 3, 2): columns X and Y
    mu = coef[:, 0, :]
    w = np.stack([coef[:, 1, 0], coef[:, 2, 0], coef[:, 1, 1], coef[:, 2, 1]], axis=1)

    if constraint == "project":
        g = _constraint_vector(mu)
        w = w - (np.einsum("mi,mi->m", g, w) / np.einsum("mi,mi->m", g, g))[:, None] * g
    elif constraint == "exact":
        coef = _exact_constraint(G, coef, ok)
        mu = coef[:, 0, :]
        w = np.stack([coef[:, 1, 0], coef[:, 2, 0], coef[:, 1, 1], coef[:, 2, 1]], axis=1)
    W = w.reshape(-1, 2, 2)
    return mu, W, ok


def _exact_constraint(G, coef, ok, iterations=2):
    """Least squares under g(mu) . w = 0, the metric being the normal matrix G.

    For fixed g the minimiser of |A c_X - X|^2 + |A c_Y - Y|^2 subject to a . c = 0 is
    c = c0 - G^-1 a (a . c0) / (a . G^-1 a); g depends on mu, so iterate.
    """
    Gs = np.where(ok[:, None, None], G, np.eye(3))
    c0 = coef.copy()
    c = coef
    for _ in range(iterations):
        g = _constraint_vector(c[:, 0, :])
        a = np.zeros((len(G), 3, 2))
        a[:, 1:, 0] = g[:, 0:2]
        a[:, 1:, 1] = g[:, 2:4]
        Ginv_a = np.linalg.solve(Gs, a)
        num = np.einsum("mpq,mpq->m", a, c0)
        den = np.einsum("mpq,mpq->m", a, Ginv_a)
        den = np.where(np.abs(den) > 0, den, 1.0)
        c = c0 - Ginv_a * (num / den)[:, None, None]
    return c
