"""A follower's normal and curvatures from the fits of the anchors around it (:mod:`core.anchors`).

A fit read away from its centre carries a bias that grows with the offset: the normal
field's higher terms that the cubic cannot hold are spread, by the least squares, over the
monomials symmetrically about the centre, and their slopes at an offset d are wrong by
O(d). A follower therefore reads up to ``ANCHOR_BLEND`` anchors and averages them with
affine weights w (sum w = 1) whose weighted offsets cancel in its tangent plane
(sum w (a - p) = 0, the least-norm such w): the bias linear in the offsets cancels, and
the average of several fits also has less noise. The fits are averaged as the normal
(sum w n_a, normalised) and the shape operator as a tensor (sum w (k1 e1 e1^T + k2 e2
e2^T)), read in the averaged normal's tangent plane. Where fewer than three anchors are
near, or they lie on one side (a weight below ``-FLOOR``), the weights fall back to
inverse squared distances.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .frame import darboux_frame
from .kernels.algebra import MAX_TERMS
from .kernels.anchors import AnchorFits, Blended, blend
from .linalg import tangent_basis
from .tuning import MAX_TILT2

#: the most negative affine weight accepted (beyond it the anchors are on one side: the
#: follower would be extrapolated, and the noise of the fits amplified)
FLOOR = 0.5
#: (i, j) of monomial u^i v^j, in :func:`core.kernels.algebra.poly_row`'s order
_POWERS = np.array([(t - j, j) for t in range(4) for j in range(t + 1)][:MAX_TERMS])


def affine_weights(pts, nrm, points, picked) -> np.ndarray:
    """(F, B) weights of the anchors ``picked`` (F, B; -1: none) of ``points`` (F,), zero
    where none: affine, with the weighted offsets cancelling in the tangent plane of the
    points' normals ``nrm[points]``, else inverse squared distances (see the module)."""
    has = picked >= 0
    d = pts[np.where(has, picked, points[:, None])] - pts[points][:, None]
    t1, t2 = tangent_basis(nrm[points])
    x, y = np.einsum("fbk,fk->fb", d, t1), np.einsum("fbk,fk->fb", d, t2)
    dist2 = np.einsum("fbk,fbk->fb", d, d)
    scale = np.sqrt(dist2.max(axis=1, initial=0.0))[:, None]
    scale[scale == 0.0] = 1.0
    A = np.stack([has.astype(float), x / scale, y / scale], axis=1)  # (F, 3, B)
    M = A @ A.transpose(0, 2, 1)
    w = np.zeros(has.shape)
    solvable = (has.sum(axis=1) >= 3) & (np.abs(np.linalg.det(M)) > 1e-6)
    if solvable.any():
        z = np.linalg.solve(M[solvable], np.broadcast_to([1.0, 0.0, 0.0], (int(solvable.sum()), 3))[..., None])
        w[solvable] = (A[solvable].transpose(0, 2, 1) @ z)[..., 0]
    shepard = ~solvable | ~(w >= -FLOOR).all(axis=1)
    inv = np.where(has, 1.0 / np.where(has & (dist2 > 0.0), dist2, 1.0), 0.0)
    w[shepard] = inv[shepard] / inv[shepard].sum(axis=1, keepdims=True)
    return w


def blended(kept, pts, nrm, points, picked, constraint):
    """``(frame, good, r)``: the normal, principal curvatures and directions of the
    followers ``points`` from the fits of their anchors ``picked`` (F, B) in ``kept``
    (:class:`core.anchors.Kept`) averaged as the module says (compiled:
    :func:`core.kernels.anchors.blend`), whether every anchor read was usable there, and
    the row of each follower's nearest anchor in ``kept``."""
    f = len(points)
    out = Blended(np.full((f, 3), np.nan), np.full(f, np.nan), np.full(f, np.nan), np.full((f, 3), np.nan),
                  np.full((f, 3), np.nan))
    good = np.zeros(f, dtype=bool)
    fits = AnchorFits(kept.row, kept.coef, kept.frame, kept.h, kept.ok)
    blend(np.ascontiguousarray(pts, dtype=np.float64), np.ascontiguousarray(nrm, dtype=np.float64), points,
          np.ascontiguousarray(picked), fits, constraint == "project", MAX_TILT2, FLOOR, out, good)
    return out, good, kept.row[picked[:, 0]]


