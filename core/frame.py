"""The one shared path from fitted normal derivatives to the augmented Darboux frame.

Every method ends here: it reports, in a local orthonormal frame (t1, t2, z) at p,
the normal at p as its first two components mu = (X, Y) and the derivatives of the
normal components along the frame's tangent coordinates,

    W = [[X_u, X_v],
         [Y_u, Y_v]]          (paper eq. 21: the matrix of dn in the basis r_u, r_v).

Point-fitting methods (z = f(u, v) with the frame's z as normal) report mu = 0 and
W = -Hess f(0, 0).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .kernels.frame import frame_curvatures, frame_directions
from .tuning import MAX_TILT2


class DarbouxFrame(NamedTuple):
    """The augmented Darboux frame of M points: ``normal``, ``e1``, ``e2`` (M, 3),
    ``k1`` >= ``k2`` (M,) and ``ok`` (M,) bool."""

    normal: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    ok: np.ndarray


def darboux_frame(t1, t2, z, mu, W):
    """Normal, principal curvatures and directions from (mu, W) in local frames.

    Parameters
    ----------
    t1, t2, z : (M, 3) orthonormal local frames (z is the current normal).
    mu : (M, 2) fitted normal components (X, Y) at p (paper eqs. 25–26).
    W : (M, 2, 2) fitted normal derivatives (eq. 21), in the height-field basis.

    Returns
    -------
    DarbouxFrame: normal, e1, e2 : (M, 3); k1, k2 : (M,) with k1 >= k2; ok : (M,) bool.

    Notes
    -----
    With Z0 = sqrt(1 - X^2 - Y^2), f_u = -X/Z0 and f_v = -Y/Z0 (eq. A1), the tangent
    vectors are r_u = (1, 0, f_u), r_v = (0, 1, f_v). dn maps r_u -> n_u, r_v -> n_v,
    so its matrix in (r_u, r_v) is W. In an orthonormal basis B = (b1, b2) of the tangent
    plane, with P = B^T [r_u r_v], the matrix is S = P W P^-1, symmetric for exact data
    (the symmetry constraint, eq. 22). It is symmetrised and diagonalised; the
    eigenvalues are k1 >= k2 (eq. 5), with the sign convention k = +1/R on a sphere
    with outward normals. Computed per point in :mod:`core.kernels.frame`.
    """
    t1, t2, z, mu, normal, k1, k2, yx, ok = _curvatures(t1, t2, z, mu, W)
    m = len(mu)
    e1, e2 = np.empty((m, 3)), np.empty((m, 3))
    phi = 0.5 * np.arctan2(yx[:, 0], yx[:, 1])
    frame_directions(t1, t2, z, mu, ok, np.cos(phi), np.sin(phi), e1, e2)
    ok &= np.isfinite(k1) & np.isfinite(k2)
    return DarbouxFrame(normal, k1, k2, e1, e2, ok)


def frame_valid(t1, t2, z, mu, W) -> np.ndarray:
    """(M,) bool: :func:`darboux_frame`'s ``ok`` alone (mu and W usable, k1 and k2 finite), without
    the principal directions (a fit read only for its residuals keeps no frame)."""
    *_, k1, k2, _, ok = _curvatures(t1, t2, z, mu, W)
    return ok & np.isfinite(k1) & np.isfinite(k2)


def _curvatures(t1, t2, z, mu, W):
    """The contiguous ``t1, t2, z, mu`` and :func:`core.kernels.frame.frame_curvatures`' ``normal,
    k1, k2, yx, ok`` of :func:`darboux_frame`."""
    t1, t2, z = (np.ascontiguousarray(a, dtype=np.float64) for a in (t1, t2, z))
    mu = np.ascontiguousarray(mu, dtype=np.float64)
    W = np.ascontiguousarray(W, dtype=np.float64)
    m = len(mu)
    normal, k1, k2, yx, ok = np.empty((m, 3)), np.empty(m), np.empty(m), np.empty((m, 2)), np.empty(m, dtype=bool)
    frame_curvatures(t1, t2, z, mu, W, MAX_TILT2, normal, k1, k2, yx, ok)
    return t1, t2, z, mu, normal, k1, k2, yx, ok


def turned_over(normal, k1, k2, e1, e2, flip):
    """The frame with its normal turned over where ``flip`` (N,) bool: k1, k2 -> -k2, -k1 and
    e1 <-> e2, so that k1 >= k2 and e1 x e2 = n still hold (the SPEC conventions)."""
    col = flip[:, None]
    return (np.where(col, -normal, normal), np.where(flip, -k2, k1), np.where(flip, -k1, k2),
            np.where(col, e2, e1), np.where(col, e1, e2))


#: the world direction that fixes the principal directions' signs (generic, so that no axis-aligned
#: sampling puts whole rows of points on the tie e1 . DIRECTION_SIGN = 0)
DIRECTION_SIGN = np.array([0.5773, 0.6236, 0.5270]) / np.linalg.norm([0.5773, 0.6236, 0.5270])


def signed_directions(e1, e2):
    """``e1, e2`` both negated where ``e1 . DIRECTION_SIGN < 0`` (e1 x e2 = n still holds).

    A principal direction's sign is arbitrary; the fit's own sign depends on its tangent
    frame and on which way the normal was turned when (:func:`turned_over`), so the same
    surface read in tiles or in memory, or refined in another number of passes, would
    show e1 both ways. One world rule makes the field reproducible and its glyphs coherent.
    NaN rows stay NaN.
    """
    flip = (e1 @ DIRECTION_SIGN < 0)[:, None]
    return np.where(flip, -e1, e1), np.where(flip, -e2, e2)


def height_field_derivatives(fu, fv, fuu, fuv, fvv):
    """(mu, W) of the graph z = f(u, v) at the origin, with the upward normal.

    n = (-f_u, -f_v, 1) / g, g = sqrt(1 + f_u^2 + f_v^2); differentiating gives W = dn
    in the basis (r_u, r_v). With f_u = f_v = 0 this is simply W = -Hess f.
    """
    g = np.sqrt(1.0 + fu * fu + fv * fv)
    g3 = g**3
    du = (fu * fuu + fv * fuv) / g3  # d(1/g)/du = -du, so X_u = -fuu/g + fu*du
    dv = (fu * fuv + fv * fvv) / g3
    mu = np.stack([-fu / g, -fv / g], axis=1)
    W = np.empty(fu.shape + (2, 2))
    W[:, 0, 0] = -fuu / g + fu * du
    W[:, 0, 1] = -fuv / g + fu * dv
    W[:, 1, 0] = -fuv / g + fv * du
    W[:, 1, 1] = -fvv / g + fv * dv
    return mu, W


def quadratic_form(a, b, c):
    """(mu, W) for a fit whose frame z is the normal and whose Hessian is [[a, b], [b, c]]."""
    zero = np.zeros_like(a)
    return height_field_derivatives(zero, zero, a, b, c)


def jet_frames(coef, t1, t2, z, s, rows=131_072):
    """The Darboux frames ``(normal, k1, k2, e1, e2, ok)`` of the cubic height jets ``coef`` (N, 10) in
    (t1, t2, z), lengths in units of ``s``, by ``rows`` rows: the same numbers without N-long temporaries
    (~250 MiB at 1M points; 32k rows: 0.25 CPU s more)."""
    n = len(coef)
    out = (np.empty((n, 3)), np.empty(n), np.empty(n), np.empty((n, 3)), np.empty((n, 3)), np.empty(n, dtype=bool))
    for start in range(0, n, rows):
        r, c = slice(start, start + rows), coef[start:start + rows]
        mu, W = height_field_derivatives(c[:, 1], c[:, 2], 2 * c[:, 3], c[:, 4], 2 * c[:, 5])
        with np.errstate(invalid="ignore", divide="ignore"):
            frame = darboux_frame(t1[r], t2[r], z[r], np.nan_to_num(mu), np.nan_to_num(W) / s[r, None, None])
        for dst, src in zip(out, frame):
            dst[r] = src
    return out
