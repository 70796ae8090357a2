"""QP and QN: the quadric z = a/2 x^2 + b xy + c/2 y^2 fitted to points or to normals (§3)."""

from __future__ import annotations

import numpy as np

from ..frame import quadratic_form
from ..linalg import weighted_lstsq
from ._result import MethodFit
from ._sanity import judged

QP_DOC = "Quadric fitted to points: a/2·u² + b·uv + c/2·v² = w (eq. 7), dn = -Hess."
QN_DOC = (
    "Quadric fitted to normals: a·u + b·v = -X/Z and b·u + c·v = -Y/Z (eqs. 8–9), dn = -Hess."
)


def fit_points(chunk):
    patch = chunk.patch
    u, v = patch.u, patch.v
    A = np.stack([0.5 * u * u, u * v, 0.5 * v * v], axis=2)
    x, ok = weighted_lstsq(A, patch.w)
    mu, W = quadratic_form(x[:, 0], x[:, 1], x[:, 2])
    return MethodFit(mu, W, judged(ok, W))


def normal_rows(patch):
    """Design rows and targets of the normal equations shared by QN, CN and CF. A
    neighbour's normal in the tangent plane (Z = 0: at its smallest k on a grid) gives an
    inf or NaN target: the point's curvatures come out non-finite and the frame flags it
    invalid (:func:`core.frame.darboux_frame`); targets near it, huge slopes: flagged by
    :func:`core.methods._sanity.judged`."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return -patch.X / patch.Z, -patch.Y / patch.Z


def fit_normals(chunk):
    patch = chunk.patch
    u, v = patch.u, patch.v
    zero = np.zeros_like(u)
    sx, sy = normal_rows(patch)
    A = np.concatenate([np.stack([u, v, zero], axis=2), np.stack([zero, u, v], axis=2)], axis=1)
    y = np.concatenate([sx, sy], axis=1)
    wt = np.concatenate([patch.weight, patch.weight], axis=1)
    x, ok = weighted_lstsq(A, y, wt)
    mu, W = quadratic_form(x[:, 0], x[:, 1], x[:, 2])
    return MethodFit(mu, W, judged(ok, W, (A, y, wt, x)))