def blended_reference(kept, pts, nrm, points, picked, constraint):
    """Numpy reference of :func:`blended`."""
    w = affine_weights(pts, nrm, points, picked)
    f = len(points)
    normal, S, good, r0 = np.zeros((f, 3)), np.zeros((f, 3, 3)), np.ones(f, dtype=bool), None
    for j in range(picked.shape[1]):
        rows = np.flatnonzero(picked[:, j] >= 0)
        r = kept.row[picked[rows, j]]
        f = kept.frame[r]
        mu, W = read_at_reference(pts, points[rows], picked[rows, j], kept.coef[r], f, kept.h[r], constraint == "project")
        frame = darboux_frame(f[:, 0], f[:, 1], f[:, 2], mu, W)
        ok = kept.ok[r] & frame.ok
        good[rows] &= ok
        if j == 0:
            r0 = r
        side = np.where(np.einsum("ij,ij->i", frame.normal, nrm[points[rows]]) < 0.0, -1.0, 1.0)  # the point's side
        wj = np.where(ok, w[rows, j] * side, 0.0)
        e1, e2 = np.nan_to_num(frame.e1), np.nan_to_num(frame.e2)
        k1, k2 = np.nan_to_num(frame.k1), np.nan_to_num(frame.k2)
        normal[rows] += wj[:, None] * np.nan_to_num(frame.normal)
        S[rows] += wj[:, None, None] * (k1[:, None, None] * e1[:, :, None] * e1[:, None, :]
                                        + k2[:, None, None] * e2[:, :, None] * e2[:, None, :])
    length = np.linalg.norm(normal, axis=1)
    good &= length > 0.0
    normal /= np.where(good, length, 1.0)[:, None]
    return _principal(normal, S, good), good, r0


def _principal(normal, S, good):
    """The principal curvatures k1 >= k2 and directions of the tensors ``S`` in the tangent
    planes of ``normal`` (e1 x e2 = normal), NaN where not ``good``."""
    b1, b2 = tangent_basis(normal)
    s11 = np.einsum("fi,fij,fj->f", b1, S, b1)
    s12 = np.einsum("fi,fij,fj->f", b1, S, b2)
    s22 = np.einsum("fi,fij,fj->f", b2, S, b2)
    mean, half = 0.5 * (s11 + s22), 0.5 * (s11 - s22)
    rad = np.hypot(half, s12)
    phi = 0.5 * np.arctan2(s12, half)
    c, s = np.cos(phi)[:, None], np.sin(phi)[:, None]
    bad = ~good
    out = SimpleNamespace(normal=normal, k1=mean + rad, k2=mean - rad, e1=c * b1 + s * b2, e2=-s * b1 + c * b2)
    for name in ("normal", "k1", "k2", "e1", "e2"):
        getattr(out, name)[bad] = np.nan
    return out


def read_at_reference(pts, points, anchors, coef, frame, h, project):
    """``(mu, W)``: the polynomials ``coef`` of the anchors' fits (rows of ``coef``, ``frame``
    and ``h`` per follower) read at the followers' offsets, W in units of 1/h and projected
    onto eq. 22's plane when ``project`` (numpy reference of the reading inside
    :func:`core.kernels.anchors.blend`)."""
    d = (pts[points] - pts[anchors]) / h[:, None]
    u, v = np.einsum("ij,ij->i", d, frame[:, 0]), np.einsum("ij,ij->i", d, frame[:, 1])
    i, j = _POWERS[:, 0], _POWERS[:, 1]
    ui, vj = u[:, None] ** i, v[:, None] ** j
    du = i * u[:, None] ** np.maximum(i - 1, 0) * vj
    dv = j * ui * v[:, None] ** np.maximum(j - 1, 0)
    mu = np.einsum("mct,mt->mc", coef, ui * vj)
    W = np.stack([np.einsum("mct,mt->mc", coef, du), np.einsum("mct,mt->mc", coef, dv)], axis=2) / h[:, None, None]
    return mu, (_projected(mu, W) if project else W)


def _projected(mu, W):
    """W with its component along eq. 22's g removed (§4.4, as the NF kernel does at a centre)."""
    X, Y = mu[:, 0], mu[:, 1]
    g = np.stack([X * Y, -(1.0 - Y * Y), 1.0 - X * X, -X * Y], axis=1)
    w = W.reshape(len(W), 4)
    t = np.einsum("ij,ij->i", g, w) / np.einsum("ij,ij->i", g, g)
    return (w - t[:, None] * g).reshape(-1, 2, 2)
