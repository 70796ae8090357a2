"""CF and CN: the cubic of Goldfeather & Interrante (2004) fitted to points and normals, or normals only (§3)."""

from __future__ import annotations

import numpy as np

from ..frame import quadratic_form
from ..linalg import weighted_lstsq
from ._result import MethodFit
from ._sanity import judged
from .quadric import normal_rows

CF_DOC = (
    "Cubic a/2·u² + b·uv + c/2·v² + d·u³ + e·u²v + f·uv² + g·v³ = w fitted to points (eq. 10) "
    "and normals (eqs. 11–12) together (Goldfeather & Interrante 2004); dn = -Hess."
)
CN_DOC = "The cubic of eq. 10 fitted to normals only (eqs. 11–12); dn = -Hess."


def _normal_design(u, v):
    zero = np.zeros_like(u)
    ax = np.stack([u, v, zero, 3 * u * u, 2 * u * v, v * v, zero], axis=2)  # eq. 11
    ay = np.stack([zero, u, v, zero, u * u, 2 * u * v, 3 * v * v], axis=2)  # eq. 12
    return ax, ay


def _solve(A, y, wt, first=0):
    """The fit; rows from ``first`` on are normal rows, judged by their slope residual."""
    x, ok = weighted_lstsq(A, y, wt)
    mu, W = quadratic_form(x[:, 0], x[:, 1], x[:, 2])
    return MethodFit(mu, W, judged(ok, W, (A[:, first:], y[:, first:], wt[:, first:], x)))


def fit_points_normals(chunk):
    patch = chunk.patch
    u, v = patch.u, patch.v
    ap = np.stack([0.5 * u * u, u * v, 0.5 * v * v, u**3, u * u * v, u * v * v, v**3], axis=2)
    ax, ay = _normal_design(u, v)
    sx, sy = normal_rows(patch)
    A = np.concatenate([ap, ax, ay], axis=1)
    y = np.concatenate([patch.w, sx, sy], axis=1)
    wt = np.concatenate([np.ones_like(u), patch.weight, patch.weight], axis=1)
    return _solve(A, y, wt, u.shape[1])


def fit_normals(chunk):
    patch = chunk.patch
    ax, ay = _normal_design(patch.u, patch.v)
    sx, sy = normal_rows(patch)
    A = np.concatenate([ax, ay], axis=1)
    y = np.concatenate([sx, sy], axis=1)
    wt = np.concatenate([patch.weight, patch.weight], axis=1)
    return _solve(A, y, wt)
